//! Point clouds from outside 8i's integer grid: 3D Gaussian splatting files (their Gaussians' base colours, checked
//! against the coloured cloud their authors made; their images against a splatting reference; a warning where a
//! file lacks the Gaussians' shapes), and sequences in metres, whose splats took one unit (the subject's size many
//! times over) and rendered empty images.

use std::path::Path;
use std::process::Command;

use glam::DVec3;
use vvgen::scene::ply;

/// Runs the `vvgen` binary in `dir`: its exit code, stdout and stderr.
fn vvgen_out(dir: &Path, args: &[&str]) -> (Option<i32>, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_vvgen")).current_dir(dir).args(args).output().unwrap();
    let text = |b: &[u8]| String::from_utf8_lossy(b).into_owned();
    (out.status.code(), text(&out.stdout), text(&out.stderr))
}

/// [`vvgen_out`]'s exit code and stderr.
fn vvgen(dir: &Path, args: &[&str]) -> (Option<i32>, String) {
    let (code, _, err) = vvgen_out(dir, args);
    (code, err)
}

/// The rows of a binary little-endian PLY body of `width` f32 properties.
fn rows(path: &Path, width: usize) -> Vec<Vec<f32>> {
    let bytes = std::fs::read(path).unwrap();
    let start = bytes.windows(11).position(|w| w == b"end_header\n").unwrap() + 11;
    let floats: Vec<f32> = bytes[start..].chunks_exact(4).map(|c| f32::from_le_bytes(c.try_into().unwrap())).collect();
    floats.chunks_exact(width).map(<[f32]>::to_vec).collect()
}

/// A Mip-Splatting donut's Gaussians read as the coloured cloud its authors made of them, byte for byte, less
/// the Gaussians no view can show (peak alpha under 1/255, which 3DGS's rasterizer never blends); the streamed
/// file read and the in-memory read agree, and a degree-3 file with (zero) normals reads too.
#[test]
fn a_gaussian_splatting_file_reads_as_its_gaussians_base_colours() {
    let gaussians = crate::common::data("splats/donut_2000.ply");
    let theirs = ply::read_file(&crate::common::data("splats/donut_2000_color.ply")).unwrap();
    let ours = ply::read_file(&gaussians).unwrap();
    assert_eq!(ours, ply::read(&std::fs::read(&gaussians).unwrap()).unwrap());
    // x y z, f_dc_0..2, opacity (logit), scale_0..2, rot_0..3.
    let shows: Vec<bool> =
        rows(&gaussians, 14).iter().map(|r| 1.0 / (1.0 + (-(r[6] as f64)).exp()) >= 1.0 / 255.0).collect();
    let faint = shows.iter().filter(|s| !**s).count();
    assert!((5..200).contains(&faint), "{faint} of 2000 never show");
    let kept = |v: &[[u8; 4]]| -> Vec<[u8; 4]> { v.to_vec() };
    let their_colours = theirs.colors.as_deref().unwrap();
    let expected_colours: Vec<[u8; 4]> =
        their_colours.iter().zip(&shows).filter(|(_, s)| **s).map(|(c, _)| *c).collect();
    let expected_positions: Vec<[f32; 3]> =
        theirs.positions.iter().zip(&shows).filter(|(_, s)| **s).map(|(p, _)| *p).collect();
    assert_eq!(ours.positions, expected_positions);
    assert_eq!(kept(ours.colors.as_deref().unwrap()), expected_colours, "the base colours, as their cloud has them");
    assert!(their_colours.iter().map(|c| c[0]).collect::<std::collections::BTreeSet<_>>().len() > 100);

    let train = ply::read_file(&crate::common::data("splats/train_200.ply")).unwrap();
    let train_rows = rows(&crate::common::data("splats/train_200.ply"), 62);
    let n = train_rows.iter().filter(|r| 1.0 / (1.0 + (-(r[54] as f64)).exp()) >= 1.0 / 255.0).count();
    assert_eq!((train.positions.len(), train.colors.as_ref().map(Vec::len)), (n, Some(n)));
    assert_eq!(train.positions[0], [train_rows[0][0], train_rows[0][1], train_rows[0][2]]);
    assert!(train.normals.unwrap().iter().all(|n| *n == [0.0; 3]), "3DGS writes zero normals");
    // Its Gaussians' shapes and colours: degree 3, the higher bands regrouped per coefficient from the file's
    // channel-by-channel `f_rest_*` (red's 15, green's, blue's), the values as stored.
    let g = train.gaussians.expect("scales and rotations read");
    let first = train_rows.iter().find(|r| 1.0 / (1.0 + (-(r[54] as f64)).exp()) >= 1.0 / 255.0).unwrap();
    assert_eq!((g.degree, g.sh.len(), g.scales.len()), (3, 16 * n, n));
    assert_eq!(g.sh[0], [first[6], first[7], first[8]]);
    assert_eq!(g.sh[1], [first[9], first[24], first[39]]);
    assert_eq!(g.sh[15], [first[23], first[38], first[53]]);
    assert_eq!(
        (g.opacities[0], g.scales[0], g.rotations[0]),
        (first[54], [first[55], first[56], first[57]], [first[58], first[59], first[60], first[61]])
    );
    assert_eq!(ours.gaussians.map(|g| g.degree), Some(0), "the donut has band 0 only");
}

/// 3DGS files as a newcomer builds them, from their own folder with bare names: the images are the Gaussians as
/// splatting draws them. The references were rendered apart from vvgen (`benches/gaussians_reference.py`):
/// gsplat's PyTorch projection and spherical harmonics, blended as graphdeco-inria's rasterizer blends, from the
/// cameras of this manifest's dataset; a band-0 donut seen Z up and a degree-3 file turned Y up (so its colours are
/// read along directions taken back into its own axes). Nothing about Gaussians is warned of.
#[test]
fn a_gaussian_splatting_file_renders_as_the_splatting_reference() {
    // The PLY, and splat-transform 2.7.1's glTF of it (`KHR_gaussian_splatting`: linear scales, activated
    // opacities, one attribute per coefficient), which it writes turned 180° about Z: the manifest turns it back.
    let turned = "[source.s.transform]\nmatrix = [[-1, 0, 0, 0], [0, -1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]\n";
    let files = ["ply", "glb"].into_iter().flat_map(|ext| [("donut_2000", "z", ext), ("train_200", "y", ext)]);
    let mut points = std::collections::HashMap::new();
    for (name, up, ext) in files {
        let tmp = tempfile::tempdir().unwrap();
        let d = tmp.path();
        let file = format!("{name}.{ext}");
        std::fs::copy(crate::common::data(&format!("splats/{file}")), d.join(&file)).unwrap();
        let turn = if ext == "glb" { turned } else { "" };
        let text = format!(
            "[dataset]\nname = \"{name}\"\nout = \"out\"\npreview = false\n\n[source.s]\nmesh = \"{file}\"\n\n{turn}\
             [transform]\nup = \"{up}\"\nfit = \"frame\"\ncenter = \"bbox\"\n\n[render]\nresolution = [128, 128]\n\n\
             [rig.h]\nkind = \"hemisphere\"\n\n[split.train]\nrig = \"h\"\nviews = 3\n\n[output.d]\nwriter = \"dnerf\"\n"
        );
        std::fs::write(d.join("m.toml"), text).unwrap();
        for cmd in ["check", "build"] {
            let (code, err) = vvgen(d, &[cmd, "m.toml"]);
            assert_eq!(code, Some(0), "{cmd}: {err}");
            assert!(!err.contains("Gaussians"), "{cmd}: {err}");
        }
        let mut shown = 0;
        for v in 0..3 {
            let ours = image::open(d.join(format!("out/{name}_dnerf/train/r_{v:04}.png"))).unwrap().into_rgba8();
            let path = crate::common::data(&format!("splats/reference/{name}/{v:03}.png"));
            let theirs = image::open(path).unwrap().into_rgba8();
            // Over white, as D-NeRF's loader reads an RGBA image; and the alpha itself.
            let white = |p: &image::Rgba<u8>, c: usize| p[c] as f32 * p[3] as f32 / 255.0 + 255.0 - p[3] as f32;
            for (o, t) in ours.pixels().zip(theirs.pixels()) {
                shown += (t[3] > 0) as usize;
                let worst = (0..3).map(|c| (white(o, c) - white(t, c)).abs()).fold(0.0, f32::max);
                assert!(worst <= 2.0 && o[3].abs_diff(t[3]) <= 2, "{file} view {v}: {o:?} against {t:?}");
            }
        }
        assert!(shown > 1000, "{file}: {shown} pixels drawn");
        // The points written beside the images (the Gaussians' centres in their base colours) are the PLY's.
        let cloud = std::fs::read(d.join(format!("out/{name}_dnerf/points3d.ply"))).unwrap();
        match points.get(name) {
            None => drop(points.insert(name, cloud)),
            Some(ply) => assert!(ply == &cloud, "{file}: its points3d.ply differs from the PLY's"),
        }
    }
}

/// A file with 3D Gaussians' colours and opacities but not their shapes is drawn as points, and `check` and
/// `build` say so; the images show the donut's colours.
#[test]
fn gaussians_without_their_shapes_are_drawn_as_points_and_say_so() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    // The donut's x, y, z, f_dc_0..2 and opacity, without scale_0..2 and rot_0..3.
    let kept: Vec<f32> =
        rows(&crate::common::data("splats/donut_2000.ply"), 14).iter().flat_map(|r| r[..7].to_vec()).collect();
    let mut bytes = b"ply\nformat binary_little_endian 1.0\nelement vertex 2000\n".to_vec();
    for p in ["x", "y", "z", "f_dc_0", "f_dc_1", "f_dc_2", "opacity"] {
        bytes.extend(format!("property float {p}\n").bytes());
    }
    bytes.extend(b"end_header\n");
    bytes.extend(kept.iter().flat_map(|v| v.to_le_bytes()));
    std::fs::write(d.join("point_cloud.ply"), bytes).unwrap();
    assert_eq!(vvgen(d, &["new", "point_cloud.ply"]).0, Some(0));
    let text = std::fs::read_to_string(d.join("point-cloud.toml")).unwrap();
    let small = text
        .replace("views = 100", "views = 2")
        .replace("views = 10", "views = 1")
        .replace("views    = 20", "views = 1");
    std::fs::write(d.join("point-cloud.toml"), small.replace("[400, 400]", "[96, 96]")).unwrap();
    for cmd in ["check", "build"] {
        let (code, err) = vvgen(d, &[cmd, "point-cloud.toml"]);
        assert_eq!(code, Some(0), "{cmd}: {err}");
        for says in ["point_cloud.ply: holds 3D Gaussians", "not", "their shapes", "as a point", "opacity under 1/255"]
        {
            assert!(err.contains(says), "{cmd}: `{says}` not in {err}");
        }
    }
    let img = image::open(d.join("out/point-cloud/point-cloud_dnerf/train/r_0000.png")).unwrap().into_rgba8();
    let shown: Vec<&image::Rgba<u8>> = img.pixels().filter(|p| p[3] == 255).collect();
    assert!(shown.len() > 200, "{} opaque pixels", shown.len());
    // The icing is pink and the sprinkles blue: not the white of a cloud without colours.
    let pinkish = shown.iter().filter(|p| p[0] as i32 > p[1] as i32 + 30).count();
    assert!(pinkish * 4 > shown.len(), "{pinkish} of {} pixels pink", shown.len());
}

/// A voxelized sphere shell (every voxel within half a voxel of radius 20: each point has a neighbour one voxel
/// away) moved off the integer grid into metres (every coordinate times 2⁻¹⁰, exactly): the same images, byte for
/// byte, as the integer frames, where before every splat was a unit cube (the sphere 25 times over) and the
/// images were empty; the voxel is measured from the points (`inspect` says so). As static clouds the same (they
/// took 1.5-pixel squares, whatever their spacing).
#[test]
fn a_sequence_in_metres_renders_as_its_integer_twin() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    let mut grid = Vec::new();
    for z in -21i32..=21 {
        for y in -21i32..=21 {
            for x in -21i32..=21 {
                let r = ((x * x + y * y + z * z) as f32).sqrt();
                if (r - 20.0).abs() < 0.5 {
                    grid.push([x as f32, y as f32, z as f32]);
                }
            }
        }
    }
    let colours: Vec<[u8; 3]> = grid.iter().map(|p| p.map(|c| (128.0 + 6.0 * c) as u8)).collect();
    for f in 0..2 {
        // The second frame a voxel higher.
        let at = |scale: f32| -> Vec<[f32; 3]> {
            grid.iter().map(|p| [p[0], p[1], p[2] + f as f32].map(|c| c * scale)).collect()
        };
        for (name, scale) in [("grid", 1.0), ("metres", 1.0 / 1024.0)] {
            let positions = at(scale);
            let out = ply::PlyOut { positions: &positions, colors: Some(&colours), ..Default::default() };
            std::fs::write(d.join(format!("{name}_{f}.ply")), ply::write(&out)).unwrap();
        }
    }
    // As sequences, and as static clouds (the first frame alone).
    let sources = [
        ("grid", "ply_sequence = \"grid_{frame}.ply\"\nframes = { start = 0, end = 1 }"),
        ("metres", "ply_sequence = \"metres_{frame}.ply\"\nframes = { start = 0, end = 1 }"),
        ("grid-static", "mesh = \"grid_0.ply\""),
        ("metres-static", "mesh = \"metres_0.ply\""),
    ];
    for (name, source) in sources {
        let text = format!(
            "[dataset]\nname = \"{name}\"\nout = \"out\"\npreview = false\n\
             [source.shell]\n{source}\n\
             [transform]\nfit = \"frame\"\ncenter = \"bbox\"\n\
             [render]\nresolution = [120, 120]\n[rig.h]\nkind = \"hemisphere\"\n[split.train]\nrig = \"h\"\nviews = 2\n\
             [output.d]\nwriter = \"dnerf\"\n"
        );
        std::fs::write(d.join(format!("{name}.toml")), text).unwrap();
        let m = crate::common::load(&d.join(format!("{name}.toml")));
        vvgen::build::build(&m, &d.join("cache"), Default::default(), &vvgen::build::Silent).unwrap();
    }
    let mut covered = 0;
    for v in 0..2 {
        let read = |name: &str| std::fs::read(d.join(format!("out/{name}_dnerf/train/r_{v:04}.png"))).unwrap();
        assert!(read("grid") == read("metres"), "view {v}");
        assert!(read("grid-static") == read("metres-static"), "view {v} of the static clouds");
        // Closed as the sequence's are: 1.5-pixel squares covered a third less.
        let solid = |name: &str| {
            image::load_from_memory(&read(name)).unwrap().into_rgba8().pixels().filter(|p| p[3] == 255).count() as f64
        };
        let (sequence, single) = (solid("metres"), solid("metres-static"));
        assert!((single / sequence - 1.0).abs() < 0.1, "view {v}: {single} pixels covered against {sequence}");
        let img = image::load_from_memory(&read("metres")).unwrap().into_rgba8();
        covered += img.pixels().filter(|p| p[3] == 255).count();
    }
    assert!(covered > 4000, "{covered} pixels covered");
    let (_, said, _) = vvgen_out(d, &["inspect", "metres.toml"]);
    assert!(said.contains("voxel: 0.0009765625 source units (9 points in 10"), "{said}");
}

/// Formats a newcomer brings that vvgen does not read are refused by `new` and by `check` with the tool that turns
/// them into one it reads: Gaussian splats packed by SuperSplat (`.compressed.ply`) or in web forms (`.spz`,
/// `.splat`), Alembic and USD (through Blender, as a `.blend`), OFF, PCD and LAS/LAZ (through trimesh, Open3D and
/// laspy, as a PLY).
#[test]
fn a_splat_or_scene_format_vvgen_does_not_read_names_the_converter() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    // SuperSplat's compressed layout: a chunk element, then vertices of packed words.
    let mut packed = b"ply\nformat binary_little_endian 1.0\nelement chunk 1\nproperty float min_x\n\
        element vertex 2\nproperty uint packed_position\nproperty uint packed_color\nend_header\n"
        .to_vec();
    packed.extend([0u8; 4 + 16]);
    std::fs::write(d.join("scan.compressed.ply"), packed).unwrap();
    std::fs::write(d.join("scan.spz"), [0x1f, 0x8b, 8, 0]).unwrap();
    std::fs::write(d.join("shot.usdz"), b"PK").unwrap();
    std::fs::write(d.join("homer.off"), b"OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n").unwrap();
    std::fs::write(d.join("bunny.pcd"), b"VERSION .5\nFIELDS x y z\nPOINTS 1\nDATA ascii\n0 0 0\n").unwrap();
    std::fs::write(d.join("autzen.laz"), b"LASF").unwrap();
    let cases = [
        ("scan.compressed.ply", "splat-transform in.compressed.ply out.ply"),
        ("scan.spz", "splat-transform \"scan.spz\" \"scan.ply\""),
        ("shot.usdz", "save it as a .blend"),
        ("homer.off", "trimesh.load('homer.off').export('homer.ply')"),
        ("bunny.pcd", "o3d.io.write_point_cloud('bunny.ply', o3d.io.read_point_cloud('bunny.pcd'))"),
        ("autzen.laz", "l = laspy.read('autzen.laz');"),
    ];
    for (file, says) in cases {
        let (code, err) = vvgen(d, &["new", file]);
        assert_eq!(code, Some(2), "{file}: {err}");
        assert!(err.contains(says) && err.contains(file.split('.').next().unwrap()), "{file}: `{says}` not in {err}");
        let manifest = format!(
            "[dataset]\nname = \"m\"\nout = \"out\"\n[source.s]\nmesh = \"{file}\"\n[render]\nresolution = [8, 8]\n\
             [rig.h]\nkind = \"hemisphere\"\n[split.train]\nrig = \"h\"\nviews = 1\n[output.d]\nwriter = \"nerfstudio\"\n"
        );
        std::fs::write(d.join("m.toml"), manifest).unwrap();
        let (code, err) = vvgen(d, &["check", "m.toml"]);
        assert_eq!(code, Some(2), "{file}: {err}");
        assert!(err.contains(says), "check {file}: `{says}` not in {err}");
    }
}

/// Hostile Gaussians: a NaN colour is an error naming the file and the row (exit 2, from `check` as from `build`);
/// scales whose exponent overflows, a zero quaternion and Gaussians far larger than the image draw without a
/// panic.
#[test]
fn gaussians_that_are_not_numbers_are_refused_and_huge_ones_draw() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    let source = crate::common::data("splats/donut_2000.ply");
    let bytes = std::fs::read(&source).unwrap();
    let body = bytes.windows(11).position(|w| w == b"end_header\n").unwrap() + 11;
    // x y z, f_dc_0..2, opacity, scale_0..2, rot_0..3: 14 floats a row.
    let with = |edit: &dyn Fn(usize, &mut [f32])| -> Vec<u8> {
        let mut rows = rows(&source, 14);
        for (i, r) in rows.iter_mut().enumerate() {
            edit(i, r);
        }
        let mut out = bytes[..body].to_vec();
        out.extend(rows.iter().flatten().flat_map(|v| v.to_le_bytes()));
        out
    };
    let manifest = |name: &str| {
        format!(
            "[dataset]\nname = \"{name}\"\nout = \"out\"\npreview = false\n[source.s]\nmesh = \"{name}.ply\"\n\
             [transform]\nfit = \"frame\"\ncenter = \"bbox\"\n[render]\nresolution = [64, 64]\npasses = [\"rgba\", \"depth\"]\n\
             [rig.h]\nkind = \"hemisphere\"\n[split.train]\nrig = \"h\"\nviews = 2\n[output.d]\nwriter = \"dnerf\"\n"
        )
    };
    std::fs::write(
        d.join("nan.ply"),
        with(&|i, r| {
            if i == 7 {
                r[8] = f32::NAN
            }
        }),
    )
    .unwrap();
    std::fs::write(d.join("nan.toml"), manifest("nan")).unwrap();
    for cmd in ["check", "build"] {
        let (code, err) = vvgen(d, &[cmd, "nan.toml"]);
        assert_eq!(code, Some(2), "{cmd}: {err}");
        for says in ["nan.ply", "row 7", "not a finite number"] {
            assert!(err.contains(says), "{cmd}: `{says}` not in {err}");
        }
    }
    // Every other Gaussian a thousand times wider than the subject (exp(90) overflows f32 for one in ten), the
    // third a zero quaternion, every fifth an infinite opacity logit (splat-transform writes one for an opacity
    // quantized to 1: 3DGS's sigmoid makes it 1).
    let huge = with(&|i, r| {
        if i % 5 == 1 {
            r[6] = f32::INFINITY;
        }
        if i % 2 == 0 {
            r[7..10].copy_from_slice(&[if i % 10 == 0 { 90.0 } else { 3.0 }; 3]);
        }
        if i == 3 {
            r[10..14].copy_from_slice(&[0.0; 4]);
        }
    });
    std::fs::write(d.join("huge.ply"), huge).unwrap();
    std::fs::write(d.join("huge.toml"), manifest("huge")).unwrap();
    let (code, err) = vvgen(d, &["build", "huge.toml"]);
    assert_eq!(code, Some(0), "{err}");
    let img = image::open(d.join("out/huge_dnerf/train/r_0000.png")).unwrap().into_rgba8();
    assert!(img.pixels().any(|p| p[3] > 0), "something is drawn");
}

/// A splatting model's own cameras (`cameras.json`, as graphdeco-inria's trainer writes them: camera-to-world
/// rotations in OpenCV's axes, rows, and centres) as a `from-file` rig, tested by reprojection: three small round
/// Gaussians, in a world left as the file's (`up = "z"`, no fit), land at the pixels OpenCV's pinhole puts them
/// at from those cameras, with `[render]`'s focal length and a centred principal point, to a twentieth of a pixel.
/// A `[transform]` that moves the scene off the file's coordinates is warned of.
#[test]
fn a_splatting_models_cameras_json_is_a_rig_that_reprojects() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    let centres = [[0.0f32, 0.0, 0.0], [0.5, 0.2, 0.1], [-0.4, -0.3, 0.2]];
    let mut bytes = format!("ply\nformat binary_little_endian 1.0\nelement vertex {}\n", centres.len()).into_bytes();
    let props = ["x", "y", "z", "f_dc_0", "f_dc_1", "f_dc_2", "opacity", "scale_0", "scale_1", "scale_2"];
    for p in props.iter().chain(&["rot_0", "rot_1", "rot_2", "rot_3"]) {
        bytes.extend(format!("property float {p}\n").bytes());
    }
    bytes.extend(b"end_header\n");
    for c in centres {
        // White, opaque, σ = 0.01, unrotated.
        let row = [c[0], c[1], c[2], 1.8, 1.8, 1.8, 6.0, -4.6, -4.6, -4.6, 1.0, 0.0, 0.0, 0.0];
        bytes.extend(row.iter().flat_map(|v| v.to_le_bytes()));
    }
    std::fs::write(d.join("point_cloud.ply"), bytes).unwrap();
    // Two cameras aimed near the origin with a roll: columns right, down, forward (x = y × z).
    let cameras: Vec<(DVec3, glam::DMat3)> = [(DVec3::new(0.3, -0.2, -4.0), 0.3), (DVec3::new(-3.0, 1.0, 2.0), -0.5)]
        .into_iter()
        .map(|(eye, roll): (DVec3, f64)| {
            let z = (DVec3::new(0.05, 0.02, 0.0) - eye).normalize();
            let down = DVec3::new(roll.sin(), roll.cos(), 0.2);
            let y = (down - z * down.dot(z)).normalize();
            (eye, glam::DMat3::from_cols(y.cross(z), y, z))
        })
        .collect();
    let json: Vec<String> = cameras
        .iter()
        .enumerate()
        .map(|(i, (eye, r))| {
            let rows: Vec<String> =
                (0..3).map(|k| format!("[{}, {}, {}]", r.row(k).x, r.row(k).y, r.row(k).z)).collect();
            format!(
                "{{\"id\": {i}, \"img_name\": \"{i}\", \"width\": 100, \"height\": 100, \"position\": [{}, {}, {}], \
                 \"rotation\": [{}], \"fy\": 1.0, \"fx\": 1.0}}",
                eye.x,
                eye.y,
                eye.z,
                rows.join(", ")
            )
        })
        .collect();
    std::fs::write(d.join("cameras.json"), format!("[{}]", json.join(", "))).unwrap();
    let angle = 0.7f64;
    let text = format!(
        "[dataset]\nname = \"c\"\nout = \"out\"\npreview = false\n[source.s]\nmesh = \"point_cloud.ply\"\n\
         [transform]\nup = \"z\"\n[render]\nresolution = [160, 120]\ncamera_angle_x = {angle}\n\
         [rig.trained]\nkind = \"from-file\"\nfile = \"cameras.json\"\n[split.train]\nrig = \"trained\"\n\
         [output.d]\nwriter = \"dnerf\"\n"
    );
    std::fs::write(d.join("m.toml"), text).unwrap();
    let (code, err) = vvgen(d, &["build", "m.toml"]);
    assert_eq!(code, Some(0), "{err}");
    let f = 0.5 * 160.0 / (0.5 * angle).tan();
    for (v, (eye, r)) in cameras.iter().enumerate() {
        let img = image::open(d.join(format!("out/c_dnerf/train/r_{v:04}.png"))).unwrap().into_rgba8();
        for c in centres {
            let p = r.transpose() * (DVec3::new(c[0] as f64, c[1] as f64, c[2] as f64) - *eye);
            let (u, w) = (f * p.x / p.z + 80.0, f * p.y / p.z + 60.0);
            // The alpha-weighted centroid of the blob around the expected pixel (pixel centres at +0.5).
            let (mut sum, mut at) = (0.0, DVec3::ZERO);
            for y in (w as i64 - 8).max(0)..(w as i64 + 9).min(120) {
                for x in (u as i64 - 8).max(0)..(u as i64 + 9).min(160) {
                    let a = img.get_pixel(x as u32, y as u32)[3] as f64;
                    sum += a;
                    at += DVec3::new(x as f64 + 0.5, y as f64 + 0.5, 0.0) * a;
                }
            }
            assert!(sum > 255.0, "view {v}: nothing at ({u:.2}, {w:.2})");
            let got = at / sum;
            assert!(
                (got.x - u).abs() < 0.05 && (got.y - w).abs() < 0.05,
                "view {v}: at {got:?}, OpenCV says ({u}, {w})"
            );
        }
    }
    // Moved off the file's coordinates, the cameras would miss the scene: `check` says so and what moved it.
    let (code, err) = vvgen(d, &["check", "m.toml"]);
    assert!(code == Some(0) && !err.contains("cameras.json"), "{err}");
    let moved =
        std::fs::read_to_string(d.join("m.toml")).unwrap().replace("up = \"z\"", "up = \"z\"\ncenter = \"bbox\"");
    std::fs::write(d.join("m.toml"), moved).unwrap();
    let (code, err) = vvgen(d, &["check", "m.toml"]);
    assert_eq!(code, Some(0), "{err}");
    for says in ["rig `trained` reads a splatting model's cameras.json", "`center` moves the scene", "up = \"z\""] {
        assert!(err.contains(says), "`{says}` not in {err}");
    }
}

/// `vvgen new` on 3D Gaussians in glTF guesses their up axis from their extents, as it does a scan's: the tools
/// that write them keep the trainer's axes (splat-transform turns them 180° about Z only), so glTF's +Y may lie
/// on its side (the donut is flat along z).
#[test]
fn new_guesses_the_up_axis_of_gaussians_in_gltf_from_their_extents() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    std::fs::copy(crate::common::data("splats/donut_2000.glb"), d.join("donut.glb")).unwrap();
    let (code, err) = vvgen(d, &["new", "donut.glb"]);
    assert_eq!(code, Some(0), "{err}");
    let text = std::fs::read_to_string(d.join("donut.toml")).unwrap();
    assert!(text.contains("up     = \"z\""), "{text}");
    assert!(err.contains("3D Gaussians") && err.contains("flat along z"), "{err}");
}

/// Gaussians in glTF are placed by their node's transform, colours included: the degree-3 train subset under a
/// node turned and scaled renders as the same file turned and scaled by the manifest's `matrix`.
#[test]
fn gaussians_in_gltf_follow_their_nodes_transform() {
    let (mut json, bin) =
        crate::common::glb_split(&std::fs::read(crate::common::data("splats/train_200.glb")).unwrap());
    // 60° about X and a uniform scale of 2; the same as a row-major matrix.
    let (s, c) = (60f64.to_radians().sin(), 60f64.to_radians().cos());
    json["nodes"][0]["rotation"] =
        serde_json::json!([(30f64.to_radians()).sin(), 0.0, 0.0, (30f64.to_radians()).cos()]);
    json["nodes"][0]["scale"] = serde_json::json!([2.0, 2.0, 2.0]);
    let matrix =
        format!("[[2, 0, 0, 0], [0, {}, {}, 0], [0, {}, {}, 0], [0, 0, 0, 1]]", 2.0 * c, -2.0 * s, 2.0 * s, 2.0 * c);
    let image = |glb: Vec<u8>, transform: String| {
        let tmp = tempfile::tempdir().unwrap();
        let d = tmp.path();
        std::fs::write(d.join("t.glb"), glb).unwrap();
        let text = format!(
            "[dataset]\nname = \"t\"\nout = \"out\"\npreview = false\n[source.s]\nmesh = \"t.glb\"\n{transform}\
             [transform]\nup = \"y\"\nfit = {{ radius = 1.0 }}\n[render]\nresolution = [160, 160]\n\
             [rig.h]\nkind = \"hemisphere\"\n[split.train]\nrig = \"h\"\nviews = 2\n[output.d]\nwriter = \"dnerf\"\n"
        );
        std::fs::write(d.join("m.toml"), text).unwrap();
        let (code, err) = vvgen(d, &["build", "m.toml"]);
        assert_eq!(code, Some(0), "{err}");
        (0..2)
            .map(|v| image::open(d.join(format!("out/t_dnerf/train/r_{v:04}.png"))).unwrap().into_rgba8())
            .collect::<Vec<_>>()
    };
    let by_node = image(crate::common::glb_join(&json, &bin), String::new());
    json["nodes"][0] = serde_json::json!({ "mesh": 0 });
    let by_manifest = image(crate::common::glb_join(&json, &bin), format!("[source.s.transform]\nmatrix = {matrix}\n"));
    let mut shown = 0;
    for (a, b) in by_node.iter().zip(&by_manifest) {
        for (p, q) in a.pixels().zip(b.pixels()) {
            shown += (p[3] > 0) as usize;
            assert!(p.0.iter().zip(q.0).all(|(x, y)| x.abs_diff(y) <= 1), "{p:?} vs {q:?}");
        }
    }
    assert!(shown > 300, "{shown} pixels drawn");
}
