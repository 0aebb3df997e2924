//! The action graph (issue 13): every cacheable action is planned, keyed, explained and counted in one place.
//! A no-op build does nothing of any kind; each setting, changed alone, invalidates exactly the actions that
//! read it (and the incremental result equals a fresh build byte for byte); `status`, `plan`, `release` and
//! `gc` read the same graph.

use std::collections::BTreeMap;
use std::path::Path;
use std::process::Command;

use crate::common::{cesium_head, load, tree};
use vvgen::build::{self, Error, Silent, State, Status};
use vvgen::plan::actions::Kind;

/// CesiumMan, 2 frames, 32², every pass; `outputs` appended. 6 images: 2 training views and 1 test view.
fn manifest(render: &str, outputs: &str) -> String {
    format!(
        "{}[render]\nresolution = [32, 32]\nsamples = 4\npasses = [\"rgba\", \"depth\", \"normal\", \"mask\"]\n{render}\n\
         [rig.h]\nkind = \"hemisphere\"\n[split.train]\nrig = \"h\"\nviews = 2\n[split.test]\nrig = \"h\"\nviews = 1\n\
         {outputs}",
        cesium_head(2, 4, 2.4, "seed = 5", "")
    )
}

/// One output of every writer: every action kind is planned.
const EVERY_WRITER: &str = r#"
[output.d]
writer = "dnerf"
init_points = 100
[output.ns]
writer = "nerfstudio"
init_points = 100
[output.ngp]
writer = "instant-ngp"
[output.sf]
writer = "static-frames"
init_points = 50
[output.col]
writer = "colmap"
init_points = 50
[output.dy]
writer = "dynerf"
init_points = 50
[output.p]
writer = "ply-sequence"
points = 2000
voxel = 0.05
[output.v]
writer = "ply-sequence"
points = 2000
vox = 8
dir = "vox"
"#;

/// Lit shading under an environment map: the render settings that plan every kind of action (the map's
/// prefiltering among them).
fn lit() -> String {
    format!("shading = \"pbr\"\n[environment]\nmap = \"{}\"\n", crate::common::data("hdri/sunset.exr").display())
}

/// Writes `text` as `dir/m.toml` and builds it.
fn run(dir: &Path, text: &str) -> build::Report {
    std::fs::write(dir.join("m.toml"), text).unwrap();
    build::build(&load(&dir.join("m.toml")), &dir.join("cache"), Default::default(), &Silent).unwrap()
}

/// What a build of `text` in `dir` would do, explained.
fn status(dir: &Path, text: &str) -> Status {
    std::fs::write(dir.join("m.toml"), text).unwrap();
    build::status(&load(&dir.join("m.toml")), &dir.join("cache"), true).unwrap()
}

/// Actions to run, by kind.
fn to_run(st: &Status) -> BTreeMap<Kind, usize> {
    st.kinds.iter().filter(|(_, k)| k.run > 0).map(|(kind, k)| (*kind, k.run)).collect()
}

/// The reasons of every action of `kind` that would run.
fn reasons(st: &Status, kind: Kind) -> Vec<Vec<String>> {
    st.actions.iter().filter(|a| a.kind == kind && a.state == State::Run).map(|a| a.reasons.clone()).collect()
}

#[test]
fn every_kind_runs_once_and_a_second_build_has_nothing_to_do() {
    let dir = tempfile::tempdir().unwrap();
    let text = manifest(&lit(), EVERY_WRITER);
    let first = run(dir.path(), &text);
    for kind in Kind::ALL {
        let c = first.actions.get(&kind).copied().unwrap_or_default();
        assert!(c.planned > 0 && c.ran == c.planned, "{kind:?}: {c:?}");
    }
    // Shared work is one action: dnerf and nerfstudio ask for the same init cloud.
    // The previews of the six image outputs share one sample of the subject (the same frame and count).
    assert_eq!(first.actions[&Kind::InitCloud].planned, 1 + 2 + 1 + 1, "d/ns, two static frames, dynerf, preview");
    assert_eq!(first.actions[&Kind::PreviewSheet].planned, 2, "one sheet per split, shared by the outputs");
    assert_eq!(first.actions[&Kind::Composite].planned, 6, "colmap and dynerf share the composites");
    let again = run(dir.path(), &text);
    assert!(again.nothing_to_do(), "{:?}", again.actions);
    for kind in Kind::ALL {
        assert_eq!(again.actions[&kind].cached, again.actions[&kind].planned, "{kind:?}");
    }
    let st = status(dir.path(), &text);
    assert!(st.up_to_date() && st.pending() == 0, "{:?}", to_run(&st));
}

/// Reproduction 1: a changed point count was invisible to `status`, `plan` and `release`.
#[test]
fn a_changed_point_count_is_stale_in_status_plan_and_release() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let points = "[output.p]\nwriter = \"ply-sequence\"\npoints = 2000\nvoxel = 0.05\n";
    run(d, &manifest("", points));
    let changed = manifest("", &points.replace("2000", "3000"));
    let st = status(d, &changed);
    let expect = [(Kind::SampleFrame, 2), (Kind::PointFrame, 2), (Kind::PreviewStrip, 1), (Kind::WriteOutput, 1)];
    assert_eq!(to_run(&st), BTreeMap::from(expect));
    assert!(!st.up_to_date());
    for r in reasons(&st, Kind::SampleFrame) {
        assert_eq!(r, ["points: 2000 → 3000"]);
    }
    // The reduction reads the new samples: its reason is its input's key.
    for r in reasons(&st, Kind::PointFrame) {
        assert!(r.len() == 1 && r[0].starts_with("samples: "), "{r:?}");
    }
    let err = vvgen::release::release(&load(&d.join("m.toml")), &d.join("cache")).unwrap_err();
    assert!(matches!(err, Error::NotBuilt { pending: 5 }), "{err}");
    assert_eq!(err.exit_code(), 1);
    let r = run(d, &changed);
    assert_eq!((r.ran(Kind::SampleFrame), r.ran(Kind::PointFrame), r.ran(Kind::RenderPass)), (2, 2, 0));
    assert_eq!(vvgen::release::release(&load(&d.join("m.toml")), &d.join("cache")).unwrap().len(), 1);
}

/// Sets every file under `dir` to have been written `hours` ago.
fn backdate(dir: &Path, hours: u64) {
    let then = std::time::SystemTime::now() - std::time::Duration::from_secs(hours * 3600);
    for (rel, _) in tree(dir) {
        let f = std::fs::File::options().append(true).open(dir.join(rel)).unwrap();
        f.set_modified(then).unwrap();
    }
}

/// Reproduction 2: `gc --keep` deleted every record `export` wrote, and the next build re-sampled everything.
#[test]
fn gc_after_the_grace_period_keeps_everything_the_graph_reaches() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let outputs = "[output.d]\nwriter = \"colmap\"\ninit_points = 50\n\
                   [output.p]\nwriter = \"ply-sequence\"\npoints = 2000\nvox = 8\n";
    let text = manifest("", outputs);
    run(d, &text);
    backdate(&d.join("cache"), 2);
    let keep = [load(&d.join("m.toml"))];
    let c = build::collect_garbage(&keep, &d.join("cache"), None, vvgen::cache::gc::GRACE).unwrap();
    assert_eq!(c.files, 0, "everything is reachable");
    assert!(run(d, &text).nothing_to_do());
    // After an edit, what only the old manifest reached goes, and nothing the new one reaches.
    let edited = text.replace("points = 2000", "points = 2500");
    run(d, &edited);
    backdate(&d.join("cache"), 2);
    let c =
        build::collect_garbage(&[load(&d.join("m.toml"))], &d.join("cache"), None, vvgen::cache::gc::GRACE).unwrap();
    // 2 sample and 2 point-frame records with their 4 blobs, the preview strip's record with its 2 blobs (the
    // picture and the viewer's frames), both outputs' old metadata (which record the manifest's digest) and the
    // point output's old viewer page (which embeds its frames).
    assert_eq!(c.files, 2 * 2 * 2 + 3 + 2 + 1);
    assert!(run(d, &edited).nothing_to_do());
    // The cached intermediate samples survived too: a reduction change re-runs only the reduction.
    let r = run(d, &edited.replace("vox = 8", "vox = 9"));
    assert_eq!((r.ran(Kind::SampleFrame), r.ran(Kind::PointFrame)), (0, 2));
}

/// Reproduction 3: asking for EXR was explained as "cached result missing or corrupt".
#[test]
fn asking_for_exr_is_explained_by_the_field_that_changed() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let outputs = "[output.d]\nwriter = \"dnerf\"\ninit_points = 0\n";
    run(d, &manifest("", outputs));
    let st = status(d, &manifest("depth = { exr = true }", outputs));
    // The contact sheets read the depth renders (by their keys).
    let expect = [(Kind::RenderPass, 6), (Kind::PreviewSheet, 2), (Kind::WriteOutput, 1)];
    assert_eq!(to_run(&st), BTreeMap::from(expect));
    let stale: Vec<_> = st.actions.iter().filter(|a| a.kind == Kind::RenderPass && a.state == State::Run).collect();
    for a in &stale {
        assert!(a.label.ends_with(" depth"), "{}", a.label);
        assert_eq!(a.reasons, ["exr: false → true"]);
    }
    let r = run(d, &manifest("depth = { exr = true }", outputs));
    assert_eq!(r.ran(Kind::RenderPass), 6);
    assert!(d.join("out/m_dnerf/depth/train/r_0000.exr").exists());
}

/// Each setting, changed alone from the base, runs exactly the actions that read it, and the incremental
/// result is byte for byte what a fresh build of the edited manifest writes (so no key leaves out a field that
/// moves bytes).
#[test]
fn each_setting_invalidates_exactly_the_actions_that_read_it() {
    let outputs =
        "[output.d]\nwriter = \"dnerf\"\ninit_points = 100\n[output.c]\nwriter = \"colmap\"\ninit_points = 40\n\
                   [output.p]\nwriter = \"ply-sequence\"\npoints = 1500\nvoxel = 0.05\n";
    let base = manifest("", outputs);
    use Kind::*;
    // 6 images × 4 passes; colmap composites each image; every output's metadata records the manifest.
    /// What changed, the edited manifest, and what must run besides the three outputs.
    type Case = (&'static str, String, Vec<(Kind, usize)>);
    let cases: [Case; 9] = [
        // The contact sheets (one per split) read the RGBA, depth and mask renders; the strip the point frames.
        (
            "background",
            manifest("background = \"black\"", outputs),
            vec![(RenderPass, 6), (Composite, 6), (PreviewSheet, 2)],
        ),
        ("depth kind", manifest("depth = { kind = \"ray\" }", outputs), vec![(RenderPass, 6), (PreviewSheet, 2)]),
        ("normal space", manifest("normal = { space = \"camera\" }", outputs), vec![(RenderPass, 6)]),
        (
            "lights",
            manifest("shading = \"lambert\"", outputs),
            vec![(RenderPass, 6), (Composite, 6), (PreviewSheet, 2)],
        ),
        (
            "samples",
            base.replace("samples = 4", "samples = 1"),
            vec![(RenderPass, 24), (Composite, 6), (PreviewSheet, 2)],
        ),
        (
            "png",
            manifest("png_compression = \"best\"", outputs),
            vec![(RenderPass, 24), (Composite, 6), (PreviewSheet, 2)],
        ),
        ("voxel", base.replace("voxel = 0.05", "voxel = 0.08"), vec![(PointFrame, 2), (PreviewStrip, 1)]),
        // Lit shading: the map is prefiltered, each of the two frames' light gathered, and the RGBA passes
        // re-render (composited by colmap, shown by the sheets); depth, normals, masks, bounds, samples and clouds
        // do not depend on shading.
        (
            "shading",
            manifest(&lit(), outputs),
            vec![(Environment, 1), (Light, 2), (RenderPass, 6), (Composite, 6), (PreviewSheet, 2)],
        ),
        ("init points", base.replace("init_points = 100", "init_points = 150"), vec![(InitCloud, 1)]),
    ];
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    run(d, &base);
    for (what, text, expect) in cases {
        let mut expect: BTreeMap<Kind, usize> = expect.into_iter().collect();
        expect.insert(WriteOutput, 3);
        assert_eq!(to_run(&status(d, &text)), expect, "{what}");
        run(d, &text);
        let fresh = tempfile::tempdir().unwrap();
        run(fresh.path(), &text);
        let (a, b) = (tree(&d.join("out")), tree(&fresh.path().join("out")));
        assert_eq!(a.keys().collect::<Vec<_>>(), b.keys().collect::<Vec<_>>(), "{what}");
        for (k, v) in &a {
            assert!(v == &b[k], "{what}: {k} differs from a fresh build");
        }
        // Back to the base: everything cached.
        assert_eq!(run(d, &base).actions.iter().filter(|(k, _)| k.cached()).map(|(_, c)| c.ran).sum::<usize>(), 0);
    }
}

#[test]
fn plan_json_lists_every_action_with_its_kind_key_state_and_reason() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    run(d, &manifest(&lit(), EVERY_WRITER));
    std::fs::write(d.join("m.toml"), manifest(&lit(), &EVERY_WRITER.replace("vox = 8", "vox = 9"))).unwrap();
    let out =
        Command::new(env!("CARGO_BIN_EXE_vvgen")).current_dir(d).args(["plan", "--json", "m.toml"]).output().unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let mut kinds: Vec<&str> = v["kinds"].as_object().unwrap().keys().map(String::as_str).collect();
    kinds.sort_unstable();
    let mut all: Vec<&str> = Kind::ALL.iter().map(|k| k.name()).collect();
    all.sort_unstable();
    assert_eq!(kinds, all);
    for a in v["actions"].as_array().unwrap() {
        let key = a["key"].as_str().unwrap();
        assert!(key.len() == 64 && key.bytes().all(|c| c.is_ascii_hexdigit()), "{a}");
        let reasons = a["reasons"].as_array().unwrap();
        match a["state"].as_str().unwrap() {
            "run" => assert!(!reasons.is_empty(), "{a}"),
            "cached" => assert!(reasons.is_empty(), "{a}"),
            s => panic!("{s}: {a}"),
        }
    }
    let stale: Vec<&str> = v["actions"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|a| a["state"] == "run" && a["kind"] == "point-frame")
        .map(|a| a["label"].as_str().unwrap())
        .collect();
    assert_eq!(stale, ["points v/0", "points v/1"]);
}

/// A corrupt `.glb` is bad input (exit 2), named by its variant; an unwritable cache is a failure (exit 1).
#[test]
fn errors_are_typed_and_map_to_exit_codes() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let glb = std::fs::read(crate::common::cesium_glb()).unwrap();
    std::fs::write(d.join("broken.glb"), &glb[..glb.len() / 3]).unwrap();
    let text = manifest("", "[output.d]\nwriter = \"dnerf\"\n")
        .replace(&crate::common::cesium_glb().display().to_string(), "broken.glb");
    let err = build::Build::from_manifest_str(&text, d).unwrap().cache(d.join("cache")).run(&Silent).unwrap_err();
    match &err {
        Error::Scene { source, .. } => match &**source {
            vvgen::scene::Error::Gltf { path, .. } => assert!(path.ends_with("broken.glb")),
            e => panic!("{e:?}"),
        },
        e => panic!("{e:?}"),
    }
    assert_eq!(err.exit_code(), 2);
    std::fs::write(d.join("m.toml"), &text).unwrap();
    let cli = |args: &[&str]| Command::new(env!("CARGO_BIN_EXE_vvgen")).current_dir(d).args(args).output().unwrap();
    let out = cli(&["-q", "build", "m.toml"]);
    assert_eq!(out.status.code(), Some(2), "{}", String::from_utf8_lossy(&out.stderr));
    assert!(String::from_utf8_lossy(&out.stderr).contains("broken.glb"));
    // A cache that cannot be created: an I/O failure, not the input's fault.
    std::fs::write(d.join("m.toml"), manifest("", "[output.d]\nwriter = \"dnerf\"\n")).unwrap();
    std::fs::write(d.join("cache"), "a file where the cache directory should be").unwrap();
    let out = cli(&["-q", "build", "m.toml"]);
    assert_eq!(out.status.code(), Some(1), "{}", String::from_utf8_lossy(&out.stderr));
    let err = build::build(&load(&d.join("m.toml")), &d.join("cache"), Default::default(), &Silent).unwrap_err();
    assert!(matches!(err, Error::Cache { .. }), "{err:?}");
}

/// A degenerate camera (an explicit pose at its own target) is refused by the plan before anything renders or
/// any writer could emit NaN.
#[test]
fn a_non_finite_camera_is_refused_before_anything_is_written() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let text = manifest("", "[output.d]\nwriter = \"dnerf\"\n").replace(
        "[rig.h]\nkind = \"hemisphere\"",
        "[rig.h]\nkind = \"explicit\"\nposes = [{ position = [0.0, 0.0, 0.0] }]",
    );
    std::fs::write(d.join("m.toml"), &text).unwrap();
    let err = build::build(&load(&d.join("m.toml")), &d.join("cache"), Default::default(), &Silent).unwrap_err();
    match &err {
        Error::Plan { source, .. } => {
            assert!(matches!(**source, vvgen::plan::Error::NonFinite { view: 0, .. }), "{source}")
        }
        e => panic!("{e:?}"),
    }
    assert_eq!(err.exit_code(), 2);
    assert!(!d.join("out").exists());
}

/// `dir = "."` puts the dataset at `out` itself (it used to pass `check` and then fail to create `out/.`).
#[test]
fn an_output_may_be_the_out_directory_itself() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    run(d, &manifest("", "[output.n]\nwriter = \"nerfstudio\"\ndir = \".\"\ninit_points = 0\n"));
    let t: serde_json::Value = serde_json::from_slice(&std::fs::read(d.join("out/transforms.json")).unwrap()).unwrap();
    assert_eq!(t["frames"].as_array().unwrap().len(), 6);
    assert!(
        run(d, &manifest("", "[output.n]\nwriter = \"nerfstudio\"\ndir = \".\"\ninit_points = 0\n")).nothing_to_do()
    );
}

/// `plan` says how many images a build would render and bounds their size; past a limit, `build` refuses to
/// start without `--yes` (the CLI's limit is 100 000 images per process).
#[test]
fn a_huge_build_asks_for_yes_first() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let text = manifest("", "[output.d]\nwriter = \"dnerf\"\ninit_points = 0\n");
    let st = status(d, &text);
    assert_eq!((st.images_to_render, st.bytes_upper_bound), (6, 6 * 32 * 32 * (4 + 2 + 3 + 1)));
    let m = load(&d.join("m.toml"));
    let limited = |max| build::Options { max_images: Some(max), ..Default::default() };
    let err = build::build(&m, &d.join("cache"), limited(5), &Silent).unwrap_err();
    assert!(matches!(err, Error::TooMuchWork { images: 6, max: 5, .. }), "{err:?}");
    assert_eq!(err.exit_code(), 2);
    assert_eq!(st.seconds_estimate, None, "no estimate before anything rendered here");
    assert_eq!(build::build(&m, &d.join("cache"), limited(6), &Silent).unwrap().renders, 6);
    assert_eq!(status(d, &text).images_to_render, 0);
    // A third training view: two new images, timed at the rate the build just measured.
    let more = status(d, &text.replacen("views = 2", "views = 3", 1));
    assert_eq!(more.images_to_render, 2);
    assert!(more.seconds_estimate.is_some_and(|s| s > 0.0 && s.is_finite()), "{:?}", more.seconds_estimate);
    // The CLI's own limit, on a mistyped view count: refused before anything renders.
    std::fs::write(d.join("tri.gltf"), crate::common::animated_triangle(0.3)).unwrap();
    let huge = crate::common::triangle_manifest(1, 1, 8, 100_001, "[output.d]\nwriter = \"dnerf\"\ninit_points = 0\n")
        .replace("kind = \"orbit\"", "kind = \"fibonacci\"");
    std::fs::write(d.join("huge.toml"), huge).unwrap();
    let out =
        Command::new(env!("CARGO_BIN_EXE_vvgen")).current_dir(d).args(["-q", "build", "huge.toml"]).output().unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(
        String::from_utf8_lossy(&out.stderr).contains("would render 100001 images"),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(!d.join("out/tri_dnerf").exists());
}

/// Geometry that overflows to infinity once posed (a node scaled by 1e30 twice) yields an error naming what is
/// not finite, never a dataset with `null` in its JSON or NaN in its PLYs.
#[test]
fn overflowing_geometry_never_reaches_a_dataset() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let mut doc: serde_json::Value = serde_json::from_str(&crate::common::animated_triangle(0.3)).unwrap();
    doc["nodes"] =
        serde_json::json!([{"children": [1], "scale": [1e30, 1e30, 1e30]}, {"mesh": 0, "scale": [1e30, 1e30, 1e30]}]);
    doc["scenes"][0]["nodes"] = serde_json::json!([0]);
    doc["animations"][0]["channels"][0]["target"]["node"] = 1.into();
    std::fs::write(d.join("tri.gltf"), doc.to_string()).unwrap();
    let outputs = [
        "[output.n]\nwriter = \"instant-ngp\"\n",
        "[output.p]\nwriter = \"ply-sequence\"\npoints = 100\n",
        "[output.d]\nwriter = \"dnerf\"\ninit_points = 0\n",
    ];
    for output in outputs {
        std::fs::write(d.join("m.toml"), crate::common::triangle_manifest(2, 1, 8, 1, output)).unwrap();
        let err = build::build(&load(&d.join("m.toml")), &d.join("cache"), Default::default(), &Silent).unwrap_err();
        let chain = crate::common::error_chain(&err);
        assert!(chain.contains("not finite"), "{output}: {chain}");
        assert_eq!(err.exit_code(), 2, "{output}");
    }
    assert!(!d.join("out/tri_ngp/transforms_train.json").exists());
}

/// `correspondence` is judged on the source a point output samples: a glTF source tracks its surface even
/// when another source of the manifest is a PLY sequence (it used to be refused).
#[test]
fn correspondence_looks_only_at_the_sampled_source() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let seq = crate::common::data("seq/torus_vox10_{frame:04}.ply");
    let text = format!(
        "{}[source.torus]\nply_sequence = \"{}\"\nframes = {{ start = 1000, end = 1001 }}\n\
         [output.p]\nwriter = \"ply-sequence\"\nsource = \"man\"\ncorrespondence = true\npoints = 300\n",
        cesium_head(2, 4, 2.4, "", ""),
        seq.display()
    );
    let r = run(d, &text);
    assert_eq!(r.ran(Kind::PointFrame), 2);
    let ply = std::fs::read(d.join("out/m_points/m_0001.ply")).unwrap();
    assert!(String::from_utf8_lossy(&ply[..400]).contains("point_id"), "tracked points carry their id");
}
