//! The manifest language: every table parses, every class of error is reported with the right place and fix.

use std::path::{Path, PathBuf};
use std::process::Command;

use vvgen::manifest::{self, Report};

fn data(rel: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data").join(rel).to_string_lossy().replace('\\', "/")
}

/// Parses `text` as if it were `<tmp>/m.toml`.
fn check(text: &str) -> Result<manifest::Manifest, Report> {
    manifest::parse(text, Path::new("/nonexistent-dir/m.toml")).map(|(m, _)| m)
}

fn errors(text: &str) -> Report {
    match check(text) {
        Ok(_) => panic!("manifest was accepted:\n{text}"),
        Err(r) => r,
    }
}

/// The (line, message, help) of every error.
fn lines(r: &Report) -> Vec<(usize, String, String)> {
    r.diagnostics
        .iter()
        .filter(|d| d.is_error())
        .map(|d| {
            (
                d.span.as_ref().map_or(0, |s| r.line_col(s.start).0),
                d.message.clone(),
                d.help.clone().unwrap_or_default(),
            )
        })
        .collect()
}

fn full_manifest() -> String {
    format!(
        r#"
[dataset]
name = "full"
version = "2.1"
out = "out/full"
seed = 42
cache = "my-cache"

[source.man]
gltf = "{man}"
animation = 0
frames = {{ count = 10, fps = 24 }}
transform = {{ up = "y", translate = [1.0, 0.0, 0.0] }}

[source.box]
mesh = "{box_}"

[source.torus]
ply_sequence = "{seq}"
frames = {{ start = 1000, end = 1002, step = 1 }}

[transform]
up = "y"
fit = {{ height = 2.4 }}
center = "centroid"
rotate_deg = [0.0, 0.0, 90.0]
scale = [1.0, 1.0, 1.0]
matrix = [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]]
over = "first"

[render]
resolution = [640, 480]
fx = 500.0
fy = 510.0
cx = 320.0
cy = 240.0
near = 0.1
far = 50.0
samples = 9
shading = "lambert"
background = [1.0, 1.0, 1.0]
passes = ["rgba", "depth", "normal", "mask"]
depth = {{ kind = "planar", exr = true }}
normal = {{ space = "camera" }}
splat = {{ shape = "disk", size_px = 2.0 }}
lights = [{{ direction = [0.0, 0.0, -1.0], intensity = 0.8 }}]
ambient = 0.2
png_compression = "default"

[rig.hemi]
kind = "hemisphere"
radius = 4.0311
numpy_seed = 0
jitter = {{ position = 0.01 }}

[rig.fib]
kind = "fibonacci"
elevation_range_deg = [-10.0, 80.0]

[rig.ring]
kind = "orbit"
schedule = "nerf-test"
start_azimuth_deg = 90.0

[rig.dome]
kind = "dome"
rings = 3
band = "upper"

[rig.ff]
kind = "forward-facing"
layout = "spiral"
extent = [1.0, 0.5]

[rig.fixed]
kind = "explicit"
poses = [{{ position = [0.0, -4.0, 1.0] }}, {{ c2w = [[1, 0, 0, 0], [0, 0, -1, -4], [0, 1, 0, 0], [0, 0, 0, 1]] }}]

[split.train]
rig = "hemi"
views = 100
time = "all"
frames = {{ start = 0, every = 2 }}

[split.val]
rig = "dome"
views = 9
time = "monocular"
seed = 3

[split.test]
rig = "ring"
views = 20
time = "random"
pairs = 50
frames = [0, 5, 9]

[output.dnerf]
writer = "dnerf"
dir = "full_dnerf"
init_points = 50000

[output.ngp]
writer = "instant-ngp"
splits = ["train"]
aabb_scale = 4

[output.pc]
writer = "ply-sequence"
source = "man"
points = 100000
voxel = 0.01
vox = 10
correspondence = true
motion = false
reduce = "nearest"
color_average = "srgb"
pattern = "man_vox10_{{frame:04}}.ply"
format = "ascii"
"#,
        man = data("gltf/CesiumMan/CesiumMan.glb"),
        box_ = data("gltf/BoxTextured/BoxTextured.glb"),
        seq = data("seq/torus_vox10_{frame:04}.ply"),
    )
}

#[test]
fn every_table_parses_from_a_full_example() {
    let m = check(&full_manifest()).unwrap_or_else(|r| panic!("{}", r.render(false)));
    assert_eq!(m.dataset.name(), "full");
    assert_eq!(m.dataset.seed, 42);
    assert_eq!(m.sources.len(), 3);
    assert_eq!(m.rigs.len(), 6);
    assert_eq!(m.splits.len(), 3);
    assert_eq!(m.outputs.len(), 3);
    assert_eq!(m.render.size(), (640, 480));
    assert_eq!(m.render.intrinsics(), (500.0, 510.0, 320.0, 240.0));
    assert_eq!(m.transform.over, Some(manifest::transform::Over::First));
    assert_eq!(m.splits["test"].time, manifest::TimeMode::Random);
    assert_eq!(m.outputs["pc"].writer(), manifest::Writer::PlySequence);
    // Named tables are kept by name: table order in the file does not matter.
    assert_eq!(m.rigs.keys().collect::<Vec<_>>(), ["dome", "ff", "fib", "fixed", "hemi", "ring"]);
}

#[test]
fn syntax_error_has_line_and_column() {
    let r = errors("[dataset]\nname = \"x\"\nout = \"o\nseed = 1\n");
    let l = lines(&r);
    assert_eq!(l.len(), 1, "{l:?}");
    assert_eq!(l[0].0, 3);
    assert!(l[0].1.starts_with("TOML syntax"), "{l:?}");
    assert!(r.render(false).contains("m.toml:3:"), "{}", r.render(false));
}

#[test]
fn unknown_key_suggests_the_nearest() {
    let text = full_manifest().replace("views = 100", "veiws = 100");
    let r = errors(&text);
    let l = lines(&r);
    let line = text.lines().position(|l| l.starts_with("veiws")).unwrap() + 1;
    assert!(l.iter().any(|(n, m, _)| *n == line && m == "unknown key `veiws`, did you mean `views`?"), "{l:?}");
    // The follow-on "missing views" must not be reported twice as a separate problem.
    let rendered = r.render(false);
    assert!(rendered.contains(&format!("m.toml:{line}:1")), "{rendered}");
    assert!(rendered.contains("help: did you mean `views`?"), "{rendered}");
}

#[test]
fn unknown_table_and_enum_value_suggest() {
    let text = full_manifest().replace("[output.ngp]", "[ouptut.ngp]").replace("\"fibonacci\"", "\"fibonaci\"");
    let l = lines(&errors(&text));
    assert!(l.iter().any(|(_, m, _)| m == "unknown table `ouptut`, did you mean `output`?"), "{l:?}");
    assert!(l.iter().any(|(_, m, _)| m == "unknown value `fibonaci`, did you mean `fibonacci`?"), "{l:?}");
}

#[test]
fn a_table_for_a_one_word_value_gets_one_error() {
    // `time` takes a word; a table is read as serde's one-key enum form. The unknown key is the error; dropping it
    // to go on must not add "wanted exactly 1 element, found 0 elements" for the emptied table.
    let text = full_manifest().replacen("time = \"all\"", "time = { frames = [0, 12] }", 1);
    let l = lines(&errors(&text));
    assert_eq!(l.len(), 1, "{l:?}");
    assert_eq!(l[0].1, "unknown value `frames`", "{l:?}");
}

#[test]
fn wrong_type_is_named() {
    let text = full_manifest().replace("samples = 9", "samples = \"nine\"");
    let line = text.lines().position(|l| l.starts_with("samples")).unwrap() + 1;
    let l = lines(&errors(&text));
    assert!(l.iter().any(|(n, m, _)| *n == line && m.contains("wrong type") && m.contains("\"nine\"")), "{l:?}");
}

#[test]
fn type_errors_say_what_the_key_takes_in_words_with_an_example() {
    // (the line as written, as the test writes it, the exact message and help)
    let cases = [
        (
            "seed = 42",
            "seed = \"x\"",
            "wrong type: string \"x\" where a whole number, 0 or more (e.g. 80) is expected",
            "write a whole number, 0 or more (e.g. 80) here",
        ),
        (
            "animation = 0",
            "animation = true",
            "`animation` takes a clip index, a clip name, a list of them, or \"all\"",
            "e.g. animation = 0, animation = \"Walk\", animation = [0, \"Wave\"] or animation = \"all\"",
        ),
        (
            "background = [1.0, 1.0, 1.0]",
            "background = 3",
            "`background` takes a name or an sRGB colour",
            "e.g. background = \"white\" or background = [0.5, 0.5, 0.5]",
        ),
    ];
    for (from, to, message, help) in cases {
        let base = full_manifest();
        assert!(base.lines().any(|l| l.trim() == from), "the full manifest has no line {from:?}");
        let text = base.replacen(from, to, 1);
        let line = text.lines().position(|l| l.trim() == to).unwrap() + 1;
        let l = lines(&errors(&text));
        assert!(l.contains(&(line, message.to_string(), help.to_string())), "{to}: {l:#?}");
    }
}

#[test]
fn dangling_reference_names_the_missing_rig() {
    let text = full_manifest().replace("rig = \"ring\"", "rig = \"rign\"");
    let line = text.lines().position(|l| l == "rig = \"rign\"").unwrap() + 1;
    let l = lines(&errors(&text));
    assert!(
        l.iter().any(|(n, m, h)| *n == line
            && m == "split `test` uses rig `rign`, which is not defined"
            && h == "did you mean `ring`?"),
        "{l:?}"
    );
}

#[test]
fn missing_file_is_an_error_at_its_path() {
    let text = full_manifest().replace("BoxTextured.glb\"", "BoxTexture.glb\"");
    let line = text.lines().position(|l| l.contains("BoxTexture.glb")).unwrap() + 1;
    let l = lines(&errors(&text));
    assert!(
        l.iter().any(|(n, m, _)| *n == line && m.starts_with("file not found") && m.contains("BoxTexture.glb")),
        "{l:?}"
    );
}

#[test]
fn missing_sequence_frame_is_named() {
    let text = full_manifest().replace("end = 1002", "end = 1003");
    let l = lines(&errors(&text));
    assert!(
        l.iter().any(|(_, m, _)| m.contains("frame 1003 is missing") && m.contains("torus_vox10_1003.ply")),
        "{l:?}"
    );
}

#[test]
fn output_path_may_not_escape() {
    let text = full_manifest().replace("dir = \"full_dnerf\"", "dir = \"../../elsewhere_dnerf\"");
    let line = text.lines().position(|l| l.contains("elsewhere_dnerf")).unwrap() + 1;
    let l = lines(&errors(&text));
    assert!(l.iter().any(|(n, m, _)| *n == line && m.contains("escapes the dataset's `out` directory")), "{l:?}");
    let l = lines(&errors(&full_manifest().replace("dir = \"full_dnerf\"", "dir = \"/abs_dnerf\"")));
    assert!(l.iter().any(|(_, m, _)| m.contains("escapes")), "{l:?}");
    assert!(check(&full_manifest().replace("dir = \"full_dnerf\"", "dir = \"a/../b_dnerf\"")).is_ok());
}

/// Split and output names become file and folder names: one that could climb out of the dataset is refused at
/// its key, and a plain one with dots is fine.
#[test]
fn split_and_output_names_are_plain_file_names() {
    let text = full_manifest().replace("[split.train]", "[split.\"../../evil\"]");
    let line = text.lines().position(|l| l.contains("../../evil")).unwrap() + 1;
    let l = lines(&errors(&text));
    assert!(
        l.iter().any(|(n, m, _)| *n == line && m.contains("split name `../../evil` is not a plain file name")),
        "{l:?}"
    );
    let l = lines(&errors(&full_manifest().replace("[split.train]", "[split.\"..\"]")));
    assert!(l.iter().any(|(_, m, _)| m.contains("split name `..`")), "{l:?}");
    let text = full_manifest().replacen("[output.", "[output.\"a/b\".x]\n[output.", 1);
    let l = lines(&errors(&text));
    assert!(l.iter().any(|(_, m, _)| m.contains("output name `a/b` is not a plain file name")), "{l:?}");
    let fine = full_manifest().replace("[split.train]", "[split.\"train.v2\"]").replace("\"train\"", "\"train.v2\"");
    assert!(check(&fine).is_ok(), "{:?}", check(&fine).err().map(|r| lines(&r)));
}

#[test]
fn zero_and_absurd_counts() {
    for (from, to, expect) in [
        ("views = 100", "views = 0", "views = 0: the split would be empty"),
        ("points = 100000", "points = 0", "points = 0 is outside"),
        ("resolution = [640, 480]", "resolution = [640, 20000]", "resolution 640×20000 is outside 1..=16384"),
        ("count = 10, fps = 24", "count = 0, fps = 24", "count = 0: the frame range is empty"),
        ("end = 1002", "end = 999", "empty frame range"),
        ("samples = 9", "samples = 5", "samples = 5 is not a square supersampling count"),
        (
            "samples = 9",
            "samples = 9\nfilter = \"blackman-harris\"\nfilter_width = 0",
            "filter_width = 0 is not a width",
        ),
        ("samples = 9", "samples = 9\nfilter_width = 2.0", "`filter_width` is the width of the Blackman-Harris"),
    ] {
        let text = full_manifest().replace(from, to);
        // The error points at the last line replaced.
        let last = to.lines().last().unwrap();
        let line = text.lines().position(|l| l.contains(last)).unwrap() + 1;
        let l = lines(&errors(&text));
        assert!(l.iter().any(|(n, m, _)| *n == line && m.contains(expect)), "{to}: {l:?}");
    }
}

#[test]
fn all_errors_are_reported_together() {
    let text = full_manifest()
        .replace("views = 100", "veiws = 100")
        .replace("samples = 9", "samples = \"nine\"")
        .replace("rig = \"ring\"", "rig = \"rign\"")
        .replace("BoxTextured.glb\"", "BoxTexture.glb\"")
        .replace("dir = \"full_dnerf\"", "dir = \"../x_dnerf\"")
        .replace("points = 100000", "points = 0")
        .replace("kind = \"dome\"", "kind = \"dome\"\nradius = -1.0");
    let r = errors(&text);
    let l = lines(&r);
    for expect in ["veiws", "wrong type", "rign", "file not found", "escapes", "points = 0", "radius = -1"] {
        assert!(l.iter().any(|(_, m, _)| m.contains(expect)), "missing {expect}: {l:?}");
    }
    // Reported in reading order.
    let ns: Vec<usize> = l.iter().map(|x| x.0).collect();
    let mut sorted = ns.clone();
    sorted.sort();
    assert_eq!(ns, sorted);
}

#[test]
fn keys_of_another_kind_are_rejected() {
    let text = full_manifest().replace("schedule = \"nerf-test\"", "schedule = \"nerf-test\"\nrings = 4");
    let l = lines(&errors(&text));
    assert!(l.iter().any(|(_, m, _)| m == "key `rings` does not apply to rig `ring` (kind = \"orbit\")"), "{l:?}");
}

/// `rings = 0` on a dome is an error, not a remainder by zero in the checker.
#[test]
fn a_dome_with_zero_rings_is_an_error() {
    let l = lines(&errors(&full_manifest().replace("rings = 3", "rings = 0")));
    assert!(l.iter().any(|(_, m, _)| m == "rings = 0 must be in 1..=1000"), "{l:?}");
}

/// A dynerf output over splits that are not synchronized video is refused by check, before anything renders.
#[test]
fn dynerf_needs_every_camera_at_every_frame() {
    let text = full_manifest().replace(
        "[output.ngp]",
        "[output.dy]\nwriter = \"dynerf\"\nsplits = [\"train\", \"val\", \"test\"]\n[output.ngp]",
    );
    let l = lines(&errors(&text));
    let dy: Vec<&str> = l.iter().filter(|(_, m, _)| m.contains("(dynerf)")).map(|(_, m, _)| m.as_str()).collect();
    assert_eq!(
        dy,
        [
            "output `dy` (dynerf) writes split `val`, whose time is not \"all\"",
            "output `dy` (dynerf): splits `train` and `val` select different frames",
            "output `dy` (dynerf) writes split `test`, whose time is not \"all\"",
            "output `dy` (dynerf): splits `train` and `test` select different frames",
        ]
    );
}

/// NaN, infinity and overflowing literals are refused wherever a float stands, with their place.
#[test]
fn every_float_must_be_finite() {
    let text = full_manifest()
        .replace("translate = [1.0, 0.0, 0.0]", "translate = [inf, 0.0, 0.0]")
        .replace("voxel = 0.01", "voxel = nan")
        .replace("start_azimuth_deg = 90.0", "start_azimuth_deg = -1e400");
    let l = lines(&errors(&text));
    let bad: Vec<&str> =
        l.iter().filter(|(_, m, _)| m.ends_with("is not a finite number")).map(|(_, m, _)| m.as_str()).collect();
    assert_eq!(
        bad,
        ["`inf` is not a finite number", "`-1e400` is not a finite number", "`nan` is not a finite number"]
    );
}

/// What the plan would refuse, `check` refuses first (before any rendering).
#[test]
fn check_refuses_what_the_plan_would() {
    let l = lines(&errors(&full_manifest().replace("[split.test]", "[split.test_ring]")));
    assert!(l.iter().any(|(_, m, h)| m.contains("`test_ring`") && h.contains("K-Planes")), "{l:?}");
    let l = lines(&errors(&full_manifest().replace("motion = false", "motion = true")));
    assert!(l.iter().any(|(_, m, _)| m.contains("`motion` needs correspondence and no `voxel`")), "{l:?}");
    let seq = full_manifest().replace("source = \"man\"\n", "source = \"torus\"\n");
    let l = lines(&errors(&seq));
    assert!(l.iter().any(|(_, m, _)| m.contains("`correspondence` needs mesh sources")), "{l:?}");
}

#[test]
fn dnerf_with_non_square_images_warns_citing_loaders() {
    let m = manifest::parse(&full_manifest(), Path::new("/nonexistent-dir/m.toml")).unwrap().1;
    let w: Vec<_> = m.diagnostics.iter().filter(|d| !d.is_error()).collect();
    assert!(
        w.iter()
            .any(|d| d.message.contains("non-square 640×480") && d.help.as_deref().unwrap_or("").contains("K-Planes")),
        "{w:?}"
    );
}

#[test]
fn shipped_manifests_check() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("manifests");
    let mut kinds = std::collections::BTreeSet::new();
    for entry in std::fs::read_dir(&dir).unwrap() {
        let p: PathBuf = entry.unwrap().path();
        if p.extension().is_some_and(|e| e == "toml") {
            let (m, _) = manifest::load(&p).unwrap_or_else(|r| panic!("{}", r.render(false)));
            for s in m.sources.values() {
                kinds.insert(s.kind().map_or("Plane".to_string(), |k| format!("{:?}", k.0)));
            }
        }
    }
    assert_eq!(kinds.into_iter().collect::<Vec<_>>(), ["Gltf", "Mesh", "Plane", "PlySequence"]);
}

#[test]
fn cli_check_exits_2_with_line_and_suggestion() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("typo.toml");
    let text = full_manifest().replace("views = 100", "veiws = 100");
    std::fs::write(&path, &text).unwrap();
    let out =
        Command::new(env!("CARGO_BIN_EXE_vvgen")).args(["check", "--color", "never"]).arg(&path).output().unwrap();
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    let line = text.lines().position(|l| l.starts_with("veiws")).unwrap() + 1;
    assert!(err.contains(&format!("typo.toml:{line}:1")), "{err}");
    assert!(err.contains("did you mean `views`?"), "{err}");

    std::fs::write(&path, full_manifest()).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_vvgen")).args(["check", "-q"]).arg(&path).output().unwrap();
    assert_eq!(out.status.code(), Some(0), "{}", String::from_utf8_lossy(&out.stderr));
}

#[test]
fn after_manifests_vouch_for_the_sequences_they_write() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let glb = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/gltf/CesiumMan/CesiumMan.glb");
    let points = format!(
        "[dataset]\nname = \"m\"\nout = \"out\"\n[source.a]\ngltf = \"{}\"\nframes = {{ count = 2 }}\n\
         [output.v]\nwriter = \"ply-sequence\"\npoints = 1000\ndir = \"v\"\npattern = \"{{name}}_{{frame:03}}.ply\"\n",
        glb.display()
    );
    std::fs::write(d.join("points.toml"), &points).unwrap();
    let render = |after: &str, pattern: &str| {
        format!(
            "[dataset]\nname = \"r\"\nout = \"out\"\nafter = [\"{after}\"]\n\
             [source.c]\nply_sequence = \"{pattern}\"\nframes = {{ start = 0, end = 1 }}\n"
        )
    };
    let load = |name: &str, text: &str| {
        std::fs::write(d.join(name), text).unwrap();
        manifest::load(&d.join(name))
    };
    // Not built yet, but `points.toml` writes exactly these files.
    let (m, _) = load("r.toml", &render("points.toml", "out/v/./m_{frame:03}.ply"))
        .unwrap_or_else(|r| panic!("{}", r.render(false)));
    assert_eq!(m.after.len(), 1);
    // A path no prerequisite writes is still checked.
    let err = load("r.toml", &render("points.toml", "out/v/m_{frame:04}.ply")).unwrap_err().render(false);
    assert!(err.contains("frame 0 is missing") && err.contains("r.toml:6:16"), "{err}");
    // A prerequisite with errors, or that is missing, is an error at the `after` entry.
    std::fs::write(d.join("points.toml"), points.replace("points = 1000", "pionts = 1000")).unwrap();
    let err = load("r.toml", &render("points.toml", "out/v/m_{frame:03}.ply")).unwrap_err().render(false);
    assert!(err.contains("points.toml` has ") && err.contains("needs `points`"), "{err}");
    let err = load("r.toml", &render("nope.toml", "x_{frame}.ply")).unwrap_err().render(false);
    assert!(err.contains("cannot read") && err.contains("r.toml:4:10"), "{err}");
    // Cycles are named.
    std::fs::write(d.join("points.toml"), points.replace("out = \"out\"\n", "out = \"out\"\nafter = [\"r.toml\"]\n"))
        .unwrap();
    let err = load("r.toml", &render("points.toml", "out/v/m_{frame:03}.ply")).unwrap_err().render(false);
    assert!(err.contains("`after` cycle:") && err.contains("r.toml → "), "{err}");
}
