//! `[environment]` and `[light.NAME]`: what lights `[render] shading = "pbr"`, in Blender's units.

use std::ops::Range;

use serde::Deserialize;
use toml::Spanned;

use super::diag::Diagnostic;

/// `[environment]`: an HDR equirectangular map lighting the scene (absent: the built-in studio environment).
#[derive(Debug, Clone, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Environment {
    /// An equirectangular map, `.hdr` (Radiance) or `.exr`, relative to the manifest; absent: the built-in
    /// studio environment.
    #[schemars(with = "Option<String>")]
    pub(crate) map: Option<Spanned<String>>,
    /// Radiance multiplier (Blender's Background Strength; default 1).
    #[schemars(with = "Option<f64>")]
    pub(crate) strength: Option<Spanned<f64>>,
    /// Rotation about world +Z in degrees (a Mapping node's Z rotation in Blender; default 0).
    #[serde(default)]
    pub rotation_deg: f64,
    /// Whether the map is the RGBA pass's background (default false: transparent, as NeRF datasets expect).
    #[serde(default)]
    pub visible: bool,
}

/// `[light.NAME]`.
#[derive(Debug, Clone, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Light {
    /// `"sun"`, `"point"` or `"spot"`.
    #[schemars(with = "LightKind")]
    pub(crate) kind: Spanned<LightKind>,
    /// Sun: the direction the light travels (world, +Z up), e.g. `[0.3, 0.2, -1]`.
    #[schemars(with = "Option<[f64; 3]>")]
    pub(crate) direction: Option<Spanned<[f64; 3]>>,
    /// Point, spot: where the light is.
    #[schemars(with = "Option<[f64; 3]>")]
    pub(crate) position: Option<Spanned<[f64; 3]>>,
    /// Spot: the point it aims at (default: the world origin).
    #[schemars(with = "Option<[f64; 3]>")]
    pub(crate) target: Option<Spanned<[f64; 3]>>,
    /// Linear RGB colour (Blender's light Color), default white.
    #[serde(default = "white")]
    #[schemars(with = "[f64; 3]")]
    pub(crate) color: Spanned<[f64; 3]>,
    /// Sun: irradiance in W/m² (Blender's Strength); point, spot: power in W (Blender's Power).
    #[schemars(with = "f64")]
    pub(crate) intensity: Spanned<f64>,
    /// Sun: angular diameter in degrees (soft shadows; default 0.526, Blender's and the real sun's).
    #[schemars(with = "Option<f64>")]
    pub(crate) angle_deg: Option<Spanned<f64>>,
    /// Point, spot: radius in world units (soft shadows; default 0.1, Blender's).
    #[schemars(with = "Option<f64>")]
    pub(crate) radius: Option<Spanned<f64>>,
    /// Spot: full cone angle in degrees (Blender's Spot Size; default 45).
    #[schemars(with = "Option<f64>")]
    pub(crate) cone_deg: Option<Spanned<f64>>,
    /// Spot: the fraction of the cone over which it fades (Blender's Blend; default 0.15).
    #[schemars(with = "Option<f64>")]
    pub(crate) blend: Option<Spanned<f64>>,
    /// Whether it casts shadows (default true).
    #[serde(default = "yes")]
    pub shadows: bool,
}

fn white() -> Spanned<[f64; 3]> {
    Spanned::new(0..0, [1.0; 3])
}
fn yes() -> bool {
    true
}

/// The kinds of `[light.NAME]`.
#[derive(Debug, Clone, Copy, Deserialize, PartialEq, Eq, schemars::JsonSchema)]
#[serde(rename_all = "lowercase")]
pub enum LightKind {
    /// Parallel light from far away.
    Sun,
    /// Light from a point in all directions.
    Point,
    /// Light from a point in a cone.
    Spot,
}

impl LightKind {
    fn name(self) -> &'static str {
        match self {
            LightKind::Sun => "sun",
            LightKind::Point => "point",
            LightKind::Spot => "spot",
        }
    }
}

/// An optional `[light.NAME]` key: its name, where it is set (if it is), and the kinds it applies to.
type KeyUse<'a> = (&'a str, Option<Range<usize>>, &'a [LightKind]);

/// Blender's default sun angle (degrees).
pub(crate) const SUN_ANGLE: f64 = 0.526;

impl Environment {
    /// The map file (manifest-relative), when given.
    pub fn map(&self) -> Option<&str> {
        self.map.as_ref().map(|m| m.get_ref().as_str())
    }

    /// The radiance multiplier.
    pub fn strength(&self) -> f64 {
        self.strength.as_ref().map_or(1.0, |s| *s.get_ref())
    }

    /// The table's own checks; the map file is checked where inputs are opened (`crate::settings::diagnose`).
    pub(super) fn validate(&self, diags: &mut Vec<Diagnostic>) {
        if let Some(s) = &self.strength {
            if *s.get_ref() < 0.0 {
                diags.push(Diagnostic::error("strength must be ≥ 0", Some(s.span())));
            }
        }
    }
}

impl Light {
    pub(super) fn validate(&self, name: &str, span: Range<usize>, diags: &mut Vec<Diagnostic>) {
        let kind = *self.kind.get_ref();
        let wrong = |key: &str, s: Range<usize>, diags: &mut Vec<Diagnostic>| {
            diags.push(
                Diagnostic::error(format!("`{key}` does not apply to a {} light", kind.name()), Some(s)).with_help(
                    match kind {
                        LightKind::Sun => "a sun takes `direction`, `intensity` (W/m²), `angle_deg`",
                        LightKind::Point => "a point light takes `position`, `intensity` (W), `radius`",
                        LightKind::Spot => {
                            "a spot takes `position`, `target`, `intensity` (W), `cone_deg`, `blend`, `radius`"
                        }
                    },
                ),
            )
        };
        // Which kinds each optional key belongs to; one that is set on another kind is a mistake.
        use LightKind::{Point, Spot, Sun};
        let span3 = |v: &Option<Spanned<[f64; 3]>>| v.as_ref().map(|v| v.span());
        let span1 = |v: &Option<Spanned<f64>>| v.as_ref().map(|v| v.span());
        let keys: [KeyUse; 7] = [
            ("direction", span3(&self.direction), &[Sun]),
            ("angle_deg", span1(&self.angle_deg), &[Sun]),
            ("position", span3(&self.position), &[Point, Spot]),
            ("radius", span1(&self.radius), &[Point, Spot]),
            ("target", span3(&self.target), &[Spot]),
            ("cone_deg", span1(&self.cone_deg), &[Spot]),
            ("blend", span1(&self.blend), &[Spot]),
        ];
        for (key, at, kinds) in keys {
            if let Some(at) = at.filter(|_| !kinds.contains(&kind)) {
                wrong(key, at, diags);
            }
        }
        let needs = |key: &str, example: &str, diags: &mut Vec<Diagnostic>| {
            diags.push(
                Diagnostic::error(format!("light `{name}` ({}) needs `{key}`", kind.name()), Some(span.clone()))
                    .with_help(example.to_string()),
            )
        };
        match (kind, &self.direction, &self.position) {
            (Sun, None, _) => {
                needs("direction", "the direction the light travels, e.g. direction = [0.3, 0.2, -1]", diags)
            }
            (Sun, Some(d), _) if glam::DVec3::from(*d.get_ref()).length() < 1e-9 => {
                diags.push(Diagnostic::error("`direction` must not be zero", Some(d.span())))
            }
            (Point | Spot, _, None) => needs("position", "e.g. position = [2, -2, 3]", diags),
            (Spot, _, Some(p)) => {
                let t = self.target.as_ref().map_or([0.0; 3], |t| *t.get_ref());
                if (glam::DVec3::from(*p.get_ref()) - glam::DVec3::from(t)).length() < 1e-9 {
                    diags.push(
                        Diagnostic::error("the spot's `target` is its `position`", Some(p.span()))
                            .with_help("aim it at another point (`target` defaults to the world origin)"),
                    );
                }
            }
            _ => {}
        }
        let i = *self.intensity.get_ref();
        if i < 0.0 {
            diags.push(Diagnostic::error("intensity must be ≥ 0", Some(self.intensity.span())));
        }
        if self.color.get_ref().iter().any(|c| *c < 0.0) {
            diags.push(Diagnostic::error("colour components must be ≥ 0", Some(self.color.span())));
        }
        let ranges = [
            (&self.angle_deg, "angle_deg", 0.0, 179.0, "a sun's angular diameter in degrees, e.g. 0.526"),
            (&self.cone_deg, "cone_deg", 1.0, 180.0, "a spot's full cone in degrees, 1..=180"),
            (&self.blend, "blend", 0.0, 1.0, "a fraction, 0..=1"),
            (&self.radius, "radius", 0.0, 1e6, "a radius in world units, ≥ 0"),
        ];
        for (v, key, lo, hi, help) in ranges {
            if let Some(v) = v {
                if !(lo..=hi).contains(v.get_ref()) {
                    diags.push(
                        Diagnostic::error(format!("{key} = {} is out of range", v.get_ref()), Some(v.span()))
                            .with_help(help),
                    );
                }
            }
        }
    }
}
