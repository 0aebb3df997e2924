//! Previews (issue 18): contact sheets, the rig plot, the point-cloud strip and the HTML viewer are planned,
//! cached and locked like the rest of a dataset, never where a consumer scans, and the viewer works in a real
//! browser (Debian's chromium, headless) from `file://`.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use std::process::Command;

use crate::common::{cesium_head, load, tree};
use vvgen::build::{self, Silent};
use vvgen::plan::actions::Kind;

/// CesiumMan, 3 frames at 48², RGBA + depth + mask; 3 training views (every frame), 2 test views; `rig`
/// radius; a D-NeRF output and a point-cloud sequence. `dataset` adds to `[dataset]`.
fn manifest(dataset: &str, radius: f64) -> String {
    format!(
        "{}[render]\nresolution = [48, 48]\nsamples = 1\npasses = [\"rgba\", \"depth\", \"mask\"]\n\
         [rig.h]\nkind = \"hemisphere\"\nradius = {radius}\n[split.train]\nrig = \"h\"\nviews = 3\n\
         [split.test]\nrig = \"h\"\nviews = 2\n\
         [output.d]\nwriter = \"dnerf\"\ninit_points = 200\n[output.p]\nwriter = \"ply-sequence\"\npoints = 3000\n",
        cesium_head(3, 24, 2.4, &format!("seed = 3\n{dataset}"), "")
    )
}

fn run(dir: &Path, text: &str) -> build::Report {
    std::fs::write(dir.join("m.toml"), text).unwrap();
    build::build(&load(&dir.join("m.toml")), &dir.join("cache"), Default::default(), &Silent).unwrap()
}

fn png(path: &Path) -> image::RgbImage {
    image::open(path).unwrap_or_else(|e| panic!("{}: {e}", path.display())).into_rgb8()
}

#[test]
fn previews_are_planned_cached_locked_and_out_of_the_consumers_way() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let first = run(d, &manifest("", 4.0));
    for kind in [Kind::PreviewSheet, Kind::PreviewRig, Kind::PreviewStrip] {
        assert!(first.ran(kind) > 0, "{kind:?} ran");
    }
    let root = d.join("out/m_dnerf");
    let files: BTreeSet<String> = tree(&root.join("preview")).into_keys().collect();
    let expect = ["index.html", "rig.png", "sheet-test.png", "sheet-train.png", "three.min.js"];
    assert_eq!(files, expect.iter().map(|s| s.to_string()).collect());
    let points: BTreeSet<String> = tree(&d.join("out/m_points/preview")).into_keys().collect();
    assert_eq!(points, ["index.html", "points.png", "three.min.js"].iter().map(|s| s.to_string()).collect());
    // Nothing a consumer reads moved: the root holds what it held, and no JSON is in the preview (instant-ngp
    // loads every root `*.json`; nerfstudio, D-NeRF and K-Planes read named files).
    assert!(tree(&root).keys().all(|f| !f.starts_with("preview/") || !f.ends_with(".json")));

    // The training sheet: 3 views down, 3 frames across (multi-view video), each cell with its depth and mask.
    let sheet = png(&root.join("preview/sheet-train.png"));
    // (three thumbnails across are too narrow for the title and the depth note side by side: two header lines)
    let (pad, thumb, head) = (8, 160, 50);
    assert_eq!(sheet.width(), pad + 3 * (thumb + pad));
    assert_eq!(sheet.height(), head + 3 * (thumb + thumb / 2 + 16 + pad) + pad);
    // Each thumbnail shows the subject: it differs from the bare checkerboard somewhere.
    for row in 0..3u32 {
        for col in 0..3u32 {
            let (x0, y0) = (pad + col * (thumb + pad), head + row * (thumb + thumb / 2 + 16 + pad));
            let inked = (0..thumb * thumb)
                .map(|i| sheet.get_pixel(x0 + i % thumb, y0 + i / thumb).0)
                .filter(|p| *p != [200, 200, 200] && *p != [150, 150, 150])
                .count();
            assert!(inked > 200, "cell {row},{col}: {inked} pixels of subject");
        }
    }

    // The rig plot draws every split's cameras in its colour.
    let rig = png(&root.join("preview/rig.png"));
    for color in &vvgen::preview::rig_plot::SPLIT_COLORS[..2] {
        assert!(rig.pixels().filter(|p| p.0 == *color).count() > 20, "{color:?}");
    }

    // A second build does nothing; release locks the preview with the rest, and it verifies.
    assert!(run(d, &manifest("", 4.0)).nothing_to_do());
    vvgen::release::release(&load(&d.join("m.toml")), &d.join("cache")).unwrap();
    let lock = std::fs::read_to_string(root.join("vvgen.lock")).unwrap();
    assert!(lock.contains("\"preview/index.html\"") && lock.contains("\"preview/sheet-train.png\""));
    assert!(vvgen::release::verify(&root).unwrap().ok());

    // Without previews they go, from the disk and the lock alike, and the dataset still verifies.
    let r = run(d, &manifest("preview = false", 4.0));
    assert_eq!(r.actions.get(&Kind::PreviewSheet).map_or(0, |c| c.planned), 0);
    assert!(!root.join("preview").join("index.html").exists());
    vvgen::release::release(&load(&d.join("m.toml")), &d.join("cache")).unwrap();
    let v = vvgen::release::verify(&root).unwrap();
    assert!(v.ok(), "{v:?}");
    assert!(!std::fs::read_to_string(root.join("vvgen.lock")).unwrap().contains("preview/"));
}

/// The crop count is what the rig plot is for: cameras too close to the subject are called out in red.
#[test]
fn the_rig_plot_calls_out_cameras_that_crop_the_subject() {
    const WARN: [u8; 3] = [255, 110, 90];
    let reds = |radius: f64| {
        let dir = tempfile::tempdir().unwrap();
        run(dir.path(), &manifest("", radius));
        // Text is anti-aliased: count the pixels (nearly) fully inked in the warning colour.
        let near = |p: &image::Rgb<u8>| p.0.iter().zip(WARN).all(|(a, b)| a.abs_diff(b) <= 10);
        png(&dir.path().join("out/m_dnerf/preview/rig.png")).pixels().filter(|p| near(p)).count()
    };
    assert_eq!(reds(4.0), 0, "every camera of the NeRF recipe sees the whole subject");
    assert!(reds(1.4) > 20, "cameras inside the subject's reach crop it");
}

/// Debian's chromium, or `None` with the reason printed.
fn chromium() -> Option<PathBuf> {
    let found = ["/usr/bin/chromium", "/usr/bin/chromium-browser"].into_iter().map(PathBuf::from).find(|p| p.exists());
    if found.is_none() {
        eprintln!("SKIPPED: the viewer test needs Debian's chromium (apt install chromium; .ci/run installs it)");
    }
    found
}

/// Runs headless chromium on `url` with `what` (`--dump-dom`, or `--screenshot=FILE`); returns standard output.
fn browse(chromium: &Path, profile: &Path, url: &str, what: &str) -> String {
    let out = Command::new(chromium)
        .args([
            "--headless",
            "--no-sandbox",
            "--disable-gpu",
            "--enable-unsafe-swiftshader",
            "--disable-quic",
            "--no-first-run",
            "--disable-background-networking",
            "--disable-component-update",
            "--disable-sync",
            "--window-size=1000,700",
            "--virtual-time-budget=10000",
        ])
        .arg(format!("--user-data-dir={}", profile.display()))
        .arg(what)
        .arg(url)
        .output()
        .expect("chromium runs");
    assert!(out.status.success(), "chromium: {}", String::from_utf8_lossy(&out.stderr));
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// The value of attribute `attr` of the element with id `id` in `dom`.
fn attribute(dom: &str, id: &str, attr: &str) -> Option<String> {
    let start = dom.find(&format!("id=\"{id}\""))?;
    let tag = &dom[dom[..start].rfind('<')?..];
    let tag = &tag[..tag.find('>')?];
    let at = tag.find(&format!(" {attr}=\""))? + attr.len() + 3;
    Some(tag[at..at + tag[at..].find('"')?].to_string())
}

#[test]
fn the_viewer_renders_in_headless_chromium_and_shows_a_cameras_image() {
    let Some(chromium) = chromium() else { return };
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(d.join("m.toml"), manifest("", 4.0)).unwrap();
    // `vvgen preview --out` builds, then copies the preview elsewhere, its viewer pointed at the dataset.
    let status = Command::new(env!("CARGO_BIN_EXE_vvgen"))
        .args(["-q", "preview", "m.toml", "--out", "look"])
        .current_dir(d)
        .status()
        .unwrap();
    assert!(status.success());
    let root = d.join("out/m_dnerf");
    let meta: serde_json::Value =
        serde_json::from_slice(&std::fs::read(root.join(vvgen::export::META)).unwrap()).unwrap();
    let cameras: BTreeSet<(String, u64)> = meta["images"]
        .as_array()
        .unwrap()
        .iter()
        .map(|i| (i["split"].as_str().unwrap().to_string(), i["view"].as_u64().unwrap()))
        .collect();
    assert_eq!(cameras.len(), 5);

    for (k, page) in [root.join("preview/index.html"), d.join("look/d/index.html")].iter().enumerate() {
        let url = format!("file://{}#camera=train/2&frame=1", page.display());
        let dom = browse(&chromium, &d.join(format!("profile{k}")), &url, "--dump-dom");
        assert_eq!(attribute(&dom, "status", "data-ready").as_deref(), Some("1"), "{dom:.2000}");
        assert_eq!(attribute(&dom, "status", "data-cameras"), Some(cameras.len().to_string()));
        assert_eq!(
            attribute(&dom, "status", "data-images"),
            Some(meta["images"].as_array().unwrap().len().to_string())
        );
        // The selected camera's image at that frame loaded from disk (its natural width).
        assert_eq!(attribute(&dom, "photo", "data-loaded").as_deref(), Some("48"), "{}", page.display());
    }

    // A click where a camera is drawn selects it and shows its image (the click is dispatched at the camera's
    // projected position; the page picks the nearest camera within 14 px).
    let url = format!("file://{}#frame=2&click=test/1", root.join("preview/index.html").display());
    let dom = browse(&chromium, &d.join("profile-click"), &url, "--dump-dom");
    assert_eq!(attribute(&dom, "photo", "data-camera").as_deref(), Some("test/1"), "{dom:.3000}");
    assert_eq!(attribute(&dom, "photo", "data-loaded").as_deref(), Some("48"));

    // A point-cloud sequence's viewer steps through its frames, with no cameras.
    let page = d.join("out/m_points/preview/index.html");
    let dom = browse(&chromium, &d.join("profile-points"), &format!("file://{}#frame=2", page.display()), "--dump-dom");
    assert_eq!(attribute(&dom, "status", "data-ready").as_deref(), Some("1"), "{dom:.2000}");
    assert_eq!(attribute(&dom, "status", "data-cameras").as_deref(), Some("0"));
    assert_eq!(attribute(&dom, "status", "data-frames").as_deref(), Some("3"));

    // The canvas is not blank: the subject's samples, the frusta and the axes cover part of it in many colours.
    let shot = d.join("shot.png");
    let url = format!("file://{}", root.join("preview/index.html").display());
    browse(&chromium, &d.join("profile-shot"), &url, &format!("--screenshot={}", shot.display()));
    let img = png(&shot);
    // The 3D view is the left part of the window, above the time bar (the side panel is 360 px wide).
    let (w, h) = (img.width() - 360, img.height() - 56);
    let background = img.get_pixel(2, 2).0;
    let mut colors = BTreeSet::new();
    let mut drawn = 0;
    for y in 0..h {
        for x in 0..w {
            let p = img.get_pixel(x, y).0;
            if p != background {
                drawn += 1;
                colors.insert(p);
            }
        }
    }
    assert!(drawn as f64 > 0.01 * (w * h) as f64, "{drawn} of {} pixels drawn", w * h);
    assert!(colors.len() > 50, "{} colours", colors.len());
}
