//! Point-cloud sequences (issue 7): samples on the posed surface, texture colours at the sampled uv, the same
//! bytes whatever the thread count, voxel reductions, the sequence metadata, and a voxel-size change that re-runs
//! only the reduction.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use glam::{Vec2, Vec3, Vec4};
use vvgen::sample::{self, voxel};
use vvgen::scene::material::Material;
use vvgen::scene::ply;
use vvgen::scene::texture::{Texture, TextureRef, Wrap};
use vvgen::scene::{PosedPrimitive, PosedScene, PrimKind};

fn cesium_manifest(dir: &Path, output: &str) -> PathBuf {
    let text = format!("{}{output}", crate::common::cesium_head(3, 2, 1.8, "seed = 3", "over = \"all-frames\""));
    let p = dir.join("m.toml");
    std::fs::write(&p, text).unwrap();
    p
}

fn build(manifest: &Path, threads: usize) -> vvgen::build::Report {
    let m = crate::common::load(manifest);
    let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
    pool.install(|| {
        vvgen::build::build(&m, &vvgen::build::default_cache_dir(&m), Default::default(), &vvgen::build::Silent)
    })
    .unwrap()
}

fn read_ply(p: &Path) -> ply::PlyData {
    ply::read(&std::fs::read(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))).unwrap()
}

/// Distance from `p` to triangle (a, b, c) (Ericson, Real-Time Collision Detection, 5.1.5), in f64.
fn point_triangle_distance(p: [f64; 3], a: [f64; 3], b: [f64; 3], c: [f64; 3]) -> f64 {
    let sub = |u: [f64; 3], v: [f64; 3]| [u[0] - v[0], u[1] - v[1], u[2] - v[2]];
    let dot = |u: [f64; 3], v: [f64; 3]| u[0] * v[0] + u[1] * v[1] + u[2] * v[2];
    let at = |u: f64, v: f64, w: f64| [0, 1, 2].map(|k| a[k] * u + b[k] * v + c[k] * w);
    let (ab, ac, ap) = (sub(b, a), sub(c, a), sub(p, a));
    let (d1, d2) = (dot(ab, ap), dot(ac, ap));
    let q = if d1 <= 0.0 && d2 <= 0.0 {
        a
    } else {
        let bp = sub(p, b);
        let (d3, d4) = (dot(ab, bp), dot(ac, bp));
        let cp = sub(p, c);
        let (d5, d6) = (dot(ab, cp), dot(ac, cp));
        let (va, vb, vc) = (d3 * d6 - d5 * d4, d5 * d2 - d1 * d6, d1 * d4 - d3 * d2);
        if d3 >= 0.0 && d4 <= d3 {
            b
        } else if d6 >= 0.0 && d5 <= d6 {
            c
        } else if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
            let v = d1 / (d1 - d3);
            at(1.0 - v, v, 0.0)
        } else if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
            let w = d2 / (d2 - d6);
            at(1.0 - w, 0.0, w)
        } else if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
            let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
            at(0.0, 1.0 - w, w)
        } else {
            let s = 1.0 / (va + vb + vc);
            at(va * s, vb * s, vc * s)
        }
    };
    dot(sub(p, q), sub(p, q)).sqrt()
}

#[test]
fn samples_lie_on_the_posed_surface_of_their_frame() {
    let dir = tempfile::tempdir().unwrap();
    let m = cesium_manifest(dir.path(), "[output.p]\nwriter = \"ply-sequence\"\npoints = 600\n");
    build(&m, 2);
    let (manifest, _) = vvgen::manifest::load(&m).unwrap();
    let scene = vvgen::settings::scene::open(&manifest, None).unwrap();
    let mut poser = Default::default();
    for f in [0usize, 2] {
        let posed = scene.pose(f, &mut poser).unwrap();
        let (lo, hi) = posed.bounds().unwrap();
        let extent = (hi - lo).max_element() as f64;
        let tris: Vec<[[f64; 3]; 3]> = posed
            .primitives
            .iter()
            .filter(|p| p.kind == PrimKind::Triangles)
            .flat_map(|p| {
                p.indices
                    .chunks_exact(3)
                    .map(|t| t.iter().map(|&i| p.positions[i as usize].as_dvec3().to_array()).collect::<Vec<_>>())
            })
            .map(|v| [v[0], v[1], v[2]])
            .collect();
        let cloud = read_ply(&dir.path().join(format!("out/m_points/m_{f:04}.ply")));
        assert_eq!(cloud.positions.len(), 600);
        for q in &cloud.positions {
            let q = q.map(f64::from);
            let d = tris.iter().map(|t| point_triangle_distance(q, t[0], t[1], t[2])).fold(f64::MAX, f64::min);
            assert!(d < 1e-5 * extent, "frame {f}: {q:?} is {d} from the surface (extent {extent})");
        }
    }
}

/// An 8×8 sRGB texture with a different colour in every texel, on the unit quad z = 0 with uv = (x, 1 − y).
fn textured_quad() -> (PosedScene, Vec<u8>) {
    let size = 8u32;
    let rgba: Vec<u8> = (0..size * size)
        .flat_map(|i| [(i * 37 % 256) as u8, (i * 91 % 256) as u8, (255 - i * 13 % 256) as u8, 255])
        .collect();
    let positions =
        vec![Vec3::new(0.0, 0.0, 0.0), Vec3::new(1.0, 0.0, 0.0), Vec3::new(1.0, 1.0, 0.0), Vec3::new(0.0, 1.0, 0.0)];
    let uvs = positions.iter().map(|p| Vec2::new(p.x, 1.0 - p.y)).collect();
    let tex = TextureRef { wrap_s: Wrap::Clamp, wrap_t: Wrap::Clamp, ..TextureRef::new(0) };
    let scene = PosedScene {
        primitives: vec![PosedPrimitive {
            kind: PrimKind::Triangles,
            positions,
            normals: vec![Vec3::Z; 4],
            tangents: Vec::new(),
            uvs: Arc::new(uvs),
            colors: Arc::new(Vec::new()),
            indices: Arc::new(vec![0, 1, 2, 0, 2, 3]),
            material: 0,
            object: 0,
            gaussians: None,
        }],
        materials: Arc::new(vec![Material {
            base_color: Vec4::new(1.0, 0.5, 1.0, 1.0),
            base_color_texture: Some(tex),
            ..Material::default()
        }]),
        textures: Arc::new(vec![Texture::new(size, size, rgba.clone(), true)]),
        lights: Vec::new(),
    };
    (scene, rgba)
}

#[test]
fn textured_quad_colours_match_the_texture_at_the_sampled_uv() {
    let (scene, rgba) = textured_quad();
    let decode = |v: u8| {
        let c = v as f64 / 255.0;
        if c <= 0.04045 {
            c / 12.92
        } else {
            ((c + 0.055) / 1.055).powf(2.4)
        }
    };
    // Bilinear in linear light with clamp-to-edge, texel centres at +0.5 (glTF / GL), written out here from the
    // definition rather than through the renderer's sampler.
    let texel = |x: i64, y: i64, ch: usize| {
        let (x, y) = (x.clamp(0, 7) as usize, y.clamp(0, 7) as usize);
        decode(rgba[(y * 8 + x) * 4 + ch])
    };
    let expect = |u: f64, v: f64, ch: usize| {
        let (fx, fy) = (u * 8.0 - 0.5, v * 8.0 - 0.5);
        let (x0, y0) = (fx.floor(), fy.floor());
        let (tx, ty) = (fx - x0, fy - y0);
        let (x0, y0) = (x0 as i64, y0 as i64);
        let top = texel(x0, y0, ch) * (1.0 - tx) + texel(x0 + 1, y0, ch) * tx;
        let bottom = texel(x0, y0 + 1, ch) * (1.0 - tx) + texel(x0 + 1, y0 + 1, ch) * tx;
        top * (1.0 - ty) + bottom * ty
    };
    let pts = sample::sample(&scene, 5000, &[b"quad"]);
    assert_eq!(pts.len(), 5000);
    let factor = [1.0, 0.5, 1.0];
    for (p, c) in pts.positions.iter().zip(&pts.colors) {
        let (u, v) = (p[0] as f64, 1.0 - p[1] as f64);
        for ch in 0..3 {
            let want = expect(u, v, ch) * factor[ch];
            assert!((c[ch] as f64 - want).abs() < 2e-3, "at uv ({u}, {v}) channel {ch}: {} vs {want}", c[ch]);
        }
    }
}

#[test]
fn sampling_and_reduction_do_not_depend_on_the_thread_count() {
    let (quad, _) = textured_quad();
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| {
            // More than one parallel chunk, so the work really is split.
            let pts = sample::sample(&quad, 300_000, &[b"threads"]);
            let reduced = voxel::downsample(&pts, 0.01, voxel::Reduction::default());
            let nearest = voxel::downsample(
                &pts,
                0.02,
                voxel::Reduction { reduce: voxel::Reduce::Nearest, position: voxel::VoxelPosition::Points },
            );
            (pts.to_bytes(), reduced.to_bytes(), nearest.to_bytes())
        })
    };
    assert!(run(1) == run(2), "1 and 2 threads gave different bytes");
}

#[test]
fn nearest_and_first_keep_one_sample_per_voxel() {
    let dir = tempfile::tempdir().unwrap();
    let outputs = "[output.raw]\nwriter = \"ply-sequence\"\npoints = 20000\ndir = \"raw\"\n\
                   [output.near]\nwriter = \"ply-sequence\"\npoints = 20000\nvoxel = 0.05\nreduce = \"nearest\"\ndir = \"near\"\n\
                   [output.first]\nwriter = \"ply-sequence\"\npoints = 20000\nvoxel = 0.05\nreduce = \"first\"\ndir = \"first\"\n\
                   [output.centre]\nwriter = \"ply-sequence\"\npoints = 20000\nvoxel = 0.05\nposition = \"center\"\ndir = \"centre\"\n";
    build(&cesium_manifest(dir.path(), outputs), 2);
    let out = dir.path().join("out");
    // The three outputs share the seed and sample settings, so they reduce the very samples `raw` holds.
    let raw = read_ply(&out.join("raw/m_0001.ply"));
    let cell = |p: &[f32; 3]| p.map(|c| (c as f64 / 0.05).floor() as i64);
    let mut by_cell: std::collections::BTreeMap<[i64; 3], Vec<usize>> = Default::default();
    for (i, p) in raw.positions.iter().enumerate() {
        by_cell.entry(cell(p)).or_default().push(i);
    }
    let centre = |c: [i64; 3]| c.map(|v| (v as f64 + 0.5) * 0.05);
    let d2 = |p: &[f32; 3], c: [f64; 3]| (0..3).map(|k| (p[k] as f64 - c[k]).powi(2)).sum::<f64>();
    let near = read_ply(&out.join("near/m_0001.ply"));
    let first = read_ply(&out.join("first/m_0001.ply"));
    assert_eq!(near.positions.len(), by_cell.len());
    assert_eq!(first.positions.len(), by_cell.len());
    for (p, q) in near.positions.iter().zip(&first.positions) {
        let members = &by_cell[&cell(p)];
        let c = centre(cell(p));
        let best = members.iter().map(|&i| d2(&raw.positions[i], c)).fold(f64::MAX, f64::min);
        assert!(members.iter().any(|&i| raw.positions[i] == *p), "{p:?} is one of the samples");
        assert_eq!(d2(p, c), best, "nearest to the voxel centre");
        assert_eq!(*q, raw.positions[by_cell[&cell(q)][0]], "first sample of its voxel");
    }
    for p in &read_ply(&out.join("centre/m_0001.ply")).positions {
        let c = centre(cell(p));
        assert!((0..3).all(|k| (p[k] as f64 - c[k]).abs() < 1e-6), "{p:?} at its voxel centre");
    }
}

#[test]
fn sequence_metadata_records_times_counts_and_the_grid() {
    let dir = tempfile::tempdir().unwrap();
    let output =
        "[output.v]\nwriter = \"ply-sequence\"\npoints = 30000\nvox = 9\npattern = \"{name}_vox9_{frame:04}.ply\"\n";
    build(&cesium_manifest(dir.path(), output), 2);
    let root = dir.path().join("out/m_points");
    let meta: serde_json::Value =
        serde_json::from_slice(&std::fs::read(root.join(vvgen::export::META)).unwrap()).unwrap();
    let seq = &meta["sequence"];
    let frames = seq["frames"].as_array().unwrap();
    assert_eq!(frames.len(), 3);
    let g = &seq["grid"];
    assert_eq!(g["size"], 512);
    let (origin, cell) = (g["origin"].as_array().unwrap(), g["cell"].as_f64().unwrap());
    for (f, e) in frames.iter().enumerate() {
        assert_eq!(e["time"].as_f64().unwrap(), f as f64 / 2.0);
        let file = e["file"].as_str().unwrap();
        assert_eq!(file, format!("m_vox9_{f:04}.ply"));
        let cloud = read_ply(&root.join(file));
        assert_eq!(e["points"].as_u64().unwrap() as usize, cloud.positions.len());
        // Mapping the integer coordinates back with the recorded grid lands on the posed surface's bounds.
        let world: Vec<[f64; 3]> = cloud
            .positions
            .iter()
            .map(|p| [0, 1, 2].map(|k| origin[k].as_f64().unwrap() + (p[k] as f64 + 0.5) * cell))
            .collect();
        let top = world.iter().map(|p| p[2]).fold(f64::MIN, f64::max);
        let bottom = world.iter().map(|p| p[2]).fold(f64::MAX, f64::min);
        assert!((top - bottom - 1.8).abs() < 0.1, "height {} (fit to 1.8)", top - bottom);
    }
}

#[test]
fn a_voxel_size_change_reruns_only_the_reduction() {
    use vvgen::plan::actions::Kind;
    let dir = tempfile::tempdir().unwrap();
    let m = cesium_manifest(dir.path(), "[output.p]\nwriter = \"ply-sequence\"\npoints = 5000\nvoxel = 0.02\n");
    let r = build(&m, 2);
    assert_eq!((r.ran(Kind::SampleFrame), r.ran(Kind::PointFrame)), (3, 3));
    let m = cesium_manifest(dir.path(), "[output.p]\nwriter = \"ply-sequence\"\npoints = 5000\nvoxel = 0.04\n");
    let r = build(&m, 2);
    // Three frames: three new reductions, and the samples found in the cache.
    assert_eq!((r.ran(Kind::SampleFrame), r.ran(Kind::PointFrame)), (0, 3));
    let cloud = read_ply(&dir.path().join("out/m_points/m_0000.ply"));
    assert!(cloud.positions.len() < 5000);
}

#[test]
fn round_trip_the_vox_sequence_renders_back_as_cubes_where_the_mesh_was() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let view = "[render]\nresolution = [64, 64]\nsamples = 4\nsplat = { shape = \"cube\", min_px = 0 }\n\
                [rig.o]\nkind = \"orbit\"\nradius = 4.0\nelevation_deg = 20.0\n[split.test]\nrig = \"o\"\nviews = 2\n";
    // True cube sizes (min_px = 0): at 64² the default one-pixel minimum would widen this 10-pixel-wide
    // silhouette by half a pixel on each side, and the comparison is of geometry.
    // Step 1: the mesh, rendered, and as a vox9 sequence; step 2 (its own manifest, same `out`, step 1 as its
    // `after`): the sequence as a source, rendered from the same cameras. One build call does both, and the
    // second manifest checks before the sequence exists.
    cesium_manifest(
        d,
        &format!(
            "{view}[output.v]\nwriter = \"ply-sequence\"\npoints = 200000\nvox = 9\n[output.d]\nwriter = \"dnerf\"\n"
        ),
    );
    let cloud = d.join("cloud.toml");
    let text = format!(
        "[dataset]\nname = \"m\"\nout = \"out\"\ncache = \"cache\"\nseed = 3\nafter = [\"m.toml\"]\n\
         [source.c]\nply_sequence = \"out/m_points/m_{{frame:04}}.ply\"\nframes = {{ start = 0, end = 2, fps = 2 }}\n\
         [transform]\nfit = {{ height = 1.8 }}\ncenter = \"bbox\"\nover = \"all-frames\"\n{view}[output.d]\nwriter = \"dnerf\"\ndir = \"cloud\"\n"
    );
    std::fs::write(&cloud, text).unwrap();
    let report = build(&cloud, 2);
    let after: Vec<&str> = report.after.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(after, ["m.toml/d", "m.toml/v"]);
    assert!(d.join("out/m_points/m_0002.ply").exists(), "the second manifest pruned the first one's files");
    let alpha = |p: PathBuf| {
        image::open(&p)
            .unwrap_or_else(|e| panic!("{}: {e}", p.display()))
            .to_rgba8()
            .pixels()
            .map(|px| px[3] >= 128)
            .collect::<Vec<_>>()
    };
    let frames = |root: &str| {
        let t: serde_json::Value =
            serde_json::from_slice(&std::fs::read(d.join(root).join("transforms_test.json")).unwrap()).unwrap();
        t["frames"].as_array().unwrap().clone()
    };
    let (mesh_frames, cloud_frames) = (frames("out/m_dnerf"), frames("out/cloud"));
    assert_eq!(mesh_frames.len(), 6);
    for (m, c) in mesh_frames.iter().zip(&cloud_frames) {
        assert_eq!((&m["time"], &m["transform_matrix"]), (&c["time"], &c["transform_matrix"]), "same cameras");
        let f = m["time"].as_f64().unwrap();
        let name = format!("{}.png", m["file_path"].as_str().unwrap());
        let (a, b) = (alpha(d.join("out/m_dnerf").join(&name)), alpha(d.join("out/cloud").join(&name)));
        let inter = a.iter().zip(&b).filter(|(x, y)| **x && **y).count() as f64;
        let union = a.iter().zip(&b).filter(|(x, y)| **x || **y).count() as f64;
        assert!(union > 100.0 && inter / union > 0.9, "frame {f}: IoU {}", inter / union);
    }
}

/// An initialization cloud has the size asked for, whatever the input's: a point-cloud source's own points are
/// subsampled (keyed, without replacement), not all copied in (40 frames of 800k points made a 32M-point cloud and
/// held it in memory).
#[test]
fn init_clouds_of_point_sources_have_the_size_asked_for() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    let text = format!(
        "[dataset]\nname = \"t\"\nout = \"out\"\ncache = \"cache\"\n\
         [source.torus]\nply_sequence = \"{}\"\nframes = {{ start = 1000, end = 1002 }}\ntransform = {{ up = \"y\" }}\n\
         [transform]\nfit = {{ height = 0.6 }}\ncenter = \"bbox\"\n\
         [render]\nresolution = [32, 32]\n[rig.h]\nkind = \"hemisphere\"\n[split.train]\nrig = \"h\"\nviews = 1\n\
         [output.d]\nwriter = \"dnerf\"\ninit_points = 300\n\
         [output.c]\nwriter = \"colmap\"\ninit_points = 100\n",
        crate::common::data("seq/torus_vox10_{frame:04}.ply").display()
    );
    std::fs::write(d.join("m.toml"), text).unwrap();
    let m = crate::common::load(&d.join("m.toml"));
    vvgen::build::build(&m, &d.join("cache"), Default::default(), &vvgen::build::Silent).unwrap();
    let cloud = read_ply(&d.join("out/t_dnerf/points3d.ply"));
    assert_eq!(cloud.positions.len(), 300, "3 frames × 100 of their 3996 points");
    // Distinct points: sampled without replacement.
    let mut seen: Vec<[u32; 3]> = cloud.positions.iter().map(|p| p.map(f32::to_bits)).collect();
    seen.sort();
    seen.dedup();
    assert!(seen.len() > 290, "{} distinct", seen.len());
    let txt = std::fs::read_to_string(d.join("out/t_colmap/frame_0000/sparse/0/points3D.txt")).unwrap();
    assert_eq!(txt.lines().filter(|l| !l.starts_with('#')).count(), 100);
}
