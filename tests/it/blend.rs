//! `.blend` sources: a file Blender writes (a keyframed, textured cube; an armature-skinned cylinder with an
//! animated shape key) imports through Blender's glTF export and poses as Blender's own evaluation does; the
//! import runs once per content of the file and what it names; without Blender, `check` says the two ways out.
//! These tests need Blender and numpy (`apt install blender python3-numpy`; `.ci/run` installs both) and skip
//! visibly without them.

use std::path::{Path, PathBuf};
use std::process::Command;

use vvgen::cache::{StatCache, Store};
use vvgen::scene::{blend::Importer, Poser};

fn vvgen(dir: &Path, args: &[&str], blender: &Path) -> (i32, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_vvgen"))
        .current_dir(dir)
        .env("VVGEN_BLENDER", blender)
        .env_remove("VVGEN_CACHE")
        .args(args)
        .output()
        .unwrap();
    (out.status.code().unwrap_or(-1), String::from_utf8_lossy(&out.stderr).into_owned())
}

/// Blender on the PATH, or why the test skips.
fn blender() -> Option<PathBuf> {
    match vvgen::scene::blend::blender_exe() {
        Ok(p) => Some(p),
        Err(why) => {
            eprintln!("skipping: {why} (.ci/run installs Blender)");
            None
        }
    }
}

/// Writes the test scene and Blender's posed vertices of it (`posed.json`) into `dir`; `None` (said) when this
/// Blender cannot export glTF.
fn make_scene(blender: &Path, dir: &Path) -> Option<()> {
    let script = crate::common::data("blend/make_scene.py");
    let out = Command::new(blender)
        .args(["-b", "--factory-startup", "--python"])
        .arg(script)
        .arg("--")
        .arg(dir)
        .output()
        .unwrap();
    if out.status.code() == Some(5) {
        eprintln!("skipping: Blender's Python lacks numpy, which its glTF exporter needs (apt install python3-numpy)");
        return None;
    }
    assert!(out.status.success() && dir.join("posed.json").is_file(), "{}", String::from_utf8_lossy(&out.stderr));
    Some(())
}

/// A manifest with the scene's `.blend` as its one source, as written (no transform: Blender's world).
fn write_manifest(dir: &Path, extra: &str) {
    let text = format!(
        "[dataset]\nname = \"b\"\nout = \"out\"\n[source.s]\nblend = \"scene.blend\"\n{extra}\n\
         [render]\nresolution = [48, 48]\n[rig.h]\nkind = \"hemisphere\"\n[split.train]\nrig = \"h\"\nviews = 3\n\
         [output.d]\nwriter = \"nerfstudio\"\n"
    );
    std::fs::write(dir.join("m.toml"), text).unwrap();
}

/// Largest distance between the point sets, both ways (vertices split at seams by the glTF export sit on
/// Blender's, so the sets match without a correspondence).
fn hausdorff(a: &[[f32; 3]], b: &[[f32; 3]]) -> f32 {
    let v = |s: &[[f32; 3]]| s.iter().map(|p| glam::Vec3::from_array(*p)).collect::<Vec<_>>();
    crate::common::hausdorff(&v(a), &v(b))
}

#[test]
fn blend_poses_as_blender_evaluates_it_and_imports_once() {
    let Some(blender) = blender() else { return };
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    if make_scene(&blender, d).is_none() {
        return;
    }
    let reference: std::collections::BTreeMap<String, Vec<[f32; 3]>> =
        serde_json::from_slice(&std::fs::read(d.join("posed.json")).unwrap()).unwrap();
    write_manifest(d, "");
    let m = crate::common::load(&d.join("m.toml"));
    let store = Store::open(&d.join("library-cache")).unwrap();
    let stat = StatCache::load(&d.join("stat"));
    let importer = Importer::new(&store, &stat, None);
    let scene = vvgen::settings::scene::open(&m, Some(&importer)).unwrap();
    // The file's frame range, 1–24: scene frame i is Blender's frame 1 + i.
    assert_eq!(scene.frames, 24);
    let mut poser = Poser::default();
    let all = &reference["1"];
    let height = all.iter().map(|p| p[2]).fold(f32::MIN, f32::max) - all.iter().map(|p| p[2]).fold(f32::MAX, f32::min);
    for (frame, want) in &reference {
        let f: usize = frame.parse().unwrap();
        let posed = scene.pose(f - 1, &mut poser).unwrap();
        let got: Vec<[f32; 3]> =
            posed.primitives.iter().flat_map(|p| p.positions.iter().map(|v| v.to_array())).collect();
        let off = hausdorff(&got, want);
        assert!(off < 1e-4 * height, "Blender frame {f}: {off} from Blender's evaluated vertices (height {height})");
    }
    // The bend and the bulge moved it: a pose that ignored the animation would fail above, and this says so.
    assert!(hausdorff(&reference["1"], &reference["24"]) > 0.1 * height);

    // The CLI through a Blender that logs its runs: the first build imports once; the second starts no
    // Blender at all; a changed texture the file names imports again.
    let log = d.join("runs.log");
    let wrapper = d.join("blender-logged");
    std::fs::write(
        &wrapper,
        format!("#!/bin/sh\necho \"$*\" >> '{}'\nexec '{}' \"$@\"\n", log.display(), blender.display()),
    )
    .unwrap();
    Command::new("chmod").arg("755").arg(&wrapper).status().unwrap();
    // Older than the stat cache's racy window, as installed programs and saved files are.
    Command::new("touch").args(["-d", "2026-01-01"]).arg(&wrapper).arg(d.join("scene.blend")).status().unwrap();
    let runs = || std::fs::read_to_string(&log).unwrap_or_default().lines().filter(|l| l.contains("--python")).count();
    let starts = || std::fs::read_to_string(&log).unwrap_or_default().lines().count();
    // `status` must import to count the frames, and says so while it does.
    let (code, err) = vvgen(d, &["status", "m.toml"], &wrapper);
    assert_eq!(code, 0, "{err}");
    assert_eq!(runs(), 1, "{err}");
    assert!(err.contains("importing") && err.contains("scene.blend"), "{err}");
    let (code, err) = vvgen(d, &["build", "m.toml"], &wrapper);
    assert_eq!(code, 0, "{err}");
    assert_eq!(runs(), 1, "the build reuses the import `status` made: {err}");
    let before = starts();
    let (code, err) = vvgen(d, &["build", "m.toml"], &wrapper);
    assert_eq!(code, 0, "{err}");
    assert_eq!(starts(), before, "a second build started Blender: {err}");
    assert!(!err.contains("importing"), "{err}");
    let png = image::RgbaImage::from_pixel(8, 8, image::Rgba([200, 30, 30, 255]));
    png.save(d.join("checker.png")).unwrap();
    let (code, err) = vvgen(d, &["build", "m.toml"], &wrapper);
    assert_eq!(code, 0, "{err}");
    assert_eq!(runs(), 2, "the texture changed: {err}");
    assert!(err.contains("importing") && err.contains("scene.blend"), "the build says it imports: {err}");
    // The frames rendered again: each frame's glTF names the texture, which keys the frame.
    assert!(err.contains("render-pass 72/72"), "{err}");

    // `vvgen new` writes the file's frame range and rate, through the cache its manifest uses (which holds the
    // import already); what it writes names the same frames another way, and checks without importing again.
    let (code, err) = vvgen(d, &["new", "scene.blend", "-o", "fresh.toml"], &wrapper);
    assert_eq!(code, 0, "{err}");
    let text = std::fs::read_to_string(d.join("fresh.toml")).unwrap();
    assert!(text.contains("blend  = \"scene.blend\"") && text.contains("start = 1, end = 24, fps = 24"), "{text}");
    let before = starts();
    let (code, err) = vvgen(d, &["check", "fresh.toml"], &wrapper);
    assert_eq!(code, 0, "{err}");
    assert_eq!(runs(), 2, "{err}");
    // `gc` keeps what the manifest reaches (the current import and its placed files) and drops the import the
    // texture change left behind; the next build starts no Blender.
    let placed = || std::fs::read_dir(d.join("cache/blend")).unwrap().count();
    assert_eq!(placed(), 2);
    let (code, err) = vvgen(d, &["gc", "--keep", "m.toml", "--min-age", "0"], &wrapper);
    assert_eq!(code, 0, "{err}");
    assert_eq!(placed(), 1, "{err}");
    let (code, err) = vvgen(d, &["build", "m.toml"], &wrapper);
    assert_eq!(code, 0, "{err}");
    assert!(!err.contains("importing") && err.contains("nothing to do"), "{err}");
    // At most `blender --version`: Blender's version is remembered per dataset's stat file, and this is a new one.
    assert!(starts() <= before + 1, "check imported again: {err}");
}

#[test]
fn blend_errors_name_the_file_and_the_way_out() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    // Without Blender (whatever this machine has): `check` refuses with exit 2, naming both ways out.
    std::fs::write(d.join("scene.blend"), b"BLENDER-v304 not really").unwrap();
    write_manifest(d, "");
    let (code, err) = vvgen(d, &["check", "m.toml"], &d.join("no-blender-here"));
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("scene.blend") && err.contains("install Blender") && err.contains("glTF 2.0"), "{err}");
    // Settings that do not fit a `.blend` are manifest errors, before any Blender runs.
    for (extra, says) in [
        ("animation = 0", "`animation` applies only to"),
        ("scene = 1", "chosen by name"),
        ("object = \"A\"\ncollection = \"B\"", "not both"),
    ] {
        write_manifest(d, extra);
        let (code, err) = vvgen(d, &["check", "m.toml"], &d.join("no-blender-here"));
        assert_eq!(code, 2, "{extra}: {err}");
        assert!(err.contains(says), "{extra}: {err}");
    }
    let Some(blender) = blender() else { return };
    // A file Blender cannot read, and a selection the file lacks: Blender's word, said as vvgen's error.
    write_manifest(d, "");
    let (code, err) = vvgen(d, &["check", "m.toml"], &blender);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("scene.blend"), "{err}");
    if make_scene(&blender, d).is_none() {
        return;
    }
    for (extra, says) in [
        ("object = \"Nope\"", "has no object `Nope`; its objects: Arm, Cube, Linked, Rig"),
        ("scene = \"Nope\"", "has no scene `Nope`; its scenes: Scene"),
        ("collection = \"Nope\"", "has no collection `Nope`"),
    ] {
        write_manifest(d, extra);
        let (code, err) = vvgen(d, &["check", "m.toml"], &blender);
        assert_eq!(code, 2, "{extra}: {err}");
        assert!(err.contains(says), "{extra}: {err}");
    }
    // One object, as its armature deforms it.
    write_manifest(d, "object = \"Arm\"");
    let (code, err) = vvgen(d, &["check", "m.toml"], &blender);
    assert_eq!(code, 0, "{err}");
}

/// A Python with Blender's `bpy` module (the PyPI wheel: a current Blender where the system's is old) in
/// `VVGEN_BLENDER` imports a `.blend` as Blender does: it opens the file, then runs the same export. Played here
/// by Blender's own Python (`bpy` is `bpy`), behind a `python3` that runs `-c CODE ARGS…` inside Blender: the
/// images are the Blender binary's, byte for byte. A Python without `bpy` is refused, saying how to add it.
#[test]
fn a_python_with_bpy_imports_a_blend_as_blender_does() {
    let Some(blender) = blender() else { return };
    let tmp = tempfile::tempdir().unwrap();
    let (by_blender, by_python) = (tmp.path().join("blender"), tmp.path().join("python"));
    std::fs::create_dir_all(&by_blender).unwrap();
    if make_scene(&blender, &by_blender).is_none() {
        return;
    }
    // The scene with what it reads (its linked library, its texture).
    std::fs::create_dir_all(&by_python).unwrap();
    for f in std::fs::read_dir(&by_blender).unwrap().map(|e| e.unwrap().path()) {
        std::fs::copy(&f, by_python.join(f.file_name().unwrap())).unwrap();
    }
    let bin = tmp.path().join("venv/bin");
    std::fs::create_dir_all(&bin).unwrap();
    let python = bin.join("python3");
    let code = bin.join("code.py");
    let expr = format!(
        "import sys; sys.argv = ['-c'] + sys.argv[sys.argv.index('--') + 1:]; exec(compile(open('{}').read(), '<string>', 'exec'))",
        code.display()
    );
    let script = format!(
        "#!/bin/sh\n[ \"$1\" = -c ] || exit 64\nprintf '%s' \"$2\" > '{}'\nshift 2\nexec '{}' -b --factory-startup -noaudio \
         --python-expr \"{expr}\" -- \"$@\"\n",
        code.display(),
        blender.display(),
    );
    std::fs::write(&python, script).unwrap();
    use std::os::unix::fs::PermissionsExt;
    std::fs::set_permissions(&python, std::fs::Permissions::from_mode(0o755)).unwrap();

    let images = |d: &Path, exe: &Path| -> Vec<Vec<u8>> {
        write_manifest(d, "frames = { start = 1, end = 3 }");
        let (code, err) = vvgen(d, &["build", "m.toml"], exe);
        assert_eq!(code, 0, "{err}");
        assert!(err.contains("scene.blend with Blender "), "{err}");
        // Every PNG the dataset holds, in path order.
        let (mut files, mut dirs) = (Vec::new(), vec![d.join("out")]);
        while let Some(dir) = dirs.pop() {
            for p in std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().path()) {
                match p.extension().and_then(|e| e.to_str()) {
                    _ if p.is_dir() => dirs.push(p),
                    Some("png") => files.push(p),
                    _ => {}
                }
            }
        }
        files.sort();
        assert!(files.len() >= 9, "three frames, three views: {files:?}");
        files.iter().map(|f| std::fs::read(f).unwrap()).collect()
    };
    assert!(images(&by_python, &python) == images(&by_blender, &blender), "the Python route renders otherwise");

    // A Python without `bpy`: the system's, under a name that says Python.
    let Some(system) = std::env::split_paths(&std::env::var_os("PATH").unwrap_or_default())
        .map(|d| d.join("python3"))
        .find(|p| p.is_file())
    else {
        eprintln!("skipping the bpy-less Python: no python3 on the PATH");
        return;
    };
    let plain = tmp.path().join("plain");
    std::fs::create_dir_all(&plain).unwrap();
    std::fs::copy(by_blender.join("scene.blend"), plain.join("scene.blend")).unwrap();
    write_manifest(&plain, "");
    let (code, err) = vvgen(&plain, &["check", "m.toml"], &system);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("cannot import Blender's `bpy` module") && err.contains("pip install bpy"), "{err}");
}

/// Runs Python `make` in Blender (the folder `d` after `--`), which saves `d/scene.blend`, then `vvgen check` of
/// a manifest with that file as its source: the exit code and what it printed, or `None` (said) when Blender's
/// Python lacks numpy.
fn check_made(blender: &Path, d: &Path, make: &str) -> Option<(i32, String)> {
    let out =
        Command::new(blender).args(["-b", "--factory-startup", "--python-expr", make, "--"]).arg(d).output().unwrap();
    assert!(out.status.success() && d.join("scene.blend").is_file(), "{}", String::from_utf8_lossy(&out.stderr));
    write_manifest(d, "");
    let (code, err) = vvgen(d, &["check", "m.toml"], blender);
    if err.contains("numpy") {
        eprintln!("skipping: Blender's Python lacks numpy (apt install python3-numpy)");
        return None;
    }
    Some((code, err))
}

/// A library the file links from Blender's own bundled assets (`…/datafiles/assets/…`: the essentials brushes
/// a Blender 4.3+ file links by its path on the authoring machine) is Blender's, not the file's: missing here,
/// it is not warned of, while another missing library is.
#[test]
fn blenders_own_asset_libraries_are_not_missing_inputs() {
    let Some(blender) = blender() else { return };
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    let make = r#"import bpy, os, sys
out = sys.argv[sys.argv.index("--") + 1]
libs = [os.path.join(out, "blender", "datafiles", "assets", "brushes.blend"), os.path.join(out, "mine", "parts.blend")]
for i, lib in enumerate(libs):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.data.materials.new("M%d" % i).use_fake_user = True
    os.makedirs(os.path.dirname(lib), exist_ok=True)
    bpy.ops.wm.save_as_mainfile(filepath=lib)
bpy.ops.wm.read_factory_settings(use_empty=True)
bpy.ops.mesh.primitive_cube_add()
for i, lib in enumerate(libs):
    with bpy.data.libraries.load(lib, link=True) as (src, dst):
        dst.materials = ["M%d" % i]
    for m in dst.materials:
        m.use_fake_user = True
bpy.ops.wm.save_as_mainfile(filepath=os.path.join(out, "scene.blend"))
for lib in libs:
    os.remove(lib)
"#;
    let Some((code, err)) = check_made(&blender, d, make) else { return };
    assert_eq!(code, 0, "{err}");
    assert!(err.contains("parts.blend`, which is missing"), "the file's own library is warned of: {err}");
    assert!(!err.contains("brushes.blend"), "Blender's bundled library is not: {err}");
}

/// A scene whose only object is one Blender's glTF exporter skips (hair curves here; point clouds, volumes and
/// grease pencil too) has nothing to draw, and the error names the object and says to convert it to a mesh.
#[test]
fn a_scene_of_objects_the_exporter_skips_says_to_convert_them() {
    let Some(blender) = blender() else { return };
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    let make = "import bpy, os, sys\nbpy.ops.wm.read_factory_settings(use_empty=True)\n\
                o = bpy.data.objects.new('Hair', bpy.data.hair_curves.new('Hair'))\n\
                bpy.context.scene.collection.objects.link(o)\n\
                bpy.ops.wm.save_as_mainfile(filepath=os.path.join(sys.argv[sys.argv.index('--') + 1], 'scene.blend'))\n";
    let Some((code, err)) = check_made(&blender, d, make) else { return };
    assert_eq!(code, 2, "{err}");
    for says in ["has nothing to draw", "hair curves", "(Hair)", "Object > Convert > Mesh"] {
        assert!(err.contains(says), "`{says}` not in: {err}");
    }
}
