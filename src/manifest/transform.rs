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
    #[schemars(with = "Option<FitSchema>")]
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

impl Transform {
    /// What of this table moves coordinates off the file's own (`None` when it leaves them as they are, reading
    /// an unset `up` as `"z"`, a PLY's default): a camera set in the file's coordinates no longer matches.
    pub fn moves(&self) -> Option<&'static str> {
        let turned = !matches!(self.up, None | Some(UpAxis::Z));
        [
            (turned, "up"),
            (self.fit.is_some(), "fit"),
            (!matches!(self.center, None | Some(Center::None)), "center"),
            (self.rotate_deg.is_some_and(|r| r != [0.0; 3]), "rotate_deg"),
            (self.translate.is_some_and(|t| t != [0.0; 3]), "translate"),
            (self.scale.is_some(), "scale"),
            (self.matrix.is_some(), "matrix"),
        ]
        .into_iter()
        .find(|(moved, _)| *moved)
        .map(|(_, key)| key)
    }
}

/// Source up axis.
#[derive(Debug, Clone, Copy, Deserialize, PartialEq, Eq, schemars::JsonSchema)]
pub enum UpAxis {
    /// +Y up (glTF's convention).
    #[serde(rename = "y")]
    Y,
    /// +Z up (already the world's).
    #[serde(rename = "z")]
    Z,
    /// −Y up (a COLMAP reconstruction of upright photos, and the splatting files trained on one).
    #[serde(rename = "-y")]
    NegY,
    /// −Z up.
    #[serde(rename = "-z")]
    NegZ,
    /// +X up.
    #[serde(rename = "x")]
    X,
    /// −X up.
    #[serde(rename = "-x")]
    NegX,
}

/// `fit = "frame"`, `{ frame = true, margin = … }`, `{ height = … }`, `{ radius = … }` or `{ extent = … }`:
/// exactly one measure.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Fit {
    /// Size along world Z.
    pub height: Option<f64>,
    /// Radius of the sphere about the centre that encloses the bounding box.
    pub radius: Option<f64>,
    /// Largest side of the bounding box.
    pub extent: Option<f64>,
    /// Scale so that the subject, over every frame, is whole inside every camera of every rig a split uses.
    pub frame: bool,
    /// With `frame`: the share of the room to the image's nearest edge left empty (default
    /// [`FRAME_MARGIN`]).
    pub margin: Option<f64>,
}

/// The margin `fit = "frame"` leaves: the subject's bounding sphere reaches 95 % of the way to the nearest image
/// edge, so an edge pixel's filter footprint still sees background.
pub const FRAME_MARGIN: f64 = 0.05;

impl Fit {
    /// The margin of a frame fit (`None` for the other measures).
    pub fn frame_margin(&self) -> Option<f64> {
        self.frame.then(|| self.margin.unwrap_or(FRAME_MARGIN))
    }
}

/// The table form of [`Fit`] as written.
#[derive(Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
struct FitTable {
    /// Size along world Z (NeRF-synthetic subjects: `height = 2.4`).
    height: Option<f64>,
    /// Radius of the sphere about the centre that encloses the bounding box.
    radius: Option<f64>,
    /// Largest side of the bounding box.
    extent: Option<f64>,
    /// `true`: as `fit = "frame"`.
    frame: Option<bool>,
    /// With `frame = true`: the share of the room to the nearest image edge left empty (default 0.05).
    margin: Option<f64>,
}

/// The word form: `fit = "frame"`.
#[derive(schemars::JsonSchema)]
#[serde(rename_all = "lowercase")]
#[allow(dead_code)]
enum FitWord {
    /// The whole subject, over the whole clip, inside every camera of every rig, with a 5 % margin.
    Frame,
}

/// What `fit` accepts, for the schema.
#[derive(schemars::JsonSchema)]
#[serde(untagged)]
#[allow(dead_code)]
enum FitSchema {
    /// `fit = "frame"`.
    Word(FitWord),
    /// `fit = { height = 2.4 }` and the like.
    Table(FitTable),
}

impl<'de> Deserialize<'de> for Fit {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Fit, D::Error> {
        // By hand rather than an untagged enum: serde's untagged error ("did not match any variant") names
        // neither form.
        struct V;
        impl<'de> serde::de::Visitor<'de> for V {
            type Value = Fit;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("\"frame\" or a table such as { height = 2.4 }")
            }
            fn visit_str<E: serde::de::Error>(self, v: &str) -> Result<Fit, E> {
                match v {
                    "frame" => Ok(Fit { frame: true, ..Fit::default() }),
                    _ => Err(E::invalid_value(serde::de::Unexpected::Str(v), &self)),
                }
            }
            fn visit_map<A: serde::de::MapAccess<'de>>(self, a: A) -> Result<Fit, A::Error> {
                let t = FitTable::deserialize(serde::de::value::MapAccessDeserializer::new(a))?;
                Ok(Fit {
                    height: t.height,
                    radius: t.radius,
                    extent: t.extent,
                    frame: t.frame.unwrap_or(false),
                    margin: t.margin,
                })
            }
        }
        d.deserialize_any(V)
    }
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
            if f.frame && !given.is_empty() || !f.frame && given.len() != 1 {
                diags.push(
                    Diagnostic::error(
                        "`fit` takes exactly one of `frame`, `height`, `radius`, `extent`",
                        Some(fit.span()),
                    )
                    .with_help("e.g. fit = \"frame\" (the whole subject in every camera) or fit = { height = 2.4 }"),
                );
            } else if f.margin.is_some() && !f.frame {
                diags.push(
                    Diagnostic::error("`margin` goes with `frame` only", Some(fit.span()))
                        .with_help("fit = { frame = true, margin = 0.1 }"),
                );
            } else if let Some(m) = f.margin.filter(|m| !(0.0..0.9).contains(m)) {
                diags.push(
                    Diagnostic::error(format!("margin {m} is outside 0 … 0.9"), Some(fit.span()))
                        .with_help("the share of the room to the image edge left empty, e.g. margin = 0.05"),
                );
            } else if let Some(&v) = given.first().filter(|v| !(v.is_finite() && **v > 0.0)) {
                diags.push(Diagnostic::error(format!("fit size {v} must be a positive number"), Some(fit.span())));
            }
        }
        if let Some(spanned) = &self.matrix {
            let m = spanned.get_ref();
            let finite = m.iter().flatten().all(|v| v.is_finite());
            if !finite || m[3] != [0.0, 0.0, 0.0, 1.0] {
                diags.push(
                    Diagnostic::error("`matrix` must be finite with a last row of [0, 0, 0, 1]", Some(spanned.span()))
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
