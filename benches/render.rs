//! Renderer benchmarks (issue 4), 800 × 800, PNG encode included: CesiumMan at 1 and 4 samples per pixel, the
//! peers' 100k-triangle vertex-coloured torus (head-lit), and an 800k-point frame drawn as true 3D cubes.
//! Views: 20 cameras at radius 4 on the upper hemisphere, `camera_angle_y` 0.6911 (pyrender's bench setup).
//!
//! Run: `cargo bench --bench render [-- OUT_DIR] [--only cesium|torus|points] [--points N] [--case TEXT]
//! [--samples N] [--runs N]` (the flags run one group, one cloud size, the point cases whose label contains TEXT,
//! or CesiumMan at one sample count, and set the timed repeats, default 3: for profiling). The
//! point clouds are left in OUT_DIR (default `target/bench-data`) as `pc_100k.ply` and `pc_800k.ply`, so
//! pyrender can draw the same points in the same run (`benches/peers.sh render …`).

use std::f32::consts::{PI, TAU};
use std::path::PathBuf;
use std::time::Instant;

use glam::{Vec3, Vec4};
use vvgen::render::encode::PngCompression;
use vvgen::render::Shading;
use vvgen::render::{encode, render, Buffers, Camera, RenderSettings, SplatSettings, SplatShape, SplatSize};
use vvgen::scene::material::Material;
use vvgen::scene::ply::{self, PlyOut};
use vvgen::scene::{PosedScene, PrimKind};

mod common;

const RES: u32 = 800;

/// xorshift: the bench's own fixed stream (no need for keyed identity here).
struct Rng(u64);
impl Rng {
    fn f(&mut self) -> f32 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 40) as f32 / (1u64 << 24) as f32
    }
}

/// 20 cameras looking at `target` from radius 4 (elevation 3°–70°), vertical field of view 0.6911.
fn cameras(target: Vec3) -> Vec<Camera> {
    let mut r = Rng(0x5EED);
    let f = RES as f64 / 2.0 / (0.6911f64 / 2.0).tan();
    (0..20)
        .map(|_| {
            let (th, ph) = (r.f() * TAU, 0.05 + r.f() * (PI / 2.0 - 0.2));
            let eye = target + 4.0 * Vec3::new(th.cos() * ph.cos(), th.sin() * ph.cos(), ph.sin());
            Camera {
                width: RES,
                height: RES,
                fx: f,
                fy: f,
                cx: RES as f64 / 2.0,
                cy: RES as f64 / 2.0,
                near: 0.05,
                far: 100.0,
                c2w: Camera::look_at(eye, target, Vec3::Z),
            }
        })
        .collect()
}

/// One image: render, then encode the RGBA PNG; returns the covered fraction.
fn one(scene: &PosedScene, c: &Camera, s: &RenderSettings) -> f64 {
    let f = render(scene, c, s);
    let png = encode::rgba_png(&f.rgba, f.width, f.height, PngCompression::Fast);
    std::hint::black_box(png);
    f.coverage.iter().filter(|&&a| a > 0).count() as f64 / f.coverage.len() as f64
}

/// Median over `runs` passes of the views of (milliseconds per image one after another, each image using both
/// cores inside; milliseconds per image with the views rendered in parallel, as `vvgen build` runs them), and
/// the coverage.
fn per_image(scene: &PosedScene, cams: &[Camera], s: &RenderSettings, runs: usize) -> (f64, f64, f64) {
    use rayon::prelude::*;
    // `passes = ["rgba"]`, as the shipped examples' colour images: no depth, normal or object buffers.
    let s = &RenderSettings { buffers: Buffers { depth: false, normal: false, object: false }, ..s.clone() };
    let (mut serial, mut parallel) = (Vec::new(), Vec::new());
    let mut coverage = 0.0;
    for _ in 0..runs {
        let t = Instant::now();
        for c in cams {
            coverage = one(scene, c, s);
        }
        serial.push(t.elapsed().as_secs_f64() * 1e3 / cams.len() as f64);
        let t = Instant::now();
        cams.par_iter().for_each(|c| {
            one(scene, c, s);
        });
        parallel.push(t.elapsed().as_secs_f64() * 1e3 / cams.len() as f64);
    }
    serial.sort_by(f64::total_cmp);
    parallel.sort_by(f64::total_cmp);
    (serial[runs / 2], parallel[runs / 2], coverage)
}

fn line(label: &str, (ms, par, cov): (f64, f64, f64)) {
    println!(
        "  {label:<38} {ms:6.1} ms/image one at a time  {par:6.1} ms/image in parallel ({:5.1} images/s)  coverage {:.0} %",
        1e3 / par,
        cov * 100.0
    );
}

/// The peers' bumpy torus: 500 × 100 grid, 100 000 triangles, colours by position.
fn torus_100k() -> PosedScene {
    let common::Torus { positions, colors, indices, .. } = common::torus_100k();
    let mut normals = vec![Vec3::ZERO; positions.len()];
    for t in indices.chunks_exact(3) {
        let [a, b, c] = [0, 1, 2].map(|k| positions[t[k] as usize]);
        let n = (b - a).cross(c - a);
        t.iter().for_each(|&k| normals[k as usize] += n);
    }
    normals.iter_mut().for_each(|n| *n = n.normalize_or_zero());
    mesh(positions, normals, colors, indices, PrimKind::Triangles)
}

fn mesh(positions: Vec<Vec3>, normals: Vec<Vec3>, colors: Vec<Vec4>, indices: Vec<u32>, kind: PrimKind) -> PosedScene {
    let material = Material { double_sided: true, ..Material::default() };
    PosedScene::single(kind, positions, normals, colors, indices, material)
}

/// A scan-like cloud of `n` points spanning ~2 m (make_pointclouds.py's recipe: a sphere shell over a ground
/// patch and a torus ring, coloured by position), centred on the origin like pyrender's bench does.
fn cloud(n: usize, seed: u64) -> (Vec<Vec3>, Vec<Vec4>) {
    let mut r = Rng(seed);
    let (ns, ng) = (n * 45 / 100, n * 35 / 100);
    let mut p = Vec::with_capacity(n);
    for i in 0..n {
        p.push(if i < ns {
            let (z, a) = (r.f() * 2.0 - 1.0, r.f() * TAU);
            let s = (1.0 - z * z).sqrt();
            Vec3::new(s * a.cos(), s * a.sin(), z) * 0.6 + Vec3::new(0.0, 0.0, 0.6)
        } else if i < ns + ng {
            Vec3::new(r.f() * 2.0 - 1.0, r.f() * 2.0 - 1.0, 0.0)
        } else {
            let (a, b) = (r.f() * TAU, r.f() * TAU);
            Vec3::new((0.8 + 0.08 * b.cos()) * a.cos(), (0.8 + 0.08 * b.cos()) * a.sin(), 0.6 + 0.08 * b.sin())
        });
    }
    let (lo, hi) = p.iter().fold((Vec3::MAX, Vec3::MIN), |(l, h), q| (l.min(*q), h.max(*q)));
    let mid = (lo + hi) / 2.0;
    p.iter_mut().for_each(|q| *q -= mid);
    let c = p.iter().map(|q| ((*q - lo + mid) / (hi - lo)).clamp(Vec3::ZERO, Vec3::ONE).extend(1.0)).collect();
    (p, c)
}

fn main() {
    // As the `vvgen` binary does.
    vvgen::alloc::retain_freed_memory();
    let args: Vec<String> = std::env::args().skip(1).collect();
    // The output directory is the first argument that is neither a flag nor a flag's value.
    let out: PathBuf = args
        .iter()
        .enumerate()
        .find(|(i, a)| !a.starts_with('-') && (*i == 0 || !args[i - 1].starts_with("--")))
        .map(|(_, a)| PathBuf::from(a))
        .unwrap_or("target/bench-data".into());
    let value = |flag: &str| args.iter().position(|a| a == flag).and_then(|i| args.get(i + 1)).cloned();
    // `--only cesium|torus|points` runs one group (for profiling).
    let only = value("--only");
    let run = |group: &str| only.as_deref().is_none_or(|o| o == group);
    // `--case TEXT` runs only the point cases whose label contains TEXT, and `--points N` only the N-point cloud.
    let case = value("--case");
    let points: Option<usize> = value("--points").and_then(|v| v.parse().ok());
    let samples: Option<u32> = value("--samples").and_then(|v| v.parse().ok());
    let runs: usize = value("--runs").and_then(|v| v.parse().ok()).unwrap_or(3).max(1);
    std::fs::create_dir_all(&out).unwrap();
    println!("threads: {}, {RES}×{RES}, RGBA PNG (fast) included", rayon::current_num_threads());

    // CesiumMan through the manifest path (normalized like the shipped example), frame 0.
    let dir = out.join("render-bench");
    std::fs::create_dir_all(&dir).unwrap();
    let glb = std::fs::canonicalize("tests/data/gltf/CesiumMan/CesiumMan.glb").unwrap();
    let text = format!(
        "[dataset]\nname = \"b\"\nout = \"out\"\n[source.man]\ngltf = \"{}\"\nframes = {{ count = 24, fps = 24 }}\n\
         [transform]\nup = \"y\"\nfit = {{ height = 2.4 }}\ncenter = \"bbox\"\nover = \"all-frames\"\n",
        glb.display()
    );
    std::fs::write(dir.join("b.toml"), text).unwrap();
    let (m, _) = vvgen::manifest::load(&dir.join("b.toml")).unwrap_or_else(|r| panic!("{r:?}"));
    let scene = vvgen::settings::scene::open(&m, None).unwrap();
    let man = scene.pose(0, &mut Default::default()).unwrap().clone();
    let cams = cameras(Vec3::ZERO);
    if run("cesium") {
        println!("CesiumMan ({} triangles, 1 texture), unlit:", man.triangle_count());
    }
    for spp in [1, 4].into_iter().filter(|&n| run("cesium") && samples.is_none_or(|s| s == n)) {
        line(
            &format!("samples = {spp}"),
            per_image(&man, &cams, &RenderSettings { samples: spp, ..Default::default() }, runs),
        );
    }

    if run("torus") {
        let torus = torus_100k();
        println!("bumpy torus ({} triangles, vertex colours), lambert head light:", torus.triangle_count());
        let lit = RenderSettings { shading: Shading::Lambert, ..Default::default() };
        line("samples = 1", per_image(&torus, &cams, &lit, runs));
    }

    for (n, name) in [(100_000usize, "pc_100k.ply"), (800_000, "pc_800k.ply")]
        .into_iter()
        .filter(|&(n, _)| run("points") && points.is_none_or(|p| p == n))
    {
        let (p, c) = cloud(n, n as u64);
        let pos: Vec<[f32; 3]> = p.iter().map(|v| v.to_array()).collect();
        let col: Vec<[u8; 3]> = c.iter().map(|v| [0, 1, 2].map(|k| (v[k] * 255.0).round() as u8)).collect();
        std::fs::write(
            out.join(name),
            ply::write(&PlyOut { positions: &pos, colors: Some(&col), ..Default::default() }),
        )
        .unwrap();
        let n_pts = p.len();
        let pts = mesh(p, vec![Vec3::ZERO; n_pts], c, Vec::new(), PrimKind::Points);
        println!("{n} points (the same file pyrender draws):");
        for (label, shape, size, min_px) in [
            ("cubes, edge 4 mm (~1.1 px at 4 m)", SplatShape::Cube, SplatSize::World(0.004), 1.0),
            ("cubes, edge 4 mm, true size (min_px 0)", SplatShape::Cube, SplatSize::World(0.004), 0.0),
            ("cubes, edge 1 cm", SplatShape::Cube, SplatSize::World(0.01), 1.0),
            ("surfels, diameter 4 mm", SplatShape::Surfel, SplatSize::World(0.004), 1.0),
            ("squares, 1 px", SplatShape::Square, SplatSize::Pixels(1.0), 1.0),
        ]
        .into_iter()
        .filter(|(label, ..)| case.as_deref().is_none_or(|c| label.contains(c)))
        {
            let s = RenderSettings { splat: SplatSettings { shape, size, min_px }, ..Default::default() };
            line(label, per_image(&pts, &cams, &s, runs));
        }
    }
}
