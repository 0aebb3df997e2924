//! A mutation fuzzer that runs on stable Rust, under `cargo test` (issue 15). Seeds are the files in `tests/data`
//! and the shipped manifests; a fixed-seed stream mutates them (bit flips, interesting bytes, chunk deletes and
//! duplicates, splices between seeds, numbers swapped for extreme ones) and each mutant goes through a target
//! under `catch_unwind`: PLY reading and rendering, glTF/GLB and FBX loading (as `inspect` loads), posing and rendering,
//! and the manifest checker. Any panic fails the test; the mutants that panicked are kept in
//! `target/fuzz-crashes/` to reproduce.
//!
//! `VVGEN_FUZZ_EXECS` sets the executions per target (the suite runs 4 000 per target); a long run:
//! `VVGEN_FUZZ_EXECS=400000 cargo test --release --test it fuzz -- --nocapture`.

use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::{Path, PathBuf};

use vvgen::camera::Camera;
use vvgen::render::encode::PngCompression;
use vvgen::render::light::environment;
use vvgen::render::{render, RenderSettings};
use vvgen::scene::gltf::{self, PoseScratch};
use vvgen::scene::PosedScene;

/// splitmix64: a small, fixed-seed stream, so a run is reproducible.
pub(crate) struct Rng(pub(crate) u64);

impl Rng {
    pub(crate) fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    pub(crate) fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }

    /// One entry of `from`.
    pub(crate) fn pick<'a, T>(&mut self, from: &'a [T]) -> &'a T {
        &from[self.below(from.len())]
    }
}

const BYTES: &[u8] = &[0, 0xff, 0x7f, 0x80, b'-', b'9', b'e', b'"', b'{', b'[', b'\n', b' ', b'.'];
const NUMBERS: &[&str] =
    &["0", "-1", "255", "65536", "4294967295", "18446744073709551615", "1e308", "-1e38", "nan", "inf", "999999999"];

/// One mutant of `seed` (possibly spliced with `other`).
fn mutate(rng: &mut Rng, seed: &[u8], other: &[u8]) -> Vec<u8> {
    let mut b = seed.to_vec();
    for _ in 0..1 + rng.below(4) {
        let at = rng.below(b.len());
        match rng.below(7) {
            0 if !b.is_empty() => b[at] ^= 1 << rng.below(8),
            1 if !b.is_empty() => b[at] = BYTES[rng.below(BYTES.len())],
            2 if !b.is_empty() => {
                let end = (at + 1 + rng.below(16)).min(b.len());
                b.drain(at..end);
            }
            3 if !b.is_empty() => {
                let end = (at + 1 + rng.below(16)).min(b.len());
                let chunk = b[at..end].to_vec();
                b.splice(at..at, chunk);
            }
            4 if !other.is_empty() => {
                let from = rng.below(other.len());
                let len = rng.below(64).min(other.len() - from);
                b.splice(at..(at + len).min(b.len()), other[from..from + len].iter().copied());
            }
            5 => {
                // A run of ASCII digits at or after `at` becomes an extreme number.
                if let Some(start) = b[at..].iter().position(u8::is_ascii_digit).map(|p| p + at) {
                    let end = b[start..].iter().position(|c| !c.is_ascii_digit()).map_or(b.len(), |p| p + start);
                    b.splice(start..end, NUMBERS[rng.below(NUMBERS.len())].bytes());
                }
            }
            _ => b.insert(at.min(b.len()), rng.next() as u8),
        }
    }
    b
}

fn executions() -> usize {
    std::env::var("VVGEN_FUZZ_EXECS").ok().and_then(|v| v.parse().ok()).unwrap_or(4000)
}

/// Runs `target` on `executions()` mutants of `seeds`; returns how many ran, failing on any panic.
fn fuzz(name: &str, seeds: &[(PathBuf, Vec<u8>)], key: u64, target: impl Fn(&Path, &[u8])) -> usize {
    assert!(!seeds.is_empty(), "{name}: no seeds");
    let mut rng = Rng(key);
    let mut crashes = Vec::new();
    let n = executions();
    for i in 0..n {
        let (path, seed) = &seeds[rng.below(seeds.len())];
        let other = &seeds[rng.below(seeds.len())].1;
        let mutant = mutate(&mut rng, seed, other);
        if catch_unwind(AssertUnwindSafe(|| target(path, &mutant))).is_err() {
            let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("target/fuzz-crashes");
            std::fs::create_dir_all(&dir).unwrap();
            let ext = path.extension().map_or(String::new(), |e| e.to_string_lossy().into_owned());
            let file = dir.join(format!("{name}-{i}.{ext}"));
            std::fs::write(&file, &mutant).unwrap();
            crashes.push(format!("{} (from {})", file.display(), path.display()));
        }
    }
    assert!(crashes.is_empty(), "{name}: {} panics in {n} executions:\n{}", crashes.len(), crashes.join("\n"));
    eprintln!("fuzz {name}: {n} executions, no panic");
    n
}

/// Files under `tests/data/<dir>` with one of `exts`, with their bytes.
fn seeds(dir: &str, exts: &[&str]) -> Vec<(PathBuf, Vec<u8>)> {
    let mut out = Vec::new();
    let mut stack = vec![crate::common::data(dir)];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap().flatten() {
            let p = e.path();
            if p.is_dir() {
                stack.push(p);
            } else if p.extension().is_some_and(|x| exts.iter().any(|e| x.eq_ignore_ascii_case(e)))
                && std::fs::metadata(&p).unwrap().len() < 64 << 10
            {
                out.push((p.clone(), std::fs::read(&p).unwrap()));
            }
        }
    }
    out.sort();
    out
}

/// Renders `scene` small from a camera that frames its bounds (when it has any).
pub(crate) fn render_small(scene: &PosedScene) {
    let Some((lo, hi)) = scene.bounds() else { return };
    let (c, r) = ((lo + hi) * 0.5, (hi - lo).length().max(1e-3));
    if !(c.is_finite() && r.is_finite()) {
        return;
    }
    let c2w = Camera::look_at(c + glam::Vec3::new(0.3, -1.0, 0.6).normalize() * r * 2.0, c, glam::Vec3::Z);
    let cam = Camera { width: 16, height: 16, fx: 16.0, fy: 16.0, cx: 8.0, cy: 8.0, near: 0.01, far: 1e4, c2w };
    let _ = render(scene, &cam, &RenderSettings::default());
}

#[test]
fn fuzz_ply_reading_and_rendering() {
    let seeds = [seeds("bad/ply", &["ply"]), seeds("gltf", &["ply"])].concat();
    fuzz("ply", &seeds, 1, |path, bytes| {
        if let Ok(scene) = vvgen::scene::source::ply_scene_slice(bytes, path) {
            render_small(&scene);
        }
    });
}

#[test]
fn fuzz_stl_reading_and_rendering() {
    // SolidWorks' binary cube (its header starting with `solid`) and two ASCII solids; a mutant's size decides its
    // form, as the reader decides it, so both readers are reached.
    let seeds = seeds("stl", &["stl"]);
    let dir = tempfile::tempdir().unwrap();
    fuzz("stl", &seeds, 7, |_, bytes| {
        let path = dir.path().join("part.stl");
        std::fs::write(&path, bytes).unwrap();
        if let Ok(scene) = vvgen::scene::stl::scene(&path) {
            render_small(&scene);
        }
    });
}

#[test]
fn fuzz_drc_decoding_and_rendering() {
    // google/draco's meshes and point clouds (EdgeBreaker, kd-tree, sequential, unquantized).
    let seeds = seeds("drc", &["drc"]);
    fuzz("drc", &seeds, 8, |path, bytes| {
        if let Ok(scene) = vvgen::scene::drc::scene_slice(bytes, path) {
            render_small(&scene);
        }
    });
}

#[test]
fn fuzz_gltf_loading_posing_and_rendering() {
    let mut seeds = seeds("gltf", &["gltf", "glb"]);
    // Files the tests make: lights (KHR_lights_punctual, animated) and a normal texture with and without TANGENT.
    let made = [
        ("lights.gltf", crate::gltf_lights::floor_with_lights(683.0, 50.0, None)),
        (
            "spot.gltf",
            crate::gltf_lights::floor_with_lights(
                1.0,
                1.0,
                Some(r#"{"type": "spot", "spot": {"outerConeAngle": 0.5}}"#),
            ),
        ),
        ("normal.gltf", crate::normal_maps::quad_gltf(glam::Vec3::new(0.3, 0.2, 0.9), 1.0, false)),
        ("tangent.gltf", crate::normal_maps::quad_gltf(glam::Vec3::new(0.3, 0.2, 0.9), 0.5, true)),
    ];
    seeds.extend(made.into_iter().map(|(name, json)| (PathBuf::from(name), json.into_bytes())));
    // KTX2 textures (ETC1S and UASTC with Zstandard), so that mutants reach the KTX2 header check and the transcoder.
    for name in ["2d_etc1s", "BoxTextured_uastc"] {
        let ktx2 = std::fs::read(crate::common::data(&format!("gltf/ktx2/{name}.ktx2"))).unwrap();
        let (json, bin) = crate::compressed::box_with_image(&ktx2, "image/ktx2", false);
        seeds.push((PathBuf::from(format!("{name}.glb")), crate::common::glb_join(&json, &bin)));
    }
    fuzz("gltf", &seeds, 2, |path, bytes| {
        let Ok(asset) = gltf::load_slice(bytes, path, None) else { return };
        let clips: Vec<usize> = (0..asset.animations.len()).collect();
        let mut posed = PosedScene {
            materials: std::sync::Arc::new(asset.materials.clone()),
            textures: std::sync::Arc::clone(&asset.textures),
            ..Default::default()
        };
        let mut scratch = PoseScratch::default();
        for t in [0.0, 0.7] {
            asset.pose(&clips, t, glam::Mat4::IDENTITY, &mut scratch, &mut posed);
        }
        render_small(&posed);
    });
}

#[test]
fn fuzz_the_manifest_checker() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("manifests");
    let mut seeds: Vec<(PathBuf, Vec<u8>)> = std::fs::read_dir(&dir)
        .unwrap()
        .flatten()
        .map(|e| e.path())
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .map(|p| (p.clone(), std::fs::read(&p).unwrap()))
        .collect();
    seeds.sort();
    fuzz("manifest", &seeds, 3, |path, bytes| {
        let _ = vvgen::manifest::parse(&String::from_utf8_lossy(bytes), path);
    });
}

/// The mesh-frame seeds' material library: a textured material and a plain one (the OBJ seeds use both).
const MTL: &str = "newmtl skin\nKd 0.8 0.7 0.6\nd 1\nmap_Kd tex.png\nnewmtl plain\nKd 0.2 0.4 0.9\n";

#[test]
fn fuzz_mesh_sequence_frames() {
    // Mesh-sequence frames as captures ship them: OBJ (a library and its texture, normals, vertex colours,
    // negative and slash-free indices, polygons, objects and groups), the MTL it names, and a PLY mesh textured
    // by `comment TextureFile`. Each mutant is written in its place beside unmutated companions and read as a
    // build reads a frame: its dependencies for the key, then the scene, then a render.
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    image::RgbaImage::from_raw(2, 2, [[255, 0, 0, 255], [0, 255, 0, 255], [0, 0, 255, 255], [255; 4]].concat())
        .unwrap()
        .save(d.join("tex.png"))
        .unwrap();
    let quad = "mtllib skin.mtl\no quad\nv -0.5 -0.5 0\nv 0.5 -0.5 0\nv 0.5 0.5 0\nv -0.5 0.5 0\n\
                vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvn 0 0 1\nusemtl skin\nf 1/1/1 2/2/1 3/3/1 4/4/1\n";
    let fan = "mtllib skin.mtl\ng fan\nv 0 0 0 1 0 0\nv 1 0 0 0 1 0\nv 1 1 0 0 0 1\nv 0 1 0.5 1 1 1\n\
               v -1 0.5 0.2 0.5 0.5 0.5\nusemtl plain\nf 1 2 3 4 5\no tail\nvt 0.5 0.5\nusemtl skin\n\
               f -3/1 -2/1 -1/1\ns 1\nf 1 2 3\n";
    let ply = "ply\nformat ascii 1.0\ncomment TextureFile tex.png\nelement vertex 4\nproperty float x\n\
               property float y\nproperty float z\nproperty float s\nproperty float t\nelement face 2\n\
               property list uchar int vertex_indices\nend_header\n0 0 0 0 0\n1 0 0 1 0\n1 1 0 1 1\n0 1 0 0 1\n\
               3 0 1 2\n3 0 2 3\n";
    let seeds: Vec<(PathBuf, Vec<u8>)> = [("frame.obj", quad), ("fan.obj", fan), ("skin.mtl", MTL), ("frame.ply", ply)]
        .into_iter()
        .map(|(name, text)| (PathBuf::from(name), text.as_bytes().to_vec()))
        .collect();
    for (name, text) in &seeds {
        std::fs::write(d.join(name), text).unwrap();
    }
    // The seeds themselves load (else the mutants would test little beyond the first error).
    for (name, _) in &seeds {
        if name.extension().is_some_and(|e| e != "mtl") {
            let scene = vvgen::scene::source::mesh_frame(&d.join(name)).unwrap_or_else(|e| panic!("{name:?}: {e}"));
            assert!(scene.primitives.iter().any(|p| !p.indices.is_empty()), "{name:?}");
        }
    }
    fuzz("mesh-frame", &seeds, 4, |path, bytes| {
        // Companions as seeded (a mutant that panicked left its file behind), then the mutant in its place.
        for (name, text) in &seeds {
            std::fs::write(d.join(name), if name == path { bytes } else { text }).unwrap();
        }
        // An MTL mutant is read through the OBJ that names it.
        let frame = d.join(if path.extension().is_some_and(|e| e == "mtl") { Path::new("frame.obj") } else { path });
        if vvgen::scene::source::mesh_frame_deps(&frame).is_ok() {
            if let Ok(scene) = vvgen::scene::source::mesh_frame(&frame) {
                render_small(&scene);
            }
        }
    });
}

#[test]
fn fuzz_environment_maps() {
    // Equirectangular maps as `[environment] map` reads them: OpenEXR (RLE and ZIP, as vvgen writes them) and
    // Radiance HDR, small so that a mutant decodes in microseconds. Each is read as check and build do (header,
    // then texels) and looked up.
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let (w, h) = (8u32, 4u32);
    let channel = |k: f32| (0..w * h).map(|i| k * (i % w) as f32 + 0.1 * (i / w) as f32).collect::<Vec<f32>>();
    let (r, g, b) = (channel(0.5), channel(0.25), channel(2.0));
    let rgb = [("R", &r[..]), ("G", &g[..]), ("B", &b[..])];
    let mut seeds: Vec<(PathBuf, Vec<u8>)> = [("rle.exr", PngCompression::Fast), ("zip.exr", PngCompression::Default)]
        .into_iter()
        .map(|(name, c)| (PathBuf::from(name), vvgen::render::encode::f32_exr(&rgb, w, h, c)))
        .collect();
    let hdr = image::Rgb32FImage::from_fn(w, h, |x, y| {
        let i = (y * w + x) as usize;
        image::Rgb([r[i], g[i], b[i]])
    });
    image::DynamicImage::ImageRgb32F(hdr).save(d.join("map.hdr")).unwrap();
    seeds.push((PathBuf::from("map.hdr"), std::fs::read(d.join("map.hdr")).unwrap()));
    let read = |path: &Path| {
        environment::header(path)?;
        environment::load(path)
    };
    for (name, bytes) in &seeds {
        std::fs::write(d.join(name), bytes).unwrap();
        let map = read(&d.join(name)).unwrap_or_else(|e| panic!("{name:?}: {e}"));
        assert_eq!((map.width, map.height), (w, h), "{name:?}");
    }
    fuzz("environment", &seeds, 5, |path, bytes| {
        let file = d
            .join(path.file_name().unwrap())
            .with_extension(format!("mutant.{}", path.extension().unwrap().to_string_lossy()));
        std::fs::write(&file, bytes).unwrap();
        if let Ok(map) = read(&file) {
            for v in [glam::Vec3::X, glam::Vec3::NEG_Z, glam::Vec3::new(0.3, -0.4, 0.8)] {
                assert!(map.radiance(v).is_finite());
            }
        }
    });
}

#[test]
fn fuzz_fbx_loading_posing_and_rendering() {
    // The small FBX files under tests/data (the y-up and z-up scenes, the blend-shape animation), ufbx's fuzz
    // cases and an ASCII file, loaded from memory as a build loads them from disk, posed at rest and in their first take, rendered.
    let mut seeds = seeds("fbx", &["fbx"]);
    // An ASCII FBX (6100, skinned, one take): text mutates into files that still parse, and so reaches posing;
    // binary FBX keeps its arrays deflated, where most mutants stop.
    // It is drawn as often as all the binary files together.
    let ascii = crate::common::data("fbx/blender_279_sausage_6100_ascii.fbx");
    let text = std::fs::read(&ascii).unwrap();
    seeds.extend(std::iter::repeat_n((ascii, text), seeds.len()));
    let loaded = std::sync::atomic::AtomicUsize::new(0);
    let n = fuzz("fbx", &seeds, 6, |path, bytes| {
        let Ok(asset) = vvgen::scene::fbx::load_slice(bytes, path) else { return };
        loaded.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        let mut posed = PosedScene::default();
        for (take, t) in [(None, 0.0), (Some(0), 0.0), (Some(0), 0.5)] {
            let take = take.filter(|_| !asset.takes.is_empty());
            if asset.pose(take, t, glam::Mat4::IDENTITY, &mut posed).is_ok() {
                render_small(&posed);
            }
        }
        let _ = asset.control_points(None, 0.0);
    });
    // Mutants that still load are what reach posing and rendering: a target that rejects everything would test
    // only the header check.
    let loaded = loaded.into_inner();
    eprintln!("fuzz fbx: {loaded} of {n} mutants loaded");
    assert!(loaded * 20 >= n, "only {loaded} of {n} mutants loaded");
}
