//! `[rig.NAME]`: camera placement recipes. The number of views comes from the split that uses the rig.

use std::ops::Range;

use serde::Deserialize;
use toml::Spanned;

use super::diag::Diagnostic;
use super::suggest::inapplicable_keys;

/// NeRF-synthetic camera distance: |(0, 4, 0.5)|.
pub const NERF_RADIUS: f64 = 4.031128874149275;

/// One `[rig.NAME]` table.
#[derive(Debug, Clone, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Rig {
    /// The recipe.
    #[schemars(with = "RigKind")]
    pub(super) kind: Spanned<RigKind>,
    /// Distance from the target (default `hypot(4, 0.5)` = 4.031128874149275, NeRF-synthetic's `(0, 4, 0.5)`).
    #[schemars(with = "Option<f64>")]
    pub(super) radius: Option<Spanned<f64>>,
    /// Point the cameras look at (default the origin).
    pub target: Option<[f64; 3]>,
    /// `sphere`/`fibonacci`/`dome`: elevation band, `"full"` or `"upper"` (default `"upper"`).
    pub band: Option<Band>,
    /// `sphere`/`fibonacci`/`dome`: elevation limits in degrees, `[min, max]` (overrides `band`).
    #[schemars(with = "Option<[f64; 2]>")]
    pub(super) elevation_range_deg: Option<Spanned<[f64; 2]>>,
    /// `orbit`: elevation in degrees (default 30).
    pub elevation_deg: Option<f64>,
    /// `orbit`: `"fixed"` elevation (default) or the NeRF-synthetic test `"nerf-test"` schedule.
    pub schedule: Option<OrbitSchedule>,
    /// `orbit`/`dome`: azimuth of the first view in degrees.
    pub start_azimuth_deg: Option<f64>,
    /// `dome`: number of rings (the split's views are shared evenly among them).
    #[schemars(with = "Option<u32>")]
    pub(super) rings: Option<Spanned<u32>>,
    /// `forward-facing`: `"plane"` grid (default) or `"spiral"`.
    pub layout: Option<ForwardLayout>,
    /// `forward-facing`: size of the camera plane `[width, height]` in world units (default [1, 0.75]).
    pub extent: Option<[f64; 2]>,
    /// `hemisphere`: reproduce the 6-DoF toolkit's cameras, `np.random.seed(s)` (MT19937) with two draws per
    /// view of which the first places the camera, instead of vvgen's keyed stream.
    pub numpy_seed: Option<u32>,
    /// `explicit`: the poses.
    #[schemars(with = "Option<Vec<Pose>>")]
    pub(super) poses: Option<Spanned<Vec<Pose>>>,
    /// `from-file`: a transforms.json (NeRF, D-NeRF, nerfstudio) whose cameras to reuse; `path`: a nerfstudio
    /// viewer `camera_path.json` whose cameras to follow.
    #[schemars(with = "Option<String>")]
    pub(super) file: Option<Spanned<String>>,
    /// `path`: the keyframes the camera passes through, in time order.
    #[schemars(with = "Option<Vec<Keyframe>>")]
    pub(super) keyframes: Option<Spanned<Vec<Keyframe>>>,
    /// `path`: a 6-DoF viewer trace, a CSV whose header names `time` (seconds), `x`, `y`, `z` and `qx`, `qy`, `qz`,
    /// `qw` (the camera-to-trace rotation) in any order.
    #[schemars(with = "Option<String>")]
    pub(super) trace: Option<Spanned<String>>,
    /// `path` with `trace`: the trace's frame → world, a 4×4 matrix (rows), e.g. Y-up → Z-up.
    #[schemars(with = "Option<[[f64; 4]; 4]>")]
    pub(super) trace_to_world: Option<Spanned<[[f64; 4]; 4]>>,
    /// `path` with `trace`: the trace's handedness (default `"right"`).
    pub trace_handedness: Option<Handedness>,
    /// `path` with `file`: the `dataparser_transforms.json` nerfstudio saved beside the model the path was drawn
    /// in; the path is in that model's coordinates, which this maps back to the world's. Without it the path
    /// is taken as in world coordinates (a model trained with `--orientation-method none --center-method none
    /// --auto-scale-poses False`).
    #[schemars(with = "Option<String>")]
    pub(super) dataparser_transforms: Option<Spanned<String>>,
    /// Random perturbation of each pose.
    pub jitter: Option<Jitter>,
}

/// Camera placement recipe.
#[derive(Debug, Clone, Copy, Deserialize, PartialEq, Eq, Hash, schemars::JsonSchema)]
#[serde(rename_all = "kebab-case")]
pub enum RigKind {
    /// NeRF-synthetic's random upper hemisphere.
    Hemisphere,
    /// Uniform random directions within an elevation band.
    Sphere,
    /// Golden-angle spiral within an elevation band (deterministic).
    Fibonacci,
    /// A circle around the target.
    Orbit,
    /// Rings of cameras at evenly spaced elevations.
    Dome,
    /// Cameras on a plane or spiral facing the target (LLFF / DyNeRF).
    ForwardFacing,
    /// Poses listed in the manifest.
    Explicit,
    /// Poses read from an existing transforms.json.
    FromFile,
    /// A camera moving over time: one pose per frame, from keyframes, a nerfstudio camera path or a viewer trace.
    Path,
}

impl RigKind {
    /// Keys a rig of this kind accepts besides `kind`.
    pub fn allowed_keys(self) -> &'static [&'static str] {
        match self {
            RigKind::Hemisphere => &["radius", "target", "numpy_seed", "jitter"],
            RigKind::Sphere | RigKind::Fibonacci => &["radius", "target", "band", "elevation_range_deg", "jitter"],
            RigKind::Orbit => &["radius", "target", "elevation_deg", "schedule", "start_azimuth_deg", "jitter"],
            RigKind::Dome => {
                &["radius", "target", "band", "elevation_range_deg", "rings", "start_azimuth_deg", "jitter"]
            }
            RigKind::ForwardFacing => &["radius", "target", "layout", "extent", "jitter"],
            RigKind::Explicit => &["poses", "jitter"],
            RigKind::FromFile => &["file", "jitter"],
            RigKind::Path => {
                &["keyframes", "file", "dataparser_transforms", "trace", "trace_to_world", "trace_handedness"]
            }
        }
    }

    /// Whether the rig itself fixes the number of views.
    pub fn counts_itself(self) -> bool {
        matches!(self, RigKind::Explicit | RigKind::FromFile | RigKind::Path)
    }

    /// Manifest spelling.
    pub fn name(self) -> &'static str {
        match self {
            RigKind::Hemisphere => "hemisphere",
            RigKind::Sphere => "sphere",
            RigKind::Fibonacci => "fibonacci",
            RigKind::Orbit => "orbit",
            RigKind::Dome => "dome",
            RigKind::ForwardFacing => "forward-facing",
            RigKind::Explicit => "explicit",
            RigKind::FromFile => "from-file",
            RigKind::Path => "path",
        }
    }
}

/// Elevation band.
#[derive(Debug, Clone, Copy, Deserialize, PartialEq, Eq, Hash, schemars::JsonSchema)]
#[serde(rename_all = "lowercase")]
pub enum Band {
    /// −90° … 90°.
    Full,
    /// 0° … 90°.
    Upper,
}

/// Orbit elevation schedule.
#[derive(Debug, Clone, Copy, Deserialize, PartialEq, Eq, Hash, schemars::JsonSchema)]
#[serde(rename_all = "kebab-case")]
pub enum OrbitSchedule {
    /// Constant `elevation_deg`.
    Fixed,
    /// NeRF-synthetic's test orbit: tilt `0.7·(cos(2πi/N)+1)/2` rad from (0, 4, 0.5).
    NerfTest,
}

/// Forward-facing camera layout.
#[derive(Debug, Clone, Copy, Deserialize, PartialEq, Eq, Hash, schemars::JsonSchema)]
#[serde(rename_all = "lowercase")]
pub enum ForwardLayout {
    /// A regular grid on a plane.
    Plane,
    /// A spiral on a plane.
    Spiral,
}

/// One explicit pose: a camera-to-world matrix (OpenGL axes, rows), or a position and a target.
#[derive(Debug, Clone, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Pose {
    /// 4×4 camera-to-world, rows, OpenGL/Blender camera axes.
    pub c2w: Option<[[f64; 4]; 4]>,
    /// Camera position.
    pub position: Option<[f64; 3]>,
    /// Point to look at (default the origin).
    pub target: Option<[f64; 3]>,
}

/// One keyframe of a `path` rig: where the camera is at `time`.
#[derive(Debug, Clone, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Keyframe {
    /// Seconds from the dataset's first frame (frame `f` is at `f × step / fps`).
    pub time: f64,
    /// 4×4 camera-to-world, rows, OpenGL/Blender camera axes.
    pub c2w: Option<[[f64; 4]; 4]>,
    /// Camera position.
    pub position: Option<[f64; 3]>,
    /// Point to look at (default the origin).
    pub target: Option<[f64; 3]>,
    /// Vertical field of view in degrees (default `[render]`'s); it changes linearly between keyframes, and
    /// only writers that record focal lengths per image (nerfstudio) take a path that zooms.
    pub fov_deg: Option<f64>,
}

/// A trace's handedness.
#[derive(Debug, Clone, Copy, Deserialize, PartialEq, Eq, Hash, schemars::JsonSchema)]
#[serde(rename_all = "lowercase")]
pub enum Handedness {
    /// Right-handed, the camera looking along its −Z with +Y up (OpenGL, WebXR, glTF).
    Right,
    /// Left-handed, the camera looking along its +Z with +Y up (Unity).
    Left,
}

/// Most keyframes one path may list.
pub const MAX_KEYFRAMES: usize = 100_000;

/// Random pose perturbation.
#[derive(Debug, Clone, Copy, Deserialize, PartialEq, Default, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Jitter {
    /// Position noise, world units (uniform in a ball).
    #[serde(default)]
    pub position: f64,
    /// Look-at target noise, world units (keeps cameras aimed near the subject).
    #[serde(default)]
    pub target: f64,
}

impl Rig {
    pub(crate) fn validate(&self, name: &str, present: &[(&str, Range<usize>)], diags: &mut Vec<Diagnostic>) {
        let kind = *self.kind.get_ref();
        let owner = format!("rig `{name}` (kind = \"{}\")", kind.name());
        inapplicable_keys(present, "kind", kind.allowed_keys(), &owner, diags);
        if let Some(r) = &self.radius {
            if !(r.get_ref().is_finite() && *r.get_ref() > 0.0) {
                diags.push(Diagnostic::error(format!("radius = {} must be positive", r.get_ref()), Some(r.span())));
            }
        }
        if let Some(e) = &self.elevation_range_deg {
            let [lo, hi] = *e.get_ref();
            if !(-90.0..=90.0).contains(&lo) || !(-90.0..=90.0).contains(&hi) || lo > hi {
                diags.push(Diagnostic::error(
                    format!("elevation range [{lo}, {hi}] must satisfy -90 ≤ min ≤ max ≤ 90"),
                    Some(e.span()),
                ));
            }
        }
        if let Some(r) = &self.rings {
            if *r.get_ref() == 0 || *r.get_ref() > 1000 {
                diags.push(Diagnostic::error(format!("rings = {} must be in 1..=1000", r.get_ref()), Some(r.span())));
            }
        }
        match kind {
            RigKind::Explicit => match &self.poses {
                None => diags.push(
                    Diagnostic::error(format!("rig `{name}` (explicit) lists no `poses`"), Some(self.kind.span()))
                        .with_help("e.g. poses = [{ position = [0, -4, 1] }]"),
                ),
                Some(p) if p.get_ref().is_empty() => diags.push(Diagnostic::error("empty `poses`", Some(p.span()))),
                Some(p) => {
                    for (i, pose) in p.get_ref().iter().enumerate() {
                        if pose.c2w.is_some() == pose.position.is_some() {
                            diags.push(Diagnostic::error(
                                format!("pose {i} needs either `c2w` or `position`"),
                                Some(p.span()),
                            ));
                        }
                    }
                }
            },
            RigKind::Path => self.validate_path(name, diags),
            RigKind::FromFile if self.file.is_none() => diags.push(
                Diagnostic::error(format!("rig `{name}` (from-file) names no `file`"), Some(self.kind.span()))
                    .with_help("e.g. file = \"transforms_test.json\""),
            ),
            _ => {}
        }
    }
}

impl Rig {
    fn validate_path(&self, name: &str, diags: &mut Vec<Diagnostic>) {
        let given = [self.keyframes.is_some(), self.file.is_some(), self.trace.is_some()];
        if given.iter().filter(|g| **g).count() != 1 {
            diags.push(
                Diagnostic::error(
                    format!("rig `{name}` (path) takes exactly one of `keyframes`, `file`, `trace`"),
                    Some(self.kind.span()),
                )
                .with_help(
                    r#"keyframes = [{ time = 0, position = [0, -4, 1] }, { time = 2, position = [4, 0, 1] }], or file = "camera_path.json" (nerfstudio's viewer), or trace = "viewer.csv""#,
                ),
            );
        }
        if let Some(k) = &self.keyframes {
            let list = k.get_ref();
            let span = Some(k.span());
            if list.is_empty() || list.len() > MAX_KEYFRAMES {
                diags.push(Diagnostic::error(
                    format!("{} keyframes: a path needs 1 to {MAX_KEYFRAMES}", list.len()),
                    span.clone(),
                ));
            }
            for (i, f) in list.iter().enumerate() {
                let mut bad = |msg: String, help: &str| {
                    diags.push(Diagnostic::error(format!("keyframe {i}: {msg}"), span.clone()).with_help(help))
                };
                if !f.time.is_finite() {
                    bad(format!("time = {} is not a number of seconds", f.time), "e.g. time = 1.5");
                } else if i > 0 && f.time <= list[i - 1].time {
                    bad(
                        format!("time = {} does not come after keyframe {}'s {}", f.time, i - 1, list[i - 1].time),
                        "list keyframes in increasing time",
                    );
                }
                if f.c2w.is_some() == f.position.is_some() {
                    bad("needs either `c2w` or `position`".into(), "e.g. position = [0, -4, 1], target = [0, 0, 0]");
                } else if f.c2w.is_some() && f.target.is_some() {
                    bad("`target` goes with `position`, not `c2w`".into(), "drop `target`, or give `position`");
                }
                let finite = f.c2w.iter().flatten().flatten().chain(f.position.iter().flatten()).all(|v| v.is_finite())
                    && f.target.iter().flatten().all(|v| v.is_finite());
                if !finite || f.c2w.is_some_and(|m| m[3] != [0.0, 0.0, 0.0, 1.0]) {
                    bad("a pose must be finite, a `c2w` with a last row of [0, 0, 0, 1]".into(), "rows, top to bottom");
                }
                if let Some(fov) = f.fov_deg.filter(|v| !(*v > 0.0 && *v < 180.0)) {
                    bad(format!("fov_deg = {fov} is not a field of view"), "degrees between 0 and 180, e.g. 40");
                }
            }
        }
        match (&self.trace, &self.trace_to_world) {
            (Some(t), None) => diags.push(
                Diagnostic::error("a trace needs `trace_to_world`: the map from its frame to the world", Some(t.span()))
                    .with_help(
                        r#"the world is +Z up; for a +Y-up trace (WebXR, Unity with trace_handedness = "left"): trace_to_world = [[1, 0, 0, 0], [0, 0, -1, 0], [0, 1, 0, 0], [0, 0, 0, 1]]"#,
                    ),
            ),
            (Some(_), Some(m)) => {
                let v = m.get_ref();
                if !v.iter().flatten().all(|x| x.is_finite()) || v[3] != [0.0, 0.0, 0.0, 1.0] {
                    diags.push(
                        Diagnostic::error("`trace_to_world` must be finite with a last row of [0, 0, 0, 1]", Some(m.span()))
                            .with_help("rows are listed top to bottom; the translation is the last column"),
                    );
                }
            }
            (None, Some(m)) => diags.push(
                Diagnostic::error("`trace_to_world` goes with `trace` only", Some(m.span())).with_help("remove it"),
            ),
            (None, None) => {}
        }
        if let Some(m) = self.trace_to_world.as_ref().filter(|m| det3(m.get_ref()) <= 0.0) {
            diags.push(
                Diagnostic::error("`trace_to_world` mirrors or flattens the trace", Some(m.span()))
                    .with_help("give a rotation (and scale) with a positive determinant; a left-handed trace says trace_handedness = \"left\""),
            );
        }
        if let (Some(d), None) = (&self.dataparser_transforms, &self.file) {
            diags.push(
                Diagnostic::error("`dataparser_transforms` goes with `file` (a camera_path.json)", Some(d.span()))
                    .with_help("remove it"),
            );
        }
    }
}

/// The determinant of a 4×4's upper 3×3.
fn det3(m: &[[f64; 4]; 4]) -> f64 {
    m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
        + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
}

/// Plain values of the fields whose spans stay inside `manifest` (for diagnostics).
impl Rig {
    /// The rig's kind.
    pub fn kind(&self) -> RigKind {
        *self.kind.get_ref()
    }

    /// Camera distance, when given.
    pub fn radius(&self) -> Option<f64> {
        self.radius.as_ref().map(|r| *r.get_ref())
    }

    /// Elevation range in degrees, when given.
    pub fn elevation_range_deg(&self) -> Option<[f64; 2]> {
        self.elevation_range_deg.as_ref().map(|e| *e.get_ref())
    }

    /// Rings of a dome, when given.
    pub fn rings(&self) -> Option<u32> {
        self.rings.as_ref().map(|r| *r.get_ref())
    }

    /// Explicit poses (empty when none).
    pub fn poses(&self) -> &[Pose] {
        self.poses.as_ref().map_or(&[], |p| p.get_ref().as_slice())
    }

    /// The camera file of a from-file or path rig, when given.
    pub fn file(&self) -> Option<&str> {
        self.file.as_ref().map(|f| f.get_ref().as_str())
    }

    /// A path's keyframes (empty when none).
    pub fn keyframes(&self) -> &[Keyframe] {
        self.keyframes.as_ref().map_or(&[], |k| k.get_ref().as_slice())
    }

    /// A path's trace file, when given.
    pub fn trace(&self) -> Option<&str> {
        self.trace.as_ref().map(|t| t.get_ref().as_str())
    }

    /// A camera path's `dataparser_transforms.json`, when given.
    pub fn dataparser_transforms(&self) -> Option<&str> {
        self.dataparser_transforms.as_ref().map(|f| f.get_ref().as_str())
    }

    /// A trace's frame → world (rows), when given.
    pub fn trace_to_world(&self) -> Option<[[f64; 4]; 4]> {
        self.trace_to_world.as_ref().map(|m| *m.get_ref())
    }
}
