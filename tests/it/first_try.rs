//! What a newcomer meets in the first hour, besides framing (`corpus.rs`): `vvgen new`'s edges, a cache that
//! does not follow the working directory, outputs that remove what they no longer hold, and warnings about
//! frames a clip does not cover.

use std::path::Path;
use std::process::Command;

use crate::common::data;

fn vvgen(dir: &Path, args: &[&str]) -> (i32, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_vvgen")).current_dir(dir).args(args).output().unwrap();
    (out.status.code().unwrap_or(-1), String::from_utf8_lossy(&out.stderr).into_owned())
}

/// The walking long box's folder, copied into `dir`.
fn longbox(dir: &Path) {
    for f in ["longbox.gltf", "longbox.bin"] {
        std::fs::copy(data("wide/longbox").join(f), dir.join(f)).unwrap();
    }
}

/// Makes a manifest `new` wrote small: 48², one sample.
fn small(path: &Path) {
    let t = std::fs::read_to_string(path).unwrap();
    let t = t
        .lines()
        .map(|l| match l {
            l if l.starts_with("resolution") => "resolution = [48, 48]",
            l if l.starts_with("samples") => "samples = 1",
            l => l,
        })
        .collect::<Vec<_>>()
        .join("\n");
    std::fs::write(path, t).unwrap();
}

/// A folder holding the walking long box and the manifest `vvgen new` writes for it with `writer`, made small
/// (`m.toml`).
fn project(writer: &str) -> tempfile::TempDir {
    let tmp = tempfile::tempdir().unwrap();
    longbox(tmp.path());
    let (code, err) = vvgen(tmp.path(), &["new", "longbox.gltf", "--writer", writer, "-o", "m.toml"]);
    assert_eq!(code, 0, "{err}");
    small(&tmp.path().join("m.toml"));
    tmp
}

/// `vvgen check` of `d/m.toml` with the first `from` replaced by `to`, written as `d/a.toml`.
fn check_edited(d: &Path, from: &str, to: &str) -> (i32, String) {
    let text = std::fs::read_to_string(d.join("m.toml")).unwrap();
    assert!(text.contains(from), "{from:?} not in\n{text}");
    std::fs::write(d.join("a.toml"), text.replacen(from, to, 1)).unwrap();
    vvgen(d, &["--color", "never", "check", "a.toml"])
}

#[test]
fn new_writes_where_asked_and_refuses_what_is_not_an_asset() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    longbox(d);
    // Into a folder that does not exist yet; the asset's path is relative to the manifest there.
    let (code, err) = vvgen(d, &["new", "longbox.gltf", "-o", "sub/deeper/box.toml"]);
    assert_eq!(code, 0, "{err}");
    let text = std::fs::read_to_string(d.join("sub/deeper/box.toml")).unwrap();
    assert!(text.contains("gltf   = \"../../longbox.gltf\""), "{text}");
    // Each clip with the frame count that covers it.
    assert!(text.contains("#   1: `Idle`, 0.500 s: frames = { count = 16, fps = 30 }"), "{text}");
    let (code, err) = vvgen(d, &["check", "sub/deeper/box.toml"]);
    assert_eq!(code, 0, "{err}");
    // A manifest is not an asset, whether or not it exists.
    let (code, err) = vvgen(d, &["new", "sub/deeper/box.toml"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("not a glTF, FBX, .blend, PLY, OBJ, STL or Draco file"), "{err}");
    // `new .` in a folder of frames names the dataset after the folder.
    let frames = d.join("torus frames");
    std::fs::create_dir_all(&frames).unwrap();
    for f in 1000..1003 {
        let name = format!("torus_vox10_{f}.ply");
        std::fs::copy(data("seq").join(&name), frames.join(&name)).unwrap();
    }
    let (code, err) = vvgen(&frames, &["new", "."]);
    assert_eq!(code, 0, "{err}");
    let text = std::fs::read_to_string(frames.join("torus-frames.toml")).unwrap();
    assert!(text.contains("name = \"torus-frames\""), "{text}");
}

#[test]
fn the_cache_is_beside_the_manifest_wherever_the_command_runs() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path().join("project");
    std::fs::create_dir_all(&d).unwrap();
    longbox(&d);
    assert_eq!(vvgen(&d, &["new", "longbox.gltf"]).0, 0);
    small(&d.join("longbox.toml"));
    let (code, err) = vvgen(&d, &["build", "longbox.toml"]);
    assert_eq!(code, 0, "{err}");
    // From the parent folder and from elsewhere: the same cache, so nothing runs again.
    for (cwd, arg) in
        [(tmp.path().to_path_buf(), "project/longbox.toml".to_string()), (d.join("out"), "../longbox.toml".into())]
    {
        let (code, err) = vvgen(&cwd, &["build", &arg]);
        assert_eq!(code, 0, "{err}");
        assert!(err.contains("nothing to do"), "from {}: {err}", cwd.display());
        assert!(!cwd.join("cache").exists(), "a second cache in {}", cwd.display());
    }
    let out = Command::new(env!("CARGO_BIN_EXE_vvgen"))
        .current_dir(tmp.path())
        .args(["status", "project/longbox.toml"])
        .env_remove("VVGEN_CACHE")
        .output()
        .unwrap();
    let said = String::from_utf8_lossy(&out.stdout);
    assert!(said.contains("project/cache (the default: cache/ beside the manifest)"), "{said}");
}

#[test]
fn an_output_removes_what_it_no_longer_holds_and_nothing_else() {
    let tmp = project("colmap");
    let d = tmp.path();
    let text = std::fs::read_to_string(d.join("m.toml")).unwrap();
    let set = |count: u32, writer: &str, cache: &str| {
        let t = text
            .replace("frames = { count = 31, fps = 30 }", &format!("frames = {{ count = {count}, fps = 30 }}"))
            .replace("writer = \"colmap\"", &format!("writer = \"{writer}\""))
            .replace("seed = 0", &format!("seed = 0\ncache = \"{cache}\""));
        assert_ne!(t, text);
        std::fs::write(d.join("m.toml"), t).unwrap();
    };
    set(8, "colmap", "cache-a");
    assert_eq!(vvgen(d, &["-q", "build", "m.toml"]).0, 0);
    let root = d.join("out/longbox/longbox_colmap");
    assert!(root.join("frame_0007/sparse/0/images.txt").is_file());
    // A file of the user's, inside a folder the build will empty: it stays, and so does its folder.
    std::fs::write(root.join("frame_0006/notes.txt"), "mine").unwrap();
    // Fewer frames, built through another cache (whose record knows nothing of the first build): the output's
    // own list says what it wrote.
    set(3, "colmap", "cache-b");
    let (code, err) = vvgen(d, &["build", "m.toml"]);
    assert_eq!(code, 0, "{err}");
    assert!(err.contains("removed ") && err.contains(" stale file(s)"), "{err}");
    for f in 3..8 {
        let frame = root.join(format!("frame_{f:04}"));
        assert_eq!(frame.exists(), f == 6, "{}", frame.display());
    }
    assert_eq!(std::fs::read_to_string(root.join("frame_0006/notes.txt")).unwrap(), "mine");
    assert_eq!(std::fs::read_dir(root.join("frame_0006")).unwrap().count(), 1, "only the user's file is left");
    assert!(root.join("frame_0002/sparse/0/images.txt").is_file());
    // Another writer: the old output goes whole (but for the user's file).
    set(3, "dnerf", "cache-b");
    assert_eq!(vvgen(d, &["-q", "build", "m.toml"]).0, 0);
    assert!(d.join("out/longbox/longbox_dnerf/transforms_train.json").is_file());
    let left: Vec<_> = walk(&root);
    assert_eq!(left, vec![root.join("frame_0006/notes.txt")], "the colmap output is gone but for the user's file");
}

fn walk(dir: &Path) -> Vec<std::path::PathBuf> {
    let mut v = Vec::new();
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            v.extend(walk(&p));
        } else {
            v.push(p);
        }
    }
    v
}

#[test]
fn frames_past_a_clip_are_warned_of_with_the_count_that_covers_it() {
    let tmp = project("dnerf");
    let d = tmp.path();
    // `Idle` lasts 0.5 s; the manifest keeps Walk's 31 frames at 30 fps.
    let t = std::fs::read_to_string(d.join("m.toml")).unwrap().replace("animation = 0", "animation = \"Idle\"");
    std::fs::write(d.join("m.toml"), t).unwrap();
    let want = "warning: source `longbox`: clip `Idle` lasts 0.50 s, so 14 of its 31 frames at 30 fps hold its last \
                pose; frames = { count = 16, fps = 30 } covers it";
    let (code, err) = vvgen(d, &["--color", "never", "check", "m.toml"]);
    assert_eq!(code, 0, "{err}");
    assert!(err.contains(want), "{err}");
    let (code, err) = vvgen(d, &["--color", "never", "build", "m.toml"]);
    assert_eq!(code, 0, "{err}");
    assert!(err.contains(&want["warning: ".len()..]), "{err}");
}

#[test]
fn the_command_line_s_edges() {
    use std::io::Read;
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    longbox(d);
    assert_eq!(vvgen(d, &["new", "longbox.gltf", "-o", "m.toml"]).0, 0);
    // A reader that stops early (`| head`): the process ends quietly, as cat does, without a panic.
    let mut child = Command::new(env!("CARGO_BIN_EXE_vvgen"))
        .current_dir(d)
        .args(["plan", "--json", "m.toml"])
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let mut first = [0u8; 16];
    child.stdout.as_mut().unwrap().read_exact(&mut first).unwrap();
    drop(child.stdout.take());
    let out = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!err.contains("panicked"), "{err}");
    // `inspect --source` with a name the manifest lacks is an error naming the sources.
    let (code, err) = vvgen(d, &["inspect", "m.toml", "--source", "nope"]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("no source `nope`") && err.contains("the sources are longbox"), "{err}");
    // Ctrl-C mid-build: it says what is kept, and the next build resumes instead of starting over.
    #[cfg(target_os = "linux")]
    interrupt_and_resume(d);
    // gc says what it kept for its age, and how to collect it anyway.
    gc_says_what_it_kept(d);
}

#[cfg(target_os = "linux")]
fn interrupt_and_resume(d: &Path) {
    use std::io::BufRead;
    let mut child = Command::new(env!("CARGO_BIN_EXE_vvgen"))
        .current_dir(d)
        .args(["build", "m.toml"])
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let mut lines = std::io::BufReader::new(child.stderr.take().unwrap()).lines();
    let started = lines.by_ref().map(|l| l.unwrap()).find(|l| l.contains("running")).unwrap();
    // Let a few renders finish.
    let _ = lines.next();
    unsafe {
        libc::kill(child.id() as i32, libc::SIGINT);
    }
    let rest: Vec<String> = lines.map(|l| l.unwrap()).collect();
    let status = child.wait().unwrap();
    if status.code() == Some(130) {
        let said = rest.join("\n");
        assert!(said.contains("actions finished and are kept in the cache"), "{started}\n{said}");
        let (code, err) = vvgen(d, &["build", "m.toml"]);
        assert_eq!(code, 0, "{err}");
        // "N actions cached, running M": what the interrupted build finished is not run again (a lit build's
        // first finished actions may be its environment and light actions, not yet an image).
        let cached = err
            .split(" actions cached")
            .next()
            .and_then(|s| s.rsplit(|c: char| !c.is_ascii_digit()).next())
            .and_then(|n| n.parse::<u32>().ok());
        assert!(cached.is_some_and(|n| n > 0), "the build started over: {err}");
    } else {
        // The build won the race and finished first: nothing to check of the interruption.
        assert!(status.success(), "{status:?}");
    }
}

fn gc_says_what_it_kept(d: &Path) {
    let fewer = std::fs::read_to_string(d.join("m.toml")).unwrap().replace("count = 31,", "count = 5,");
    std::fs::write(d.join("m.toml"), fewer).unwrap();
    let out =
        Command::new(env!("CARGO_BIN_EXE_vvgen")).current_dir(d).args(["gc", "--keep", "m.toml"]).output().unwrap();
    let said = String::from_utf8_lossy(&out.stdout);
    assert!(said.contains("younger than 3600 s") && said.contains("--min-age 0"), "{said}");
    let out = Command::new(env!("CARGO_BIN_EXE_vvgen"))
        .current_dir(d)
        .args(["gc", "--keep", "m.toml", "--min-age", "0"])
        .output()
        .unwrap();
    let said = String::from_utf8_lossy(&out.stdout);
    assert!(!said.contains("removed 0 files") && !said.contains("younger"), "{said}");
}

#[test]
fn a_refused_value_is_one_error_and_a_missing_clip_is_pointed_at() {
    let tmp = project("dnerf");
    let d = tmp.path();
    let text = std::fs::read_to_string(d.join("m.toml")).unwrap();
    // `views = 1e7` is a wrong type, said once: not also "split needs `views`".
    let (code, err) = check_edited(d, "time  = \"monocular\"", "views = 1e7");
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("wrong type: floating point `10000000.0` where a whole number, 0 or more (e.g. 80) is expected")
    );
    assert!(!err.contains("needs `views`") && err.contains("a.toml: 1 error"), "{err}");
    // A clip the file lacks: the line and column where the manifest names it, the clips there are, a fix.
    let t = text.replace("animation = 0", "animation = \"Trot\"");
    std::fs::write(d.join("b.toml"), &t).unwrap();
    let line = t.lines().position(|l| l.starts_with("animation")).unwrap() + 1;
    let (code, err) = vvgen(d, &["--color", "never", "check", "b.toml"]);
    assert_eq!(code, 2, "{err}");
    let want =
        format!("error: ./longbox.gltf: no animation named `Trot` (clips: Walk, Idle)\n  --> b.toml:{line}:13\n");
    assert!(err.starts_with(&want), "{err}");
    assert!(err.contains("= help: name one of the file's clips (by name or index), a list of them, or \"all\""));
}

#[test]
fn plan_estimates_every_kind_it_has_timed() {
    let tmp = project("colmap");
    let d = tmp.path();
    let plan = |d: &Path| {
        let out = Command::new(env!("CARGO_BIN_EXE_vvgen")).current_dir(d).args(["plan", "m.toml"]).output().unwrap();
        String::from_utf8_lossy(&out.stdout).into_owned()
    };
    // Nothing timed yet: no estimate.
    assert!(!plan(d).contains("about"), "{}", plan(d));
    assert_eq!(vvgen(d, &["-q", "build", "m.toml"]).0, 0);
    // A new seed re-samples every frame's COLMAP points and re-renders the training views: both are timed.
    let t = std::fs::read_to_string(d.join("m.toml")).unwrap().replace("seed = 0", "seed = 1");
    std::fs::write(d.join("m.toml"), t).unwrap();
    let said = plan(d);
    assert!(said.contains("colmap-points") && said.contains("about ") && !said.contains("besides"), "{said}");
}

#[test]
fn counts_and_places_are_the_ones_a_user_means() {
    // The dynerf frame-count caveat counts the frames the output's splits select (24 of the clip's 31), in
    // check as in build.
    let tmp = project("dynerf");
    let d = tmp.path();
    let t = std::fs::read_to_string(d.join("m.toml")).unwrap();
    let t = t.replace("views = 1     # camera 00", "views = 1\nframes = { start = 0, end = 23 }     # camera 00");
    let t = t.replace("rig   = \"front\"\nviews = 6", "rig   = \"front\"\nviews = 6\nframes = { start = 0, end = 23 }");
    assert_eq!(t.matches("end = 23").count(), 2, "{t}");
    std::fs::write(d.join("m.toml"), t).unwrap();
    for cmd in ["check", "build"] {
        let (code, err) = vvgen(d, &["--color", "never", cmd, "m.toml"]);
        assert_eq!(code, 0, "{err}");
        assert!(err.contains("output `dynerf` (dynerf) has 24 frames"), "{cmd}: {err}");
        assert!(err.contains("K-Planes crashes on fewer than 25 frames"), "{cmd}: {err}");
        assert!(!err.contains("has 31 frames"), "{cmd}: {err}");
    }
    // A warning with no place in the text names the file under its title, with no empty frame.
    assert_eq!(vvgen(d, &["new", "longbox.gltf", "-o", "h.toml"]).0, 0);
    let h =
        std::fs::read_to_string(d.join("h.toml")).unwrap().replacen("fit    = \"frame\"", "fit = { height = 2.4 }", 1);
    std::fs::write(d.join("h.toml"), h).unwrap();
    let (_, err) = vvgen(d, &["--color", "never", "check", "h.toml"]);
    let first = err.lines().position(|l| l.contains("images crop the subject")).unwrap_or_else(|| panic!("{err}"));
    assert_eq!(err.lines().nth(first + 1), Some("  --> h.toml"), "{err}");
    assert!(!err.contains(" |\n |"), "{err}");
    // `inspect --source S --ply` writes S alone: the ground plane's two triangles stay out.
    let g = std::fs::read_to_string(d.join("m.toml")).unwrap() + "\n[source.ground]\nplane = { size = [3, 3] }\n";
    std::fs::write(d.join("g.toml"), g).unwrap();
    let (code, err) = vvgen(d, &["inspect", "g.toml", "--source", "longbox", "--ply", "box.ply"]);
    assert_eq!(code, 0, "{err}");
    let (code, err) = vvgen(d, &["inspect", "g.toml", "--ply", "all.ply"]);
    assert_eq!(code, 0, "{err}");
    let faces = |f: &str| -> usize {
        let text = std::fs::read(d.join(f)).unwrap();
        let head =
            String::from_utf8_lossy(&text[..text.windows(10).position(|w| w == b"end_header").unwrap()]).into_owned();
        head.lines().find_map(|l| l.strip_prefix("element face ")).unwrap().trim().parse().unwrap()
    };
    assert_eq!(faces("all.ply"), faces("box.ply") + 2, "the ground's two triangles");
}

#[test]
fn a_rig_kind_typo_is_one_error_and_a_points_build_prints_no_image_rate() {
    let tmp = project("dnerf");
    let d = tmp.path();
    let (code, err) = check_edited(d, "kind = \"hemisphere\"", "kind = \"hemisphre\"");
    assert_eq!(code, 2, "{err}");
    assert!(err.starts_with("error: unknown value `hemisphre`, did you mean `hemisphere`?"), "{err}");
    // Nothing follows from it: not the splits that use the rig, not the outputs.
    assert!(err.ends_with("a.toml: 1 error\n") && !err.contains("warning"), "{err}");
    // A point-cloud-only build renders no image and says no image rate.
    let (code, err) = vvgen(d, &["new", "longbox.gltf", "--writer", "ply-sequence", "-o", "p.toml"]);
    assert_eq!(code, 0, "{err}");
    let (code, err) = vvgen(d, &["build", "p.toml"]);
    assert_eq!(code, 0, "{err}");
    assert!(!err.contains("images") && err.contains(" s in all"), "{err}");
}

/// A first try is often `vvgen build model.glb`: every command that takes a manifest names an asset or a folder
/// for what it is, with exit 2 and the command that writes its manifest (quoted as typed when the name has
/// spaces), instead of a TOML syntax error at its first byte.
#[test]
fn an_asset_named_where_a_manifest_belongs_is_told_what_to_run() {
    let tmp = tempfile::tempdir().unwrap();
    let d = tmp.path();
    longbox(d);
    std::fs::copy(d.join("longbox.gltf"), d.join("Samba Dancing.gltf")).unwrap();
    for cmd in ["check", "build", "plan", "inspect"] {
        for (arg, says) in [
            ("longbox.gltf", ["longbox.gltf is a glTF file, not a manifest", "`vvgen new longbox.gltf`"]),
            ("Samba Dancing.gltf", ["is a glTF file", "`vvgen new 'Samba Dancing.gltf'`"]),
            (".", [". is a folder, not a manifest", "`vvgen new .`"]),
        ] {
            let (code, err) = vvgen(d, &[cmd, arg]);
            assert_eq!(code, 2, "{cmd} {arg}: {err}");
            for s in says {
                assert!(err.contains(s), "{cmd} {arg}: `{s}` not in: {err}");
            }
        }
    }
    // A folder with manifests lists them.
    let (code, err) = vvgen(d, &["new", "longbox.gltf", "-o", "longbox.toml"]);
    assert_eq!(code, 0, "{err}");
    let (code, err) = vvgen(d, &["build", "."]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("name a manifest: ./longbox.toml"), "{err}");
}
