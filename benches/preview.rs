//! Preview cost: the main example (`manifests/cesium-man.toml`) built cold with and without its previews,
//! alternating, 3 times each (each build in a fresh cache and output folder); reports the medians, the
//! preview's share of the cold build (target: under 10 %) and the preview actions' own time.
//! Run: `cargo bench --bench preview`.

use std::time::Instant;

use vvgen::build::{self, Silent};
use vvgen::plan::actions::Kind;

fn main() {
    vvgen::alloc::retain_freed_memory();
    let manifest = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("manifests/cesium-man.toml");
    let (mut with, mut without, mut own) = (Vec::new(), Vec::new(), Vec::new());
    for _ in 0..3 {
        for preview in [true, false] {
            let scratch = tempfile::tempdir().unwrap();
            // The manifest as shipped, its dataset written to the scratch folder instead of beside it.
            let text = std::fs::read_to_string(&manifest).unwrap().replace("../out/cesium-man", "out");
            let text = text.replace("../tests/", &format!("{}/tests/", env!("CARGO_MANIFEST_DIR")));
            let mut m = build::Build::from_manifest_str(&text, scratch.path()).unwrap().manifest().clone();
            m.dataset.preview = preview;
            let t = Instant::now();
            let r = build::build(&m, &scratch.path().join("cache"), Default::default(), &Silent).unwrap();
            let secs = t.elapsed().as_secs_f64();
            if preview {
                with.push(secs);
                let kinds = [Kind::PreviewSheet, Kind::PreviewRig, Kind::PreviewStrip];
                own.push(kinds.iter().map(|k| r.actions.get(k).map_or(0.0, |c| c.seconds)).sum::<f64>());
            } else {
                without.push(secs);
            }
        }
    }
    let median = |v: &mut Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    let (a, b, c) = (median(&mut with), median(&mut without), median(&mut own));
    println!("main example, cold: {a:.2} s with previews, {b:.2} s without (medians of 3)");
    println!(
        "previews add {:.1} % (preview actions alone: {c:.2} s, {:.1} % of the build)",
        100.0 * (a - b) / b,
        100.0 * c / a
    );
}
