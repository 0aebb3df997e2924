//! One source, loaded: its geometry and its frame list, posable in source space.

use std::path::PathBuf;
use std::sync::Arc;

use glam::{Mat4, Vec3, Vec4};

use super::gltf::{GltfAsset, PoseScratch};
use super::input::{folder_of, Clip, Clips, FrameFile, FrameRange, Ground, SourceFile, SourceRequest, UpAxis};
use super::material::Material;
use super::ply_scene::splats_of;
pub use super::ply_scene::{
    checked_ply, ply_facts, ply_scene, ply_scene_at, ply_scene_slice, ply_textures, ply_textures_cached, PlyFacts,
};
use super::posed::{PosedPrimitive, PosedScene};
use super::Error;

/// A loaded source.
#[derive(Debug)]
pub enum SourceData {
    /// An animated glTF and the times of its frames (seconds).
    Gltf {
        /// The file.
        asset: Box<GltfAsset>,
        /// Clips that play.
        clips: Vec<usize>,
        /// Frame times.
        times: Vec<f32>,
    },
    /// An FBX file, the take that plays (none: the file at rest) and the times of its frames (seconds from the
    /// take's start).
    Fbx {
        /// The file.
        asset: Box<super::fbx::FbxAsset>,
        /// The take.
        take: Option<usize>,
        /// Frame times.
        times: Vec<f32>,
    },
    /// A static mesh, posed once in source space.
    Static(PosedScene),
    /// A PLY sequence, read frame by frame.
    Sequence(Vec<FrameFile>),
    /// A mesh sequence (OBJ + MTL, textured PLY, or glTF per frame), read frame by frame; the topology may change
    /// every frame.
    MeshSequence(Vec<FrameFile>),
}

/// A source with its name.
#[derive(Debug)]
pub struct LoadedSource {
    /// Manifest name.
    pub name: String,
    /// Geometry.
    pub data: SourceData,
    /// The up axis its transform assumes by default.
    pub default_up: UpAxis,
    /// A built-in ground plane, placed in world units ([`super::Scene::open`] makes its geometry).
    pub ground: Option<Ground>,
    /// What the user should know about how it loaded (a `.blend`'s import notes, an FBX's missing textures).
    pub warnings: Vec<String>,
    /// Subtracted from its PLY files' coordinates as they are read, in double precision.
    pub origin: [f64; 3],
    /// Whether its PLY files hold 3D Gaussians with their shapes, drawn as splatting draws them (found from the
    /// first frame's header, as `check` sees it).
    pub splats: bool,
    /// Whether every material's own opacity is taken as 1 ([`PosedScene::make_opaque`], on every frame posed).
    pub opaque: bool,
}

impl LoadedSource {
    /// Loads a source; `importer` imports a `.blend`.
    pub fn load(req: &SourceRequest, importer: Option<&super::blend::Importer>) -> Result<LoadedSource, Error> {
        let name = req.name.clone();
        let (mut warnings, mut ground) = (Vec::new(), None);
        let data = match &req.file {
            SourceFile::Ground(g) => {
                ground = Some(*g);
                SourceData::Static(PosedScene::default())
            }
            SourceFile::Gltf { path, scene } => {
                let asset = super::gltf::load(path, *scene)?;
                if let Some(message) = nothing_drawn(path, asset.holds()) {
                    return Err(Error::Source { name, message });
                }
                let clips =
                    select_clips(&asset, &req.clips).map_err(|message| Error::Clip { name: name.clone(), message })?;
                let duration = clips.iter().map(|&c| asset.animations[c].duration()).fold(0.0f32, f32::max);
                let times = frame_times(&req.frames, duration as f64, "animation")
                    .map_err(|message| Error::Clip { name: name.clone(), message })?;
                SourceData::Gltf { asset: Box::new(asset), clips, times }
            }
            SourceFile::Fbx(path) => {
                let asset = super::fbx::load(path)?;
                if let Some(message) = nothing_drawn(path, asset.holds()) {
                    return Err(Error::Source { name, message });
                }
                warnings.extend(asset.warnings.iter().map(|w| format!("{}: {w}", path.display())));
                if !req.opaque {
                    warnings.extend(asset.unseen.iter().map(|w| format!("{}: {w}", path.display())));
                }
                let take = super::fbx::select_take(&asset, &name, &req.clips)?;
                let duration = take.map_or(0.0, |t| asset.takes[t].duration());
                let times = frame_times(&req.frames, duration, "take")
                    .map_err(|message| Error::Clip { name: name.clone(), message })?;
                SourceData::Fbx { asset: Box::new(asset), take, times }
            }
            SourceFile::Blend { path, select } => {
                let importer = importer.ok_or_else(|| Error::Blend {
                    path: path.clone(),
                    message: "a .blend is imported through a cache: open the scene with an importer".into(),
                })?;
                let got = importer.import(path, select, &req.frames)?;
                warnings.extend(got.info.warnings.iter().map(|w| format!("{}: {w}", path.display())));
                let frames = got.info.frames.iter().enumerate();
                let file = |(i, &number): (usize, &i64)| FrameFile {
                    number,
                    path: got.dir.join(format!("frame_{i:05}.gltf")),
                };
                SourceData::MeshSequence(frames.map(file).collect())
            }
            SourceFile::Mesh { path, .. } if is_ply(path) => SourceData::Static(ply_scene_at(path, req.origin)?),
            SourceFile::Mesh { path, .. } if is_stl(path) || is_drc(path) => SourceData::Static(mesh_frame(path)?),
            SourceFile::Mesh { path, .. } if is_obj(path) => {
                let (scene, missing) = super::obj::scene_and_missing(path, req.origin)?;
                warnings.extend(missing);
                SourceData::Static(scene)
            }
            SourceFile::Mesh { path, scene } => {
                if let Some(message) = way_out_of(path) {
                    return Err(Error::Source { name, message });
                }
                let asset = super::gltf::load(path, *scene)?;
                if let Some(message) = nothing_drawn(path, asset.holds()) {
                    return Err(Error::Source { name, message });
                }
                SourceData::Static(at_rest(&asset))
            }
            SourceFile::PlySequence(frames) => SourceData::Sequence(frames.clone()),
            SourceFile::MeshSequence(frames) => SourceData::MeshSequence(frames.clone()),
        };
        // An empty PLY, OBJ, STL or Draco file (a header alone, `solid`/`endsolid` alone) would render blank images:
        // refused as a glTF or FBX with nothing to draw is.
        if let (SourceFile::Mesh { path, .. }, SourceData::Static(s)) = (&req.file, &data) {
            if (is_ply(path) || is_obj(path) || is_stl(path) || is_drc(path))
                && s.triangle_count() + s.point_count() == 0
            {
                let drawn =
                    Holds { draws: false, nodes: 0, meshes: true, clips: 0, clip: "", skeleton: false, curves: 0 };
                return Err(Error::Source { name, message: nothing_drawn(path, drawn).unwrap_or_default() });
            }
        }
        // A 3D Gaussian splatting file (found from its first frame's header, as `check` sees it) is drawn as
        // splatting draws it; one without the Gaussians' shapes as points, which is said.
        let first_ply = match &req.file {
            SourceFile::Mesh { path, .. } if is_ply(path) => Some(path),
            SourceFile::PlySequence(frames) | SourceFile::MeshSequence(frames) => {
                frames.first().map(|f| &f.path).filter(|p| is_ply(p))
            }
            _ => None,
        };
        let mut splats = false;
        if let Some(path) = first_ply {
            let (splatted, note) = splats_of(path)?;
            splats = splatted;
            warnings.extend(note);
        }
        // The libraries and textures an OBJ names and that are missing, and a material wholly transparent (`d 0`),
        // which draws nothing, in Blender too (some exporters write it for opaque surfaces): said of the first
        // frame, as `check` sees it.
        let first_obj = match &req.file {
            SourceFile::Mesh { path, .. } if is_obj(path) => Some(path),
            SourceFile::MeshSequence(frames) => frames.first().map(|f| &f.path).filter(|p| is_obj(p)),
            _ => None,
        };
        if let Some(path) = first_obj {
            // A static OBJ's were said as it was read.
            if matches!(req.file, SourceFile::MeshSequence(_)) {
                warnings.extend(super::obj::missing(path)?);
            }
            if !req.opaque {
                warnings.extend(super::obj::unseen_materials(path)?);
            }
        }
        // PLY is a scanner's format (Z up), and so is Draco's `.drc` (most often a compressed PLY); STL a printer's
        // (Z up, as slicers and Blender read it); OBJ and glTF are Y up; FBX is loaded in the world's axes, and a
        // .blend in Blender's (exported +Z up). A ground plane is placed in world units.
        let z_up = |p: &std::path::Path| is_ply(p) || is_stl(p) || is_drc(p);
        let default_up = match &req.file {
            SourceFile::Mesh { path, .. } if z_up(path) => UpAxis::Z,
            SourceFile::MeshSequence(frames) if frames.first().is_some_and(|f| z_up(&f.path)) => UpAxis::Z,
            SourceFile::Gltf { .. } | SourceFile::Mesh { .. } | SourceFile::MeshSequence(_) => UpAxis::Y,
            _ => UpAxis::Z,
        };
        Ok(LoadedSource { name, data, default_up, ground, warnings, origin: req.origin, splats, opaque: req.opaque })
    }

    /// blake3 of the bytes a frame is read from: the frame's PLY for a sequence, the file for glTF and meshes
    /// (whose per-frame content is the posed geometry, hashed by [`PosedScene::digest`]).
    pub fn content_digest(&self, frame: usize, file: &std::path::Path) -> Result<blake3::Hash, Error> {
        let path = match &self.data {
            SourceData::Sequence(frames) | SourceData::MeshSequence(frames) => {
                frames[frame.min(frames.len() - 1)].path.as_path()
            }
            _ => file,
        };
        let bytes = std::fs::read(path).map_err(|e| Error::Io { path: path.to_path_buf(), source: e })?;
        Ok(blake3::hash(&bytes))
    }

    /// Number of frames (1 for a static mesh).
    pub fn frame_count(&self) -> usize {
        match &self.data {
            SourceData::Gltf { times, .. } | SourceData::Fbx { times, .. } => times.len(),
            SourceData::Static(_) => 1,
            SourceData::Sequence(f) | SourceData::MeshSequence(f) => f.len(),
        }
    }

    /// Poses frame `frame` (clamped to the last) with `post` applied, into `out`.
    pub fn pose(&self, frame: usize, post: Mat4, scratch: &mut PoseScratch, out: &mut PosedScene) -> Result<(), Error> {
        match &self.data {
            SourceData::Gltf { asset, clips, times } => {
                if out.materials.len() != asset.materials.len() || out.textures.len() != asset.textures.len() {
                    out.materials = Arc::new(asset.materials.clone());
                    out.textures = Arc::clone(&asset.textures);
                    out.primitives.clear();
                }
                let t = times[frame.min(times.len() - 1)];
                asset.pose(clips, t, post, scratch, out);
            }
            SourceData::Fbx { asset, take, times } => {
                asset.pose(*take, times[frame.min(times.len() - 1)] as f64, post, out)?;
            }
            SourceData::Static(rest) => transform_into(rest, post, out),
            // A frame read from its file is transformed where it lies and becomes `out`: copying it into `out`'s
            // buffers would hold a second copy of its positions and normals (24 bytes a point) for nothing.
            SourceData::Sequence(frames) => {
                let f = &frames[frame.min(frames.len() - 1)];
                *out = transformed(ply_scene_at(&f.path, self.origin)?, post);
            }
            SourceData::MeshSequence(frames) => {
                *out = transformed(mesh_frame_at(&frames[frame.min(frames.len() - 1)].path, self.origin)?, post);
            }
        }
        if self.opaque {
            out.make_opaque();
        }
        Ok(())
    }
}

/// What a glTF or FBX file holds: whether it draws anything, and what it has instead for the error that refuses
/// it when it does not ([`nothing_drawn`]).
#[derive(Debug, Clone, Copy)]
pub struct Holds {
    /// Whether it has something to draw (or, in glTF, a light).
    pub draws: bool,
    /// Its nodes.
    pub nodes: usize,
    /// Whether some node has a mesh (of lines, or empty: nothing vvgen draws).
    pub meshes: bool,
    /// Its clips (glTF animations, FBX takes).
    pub clips: usize,
    /// What the format calls a clip: "animation", "take".
    pub clip: &'static str,
    /// Whether it has a skeleton (glTF skins, FBX bones): a clip then most likely moves a character left out.
    pub skeleton: bool,
    /// Its curves and NURBS surfaces (FBX): shapes a modeller draws that are not polygon meshes.
    pub curves: usize,
}

/// Why a glTF or FBX file with nothing to draw (nor, in glTF, a light) cannot be a source, and the way out;
/// `None` when it draws something. A file without any mesh is most often an animation-only export, a skeleton
/// and its clips: Mixamo's "Without Skin" download, or an exporter asked for the animation alone.
pub fn nothing_drawn(path: &std::path::Path, h: Holds) -> Option<String> {
    if h.draws {
        return None;
    }
    let file = path.file_name().map_or_else(|| path.display().to_string(), |f| f.to_string_lossy().into_owned());
    Some(match h {
        Holds { meshes: true, .. } => {
            format!("`{file}`: nothing to render: no triangles or points (vvgen draws neither lines nor empty meshes)")
        }
        Holds { curves: 1.., .. } => format!(
            "`{file}` holds {} curve or NURBS object(s) and no polygon mesh: vvgen draws polygon meshes only (as \
             Blender's FBX importer, which skips them too); convert them before export (Maya: Modify > Convert > \
             NURBS to Polygons; 3ds Max: Convert To > Editable Poly; Blender: Object > Convert > Mesh)",
            h.curves
        ),
        Holds { clips: clips @ 1.., skeleton: true, nodes, clip, .. } => format!(
            "`{file}` holds {nodes} node(s) and {clips} {clip}(s) but no mesh: an animation-only export (a skeleton \
             and its motion, as Mixamo's \"Without Skin\" download); download or export the character with its mesh \
             (Mixamo: \"With Skin\"), or in Blender apply the motion to the character and name the .blend"
        ),
        Holds { nodes, clips, clip, .. } => {
            let moving = if clips > 0 { format!(" and {clips} {clip}(s)") } else { String::new() };
            let what = if nodes > 0 { " (cameras, lights or empty nodes)" } else { "" };
            format!(
                "`{file}` holds {nodes} node(s){moving} and no mesh{what}: nothing to render; name a file with the \
                 subject's mesh"
            )
        }
    })
}

fn select_clips(asset: &GltfAsset, sel: &Clips) -> Result<Vec<usize>, String> {
    let n = asset.animations.len();
    let find = |r: &Clip| -> Result<usize, String> {
        match r {
            Clip::Index(i) if *i < n => Ok(*i),
            Clip::Index(i) => Err(format!("{}: there is no animation {i} (the file has {n})", asset.path.display())),
            Clip::Name(name) => {
                asset.animations.iter().position(|a| a.name.as_deref() == Some(name)).ok_or_else(|| {
                    let names: Vec<String> = asset
                        .animations
                        .iter()
                        .enumerate()
                        .map(|(i, a)| a.name.clone().unwrap_or(format!("#{i}")))
                        .collect();
                    format!("{}: no animation named `{name}` (clips: {})", asset.path.display(), names.join(", "))
                })
            }
        }
    };
    match sel {
        Clips::First => Ok(if n > 0 { vec![0] } else { vec![] }),
        Clips::All => Ok((0..n).collect()),
        Clips::These(v) => v.iter().map(find).collect(),
    }
}

/// Whether a file is a PLY, by its extension.
pub(crate) fn is_ply(path: &std::path::Path) -> bool {
    path.extension().is_some_and(|e| e.eq_ignore_ascii_case("ply"))
}

/// Whether a file is an OBJ, by its extension.
pub(crate) fn is_obj(path: &std::path::Path) -> bool {
    path.extension().is_some_and(|e| e.eq_ignore_ascii_case("obj"))
}

pub(crate) use super::drc::is_drc;
pub(crate) use super::stl::is_stl;
pub use super::way_out::way_out_of;

/// The times (seconds from the clip's start) of an animated source's frames: `frames`, else the clip's whole
/// `duration` at its rate. The manifest bounds `frames`; a whole clip longer than
/// [`super::input::MAX_FRAMES`] frames (exporters leave takes 92 hours long) is refused, saying how to
/// take part of it.
fn frame_times(f: &FrameRange, duration: f64, clip: &str) -> Result<Vec<f32>, String> {
    let fps = f.fps();
    let start = f.start.unwrap_or(0);
    let step = f.step() as i64;
    let end = match (f.end, f.count) {
        (Some(e), _) => e,
        (None, Some(c)) => start + (c as i64 - 1) * step,
        (None, None) => {
            let last = duration * fps + 1e-4;
            let max = super::input::MAX_FRAMES;
            if !last.is_finite() || last >= (max * f.step()) as f64 {
                return Err(format!(
                    "the {clip} is {duration:.3} s long: {:.0} frames at {fps} fps, more than {max}; take part of it \
                     with `frames = {{ count = N }}` (or `start` and `end`)",
                    last.floor() + 1.0
                ));
            }
            start.max(last.floor() as i64)
        }
    };
    Ok((start..=end).step_by(step as usize).map(|n| (n as f64 / fps) as f32).collect())
}

/// One frame of a mesh sequence, by its extension: OBJ (with MTL and textures), PLY (textured when it has
/// `comment TextureFile` and texture coordinates, per vertex or per face corner), STL, Draco (`.drc`), or glTF
/// posed at rest.
pub fn mesh_frame(path: &std::path::Path) -> Result<PosedScene, Error> {
    mesh_frame_at(path, [0.0; 3])
}

/// [`mesh_frame`] with `origin` subtracted from a PLY or OBJ frame's coordinates as they are read (the manifest
/// allows `origin` only where the frames are PLY or OBJ).
fn mesh_frame_at(path: &std::path::Path, origin: [f64; 3]) -> Result<PosedScene, Error> {
    let ext = path.extension().map(|e| e.to_string_lossy().to_ascii_lowercase()).unwrap_or_default();
    match ext.as_str() {
        "obj" => super::obj::scene_at(path, origin),
        "ply" => ply_scene_at(path, origin),
        "stl" => super::stl::scene(path),
        "drc" => super::drc::scene(path),
        _ => match way_out_of(path) {
            Some(message) => Err(Error::Mesh { path: path.to_path_buf(), line: None, message }),
            None => gltf_at_rest(path, None),
        },
    }
}

/// A glTF file's scene `scene` (default: the file's) posed at rest, in source space.
fn gltf_at_rest(path: &std::path::Path, scene: Option<usize>) -> Result<PosedScene, Error> {
    Ok(at_rest(&super::gltf::load(path, scene)?))
}

/// A glTF asset posed at rest (no clip), with its materials and textures.
fn at_rest(asset: &GltfAsset) -> PosedScene {
    let mut posed = PosedScene {
        materials: Arc::new(asset.materials.clone()),
        textures: Arc::clone(&asset.textures),
        ..Default::default()
    };
    asset.pose(&[], 0.0, Mat4::IDENTITY, &mut PoseScratch::default(), &mut posed);
    posed
}

/// The files one mesh-sequence frame is read from besides itself (an OBJ's MTL files and textures, a PLY's
/// `TextureFile`, a glTF's buffers and images): they key the frame with it.
pub fn mesh_frame_deps(path: &std::path::Path) -> Result<Vec<PathBuf>, Error> {
    let ext = path.extension().map(|e| e.to_string_lossy().to_ascii_lowercase()).unwrap_or_default();
    match ext.as_str() {
        "obj" => super::obj::scan(path),
        // Nothing beside it; its form and size checked (`vvgen check` runs this on every frame).
        "stl" => super::stl::check_file(path).map(|()| Vec::new()),
        "drc" => super::drc::check_file(path).map(|()| Vec::new()),
        "ply" => ply_textures(path),
        _ => Ok(beside(path, gltf_side_files(path)?)),
    }
}

/// A glTF frame's buffers and images beside it, relative to its folder (an error in the glTF's errors' form).
fn gltf_side_files(path: &std::path::Path) -> Result<Vec<PathBuf>, Error> {
    super::gltf::side_files(path).map_err(|message| Error::Gltf { path: path.to_path_buf(), message })
}

/// `rel` (a glTF's side files) placed in the glTF's folder.
fn beside(path: &std::path::Path, rel: Vec<PathBuf>) -> Vec<PathBuf> {
    let dir = folder_of(path);
    rel.into_iter().map(|r| dir.join(r)).collect()
}

/// [`mesh_frame_deps`] for keying: what a frame's own content decides (an OBJ's face indices and the libraries it
/// names, a PLY's texture name) is remembered by the stat cache for that content, so keying unchanged frames
/// reads none of them in full; the files they name are checked every time.
pub fn mesh_frame_deps_cached(path: &std::path::Path, stat: &crate::cache::StatCache) -> Result<Vec<PathBuf>, Error> {
    let ext = path.extension().map(|e| e.to_string_lossy().to_ascii_lowercase()).unwrap_or_default();
    match ext.as_str() {
        "obj" => super::obj::scan_cached(path, stat),
        "stl" | "drc" => Ok(Vec::new()),
        "ply" => ply_textures_cached(path, stat),
        _ => {
            // The names a glTF frame's JSON gives its buffers and images, remembered for that content (as
            // relative names: the same content elsewhere names the files beside it there).
            let io = |e| Error::Io { path: path.to_path_buf(), source: e };
            let names = stat
                .derived("gltf side files 2", path, || {
                    let files = gltf_side_files(path)?;
                    Ok::<_, Error>(serde_json::to_string(&files).expect("paths serialize"))
                })
                .map_err(io)??;
            Ok(beside(path, serde_json::from_str(&names).unwrap_or_default()))
        }
    }
}

/// Copies `rest` into `out` with `m` applied, reusing `out`'s buffers.
fn transform_into(rest: &PosedScene, m: Mat4, out: &mut PosedScene) {
    let t = VertexTransform::new(m);
    out.materials = rest.materials.clone();
    out.textures = rest.textures.clone();
    out.lights.clear();
    out.lights.extend(rest.lights.iter().map(|l| l.transformed(m)));
    out.primitives.truncate(rest.primitives.len());
    for (i, p) in rest.primitives.iter().enumerate() {
        if i == out.primitives.len() {
            out.primitives.push(PosedPrimitive {
                positions: Vec::new(),
                normals: Vec::new(),
                tangents: Vec::new(),
                ..p.clone()
            });
        }
        let o = &mut out.primitives[i];
        o.kind = p.kind;
        o.uvs = p.uvs.clone();
        o.colors = p.colors.clone();
        o.indices = p.indices.clone();
        o.material = p.material;
        o.object = p.object;
        o.gaussians = p.gaussians.as_ref().map(|g| g.transformed(t.linear()));
        o.positions.clear();
        o.positions.extend(p.positions.iter().map(|&v| t.point(v)));
        o.normals.clear();
        o.normals.extend(p.normals.iter().map(|&n| t.normal(n)));
        o.tangents.clear();
        o.tangents.extend(p.tangents.iter().map(|&v| t.tangent(v)));
    }
}

/// `scene` transformed by `m` in place: what [`transform_into`] copies out of a scene it borrows, bit for bit.
fn transformed(mut scene: PosedScene, m: Mat4) -> PosedScene {
    let t = VertexTransform::new(m);
    for l in &mut scene.lights {
        *l = l.transformed(m);
    }
    for p in &mut scene.primitives {
        p.positions.iter_mut().for_each(|v| *v = t.point(*v));
        p.normals.iter_mut().for_each(|n| *n = t.normal(*n));
        p.tangents.iter_mut().for_each(|v| *v = t.tangent(*v));
        p.gaussians = p.gaussians.take().map(|g| g.transformed(t.linear()));
    }
    scene
}

/// What a transform does to a vertex's position, normal and tangent: one definition for [`transform_into`] and
/// [`transformed`], so the copy and the in-place transform agree bit for bit.
struct VertexTransform {
    m: Mat4,
    /// The normals' matrix (the cofactor matrix: right under non-uniform scale and mirroring).
    nm: glam::Mat3,
}

impl VertexTransform {
    fn new(m: Mat4) -> VertexTransform {
        VertexTransform { m, nm: super::gltf::pose::normal_matrix(&m) }
    }

    #[inline]
    fn point(&self, v: Vec3) -> Vec3 {
        self.m.transform_point3(v)
    }

    /// The linear part, which carries a Gaussian's covariance.
    fn linear(&self) -> glam::Mat3 {
        glam::Mat3::from_mat4(self.m)
    }

    #[inline]
    fn normal(&self, n: Vec3) -> Vec3 {
        (self.nm * n).normalize_or_zero()
    }

    #[inline]
    fn tangent(&self, t: Vec4) -> Vec4 {
        super::gltf::pose::tangent(&self.m, t)
    }
}

/// The ground plane's geometry at height `z`, in world space: a double-sided diffuse rectangle facing +Z (two
/// triangles) that receives shadows and casts none. Lit shading reads the environment's visibility over it from
/// a grid (`render::light`), not from its vertices.
pub fn ground(p: &Ground, z: f32) -> PosedScene {
    let [w, d] = p.size.map(|v| v as f32 * 0.5);
    let corners = [Vec3::new(-w, -d, z), Vec3::new(w, -d, z), Vec3::new(w, d, z), Vec3::new(-w, d, z)];
    let c = p.color.map(|v| v as f32);
    let material = Material {
        base_color: Vec4::new(c[0], c[1], c[2], 1.0),
        double_sided: true,
        metallic: 0.0,
        roughness: 1.0,
        specular: 0.0,
        casts_shadows: false,
        ..Material::default()
    };
    PosedScene::quad(corners, Vec3::Z, material)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::light::{Light, LightKind};
    use crate::scene::PrimKind;

    #[test]
    fn transformed_in_place_matches_the_copy_bit_for_bit() {
        let mut scene = PosedScene::single(
            PrimKind::Triangles,
            vec![Vec3::new(0.1, 2.0, -3.0), Vec3::new(1.0, 0.0, 0.5), Vec3::new(-0.7, 0.3, 0.9)],
            vec![Vec3::X, Vec3::new(0.0, 0.6, 0.8), Vec3::ZERO],
            vec![Vec4::ONE; 3],
            vec![0, 1, 2],
            Material::default(),
        );
        scene.primitives[0].tangents = vec![Vec4::new(0.0, 1.0, 0.0, -1.0); 3];
        scene.lights.push(Light {
            kind: LightKind::Point { position: Vec3::new(1.0, 2.0, 3.0), radius: 0.1 },
            color: Vec3::ONE,
            intensity: 100.0,
            shadows: true,
        });
        // Rotation, non-uniform scale and translation: normals and tangents take different matrices.
        let m = Mat4::from_scale_rotation_translation(
            Vec3::new(2.0, 0.5, 1.5),
            glam::Quat::from_euler(glam::EulerRot::XYZ, 0.3, -1.1, 2.0),
            Vec3::new(0.25, -4.0, 7.0),
        );
        let mut copy = PosedScene::default();
        transform_into(&scene, m, &mut copy);
        let moved = transformed(scene, m);
        assert_eq!(moved.lights, copy.lights);
        let (a, b) = (&moved.primitives[0], &copy.primitives[0]);
        let bits = |v: &[Vec3]| v.iter().flat_map(|v| v.to_array().map(f32::to_bits)).collect::<Vec<_>>();
        assert_eq!(bits(&a.positions), bits(&b.positions));
        assert_eq!(bits(&a.normals), bits(&b.normals));
        let tbits = |v: &[Vec4]| v.iter().flat_map(|v| v.to_array().map(f32::to_bits)).collect::<Vec<_>>();
        assert_eq!(tbits(&a.tangents), tbits(&b.tangents));
        assert_ne!(a.positions[0], Vec3::new(0.1, 2.0, -3.0), "the transform applies");
    }
}
