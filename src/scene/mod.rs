//! Scene sources: glTF, FBX, `.blend`, OBJ and PLY files → [`PosedScene`] at any frame, in world space after
//! their placements. What to load comes as a [`Request`] ([`input`]), in the scene's own terms. The transforms are resolved once per sequence when the scene opens ([`Scene::open`]), never per
//! frame, so the subject does not jump or breathe between frames.

pub mod blend;
pub mod drc;
pub mod fbx;
mod fbx_layers;
mod fbx_materials;
pub mod gaussians;
pub mod gltf;
pub mod input;
pub mod light;
pub mod material;
mod mtl;
pub mod obj;
mod obj_text;
pub mod ply;
mod ply_scene;
mod polygon;
pub mod posed;
pub mod source;
pub mod spacing;
pub mod stl;
pub mod texture;
pub mod transform;
mod way_out;

use std::path::PathBuf;
use std::sync::Arc;

use glam::{Mat4, Vec3};

pub use posed::{PosedPrimitive, PosedScene, PrimKind};
pub use source::{LoadedSource, SourceData};

use gltf::PoseScratch;
pub use input::Request;
use input::{Over, Placement, SourceRequest, UpAxis};
use transform::Stats;

/// What can go wrong opening or posing a scene. Every variant is a problem with the input (exit 2 at the CLI).
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A source file cannot be read.
    #[error("{}: cannot read", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// Why.
        #[source]
        source: std::io::Error,
    },
    /// A glTF file is malformed or uses what vvgen does not support.
    #[error("{}: {message}", path.display())]
    Gltf {
        /// The file.
        path: PathBuf,
        /// What is wrong, with the glTF object it is in (`accessor 3`, `animation 0 channel 2`).
        message: String,
    },
    /// An FBX file is malformed, over a limit, or refers to a texture that is missing.
    #[error("{}: {message}", path.display())]
    Fbx {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// A `.blend` file cannot be imported: no Blender, or Blender refused it or what the manifest selects.
    #[error("{}: {message}", path.display())]
    Blend {
        /// The file.
        path: PathBuf,
        /// What is wrong, and the ways out.
        message: String,
    },
    /// A PLY file is malformed.
    #[error("{}", path.display())]
    Ply {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        #[source]
        source: ply::PlyError,
    },
    /// A mesh frame (OBJ, its MTL, a texture, a textured PLY) is malformed or refers to a file that is missing.
    #[error("{}{}: {message}", path.display(), line.map(|l| format!(":{l}")).unwrap_or_default())]
    Mesh {
        /// The file.
        path: PathBuf,
        /// The 1-based line, when the problem has one.
        line: Option<usize>,
        /// What is wrong.
        message: String,
    },
    /// A source's settings do not fit its file (an animation it lacks, a sequence with no frames).
    #[error("source `{name}`: {message}")]
    Source {
        /// The source.
        name: String,
        /// What is wrong.
        message: String,
    },
    /// A source names a clip its file lacks.
    #[error("source `{name}`: {message}")]
    Clip {
        /// The source.
        name: String,
        /// Which clip, and the clips there are.
        message: String,
    },
    /// A `[transform]` cannot be resolved (fitting a source with no extent).
    #[error("{table}")]
    Transform {
        /// `source `NAME`` or `[transform]`.
        table: String,
        /// What is wrong.
        #[source]
        source: transform::Error,
    },
    /// A sequence's frames cannot be listed.
    #[error("source `{name}`: {message}")]
    Sequence {
        /// The source.
        name: String,
        /// What is wrong (a malformed pattern, a missing frame file).
        message: String,
    },
}

/// Every source of a [`Request`], loaded, with its resolved placement.
#[derive(Debug)]
pub struct Scene {
    /// Sources, sorted by name.
    pub sources: Vec<LoadedSource>,
    /// Per-source transform (the source's `[transform]` with its up axis), source → scene.
    pub locals: Vec<Mat4>,
    /// The global `[transform]`, scene → world.
    pub global: Mat4,
    /// Frames of the scene: the longest source's count (shorter sources hold their last frame).
    pub frames: usize,
    /// Non-fatal problems found while loading.
    pub warnings: Vec<String>,
    /// Whether the sources' own lights (glTF `KHR_lights_punctual`) are posed with them: in `pbr` renders
    /// unless `[render] gltf_lights = false`. When not, posed frames carry no lights, so nothing keys or
    /// shades them.
    pub file_lights: bool,
    /// The first point cloud (a sequence, or a source of points only) and one voxel of it in its source units,
    /// the default splat size ([`spacing`]): 1 where its (first frame's) coordinates are whole numbers (8i,
    /// vsense), else the distance within which nine of its points in ten have a neighbour; `None` without a
    /// cloud, or when its points give no such distance.
    pub voxel: Option<(usize, f32)>,
}

/// Reusable buffers for posing a scene; posing a single-source scene after its first frame allocates nothing.
#[derive(Debug, Default)]
pub struct Poser {
    scratch: Vec<PoseScratch>,
    parts: Vec<PosedScene>,
    out: PosedScene,
}

impl Poser {
    /// Where source `i`'s primitives begin among those of the frame [`Scene::pose`] last posed whole with this
    /// poser (it puts every source's after those of the sources before it, in order).
    pub fn first_primitive_of(&self, i: usize) -> usize {
        self.parts.iter().take(i).map(|p| p.primitives.len()).sum()
    }
}

/// [`Scene::voxel`] of `sources`: their first point cloud's, a sequence's first frame (read once more) or a
/// static cloud (a source of points only). (A sequence in metres took one unit for its voxel before, and its
/// splats, each the subject's size many times over, were all dropped at the near plane: empty images; a static
/// cloud took 1.5 pixels, holes between the points of any cloud not dense for the image.)
fn first_voxel(sources: &[LoadedSource]) -> Result<Option<(usize, f32)>, Error> {
    for (i, src) in sources.iter().enumerate() {
        let measure = |points: &[Vec3]| {
            let v = if spacing::on_whole_grid(points) { Some(1.0) } else { spacing::typical(points) };
            v.map(|v| (i, v))
        };
        match &src.data {
            SourceData::Sequence(frames) => {
                let Some(first) = frames.first() else { continue };
                let frame = source::ply_scene_at(&first.path, src.origin)?;
                return Ok(measure(frame.primitives.first().map_or(&[][..], |p| &p.positions[..])));
            }
            SourceData::Static(rest)
                if !rest.primitives.is_empty() && rest.primitives.iter().all(|p| p.kind == PrimKind::Points) =>
            {
                let points: Vec<Vec3> = rest.primitives.iter().flat_map(|p| p.positions.iter().copied()).collect();
                return Ok(measure(&points));
            }
            _ => {}
        }
    }
    Ok(None)
}

impl Scene {
    /// Loads every source and resolves the placements (reading every frame once when a placement needs the
    /// bounds of all frames). A `.blend` source needs [`Scene::open_importing`].
    pub fn open(req: &Request) -> Result<Scene, Error> {
        Scene::open_importing(req, None)
    }

    /// [`Scene::open`], importing `.blend` sources through `importer` (a cache).
    pub fn open_importing(req: &Request, importer: Option<&blend::Importer>) -> Result<Scene, Error> {
        let mut sources = Vec::new();
        for s in &req.sources {
            sources.push(LoadedSource::load(s, importer)?);
        }
        let mut warnings: Vec<String> = sources.iter().flat_map(|s| s.warnings.iter().cloned()).collect();
        for (s, r) in sources.iter().zip(&req.sources) {
            if let SourceData::Gltf { asset, clips, times } = &s.data {
                warnings.extend(asset.warnings.iter().map(|w| format!("{}: {w}", asset.path.display())));
                warnings.extend(held_frames(&s.name, asset, clips, times, &r.frames));
            }
        }
        let mut scratch = PoseScratch::default();
        let mut posed = PosedScene::default();
        let mut locals = Vec::new();
        let reach = req.reach.as_ref();
        for (src, SourceRequest { placement: t, .. }) in sources.iter().zip(&req.sources) {
            if src.ground.is_some() {
                // Placed in world units: no transform, and no part in fitting the others.
                locals.push(Mat4::IDENTITY);
                continue;
            }
            let up = t.up.unwrap_or(src.default_up);
            let over = t.over;
            let pre = transform::pre(t, up).as_mat4();
            let mut stats = Stats::default();
            if transform::needs_stats(t) {
                gather(src, pre, over, &mut scratch, &mut posed, &mut |p| stats.add(p))?;
                let to_file = pre.as_dmat4().inverse();
                warnings.extend(stats.far_from_origin(to_file).map(|w| format!("source `{}`: {w}", src.name)));
            }
            if let Some(c) = transform::frame_centre(t, &stats) {
                gather(src, pre, over, &mut scratch, &mut posed, &mut |p| stats.far = stats.far.max(farthest(p, c)))?;
            }
            let table = || format!("source `{}`", src.name);
            locals.push(
                transform::resolve(t, up, &stats, reach)
                    .map_err(|source| Error::Transform { table: table(), source })?,
            );
        }
        // The global placement's `up` is only the sources' default: the rotation was applied per source.
        let g = Placement { up: None, ..req.global.clone() };
        let g_pre = transform::pre(&g, UpAxis::Z).as_mat4();
        let mut stats = Stats::default();
        let over = g.over;
        let fitted = || sources.iter().zip(&locals).filter(|(s, _)| s.ground.is_none());
        if transform::needs_stats(&g) {
            for (src, local) in fitted() {
                // Per source, to name the one whose coordinates are too far out for single precision.
                let mut own = Stats::default();
                gather(src, g_pre * *local, over, &mut scratch, &mut posed, &mut |p| {
                    own.add(p);
                    stats.add(p);
                })?;
                let to_file = (g_pre * *local).as_dmat4().inverse();
                warnings.extend(own.far_from_origin(to_file).map(|w| format!("source `{}`: {w}", src.name)));
            }
        }
        if let Some(c) = transform::frame_centre(&g, &stats) {
            for (src, local) in fitted() {
                let far = &mut stats.far;
                gather(src, g_pre * *local, over, &mut scratch, &mut posed, &mut |p| *far = far.max(farthest(p, c)))?;
            }
        }
        let global = transform::resolve(&g, UpAxis::Z, &stats, reach)
            .map_err(|source| Error::Transform { table: "[transform]".into(), source })?;
        let frames = sources.iter().map(LoadedSource::frame_count).max().unwrap_or(0);
        let file_lights = req.file_lights;
        let voxel = first_voxel(&sources)?;
        let mut scene = Scene { sources, locals, global, frames, warnings, file_lights, voxel };
        scene.place_ground(&mut scratch, &mut posed)?;
        Ok(scene)
    }

    /// Checks every frame file of the sequences as the build will find it, without posing: a mesh sequence's
    /// frames are scanned (an OBJ's face indices, its MTL files and textures; a PLY's header and texture), as the
    /// build's keying will, and a PLY sequence's frames have their headers checked and their sizes against the
    /// rows they declare; so `vvgen check` names a broken frame's file and line before anything renders.
    pub fn check_frame_files(&self) -> Result<(), Error> {
        for src in &self.sources {
            match &src.data {
                SourceData::MeshSequence(files) => {
                    for f in files {
                        source::mesh_frame_deps(&f.path)?;
                    }
                }
                SourceData::Sequence(files) => {
                    for f in files {
                        // Its header, and the textures a textured mesh's names.
                        source::ply_textures(&f.path)?;
                    }
                }
                _ => {}
            }
        }
        Ok(())
    }

    /// Makes the ground planes' geometry: at their `z`, or at the lowest point of the other sources over all
    /// their frames (read once here, like a fitted transform's bounds).
    fn place_ground(&mut self, scratch: &mut PoseScratch, posed: &mut PosedScene) -> Result<(), Error> {
        let mut lowest = 0.0;
        if self.sources.iter().any(|s| s.ground.is_some_and(|g| g.z.is_none())) {
            let mut stats = Stats::default();
            for i in 0..self.sources.len() {
                if self.sources[i].ground.is_none() {
                    gather(&self.sources[i], self.world_from_source(i), Over::AllFrames, scratch, posed, &mut |p| {
                        stats.add(p)
                    })?;
                }
            }
            if stats.count > 0 {
                lowest = stats.lo.z as f32;
            }
        }
        for s in &mut self.sources {
            if let Some(g) = s.ground {
                s.data = SourceData::Static(source::ground(&g, g.z.map_or(lowest, |z| z as f32)));
            }
        }
        Ok(())
    }

    /// Source → world matrix of source `i` (identity for a ground plane, placed in world units).
    pub fn world_from_source(&self, i: usize) -> Mat4 {
        if self.sources[i].ground.is_some() {
            return Mat4::IDENTITY;
        }
        self.global * self.locals[i]
    }

    /// World size of one voxel of the first point cloud ([`Scene::voxel`]), the default splat size.
    pub fn voxel_size(&self) -> Option<f32> {
        let (i, v) = self.voxel?;
        Some(v * self.world_from_source(i).x_axis.truncate().length())
    }

    /// Whether some source reads a file per frame (PLY or mesh sequences): posing a frame then costs a read,
    /// where other sources pose from memory.
    pub fn reads_frame_files(&self) -> bool {
        self.sources.iter().any(|s| matches!(s.data, SourceData::Sequence(_) | SourceData::MeshSequence(_)))
    }

    /// Whether any source draws points: a PLY sequence, a PLY cloud, or glTF points (judged on frame 0).
    pub fn has_points(&self) -> bool {
        let mut poser = Poser::default();
        (0..self.sources.len()).any(|i| match &self.sources[i].data {
            SourceData::Sequence(_) => true,
            _ => self.pose_source(i, 0, &mut poser).is_ok_and(|p| p.point_count() > 0),
        })
    }

    /// Poses frame `frame` of source `i` alone, in world space.
    pub fn pose_source<'a>(&self, i: usize, frame: usize, poser: &'a mut Poser) -> Result<&'a PosedScene, Error> {
        poser.scratch.resize_with(self.sources.len(), PoseScratch::default);
        self.sources[i].pose(frame, self.world_from_source(i), &mut poser.scratch[i], &mut poser.out)?;
        if !self.file_lights {
            poser.out.lights.clear();
        }
        Ok(&poser.out)
    }

    /// Index of the source called `name`.
    pub fn source_index(&self, name: &str) -> Option<usize> {
        self.sources.iter().position(|s| s.name == name)
    }

    /// Poses frame `frame` of every source, in world space.
    pub fn pose<'a>(&self, frame: usize, poser: &'a mut Poser) -> Result<&'a PosedScene, Error> {
        let n = self.sources.len();
        poser.scratch.resize_with(n, PoseScratch::default);
        if n == 1 {
            self.sources[0].pose(frame, self.world_from_source(0), &mut poser.scratch[0], &mut poser.out)?;
        } else {
            poser.parts.resize_with(n, PosedScene::default);
            for i in 0..n {
                self.sources[i].pose(frame, self.world_from_source(i), &mut poser.scratch[i], &mut poser.parts[i])?;
            }
            merge(&poser.parts, &mut poser.out);
        }
        if !self.file_lights {
            poser.out.lights.clear();
        }
        Ok(&poser.out)
    }
}

/// Accumulates the bounds of `src`'s frames (`over`) after `post`.
/// A warning when frames run past the end of the clips they play (they would all hold its last pose), with the
/// clip's length and the frame count that covers it.
fn held_frames(
    name: &str,
    asset: &gltf::GltfAsset,
    clips: &[usize],
    times: &[f32],
    f: &input::FrameRange,
) -> Option<String> {
    let longest = clips
        .iter()
        .copied()
        .max_by(|a, b| asset.animations[*a].duration().total_cmp(&asset.animations[*b].duration()))?;
    let duration = asset.animations[longest].duration();
    let (fps, start, step) = (f.fps(), f.start.unwrap_or(0), f.step() as i64);
    // A frame a little past the end (the clip's length is rarely a whole number of frames) is not held.
    let held = times.iter().filter(|&&t| t as f64 > duration as f64 + 1.0 / fps + 1e-6).count();
    if held == 0 || duration <= 0.0 {
        return None;
    }
    let covers = (((duration as f64 * fps + 1e-4).floor() as i64 - start).max(0) / step + 1).max(1);
    let clip = asset.animations[longest].name.clone().unwrap_or_else(|| format!("#{longest}"));
    Some(format!(
        "source `{name}`: clip `{clip}` lasts {duration:.2} s, so {held} of its {} frames at {fps} fps hold its last \
         pose; frames = {{ count = {covers}, fps = {fps} }} covers it",
        times.len()
    ))
}

/// The distance of the point of `points` farthest from `c`.
fn farthest(points: &[glam::Vec3], c: glam::DVec3) -> f64 {
    points.iter().map(|p| p.as_dvec3().distance_squared(c)).fold(0.0, f64::max).sqrt()
}

/// Shows `visit` the positions of every frame `over` selects of `src`, after `post`, in frame order.
fn gather(
    src: &LoadedSource,
    post: Mat4,
    over: Over,
    scratch: &mut PoseScratch,
    posed: &mut PosedScene,
    visit: &mut dyn FnMut(&[glam::Vec3]),
) -> Result<(), Error> {
    let frames = if over == Over::First { 1 } else { src.frame_count() };
    // Fresh buffers per source (another source's materials must not carry over), reused across its frames.
    *posed = PosedScene::default();
    if matches!(src.data, SourceData::Sequence(_) | SourceData::MeshSequence(_)) {
        // One file per frame: reading them is the cost, so read a few at once (as many as there are threads,
        // which bounds the memory), and add their points in frame order, as the sequential loop would.
        use rayon::prelude::*;
        let window = rayon::current_num_threads().max(1);
        for start in (0..frames).step_by(window) {
            let read: Vec<Result<PosedScene, Error>> = (start..(start + window).min(frames))
                .into_par_iter()
                .map(|f| {
                    let mut out = PosedScene::default();
                    src.pose(f, post, &mut PoseScratch::default(), &mut out)?;
                    Ok(out)
                })
                .collect();
            for frame in read {
                for p in &frame?.primitives {
                    visit(&p.positions);
                }
            }
        }
        return Ok(());
    }
    for f in 0..frames {
        src.pose(f, post, scratch, posed)?;
        for p in &posed.primitives {
            visit(&p.positions);
        }
    }
    Ok(())
}

/// Concatenates several posed scenes (sources, or parts a caller builds) into `out`, in order, renumbering
/// materials, textures and objects; lights are kept as they are.
pub fn merge(parts: &[PosedScene], out: &mut PosedScene) {
    let mut materials = Vec::new();
    let mut textures = Vec::new();
    out.primitives.clear();
    out.lights.clear();
    let mut object_base = 0;
    for part in parts {
        out.lights.extend(part.lights.iter().cloned());
        let (mb, tb) = (materials.len() as u32, textures.len() as u32);
        materials.extend(part.materials.iter().cloned().map(|mut m: material::Material| {
            for (t, _) in m.texture_refs_mut() {
                t.texture += tb;
            }
            m
        }));
        textures.extend(part.textures.iter().cloned());
        let mut max_object = 0;
        for p in &part.primitives {
            let mut q = p.clone();
            q.material += mb;
            q.object += object_base;
            max_object = max_object.max(p.object + 1);
            out.primitives.push(q);
        }
        object_base += max_object;
    }
    out.materials = Arc::new(materials);
    out.textures = Arc::new(textures);
}
