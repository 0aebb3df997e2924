//! OBJ materials as a newcomer's files have them: texture statements written on Windows (backslashes, spaces,
//! options, absolute paths from the author's machine), a renamed material library, `map_Kd` beside `Kd`, and
//! transparency; read as Blender 4.5's importer reads them.

use std::path::Path;

use vvgen::build::{build, Options, Silent};

/// Two unit quads side by side in the XY plane facing +Z (y up, as OBJ is), the left of material `skin`, the
/// right of `lid`, over the whole of their textures.
const OBJ: &str = "mtllib model.mtl\n\
    v -1.05 -0.5 0\nv -0.05 -0.5 0\nv -0.05 0.5 0\nv -1.05 0.5 0\n\
    v 0.05 -0.5 0\nv 1.05 -0.5 0\nv 1.05 0.5 0\nv 0.05 0.5 0\n\
    vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n\
    usemtl skin\nf 1/1 2/2 3/3 4/4\nusemtl lid\nf 5/1 6/2 7/3 8/4\n";

fn manifest() -> &'static str {
    "[dataset]\nname = \"m\"\nout = \"out\"\ncache = \"cache\"\npreview = false\n\
     [source.model]\nmesh = \"model.obj\"\n\
     [render]\nresolution = [64, 32]\nsamples = 4\npasses = [\"rgba\"]\n\
     [rig.front]\nkind = \"explicit\"\nposes = [{ position = [0.0, -3.0, 0.0] }]\n\
     [split.train]\nrig = \"front\"\n\
     [output.d]\nwriter = \"dnerf\"\ninit_points = 0\n"
}

/// The rendered image's texel at (x, y).
fn pixel(d: &Path, x: u32, y: u32) -> [u8; 4] {
    image::open(d.join("out/m_dnerf/train/r_0000.png")).unwrap().to_rgba8().get_pixel(x, y).0
}

fn run(d: &Path) {
    std::fs::write(d.join("m.toml"), manifest()).unwrap();
    let m = crate::common::load(&d.join("m.toml"));
    build(&m, &d.join("cache"), Options::default(), &Silent).unwrap();
}

#[test]
fn a_windows_authored_mtl_finds_its_textures_as_blender_does() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    std::fs::create_dir_all(d.join("maps")).unwrap();
    image::RgbaImage::from_pixel(2, 2, image::Rgba([230, 40, 40, 255])).save(d.join("maps/skin tone.png")).unwrap();
    image::RgbaImage::from_pixel(2, 2, image::Rgba([40, 40, 230, 255])).save(d.join("lid.png")).unwrap();
    std::fs::write(d.join("model.obj"), OBJ).unwrap();
    // 3ds Max style: a subfolder with a backslash, a name with a space after an option, and an absolute path
    // from the author's machine whose file lies beside the MTL. `Kd` beside `map_Kd` does not darken it:
    // Blender links the image in its place.
    let mtl = "newmtl skin\n\tKd 0.5 0.5 0.5\n\tTf 1 1 1\n\tmap_Kd -s 1 1 1 maps\\skin tone.png\n\
               newmtl lid\n\tKd 0.588 0.588 0.588\n\tmap_Kd C:\\Users\\artist\\Desktop\\car\\lid.png\n";
    std::fs::write(d.join("model.mtl"), mtl).unwrap();
    run(d);
    let (left, right) = (pixel(d, 16, 16), pixel(d, 47, 16));
    assert!(left[0].abs_diff(230) <= 2 && left[1].abs_diff(40) <= 2 && left[3] == 255, "{left:?}");
    assert!(right[2].abs_diff(230) <= 2 && right[0].abs_diff(40) <= 2, "{right:?}");
}

/// Game assets and 3ds Max exports name TGA and BMP textures, which Blender reads: they render as the PNG does.
#[test]
fn tga_and_bmp_textures_render_as_the_png_does() {
    let mut images = Vec::new();
    for ext in ["png", "tga", "bmp"] {
        let tmp = tempfile::tempdir().unwrap();
        let d = tmp.path();
        let mut checker = image::RgbImage::new(4, 4);
        for (x, y, p) in checker.enumerate_pixels_mut() {
            *p = if (x + y) % 2 == 0 { image::Rgb([230, 40, 40]) } else { image::Rgb([40, 40, 230]) };
        }
        checker.save(d.join(format!("skin.{ext}"))).unwrap();
        std::fs::write(d.join("model.obj"), OBJ).unwrap();
        std::fs::write(d.join("model.mtl"), format!("newmtl skin\nmap_Kd skin.{ext}\nnewmtl lid\nKd 1 1 1\n")).unwrap();
        run(d);
        images.push(std::fs::read(d.join("out/m_dnerf/train/r_0000.png")).unwrap());
    }
    assert_eq!(images[0], images[1], "TGA");
    assert_eq!(images[0], images[2], "BMP");
}

/// A library or texture named and missing is left out, as Blender's importer leaves it: the model renders (in
/// Blender's grey where the library would colour it), `check` warns naming the line and what lies beside, and
/// `--deny-warnings` refuses. Once the file is there, the frame re-renders with it.
#[test]
fn a_missing_texture_or_library_is_a_warning_naming_its_line_and_what_lies_beside() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    std::fs::write(d.join("model.obj"), OBJ).unwrap();
    std::fs::write(d.join("m.toml"), manifest()).unwrap();
    let check = |deny: bool| {
        let mut cmd = std::process::Command::new(env!("CARGO_BIN_EXE_vvgen"));
        cmd.arg("check").args(deny.then_some("--deny-warnings")).arg(d.join("m.toml"));
        let out = cmd.output().unwrap();
        (out.status.code(), String::from_utf8_lossy(&out.stderr).into_owned())
    };
    // The library was renamed apart from the OBJ (as downloads are): the warning names the one beside it.
    std::fs::write(d.join("model.mt"), "newmtl skin\nKd 1 0 0\nnewmtl lid\nKd 0 0 1\n").unwrap();
    let (code, err) = check(false);
    assert_eq!(code, Some(0), "{err}");
    assert!(
        err.contains("model.obj:1: material library `model.mtl` not found")
            && err.contains("beside it: `model.mt`. Point line 1"),
        "{err}"
    );
    assert_eq!(check(true).0, Some(2));
    run(d);
    let grey = pixel(d, 16, 16);
    assert!(grey[0] == grey[2] && grey[0] > 100 && grey[3] == 255, "Blender's grey: {grey:?}");
    // A texture found nowhere: its MTL's line, and where it was looked for; the library's colours now show.
    std::fs::rename(d.join("model.mt"), d.join("model.mtl")).unwrap();
    std::fs::write(
        d.join("model.mtl"),
        "newmtl skin\nKd 1 0 0\nmap_d -imfchan m textures\\gone.png\nnewmtl lid\nKd 0 0 1\n",
    )
    .unwrap();
    let (code, err) = check(false);
    assert_eq!(code, Some(0), "{err}");
    assert!(
        err.contains("model.mtl:3: texture `textures\\gone.png` not found") && err.contains("textures/gone.png"),
        "{err}"
    );
    run(d);
    let red = pixel(d, 16, 16);
    assert!(red[0] > 200 && red[2] < 60 && red[3] == 255, "the library's colour: {red:?}");
}

#[test]
fn dissolve_and_an_alpha_map_make_a_surface_translucent() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    std::fs::write(d.join("model.obj"), OBJ).unwrap();
    // `d 0.5`; and `map_d` read from its image's alpha channel, as Blender links its Alpha output.
    image::RgbaImage::from_pixel(2, 2, image::Rgba([255, 255, 255, 64])).save(d.join("mask.png")).unwrap();
    std::fs::write(
        d.join("model.mtl"),
        "newmtl skin\nKd 0.8 0.2 0.2\nd 0.5\nnewmtl lid\nKd 0.2 0.2 0.8\nmap_d mask.png\n",
    )
    .unwrap();
    run(d);
    let (left, right) = (pixel(d, 16, 16), pixel(d, 47, 16));
    assert!(left[3].abs_diff(128) <= 2, "{left:?}");
    assert!(right[3].abs_diff(64) <= 2, "{right:?}");
    // The colour stays Kd's: the alpha map carries alpha alone.
    assert!(right[2] > 200 && right[0] < 130, "{right:?}");
}

#[test]
fn a_wholly_transparent_material_is_warned_of() {
    // `d 0` shows nothing (in Blender too); some exporters write it meaning opaque.
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    std::fs::write(d.join("model.obj"), OBJ).unwrap();
    std::fs::write(d.join("model.mtl"), "newmtl skin\nKd 0.8 0.2 0.2\nd 0.000000\nnewmtl lid\nKd 0.2 0.2 0.8\nd 0.5\n")
        .unwrap();
    std::fs::write(d.join("m.toml"), manifest()).unwrap();
    let out =
        std::process::Command::new(env!("CARGO_BIN_EXE_vvgen")).arg("check").arg(d.join("m.toml")).output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "{err}");
    assert!(
        err.contains("material `skin` has `d 0`")
            && !err.contains("`lid`")
            && err.contains("set `opaque = true`")
            && err.contains("`d 1` in its MTL"),
        "{err}"
    );
}

#[test]
fn new_writes_one_obj_as_a_static_mesh() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    std::fs::write(d.join("model.obj"), OBJ).unwrap();
    std::fs::write(d.join("model.mtl"), "newmtl skin\nKd 0.8 0.2 0.2\nnewmtl lid\nKd 0.2 0.2 0.8\n").unwrap();
    let vvgen = |args: &[&str]| {
        std::process::Command::new(env!("CARGO_BIN_EXE_vvgen")).current_dir(d).args(args).output().unwrap()
    };
    assert!(vvgen(&["new", "model.obj"]).status.success());
    let text = std::fs::read_to_string(d.join("model.toml")).unwrap();
    assert!(text.contains("mesh   = \"model.obj\"") && !text.contains("fps"), "{text}");
    let out = vvgen(&["check", "model.toml"]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
}
