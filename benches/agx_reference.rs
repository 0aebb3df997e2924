//! vvgen's AgX view transform against Blender's.
//!
//! `cargo bench --bench agx_reference -- AgX_Base_sRGB.cube` compares vvgen's table, computed from the AgX
//! generator's published steps (`src/render/agx.rs`), with Blender's file node by node and prints the largest
//! difference in 8-bit codes of the displayed sRGB (all nodes, greys, and nodes inside Rec.709's gamut).
//! `-- --ramp ramp.json` instead prints, for each scene-linear colour Blender rendered through its AgX view
//! (`benches/blender_agx.py`), vvgen's sRGB code beside Blender's and the largest difference.

use vvgen::render::agx::Agx;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).filter(|a| a != "--bench").collect();
    match &args[..] {
        [flag, ramp] if flag == "--ramp" => ramp_vs(ramp),
        [cube] => table_vs(cube),
        _ => {
            eprintln!("usage: cargo bench --bench agx_reference -- AgX_Base_sRGB.cube | --ramp ramp.json");
            std::process::exit(2);
        }
    }
}

/// The sRGB code of display-linear `v`, unrounded.
fn code(v: f32) -> f32 {
    vvgen::scene::material::linear_to_srgb(v) * 255.0
}

fn table_vs(cube: &str) {
    let text = std::fs::read_to_string(cube).unwrap_or_else(|e| panic!("{cube}: {e}"));
    let theirs: Vec<[f32; 3]> = text
        .lines()
        .filter_map(|l| {
            let v: Vec<f32> = l.split_whitespace().filter_map(|t| t.parse().ok()).collect();
            (v.len() == 3 && !l.starts_with(char::is_alphabetic) && !l.starts_with('#')).then(|| [v[0], v[1], v[2]])
        })
        .collect();
    let ours = Agx::get().table();
    assert_eq!(theirs.len(), ours.len(), "node counts");
    let side = (ours.len() as f64).cbrt().round() as usize;
    let (mut all, mut grey, mut worst_at) = (0f32, 0f32, 0);
    let mut histogram = [0usize; 5];
    for (k, (a, b)) in ours.iter().zip(&theirs).enumerate() {
        // Compared as displayed: the node's value under the 2.4 power, sRGB-encoded, in codes.
        let d = (0..3).map(|c| (code(a.to_array()[c].powf(2.4)) - code(b[c].powf(2.4))).abs()).fold(0f32, f32::max);
        histogram[(d as usize).min(4)] += 1;
        if d > all {
            (all, worst_at) = (d, k);
        }
        let (r, g, b) = (k % side, (k / side) % side, k / (side * side));
        if r == g && g == b {
            grey = grey.max(d);
        }
    }
    let (r, g, b) = (worst_at % side, (worst_at / side) % side, worst_at / (side * side));
    println!(
        "{} nodes: largest difference {all:.3} codes at node ({r}, {g}, {b}): ours {:?}, Blender's {:?}",
        ours.len(),
        ours[worst_at],
        theirs[worst_at]
    );
    println!("greys: {grey:.3} codes");
    println!(
        "nodes by difference (codes): <1 {} · 1–2 {} · 2–3 {} · 3–4 {} · ≥4 {}",
        histogram[0], histogram[1], histogram[2], histogram[3], histogram[4]
    );
}

fn ramp_vs(path: &str) {
    let v: serde_json::Value =
        serde_json::from_slice(&std::fs::read(path).unwrap_or_else(|e| panic!("{path}: {e}"))).unwrap();
    let mut worst = 0f32;
    for s in v["samples"].as_array().expect("samples") {
        let lin: Vec<f32> = s["linear"].as_array().unwrap().iter().map(|x| x.as_f64().unwrap() as f32).collect();
        let theirs: Vec<f32> = s["srgb8"].as_array().unwrap().iter().map(|x| x.as_f64().unwrap() as f32).collect();
        let d = Agx::get().display(glam::Vec3::new(lin[0], lin[1], lin[2]));
        let ours = [code(d.x).round(), code(d.y).round(), code(d.z).round()];
        let diff = (0..3).map(|c| (ours[c] - theirs[c]).abs()).fold(0f32, f32::max);
        worst = worst.max(diff);
        if diff > 1.0 || std::env::var_os("VERBOSE").is_some() {
            println!("{lin:?}: vvgen {ours:?} Blender {theirs:?}");
        }
    }
    println!("largest difference: {worst} codes");
}
