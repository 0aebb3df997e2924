//! Sequence-wide transforms and multi-source scenes, through manifests.

use std::path::Path;

use glam::Vec3;
use vvgen::manifest;
use vvgen::scene::{Poser, PrimKind, Scene};

fn data(rel: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data").join(rel).to_string_lossy().replace('\\', "/")
}

fn scene(text: &str) -> Scene {
    let (m, _) =
        manifest::parse(text, Path::new("/nonexistent/m.toml")).unwrap_or_else(|r| panic!("{}", r.render(false)));
    vvgen::settings::scene::open(&m, None).unwrap()
}

fn union_bounds(s: &Scene) -> (Vec3, Vec3) {
    let mut p = Poser::default();
    (0..s.frames).fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), f| {
        let (a, b) = s.pose(f, &mut p).unwrap().bounds().unwrap();
        (lo.min(a), hi.max(b))
    })
}

fn man(transform: &str) -> String {
    format!("[dataset]\nname = \"t\"\nout = \"o\"\n[source.man]\ngltf = \"{}\"\nframes = {{ count = 20, fps = 10 }}\n[transform]\n{transform}\n", data("gltf/CesiumMan/CesiumMan.glb"))
}

#[test]
fn all_frames_normalization_fits_the_union_exactly() {
    let s = scene(&man("up = \"y\"\nfit = { height = 2.4 }\ncenter = \"bbox\""));
    assert_eq!(s.frames, 20);
    let (lo, hi) = union_bounds(&s);
    assert!(((hi.z - lo.z) - 2.4).abs() < 1e-5, "{lo} {hi}");
    assert!(((lo + hi) * 0.5).length() < 1e-5, "{lo} {hi}");
}

#[test]
fn first_frame_normalization_fits_frame_zero() {
    let s = scene(&man("fit = { height = 2.0 }\ncenter = \"bbox\"\nover = \"first\""));
    let mut p = Poser::default();
    let (lo, hi) = s.pose(0, &mut p).unwrap().bounds().unwrap();
    assert!(((hi.z - lo.z) - 2.0).abs() < 1e-5);
    // Other frames use the same matrix, so they are not refitted.
    let (lo5, hi5) = s.pose(10, &mut p).unwrap().bounds().unwrap();
    assert!(((hi5.z - lo5.z) - 2.0).abs() > 1e-4, "{lo5} {hi5}");
}

#[test]
fn up_axis_and_explicit_steps() {
    // Without a transform the glTF's +Y (the man's height) becomes world +Z.
    let (lo, hi) = union_bounds(&scene(&man("")));
    assert!(hi.z - lo.z > 1.3 && hi.y - lo.y < 1.0, "{lo} {hi}");
    // up = "z" keeps source axes: the height stays on Y.
    let (lo, hi) = union_bounds(&scene(&man("up = \"z\"")));
    assert!(hi.y - lo.y > 1.3, "{lo} {hi}");
    // translate after scale: fitted to extent 1 then moved by +10 in x.
    let (lo, hi) =
        union_bounds(&scene(&man("fit = { extent = 1.0 }\ncenter = \"bbox\"\ntranslate = [10.0, 0.0, 0.0]")));
    assert!(((hi - lo).max_element() - 1.0).abs() < 1e-5 && ((lo.x + hi.x) / 2.0 - 10.0).abs() < 1e-4, "{lo} {hi}");
    // radius: the box's corners lie on the sphere.
    let (lo, hi) = union_bounds(&scene(&man("fit = { radius = 1.5 }\ncenter = \"bbox\"")));
    assert!(((hi - lo).length() / 2.0 - 1.5).abs() < 1e-4, "{lo} {hi}");
}

#[test]
fn ply_sequence_is_normalized_once_over_all_frames() {
    let text = format!(
        "[dataset]\nname = \"t\"\nout = \"o\"\n[source.torus]\nply_sequence = \"{}\"\nframes = {{ start = 1000, end = 1002 }}\ntransform = {{ up = \"y\" }}\n[transform]\nfit = {{ height = 1.0 }}\ncenter = \"bbox\"\n",
        data("seq/torus_vox10_{frame:04}.ply")
    );
    let s = scene(&text);
    assert_eq!(s.frames, 3);
    let (lo, hi) = union_bounds(&s);
    assert!(((hi.z - lo.z) - 1.0).abs() < 1e-5, "{lo} {hi}");
    let mut p = Poser::default();
    let mut heights = Vec::new();
    for f in 0..3 {
        let posed = s.pose(f, &mut p).unwrap();
        assert_eq!(posed.primitives[0].kind, PrimKind::Points);
        let file = vvgen::scene::ply::read(&std::fs::read(data(&format!("seq/torus_vox10_{}.ply", 1000 + f))).unwrap())
            .unwrap();
        assert_eq!(posed.point_count(), file.positions.len());
        assert!(!posed.primitives[0].colors.is_empty());
        let (a, b) = posed.bounds().unwrap();
        heights.push(b.z - a.z);
        assert!(b.z <= hi.z + 1e-6 && a.z >= lo.z - 1e-6);
    }
    // The torus turns and rises: per-frame fitting would make every frame exactly 1.0 tall; one matrix for the
    // sequence keeps the frames' own sizes.
    assert!(heights.iter().filter(|h| (**h - 1.0).abs() < 1e-5).count() <= 1, "{heights:?}");
}

#[test]
fn several_sources_merge_with_their_own_transforms() {
    let text = format!(
        "[dataset]\nname = \"t\"\nout = \"o\"\n[source.a_man]\ngltf = \"{}\"\nframes = {{ count = 3 }}\n[source.b_box]\nmesh = \"{}\"\ntransform = {{ translate = [5.0, 0.0, 0.0] }}\n",
        data("gltf/CesiumMan/CesiumMan.glb"),
        data("gltf/BoxTextured/BoxTextured.glb")
    );
    let s = scene(&text);
    let mut p = Poser::default();
    let posed = s.pose(2, &mut p).unwrap();
    assert_eq!(posed.materials.len(), 2 * (1 + 2), "each glTF's material plus its two defaults");
    assert_eq!(posed.textures.len(), 2);
    let boxes: Vec<_> = posed.primitives.iter().filter(|p| p.positions.iter().all(|v| v.x > 4.0)).collect();
    assert_eq!(boxes.len(), 1);
    let m = &posed.materials[boxes[0].material as usize];
    assert_eq!(m.base_color_texture.unwrap().texture, 1, "the box's texture index is shifted past the man's");
    assert!(boxes[0].object > 0);
}

#[test]
fn a_scene_opens_from_its_own_request_as_from_the_manifest_that_says_the_same() {
    use vvgen::scene::input::{Center, Fit, FrameRange, Placement, Request, SourceFile, SourceRequest};
    // The scene's own input, with no manifest: what a bench or a test of posing writes.
    let req = Request {
        sources: vec![SourceRequest {
            name: "man".into(),
            file: SourceFile::Gltf { path: data("gltf/CesiumMan/CesiumMan.glb").into(), scene: None },
            clips: Default::default(),
            frames: FrameRange { count: Some(20), fps: Some(10.0), ..Default::default() },
            placement: Placement::default(),
            origin: [0.0; 3],
            opaque: false,
        }],
        global: Placement { fit: Some(Fit::Height(2.4)), center: Some(Center::Bbox), ..Placement::default() },
        ..Request::default()
    };
    let own = Scene::open(&req).unwrap();
    let from_manifest = scene(&man("fit = { height = 2.4 }\ncenter = \"bbox\""));
    assert_eq!((own.frames, own.global), (from_manifest.frames, from_manifest.global));
    let (lo, hi) = union_bounds(&own);
    assert!(((hi.z - lo.z) - 2.4).abs() < 1e-5, "{lo} {hi}");
}
