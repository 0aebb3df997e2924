//! The plan: a manifest and its scene → the explicit list of images (each a (split, view, frame) with its camera
//! and normalized time, [`Plan`]) and the graph of every action a build runs ([`graph::Graph`]), each keyed by
//! one canonical walk ([`key`], [`actions`]). Everything after this (executing, caching, writing) works from the
//! graph, so what a build will do is known, and explained, before it does anything.

pub mod actions;
pub mod coverage;
pub mod graph;
pub mod key;
pub mod keys;
pub mod preview;
pub mod walk;

use std::collections::BTreeSet;
use std::path::PathBuf;

use glam::DMat4;

use crate::camera::Camera;
use crate::manifest::rig::RigKind;
use crate::manifest::split::TimeMode;
use crate::manifest::Manifest;
use crate::rig::{self, random::Keyed, Identity};

/// What can go wrong planning a build. Every variant but [`Error::Input`] is decided by the manifest and its
/// inputs' content (exit 2 at the CLI).
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A split names a rig that does not exist.
    #[error("split `{split}`: no rig `{rig}`")]
    NoRig {
        /// The split.
        split: String,
        /// The rig it names.
        rig: String,
    },
    /// A split's frame selection is empty.
    #[error("split `{split}` selects no frames of the scene's {frames}")]
    NoFrames {
        /// The split.
        split: String,
        /// Frames in the scene.
        frames: usize,
    },
    /// A rig cannot place its cameras.
    #[error("split `{split}`, rig `{rig}`")]
    Rig {
        /// The split.
        split: String,
        /// The rig.
        rig: String,
        /// Why.
        #[source]
        source: crate::rig::Error,
    },
    /// A split has no cameras.
    #[error("split `{split}` has no cameras")]
    NoCameras {
        /// The split.
        split: String,
    },
    /// A camera is not finite (a degenerate rig: a target at the camera, a non-finite setting).
    #[error("split `{split}`, view {view}: the camera is not finite (is the target at the camera position?)")]
    NonFinite {
        /// The split.
        split: String,
        /// The view.
        view: usize,
    },
    /// An output's splits hold no images.
    #[error("output `{output}` has no images (its splits are empty)")]
    NoImages {
        /// The output.
        output: String,
    },
    /// An output names a split that does not exist.
    #[error("no split `{split}`")]
    NoSplit {
        /// The split.
        split: String,
    },
    /// A writer needs a pass `[render] passes` does not ask for.
    #[error("output `{output}`: the `{pass}` pass is needed for this writer; add it to `[render] passes`")]
    NeedsPass {
        /// The output.
        output: String,
        /// The pass.
        pass: &'static str,
    },
    /// The DyNeRF layout needs synchronized video.
    #[error(
        "split `{split}`: the dynerf layout needs every camera at every frame (time = \"all\" over the same frames; \
         a path split is written beside them as one video)"
    )]
    NotSynchronized {
        /// The split.
        split: String,
    },
    /// A zooming path split in an output whose format holds one focal length.
    #[error(
        "output `{output}` ({writer}) writes split `{split}`, whose path's field of view is not [render]'s, and \
         {writer} records one focal length, [render]'s: write that split with a nerfstudio output (per-frame \
         fl_x, fl_y), or give the path [render]'s field of view"
    )]
    Zoom {
        /// The output.
        output: String,
        /// Its writer.
        writer: &'static str,
        /// The split.
        split: String,
    },
    /// A D-NeRF split name K-Planes would misread.
    #[error("split `{split}`: K-Planes misreads D-NeRF file paths containing `_r`; rename the split")]
    SplitName {
        /// The split.
        split: String,
    },
    /// A point output names a source that does not exist.
    #[error("output `{output}`: no source `{source_name}`")]
    NoSource {
        /// The output.
        output: String,
        /// The source it names.
        source_name: String,
    },
    /// A point output's settings contradict each other or the scene.
    #[error("output `{output}` (ply-sequence): {why}")]
    PointSettings {
        /// The output.
        output: String,
        /// Why.
        why: String,
    },
    /// An input file cannot be read while keying it.
    #[error("{}", path.display())]
    Input {
        /// The file.
        path: PathBuf,
        /// Why.
        #[source]
        source: std::io::Error,
    },
    /// Posing a frame to key it failed.
    #[error(transparent)]
    Scene(#[from] crate::scene::Error),
}

/// Poses of two splits closer than this (in every matrix entry) count as shared.
const SHARED_POSE_EPS: f64 = 1e-6;

/// One image to render.
#[derive(Debug, Clone)]
pub struct Image {
    /// Index into [`Plan::splits`].
    pub split: usize,
    /// View (camera) index within the split.
    pub view: u32,
    /// Scene frame.
    pub frame: usize,
    /// `frame / (frames − 1)`, in [0, 1] (0 for a single-frame scene).
    pub time: f64,
    /// Position in the split's time-major order (the `r_<index>` of NeRF-style names).
    pub index: usize,
    /// Intrinsics and pose.
    pub camera: Camera,
}

/// One split's part of the plan.
#[derive(Debug, Clone)]
pub struct SplitPlan {
    /// Split name.
    pub name: String,
    /// The split's camera poses (OpenGL camera-to-world), by view.
    pub poses: Vec<DMat4>,
    /// The split's selected frames, ascending.
    pub frames: Vec<usize>,
    /// How views meet time.
    pub time: TimeMode,
    /// Whether the split's camera moves (a `path` rig): view `i` is the pose at its `i`-th frame.
    pub moving: bool,
    /// Indices into [`Plan::images`], time-major: by frame, then view.
    pub images: Vec<usize>,
}

/// Every image of a build.
#[derive(Debug, Clone)]
pub struct Plan {
    /// Splits in manifest (name) order.
    pub splits: Vec<SplitPlan>,
    /// Images, grouped split by split in time-major order.
    pub images: Vec<Image>,
    /// Frames in the scene.
    pub frames: usize,
    /// Non-fatal findings (shared poses between splits).
    pub warnings: Vec<String>,
}

/// The default seed of a split: the manifest's, or one derived from the dataset seed and the split's name, so
/// splits sharing a rig draw different cameras.
pub fn split_seed(m: &Manifest, split: &str) -> u64 {
    m.splits.get(split).and_then(|s| s.seed).unwrap_or_else(|| rig::random::derive_seed(m.dataset.seed, split))
}

/// The normalized time of `frame` among `frames`.
pub fn time_of(frame: usize, frames: usize) -> f64 {
    if frames <= 1 {
        0.0
    } else {
        frame as f64 / (frames - 1) as f64
    }
}

impl Plan {
    /// Plans every split of `m` over a scene of `frames` frames.
    pub fn new(m: &Manifest, frames: usize) -> Result<Plan, Error> {
        let (w, h) = m.render.size();
        let (fx, fy, cx, cy) = m.render.intrinsics();
        let (near, far) = (m.render.near.unwrap_or(0.05), m.render.far.unwrap_or(1000.0));
        let mut plan = Plan { splits: Vec::new(), images: Vec::new(), frames, warnings: Vec::new() };
        for (si, (name, split)) in m.splits.iter().enumerate() {
            let rig_name = split.rig();
            let rig =
                m.rigs.get(rig_name).ok_or_else(|| Error::NoRig { split: name.clone(), rig: rig_name.to_string() })?;
            let selected: Vec<usize> = match split.frames() {
                Some(f) => {
                    let s: BTreeSet<u64> = f.select(frames as u64).into_iter().collect();
                    s.into_iter().map(|f| f as usize).collect()
                }
                None => (0..frames).collect(),
            };
            if selected.is_empty() {
                return Err(Error::NoFrames { split: name.clone(), frames });
            }
            let views = match (split.views(), split.time) {
                (Some(v), _) => v,
                // Monocular without a count: one camera per frame.
                (None, TimeMode::Monocular) => selected.len() as u32,
                (None, _) => 0,
            };
            let seed = split_seed(m, name);
            let rig_err = |source| Error::Rig { split: name.clone(), rig: rig_name.to_string(), source };
            let path = rig.kind() == RigKind::Path;
            // Per view, its focal lengths: `[render]`'s, but for a path that zooms.
            let mut focal: Option<Vec<(f64, f64)>> = None;
            let poses = if path {
                // One camera per selected frame, at that frame's time.
                let times: Vec<f64> = selected.iter().map(|&f| f as f64 * m.frame_period()).collect();
                let render_fov = 2.0 * (h as f64 / 2.0 / fy).atan().to_degrees();
                let placed = rig::path::poses(rig, &times, &m.dir, render_fov).map_err(rig_err)?;
                plan.warnings.extend(placed.note.map(|n| format!("split `{name}` (rig `{rig_name}`): {n}")));
                // The vertical field of view scales `[render]`'s focal lengths (their pixel aspect kept); at
                // `[render]`'s own field of view they are its, to the bit.
                focal = placed.fov_deg.map(|fovs| {
                    fovs.iter()
                        .map(|&fov| {
                            let k = if fov == render_fov {
                                1.0
                            } else {
                                (render_fov.to_radians() / 2.0).tan() / (fov.to_radians() / 2.0).tan()
                            };
                            (fx * k, fy * k)
                        })
                        .collect()
                });
                placed.poses
            } else {
                rig::poses(rig, Identity { rig: rig_name, seed }, views, &m.dir).map_err(rig_err)?
            };
            if let Some(view) = focal.iter().flatten().position(|(a, b)| !(a.is_finite() && b.is_finite() && *a > 0.0))
            {
                return Err(Error::NonFinite { split: name.clone(), view });
            }
            // A path pairs its i-th camera with the i-th selected frame.
            let time = if path { TimeMode::Monocular } else { split.time };
            if poses.is_empty() {
                return Err(Error::NoCameras { split: name.clone() });
            }
            // The last line of defence before anything is written: no NaN or infinity in a camera.
            if let Some(view) = poses.iter().position(|p| !p.is_finite()) {
                return Err(Error::NonFinite { split: name.clone(), view });
            }
            if ![fx, fy, cx, cy, near, far].iter().all(|v| v.is_finite()) {
                return Err(Error::NonFinite { split: name.clone(), view: 0 });
            }
            let pairs: Vec<(usize, u32)> = match time {
                TimeMode::All => selected.iter().flat_map(|&f| (0..poses.len() as u32).map(move |v| (f, v))).collect(),
                TimeMode::Monocular => {
                    selected.iter().enumerate().map(|(i, &f)| (f, (i % poses.len()) as u32)).collect()
                }
                TimeMode::Random => {
                    let want = split.pairs().map_or(0, |p| p as usize);
                    random_pairs(seed, want, &selected, poses.len())
                }
            };
            let base = plan.images.len();
            for (index, &(frame, view)) in pairs.iter().enumerate() {
                let (fx, fy) = focal.as_ref().map_or((fx, fy), |f| f[view as usize]);
                let camera = Camera { width: w, height: h, fx, fy, cx, cy, near, far, c2w: poses[view as usize] };
                plan.images.push(Image { split: si, view, frame, time: time_of(frame, frames), index, camera });
            }
            plan.splits.push(SplitPlan {
                name: name.clone(),
                poses,
                frames: selected,
                time,
                moving: path,
                images: (base..plan.images.len()).collect(),
            });
        }
        plan.check_shared_poses(m);
        plan.check_zooms(m)?;
        Ok(plan)
    }

    /// A path whose field of view is not `[render]`'s (a zoom, or another lens) goes only to writers that record
    /// intrinsics per image: nerfstudio (per-frame `fl_x`, `fl_y`) and, beside its cameras, dynerf (the path's
    /// camera file). The others have one camera model per file or per split, `[render]`'s.
    fn check_zooms(&self, m: &Manifest) -> Result<(), Error> {
        use crate::manifest::output::Writer;
        let (fx, fy, _, _) = m.render.intrinsics();
        for (name, out) in &m.outputs {
            let writer = out.writer();
            if !writer.renders_images() || matches!(writer, Writer::Nerfstudio | Writer::Dynerf) {
                continue;
            }
            for &i in &self.images_of(out)? {
                let img = &self.images[i];
                if (img.camera.fx, img.camera.fy) != (fx, fy) {
                    return Err(Error::Zoom {
                        output: name.clone(),
                        writer: writer.name(),
                        split: self.splits[img.split].name.clone(),
                    });
                }
            }
        }
        Ok(())
    }

    /// Warns when two splits share a camera pose, unless either allows it.
    fn check_shared_poses(&mut self, m: &Manifest) {
        for a in 0..self.splits.len() {
            for b in a + 1..self.splits.len() {
                let (sa, sb) = (&self.splits[a], &self.splits[b]);
                let allowed = |s: &SplitPlan| m.splits.get(&s.name).is_some_and(|s| s.allow_shared_poses);
                if allowed(sa) || allowed(sb) {
                    continue;
                }
                let shared =
                    sa.poses.iter().filter(|p| sb.poses.iter().any(|q| p.abs_diff_eq(*q, SHARED_POSE_EPS))).count();
                if shared > 0 {
                    self.warnings.push(format!(
                        "splits `{}` and `{}` share {shared} camera pose(s): evaluation would see training views \
                         (set `allow_shared_poses = true` on either split if that is intended)",
                        sa.name, sb.name
                    ));
                }
            }
        }
    }

    /// The images an image output writes: its splits' (all splits by default), split by split in manifest
    /// order, time-major within each.
    pub fn images_of(&self, out: &crate::manifest::Output) -> Result<Vec<usize>, Error> {
        let names: Vec<&str> = match out.splits() {
            Some(list) => list,
            None => self.splits.iter().map(|s| s.name.as_str()).collect(),
        };
        let mut v = Vec::new();
        for n in names {
            let s = self.splits.iter().find(|s| s.name == n).ok_or_else(|| Error::NoSplit { split: n.to_string() })?;
            v.extend(&s.images);
        }
        Ok(v)
    }

    /// The number of frames output `out` shows: those its splits' images select for a writer of images, the
    /// scene's for point clouds. What the consumers' frame-count limits apply to.
    pub fn output_frames(&self, out: &crate::manifest::Output) -> Result<usize, Error> {
        Ok(if out.writer().renders_images() { self.frames_of(&self.images_of(out)?).len() } else { self.frames })
    }

    /// Distinct frames of `images` (indices into [`Plan::images`]), ascending.
    pub fn frames_of(&self, images: &[usize]) -> Vec<usize> {
        let mut f: Vec<usize> = images.iter().map(|&i| self.images[i].frame).collect();
        f.sort_unstable();
        f.dedup();
        f
    }

    /// Images of frame `f`, as indices into [`Plan::images`].
    pub fn by_frame(&self) -> Vec<(usize, Vec<usize>)> {
        let mut v: Vec<(usize, Vec<usize>)> = Vec::new();
        let mut order: Vec<usize> = (0..self.images.len()).collect();
        order.sort_by_key(|&i| self.images[i].frame);
        for i in order {
            let f = self.images[i].frame;
            match v.last_mut() {
                Some((lf, list)) if *lf == f => list.push(i),
                _ => v.push((f, vec![i])),
            }
        }
        v
    }
}

/// `want` distinct (frame, view) pairs drawn from a stream keyed by the split seed, in time-major order.
fn random_pairs(seed: u64, want: usize, frames: &[usize], views: usize) -> Vec<(usize, u32)> {
    let total = frames.len() * views;
    let want = want.min(total);
    let mut chosen = BTreeSet::new();
    let mut k = Keyed::new("pairs", &[&seed.to_le_bytes()]);
    // Rejection is fine while few are taken; past half, a shuffle of all pairs is cheaper and still keyed.
    if want * 2 <= total {
        while chosen.len() < want {
            let i = k.below(total as u64) as usize;
            chosen.insert((frames[i / views], (i % views) as u32));
        }
    } else {
        let mut all: Vec<usize> = (0..total).collect();
        for i in (1..all.len()).rev() {
            all.swap(i, k.below(i as u64 + 1) as usize);
        }
        chosen.extend(all[..want].iter().map(|&i| (frames[i / views], (i % views) as u32)));
    }
    chosen.into_iter().collect()
}
