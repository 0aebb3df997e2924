//! Every dataset writer, checked the way its consumer reads it (../shared/specs/consumer-formats.md): the test
//! re-reads the written files following the consumer's own rules (not vvgen's structs), projects the posed
//! CesiumMan vertices of each image's frame with the written camera, and requires ≥ 99 % of the front-facing
//! ones to land within 0.5 px of a covered pixel. Layout and key rules of each consumer are checked alongside.

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use glam::{DMat3, DMat4, DQuat, DVec3, DVec4};
use serde_json::Value;
use vvgen::scene::{Poser, PrimKind, Scene};

const FRAMES: usize = 3;
const W: u32 = 128;

struct Built {
    _tmp: tempfile::TempDir,
    out: PathBuf,
    scene: Scene,
}

/// Background of the opaque build (COLMAP and DyNeRF images carry no alpha): pure green, absent from CesiumMan.
const KEY: [u8; 3] = [0, 255, 0];

fn manifest_text(out: &Path, cache: &Path, opaque: bool) -> String {
    let asset = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/gltf/CesiumMan/CesiumMan.glb");
    format!(
        r#"
[dataset]
name  = "man"
out   = "{out}"
cache = "{cache}"
seed  = 3

[source.man]
gltf   = "{asset}"
frames = {{ count = {FRAMES}, fps = 2 }}

[transform]
up     = "y"
fit    = {{ height = 2.4 }}
center = "bbox"
over   = "all-frames"

[render]
resolution = [{W}, {W}]
samples    = 4
passes     = ["rgba", "depth", "mask"]
{background}

[rig.hemi]
kind = "hemisphere"

[rig.ring]
kind     = "orbit"
schedule = "nerf-test"

[split.train]
rig   = "hemi"
views = 4

[split.val]
rig  = "hemi"
time = "monocular"

[split.test]
rig   = "ring"
views = 2

{outputs}
"#,
        out = out.display(),
        cache = cache.display(),
        asset = asset.display(),
        background = if opaque {
            {
                "background = [0.0, 1.0, 0.0]"
            }
        } else {
            {
                ""
            }
        },
        outputs = if opaque {
            {
                OPAQUE_OUTPUTS
            }
        } else {
            {
                ALPHA_OUTPUTS
            }
        },
    )
}

const ALPHA_OUTPUTS: &str = r#"
[output.dnerf]
writer      = "dnerf"
init_points = 2000

[output.ns]
writer      = "nerfstudio"
init_points = 2000

[output.ngp]
writer = "instant-ngp"

[output.static]
writer = "static-frames"
init_points = 0

[output.points]
writer = "ply-sequence"
points = 2000
"#;

const OPAQUE_OUTPUTS: &str = r#"
[output.colmap]
writer      = "colmap"
init_points = 500

[output.llff]
writer = "dynerf"
splits = ["train", "test"]
init_points = 500
"#;

fn built() -> &'static Built {
    static B: OnceLock<Built> = OnceLock::new();
    B.get_or_init(|| build(false))
}

fn built_opaque() -> &'static Built {
    static B: OnceLock<Built> = OnceLock::new();
    B.get_or_init(|| build(true))
}

fn build(opaque: bool) -> Built {
    {
        let tmp = tempfile::tempdir().unwrap();
        let out = tmp.path().join("out");
        let path = tmp.path().join("m.toml");
        std::fs::write(&path, manifest_text(&out, &tmp.path().join("cache"), opaque)).unwrap();
        let (m, _) = vvgen::manifest::load(&path).unwrap_or_else(|r| panic!("{}", r.render(false)));
        let cache = vvgen::build::default_cache_dir(&m);
        vvgen::build::build(&m, &cache, Default::default(), &vvgen::build::Silent).unwrap();
        let scene = vvgen::settings::scene::open(&m, None).unwrap();
        Built { _tmp: tmp, out, scene }
    }
}

fn read_json(p: &Path) -> Value {
    serde_json::from_str(&std::fs::read_to_string(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))).unwrap()
}

/// A camera as a consumer understands it: OpenGL camera-to-world and pinhole intrinsics.
struct Cam {
    c2w: DMat4,
    fx: f64,
    fy: f64,
    cx: f64,
    cy: f64,
}

fn gl_matrix(v: &Value) -> DMat4 {
    let rows: Vec<Vec<f64>> = serde_json::from_value(v.clone()).unwrap();
    let mut a = [[0.0, 0.0, 0.0, 1.0]; 4];
    for (r, row) in rows.iter().enumerate().take(3) {
        a[r].copy_from_slice(&row[..4]);
    }
    DMat4::from_cols_array_2d(&a).transpose()
}

/// Fraction of front-facing posed vertices of `frame` that project within 0.5 px of a covered pixel.
fn reprojection_score(frame: usize, cam: &Cam, w: u32, h: u32, covered: &dyn Fn(u32, u32) -> bool) -> f64 {
    let b = built();
    let mut poser = Poser::default();
    let posed = b.scene.pose(frame, &mut poser).unwrap();
    let w2c = cam.c2w.inverse();
    let eye = cam.c2w.w_axis.truncate();
    let (mut seen, mut hit) = (0usize, 0usize);
    for p in posed.primitives.iter().filter(|p| p.kind == PrimKind::Triangles) {
        for (v, n) in p.positions.iter().zip(&p.normals) {
            let v = v.as_dvec3();
            if n.as_dvec3().dot(eye - v) <= 0.0 {
                continue;
            }
            // OpenGL camera: looks down -Z, +Y up; pixel rows grow downward, centres at +0.5.
            let q = w2c.transform_point3(v);
            let z = -q.z;
            let (u, vv) = (cam.cx + cam.fx * q.x / z, cam.cy - cam.fy * q.y / z);
            if !(0.5..w as f64 - 0.5).contains(&u) || !(0.5..h as f64 - 0.5).contains(&vv) {
                continue;
            }
            seen += 1;
            let near = [(u - 0.5, vv - 0.5), (u + 0.5, vv - 0.5), (u - 0.5, vv + 0.5), (u + 0.5, vv + 0.5), (u, vv)];
            if near.iter().any(|&(x, y)| covered(x.floor() as u32, y.floor() as u32)) {
                hit += 1;
            }
        }
    }
    assert!(seen > 100, "only {seen} vertices in view");
    hit as f64 / seen as f64
}

fn frame_of_time(t: f64) -> usize {
    let f = t * (FRAMES - 1) as f64;
    assert!((f - f.round()).abs() < 1e-9, "time {t} is not a frame");
    f.round() as usize
}

fn rgba(p: &Path) -> image::RgbaImage {
    let img = image::open(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
    assert_eq!(img.color(), image::ColorType::Rgba8, "{}: RGBA expected", p.display());
    img.into_rgba8()
}

fn assert_score(s: f64, what: &str) {
    assert!(s >= 0.99, "{what}: only {:.2} % of front-facing vertices on covered pixels", s * 100.0);
}

/// D-NeRF's load_blender.py (and nerfstudio blender-data / dnerf-data, K-Planes, 3DGS-family Blender readers).
#[test]
fn dnerf_loads_as_dnerf_kplanes_and_3dgs_read_it() {
    let root = built().out.join("man_dnerf");
    assert!(root.to_string_lossy().contains("dnerf"), "K-Planes picks its loader by the path");
    let metas: Vec<(String, Value)> = ["train", "val", "test"]
        .iter()
        .map(|s| (s.to_string(), read_json(&root.join(format!("transforms_{s}.json")))))
        .collect();
    // camera_angle_x is read from the last split loaded (test).
    let angle = metas[2].1["camera_angle_x"].as_f64().unwrap();
    for (split, meta) in &metas {
        let frames = meta["frames"].as_array().unwrap();
        let times: Vec<f64> = frames.iter().map(|f| f["time"].as_f64().unwrap()).collect();
        assert_eq!(times[0], 0.0, "{split}: D-NeRF asserts times[0] == 0");
        assert!(times.windows(2).all(|w| w[0] <= w[1]), "{split}: sorted by time");
        if split == "train" {
            assert_eq!(*times.last().unwrap(), 1.0, "train ends at exactly 1");
        }
        // fl_x agrees with camera_angle_x.
        let fl = meta["fl_x"].as_f64().unwrap();
        let mut ids = Vec::new();
        for f in frames {
            let fp = f["file_path"].as_str().unwrap();
            assert!(!fp.contains("_r"), "K-Planes: `_r` in {fp}");
            let id: usize = fp.split("r_").last().unwrap().parse().expect("ends in r_<int>");
            ids.push(id);
            assert!(Path::new(fp).extension().is_none(), "no extension: {fp}");
            let img = rgba(&root.join(format!("{fp}.png")));
            let (w, h) = img.dimensions();
            let focal = 0.5 * w as f64 / (0.5 * angle).tan();
            assert!((focal - fl).abs() < 1e-6 * focal);
            let cam = Cam {
                c2w: gl_matrix(&f["transform_matrix"]),
                fx: focal,
                fy: focal,
                cx: w as f64 * 0.5,
                cy: h as f64 * 0.5,
            };
            let frame = frame_of_time(f["time"].as_f64().unwrap());
            let s = reprojection_score(frame, &cam, w, h, &|x, y| img.get_pixel(x, y)[3] > 0);
            assert_score(s, fp);
        }
        ids.sort_unstable();
        ids.dedup();
        assert_eq!(ids.len(), frames.len(), "{split}: r_<int> indices are unique");
    }
    // 3DGS fetchPly: x y z nx ny nz float, red green blue uchar; fused.ply identical for 4DGaussians.
    let ply = std::fs::read(root.join("points3d.ply")).unwrap();
    assert_eq!(ply, std::fs::read(root.join("fused.ply")).unwrap());
    let head = String::from_utf8_lossy(&ply[..ply.windows(10).position(|w| w == b"end_header").unwrap()]).to_string();
    let props: Vec<&str> = head.lines().filter(|l| l.starts_with("property")).collect();
    assert_eq!(
        props,
        [
            "property float x",
            "property float y",
            "property float z",
            "property float nx",
            "property float ny",
            "property float nz",
            "property uchar red",
            "property uchar green",
            "property uchar blue"
        ]
    );
    assert!(head.contains("element vertex 2000"));
    // No sparse/ folder: it would divert 3DGS-family loaders to the COLMAP path.
    assert!(!root.join("sparse").exists());
}

/// nerfstudio-data (nerfstudio_dataparser.py).
#[test]
fn nerfstudio_data_reads_intrinsics_paths_lists_depth_and_masks() {
    let root = built().out.join("man_nerfstudio");
    let meta = read_json(&root.join("transforms.json"));
    for k in ["train_filenames", "val_filenames", "test_filenames"] {
        assert!(meta[k].as_array().is_some_and(|a| !a.is_empty()), "{k}");
    }
    assert_eq!(meta["applied_transform"].as_array().unwrap().len(), 3);
    let (fx, fy, cx, cy) = ["fl_x", "fl_y", "cx", "cy"].map(|k| meta[k].as_f64().unwrap()).into();
    let (w, h) = (meta["w"].as_u64().unwrap() as u32, meta["h"].as_u64().unwrap() as u32);
    let frames = meta["frames"].as_array().unwrap();
    let listed: Vec<&str> = ["train_filenames", "val_filenames", "test_filenames"]
        .iter()
        .flat_map(|k| meta[k].as_array().unwrap().iter().map(|v| v.as_str().unwrap()))
        .collect();
    for f in frames {
        let fp = f["file_path"].as_str().unwrap();
        assert!(fp.ends_with(".png") && listed.contains(&fp));
        let img = rgba(&root.join(fp));
        assert_eq!(img.dimensions(), (w, h));
        let mask = image::open(root.join(f["mask_path"].as_str().unwrap())).unwrap();
        assert_eq!(mask.color(), image::ColorType::L8, "mask_path must be single-channel");
        let depth = image::open(root.join(f["depth_file_path"].as_str().unwrap())).unwrap();
        assert_eq!(depth.color(), image::ColorType::L16, "depth is 16-bit");
        let depth = depth.into_luma16();
        let cam = Cam { c2w: gl_matrix(&f["transform_matrix"]), fx, fy, cx, cy };
        let frame = frame_of_time(f["time"].as_f64().unwrap());
        let s = reprojection_score(frame, &cam, w, h, &|x, y| img.get_pixel(x, y)[3] > 0);
        assert_score(s, fp);
        // Depth in millimetres of planar z, where the RGBA is fully covered: the camera is ~4 units away.
        let mm: Vec<u16> = depth.pixels().map(|p| p[0]).filter(|&d| d > 0).collect();
        assert!(!mm.is_empty() && mm.iter().all(|&d| (2500..5600).contains(&d)), "{fp}: depth {:?}", mm.iter().max());
    }
    assert!(root.join(meta["ply_file_path"].as_str().unwrap()).exists());
}

/// instant-ngp's nerf_loader.cu: focal from fl_x, principal point cx/cy with w/h, OpenGL c2w; the content fits
/// the unit cube after `p·scale + offset`.
#[test]
fn instant_ngp_reads_focal_and_its_box_holds_the_content() {
    let b = built();
    let root = b.out.join("man_ngp");
    let meta = read_json(&root.join("transforms_train.json"));
    let (fx, fy, cx, cy) = ["fl_x", "fl_y", "cx", "cy"].map(|k| meta[k].as_f64().unwrap()).into();
    let scale = meta["scale"].as_f64().unwrap();
    let offset: Vec<f64> = serde_json::from_value(meta["offset"].clone()).unwrap();
    assert!(meta["integer_depth_scale"].as_f64().unwrap() == 0.001);
    for f in meta["frames"].as_array().unwrap() {
        let fp = f["file_path"].as_str().unwrap();
        let img = rgba(&root.join(fp));
        let (w, h) = img.dimensions();
        assert!(root.join(f["depth_path"].as_str().unwrap()).exists());
        let cam = Cam { c2w: gl_matrix(&f["transform_matrix"]), fx, fy, cx, cy };
        let frame = frame_of_time(f["time"].as_f64().unwrap());
        assert_score(reprojection_score(frame, &cam, w, h, &|x, y| img.get_pixel(x, y)[3] > 0), fp);
        let mut poser = Poser::default();
        let (lo, hi) = b.scene.pose(frame, &mut poser).unwrap().bounds().unwrap();
        for p in [lo, hi] {
            for k in 0..3 {
                let q = p[k] as f64 * scale + offset[k];
                assert!((0.0..=1.0).contains(&q), "content outside NGP's unit cube: {q}");
            }
        }
    }
}

/// 3DGS's colmap_loader.py text reader: PINHOLE only, two lines per image, w2c quaternion in OpenCV axes.
#[test]
fn colmap_text_model_per_frame_reprojects() {
    let root = built_opaque().out.join("man_colmap");
    // 3DGS reads sparse/0 and nerfstudio's colmap parser colmap/sparse/0 by default: the same model is in both.
    for frame in 0..FRAMES {
        let model = root.join(format!("frame_{frame:04}"));
        for f in ["cameras.txt", "images.txt", "points3D.txt"] {
            let (a, b) = (model.join("sparse/0").join(f), model.join("colmap/sparse/0").join(f));
            assert_eq!(std::fs::read(a).unwrap(), std::fs::read(b).unwrap(), "{f}");
        }
    }
    let page = std::fs::read_to_string(root.join("preview/index.html")).unwrap();
    assert!(page.contains("colmap/sparse/0, the same model"), "the page says how nerfstudio loads it");
    for frame in 0..FRAMES {
        let model = root.join(format!("frame_{frame:04}"));
        let cams = std::fs::read_to_string(model.join("sparse/0/cameras.txt")).unwrap();
        let line = cams.lines().find(|l| !l.starts_with('#') && !l.is_empty()).unwrap();
        let e: Vec<&str> = line.split_whitespace().collect();
        assert_eq!(e[1], "PINHOLE", "3DGS asserts PINHOLE");
        let (w, h) = (e[2].parse::<u32>().unwrap(), e[3].parse::<u32>().unwrap());
        let [fx, fy, cx, cy] = [4, 5, 6, 7].map(|i| e[i].parse::<f64>().unwrap());
        let text = std::fs::read_to_string(model.join("sparse/0/images.txt")).unwrap();
        // The reader skips comments, then reads an image line and unconditionally the next (points) line.
        let mut lines = text.lines().filter(|l| !l.starts_with('#'));
        let mut n = 0;
        while let Some(l) = lines.next() {
            if l.trim().is_empty() {
                continue;
            }
            let points_line = lines.next().expect("two lines per image");
            assert!(points_line.trim().is_empty());
            let e: Vec<&str> = l.split_whitespace().collect();
            assert_eq!(e.len(), 10, "{l}");
            // Deformable-3DGS takes `int(name.split(".")[0])` of every image as its frame number.
            let number: usize = e[9].split('.').next().unwrap().parse().expect("a numeric image name");
            assert_eq!((number + 1).to_string(), e[0], "the name is the image id less one");
            let [qw, qx, qy, qz, tx, ty, tz] = [1, 2, 3, 4, 5, 6, 7].map(|i| e[i].parse::<f64>().unwrap());
            let r = DMat3::from_quat(DQuat::from_xyzw(qx, qy, qz, qw));
            let t = DVec3::new(tx, ty, tz);
            // OpenCV w2c → OpenGL c2w for the shared projection: c2w_cv = [Rᵀ | −Rᵀt], then flip Y and Z.
            let c2w_cv = DMat4::from_cols(
                r.transpose().x_axis.extend(0.0),
                r.transpose().y_axis.extend(0.0),
                r.transpose().z_axis.extend(0.0),
                (-(r.transpose() * t)).extend(1.0),
            );
            let c2w = c2w_cv * DMat4::from_diagonal(DVec4::new(1.0, -1.0, -1.0, 1.0));
            let img = image::open(model.join("images").join(e[9])).unwrap();
            assert_eq!(img.color(), image::ColorType::Rgb8, "COLMAP images carry no alpha");
            let img = img.into_rgb8();
            let covered = |x: u32, y: u32| img.get_pixel(x, y).0 != KEY;
            let s = reprojection_score(frame, &Cam { c2w, fx, fy, cx, cy }, w, h, &covered);
            assert_score(s, e[9]);
            n += 1;
        }
        assert_eq!(n, 4 + 2 + 1, "train 4 + test 2 + val 1 images at frame {frame}");
        // nerfstudio's colmap parser (`_get_image_indices`): once any list is there, `{split}_list.txt` must be
        // for each split it loads (train, val, test), every name in it an image under images/; so the views
        // trained on are the train split's, the evaluated ones the others'.
        let names: Vec<String> = text
            .lines()
            .filter(|l| !l.starts_with('#') && !l.trim().is_empty())
            .map(|l| l.split_whitespace().nth(9).unwrap().to_string())
            .collect();
        let list = |split: &str| -> Vec<String> {
            let t = std::fs::read_to_string(model.join(format!("{split}_list.txt"))).unwrap();
            t.lines().map(str::to_string).collect()
        };
        let meta = read_json(&root.join(vvgen::export::META));
        let split_of = |name: &str| -> String {
            // The image's id less one is its name; the metadata lists this frame's images in the same order.
            let here: Vec<&Value> = meta["images"]
                .as_array()
                .unwrap()
                .iter()
                .filter(|i| frame_of_time(i["time"].as_f64().unwrap()) == frame)
                .collect();
            let k: usize = name.split('.').next().unwrap().parse().unwrap();
            here[k]["split"].as_str().unwrap().to_string()
        };
        let (train, val, test) = (list("train"), list("val"), list("test"));
        assert_eq!((train.len(), val.len(), test.len()), (4, 1, 2), "frame {frame}");
        for (split, l) in [("train", &train), ("val", &val), ("test", &test)] {
            for name in l {
                assert!(names.contains(name) && model.join("images").join(name).is_file(), "{name}");
                assert_eq!(split_of(name), split, "{name} in {split}_list.txt");
            }
        }
        let pts = std::fs::read_to_string(model.join("sparse/0/points3D.txt")).unwrap();
        let p: Vec<&str> = pts.lines().filter(|l| !l.starts_with('#')).collect();
        assert_eq!(p.len(), 500);
        assert!(p[0].split_whitespace().count() >= 8);
    }
}

/// DyNeRF / LLFF poses_bounds.npy as K-Planes, 4DGaussians and Deformable-3DGS read it.
#[test]
fn dynerf_poses_bounds_reprojects() {
    let root = built_opaque().out.join("man_dynerf");
    let npy = std::fs::read(root.join("poses_bounds.npy")).unwrap();
    assert_eq!(&npy[..8], b"\x93NUMPY\x01\x00");
    let hlen = u16::from_le_bytes([npy[8], npy[9]]) as usize;
    let header = std::str::from_utf8(&npy[10..10 + hlen]).unwrap();
    assert!(header.contains("'descr': '<f8'") && header.contains("'shape': (6, 17)"), "{header}");
    assert_eq!((10 + hlen) % 64, 0);
    let data: Vec<f64> = npy[10 + hlen..].chunks_exact(8).map(|c| f64::from_le_bytes(c.try_into().unwrap())).collect();
    assert_eq!(data.len(), 6 * 17);
    // H, W, focal from camera 0 only; principal point at the centre.
    let p0 = &data[..15];
    let (h, w, focal) = (p0[4], p0[9], p0[14]);
    for cam in 0..6 {
        let row = &data[cam * 17..cam * 17 + 17];
        let m = |r: usize, c: usize| row[r * 5 + c];
        // Loader: [c1, -c0, c2, C] turns LLFF (down, right, back) into OpenGL (right, up, back).
        let col = |c: usize| DVec3::new(m(0, c), m(1, c), m(2, c));
        let c2w = DMat4::from_cols(col(1).extend(0.0), (-col(0)).extend(0.0), col(2).extend(0.0), col(3).extend(1.0));
        let (near, far) = (row[15], row[16]);
        assert!(0.0 < near && near < far);
        for frame in 0..FRAMES {
            let p = root.join(format!("frames/cam{cam:02}/{frame:04}.png"));
            let img = image::open(&p).unwrap().into_rgb8();
            assert_eq!(img.dimensions(), (w as u32, h as u32));
            let covered = |x: u32, y: u32| img.get_pixel(x, y).0 != KEY;
            let camera = Cam { c2w, fx: focal, fy: focal, cx: w / 2.0, cy: h / 2.0 };
            let s = reprojection_score(frame, &camera, w as u32, h as u32, &covered);
            assert_score(s, &p.display().to_string());
        }
    }
    // Camera 00 is the held-out test camera: the test split's first orbit view (NeRF-synthetic lego frame 0).
    let c0 = DVec3::new(data[3], data[8], data[13]);
    assert!((c0 - DVec3::new(0.0, 2.73726, 2.95929)).length() < 1e-4, "{c0}");
    assert!(root.join("points3D_downsample2.ply").exists());
}

/// One NeRF-synthetic set per time step.
#[test]
fn static_frames_are_nerf_synthetic_sets() {
    let root = built().out.join("man_static");
    for frame in 0..FRAMES {
        let dir = root.join(format!("t_{frame:04}"));
        let meta = read_json(&dir.join("transforms_train.json"));
        let angle = meta["camera_angle_x"].as_f64().unwrap();
        for f in meta["frames"].as_array().unwrap() {
            let fp = f["file_path"].as_str().unwrap();
            let img = rgba(&dir.join(format!("{fp}.png")));
            let (w, h) = img.dimensions();
            let focal = 0.5 * w as f64 / (0.5 * angle).tan();
            let cam = Cam {
                c2w: gl_matrix(&f["transform_matrix"]),
                fx: focal,
                fy: focal,
                cx: w as f64 / 2.0,
                cy: h as f64 / 2.0,
            };
            assert_score(reprojection_score(frame, &cam, w, h, &|x, y| img.get_pixel(x, y)[3] > 0), fp);
        }
    }
}

/// Every dataset describes itself (in `vvgen/`, out of the root); no temporary file is left anywhere.
#[test]
fn every_dataset_has_metadata_and_no_debris() {
    let roots = ["man_dnerf", "man_nerfstudio", "man_ngp", "man_static", "man_points"].map(|d| built().out.join(d));
    let opaque = ["man_colmap", "man_dynerf"].map(|d| built_opaque().out.join(d));
    for d in roots.iter().chain(&opaque) {
        let meta = read_json(&d.join(vvgen::export::META));
        assert_eq!(meta["tool"], "vvgen");
        if !d.ends_with("man_points") {
            assert!(meta["images"].as_array().is_some_and(|a| !a.is_empty()));
            assert_eq!(meta["camera"]["model"], "pinhole");
        }
    }
    let mut stack = vec![built().out.clone(), built_opaque().out.clone()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(d).unwrap() {
            let e = e.unwrap();
            assert!(!e.file_name().to_string_lossy().starts_with(vvgen::atomic::TMP_PREFIX), "{:?}", e.path());
            if e.file_type().unwrap().is_dir() {
                stack.push(e.path());
            }
        }
    }
}

/// instant-ngp's directory mode, as `Testbed::load_nerf` and `load_nerf` (nerf_loader.cu) do it: every `*.json`
/// file directly in `dir` (extension case-insensitive) is loaded; buffers are sized by the `frames` that are
/// arrays, but the image index advances by `json["frames"].size()` for any `frames` key (nlohmann: null 0, other
/// scalars 1, objects their key count). Returns the image files it would load, or how it would misread `dir`.
fn ngp_directory_load(dir: &Path) -> Result<Vec<PathBuf>, String> {
    let mut jsons: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.is_file() && p.extension().is_some_and(|e| e.eq_ignore_ascii_case("json")))
        .collect();
    jsons.sort();
    let (mut sized, mut advanced) = (0usize, 0usize);
    let mut images = Vec::new();
    for j in &jsons {
        let v: Value = serde_json::from_slice(&std::fs::read(j).unwrap()).map_err(|e| format!("{j:?}: {e}"))?;
        let Some(frames) = v.get("frames") else { continue };
        advanced += match frames {
            Value::Null => 0,
            Value::Array(a) => a.len(),
            Value::Object(o) => o.len(),
            _ => 1,
        };
        let Some(frames) = frames.as_array() else { continue };
        sized += frames.len();
        for f in frames {
            // resolve_path: relative to the JSON's folder; without an extension, the first image format that exists.
            let rel = f["file_path"].as_str().ok_or(format!("{j:?}: a frame without file_path"))?.replace('\\', "/");
            let mut p = j.parent().unwrap().join(&rel);
            if p.extension().is_none() && !p.exists() {
                if let Some(q) = ["png", "jpg", "jpeg", "exr"].iter().map(|e| p.with_extension(e)).find(|q| q.exists())
                {
                    p = q;
                }
            }
            if !p.is_file() {
                return Err(format!("{j:?}: {rel} does not resolve to a file"));
            }
            if let Some(d) = f.get("depth_path").and_then(|d| d.as_str()) {
                if !j.parent().unwrap().join(d).is_file() {
                    return Err(format!("{j:?}: depth_path {d} does not resolve to a file"));
                }
            }
            images.push(p);
        }
    }
    if sized != advanced {
        return Err(format!("{} image slots but the index advances {advanced} times: images shift", sized));
    }
    Ok(images)
}

/// No writer's folder holds a JSON file that instant-ngp's directory mode (`./instant-ngp DIR`) misreads.
#[test]
fn instant_ngp_directory_mode_reads_every_writers_folder_as_written() {
    let mut dirs: Vec<PathBuf> = ["man_dnerf", "man_nerfstudio", "man_ngp", "man_static", "man_points"]
        .iter()
        .map(|d| built().out.join(d))
        .chain(["man_colmap", "man_dynerf"].iter().map(|d| built_opaque().out.join(d)))
        .collect();
    // static-frames: each time step is a dataset of its own.
    let steps: Vec<PathBuf> = std::fs::read_dir(built().out.join("man_static"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.is_dir() && p.file_name().unwrap().to_string_lossy().starts_with("t_"))
        .collect();
    assert!(!steps.is_empty());
    dirs.extend(steps);
    for d in &dirs {
        let images = ngp_directory_load(d).unwrap_or_else(|e| panic!("{}: {e}", d.display()));
        // Every file a transforms JSON names is an image NGP loads, once.
        let unique: std::collections::BTreeSet<_> = images.iter().collect();
        assert_eq!(unique.len(), images.len(), "{}", d.display());
    }
    // The instant-ngp writer's own folder loads every image it rendered.
    let ngp = ngp_directory_load(&built().out.join("man_ngp")).unwrap();
    let meta = read_json(&built().out.join("man_ngp").join(vvgen::export::META));
    assert_eq!(ngp.len(), meta["images"].as_array().unwrap().len());
    // The rule catches what it is for: a metadata file with a scalar `frames` beside the transforms files.
    let tmp = tempfile::tempdir().unwrap();
    for e in std::fs::read_dir(built().out.join("man_ngp")).unwrap() {
        let p = e.unwrap().path();
        if p.is_file() {
            std::fs::copy(&p, tmp.path().join(p.file_name().unwrap())).unwrap();
        } else {
            std::os::unix::fs::symlink(&p, tmp.path().join(p.file_name().unwrap())).unwrap();
        }
    }
    std::fs::write(tmp.path().join("vvgen.json"), r#"{"tool": "vvgen", "frames": 4}"#).unwrap();
    assert!(ngp_directory_load(tmp.path()).unwrap_err().contains("shift"));
}
