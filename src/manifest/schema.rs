//! The manifest's JSON Schema (`vvgen schema`), derived from the same types that parse it, so it cannot drift:
//! editors read it through Taplo ("Even Better TOML") for completion, hover docs (the `///` comments) and
//! inline errors.

use std::collections::BTreeMap;

use super::dataset::Dataset;
use super::output::Output;
use super::render::Render;
use super::rig::Rig;
use super::source::Source;
use super::split::Split;
use super::transform::Transform;

/// A vvgen manifest: a dataset of dynamic 6-DoF content, declared.
// The parser reads these tables one at a time (keeping spans for its errors); this struct only gives the file its
// shape. Keep it in step with `super::TABLES` (a test compares them).
#[derive(schemars::JsonSchema)]
#[schemars(deny_unknown_fields)]
#[allow(dead_code)]
struct ManifestFile {
    /// What the dataset is called, where it goes, its seed.
    dataset: Dataset,
    /// Where geometry comes from: `[source.NAME]`, one per glTF file, mesh or sequence.
    #[schemars(default)]
    source: BTreeMap<String, Source>,
    /// The normalization of the whole scene (fit, centre, up axis), computed once per sequence.
    #[schemars(default)]
    transform: Option<Transform>,
    /// Image size, camera model, samples, passes, how points are drawn.
    #[schemars(default)]
    render: Option<Render>,
    /// The environment lighting `shading = "pbr"`: an HDR map, its strength and rotation.
    #[schemars(default)]
    environment: Option<super::light::Environment>,
    /// Lights of `shading = "pbr"`: `[light.NAME]`, sun, point or spot, in Blender's units.
    #[schemars(default)]
    light: BTreeMap<String, super::light::Light>,
    /// Camera rigs: `[rig.NAME]`.
    #[schemars(default)]
    rig: BTreeMap<String, Rig>,
    /// Splits: `[split.NAME]`, a rig's cameras over time.
    #[schemars(default)]
    split: BTreeMap<String, Split>,
    /// Outputs: `[output.NAME]`, one dataset layout each.
    #[schemars(default)]
    output: BTreeMap<String, Output>,
}

/// The top-level tables the schema describes, in its order.
pub const SCHEMA_TABLES: [&str; 9] =
    ["dataset", "source", "transform", "render", "environment", "light", "rig", "split", "output"];

/// The JSON Schema of a manifest.
pub fn json_schema() -> serde_json::Value {
    let mut s = serde_json::to_value(schemars::schema_for!(ManifestFile)).expect("BUG: a schema serializes");
    // Split and output names become file names in the dataset (`super::is_plain_name`).
    let plain = serde_json::json!({ "pattern": "^(?!\\.+$)[A-Za-z0-9_.-]+$" });
    for table in ["split", "output"] {
        if let Some(t) = s.pointer_mut(&format!("/properties/{table}")).and_then(|t| t.as_object_mut()) {
            t.insert("propertyNames".into(), plain.clone());
        }
    }
    s["$id"] = serde_json::json!("https://vvgen.dev/schema/manifest.json");
    s["title"] = serde_json::json!("vvgen manifest");
    s
}
