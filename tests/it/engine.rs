//! The incremental engine on real assets: edits re-render exactly what they change, builds are crash-safe,
//! shards and thread counts give the same release, and corruption is detected.

use std::path::Path;
use std::process::Command;

use crate::common::{animated_triangle, cesium_glb, cesium_head, data, tree, triangle_manifest};
use vvgen::build::Shard;
use vvgen::build::{build, Options, Report, Silent};
use vvgen::plan::actions::Kind;

/// CesiumMan, 2 frames, 64², with `train_views` training views.
fn cesium(train_views: u32, extra_render: &str, tail: &str) -> String {
    format!(
        r#"{}
[render]
resolution = [64, 64]
samples    = 4
{extra_render}

[rig.h]
kind = "hemisphere"

[split.train]
rig   = "h"
views = {train_views}

[split.test]
rig   = "h"
views = 1

[output.d]
writer = "dnerf"
init_points = 200
{tail}
"#,
        cesium_head(2, 4, 2.4, "", "")
    )
}

fn run(dir: &Path, text: &str) -> Report {
    run_with(dir, text, Options::default())
}

fn run_with(dir: &Path, text: &str, opts: Options) -> Report {
    let p = dir.join("m.toml");
    std::fs::write(&p, text).unwrap();
    let (m, _) = vvgen::manifest::load(&p).unwrap_or_else(|r| panic!("{}", r.render(false)));
    build(&m, &dir.join("cache"), opts, &Silent).unwrap()
}

#[test]
fn edits_rerender_exactly_what_they_change() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    // A private copy of the asset, so touching it below disturbs no other test.
    let asset = cesium_glb();
    std::fs::copy(&asset, d.join("man.glb")).unwrap();
    let cesium = |v: u32, r: &str, t: &str| cesium(v, r, t).replace(&asset.display().to_string(), "man.glb");
    let r = run(d, &cesium(4, "", ""));
    assert_eq!((r.images, r.renders, r.hits), (10, 10, 0));
    // No-op.
    assert_eq!(run(d, &cesium(4, "", "")).renders, 0);
    // 4 → 6 views: exactly 2 views × 2 frames are new.
    assert_eq!(run(d, &cesium(6, "", "")).renders, 4);
    // Renaming an output, adding comments, reordering tables: nothing renders.
    let renamed = cesium(6, "", "").replace("[output.d]", "# a comment\n[output.renamed]");
    assert_eq!(run(d, &renamed).renders, 0);
    let text = cesium(6, "", "");
    let (head, rest) = text.split_at(text.find("[rig.h]").unwrap());
    let (rigs, outputs) = rest.split_at(rest.find("[output.d]").unwrap());
    assert_eq!(run(d, &format!("{head}{outputs}\n{rigs}")).renders, 0, "table order is not content");
    // The renamed output's files are gone; the original directory is rebuilt.
    assert!(d.join("out/m_dnerf/transforms_train.json").exists());
    // Renaming a split with an explicit seed keeps its cameras: nothing renders.
    let seeded = cesium(6, "", "").replace("views = 6", "views = 6\nseed = 5");
    let r = run(d, &seeded);
    assert_eq!(r.renders, 12, "an explicit seed is a new camera set (6 views × 2 frames)");
    let renamed_split = seeded.replace("[split.train]", "[split.training]");
    assert_eq!(run(d, &renamed_split).renders, 0, "a split's name is not in any key once its seed is fixed");
    // Adding the depth pass renders each image again (to produce depth), and the RGBA bytes do not change.
    let before = std::fs::read(d.join("out/m_dnerf/test/r_0000.png")).unwrap();
    let r = run(d, &cesium(6, "passes = [\"rgba\", \"depth\"]", ""));
    assert_eq!(r.renders, 14);
    assert_eq!(std::fs::read(d.join("out/m_dnerf/test/r_0000.png")).unwrap(), before);
    assert!(d.join("out/m_dnerf/depth/test/r_0000.png").exists());
    // Resolution: everything.
    let r = run(d, &cesium(6, "passes = [\"rgba\", \"depth\"]", "").replace("[64, 64]", "[48, 48]"));
    assert_eq!(r.renders, 14);
    // Touching the source without changing its bytes: nothing.
    let f = std::fs::File::options().append(true).open(d.join("man.glb")).unwrap();
    f.set_modified(std::time::SystemTime::now()).unwrap();
    assert_eq!(run(d, &cesium(6, "passes = [\"rgba\", \"depth\"]", "").replace("[64, 64]", "[48, 48]")).renders, 0);
}

#[test]
fn a_changed_sequence_frame_rerenders_only_that_frame() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    for f in 1000..1003 {
        let name = format!("seq/torus_vox10_{f}.ply");
        std::fs::create_dir_all(d.join("seq")).unwrap();
        std::fs::copy(data(&name), d.join(&name)).unwrap();
    }
    let text = r#"[dataset]
name = "t"
out = "out"
cache = "cache"
[source.t]
ply_sequence = "seq/torus_vox10_{frame:04}.ply"
frames = { start = 1000, end = 1002 }
[transform]
fit = { height = 1.0 }
center = "bbox"
over = "first"
[render]
resolution = [48, 48]
splat = { shape = "square", size_px = 2 }
[rig.f]
kind = "fibonacci"
[split.train]
rig = "f"
views = 3
[output.s]
writer = "static-frames"
init_points = 0
"#;
    assert_eq!(run(d, text).renders, 9);
    // Change one point's colour in the last frame: its bounds (and so the transform) stay, only it re-renders.
    let p = d.join("seq/torus_vox10_1002.ply");
    let body = std::fs::read_to_string(&p).unwrap();
    let i = body.find("end_header\n").unwrap() + "end_header\n".len();
    let line_end = i + body[i..].find('\n').unwrap();
    let mut fields: Vec<String> = body[i..line_end].split(' ').map(String::from).collect();
    fields[3] = if fields[3] == "255" { "0".into() } else { "255".into() };
    std::fs::write(&p, format!("{}{}{}", &body[..i], fields.join(" "), &body[line_end..])).unwrap();
    assert_eq!(run(d, text).renders, 3);
    // Touching a frame without changing its bytes: its digest is recomputed, equal, and nothing renders.
    let f = std::fs::File::options().append(true).open(d.join("seq/torus_vox10_1000.ply")).unwrap();
    f.set_modified(std::time::SystemTime::now() + std::time::Duration::from_secs(5)).unwrap();
    assert_eq!(run(d, text).renders, 0);
}

#[test]
fn locks_match_across_jobs_and_shards_and_verify_catches_damage() {
    let lock = |d: &Path| std::fs::read_to_string(d.join("out/m_dnerf/vvgen.lock")).unwrap();
    let release = |d: &Path| {
        let (m, _) = vvgen::manifest::load(&d.join("m.toml")).unwrap();
        vvgen::release::release(&m, &d.join("cache")).unwrap()
    };
    let text = cesium(5, "passes = [\"rgba\", \"mask\"]", "");
    // One thread.
    let a = tempfile::tempdir().unwrap();
    let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
    pool.install(|| run(a.path(), &text));
    release(a.path());
    // Two threads.
    let b = tempfile::tempdir().unwrap();
    let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build().unwrap();
    pool.install(|| run(b.path(), &text));
    release(b.path());
    // Three shards on one cache, then an unsharded build that renders nothing.
    let c = tempfile::tempdir().unwrap();
    let mut rendered = 0;
    for index in 0..3 {
        let r = run_with(c.path(), &text, Options { shard: Some(Shard { index, count: 3 }), ..Default::default() });
        assert!(r.outputs.is_empty(), "a shard writes no dataset");
        rendered += r.renders;
    }
    assert_eq!(rendered, 12, "the shards partition the work");
    assert_eq!(run(c.path(), &text).renders, 0);
    release(c.path());
    assert_eq!(lock(a.path()), lock(b.path()));
    assert_eq!(lock(a.path()), lock(c.path()));
    // A dataset verifies; a flipped byte, a missing file and an extra file are named.
    let root = a.path().join("out/m_dnerf");
    assert!(vvgen::release::verify(&root).unwrap().ok());
    let victim = root.join("train/r_0003.png");
    let mut bytes = std::fs::read(&victim).unwrap();
    bytes[100] ^= 1;
    // Replace the file (not in place: it is a hard link into the cache).
    std::fs::remove_file(&victim).unwrap();
    std::fs::write(&victim, &bytes).unwrap();
    std::fs::remove_file(root.join("test/r_0001.png")).unwrap();
    std::fs::write(root.join("notes.txt"), "x").unwrap();
    let v = vvgen::release::verify(&root).unwrap();
    assert_eq!(v.modified, ["train/r_0003.png"]);
    assert_eq!(v.missing, ["test/r_0001.png"]);
    assert_eq!(v.extra, ["notes.txt"]);
    // The CLI exits non-zero.
    let status = Command::new(env!("CARGO_BIN_EXE_vvgen")).arg("-q").arg("verify").arg(&root).output().unwrap();
    assert!(!status.status.success());
    assert!(String::from_utf8_lossy(&status.stdout).contains("modified train/r_0003.png"));
    // Release refuses while something is stale: a sixth training view at both frames, two passes each, and the
    // training contact sheet and the rig plot that show it.
    std::fs::write(a.path().join("m.toml"), cesium(6, "passes = [\"rgba\", \"mask\"]", "")).unwrap();
    let (m, _) = vvgen::manifest::load(&a.path().join("m.toml")).unwrap();
    let err = vvgen::release::release(&m, &a.path().join("cache")).unwrap_err();
    assert!(matches!(err, vvgen::build::Error::NotBuilt { pending: 6 }), "{err}");
}

#[test]
fn a_corrupt_cache_blob_is_detected_and_rerendered() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let text = cesium(2, "", "");
    run(d, &text);
    let clean = tree(&d.join("out"));
    // Flip a byte of one image in place: the dataset file and its blob are one file (hard link).
    let victim = d.join("out/m_dnerf/train/r_0001.png");
    let mut bytes = std::fs::read(&victim).unwrap();
    bytes[60] ^= 0x40;
    std::fs::OpenOptions::new().write(true).open(&victim).unwrap().write_all_at_start(&bytes);
    let r = run(d, &text);
    assert_eq!(r.renders, 1, "the corrupt blob is a miss");
    assert_eq!(tree(&d.join("out")), clean, "and the dataset is whole again");
}

trait WriteAll {
    fn write_all_at_start(self, b: &[u8]);
}

impl WriteAll for std::fs::File {
    fn write_all_at_start(mut self, b: &[u8]) {
        use std::io::Write;
        self.write_all(b).unwrap();
        self.sync_all().unwrap();
    }
}

/// A build killed with SIGKILL in the middle of its work (on a progress event, so every kill lands while
/// actions are running), then rerun, ends byte-identical to an uninterrupted one, and no dataset file is ever a
/// partial write.
#[test]
fn killed_builds_resume_to_identical_output() {
    use std::io::BufRead;
    let text = cesium(6, "passes = [\"rgba\", \"depth\"]", "[output.p]\nwriter = \"ply-sequence\"\npoints = 20000\n");
    let clean = tempfile::tempdir().unwrap();
    run(clean.path(), &text);
    let expect = tree(&clean.path().join("out"));
    let d = tempfile::tempdir().unwrap();
    std::fs::write(d.path().join("m.toml"), &text).unwrap();
    let mut kills = 0;
    for _ in 0..8 {
        // Plain progress (stderr is not a terminal): "ran k/n" at each tenth of the work.
        let mut child = Command::new(env!("CARGO_BIN_EXE_vvgen"))
            .current_dir(d.path())
            .args(["build", "m.toml"])
            .stderr(std::process::Stdio::piped())
            .spawn()
            .unwrap();
        let stderr = std::io::BufReader::new(child.stderr.take().unwrap());
        let mut killed = false;
        for line in stderr.lines().map_while(Result::ok) {
            let Some((done, total)) = line.strip_prefix("ran ").and_then(|r| r.split_once('/')) else { continue };
            if done.parse::<usize>().unwrap() < total.parse::<usize>().unwrap() {
                let _ = child.kill(); // SIGKILL on Unix
                killed = true;
                break;
            }
        }
        let status = child.wait().unwrap();
        if !killed {
            assert!(status.success(), "the build that was not killed finishes");
            break;
        }
        kills += 1;
        // Whatever is in the dataset under a final name is complete.
        if d.path().join("out").exists() {
            for (name, bytes) in tree(&d.path().join("out")) {
                if name.contains(".vvgen-tmp-") {
                    continue;
                }
                if name.ends_with(".png") {
                    assert!(image::load_from_memory(&bytes).is_ok(), "{name} is a partial write");
                } else if name.ends_with(".ply") {
                    assert!(vvgen::scene::ply::read(&bytes).is_ok(), "{name} is a partial write");
                }
            }
        }
    }
    assert!(kills >= 2, "only {kills} build(s) were killed mid-work");
    let out = Command::new(env!("CARGO_BIN_EXE_vvgen")).current_dir(d.path()).args(["-q", "build", "m.toml"]).output();
    assert!(out.unwrap().status.success());
    let got = tree(&d.path().join("out"));
    assert_eq!(got.keys().collect::<Vec<_>>(), expect.keys().collect::<Vec<_>>());
    assert!(got == expect, "resumed build differs from an uninterrupted one");
    // The killed builds' temporaries are gone from the cache too (their processes are dead).
    let debris: Vec<String> = tree(&d.path().join("cache")).into_keys().filter(|k| k.contains(".vvgen-tmp-")).collect();
    assert!(debris.is_empty(), "{debris:?}");
}

#[test]
fn editing_an_animation_key_rerenders_only_the_frames_it_moves() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(d.join("tri.gltf"), animated_triangle(0.3)).unwrap();
    let text = &triangle_manifest(7, 2, 32, 2, "[output.d]\nwriter = \"dnerf\"\ninit_points = 0\n");
    assert_eq!(run(d, text).renders, 14);
    // Frames at t = 0, 0.5, …, 3 s: moving the key at t = 3 changes only t ∈ (2, 3], i.e. frames 5 and 6.
    std::fs::write(d.join("tri.gltf"), animated_triangle(0.9)).unwrap();
    let (m, _) = vvgen::manifest::load(&d.join("m.toml")).unwrap();
    let st = vvgen::build::status(&m, &d.join("cache"), true).unwrap();
    let stale: Vec<&vvgen::build::ActionStatus> =
        st.actions.iter().filter(|a| a.state == vvgen::build::State::Run && a.kind == Kind::RenderPass).collect();
    let mut labels: Vec<&str> = stale.iter().map(|a| a.label.as_str()).collect();
    labels.sort_unstable();
    assert_eq!(
        labels,
        ["render train/0/5 rgba", "render train/0/6 rgba", "render train/1/5 rgba", "render train/1/6 rgba"]
    );
    // The one field that changed is named, from the same walk that keyed it.
    assert_eq!(stale[0].reasons.len(), 1, "{:?}", stale[0].reasons);
    assert!(stale[0].reasons[0].starts_with("frame content: "), "{:?}", stale[0].reasons);
    assert_eq!(run(d, text).renders, 4);
}

/// The channels of a float EXR, by name.
fn exr_channels(p: &Path) -> std::collections::BTreeMap<String, Vec<f32>> {
    use exr::prelude::*;
    let img = read_all_flat_layers_from_file(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
    assert_eq!(img.layer_data.len(), 1);
    img.layer_data[0]
        .channel_data
        .list
        .iter()
        .map(|c| match &c.sample_data {
            FlatSamples::F32(v) => (c.name.to_string(), v.clone()),
            _ => panic!("{}: channel {} is not f32", p.display(), c.name),
        })
        .collect()
}

#[test]
fn float_exr_files_carry_the_png_passes_at_full_precision() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let passes = "passes = [\"rgba\", \"depth\", \"normal\"]";
    run(d, &cesium(2, passes, ""));
    let read = |rel: &str| std::fs::read(d.join("out/m_dnerf").join(rel)).unwrap();
    let pngs = [read("test/r_0001.png"), read("depth/test/r_0001.png"), read("normal/test/r_0001.png")];
    // Asking for the float files re-renders every image (3 views × 2 frames); the PNGs keep their bytes.
    let exr = format!("{passes}\ndepth = {{ exr = true }}\nnormal = {{ exr = true }}");
    assert_eq!(run(d, &cesium(2, &exr, "")).renders, 6);
    assert_eq!([read("test/r_0001.png"), read("depth/test/r_0001.png"), read("normal/test/r_0001.png")], pngs);
    let root = d.join("out/m_dnerf");
    let mut covered = 0;
    for i in 0..2 {
        let depth_png = image::open(root.join(format!("depth/test/r_000{i}.png"))).unwrap().to_luma16();
        let depth = &exr_channels(&root.join(format!("depth/test/r_000{i}.exr")))["Y"];
        let normal_png = image::open(root.join(format!("normal/test/r_000{i}.png"))).unwrap().to_rgb8();
        let n = exr_channels(&root.join(format!("normal/test/r_000{i}.exr")));
        assert_eq!(n.keys().collect::<Vec<_>>(), ["B", "G", "R"]);
        for (k, (mm, rgb)) in depth_png.pixels().zip(normal_png.pixels()).enumerate() {
            let (mm, z) = (mm[0] as f32, depth[k]);
            if mm == 0.0 {
                assert_eq!(z, 0.0, "background is 0 in both");
                continue;
            }
            covered += 1;
            assert!((z * 1000.0 - mm).abs() <= 0.5 + 1e-3, "pixel {k}: {z} m vs {mm} mm");
            let v = [n["R"][k], n["G"][k], n["B"][k]];
            let len = v.iter().map(|c| c * c).sum::<f32>().sqrt();
            assert!((len - 1.0).abs() < 1e-3, "pixel {k}: |n| = {len}");
            for (c, p) in v.iter().zip(rgb.0) {
                assert!(((c + 1.0) * 0.5 * 255.0 - p as f32).abs() <= 0.5 + 1e-3, "pixel {k}: {v:?} vs {:?}", rgb.0);
            }
        }
    }
    assert!(covered > 300, "the subject covers {covered} pixels");
    let meta = std::fs::read_to_string(root.join(vvgen::export::META)).unwrap();
    assert!(meta.contains("\"depth_exr\": \"depth/test/r_0001.exr\""), "the metadata lists the float files");
    // Reproducible bytes on one thread too (a fresh cache renders everything again).
    let other = tempfile::tempdir().unwrap();
    let pool = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
    pool.install(|| run(other.path(), &cesium(2, &exr, "")));
    for rel in ["depth/test/r_0001.exr", "normal/train/r_0002.exr"] {
        assert_eq!(std::fs::read(other.path().join("out/m_dnerf").join(rel)).unwrap(), read(rel), "{rel}");
    }
}

/// Shards split the `[dataset] after` manifests' work as well: the two shards' prerequisite actions add up to one
/// build's, and the final build only writes the prerequisites' outputs and runs the main manifest.
#[test]
fn shards_split_the_prerequisites_work_once() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let points = "[output.v]\nwriter = \"ply-sequence\"\npoints = 4000\nvox = 8\n";
    std::fs::write(d.join("m.toml"), format!("{}{points}", cesium_head(3, 2, 1.8, "", ""))).unwrap();
    std::fs::write(
        d.join("cloud.toml"),
        "[dataset]\nname = \"c\"\nout = \"out\"\ncache = \"cache\"\nafter = [\"m.toml\"]\n\
         [source.c]\nply_sequence = \"out/m_points/m_{frame:04}.ply\"\nframes = { start = 0, end = 2, fps = 2 }\n\
         [render]\nresolution = [32, 32]\n[rig.o]\nkind = \"orbit\"\n[split.train]\nrig = \"o\"\nviews = 2\n\
         [output.d]\nwriter = \"dnerf\"\ninit_points = 0\n",
    )
    .unwrap();
    let (m, _) = vvgen::manifest::load(&d.join("cloud.toml")).unwrap_or_else(|r| panic!("{}", r.render(false)));
    let mut point_frames = 0;
    for index in 0..2 {
        let r = build(
            &m,
            &d.join("cache"),
            Options { shard: Some(Shard { index, count: 2 }), ..Default::default() },
            &Silent,
        )
        .unwrap();
        let c = r.after_actions[&Kind::PointFrame];
        assert!(c.planned == 3 && c.ran < 3, "shard {index}: {c:?}");
        point_frames += c.ran;
        assert!(r.actions.is_empty() && r.outputs.is_empty(), "the main manifest waits for the final build");
    }
    assert_eq!(point_frames, 3, "each prerequisite frame ran in exactly one shard");
    let r = build(&m, &d.join("cache"), Options::default(), &Silent).unwrap();
    assert_eq!((r.after_actions[&Kind::PointFrame].ran, r.after_actions[&Kind::SampleFrame].ran), (0, 0));
    assert_eq!(r.ran(Kind::RenderPass), 6);
    assert!(build(&m, &d.join("cache"), Options::default(), &Silent).unwrap().nothing_to_do());
}

/// Bit rot: a byte flipped in place with the file's size, inode and mtime unchanged fools the stat cache, but not
/// `release`, which hashes every file it certifies; it removes the damaged file and its blob, so the next build
/// renders that image again and the release goes through.
#[test]
fn release_hashes_what_it_certifies_and_refuses_bit_rot() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let text = cesium(2, "", "");
    run(d, &text);
    // Files an hour old, re-recorded by a no-op build: entries the stat cache trusts (fresh ones are racy and
    // hashed again anyway).
    backdate(&d.join("out"));
    assert_eq!(run(d, &text).renders, 0);
    let (m, _) = vvgen::manifest::load(&d.join("m.toml")).unwrap();
    vvgen::release::release(&m, &d.join("cache")).unwrap();
    let victim = d.join("out/m_dnerf/train/r_0001.png");
    // Flips one byte in place, keeping size, inode and mtime.
    let rot = || {
        let mtime = std::fs::metadata(&victim).unwrap().modified().unwrap();
        let byte = std::fs::read(&victim).unwrap()[200] ^ 0x10;
        let f = std::fs::OpenOptions::new().write(true).open(&victim).unwrap();
        std::os::unix::fs::FileExt::write_all_at(&f, &[byte], 200).unwrap();
        f.set_modified(mtime).unwrap();
    };
    rot();
    // The stat cache is fooled; release, which hashes what it certifies, is not.
    assert!(vvgen::build::status(&m, &d.join("cache"), false).unwrap().up_to_date());
    let err = vvgen::release::release(&m, &d.join("cache")).unwrap_err();
    assert!(matches!(&err, vvgen::build::Error::Damaged { path } if path == &victim), "{err:?}");
    assert_eq!(run(d, &text).renders, 1, "the damaged image is rendered again");
    let roots = vvgen::release::release(&m, &d.join("cache")).unwrap();
    assert!(vvgen::release::verify(&roots[0]).unwrap().ok());
    // `--verify` hashes everything again: the damaged blob is found (and dropped) and its image rebuilt.
    backdate(&d.join("out"));
    assert_eq!(run(d, &text).renders, 0);
    rot();
    let verified = vvgen::build::status_with(&m, &d.join("cache"), false, true).unwrap();
    assert_eq!(verified.to_run(Kind::RenderPass), 1, "{:?}", verified.kinds);
    let opts = Options { verify: true, ..Default::default() };
    assert_eq!(run_with(d, &text, opts).renders, 1);
    assert!(vvgen::release::verify(&vvgen::release::release(&m, &d.join("cache")).unwrap()[0]).unwrap().ok());
}

/// Sets every file under `dir` to have been written an hour ago.
fn backdate(dir: &Path) {
    let hour_ago = std::time::SystemTime::now() - std::time::Duration::from_secs(3600);
    for (rel, _) in tree(dir) {
        std::fs::File::options().append(true).open(dir.join(rel)).unwrap().set_modified(hour_ago).unwrap();
    }
}

/// Two builds of one dataset at once: the second waits for the first's lock and then finds its work cached,
/// instead of rendering everything a second time.
#[test]
fn concurrent_builds_of_one_dataset_do_the_work_once() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(d.join("m.toml"), cesium(3, "", "")).unwrap();
    let (m, _) = vvgen::manifest::load(&d.join("m.toml")).unwrap();
    let reports: Vec<Report> = std::thread::scope(|s| {
        let a = s.spawn(|| build(&m, &d.join("cache"), Options::default(), &Silent).unwrap());
        let b = s.spawn(|| build(&m, &d.join("cache"), Options::default(), &Silent).unwrap());
        vec![a.join().unwrap(), b.join().unwrap()]
    });
    assert_eq!(reports[0].images, 8);
    assert_eq!(reports[0].renders + reports[1].renders, 8, "the images were rendered once between the two");
}

/// Only the passes asked for are written: a mask is not followed by an `instance/` tree, and asking for
/// `instance` gives 16-bit object ids that are 0 wherever the mask is.
#[test]
fn only_the_passes_asked_for_are_written() {
    let tmp = tempfile::tempdir().unwrap();
    run(tmp.path(), &cesium(1, "passes = [\"rgba\", \"mask\"]", ""));
    let root = tmp.path().join("out/m_dnerf");
    assert!(root.join("mask/train/r_0000.png").is_file());
    assert!(!root.join("instance").exists(), "instance ids written though not asked for");
    run(tmp.path(), &cesium(1, "passes = [\"rgba\", \"mask\", \"instance\"]", ""));
    let mask = image::open(root.join("mask/train/r_0000.png")).unwrap().to_luma8();
    let ids = match image::open(root.join("instance/train/r_0000.png")).unwrap() {
        image::DynamicImage::ImageLuma16(i) => i,
        other => panic!("instance ids are 16-bit grey, not {:?}", other.color()),
    };
    let mut covered = 0;
    for (m, id) in mask.pixels().zip(ids.pixels()) {
        if id[0] != 0 {
            covered += 1;
            assert!(m[0] > 0, "an object id where the mask is empty");
        }
    }
    assert!(covered > 20, "{covered} pixels carry an id");
}

/// A point kind that fails while the images render beside it (a sample blob damaged behind the stat cache's
/// back, so that only reading it finds out) stops the build with its own cause, never with the refusal the
/// renders get as the build stops; a verified rebuild then treats the blob as missing and completes.
#[test]
fn a_kind_failing_beside_running_renders_reports_its_own_cause() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let points = |voxel: f64| format!("[output.p]\nwriter = \"ply-sequence\"\npoints = 2000\nvoxel = {voxel}\n");
    let first = cesium(2, "", &points(0.02));
    run(d, &first);
    // Files an hour old, re-recorded by a no-op build: entries the stat cache trusts (fresh ones are racy and
    // hashed again anyway).
    backdate(&d.join("cache/objects"));
    assert!(run(d, &first).nothing_to_do());
    let objects = d.join("cache/objects");
    let (rel, _) =
        tree(&objects).into_iter().find(|(_, b)| b.starts_with(b"vvgenPT")).expect("a sample blob in the cache");
    let blob = objects.join(rel);
    // One byte flipped in place, keeping size, inode and mtime: only reading the blob finds out.
    let mtime = std::fs::metadata(&blob).unwrap().modified().unwrap();
    let last = std::fs::metadata(&blob).unwrap().len() - 1;
    let byte = std::fs::read(&blob).unwrap()[last as usize] ^ 1;
    let f = std::fs::OpenOptions::new().write(true).open(&blob).unwrap();
    std::os::unix::fs::FileExt::write_all_at(&f, &[byte], last).unwrap();
    f.set_modified(mtime).unwrap();
    // New voxels reduce the cached samples again while a new resolution renders every image beside them.
    let text = cesium(2, "", &points(0.03)).replace("resolution = [64, 64]", "resolution = [48, 48]");
    std::fs::write(d.join("m.toml"), &text).unwrap();
    let (m, _) = vvgen::manifest::load(&d.join("m.toml")).unwrap_or_else(|r| panic!("{}", r.render(false)));
    let err = build(&m, &d.join("cache"), Options::default(), &Silent).unwrap_err();
    let chain = crate::common::error_chain(&err);
    assert!(chain.contains("is corrupt") && !chain.contains("stopped"), "{chain}");
    let r = run_with(d, &text, Options { verify: true, ..Default::default() });
    assert!(r.ran(Kind::SampleFrame) >= 1 && r.ran(Kind::PointFrame) == 2, "{:?}", r.actions);
}
