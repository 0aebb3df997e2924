//! `vvgen schema`: the JSON Schema editors use (Taplo / Even Better TOML) accepts every shipped manifest and
//! rejects a typo, as checked by the reference validator (Python's `jsonschema`, draft 2020-12).

use std::path::Path;
use std::process::Command;

const VALIDATE: &str = r#"
import json, sys, tomllib, jsonschema
v = jsonschema.Draft202012Validator(json.load(open(sys.argv[1])))
for p in sys.argv[2:]:
    errors = list(v.iter_errors(tomllib.load(open(p, "rb"))))
    print(p, "invalid" if errors else "valid", "; ".join(e.message for e in errors[:3]))
"#;

#[test]
fn the_schema_accepts_the_shipped_manifests_and_rejects_typos() {
    // The schema describes the same top-level tables the parser reads.
    assert_eq!(vvgen::manifest::schema::SCHEMA_TABLES.as_slice(), vvgen::manifest::TABLES);
    // Debian's python3 (where .ci/run installs python3-jsonschema), else whichever python3 is first on PATH.
    let has = |py: &str| {
        Command::new(py).args(["-c", "import jsonschema, tomllib"]).output().is_ok_and(|o| o.status.success())
    };
    let Some(python) = ["/usr/bin/python3", "python3"].into_iter().find(|py| has(py)) else {
        eprintln!(
            "skipping: no python3 with jsonschema and tomllib (apt install python3-jsonschema; .ci/run installs it)"
        );
        return;
    };
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    let out = Command::new(env!("CARGO_BIN_EXE_vvgen")).arg("schema").output().unwrap();
    assert!(out.status.success());
    let schema: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(schema["$schema"], "https://json-schema.org/draft/2020-12/schema");
    // Descriptions come from the types' doc comments; enums list their values.
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("\"hemisphere\"") && text.contains("\"nerf-test\""), "enums");
    std::fs::write(d.join("schema.json"), &out.stdout).unwrap();
    let shipped: Vec<_> = std::fs::read_dir(Path::new(env!("CARGO_MANIFEST_DIR")).join("manifests"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .collect();
    assert!(shipped.len() >= 4);
    let base = std::fs::read_to_string(shipped.iter().find(|p| p.ends_with("cesium-man.toml")).unwrap()).unwrap();
    let typos = [
        ("veiws", base.replacen("views = 12", "veiws = 12", 1)),
        ("an unknown rig kind", base.replacen("kind   = \"hemisphere\"", "kind   = \"hemisfere\"", 1)),
        ("a string for a number", base.replacen("samples        = 4", "samples        = \"4\"", 1)),
        ("a split name that climbs out", base.replacen("[split.val]", "[split.\"../val\"]", 1)),
    ];
    let mut files: Vec<String> = shipped.iter().map(|p| p.display().to_string()).collect();
    for (i, (_, t)) in typos.iter().enumerate() {
        let p = d.join(format!("typo{i}.toml"));
        std::fs::write(&p, t).unwrap();
        files.push(p.display().to_string());
    }
    let out = Command::new(python).args(["-c", VALIDATE]).arg(d.join("schema.json")).args(&files).output().unwrap();
    let report = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    for (line, file) in report.lines().zip(&files) {
        let valid = line.split_whitespace().nth(1) == Some("valid");
        assert_eq!(valid, !file.contains("typo"), "{line}");
    }
    assert_eq!(report.lines().count(), files.len());
}
