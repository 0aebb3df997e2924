//! What a scene is asked to load, in the scene's own terms: the files, the clips and frames that play, and how
//! each source is placed. The manifest's declarations are translated into a [`Request`] above this layer
//! (`settings::scene`), so the scene loads and poses without knowing how a TOML file spells any of it, and a
//! test or a bench can open a scene without a manifest.

use std::path::{Path, PathBuf};

/// Everything [`super::Scene::open`] loads.
#[derive(Debug, Clone, Default)]
pub struct Request {
    /// The sources, sorted by name.
    pub sources: Vec<SourceRequest>,
    /// The whole scene's placement, scene → world, applied after each source's own.
    pub global: Placement,
    /// What a frame fit sizes the subject to: the largest sphere about the origin every camera sees whole.
    /// `None` when no camera places itself around a target (a frame fit is then refused).
    pub reach: Option<Reach>,
    /// Whether the sources' own lights (glTF `KHR_lights_punctual`) are posed with them.
    pub file_lights: bool,
}

/// One source: a file (or a built-in ground plane), what of it plays, and how it is placed.
#[derive(Debug, Clone)]
pub struct SourceRequest {
    /// The source's name (errors and warnings say it).
    pub name: String,
    /// What is read.
    pub file: SourceFile,
    /// The clips that play (glTF: any number together; FBX: one take).
    pub clips: Clips,
    /// The frames of an animated file, or of a sequence's pattern.
    pub frames: FrameRange,
    /// Source → scene.
    pub placement: Placement,
    /// Subtracted from its PLY files' coordinates as they are read, in double precision (zero: none).
    pub origin: [f64; 3],
    /// Whether every material's own opacity is taken as 1 ([`super::posed::PosedScene::make_opaque`]).
    pub opaque: bool,
}

/// What a source reads. Paths are as the caller resolved them (the manifest's folder joined).
#[derive(Debug, Clone)]
pub enum SourceFile {
    /// An animated glTF, and the scene of it to load (default: the file's).
    Gltf {
        /// The file.
        path: PathBuf,
        /// The scene index.
        scene: Option<usize>,
    },
    /// An FBX file.
    Fbx(PathBuf),
    /// A `.blend`, imported by Blender, and what of it is selected.
    Blend {
        /// The file.
        path: PathBuf,
        /// What the export script selects.
        select: BlendSelect,
    },
    /// A static mesh (PLY, OBJ or glTF at rest), and the glTF scene to load.
    Mesh {
        /// The file.
        path: PathBuf,
        /// The glTF scene index.
        scene: Option<usize>,
    },
    /// One PLY point cloud per frame.
    PlySequence(Vec<FrameFile>),
    /// One mesh per frame (OBJ, textured PLY or glTF).
    MeshSequence(Vec<FrameFile>),
    /// A built-in ground plane, placed in world units.
    Ground(Ground),
}

impl SourceFile {
    /// The file read, for the one-file kinds.
    pub fn path(&self) -> Option<&Path> {
        match self {
            SourceFile::Gltf { path, .. } | SourceFile::Blend { path, .. } | SourceFile::Mesh { path, .. } => {
                Some(path)
            }
            SourceFile::Fbx(path) => Some(path),
            _ => None,
        }
    }
}

/// What of a `.blend` is exported: a scene, an object (with its children), a collection; all by name.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct BlendSelect {
    /// The scene (default: the file's active scene).
    pub scene: Option<String>,
    /// One object and its children.
    pub object: Option<String>,
    /// One collection.
    pub collection: Option<String>,
}

/// One frame file of a sequence.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct FrameFile {
    /// Its frame number (a pattern's) or position (a glob's).
    pub number: i64,
    /// The file.
    pub path: PathBuf,
}

/// The clips that play.
#[derive(Debug, Clone, Default, PartialEq)]
pub enum Clips {
    /// The file's first clip (none when it has none).
    #[default]
    First,
    /// Every clip of the file, together.
    All,
    /// These clips, together.
    These(Vec<Clip>),
}

/// One clip, by index or by name.
#[derive(Debug, Clone, PartialEq)]
pub enum Clip {
    /// By index.
    Index(usize),
    /// By name.
    Name(String),
}

/// The most frames a source plays: the manifest's own bound (`settings` holds the two equal), which a clip's
/// whole duration, played when no frames are named, must keep too.
pub const MAX_FRAMES: u64 = 1_000_000;

/// Which frames of an animated file play: frame `n` is at `n / fps` seconds from the clip's start.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct FrameRange {
    /// The first frame number (default 0; a `.blend`'s own first frame).
    pub start: Option<i64>,
    /// The last, inclusive.
    pub end: Option<i64>,
    /// How many, from `start` (with neither `end` nor `count`: to the clip's end).
    pub count: Option<u64>,
    /// Every `step`-th frame (default 1).
    pub step: Option<u64>,
    /// Frames per second (default 30).
    pub fps: Option<f64>,
}

impl FrameRange {
    /// Frames per second, default 30.
    pub fn fps(&self) -> f64 {
        self.fps.unwrap_or(30.0)
    }

    /// The step, default 1.
    pub fn step(&self) -> u64 {
        self.step.unwrap_or(1).max(1)
    }
}

/// How a source maps into the scene (or the scene into the world):
/// `translate · rotate · scale · fit · center · up · matrix`, `fit` and `center` from the bounds of the frames
/// `over` selects, taken after `up · matrix`.
#[derive(Debug, Clone, PartialEq)]
pub struct Placement {
    /// The up axis; `None`: the file's own (glTF and OBJ +Y, PLY, FBX and `.blend` +Z).
    pub up: Option<UpAxis>,
    /// A raw 4×4 matrix (rows), applied first.
    pub matrix: Option<[[f64; 4]; 4]>,
    /// Which point moves to the origin; `None`: the bounding box's centre for a frame fit, else none.
    pub center: Option<Center>,
    /// The size to scale to.
    pub fit: Option<Fit>,
    /// Extra scale per axis.
    pub scale: [f64; 3],
    /// Extra rotation, XYZ Euler degrees about world axes, X first.
    pub rotate_deg: [f64; 3],
    /// Extra translation.
    pub translate: [f64; 3],
    /// The frames the bounds come from.
    pub over: Over,
}

impl Default for Placement {
    fn default() -> Self {
        Placement {
            up: None,
            matrix: None,
            center: None,
            fit: None,
            scale: [1.0; 3],
            rotate_deg: [0.0; 3],
            translate: [0.0; 3],
            over: Over::AllFrames,
        }
    }
}

/// A source's up axis.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum UpAxis {
    /// +Y up (glTF's convention).
    Y,
    /// +Z up (the world's).
    Z,
    /// −Y up (COLMAP's reconstructions of upright photos).
    NegY,
    /// −Z up.
    NegZ,
    /// +X up.
    X,
    /// −X up.
    NegX,
}

/// The point a placement moves to the origin.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Center {
    /// The bounding box's centre.
    Bbox,
    /// The mean of the vertices.
    Centroid,
    /// None: leave in place.
    None,
}

/// One measure a placement scales to.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Fit {
    /// Whole in every camera: the farthest point from the centre at `(1 − margin)` of [`Reach::radius`].
    Frame {
        /// The share of the room left empty.
        margin: f64,
    },
    /// Size along world Z.
    Height(f64),
    /// Radius of the sphere about the centre enclosing the bounding box.
    Radius(f64),
    /// Largest side of the bounding box.
    Extent(f64),
}

/// Which frames the bounds come from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Over {
    /// Every frame: the subject never jumps or breathes.
    #[default]
    AllFrames,
    /// Frame 0 only.
    First,
}

/// The largest sphere about the origin every sizing camera sees whole, and the rig that bounds it.
#[derive(Debug, Clone, PartialEq)]
pub struct Reach {
    /// The sphere's radius, world units (≤ 0: no sphere fits).
    pub radius: f64,
    /// The rig whose cameras bound it (an error names it).
    pub rig: String,
}

/// A ground plane: a `size[0]` × `size[1]` rectangle facing +Z, centred on the origin.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ground {
    /// Width along X and depth along Y, world units.
    pub size: [f64; 2],
    /// Linear RGB albedo.
    pub color: [f64; 3],
    /// Height; `None`: the lowest point of the other sources over all their frames.
    pub z: Option<f64>,
}

/// The folder a file's relative names resolve against: its parent, or `.` for a bare name (`Path::parent` of
/// `model.gltf` is the empty path, which `canonicalize` and `read_dir` refuse).
pub fn folder_of(file: &Path) -> &Path {
    match file.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    }
}
