//! The plan: a manifest and its scene's frame count → the explicit list of images to render, each a
//! (split, view, frame) with its camera and normalized time. Everything after this (rendering, caching, writing)
//! works from this list, so what a build will do is known before it does anything.

pub mod keys;

use std::collections::BTreeSet;

use glam::DMat4;

use crate::manifest::split::TimeMode;
use crate::manifest::Manifest;
use crate::render::Camera;
use crate::rig::{self, random::Keyed, Identity};

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
    pub fn new(m: &Manifest, frames: usize) -> Result<Plan, String> {
        let (w, h) = m.render.size();
        let (fx, fy, cx, cy) = m.render.intrinsics();
        let (near, far) = (m.render.near.unwrap_or(0.05), m.render.far.unwrap_or(1000.0));
        let mut plan = Plan { splits: Vec::new(), images: Vec::new(), frames, warnings: Vec::new() };
        for (si, (name, split)) in m.splits.iter().enumerate() {
            let rig_name = split.rig.get_ref();
            let rig = m.rigs.get(rig_name).ok_or_else(|| format!("split `{name}`: no rig `{rig_name}`"))?;
            let selected: Vec<usize> = match &split.frames {
                Some(f) => {
                    let s: BTreeSet<u64> = f.get_ref().select(frames as u64).into_iter().collect();
                    s.into_iter().map(|f| f as usize).collect()
                }
                None => (0..frames).collect(),
            };
            if selected.is_empty() {
                return Err(format!("split `{name}` selects no frames of the scene's {frames}"));
            }
            let views = match (split.views.as_ref(), split.time) {
                (Some(v), _) => *v.get_ref(),
                // Monocular without a count: one camera per frame.
                (None, TimeMode::Monocular) => selected.len() as u32,
                (None, _) => 0,
            };
            let seed = split_seed(m, name);
            let poses = rig::poses(rig, Identity { rig: rig_name, seed }, views, &m.dir)
                .map_err(|e| format!("split `{name}`, rig `{rig_name}`: {e}"))?;
            if poses.is_empty() {
                return Err(format!("split `{name}` has no cameras"));
            }
            let pairs: Vec<(usize, u32)> = match split.time {
                TimeMode::All => selected.iter().flat_map(|&f| (0..poses.len() as u32).map(move |v| (f, v))).collect(),
                TimeMode::Monocular => {
                    selected.iter().enumerate().map(|(i, &f)| (f, (i % poses.len()) as u32)).collect()
                }
                TimeMode::Random => {
                    let want = split.pairs.as_ref().map(|p| *p.get_ref() as usize).unwrap_or(0);
                    random_pairs(seed, want, &selected, poses.len())
                }
            };
            let base = plan.images.len();
            for (index, &(frame, view)) in pairs.iter().enumerate() {
                let camera = Camera { width: w, height: h, fx, fy, cx, cy, near, far, c2w: poses[view as usize] };
                plan.images.push(Image { split: si, view, frame, time: time_of(frame, frames), index, camera });
            }
            plan.splits.push(SplitPlan {
                name: name.clone(),
                poses,
                frames: selected,
                time: split.time,
                images: (base..plan.images.len()).collect(),
            });
        }
        plan.check_shared_poses(m);
        Ok(plan)
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
