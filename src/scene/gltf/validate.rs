//! Checks on the raw JSON of a glTF before the `gltf` crate sees it. Its own validation indexes some arrays
//! unchecked and unwraps some enums it could not parse (a primitive's accessor when there is no `accessors`
//! array, an animation channel's target node, an unknown target path), so a malformed file a user downloads
//! would panic instead of failing with a message. Every index the loader follows is checked here against the
//! array it points into, and every enum against the values the spec allows.

use serde_json::Value;

/// At most this many problems are listed in one error.
const MAX_LISTED: usize = 5;

/// The document's problems, or `Ok` when every reference and enum is in range.
pub(crate) fn check(root: &Value) -> Result<(), String> {
    let mut c = Checker { root, problems: Vec::new() };
    c.run();
    if c.problems.is_empty() {
        return Ok(());
    }
    let more = c.problems.len().saturating_sub(MAX_LISTED);
    let mut text = c.problems.into_iter().take(MAX_LISTED).collect::<Vec<_>>().join("; ");
    if more > 0 {
        text.push_str(&format!("; and {more} more"));
    }
    Err(text)
}

struct Checker<'a> {
    root: &'a Value,
    problems: Vec<String>,
}

/// Whether `x` is an index into an array of `len` entries.
fn indexes(x: &Value, len: usize) -> bool {
    x.as_u64().is_some_and(|i| i < len as u64)
}

/// The entries of array `key` of `v` (none when absent or not an array).
fn items<'v>(v: &'v Value, key: &str) -> &'v [Value] {
    v.get(key).and_then(Value::as_array).map_or(&[], Vec::as_slice)
}

impl<'a> Checker<'a> {
    fn len(&self, array: &str) -> usize {
        items(self.root, array).len()
    }

    /// The document's `KHR_lights_punctual` lights.
    fn lights(&self) -> &'a [Value] {
        self.root.get("extensions").and_then(|e| e.get("KHR_lights_punctual")).map_or(&[], |x| items(x, "lights"))
    }

    /// `v[key]`, when present, indexes an array of `len` entries (called `target`).
    fn index_into(&mut self, v: &Value, key: &str, path: &str, target: &str, len: usize) {
        let Some(x) = v.get(key) else { return };
        if !indexes(x, len) {
            self.problems.push(format!("{path}.{key} = {x} does not index `{target}` ({len} entries)"));
        }
    }

    /// `v[key]`, when present, indexes the document's top-level `target` array.
    fn index(&mut self, v: &Value, key: &str, path: &str, target: &str) {
        let len = self.len(target);
        self.index_into(v, key, path, target, len);
    }

    /// Every entry of array `v[key]` indexes `target`.
    fn indices(&mut self, v: &Value, key: &str, path: &str, target: &str) {
        let len = self.len(target);
        for (i, x) in items(v, key).iter().enumerate() {
            if !indexes(x, len) {
                self.problems.push(format!("{path}.{key}[{i}] = {x} does not index `{target}` ({len} entries)"));
            }
        }
    }

    /// Every value of object `map` (attribute name → accessor), when present, indexes `target`.
    fn map_values(&mut self, map: Option<&Value>, path: &str, target: &str) {
        let Some(map) = map.and_then(Value::as_object) else { return };
        let len = self.len(target);
        for (name, x) in map {
            if !indexes(x, len) {
                self.problems.push(format!("{path}.{name} = {x} does not index `{target}` ({len} entries)"));
            }
        }
    }

    /// `v[key]`, when present, is one of `allowed`.
    fn one_of(&mut self, v: &Value, key: &str, path: &str, allowed: &[Value]) {
        let Some(x) = v.get(key) else { return };
        if !allowed.contains(x) {
            let list: Vec<String> = allowed.iter().map(Value::to_string).collect();
            self.problems.push(format!("{path}.{key} = {x} is not one of {}", list.join(", ")));
        }
    }

    fn run(&mut self) {
        let root = self.root;
        let strs = |v: &[&str]| v.iter().map(|s| Value::from(*s)).collect::<Vec<_>>();
        let nums = |v: &[u64]| v.iter().map(|n| Value::from(*n)).collect::<Vec<_>>();
        self.index(root, "scene", "", "scenes");
        for (i, s) in items(root, "scenes").iter().enumerate() {
            self.indices(s, "nodes", &format!("scenes[{i}]"), "nodes");
        }
        self.forest();
        for (i, n) in items(root, "nodes").iter().enumerate() {
            let p = format!("nodes[{i}]");
            self.indices(n, "children", &p, "nodes");
            self.index(n, "mesh", &p, "meshes");
            self.index(n, "skin", &p, "skins");
            self.index(n, "camera", &p, "cameras");
            if let Some(l) = n.get("extensions").and_then(|e| e.get("KHR_lights_punctual")) {
                let len = self.lights().len();
                self.index_into(l, "light", &format!("{p}.extensions.KHR_lights_punctual"), "lights", len);
            }
        }
        for (i, l) in self.lights().iter().enumerate() {
            self.one_of(
                l,
                "type",
                &format!("KHR_lights_punctual.lights[{i}]"),
                &strs(&["directional", "point", "spot"]),
            );
        }
        for (i, m) in items(root, "meshes").iter().enumerate() {
            for (j, prim) in items(m, "primitives").iter().enumerate() {
                let p = format!("meshes[{i}].primitives[{j}]");
                self.map_values(prim.get("attributes"), &format!("{p}.attributes"), "accessors");
                self.index(prim, "indices", &p, "accessors");
                self.index(prim, "material", &p, "materials");
                self.one_of(prim, "mode", &p, &nums(&[0, 1, 2, 3, 4, 5, 6]));
                for (k, t) in items(prim, "targets").iter().enumerate() {
                    self.map_values(Some(t), &format!("{p}.targets[{k}]"), "accessors");
                }
            }
        }
        for (i, s) in items(root, "skins").iter().enumerate() {
            let p = format!("skins[{i}]");
            self.indices(s, "joints", &p, "nodes");
            self.index(s, "skeleton", &p, "nodes");
            self.index(s, "inverseBindMatrices", &p, "accessors");
        }
        for (i, a) in items(root, "accessors").iter().enumerate() {
            let p = format!("accessors[{i}]");
            self.index(a, "bufferView", &p, "bufferViews");
            self.one_of(a, "componentType", &p, &nums(&[5120, 5121, 5122, 5123, 5125, 5126]));
            self.one_of(a, "type", &p, &strs(&["SCALAR", "VEC2", "VEC3", "VEC4", "MAT2", "MAT3", "MAT4"]));
            if let Some(sparse) = a.get("sparse") {
                for part in ["indices", "values"] {
                    if let Some(v) = sparse.get(part) {
                        self.index(v, "bufferView", &format!("{p}.sparse.{part}"), "bufferViews");
                    }
                }
                if let Some(ix) = sparse.get("indices") {
                    self.one_of(ix, "componentType", &format!("{p}.sparse.indices"), &nums(&[5121, 5123, 5125]));
                }
            }
        }
        for (i, v) in items(root, "bufferViews").iter().enumerate() {
            let p = format!("bufferViews[{i}]");
            self.index(v, "buffer", &p, "buffers");
            self.one_of(v, "target", &p, &nums(&[34962, 34963]));
        }
        for (i, im) in items(root, "images").iter().enumerate() {
            let p = format!("images[{i}]");
            self.index(im, "bufferView", &p, "bufferViews");
            // The spec: exactly one of uri and bufferView, and a mimeType with a bufferView.
            match (im.get("uri").is_some(), im.get("bufferView").is_some()) {
                (true, true) | (false, false) => {
                    self.problems.push(format!("{p} needs exactly one of uri and bufferView"))
                }
                (false, true) if im.get("mimeType").is_none() => {
                    self.problems.push(format!("{p} is stored in a bufferView but has no mimeType"))
                }
                _ => {}
            }
        }
        for (i, t) in items(root, "textures").iter().enumerate() {
            let p = format!("textures[{i}]");
            self.index(t, "source", &p, "images");
            self.index(t, "sampler", &p, "samplers");
        }
        for (i, s) in items(root, "samplers").iter().enumerate() {
            let p = format!("samplers[{i}]");
            self.one_of(s, "magFilter", &p, &nums(&[9728, 9729]));
            self.one_of(s, "minFilter", &p, &nums(&[9728, 9729, 9984, 9985, 9986, 9987]));
            for wrap in ["wrapS", "wrapT"] {
                self.one_of(s, wrap, &p, &nums(&[33071, 33648, 10497]));
            }
        }
        for (i, m) in items(root, "materials").iter().enumerate() {
            let p = format!("materials[{i}]");
            self.one_of(m, "alphaMode", &p, &strs(&["OPAQUE", "MASK", "BLEND"]));
            let pbr = m.get("pbrMetallicRoughness");
            let ext = |name: &str, key: &str| m.get("extensions").and_then(|e| e.get(name)).and_then(|x| x.get(key));
            let infos = [
                (pbr.and_then(|x| x.get("baseColorTexture")), "pbrMetallicRoughness.baseColorTexture"),
                (pbr.and_then(|x| x.get("metallicRoughnessTexture")), "pbrMetallicRoughness.metallicRoughnessTexture"),
                (m.get("normalTexture"), "normalTexture"),
                (m.get("occlusionTexture"), "occlusionTexture"),
                (m.get("emissiveTexture"), "emissiveTexture"),
                (ext("KHR_materials_specular", "specularTexture"), "extensions.KHR_materials_specular.specularTexture"),
                (
                    ext("KHR_materials_specular", "specularColorTexture"),
                    "extensions.KHR_materials_specular.specularColorTexture",
                ),
                (
                    ext("KHR_materials_pbrSpecularGlossiness", "diffuseTexture"),
                    "extensions.KHR_materials_pbrSpecularGlossiness.diffuseTexture",
                ),
                (
                    ext("KHR_materials_pbrSpecularGlossiness", "specularGlossinessTexture"),
                    "extensions.KHR_materials_pbrSpecularGlossiness.specularGlossinessTexture",
                ),
            ];
            for (info, name) in infos {
                if let Some(info) = info {
                    self.index(info, "index", &format!("{p}.{name}"), "textures");
                }
            }
        }
        for (i, c) in items(root, "cameras").iter().enumerate() {
            let p = format!("cameras[{i}]");
            self.one_of(c, "type", &p, &strs(&["perspective", "orthographic"]));
            // The type names the object that holds the projection (the gltf crate unwraps it).
            if let Some(t) =
                c.get("type").and_then(Value::as_str).filter(|t| ["perspective", "orthographic"].contains(t))
            {
                if !c.get(t).is_some_and(Value::is_object) {
                    self.problems.push(format!("{p}.type is \"{t}\" but {p}.{t} is missing"));
                }
            }
        }
        self.attribute_shapes();
        self.accessor_budget();
        for (i, a) in items(root, "animations").iter().enumerate() {
            let samplers = items(a, "samplers").len();
            for (j, ch) in items(a, "channels").iter().enumerate() {
                let p = format!("animations[{i}].channels[{j}]");
                self.index_into(ch, "sampler", &p, &format!("animations[{i}].samplers"), samplers);
                if let Some(t) = ch.get("target") {
                    let p = format!("{p}.target");
                    self.index(t, "node", &p, "nodes");
                    // `pointer`: `KHR_animation_pointer`'s, whose pointer `super::pointer` checks and follows.
                    self.one_of(t, "path", &p, &strs(&["translation", "rotation", "scale", "weights", "pointer"]));
                }
            }
            for (j, s) in items(a, "samplers").iter().enumerate() {
                let p = format!("animations[{i}].samplers[{j}]");
                self.index(s, "input", &p, "accessors");
                self.index(s, "output", &p, "accessors");
                self.one_of(s, "interpolation", &p, &strs(&["LINEAR", "STEP", "CUBICSPLINE"]));
            }
        }
    }
}

/// Components an accessor with no bufferView may declare (all zeros, then its sparse values): the file's bytes
/// justify none of them, so this documented limit bounds what they allocate (2^24 components: 64 MiB of f32, a
/// 5.6-million-vertex VEC3). Accessors with a bufferView are bounded by the bytes it holds.
pub(crate) const MAX_UNBACKED_COMPONENTS: u64 = 1 << 24;

/// Components of an accessor `type`.
fn components(ty: &str) -> Option<u64> {
    Some(match ty {
        "SCALAR" => 1,
        "VEC2" => 2,
        "VEC3" => 3,
        "VEC4" | "MAT2" => 4,
        "MAT3" => 9,
        "MAT4" => 16,
        _ => return None,
    })
}

/// The accessors whose data Draco-compressed primitives decode: the attributes their extension names, and
/// their indices.
fn draco_accessors(root: &Value) -> std::collections::BTreeSet<u64> {
    let mut out = std::collections::BTreeSet::new();
    for prim in items(root, "meshes").iter().flat_map(|m| items(m, "primitives")) {
        let Some(named) = prim.pointer("/extensions/KHR_draco_mesh_compression/attributes").and_then(Value::as_object)
        else {
            continue;
        };
        let attributes = prim.get("attributes").and_then(Value::as_object);
        out.extend(named.keys().filter_map(|k| attributes.and_then(|a| a.get(k)).and_then(Value::as_u64)));
        out.extend(prim.get("indices").and_then(Value::as_u64));
    }
    out
}

/// The accessor `i` of `root`, when it exists.
fn accessor<'v>(root: &'v Value, i: &Value) -> Option<&'v Value> {
    items(root, "accessors").get(usize::try_from(i.as_u64()?).ok()?)
}

impl Checker<'_> {
    /// Each attribute's accessor has the type its semantic needs (glTF 2.0, 3.7.2.1) and as many elements as
    /// POSITION; indices are unsigned integer scalars. The loader indexes attributes by vertex, so a NORMAL of
    /// fewer elements, or a COLOR_0 of fewer components, would read past them.
    fn attribute_shapes(&mut self) {
        let root = self.root;
        for (i, m) in items(root, "meshes").iter().enumerate() {
            for (j, prim) in items(m, "primitives").iter().enumerate() {
                let p = format!("meshes[{i}].primitives[{j}]");
                let attributes = prim.get("attributes").and_then(Value::as_object);
                let count_of = |x: &Value| accessor(root, x).and_then(|a| a.get("count")).and_then(Value::as_u64);
                let position = attributes.and_then(|a| a.get("POSITION")).and_then(count_of);
                let mut sets = vec![(format!("{p}.attributes"), attributes, false)];
                for (k, t) in items(prim, "targets").iter().enumerate() {
                    sets.push((format!("{p}.targets[{k}]"), t.as_object(), true));
                }
                for (at, map, target) in sets {
                    let Some(map) = map else { continue };
                    for (name, x) in map {
                        let Some(acc) = accessor(root, x) else { continue };
                        let ty = acc.get("type").and_then(Value::as_str).unwrap_or("");
                        let base = name.split('_').next().unwrap_or(name);
                        let allowed: &[&str] = match (base, target) {
                            ("POSITION" | "NORMAL", _) | ("TANGENT", true) => &["VEC3"],
                            ("TANGENT", false) | ("JOINTS" | "WEIGHTS", _) => &["VEC4"],
                            ("TEXCOORD", _) => &["VEC2"],
                            ("COLOR", _) => &["VEC3", "VEC4"],
                            _ => &[],
                        };
                        if !allowed.is_empty() && !allowed.contains(&ty) {
                            self.problems.push(format!(
                                "{at}.{name}: accessor {x} is {ty}, where {name} must be {}",
                                allowed.join(" or ")
                            ));
                        }
                        let count = acc.get("count").and_then(Value::as_u64);
                        if let (Some(c), Some(pc)) = (count, position) {
                            if c != pc {
                                self.problems.push(format!(
                                    "{at}.{name}: accessor {x} has {c} elements, POSITION has {pc}: every attribute \
                                     needs one per vertex"
                                ));
                            }
                        }
                    }
                }
                if let Some(acc) = prim.get("indices").and_then(|x| accessor(root, x)) {
                    let ty = acc.get("type").and_then(Value::as_str).unwrap_or("");
                    let ct = acc.get("componentType").and_then(Value::as_u64).unwrap_or(0);
                    if ty != "SCALAR" || ![5121, 5123, 5125].contains(&ct) {
                        self.problems.push(format!(
                            "{p}.indices: accessor {} is {ty} of componentType {ct}, where indices are SCALAR \
                             unsigned bytes, shorts or ints (5121, 5123, 5125)",
                            prim["indices"]
                        ));
                    }
                }
            }
        }
    }

    /// Accessors with no bufferView declare at most [`MAX_UNBACKED_COMPONENTS`] components, but for those whose
    /// data a Draco-compressed primitive decodes (bounded by the decoder's own limits, `super::draco`); sparse
    /// counts fit their accessor's.
    fn accessor_budget(&mut self) {
        let draco = draco_accessors(self.root);
        for (i, a) in items(self.root, "accessors").iter().enumerate() {
            let p = format!("accessors[{i}]");
            let count = a.get("count").and_then(Value::as_u64).unwrap_or(0);
            let n = a.get("type").and_then(Value::as_str).and_then(components).unwrap_or(1);
            let unbacked = a.get("bufferView").is_none() && !draco.contains(&(i as u64));
            if unbacked && count.saturating_mul(n) > MAX_UNBACKED_COMPONENTS {
                self.problems.push(format!(
                    "{p}.count = {count} ({n} components each) with no bufferView: over vvgen's limit of \
                     {MAX_UNBACKED_COMPONENTS} components for data the file does not hold"
                ));
            }
            let sparse = a.get("sparse").and_then(|s| s.get("count")).and_then(Value::as_u64);
            if sparse.is_some_and(|k| k > count) {
                self.problems.push(format!("{p}.sparse.count = {} exceeds {p}.count = {count}", sparse.unwrap_or(0)));
            }
        }
    }

    /// The node hierarchy must be a forest (the spec: no node has two parents, no node is its own ancestor);
    /// a cycle would otherwise pose nothing, or loop.
    fn forest(&mut self) {
        let nodes = items(self.root, "nodes");
        let mut parent: Vec<Option<usize>> = vec![None; nodes.len()];
        for (i, n) in nodes.iter().enumerate() {
            for c in items(n, "children").iter().filter_map(Value::as_u64) {
                let Some(slot) = parent.get_mut(c as usize) else { continue };
                if let Some(first) = *slot {
                    self.problems.push(format!("nodes[{c}] has two parents (nodes[{first}] and nodes[{i}])"));
                    return;
                }
                *slot = Some(i);
            }
        }
        // With one parent each, a cycle is a walk up that comes back to where it started.
        for start in 0..nodes.len() {
            let mut at = parent[start];
            for _ in 0..nodes.len() {
                match at {
                    Some(p) if p == start => {
                        self.problems
                            .push(format!("nodes[{start}] is its own ancestor (the node hierarchy has a cycle)"));
                        return;
                    }
                    Some(p) => at = parent[p],
                    None => break,
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dangling_references_and_unknown_enums_are_named() {
        let doc: Value = serde_json::from_str(
            r#"{"asset": {"version": "2.0"}, "nodes": [{"mesh": 0}], "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
               "animations": [{"channels": [{"sampler": 1, "target": {"node": 4, "path": "colour"}}], "samplers": []}]}"#,
        )
        .unwrap();
        let e = check(&doc).unwrap_err();
        assert!(
            e.contains("meshes[0].primitives[0].attributes.POSITION = 0 does not index `accessors` (0 entries)"),
            "{e}"
        );
        assert!(e.contains("animations[0].channels[0].sampler = 1 does not index `animations[0].samplers`"), "{e}");
        assert!(e.contains("animations[0].channels[0].target.node = 4 does not index `nodes` (1 entries)"), "{e}");
        assert!(e.contains(r#"target.path = "colour" is not one of "translation""#), "{e}");
        let images: Value = serde_json::from_str(
            r#"{"asset": {"version": "2.0"}, "bufferViews": [{"buffer": 0, "byteLength": 1}], "buffers": [{"byteLength": 1}],
               "images": [{"bufferView": 0}, {}, {"uri": "a.png", "bufferView": 0, "mimeType": "image/png"}]}"#,
        )
        .unwrap();
        let e = check(&images).unwrap_err();
        assert!(e.contains("images[0] is stored in a bufferView but has no mimeType"), "{e}");
        assert!(e.contains("images[1] needs exactly one of uri and bufferView"), "{e}");
        assert!(e.contains("images[2] needs exactly one of uri and bufferView"), "{e}");
        let cyclic: Value =
            serde_json::from_str(r#"{"asset": {"version": "2.0"}, "nodes": [{"children": [1]}, {"children": [0]}]}"#)
                .unwrap();
        assert!(check(&cyclic).unwrap_err().contains("is its own ancestor"));
        let two_parents: Value = serde_json::from_str(
            r#"{"asset": {"version": "2.0"}, "nodes": [{"children": [2]}, {"children": [2]}, {}]}"#,
        )
        .unwrap();
        assert_eq!(check(&two_parents), Err("nodes[2] has two parents (nodes[0] and nodes[1])".into()));
        let ok: Value = serde_json::from_str(
            r#"{"asset": {"version": "2.0"}, "nodes": [{}], "scenes": [{"nodes": [0]}], "scene": 0}"#,
        )
        .unwrap();
        assert_eq!(check(&ok), Ok(()));
    }

    /// An accessor with no bufferView is held to the budget unless a Draco-compressed primitive decodes its data:
    /// ten million vertices are refused as zeros, read as a Draco primitive's positions.
    #[test]
    fn the_unbacked_budget_spares_what_draco_decodes() {
        let doc = |draco: bool| {
            let ext = if draco {
                r#", "extensions": {"KHR_draco_mesh_compression": {"bufferView": 0, "attributes": {"POSITION": 0}}}"#
            } else {
                ""
            };
            let json = format!(
                r#"{{"asset": {{"version": "2.0"}}, "buffers": [{{"byteLength": 4}}],
                   "bufferViews": [{{"buffer": 0, "byteLength": 4}}],
                   "accessors": [{{"componentType": 5126, "count": 10000000, "type": "VEC3"}}],
                   "meshes": [{{"primitives": [{{"attributes": {{"POSITION": 0}}{ext}}}]}}]}}"#
            );
            serde_json::from_str::<Value>(&json).unwrap()
        };
        let e = check(&doc(false)).unwrap_err();
        assert!(e.contains("accessors[0].count = 10000000"), "{e}");
        assert_eq!(check(&doc(true)), Ok(()));
    }
}
