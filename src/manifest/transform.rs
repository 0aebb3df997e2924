//! `[transform]` (and `[source.NAME.transform]`): how source units and axes map into the world.
//!
//! World is +Z up (Blender, NeRF-synthetic). The full map, applied to source points, is
//! `translate · rotate · scale · fit · center · up · matrix`, where `fit` and `center` are computed once per
//! sequence from bounds taken after `up · matrix` (over all frames by default).

use serde::Deserialize;
use toml::Spanned;

use super::diag::Diagnostic;

/// One transform table. Every key is optional; a source's table overrides nothing of the global one: the
/// source's transform applies first, the global one to the whole scene after it.
#[derive(Debug, Clone, Deserialize, Default, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Transform {
    /// The source's up axis: `"y"` (glTF, most scanners) or `"z"`. Default: `"y"` for glTF, `"z"` otherwise.
    pub up: Option<UpAxis>,
    /// Scale so that one measure of the bounds has this size.
    #[schemars(with = "Option<Fit>")]
    pub(super) fit: Option<Spanned<Fit>>,
    /// Which point moves to the origin (default `"none"`).
    pub center: Option<Center>,
    /// Extra rotation, XYZ Euler angles in degrees (applied about world axes, X first).
    pub rotate_deg: Option<[f64; 3]>,
    /// Extra translation, world units.
    pub translate: Option<[f64; 3]>,
    /// Extra scale: one number or one per axis.
    pub scale: Option<Scale>,
    /// A raw 4×4 matrix (rows), applied first to source coordinates.
    #[schemars(with = "Option<[[f64; 4]; 4]>")]
    pub(super) matrix: Option<Spanned<[[f64; 4]; 4]>>,
    /// Which frames the bounds for `fit`/`center` come from.
    pub over: Option<Over>,
}

/// Source up axis.
#[derive(Debug, Clone, Copy, Deserialize, PartialEq, Eq, schemars::JsonSchema)]
#[serde(rename_all = "lowercase")]
pub enum UpAxis {
    /// +Y up (glTF's convention).
    Y,
    /// +Z up (already the world's).
    Z,
}

/// `fit = { height = … }` / `{ radius = … }` / `{ extent = … }`: exactly one.
#[derive(Debug, Clone, Copy, Deserialize, PartialEq, Default, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Fit {
    /// Size along world Z.
    pub height: Option<f64>,
    /// Radius of the sphere about the centre that encloses the bounding box.
    pub radius: Option<f64>,
    /// Largest side of the bounding box.
    pub extent: Option<f64>,
}

/// Centering rule.
#[derive(Debug, Clone, Copy, Deserialize, PartialEq, Eq, schemars::JsonSchema)]
#[serde(rename_all = "lowercase")]
pub enum Center {
    /// Centre of the bounding box.
    Bbox,
    /// Mean of the vertices (over the frames in `over`).
    Centroid,
    /// Leave in place.
    None,
}

/// Extra scale.
#[derive(Debug, Clone, Copy, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(untagged)]
pub enum Scale {
    /// The same on every axis.
    Uniform(f64),
    /// Per axis.
    Axes([f64; 3]),
}

/// Which frames define the normalization.
#[derive(Debug, Clone, Copy, Deserialize, PartialEq, Eq, Default, schemars::JsonSchema)]
#[serde(rename_all = "kebab-case")]
pub enum Over {
    /// The union of every frame's bounds: the subject never jumps or breathes.
    #[default]
    AllFrames,
    /// Frame 0 only.
    First,
}

impl Transform {
    pub(crate) fn validate(&self, diags: &mut Vec<Diagnostic>) {
        if let Some(fit) = &self.fit {
            let f = fit.get_ref();
            let given: Vec<f64> = [f.height, f.radius, f.extent].into_iter().flatten().collect();
            if given.len() != 1 {
                diags.push(
                    Diagnostic::error("`fit` takes exactly one of `height`, `radius`, `extent`", Some(fit.span()))
                        .with_help("e.g. fit = { height = 2.4 }"),
                );
            } else if !(given[0].is_finite() && given[0] > 0.0) {
                diags.push(Diagnostic::error(
                    format!("fit size {} must be a positive number", given[0]),
                    Some(fit.span()),
                ));
            }
        }
        if let Some(m) = &self.matrix {
            let m = m.get_ref();
            let finite = m.iter().flatten().all(|v| v.is_finite());
            if !finite || m[3] != [0.0, 0.0, 0.0, 1.0] {
                diags.push(
                    Diagnostic::error(
                        "`matrix` must be finite with a last row of [0, 0, 0, 1]",
                        Some(self.matrix.as_ref().unwrap().span()),
                    )
                    .with_help("rows are listed top to bottom; the translation is the last column"),
                );
            }
        }
    }
}

/// Plain values of the fields whose spans stay inside `manifest` (for diagnostics).
impl Transform {
    /// The fit, when given.
    pub fn fit(&self) -> Option<&Fit> {
        self.fit.as_ref().map(|f| f.get_ref())
    }

    /// The explicit matrix (rows), when given.
    pub fn matrix(&self) -> Option<[[f64; 4]; 4]> {
        self.matrix.as_ref().map(|m| *m.get_ref())
    }
}
