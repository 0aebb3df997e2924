//! The first hour, as a newcomer lives it, over every model and sequence under `tests/data`: `vvgen new` with a
//! bare relative name, from the asset's own folder and from its parent, then `check` and a small build of the
//! manifest it wrote (64², a few views, a few frames). Every asset must check and build with no warning, crop
//! no view, and give images that are neither empty nor covered to the edge. The wide subjects in
//! `tests/data/wide` (a long low walking box, a flat plate far off the origin, a wide bending strip) are the
//! cases the old height fit cropped in every view.

use std::path::{Path, PathBuf};
use std::process::Command;

use crate::common::data;

/// Files that hold only lines, which vvgen does not draw: `new` refuses them, saying so.
const NOTHING_TO_DRAW: [&str; 3] =
    ["Mesh_PrimitiveMode_01.gltf", "Mesh_PrimitiveMode_02.gltf", "Mesh_PrimitiveMode_03.gltf"];

/// Flat subjects in the plane z = 0 with single-sided (or default) materials, whose backs glTF culls: a camera
/// behind one sees nothing, so an empty image is right there. Some image must still show each.
const ONE_SIDED_FLAT: [&str; 7] = [
    "Mesh_PrimitiveMode_04.gltf",
    "Mesh_PrimitiveMode_05.gltf",
    "Mesh_PrimitiveMode_14.gltf",
    "SimpleMorph.gltf",
    "SimpleSkin.gltf",
    "SimpleSparseAccessor.gltf",
    "unassigned-skeleton.gltf",
];

fn vvgen(dir: &Path, args: &[&str]) -> (i32, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_vvgen")).current_dir(dir).args(args).output().unwrap();
    (out.status.code().unwrap_or(-1), String::from_utf8_lossy(&out.stderr).into_owned())
}

fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap() {
        let e = e.unwrap();
        let dest = to.join(e.file_name());
        if e.file_type().unwrap().is_dir() {
            copy_dir(&e.path(), &dest);
        } else {
            std::fs::copy(e.path(), dest).unwrap();
        }
    }
}

/// Every asset a newcomer could point `vvgen new` at, below `root`: glTF and GLB files, PLY and OBJ files that
/// are not frames of a folder, and folders of frames.
fn assets(root: &Path) -> Vec<PathBuf> {
    let mut v = Vec::new();
    for group in ["gltf", "wide"] {
        for dir in std::fs::read_dir(root.join(group)).unwrap() {
            let dir = dir.unwrap().path();
            if !dir.is_dir() {
                continue;
            }
            let mut files: Vec<PathBuf> = std::fs::read_dir(&dir).unwrap().map(|e| e.unwrap().path()).collect();
            files.sort();
            let ext = |p: &Path| p.extension().map(|e| e.to_string_lossy().to_ascii_lowercase()).unwrap_or_default();
            let frames = files.iter().filter(|p| matches!(ext(p).as_str(), "obj" | "ply")).count();
            if frames > 1 {
                v.push(dir.clone());
            }
            v.extend(files.into_iter().filter(|p| match ext(p).as_str() {
                "gltf" | "glb" => true,
                "ply" | "obj" => frames == 1,
                _ => false,
            }));
        }
    }
    v.push(root.join("seq"));
    // FBX files lie in their folder's root (its subfolders hold fuzz cases and Blender's reference arrays).
    for e in std::fs::read_dir(root.join("fbx")).unwrap() {
        let p = e.unwrap().path();
        if p.extension().is_some_and(|x| x == "fbx") {
            v.push(p);
        }
    }
    v.sort();
    v
}

/// The manifest `new` wrote, made small: 64², one sample, a few views and frames. Each edit must apply, so a
/// change to `new`'s template shows here instead of silently building the full size.
fn shrink(text: &str) -> String {
    let mut t = text.to_string();
    let mut edit = |from: &str, to: &str, required: bool| {
        let hit = t.lines().any(|l| l.trim_start().starts_with(from));
        assert!(hit || !required, "no line starting {from:?} in\n{t}");
        t = t.lines().map(|l| if l.trim_start().starts_with(from) { to } else { l }).collect::<Vec<_>>().join("\n");
    };
    edit("resolution", "resolution = [64, 64]", true);
    edit("samples", "samples = 1", true);
    edit("views = 100", "views = 4", false);
    edit("views = 10", "views = 2", false);
    edit("views    = 20", "views = 2", false);
    // Three frames of a clip, evenly spread over it by a lower rate: the whole motion, in a few images.
    let re_frames = t.lines().find(|l| l.starts_with("frames = { count = ")).map(str::to_string);
    if let Some(line) = re_frames {
        let count: f64 = line["frames = { count = ".len()..].split(',').next().unwrap().trim().parse().unwrap();
        let fps = 30.0 * 2.0 / (count - 1.0).max(1.0);
        t = t.replace(&line, &format!("frames = {{ count = 3, fps = {fps} }}"));
    }
    t + "\n"
}

/// Checks every RGBA image under `dir`: something drawn (unless `may_be_empty`), something not, nothing at the
/// border. Returns how many images show something.
fn images_are_framed(dir: &Path, may_be_empty: bool, ctx: &str) -> usize {
    let mut n = 0;
    for split in ["train", "val", "test"] {
        let Ok(entries) = std::fs::read_dir(dir.join(split)) else { continue };
        for e in entries {
            let p = e.unwrap().path();
            if p.extension().is_none_or(|x| x != "png") {
                continue;
            }
            let img = image::open(&p).unwrap().to_rgba8();
            let (w, h) = img.dimensions();
            let alpha = |x: u32, y: u32| img.get_pixel(x, y)[3];
            let covered = img.pixels().filter(|px| px[3] > 0).count();
            assert!(covered > 0 || may_be_empty, "{ctx}: {} is empty", p.display());
            assert!(covered < (w * h) as usize, "{ctx}: {} is covered to every pixel", p.display());
            let border = (0..w).any(|x| alpha(x, 0) > 0 || alpha(x, h - 1) > 0)
                || (0..h).any(|y| alpha(0, y) > 0 || alpha(w - 1, y) > 0);
            assert!(!border, "{ctx}: {} reaches the image's edge (cropped)", p.display());
            n += usize::from(covered > 0);
        }
    }
    n
}

#[test]
fn every_asset_in_tests_data_builds_whole_from_a_bare_relative_name() {
    let tmp = tempfile::tempdir().unwrap();
    for group in ["gltf", "wide", "seq", "fbx"] {
        copy_dir(&data(group), &tmp.path().join(group));
    }
    let mut built = 0;
    for asset in assets(tmp.path()) {
        let folder = if asset.is_dir() { asset.clone() } else { asset.parent().unwrap().to_path_buf() };
        let name = asset.file_name().unwrap().to_string_lossy().into_owned();
        // From the asset's folder (`new model.gltf`, or `new .` for a folder of frames) and from its parent
        // (`new Folder/model.gltf`), each writing its manifest where it runs.
        let here = if asset.is_dir() { ".".to_string() } else { name.clone() };
        let from_parent = asset.strip_prefix(folder.parent().unwrap()).unwrap();
        let runs = [
            (folder.clone(), here),
            (folder.parent().unwrap().to_path_buf(), from_parent.to_string_lossy().into_owned()),
        ];
        for (cwd, arg) in runs {
            let ctx = format!("`vvgen new {arg}` in {}", cwd.display());
            let manifest = format!("m-{}.toml", name.replace('.', "-"));
            let (code, err) = vvgen(&cwd, &["new", &arg, "-o", &manifest]);
            if NOTHING_TO_DRAW.contains(&name.as_str()) {
                assert_eq!(code, 2, "{ctx}: {err}");
                assert!(err.contains("nothing to render"), "{ctx}: {err}");
                continue;
            }
            assert_eq!(code, 0, "{ctx}: {err}");
            let text = std::fs::read_to_string(cwd.join(&manifest)).unwrap();
            assert!(text.contains("fit    = \"frame\""), "{ctx}: new writes the frame fit:\n{text}");
            std::fs::write(cwd.join(&manifest), shrink(&text)).unwrap();
            let (code, err) = vvgen(&cwd, &["--color", "never", "check", &manifest]);
            assert_eq!(code, 0, "{ctx}: check: {err}");
            assert!(!err.contains("warning"), "{ctx}: check warns:\n{err}");
            let (code, err) = vvgen(&cwd, &["--color", "never", "build", &manifest]);
            assert_eq!(code, 0, "{ctx}: build: {err}");
            assert!(!err.contains("warning"), "{ctx}: build warns:\n{err}");
            // The dataset lands beside the manifest, and so does the cache, wherever the command ran.
            assert!(cwd.join("cache/objects").is_dir(), "{ctx}: no cache beside the manifest");
            let out = std::fs::read_dir(cwd.join("out")).unwrap().map(|e| e.unwrap().path()).collect::<Vec<_>>();
            let mut images = 0;
            for dataset in out.iter().flat_map(|d| std::fs::read_dir(d).unwrap()) {
                images += images_are_framed(&dataset.unwrap().path(), ONE_SIDED_FLAT.contains(&name.as_str()), &ctx);
            }
            assert!(images > 0, "{ctx}: no images built");
            built += 1;
            std::fs::remove_dir_all(cwd.join("out")).unwrap();
        }
    }
    // 15 glTF folders' files less the three line-only ones, the three wide subjects, the PLY sequence and four
    // FBX files: twice.
    assert!(built >= 2 * 24, "only {built} builds");
}

#[test]
fn the_height_convention_crops_a_wide_subject_and_check_says_how_to_keep_it_whole() {
    let tmp = tempfile::tempdir().unwrap();
    copy_dir(&data("wide/plate"), tmp.path());
    let (code, err) = vvgen(tmp.path(), &["new", "plate.ply", "-o", "m.toml"]);
    assert_eq!(code, 0, "{err}");
    let text = shrink(&std::fs::read_to_string(tmp.path().join("m.toml")).unwrap())
        .replace("fit    = \"frame\"", "fit = { height = 2.4 }");
    std::fs::write(tmp.path().join("m.toml"), text).unwrap();
    let (code, err) = vvgen(tmp.path(), &["--color", "never", "check", "m.toml"]);
    assert_eq!(code, 0, "{err}");
    // Exactly what a newcomer reads: how many, the worst, and both ways out.
    let train = err.lines().find(|l| l.contains("`train` images crop the subject")).unwrap_or_else(|| panic!("{err}"));
    assert!(
        train.starts_with("warning: 4 of 4 `train` images crop the subject (4 of 4 views; worst: view "),
        "{train}"
    );
    assert!(train.contains("of its vertices outside the image); [transform] fit = \"frame\" or rig `hemi` radius = "));
    assert!(train.ends_with(" keeps it whole"), "{train}");
    // Strict: the same warnings are errors, in check and in build, and nothing is rendered.
    let (code, err) = vvgen(tmp.path(), &["--color", "never", "check", "--deny-warnings", "m.toml"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("warnings are errors here"), "{err}");
    let strict =
        std::fs::read_to_string(tmp.path().join("m.toml")).unwrap().replace("seed = 0", "seed = 0\nstrict = true");
    std::fs::write(tmp.path().join("m.toml"), strict).unwrap();
    let (code, err) = vvgen(tmp.path(), &["build", "m.toml"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("crop the subject"), "{err}");
    let blobs = std::fs::read_dir(tmp.path().join("cache/objects")).map_or(0, |d| d.count());
    assert!(!tmp.path().join("out").exists() && blobs == 0, "the strict build rendered");
    // The suggested radius keeps it whole.
    let radius: f64 = train.split("radius = ").nth(1).unwrap().split(' ').next().unwrap().parse().unwrap();
    let fixed = std::fs::read_to_string(tmp.path().join("m.toml"))
        .unwrap()
        .replace("kind = \"hemisphere\"", &format!("kind = \"hemisphere\"\nradius = {radius}"))
        .replace("kind     = \"orbit\"", &format!("kind     = \"orbit\"\nradius = {radius}"));
    std::fs::write(tmp.path().join("m.toml"), fixed).unwrap();
    let (code, err) = vvgen(tmp.path(), &["--color", "never", "check", "m.toml"]);
    assert_eq!(code, 0, "{err}");
    assert!(!err.contains("crop"), "radius {radius} still crops:\n{err}");
}
