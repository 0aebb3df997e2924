//! The kinds of action a build runs and what each one is: its kind, its identity (what it makes, of which
//! image, frame or output), the versions of the code that shapes their bytes, and the resolved settings of a
//! point-cloud output. How each is keyed is [`super::walk`].

use serde::Serialize;

use super::Plan;
use crate::manifest::output::{ColorAverage, PlyFormat, PointColor, Reduce, VoxelPosition};
use crate::manifest::render::Pass;

/// Version of the renderer's output: bump when a change moves rendered bytes.
pub const RENDER_SALT: &str = "render 7";
/// Version of lit shading (what only `pbr` renders and lit point colours read): bump when a change moves lit
/// bytes only, so that unlit datasets keep their keys.
pub const LIT_SALT: &str = "lit 21";
/// Version of the point sampler's output.
pub const SAMPLE_SALT: &str = "sample 3";
/// How a cloud of a given size picks among a point cloud's own points (at most its share, keyed).
pub(super) const SELECTION: &str = "at most n points 1";
/// Version of the PLY / COLMAP point encodings and of compositing.
pub const ENCODE_SALT: &str = "encode 1";
/// Version of the video encoding (codec, its settings, colour conversion and container): see
/// [`crate::execute::video`].
pub const VIDEO_SALT: &str =
    "video 2: openh264 0.9, qp 12, bt601 limited 4:2:0 (block-mean chroma, least-squares luma), mp4";

/// What an action does; each kind has its own executor and its own keyed walk.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Kind {
    /// Prefilter the environment map (lit shading): irradiance and specular levels.
    Environment,
    /// One frame's light that does not depend on the camera and is costly to find (lit shading): the environment's
    /// visibility at the vertices and over the ground, and what the subject reflects onto itself and the ground.
    Light,
    /// Render one pass of one image (PNG, plus EXR or instance ids where asked).
    RenderPass,
    /// Composite an RGBA image over an opaque background (COLMAP, DyNeRF).
    Composite,
    /// Encode one camera's composites, frame by frame, as an H.264 MP4 (DyNeRF's `camNN.mp4`).
    Video,
    /// Surface samples over several frames, as an initialization PLY.
    InitCloud,
    /// One frame's surface samples as COLMAP's points3D.txt.
    ColmapPoints,
    /// The bounds of the posed geometry over several frames.
    Bounds,
    /// One frame's unreduced surface samples (the input of a reduction).
    SampleFrame,
    /// One frame of a point-cloud sequence, reduced and encoded as PLY.
    PointFrame,
    /// A split's contact sheet (PNG): thumbnails of its renders.
    PreviewSheet,
    /// The rig plot (PNG): an output's cameras around the subject.
    PreviewRig,
    /// A point-cloud output's strip (PNG): a few frames rendered.
    PreviewStrip,
    /// An output's dataset directory: place every blob, write the metadata (not cached in the store).
    WriteOutput,
}

impl Kind {
    /// Every kind, in an order that puts an action's inputs' kinds before its own (`execute` starts a kind
    /// once the kinds it reads have finished, so kinds that read nothing of each other run at once).
    pub const ALL: [Kind; 14] = [
        Kind::Environment,
        Kind::Light,
        Kind::RenderPass,
        Kind::Bounds,
        Kind::SampleFrame,
        Kind::InitCloud,
        Kind::ColmapPoints,
        Kind::Composite,
        Kind::Video,
        Kind::PointFrame,
        Kind::PreviewSheet,
        Kind::PreviewRig,
        Kind::PreviewStrip,
        Kind::WriteOutput,
    ];

    /// The kebab-case name used in listings and JSON.
    pub fn name(self) -> &'static str {
        match self {
            Kind::Environment => "environment",
            Kind::Light => "light",
            Kind::RenderPass => "render-pass",
            Kind::Composite => "composite",
            Kind::Video => "video",
            Kind::InitCloud => "init-cloud",
            Kind::ColmapPoints => "colmap-points",
            Kind::Bounds => "bounds",
            Kind::SampleFrame => "sample-frame",
            Kind::PointFrame => "point-frame",
            Kind::PreviewSheet => "preview-sheet",
            Kind::PreviewRig => "preview-rig",
            Kind::PreviewStrip => "preview-strip",
            Kind::WriteOutput => "write-output",
        }
    }

    /// Whether results of this kind live in the cache (all but writing an output).
    pub fn cached(self) -> bool {
        self != Kind::WriteOutput
    }

    /// Whether actions of this kind gather results from across the graph (every frame of a camera, thumbnails
    /// of a whole split): a shard would pull work other shards own, so they are left to the unsharded build
    /// that writes the outputs (by then their inputs are cached).
    pub fn gathers(self) -> bool {
        matches!(self, Kind::Video | Kind::PreviewSheet | Kind::PreviewRig | Kind::PreviewStrip)
    }
}

/// One action: its kind and what it acts on. Inputs that are other actions' results are the node's `deps`
/// (in the order documented per variant); source content enters through the plan's frame keys.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub enum Action {
    /// The environment map, prefiltered. No deps (the map enters by its content key).
    Environment,
    /// Scene frame `frame`'s light at its vertices and over its ground, the bounce included
    /// ([`crate::render::light::Gathered`]), shared by every lit view of it.
    /// Deps: the [`Action::Environment`] (the manifest's map or the built-in studio map, prefiltered).
    Light {
        /// Scene frame.
        frame: usize,
    },
    /// Pass `pass` of plan image `image`. Deps: for a lit (`pbr`) RGBA pass, its frame's [`Action::Light`]
    /// (which reads the environment).
    RenderPass {
        /// Index into [`Plan::images`].
        image: usize,
        /// The pass.
        pass: Pass,
    },
    /// Image `image` over `background` (sRGB bytes). Deps: the image's RGBA pass.
    Composite {
        /// Index into [`Plan::images`].
        image: usize,
        /// Opaque background, sRGB.
        background: [u8; 3],
    },
    /// One camera's video, at [`super::walk::Keying::video_fps_milli`]. Deps: the [`Action::Composite`]s of its
    /// images, in frame order.
    Video {
        /// Index into [`Plan::splits`].
        split: usize,
        /// The camera (view) within the split.
        view: u32,
    },
    /// `points` samples spread over `frames`. No deps.
    InitCloud {
        /// Scene frames, ascending.
        frames: Vec<usize>,
        /// Points in all.
        points: u64,
    },
    /// `points` samples of `frame` as points3D.txt. No deps.
    ColmapPoints {
        /// Scene frame.
        frame: usize,
        /// Points.
        points: u64,
    },
    /// Bounds over `frames`. No deps.
    Bounds {
        /// Scene frames, ascending.
        frames: Vec<usize>,
    },
    /// Unreduced samples of `frame` for point output `output`. Deps: its frame's [`Action::Light`] when its
    /// colours are lit ([`PointSettings::light_dep`]).
    SampleFrame {
        /// The `[output.NAME]`.
        output: String,
        /// Scene frame.
        frame: usize,
    },
    /// Frame `frame` of point output `output`. Deps: its [`Action::SampleFrame`] when it reduces, else its
    /// frame's [`Action::Light`] when its colours are lit; then the sequence's [`Action::Bounds`] when it
    /// quantizes (`vox`).
    PointFrame {
        /// The `[output.NAME]`.
        output: String,
        /// Scene frame.
        frame: usize,
    },
    /// Split `split`'s contact sheet. Deps: per image of [`super::preview::layout`], its RGBA pass, then
    /// its `extras` passes (depth, mask) in that order.
    PreviewSheet {
        /// Index into [`Plan::splits`].
        split: usize,
        /// The passes shown besides RGBA.
        extras: Vec<Pass>,
    },
    /// The rig plot of `splits`' cameras. Deps: the [`Action::Bounds`] of their frames, then the subject's
    /// samples ([`Action::InitCloud`] of [`super::preview::subject_frame`], [`super::preview::POINTS`]).
    PreviewRig {
        /// Indices into [`Plan::splits`], ascending.
        splits: Vec<usize>,
    },
    /// Point output `output`'s strip (and its viewer's thinned frames, a second blob). Deps: the
    /// [`Action::PointFrame`]s of [`super::preview::point_frames`].
    PreviewStrip {
        /// The `[output.NAME]`.
        output: String,
    },
    /// Output `output`'s directory. Deps: every action whose result it places.
    WriteOutput {
        /// The `[output.NAME]`.
        output: String,
    },
}

impl Action {
    /// The action's kind.
    pub fn kind(&self) -> Kind {
        match self {
            Action::Environment => Kind::Environment,
            Action::Light { .. } => Kind::Light,
            Action::RenderPass { .. } => Kind::RenderPass,
            Action::Composite { .. } => Kind::Composite,
            Action::Video { .. } => Kind::Video,
            Action::InitCloud { .. } => Kind::InitCloud,
            Action::ColmapPoints { .. } => Kind::ColmapPoints,
            Action::Bounds { .. } => Kind::Bounds,
            Action::SampleFrame { .. } => Kind::SampleFrame,
            Action::PointFrame { .. } => Kind::PointFrame,
            Action::PreviewSheet { .. } => Kind::PreviewSheet,
            Action::PreviewRig { .. } => Kind::PreviewRig,
            Action::PreviewStrip { .. } => Kind::PreviewStrip,
            Action::WriteOutput { .. } => Kind::WriteOutput,
        }
    }
}

/// A `ply-sequence` output's settings, resolved against the scene (defaults applied, source found).
#[derive(Debug, Clone, PartialEq)]
pub struct PointSettings {
    /// Surface samples per frame.
    pub points: u64,
    /// Only this source (index into the scene's sources, and its name), or every source.
    pub source: Option<(usize, String)>,
    /// Point i is the same surface point in every frame.
    pub correspondence: bool,
    /// Per-point motion to the next frame.
    pub motion: bool,
    /// Voxel edge for downsampling, world units.
    pub voxel: Option<f64>,
    /// Quantize to a 2^vox integer grid fixed over the sequence.
    pub vox: Option<u32>,
    /// Which point a voxel keeps.
    pub reduce: Reduce,
    /// Where a voxel's point goes.
    pub position: VoxelPosition,
    /// Colour averaging space.
    pub color_average: ColorAverage,
    /// Albedo or lit colours.
    pub color: crate::manifest::output::PointColor,
    /// Binary or ASCII PLY.
    pub format: PlyFormat,
    /// File name pattern with `{name}` substituted.
    pub pattern: String,
}

impl PointSettings {
    /// Whether its sample actions' light action reads the prefiltered environment (a map's, or the built-in
    /// studio's): lit colours, whatever the images' shading (they need no `pbr` images, and read the manifest's
    /// `[environment]` all the same).
    pub fn environment_dep(&self) -> bool {
        self.color == PointColor::Lit
    }

    /// Whether its sample actions read their frame's light action (their first dep): lit colours, lit as the
    /// renders light the frame (that action gathered light at every vertex of it, whichever source is sampled).
    pub fn light_dep(&self) -> bool {
        self.color == PointColor::Lit
    }

    /// Whether frames are reduced (so their unreduced samples are an action of their own).
    pub fn reduces(&self) -> bool {
        self.voxel.is_some() || self.vox.is_some()
    }
}

/// The splits (indices into [`Plan::splits`]) plan images `images` belong to, ascending: what an output's rig
/// plot shows.
pub fn splits_of(plan: &Plan, images: &[usize]) -> Vec<usize> {
    let mut splits: Vec<usize> = images.iter().map(|&i| plan.images[i].split).collect();
    splits.sort_unstable();
    splits.dedup();
    splits
}

/// The frames a rig plot's splits cover, ascending.
pub fn rig_frames(plan: &Plan, splits: &[usize]) -> Vec<usize> {
    let images: Vec<usize> = splits.iter().flat_map(|&s| plan.splits[s].images.iter().copied()).collect();
    plan.frames_of(&images)
}

/// The frame whose samples stand for the subject in a rig plot of `splits`.
pub fn rig_subject_frame(plan: &Plan, splits: &[usize]) -> usize {
    super::preview::subject_frame(&rig_frames(plan, splits))
}

/// The manifest spelling of a pass.
pub fn pass_name(p: Pass) -> &'static str {
    match p {
        Pass::Rgba => "rgba",
        Pass::Depth => "depth",
        Pass::Normal => "normal",
        Pass::Mask => "mask",
        Pass::Instance => "instance",
        Pass::Albedo => "albedo",
    }
}
