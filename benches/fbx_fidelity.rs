//! vvgen's FBX posing against Blender's own FBX import, vertex for vertex.
//!
//! `benches/blender_fbx.py` writes Blender's posed vertices of a file at some times; this loads the same file
//! with `vvgen::scene::fbx`, poses its control points at the same times and prints, per time and object, the
//! largest distance between a vertex and Blender's, as a share of the subject's height:
//!
//! ```sh
//! blender -b --factory-startup -P benches/blender_fbx.py -- FILE.fbx ref.json 0 0.5 1.0
//! cargo bench --bench fbx_fidelity -- FILE.fbx ref.json
//! ```
//!
//! `--time FILE.fbx` times what a build does with the file instead: load it, then pose 60 frames of its first
//! take at 30 fps into the renderer's buffers (median of 5 runs, after one untimed); `benches/blender_fbx.py`
//! with `--time` times Blender's import of the same file in the same session.

use std::path::Path;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).filter(|a| a != "--bench").collect();
    if let [flag, fbx] = &args[..] {
        if flag == "--time" {
            return time(Path::new(fbx));
        }
    }
    let [fbx, reference] = &args[..] else {
        eprintln!("usage: cargo bench --bench fbx_fidelity -- FILE.fbx REF.json | --time FILE.fbx");
        std::process::exit(2);
    };
    let asset = vvgen::scene::fbx::load(Path::new(fbx)).unwrap_or_else(|e| panic!("{e}"));
    let reference: serde_json::Value = serde_json::from_slice(&std::fs::read(reference).unwrap()).unwrap();
    let take = (!asset.takes.is_empty()).then_some(0);
    for frame in reference["frames"].as_array().unwrap() {
        let t = frame["time"].as_f64().unwrap();
        let ours = asset.control_points(take, t).unwrap_or_else(|e| panic!("{e}"));
        let theirs = frame["objects"].as_object().unwrap();
        let all: Vec<[f64; 3]> = theirs
            .values()
            .flat_map(|v| {
                v.as_array().unwrap().iter().map(|p| {
                    let p = p.as_array().unwrap();
                    [p[0].as_f64().unwrap(), p[1].as_f64().unwrap(), p[2].as_f64().unwrap()]
                })
            })
            .collect();
        let (lo, hi) = all.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), p| (l.min(p[2]), h.max(p[2])));
        let height = hi - lo;
        for (name, points) in &ours {
            let Some(reference) = theirs.get(name).and_then(|v| v.as_array()) else {
                println!("t = {t:.3} s  {name}: not in Blender's import");
                continue;
            };
            if reference.len() != points.len() {
                println!("t = {t:.3} s  {name}: {} vertices, Blender {}", points.len(), reference.len());
                continue;
            }
            let worst = points
                .iter()
                .zip(reference)
                .map(|(a, b)| {
                    let b = b.as_array().unwrap();
                    let d = [
                        a.x as f64 - b[0].as_f64().unwrap(),
                        a.y as f64 - b[1].as_f64().unwrap(),
                        a.z as f64 - b[2].as_f64().unwrap(),
                    ];
                    (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt()
                })
                .fold(0.0, f64::max);
            println!(
                "t = {t:.3} s  {name}: {} vertices, largest distance {worst:.2e} = {:.2e} of the height {height:.3}",
                points.len(),
                worst / height
            );
        }
    }
}

/// Load and pose 60 frames of `fbx`, as a build does: the median of 5 runs after one untimed.
fn time(fbx: &Path) {
    let run = || {
        let t0 = std::time::Instant::now();
        let asset = vvgen::scene::fbx::load(fbx).unwrap_or_else(|e| panic!("{e}"));
        let loaded = t0.elapsed();
        let take = (!asset.takes.is_empty()).then_some(0);
        let mut posed = vvgen::scene::PosedScene::default();
        for f in 0..60 {
            asset.pose(take, f as f64 / 30.0, glam::Mat4::IDENTITY, &mut posed).unwrap();
        }
        (loaded, t0.elapsed(), posed.triangle_count())
    };
    run();
    let mut runs: Vec<_> = (0..5).map(|_| run()).collect();
    runs.sort_by_key(|r| r.1);
    let (loaded, total, triangles) = runs[2];
    println!(
        "{}: {triangles} triangles; load {:.1} ms, load + 60 frames posed {:.1} ms ({:.2} ms a frame)",
        fbx.display(),
        loaded.as_secs_f64() * 1e3,
        total.as_secs_f64() * 1e3,
        (total - loaded).as_secs_f64() * 1e3 / 60.0
    );
}
