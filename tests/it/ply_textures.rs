//! PLY meshes textured per face corner (MeshLab's and OpenMVS's `texcoord` lists, OpenMVS's `texnumber` over
//! several `TextureFile`s): drawn as the same mesh exported to OBJ + MTL is, and keyed by their textures.

use std::path::Path;
use std::process::Command;

use vvgen::build::{build, Options, Silent};
use vvgen::plan::actions::Kind;

/// A 4 × 4 texture of 16 distinct colours, `shift` added to every channel (another image for the same name).
fn checker(path: &Path, shift: u8) {
    let img = image::RgbaImage::from_fn(4, 4, |x, y| {
        let k = (y * 4 + x) as u8;
        image::Rgba([k.wrapping_mul(53).wrapping_add(shift), k.wrapping_mul(97).wrapping_add(40), 255 - k * 15, 255])
    });
    img.save(path).unwrap();
}

/// A tent: two quads meeting along a ridge (x = 0), facing −y, and a triangle at its foot. Each face maps its own
/// part of the texture, so the ridge's and the triangle's corners have another pair on every face they share (a
/// seam per shared vertex). Per face: its corners (indices into [`TENT_VERTICES`]), their (u, v), its texture.
const TENT_VERTICES: [[f32; 3]; 7] = [
    [-0.8, 0.0, -0.6],
    [0.0, -0.5, -0.6],
    [0.0, -0.5, 0.6],
    [-0.8, 0.0, 0.6],
    [0.8, 0.0, -0.6],
    [0.8, 0.0, 0.6],
    [0.0, -0.5, -0.9],
];
type Face = (&'static [u32], [[f32; 2]; 4], u32);
const TENT_FACES: [Face; 3] = [
    (&[0, 1, 2, 3], [[0.0, 0.0], [0.5, 0.0], [0.5, 1.0], [0.0, 1.0]], 0),
    (&[1, 4, 5, 2], [[0.5, 0.5], [1.0, 0.5], [1.0, 1.0], [0.5, 1.0]], 1),
    (&[6, 4, 1], [[0.25, 0.0], [1.0, 0.0], [0.6, 0.45], [0.0, 0.0]], 0),
];

/// The tent as a PLY with a `texcoord` list per face (and a `texnumber` and two textures when `two`), grey vertex
/// colours the texture takes the place of; ASCII or binary.
fn tent_ply(two: bool, binary: bool) -> Vec<u8> {
    let mut s = String::from("ply\n");
    s.push_str(if binary { "format binary_little_endian 1.0\n" } else { "format ascii 1.0\n" });
    s.push_str("comment VCGLIB generated\ncomment TextureFile a.png\n");
    if two {
        s.push_str("comment TextureFile b.png\n");
    }
    s.push_str("element vertex 7\nproperty float x\nproperty float y\nproperty float z\n");
    s.push_str("property uchar red\nproperty uchar green\nproperty uchar blue\n");
    s.push_str("element face 3\nproperty list uchar int vertex_indices\nproperty list uchar float texcoord\n");
    if two {
        s.push_str("property int texnumber\n");
    }
    s.push_str("end_header\n");
    let mut body = Vec::new();
    let mut text = String::new();
    for p in TENT_VERTICES {
        body.extend(p.iter().flat_map(|c| c.to_le_bytes()));
        body.extend([128u8; 3]);
        text.push_str(&format!("{} {} {} 128 128 128\n", p[0], p[1], p[2]));
    }
    for (corners, uvs, t) in TENT_FACES {
        let n = corners.len();
        body.push(n as u8);
        body.extend(corners.iter().flat_map(|i| i.to_le_bytes()));
        body.push(2 * n as u8);
        body.extend(uvs[..n].iter().flatten().flat_map(|c| c.to_le_bytes()));
        text.push_str(&format!("{n} {} ", corners.iter().map(u32::to_string).collect::<Vec<_>>().join(" ")));
        text.push_str(&format!(
            "{} {}",
            2 * n,
            uvs[..n].iter().flatten().map(f32::to_string).collect::<Vec<_>>().join(" ")
        ));
        if two {
            body.extend(t.to_le_bytes());
            text.push_str(&format!(" {t}"));
        }
        text.push('\n');
    }
    let mut out = s.into_bytes();
    out.extend(if binary { body } else { text.into_bytes() });
    out
}

/// The same tent as an OBJ (z up as written: the manifest says so) with an MTL: one material per texture.
fn tent_obj(two: bool) -> (String, String) {
    let mut s = String::from("mtllib tent.mtl\n");
    for p in TENT_VERTICES {
        s.push_str(&format!("v {} {} {}\n", p[0], p[1], p[2]));
    }
    let mut vt = 1;
    for (corners, uvs, t) in TENT_FACES {
        let t = if two { t } else { 0 };
        for uv in &uvs[..corners.len()] {
            s.push_str(&format!("vt {} {}\n", uv[0], uv[1]));
        }
        s.push_str(&format!("usemtl m{t}\nf"));
        for &c in corners {
            s.push_str(&format!(" {}/{vt}", c + 1));
            vt += 1;
        }
        s.push('\n');
    }
    let mtl = "newmtl m0\nKd 1 1 1\nmap_Kd a.png\nnewmtl m1\nKd 1 1 1\nmap_Kd b.png\n".to_string();
    (s, mtl)
}

/// Unlit renders of `mesh` from three sides, z up.
fn manifest(mesh: &str) -> String {
    format!(
        "[dataset]\nname = \"t\"\nout = \"out\"\ncache = \"cache\"\n\
         [source.tent]\n{mesh}\n\
         [transform]\nup = \"z\"\n\
         [render]\nresolution = [64, 64]\nsamples = 4\n\
         [rig.front]\nkind = \"explicit\"\nposes = [{{ position = [0.3, -3.0, 0.4] }}, {{ position = [-2.0, -2.0, 1.0] }}, \
         {{ position = [2.5, -1.0, -0.5] }}]\n\
         [split.train]\nrig = \"front\"\n\
         [output.d]\nwriter = \"dnerf\"\ninit_points = 0\n"
    )
}

fn run(d: &Path) -> vvgen::build::Report {
    let m = crate::common::load(&d.join("m.toml"));
    build(&m, &d.join("cache"), Options::default(), &Silent).unwrap()
}

/// The train images of the build in `d`, decoded.
fn images(d: &Path) -> Vec<image::RgbaImage> {
    (0..3).map(|i| image::open(d.join(format!("out/t_dnerf/train/r_{i:04}.png"))).unwrap().to_rgba8()).collect()
}

#[test]
fn a_ply_textured_per_face_corner_draws_as_the_same_mesh_in_obj() {
    // One texture and two (OpenMVS's `texnumber`), ASCII and binary: the PLY's images are the OBJ's, pixel for
    // pixel. The texture seams are where the two loaders agree only if each corner keeps its own pair, and the
    // grey vertex colours would darken every pixel if they tinted the texture.
    for (two, binary) in [(false, false), (true, true), (true, false)] {
        let (ply_dir, obj_dir) = (tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap());
        for d in [ply_dir.path(), obj_dir.path()] {
            checker(&d.join("a.png"), 0);
            checker(&d.join("b.png"), 128);
        }
        std::fs::write(ply_dir.path().join("tent.ply"), tent_ply(two, binary)).unwrap();
        let (obj, mtl) = tent_obj(two);
        std::fs::write(obj_dir.path().join("tent.obj"), obj).unwrap();
        std::fs::write(obj_dir.path().join("tent.mtl"), mtl).unwrap();
        std::fs::write(ply_dir.path().join("m.toml"), manifest("mesh = \"tent.ply\"")).unwrap();
        std::fs::write(obj_dir.path().join("m.toml"), manifest("mesh = \"tent.obj\"")).unwrap();
        run(ply_dir.path());
        run(obj_dir.path());
        let (ply, obj) = (images(ply_dir.path()), images(obj_dir.path()));
        let colours = |im: &image::RgbaImage| {
            im.pixels().filter(|p| p[3] == 255).map(|p| p.0).collect::<std::collections::BTreeSet<_>>().len()
        };
        for (i, (p, o)) in ply.iter().zip(&obj).enumerate() {
            // The texture shows: many colours, not the one grey of an untextured mesh.
            assert!(colours(p) > 12, "two {two}, binary {binary}, view {i}: {} colours", colours(p));
            assert!(p == o, "two {two}, binary {binary}, view {i}: the PLY's image differs from the OBJ's");
        }
    }
}

#[test]
fn a_textured_ply_sequence_is_keyed_by_its_textures() {
    // A `ply_sequence` of textured meshes reads their textures: editing one re-renders the frames that use it.
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    std::fs::create_dir_all(d.join("seq")).unwrap();
    checker(&d.join("seq/a.png"), 0);
    checker(&d.join("seq/b.png"), 128);
    for f in 0..2 {
        std::fs::write(d.join(format!("seq/f_{f}.ply")), tent_ply(f == 1, true)).unwrap();
    }
    std::fs::write(d.join("m.toml"), manifest("ply_sequence = \"seq/f_*.ply\"")).unwrap();
    assert_eq!(run(d).ran(Kind::RenderPass), 6);
    assert_eq!(run(d).ran(Kind::RenderPass), 0);
    let before = image::open(d.join("out/t_dnerf/train/r_0000.png")).unwrap().to_rgba8();
    // b.png is read by the second frame alone: its passes re-run, the first frame's stay.
    checker(&d.join("seq/b.png"), 60);
    assert_eq!(run(d).ran(Kind::RenderPass), 3);
    checker(&d.join("seq/a.png"), 60);
    assert_eq!(run(d).ran(Kind::RenderPass), 6);
    let after = image::open(d.join("out/t_dnerf/train/r_0000.png")).unwrap().to_rgba8();
    assert!(before != after, "the first frame's texture changed, and its image did not");
}

/// A bad-input case: what, how the PLY's text is damaged, what the error says.
type Case = (&'static str, fn(String) -> String, &'static str);

#[test]
fn a_bad_corner_list_or_texture_number_is_named_by_file_row_and_fix() {
    let cases: [Case; 3] = [
        (
            "a texcoord list one pair short",
            |s| s.replace("3 6 4 1 6 0.25 0 1 0 0.6 0.45", "3 6 4 1 4 0.25 0 1 0"),
            "element `face` row 2: its `texcoord` list has 4 values for 3 corners",
        ),
        ("a texnumber past the textures", |s| s.replace("0.5 1 1\n", "0.5 1 2\n"), "`texnumber` 2 names no texture"),
        (
            "a texture that is not there",
            |s| s.replace("TextureFile b.png", "TextureFile c.png"),
            "`comment TextureFile c.png`: not found",
        ),
    ];
    for (what, damage, says) in cases {
        let tmp = tempfile::tempdir().unwrap();
        let d = tmp.path();
        checker(&d.join("a.png"), 0);
        checker(&d.join("b.png"), 0);
        let ply = damage(String::from_utf8(tent_ply(true, false)).unwrap());
        std::fs::write(d.join("tent.ply"), ply).unwrap();
        std::fs::write(d.join("m.toml"), manifest("mesh = \"tent.ply\"")).unwrap();
        for cmd in ["check", "build"] {
            let out =
                Command::new(env!("CARGO_BIN_EXE_vvgen")).current_dir(d).args(["-q", cmd, "m.toml"]).output().unwrap();
            let err = String::from_utf8_lossy(&out.stderr);
            assert_eq!(out.status.code(), Some(2), "{what}, {cmd}: {err}");
            assert!(err.contains("tent.ply") && err.contains(says), "{what}, {cmd}: {err}");
        }
        assert!(!d.join("out").exists(), "{what}: nothing is written");
    }
}

#[test]
fn many_comments_naming_one_image_decode_it_once() {
    // A header may name one image many times (a hostile one, thousands): it is decoded once, and the faces pick
    // their comment's material as numbered.
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    checker(&d.join("a.png"), 0);
    checker(&d.join("b.png"), 128);
    let names: String = (0..3000).map(|k| format!("comment TextureFile {}\n", ["a.png", "b.png"][k % 2])).collect();
    let ply = String::from_utf8(tent_ply(true, false))
        .unwrap()
        .replace("comment TextureFile a.png\ncomment TextureFile b.png\n", &names)
        .replace("0.5 1 1\n", "0.5 1 2999\n");
    std::fs::write(d.join("tent.ply"), ply).unwrap();
    let scene = vvgen::scene::source::mesh_frame(&d.join("tent.ply")).unwrap();
    assert_eq!((scene.textures.len(), scene.materials.len(), scene.primitives.len()), (2, 3000, 2));
    assert_eq!(scene.primitives.iter().map(|p| p.material).collect::<Vec<_>>(), [0, 2999]);
    assert_eq!(scene.materials[2999].base_color_texture.map(|t| t.texture), Some(1));
}

#[test]
fn a_texture_named_after_its_ply_through_this_is_found() {
    // MeshLab's library reads `<this>` (any case) in a `TextureFile` name as the PLY's own name without `.ply`,
    // as its samples (TextureDouble.ply: `<this>_A.png`, `<this>_B.png`) name their textures.
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    checker(&d.join("scan 07_A.png"), 0);
    checker(&d.join("scan 07.PLY.png"), 128);
    let ply = String::from_utf8(tent_ply(true, false))
        .unwrap()
        .replace("TextureFile a.png", "TextureFile <this>_A.png")
        .replace("TextureFile b.png", "TextureFile <THIS>.PLY.png");
    std::fs::write(d.join("scan 07.PLY"), ply).unwrap();
    let scene = vvgen::scene::source::mesh_frame(&d.join("scan 07.PLY")).unwrap();
    assert_eq!((scene.textures.len(), scene.primitives.len()), (2, 2));
    // The first primitive's texture is A's (shift 0): its first texel as written.
    assert_eq!(&scene.textures[0].rgba[..4], &[0, 40, 255, 255]);
    assert_eq!(&scene.textures[1].rgba[..4], &[128, 40, 255, 255]);
}
