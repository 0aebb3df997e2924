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
    /// `from-file`: a transforms.json (NeRF, D-NeRF, nerfstudio) whose cameras to reuse.
    #[schemars(with = "Option<String>")]
    pub(super) file: Option<Spanned<String>>,
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
        }
    }

    /// Whether the rig itself fixes the number of views.
    pub fn counts_itself(self) -> bool {
        matches!(self, RigKind::Explicit | RigKind::FromFile)
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
            RigKind::FromFile if self.file.is_none() => diags.push(
                Diagnostic::error(format!("rig `{name}` (from-file) names no `file`"), Some(self.kind.span()))
                    .with_help("e.g. file = \"transforms_test.json\""),
            ),
            _ => {}
        }
    }
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

    /// The camera file of a from-file rig, when given.
    pub fn file(&self) -> Option<&str> {
        self.file.as_ref().map(|f| f.get_ref().as_str())
    }
}
