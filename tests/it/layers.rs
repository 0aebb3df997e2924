//! The house's layering, read off the sources (ARCHITECTURE.md): `manifest` is the vocabulary and imports
//! nothing of the crate above it, `render` and `scene` know no manifest (they take their own inputs, which
//! `settings` translates), and no import circle spans two top-level modules.

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

/// Top-level module → the top-level modules its non-test code names as `crate::…`.
fn imports() -> BTreeMap<String, BTreeSet<String>> {
    let mut edges: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    for (rel, bytes) in crate::common::tree(&src).into_iter().filter(|(rel, _)| rel.ends_with(".rs")) {
        let top = rel.split('/').next().unwrap().trim_end_matches(".rs").to_string();
        let text = String::from_utf8(bytes).unwrap();
        // Unit tests may reach anywhere: only the code above them counts.
        let code = text.split("#[cfg(test)]").next().unwrap();
        for line in code.lines().map(str::trim).filter(|l| !l.starts_with("//")) {
            for (at, _) in line.match_indices("crate::") {
                let name: String = line[at + 7..].chars().take_while(|c| c.is_ascii_lowercase() || *c == '_').collect();
                if !name.is_empty() && name != top {
                    edges.entry(top.clone()).or_default().insert(name);
                }
            }
        }
    }
    edges
}

#[test]
fn layers_import_downward_only() {
    let edges = imports();
    assert_eq!(edges.get("manifest"), None, "manifest imports {:?}", edges.get("manifest"));
    for stage in ["render", "scene"] {
        assert!(!edges.get(stage).is_some_and(|e| e.contains("manifest")), "{stage} imports the manifest");
    }
    // A module reaching itself through another is a circle.
    let reaches = |from: &str, to: &str| {
        let (mut seen, mut todo) = (BTreeSet::new(), vec![from.to_string()]);
        while let Some(m) = todo.pop() {
            for n in edges.get(&m).into_iter().flatten() {
                if n == to {
                    return true;
                }
                if seen.insert(n.clone()) {
                    todo.push(n.clone());
                }
            }
        }
        false
    };
    for (from, to) in edges.iter().flat_map(|(f, ts)| ts.iter().map(move |t| (f, t))) {
        assert!(!reaches(to, from), "an import circle: {from} → {to} → … → {from}");
    }
    assert!(edges.len() > 10, "the walk found the modules: {edges:?}");
}
