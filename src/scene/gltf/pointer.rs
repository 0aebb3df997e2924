//! `KHR_animation_pointer`: animation channels whose target is a JSON pointer into the document instead of a
//! node and a path (Blender 4.x's exporter writes them for animated materials, lights and cameras, and the
//! Khronos samples for node transforms too). A pointer at a node's `translation`, `rotation`, `scale` or
//! `weights`, or at a mesh's default `weights`, means exactly what a core channel means: [`follow`] rewrites it
//! as one (a mesh's weights as a channel per node that shows the mesh with its default weights), so posing
//! reads it as any other. A pointer at anything else (a material's factors, a light's colour, a camera's field
//! of view) is dropped with a warning: vvgen keeps those properties at the file's values, over the whole clip.

use serde_json::Value;

/// The node properties a core channel animates, which a pointer may name too.
const NODE_PATHS: [&str; 4] = ["translation", "rotation", "scale", "weights"];

/// How many dropped pointers a warning names before it counts the rest.
const SHOWN: usize = 4;

/// The most channels a document's mesh-weight pointers may become: one pointer becomes a channel per node
/// showing the mesh, so a hostile file (10⁴ pointers at a mesh 10⁴ nodes show) would ask for 10⁸ (a crowd of
/// instanced morphing characters needs a few thousand).
const MAX_EXPANDED: usize = 1 << 18;

/// What [`follow`] did to a document.
#[derive(Debug, Default)]
pub(super) struct Followed {
    /// Whether any channel was rewritten or dropped (the document must be read again from the JSON).
    pub changed: bool,
    /// A warning per animation that lost channels, naming the properties that stay still.
    pub warnings: Vec<String>,
}

/// Rewrites every `KHR_animation_pointer` channel of `doc` that animates a node (or a mesh's default morph
/// weights) as the core channel it is, and drops the others, saying which. A pointer that names a node or mesh
/// the file does not have, or a channel of path `pointer` without one, is an error naming the channel.
pub(super) fn follow(doc: &mut Value) -> Result<Followed, String> {
    let mut out = Followed::default();
    let count = |key: &str, doc: &Value| doc.get(key).and_then(Value::as_array).map_or(0, Vec::len);
    let nodes = count("nodes", doc);
    // The nodes that show each mesh with its default weights (a node's own `weights` override the mesh's).
    let shown_by: Vec<Vec<usize>> = {
        let mut by = vec![Vec::new(); count("meshes", doc)];
        for (i, node) in doc.get("nodes").and_then(Value::as_array).into_iter().flatten().enumerate() {
            let mesh = node.get("mesh").and_then(Value::as_u64).map(|m| m as usize);
            if let Some(list) = mesh.and_then(|m| by.get_mut(m)).filter(|_| node.get("weights").is_none()) {
                list.push(i);
            }
        }
        by
    };
    let Some(animations) = doc.get_mut("animations").and_then(Value::as_array_mut) else { return Ok(out) };
    let mut expanded = 0usize;
    for (a, anim) in animations.iter_mut().enumerate() {
        let name = anim.get("name").and_then(Value::as_str).map(|n| format!(" (`{n}`)")).unwrap_or_default();
        let Some(channels) = anim.get_mut("channels").and_then(Value::as_array_mut) else { continue };
        if !channels.iter().any(is_pointer) {
            continue;
        }
        let mut kept = Vec::with_capacity(channels.len());
        let mut dropped = Vec::new();
        for (c, channel) in std::mem::take(channels).into_iter().enumerate() {
            if !is_pointer(&channel) {
                kept.push(channel);
                continue;
            }
            let at = format!("animations[{a}].channels[{c}]");
            let pointer = channel
                .pointer("/target/extensions/KHR_animation_pointer/pointer")
                .and_then(Value::as_str)
                .ok_or_else(|| {
                    format!("{at}: target.path is `pointer` but the target has no `KHR_animation_pointer` pointer")
                })?
                .to_string();
            match target(&pointer) {
                Some(Target::Node(n, path)) => {
                    if n >= nodes {
                        return Err(format!(
                            "{at}: its pointer `{pointer}` names node {n}; the file has {nodes} nodes"
                        ));
                    }
                    kept.push(core(&channel, n, path));
                }
                Some(Target::MeshWeights(m)) => {
                    let Some(shown) = shown_by.get(m) else {
                        let meshes = shown_by.len();
                        return Err(format!(
                            "{at}: its pointer `{pointer}` names mesh {m}; the file has {meshes} meshes"
                        ));
                    };
                    expanded += shown.len();
                    if expanded > MAX_EXPANDED {
                        return Err(format!(
                            "{at}: its pointer `{pointer}` animates the weights of mesh {m}, which {} nodes show; the \
                             file's mesh-weight pointers would become over {MAX_EXPANDED} channels",
                            shown.len()
                        ));
                    }
                    kept.extend(shown.iter().map(|&n| core(&channel, n, "weights")));
                }
                None => dropped.push(pointer),
            }
        }
        *channels = kept;
        out.changed = true;
        if !dropped.is_empty() {
            let more = dropped.len().saturating_sub(SHOWN);
            let shown: Vec<String> = dropped.iter().take(SHOWN).map(|p| format!("`{p}`")).collect();
            let tail = if more > 0 { format!(" and {more} more") } else { String::new() };
            out.warnings.push(format!(
                "animation {a}{name} animates {}{tail} through `KHR_animation_pointer`, which vvgen follows for \
                 nodes and morph weights only: these keep the file's values over the whole clip",
                shown.join(", ")
            ));
        }
    }
    Ok(out)
}

/// What a pointer animates, when posing can follow it.
enum Target {
    /// A node's core property.
    Node(usize, &'static str),
    /// A mesh's default morph weights.
    MeshWeights(usize),
}

/// Whether a channel targets a pointer (path `pointer`, the extension's).
fn is_pointer(channel: &Value) -> bool {
    channel.pointer("/target/path").and_then(Value::as_str) == Some("pointer")
}

/// Parses `/nodes/{n}/{path}` and `/meshes/{m}/weights` (indices in plain decimal, as JSON pointers spell them).
fn target(pointer: &str) -> Option<Target> {
    let parts: Vec<&str> = pointer.strip_prefix('/')?.split('/').collect();
    let index = |s: &str| (!s.is_empty() && s.bytes().all(|b| b.is_ascii_digit())).then(|| s.parse().ok()).flatten();
    match parts.as_slice() {
        ["nodes", n, path] => Some(Target::Node(index(n)?, NODE_PATHS.into_iter().find(|p| p == path)?)),
        ["meshes", m, "weights"] => Some(Target::MeshWeights(index(m)?)),
        _ => None,
    }
}

/// The core channel animating `path` of node `node` with `channel`'s sampler.
fn core(channel: &Value, node: usize, path: &str) -> Value {
    let mut c = channel.clone();
    c["target"] = serde_json::json!({ "node": node, "path": path });
    c
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    fn channel(pointer: &str, sampler: u64) -> Value {
        json!({"sampler": sampler, "target": {"path": "pointer", "extensions": {"KHR_animation_pointer": {"pointer": pointer}}}})
    }

    #[test]
    fn node_and_mesh_pointers_become_core_channels_and_the_rest_is_named() {
        let mut doc = json!({
            "nodes": [{"mesh": 0}, {"mesh": 0, "weights": [0.5]}, {"mesh": 0}, {}],
            "meshes": [{}],
            "animations": [{"name": "all", "channels": [
                channel("/nodes/3/rotation", 0),
                {"sampler": 1, "target": {"node": 0, "path": "translation"}},
                channel("/meshes/0/weights", 2),
                channel("/materials/0/pbrMetallicRoughness/baseColorFactor", 3),
                channel("/nodes/3/extensions/KHR_node_visibility/visible", 4),
            ], "samplers": []}]
        });
        let got = follow(&mut doc).unwrap();
        assert!(got.changed);
        let targets: Vec<(Value, Value)> = doc["animations"][0]["channels"]
            .as_array()
            .unwrap()
            .iter()
            .map(|c| (c["sampler"].clone(), c["target"].clone()))
            .collect();
        assert_eq!(
            targets,
            vec![
                (json!(0), json!({"node": 3, "path": "rotation"})),
                (json!(1), json!({"node": 0, "path": "translation"})),
                // Node 1 has weights of its own: the mesh's defaults do not show there.
                (json!(2), json!({"node": 0, "path": "weights"})),
                (json!(2), json!({"node": 2, "path": "weights"})),
            ]
        );
        assert_eq!(got.warnings.len(), 1, "{:?}", got.warnings);
        let w = &got.warnings[0];
        assert!(w.contains("animation 0 (`all`)") && w.contains("`/materials/0/pbrMetallicRoughness/baseColorFactor`"));
        assert!(w.contains("KHR_node_visibility"), "{w}");
    }

    #[test]
    fn a_file_without_pointers_is_left_alone() {
        let mut doc = json!({"nodes": [{}], "animations": [{"channels": [
            {"sampler": 0, "target": {"node": 0, "path": "rotation"}}], "samplers": []}]});
        let before = doc.clone();
        let got = follow(&mut doc).unwrap();
        assert!(!got.changed && got.warnings.is_empty());
        assert_eq!(doc, before);
    }

    #[test]
    fn a_pointer_past_the_file_or_missing_is_an_error_naming_the_channel() {
        for (bad, says) in [
            (
                channel("/nodes/7/rotation", 0),
                "animations[0].channels[0]: its pointer `/nodes/7/rotation` names node 7; the file has 1 nodes",
            ),
            (channel("/meshes/2/weights", 0), "names mesh 2; the file has 0 meshes"),
            (json!({"sampler": 0, "target": {"path": "pointer"}}), "has no `KHR_animation_pointer` pointer"),
        ] {
            let mut doc = json!({"nodes": [{}], "animations": [{"channels": [bad], "samplers": []}]});
            let e = follow(&mut doc).unwrap_err();
            assert!(e.contains(says), "{e}");
        }
        // A mesh that 600 nodes show, pointed at 600 times: 360 000 channels, past the bound.
        let mut doc = json!({"nodes": vec![json!({"mesh": 0}); 600], "meshes": [{}],
            "animations": [{"channels": vec![channel("/meshes/0/weights", 0); 600], "samplers": []}]});
        let e = follow(&mut doc).unwrap_err();
        assert!(e.contains("which 600 nodes show") && e.contains("over 262144 channels"), "{e}");
        // Not indices: `/nodes/-1/…`, `/nodes/01x/…`, and what a pointer escapes.
        for odd in ["/nodes/-1/rotation", "/nodes/1x/rotation", "/nodes/0/rotation/0", "nodes/0/rotation"] {
            assert!(target(odd).is_none(), "{odd}");
        }
    }
}
