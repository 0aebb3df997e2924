//! Point-cloud benchmarks (issue 7): 1M surface samples from a 100k-triangle textured mesh, voxel downsampling
//! of 1M points, and a full CesiumMan sequence (60 frames × 1M points, sampled, voxelized, written as PLY)
//! through the build engine with a cold cache.
//!
//! Run: `cargo bench --bench points [-- OUT_DIR] [--quick]`. The sampled 1M-point cloud is left in OUT_DIR
//! (default `target/bench-data`) as `points_1m.ply`, so Open3D can downsample the same points in the same run
//! (see docs/benchmarks.md). `--quick` skips the 60-frame sequence.

use std::path::PathBuf;
use std::sync::Arc;
use std::time::{Duration, Instant};

use glam::{Vec3, Vec4};
use vvgen::sample::{self, voxel};
use vvgen::scene::material::Material;
use vvgen::scene::ply::{self, PlyOut};
use vvgen::scene::texture::{Texture, TextureRef};
use vvgen::scene::{PosedPrimitive, PosedScene, PrimKind};

mod common;

use common::median as time;

fn ms(d: Duration) -> String {
    format!("{:8.1} ms", d.as_secs_f64() * 1e3)
}

/// The peers' bumpy torus (bench_python.py `make_mesh_100k`: 500 × 100 grid, 100 000 triangles) with uvs, a
/// 1024² sRGB texture and per-vertex colours, so every sample pays for texture and vertex-colour lookups.
fn torus_100k() -> PosedScene {
    let common::Torus { positions, uvs, colors, indices } = common::torus_100k();
    let normals = vec![Vec3::ZERO; 0];
    let size = 1024u32;
    let rgba: Vec<u8> = (0..size * size)
        .flat_map(|i| {
            let (x, y) = (i % size, i / size);
            [(x / 4) as u8, (y / 4) as u8, ((x ^ y) & 0xff) as u8, 255]
        })
        .collect();
    let texture = Texture::new(size, size, rgba, true);
    let material =
        Material { base_color: Vec4::ONE, base_color_texture: Some(TextureRef::new(0)), ..Material::default() };
    PosedScene {
        primitives: vec![PosedPrimitive {
            kind: PrimKind::Triangles,
            positions,
            normals,
            tangents: Vec::new(),
            uvs: Arc::new(uvs),
            colors: Arc::new(colors),
            indices: Arc::new(indices),
            material: 0,
            object: 0,
            gaussians: None,
        }],
        materials: Arc::new(vec![material]),
        textures: Arc::new(vec![texture]),
        lights: Vec::new(),
    }
}

fn main() {
    // As the `vvgen` binary does.
    vvgen::alloc::retain_freed_memory();
    let args: Vec<String> = std::env::args().skip(1).collect();
    let quick = args.iter().any(|a| a == "--quick");
    let out: PathBuf = args
        .iter()
        .find(|a| !a.starts_with('-'))
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from("target/bench-data"));
    std::fs::create_dir_all(&out).unwrap();
    println!("threads: {}", rayon::current_num_threads());

    let torus = torus_100k();
    println!(
        "surface sampling, 1M points from {} triangles (texture × vertex colour, normals):",
        torus.triangle_count()
    );
    let t = time(5, || sample::sample(&torus, 1_000_000, &[b"bench"]));
    println!("  sample              {}", ms(t));
    let draws = sample::draw(&torus, 1_000_000, &[b"bench"]);
    println!("    of which draw     {}", ms(time(5, || sample::draw(&torus, 1_000_000, &[b"bench"]))));
    println!("    of which evaluate {}", ms(time(5, || sample::evaluate(&torus, &draws))));
    let pts = sample::sample(&torus, 1_000_000, &[b"bench"]);
    let colors = pts.srgb8();
    let ply_bytes = ply::write(&PlyOut {
        positions: &pts.positions,
        normals: Some(&pts.normals),
        colors: Some(&colors),
        ..Default::default()
    });
    std::fs::write(out.join("points_1m.ply"), &ply_bytes).unwrap();

    println!("voxel downsampling, 1M points:");
    let t = time(5, || voxel::downsample(&pts, 0.01, Default::default()));
    println!("  torus surface, 0.01 {}  ({} voxels)", ms(t), voxel::downsample(&pts, 0.01, Default::default()).len());
    let mut s = 0x9E3779B97F4A7C15u64;
    let mut rnd = move || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        (s >> 40) as f32 / (1u64 << 24) as f32
    };
    let mut cube = sample::Points::default();
    for _ in 0..1_000_000 {
        cube.positions.push([rnd() * 2.0 - 1.0, rnd() * 2.0 - 1.0, rnd() * 2.0 - 1.0]);
        cube.normals.push([0.0, 0.0, 1.0]);
        cube.colors.push([rnd(), rnd(), rnd()]);
    }
    let t = time(5, || voxel::downsample(&cube, 0.01, Default::default()));
    println!("  uniform 2 m cube    {}  ({} voxels)", ms(t), voxel::downsample(&cube, 0.01, Default::default()).len());

    if quick {
        return;
    }
    // The whole pipeline as a user runs it: manifest → posed frames → 1M samples each → voxel means → PLY files.
    let dir = out.join("cesium-sequence");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let glb = std::fs::canonicalize("tests/data/gltf/CesiumMan/CesiumMan.glb").unwrap();
    let text = format!(
        "[dataset]\nname = \"cesium\"\nout = \"out\"\n\n[source.man]\ngltf = \"{}\"\nframes = {{ count = 60, fps = 30 }}\n\n\
         [transform]\nup = \"y\"\nfit = {{ height = 1.8 }}\n\n\
         [output.points]\nwriter = \"ply-sequence\"\npoints = 1000000\nvoxel = 0.005\n",
        glb.display()
    );
    let path = dir.join("sequence.toml");
    std::fs::write(&path, text).unwrap();
    let (m, _) = vvgen::manifest::load(&path).unwrap_or_else(|r| panic!("{r:?}"));
    let t = Instant::now();
    let report = vvgen::build::build(&m, &dir.join("cache"), Default::default(), &vvgen::build::Silent).unwrap();
    let cold = t.elapsed();
    let files: usize = report.outputs.iter().map(|(_, w)| w.files.len()).sum();
    println!("CesiumMan sequence, 60 frames × 1M samples, voxel 5 mm, cold cache:");
    println!("  build               {}  ({:.0} ms/frame, {files} files)", ms(cold), cold.as_secs_f64() * 1e3 / 60.0);
}
