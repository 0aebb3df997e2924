//! Lit (`pbr`) rendering (issue 16), by invariants that need no reference renderer: a white furnace, a shadowed
//! point that receives only the environment, an environment rotation that turns the lighting, Blender's
//! equirectangular mapping of the visible background, thread-count byte identity; and in builds: the environment
//! prefiltered as a cached action, the lights in the keys, and the albedo pass beside the lit one.

use std::path::Path;
use std::sync::Arc;

use glam::{DMat4, Vec3, Vec4};
use vvgen::render::light::environment::{prefilter, EnvMap};
use vvgen::render::light::{FrameLight, Light, LightKind};
use vvgen::render::{render_lit, Camera, Environment, RenderSettings, Shading};
use vvgen::scene::material::{linear_to_srgb, srgb8_to_linear, Material};
use vvgen::scene::{PosedScene, PrimKind};

use crate::common::{cesium_head, load};

fn cam(w: u32, f: f64, c2w: DMat4) -> Camera {
    Camera { width: w, height: w, fx: f, fy: f, cx: w as f64 / 2.0, cy: w as f64 / 2.0, near: 0.05, far: 100.0, c2w }
}

/// A UV sphere (smooth normals) of radius `r` at `centre`.
fn sphere(r: f32, centre: Vec3, material: Material) -> PosedScene {
    let (seg, rings) = (96u32, 48u32);
    let (mut pos, mut nrm, mut idx) = (Vec::new(), Vec::new(), Vec::new());
    for i in 0..=rings {
        let th = std::f32::consts::PI * i as f32 / rings as f32;
        for j in 0..seg {
            let ph = 2.0 * std::f32::consts::PI * j as f32 / seg as f32;
            let n = Vec3::new(th.sin() * ph.cos(), th.sin() * ph.sin(), th.cos());
            pos.push(centre + n * r);
            nrm.push(n);
        }
    }
    for i in 0..rings {
        for j in 0..seg {
            let (a, b) = (i * seg + j, i * seg + (j + 1) % seg);
            let (c, d) = (a + seg, b + seg);
            idx.extend_from_slice(&[a, b, c, b, d, c]);
        }
    }
    PosedScene::single(PrimKind::Triangles, pos, nrm, Vec::new(), idx, material)
}

fn lambert(grey: f32) -> Material {
    Material {
        base_color: Vec4::new(grey, grey, grey, 1.0),
        metallic: 0.0,
        roughness: 1.0,
        specular: 0.0,
        ..Material::default()
    }
}

fn uniform(radiance: f32) -> EnvMap {
    EnvMap { width: 64, height: 32, texels: vec![Vec3::splat(radiance); 64 * 32] }
}

/// A lit render of `scene` under `map` (rotated `rotation_deg`, visible or not) and `lights`.
fn lit(
    scene: &PosedScene,
    c: &Camera,
    map: EnvMap,
    rotation_deg: f32,
    visible: bool,
    lights: &[Light],
) -> vvgen::render::Frame {
    let env = Environment { map: None, strength: 1.0, rotation_deg, visible };
    let light = FrameLight::prepare(
        scene,
        lights,
        env.with(Arc::new(prefilter(&map)), Some(Arc::new(map))),
        vvgen::render::light::PointCasters::NONE,
    )
    .with_bounce(scene);
    let s = RenderSettings { samples: 4, shading: Shading::Pbr, ..Default::default() };
    render_lit(scene, c, &s, Some(&light))
}

fn rgb(f: &vvgen::render::Frame, x: u32, y: u32) -> [u8; 4] {
    let i = ((y * f.width + x) * 4) as usize;
    [f.rgba[i], f.rgba[i + 1], f.rgba[i + 2], f.rgba[i + 3]]
}

#[test]
fn a_white_lambertian_sphere_in_a_white_furnace_renders_white() {
    let s = sphere(0.5, Vec3::ZERO, lambert(1.0));
    let c = cam(96, 180.0, Camera::look_at(Vec3::new(2.0, -2.5, 1.2), Vec3::ZERO, Vec3::Z));
    let f = lit(&s, &c, uniform(1.0), 0.0, false, &[]);
    let covered: Vec<[u8; 4]> = f.rgba.chunks(4).filter(|p| p[3] == 255).map(|p| [p[0], p[1], p[2], p[3]]).collect();
    assert!(covered.len() > 2000, "{}", covered.len());
    for p in &covered {
        assert!(p[..3].iter().all(|&v| v >= 254), "{p:?}: the furnace must render white ±1/255");
    }
    // A grey one reflects its albedo: 0.5 linear is sRGB 188.
    let g = lit(&sphere(0.5, Vec3::ZERO, lambert(0.5)), &c, uniform(1.0), 0.0, false, &[]);
    for p in g.rgba.chunks(4).filter(|p| p[3] == 255) {
        assert!(p[..3].iter().all(|&v| v.abs_diff(188) <= 1), "{p:?}");
    }
}

/// The ground and a box hovering over its centre.
fn ground_and_caster() -> PosedScene {
    let plane = vvgen::scene::input::Ground { size: [4.0, 4.0], color: [0.8; 3], z: None };
    let ground = vvgen::scene::source::ground(&plane, 0.0);
    merged(&[ground, sphere(0.4, Vec3::new(0.0, 0.0, 1.0), lambert(0.5))])
}

/// `parts` as one scene, in this order (objects 0, 1, …).
fn merged(parts: &[PosedScene]) -> PosedScene {
    let mut scene = PosedScene::default();
    vvgen::scene::merge(parts, &mut scene);
    scene
}

#[test]
fn a_shadowed_point_receives_only_the_environment_and_a_lit_one_the_sun_too() {
    let scene = ground_and_caster();
    let c = cam(128, 110.0, Camera::look_at(Vec3::new(0.0, -0.01, 6.0), Vec3::ZERO, Vec3::Y));
    let sun = Light {
        kind: LightKind::Sun { direction: -Vec3::Z, angle: 0.0 },
        color: Vec3::ONE,
        intensity: 1.0,
        shadows: true,
    };
    let env = uniform(0.2);
    let with = lit(&scene, &c, env.clone(), 0.0, false, std::slice::from_ref(&sun));
    let without = lit(&scene, &c, env, 0.0, false, &[]);
    // The caster hides the shadow from the camera straight above: look beside it, off centre, where the sun is
    // blocked only for a ray straight down. Use an oblique sun instead so the shadow falls clear of the caster.
    let oblique =
        Light { kind: LightKind::Sun { direction: Vec3::new(1.0, 0.0, -1.0).normalize(), angle: 0.0 }, ..sun };
    let env = uniform(0.2);
    let shadowed = lit(&scene, &c, env.clone(), 0.0, false, std::slice::from_ref(&oblique));
    // The shadow's centre: the ray from the caster's centre (0, 0, 1) along (1, 0, −1) meets the ground at (1, 0, 0).
    let project = |p: Vec3| {
        let q = c.c2w.inverse().transform_point3(p.as_dvec3());
        ((c.cx + c.fx * q.x / -q.z) as u32, (c.cy - c.fy * q.y / -q.z) as u32)
    };
    let (sx, sy) = project(Vec3::new(1.0, 0.0, 0.0));
    let (lx, ly) = project(Vec3::new(-1.2, 0.8, 0.0));
    let env_only = lit(&scene, &c, env, 0.0, false, &[]);
    // In the shadow: exactly what the environment alone gives. In the open: more, by the sun's 0.8·E·cos/π.
    assert_eq!(rgb(&shadowed, sx, sy), rgb(&env_only, sx, sy));
    let open = rgb(&shadowed, lx, ly)[0];
    assert!(open > rgb(&env_only, lx, ly)[0] + 40, "{open} vs {:?}", rgb(&env_only, lx, ly));
    // Straight down, the shadow lies under the caster: the ground beside it is lit the same with or without...
    assert!(rgb(&with, lx, ly)[0] > rgb(&without, lx, ly)[0]);
    // ... and the whole ground receives the sun's light where nothing blocks it: 0.8/π·1 + 0.8·0.2·(visibility).
    let expect = vvgen::scene::material::linear_to_srgb8(0.8 / std::f32::consts::PI + 0.8 * 0.2);
    let (fx, fy) = project(Vec3::new(-1.8, -1.8, 0.0));
    assert!(rgb(&with, fx, fy)[0].abs_diff(expect) <= 2, "{:?} vs {expect}", rgb(&with, fx, fy));
}

/// A map bright over the hemisphere facing +X (the centre half of Blender's mapping), dark elsewhere.
fn bright_toward_x() -> EnvMap {
    let (w, h) = (128u32, 64u32);
    let texels = (0..h)
        .flat_map(|_| {
            (0..w).map(move |x| if (w / 4..3 * w / 4).contains(&x) { Vec3::splat(2.0) } else { Vec3::splat(0.05) })
        })
        .collect();
    EnvMap { width: w, height: h, texels }
}

#[test]
fn rotating_the_environment_rotates_the_lighting() {
    let s = sphere(0.5, Vec3::ZERO, lambert(0.8));
    // From straight above, +X is image right and +Y image up.
    let c = cam(96, 400.0, Camera::look_at(Vec3::new(0.0, -0.001, 5.0), Vec3::ZERO, Vec3::Y));
    let at = |f: &vvgen::render::Frame, dx: i32, dy: i32| rgb(f, (48 + dx) as u32, (48 - dy) as u32)[0];
    let r0 = lit(&s, &c, bright_toward_x(), 0.0, false, &[]);
    assert!(at(&r0, 30, 0) > at(&r0, -30, 0) + 60, "lit from +X: {} vs {}", at(&r0, 30, 0), at(&r0, -30, 0));
    // Blender's Mapping node rotates the lookup vector: +90° about Z brings the bright half to −Y.
    let r90 = lit(&s, &c, bright_toward_x(), 90.0, false, &[]);
    for (a, b) in [((30, 0), (0, -30)), ((-30, 0), (0, 30)), ((0, 30), (30, 0))] {
        let (x, y) = (at(&r0, a.0, a.1), at(&r90, b.0, b.1));
        assert!(x.abs_diff(y) <= 2, "{a:?} unrotated {x} vs {b:?} rotated {y}");
    }
}

#[test]
fn the_visible_background_is_blenders_equirectangular_mapping() {
    // Four quarters of distinct colour across u: [0, ¼) red, [¼, ½) green (+Y ends it), [½, ¾) blue (+X starts
    // it), [¾, 1) white; Blender maps +X to u = ½, +Y to u = ¼, −Y to u = ¾.
    let (w, h) = (256u32, 128u32);
    let quarter = [Vec3::X, Vec3::Y, Vec3::Z, Vec3::ONE];
    let texels = (0..h).flat_map(|_| (0..w).map(move |x| quarter[(x * 4 / w) as usize] * 0.5)).collect();
    let map = EnvMap { width: w, height: h, texels };
    let empty = PosedScene::default();
    let look = |d: Vec3| {
        let c = cam(33, 40.0, Camera::look_at(Vec3::ZERO, d, Vec3::Z));
        let f = lit(&empty, &c, map.clone(), 0.0, true, &[]);
        rgb(&f, 16, 16)
    };
    let half = vvgen::scene::material::linear_to_srgb8(0.5);
    // Just past +X (toward −Y, u > ½): blue; just past +Y toward +X (u < ½ … ¼ side): green.
    assert_eq!(look(Vec3::new(1.0, -0.3, 0.0)), [0, 0, half, 255]);
    assert_eq!(look(Vec3::new(0.3, 1.0, 0.0)), [0, half, 0, 255]);
    assert_eq!(look(Vec3::new(-1.0, 0.3, 0.0)), [half, 0, 0, 255]);
    assert_eq!(look(Vec3::new(-0.3, -1.0, 0.0)), [half, half, half, 255]);
}

#[test]
fn lit_renders_are_the_same_bytes_whatever_the_thread_count() {
    // A transparent (BLEND) sphere beside the caster: its fragments are sorted per sample, not by thread.
    let glass = sphere(
        0.3,
        Vec3::new(0.8, -0.6, 0.6),
        Material {
            base_color: Vec4::new(0.2, 0.5, 1.0, 0.4),
            alpha_mode: vvgen::scene::material::AlphaMode::Blend,
            double_sided: true,
            ..Material::default()
        },
    );
    // A glossy metal sphere beside the caster: its lobes look for what blocks them with rays, against a tree.
    let metal = sphere(
        0.25,
        Vec3::new(-0.7, 0.4, 0.5),
        Material { base_color: Vec4::new(0.9, 0.7, 0.4, 1.0), metallic: 1.0, roughness: 0.2, ..Material::default() },
    );
    let scene = merged(&[ground_and_caster(), glass, metal]);
    let c = cam(96, 120.0, Camera::look_at(Vec3::new(3.0, -4.0, 3.0), Vec3::new(0.0, 0.0, 0.5), Vec3::Z));
    let sun = Light {
        kind: LightKind::Sun { direction: Vec3::new(0.5, 0.3, -1.0).normalize(), angle: 0.05 },
        color: Vec3::new(1.0, 0.9, 0.8),
        intensity: 2.0,
        shadows: true,
    };
    let spot = Light {
        kind: LightKind::Spot {
            position: Vec3::new(-2.0, 0.0, 3.0),
            direction: Vec3::new(2.0, 0.0, -3.0).normalize(),
            cone: 1.0,
            blend: 0.2,
            radius: 0.1,
        },
        color: Vec3::ONE,
        intensity: 300.0,
        shadows: true,
    };
    let point = Light {
        kind: LightKind::Point { position: Vec3::new(1.0, -2.0, 2.0), radius: 0.2 },
        color: Vec3::ONE,
        intensity: 200.0,
        shadows: true,
    };
    let lights = [sun, spot, point];
    let go = |n: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build()
            .unwrap()
            .install(|| lit(&scene, &c, bright_toward_x(), 30.0, true, &lights))
    };
    let (one, two) = (go(1), go(2));
    assert!(one == two);
    let mut colours: Vec<&[u8]> = one.rgba.chunks(4).collect();
    colours.sort();
    colours.dedup();
    assert!(colours.len() > 200, "{}", colours.len());
}

/// Writes a `w × h` Radiance HDR map, bright above the horizon.
fn write_hdr(path: &Path, w: u32, h: u32) {
    let px: Vec<image::Rgb<f32>> = (0..h)
        .flat_map(|y| (0..w).map(move |_| if y < h / 2 { image::Rgb([1.5, 1.4, 1.2]) } else { image::Rgb([0.2; 3]) }))
        .collect();
    let f = std::io::BufWriter::new(std::fs::File::create(path).unwrap());
    image::codecs::hdr::HdrEncoder::new(f).encode(&px, w as usize, h as usize).unwrap();
}

fn lit_manifest(extra: &str) -> String {
    format!(
        "{}[source.floor]\nplane = {{ size = [4, 4] }}\n\
         [render]\nresolution = [48, 48]\nsamples = 4\nshading = \"pbr\"\npasses = [\"rgba\", \"albedo\", \"depth\"]\n\
         [environment]\nmap = \"sky.hdr\"\n\
         [light.sun]\nkind = \"sun\"\ndirection = [0.3, 0.2, -1]\nintensity = 2.0\n{extra}\n\
         [rig.h]\nkind = \"hemisphere\"\n[split.train]\nrig = \"h\"\nviews = 2\n\
         [output.d]\nwriter = \"dnerf\"\n",
        cesium_head(2, 4, 2.0, "preview = false", "")
    )
}

/// A fresh project folder holding `lit_manifest`'s map, `sky.hdr`.
fn lit_project() -> tempfile::TempDir {
    let dir = tempfile::tempdir().unwrap();
    write_hdr(&dir.path().join("sky.hdr"), 64, 32);
    dir
}

fn build_in(dir: &Path, text: &str) -> vvgen::build::Report {
    std::fs::write(dir.join("m.toml"), text).unwrap();
    vvgen::build::build(&load(&dir.join("m.toml")), &dir.join("cache"), Default::default(), &vvgen::build::Silent)
        .unwrap()
}

#[test]
fn a_lit_build_prefilters_once_keys_its_lights_and_writes_albedo_beside_rgba() {
    use vvgen::plan::actions::Kind;
    let dir = lit_project();
    let d = dir.path();
    let text = lit_manifest("");
    let first = build_in(d, &text);
    assert_eq!(first.ran(Kind::Environment), 1);
    // One light action per frame (two frames), shared by the frame's two views.
    assert_eq!(first.ran(Kind::Light), 2);
    assert_eq!(first.ran(Kind::RenderPass), 4 * 3);
    let root = d.join("out/m_dnerf");
    for f in ["train/r_0000.png", "albedo/train/r_0000.png", "depth/train/r_0000.png"] {
        assert!(root.join(f).is_file(), "{f}");
    }
    let lit_png = image::open(root.join("train/r_0000.png")).unwrap().into_rgba8();
    let albedo = image::open(root.join("albedo/train/r_0000.png")).unwrap().into_rgba8();
    assert_ne!(lit_png.as_raw(), albedo.as_raw(), "lit differs from albedo");
    // The same silhouette: shading does not move geometry.
    let alpha = |i: &image::RgbaImage| i.pixels().map(|p| p[3]).collect::<Vec<u8>>();
    assert_eq!(alpha(&lit_png), alpha(&albedo));
    // Nothing changed: nothing runs.
    assert!(build_in(d, &text).nothing_to_do());
    // Moving the sun re-renders the lit pass only, not albedo or depth, and not the prefiltering.
    let moved = build_in(d, &lit_manifest("").replace("[0.3, 0.2, -1]", "[-0.3, 0.2, -1]"));
    assert_eq!((moved.ran(Kind::RenderPass), moved.ran(Kind::Environment), moved.ran(Kind::Light)), (4, 0, 2));
    // A new map (same name, other content) is prefiltered again and re-renders the lit pass only.
    write_hdr(&d.join("sky.hdr"), 32, 16);
    let remapped = build_in(d, &lit_manifest("").replace("[0.3, 0.2, -1]", "[-0.3, 0.2, -1]"));
    assert_eq!((remapped.ran(Kind::RenderPass), remapped.ran(Kind::Environment), remapped.ran(Kind::Light)), (4, 1, 2));
    // The map shown behind the subject changes pixels, not the light: nothing is gathered again.
    let shown = lit_manifest("")
        .replace("[0.3, 0.2, -1]", "[-0.3, 0.2, -1]")
        .replace("map = \"sky.hdr\"\n", "map = \"sky.hdr\"\nvisible = true\n");
    let shown = build_in(d, &shown);
    assert_eq!((shown.ran(Kind::RenderPass), shown.ran(Kind::Environment), shown.ran(Kind::Light)), (4, 0, 0));
    // Without a map, the built-in studio map is prefiltered by an environment action of its own, once.
    let studio = lit_manifest("").replace("map = \"sky.hdr\"\n", "");
    assert!(!studio.contains("sky.hdr"));
    let r = build_in(d, &studio);
    assert_eq!((r.ran(Kind::Environment), r.ran(Kind::Light)), (1, 2));
    assert!(build_in(d, &studio).nothing_to_do());
}

/// A pixel filter keys the colour passes alone: switching to Cycles' filter re-renders `rgba` and `albedo`,
/// not depth, and prefilters nothing again.
#[test]
fn a_pixel_filter_re_renders_the_colour_passes_only() {
    use vvgen::plan::actions::Kind;
    let dir = lit_project();
    let d = dir.path();
    let text = lit_manifest("");
    build_in(d, &text);
    let read = |f: &str| std::fs::read(d.join("out/m_dnerf").join(f)).unwrap();
    let (rgba, depth) = (read("train/r_0000.png"), read("depth/train/r_0000.png"));
    let soft = text.replace("samples = 4\n", "samples = 4\nfilter = \"blackman-harris\"\n");
    let r = build_in(d, &soft);
    // Four images: their rgba and albedo; the frames' gathered light is the same.
    assert_eq!((r.ran(Kind::RenderPass), r.ran(Kind::Environment), r.ran(Kind::Light)), (8, 0, 0));
    assert_ne!(read("train/r_0000.png"), rgba);
    assert_eq!(read("depth/train/r_0000.png"), depth);
    // Its width is part of the key too; the box again is the first build's, still cached.
    let wider = soft.replace("filter = \"blackman-harris\"\n", "filter = \"blackman-harris\"\nfilter_width = 2.5\n");
    assert_eq!(build_in(d, &wider).ran(Kind::RenderPass), 8);
    assert!(build_in(d, &text).ran(Kind::RenderPass) == 0);
    assert_eq!(read("train/r_0000.png"), rgba);
}

#[test]
fn lighting_mistakes_are_named_with_their_place_and_fix() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(d.join("not-a-map.png"), b"png").unwrap();
    let cases: &[(&str, &str)] = &[
        ("[light.sun]\nkind = \"sun\"\nintensity = 2\n", "light `sun` (sun) needs `direction`"),
        (
            "[light.sun]\nkind = \"sun\"\ndirection = [0, 0, -1]\nintesity = 2\n",
            "unknown key `intesity`, did you mean `intensity`?",
        ),
        ("[light.s]\nkind = \"spot\"\nposition = [0, 0, 0]\nintensity = 2\n", "the spot's `target` is its `position`"),
        (
            "[light.p]\nkind = \"point\"\nposition = [0, 0, 2]\nintensity = 2\nangle_deg = 3\n",
            "`angle_deg` does not apply to a point light",
        ),
        ("[light.p]\nkind = \"lamp\"\nintensity = 2\n", "lamp"),
        ("[environment]\nmap = \"missing.exr\"\n", "file not found"),
        ("[environment]\nmap = \"not-a-map.png\"\n", "is not an environment map vvgen reads"),
        ("[environment]\nmap = \"broken.hdr\"\n", "not a readable Radiance HDR file"),
        ("[source.floor]\nplane = { size = [0, 4] }\n", "a plane's `size` must be two positive extents"),
        ("view_transform = \"filmic\"\n", "expected `standard` or `agx`"),
    ];
    std::fs::write(d.join("broken.hdr"), b"#?RADIANCE\nnonsense").unwrap();
    for (extra, want) in cases {
        let text = format!(
            "[dataset]\nname = \"m\"\nout = \"out\"\n[source.a]\nmesh = \"{}\"\n[render]\nshading = \"pbr\"\n{extra}\
             [rig.h]\nkind = \"hemisphere\"\n[split.t]\nrig = \"h\"\nviews = 1\n[output.o]\nwriter = \"dnerf\"\n",
            crate::common::data("gltf/BoxTextured/BoxTextured.glb").display()
        );
        let path = d.join("m.toml");
        std::fs::write(&path, &text).unwrap();
        // As `check` and the CLI load it: the manifest, then what only the renderer's readers check.
        let report = vvgen::settings::load(&path).expect_err(extra);
        let shown = report.render(false);
        assert!(shown.contains(want), "{extra}: {shown}");
        assert!(shown.contains("m.toml:"), "names the file and line: {shown}");
    }
    // A manifest parsed without those checks still cannot build with a broken map: `build` makes them first.
    let text = format!(
        "[dataset]\nname = \"m\"\nout = \"out\"\n[source.a]\nmesh = \"{}\"\n[render]\nshading = \"pbr\"\n\
         [environment]\nmap = \"broken.hdr\"\n[rig.h]\nkind = \"hemisphere\"\n[split.t]\nrig = \"h\"\nviews = 1\n\
         [output.o]\nwriter = \"dnerf\"\n",
        crate::common::data("gltf/BoxTextured/BoxTextured.glb").display()
    );
    std::fs::write(d.join("m.toml"), text).unwrap();
    let (m, _) = vvgen::manifest::load(&d.join("m.toml")).unwrap();
    let e = vvgen::build::build(&m, &d.join("cache"), Default::default(), &vvgen::build::Silent).unwrap_err();
    match e {
        vvgen::build::Error::Manifest(r) => assert!(r.render(false).contains("not a readable Radiance HDR")),
        other => panic!("{other}"),
    }
    assert!(!d.join("out").exists(), "nothing was written");
}

#[test]
fn lit_point_colours_bake_the_lighting_and_its_shadows_and_are_keyed_by_it() {
    use vvgen::plan::actions::Kind;
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_hdr(&d.join("sky.hdr"), 64, 32);
    // The floor sampled twice: its albedo (0.8 grey), and lit by the sun travelling toward +x, +y and the sky.
    let outputs = "[output.flat]\nwriter = \"ply-sequence\"\ndir = \"flat\"\nsource = \"floor\"\npoints = 6000\n\
                   [output.baked]\nwriter = \"ply-sequence\"\ndir = \"baked\"\nsource = \"floor\"\npoints = 6000\n\
                   color = \"lit\"\n";
    let dim = lit_manifest("")
        .replace("map = \"sky.hdr\"", "map = \"sky.hdr\"\nstrength = 0.2")
        .replace("intensity = 2.0", "intensity = 1.0");
    let text = format!("{dim}{outputs}");
    build_in(d, &text);
    let read = |name: &str| {
        let p = d.join(format!("out/{name}/m_0000.ply"));
        vvgen::scene::ply::read(&std::fs::read(&p).unwrap()).unwrap()
    };
    let (flat, baked) = (read("flat"), read("baked"));
    assert_eq!(flat.positions, baked.positions, "colour does not move samples");
    let grey = vvgen::scene::material::linear_to_srgb8(0.8);
    assert!(flat.colors.as_ref().unwrap().iter().all(|c| c[0] == grey));
    let lit: Vec<u8> = baked.colors.as_ref().unwrap().iter().map(|c| c[0]).collect();
    let mut sorted = lit.clone();
    sorted.sort_unstable();
    let median = sorted[sorted.len() / 2];
    assert!((150..250).contains(&median), "the open floor is lit, not saturated: {median}");
    // The man's shadow: samples far darker than the open floor, on the side the sun travels toward.
    let dark: Vec<[f32; 3]> = baked
        .positions
        .iter()
        .zip(&lit)
        .filter(|(_, &c)| (c as u32) * 100 < median as u32 * 80)
        .map(|(p, _)| *p)
        .collect();
    assert!(dark.len() > 20, "{} shadowed samples (median {median})", dark.len());
    let mean = dark.iter().fold([0.0f32; 2], |a, p| [a[0] + p[0], a[1] + p[1]]).map(|v| v / dark.len() as f32);
    assert!(mean[0] > 0.0 && mean[1] > 0.0, "the shadow falls toward +x, +y: {mean:?}");
    // Moving the sun re-bakes the lit cloud (and re-renders the lit pass), never the albedo one.
    let moved = build_in(d, &text.replace("[0.3, 0.2, -1]", "[-0.3, 0.2, -1]"));
    assert_eq!(moved.ran(Kind::PointFrame), 2, "two frames of the baked output");
    assert_eq!(moved.ran(Kind::RenderPass), 4);
}

/// A glTF point primitive (a grid of points facing up, with normals) whose material is shadeless
/// (`KHR_materials_unlit`) keeps its colour in lit point colours, as a shadeless triangle's points do; the same
/// points with an ordinary material are lit.
#[test]
fn a_shadeless_point_primitive_keeps_its_colour_in_lit_point_colours() {
    use vvgen::plan::actions::Kind;
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    write_hdr(&d.join("sky.hdr"), 64, 32);
    let mut bin: Vec<u8> = Vec::new();
    for i in 0..100 {
        for v in [(i % 10) as f32 * 0.1, (i / 10) as f32 * 0.1, 0.0] {
            bin.extend(v.to_le_bytes());
        }
    }
    for _ in 0..100 {
        for v in [0.0f32, 0.0, 1.0] {
            bin.extend(v.to_le_bytes());
        }
    }
    std::fs::write(d.join("grid.bin"), &bin).unwrap();
    let gltf = |unlit: bool| {
        let ext = if unlit { r#","extensions":{"KHR_materials_unlit":{}}"# } else { "" };
        let used = if unlit { r#""extensionsUsed":["KHR_materials_unlit"],"# } else { "" };
        format!(
            r#"{{"asset":{{"version":"2.0"}},{used}"scene":0,"scenes":[{{"nodes":[0]}}],"nodes":[{{"mesh":0}}],
            "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0,"NORMAL":1}},"mode":0,"material":0}}]}}],
            "materials":[{{"pbrMetallicRoughness":{{"baseColorFactor":[0.5,0.2,0.1,1]}}{ext}}}],
            "buffers":[{{"uri":"grid.bin","byteLength":2400}}],
            "bufferViews":[{{"buffer":0,"byteLength":1200}},{{"buffer":0,"byteOffset":1200,"byteLength":1200}}],
            "accessors":[{{"bufferView":0,"componentType":5126,"count":100,"type":"VEC3","min":[0,0,0],"max":[0.9,0.9,0]}},
            {{"bufferView":1,"componentType":5126,"count":100,"type":"VEC3"}}]}}"#
        )
    };
    let manifest = "[dataset]\nname = \"m\"\nout = \"out\"\npreview = false\n[source.grid]\ngltf = \"grid.gltf\"\n\
                    [render]\nresolution = [32, 32]\nshading = \"pbr\"\n[environment]\nmap = \"sky.hdr\"\n\
                    [light.sun]\nkind = \"sun\"\ndirection = [0.3, 0.2, -1]\nintensity = 3.0\n\
                    [rig.h]\nkind = \"hemisphere\"\n[split.train]\nrig = \"h\"\nviews = 1\n[output.d]\nwriter = \"dnerf\"\n\
                    [output.flat]\nwriter = \"ply-sequence\"\ndir = \"flat\"\npoints = 1\n\
                    [output.baked]\nwriter = \"ply-sequence\"\ndir = \"baked\"\npoints = 1\ncolor = \"lit\"\n";
    let colours = |name: &str| {
        let p = d.join(format!("out/{name}/m_0000.ply"));
        vvgen::scene::ply::read(&std::fs::read(&p).unwrap()).unwrap().colors.unwrap()
    };
    std::fs::write(d.join("grid.gltf"), gltf(false)).unwrap();
    build_in(d, manifest);
    let (flat, lit) = (colours("flat"), colours("baked"));
    assert_eq!(flat.len(), 100, "every point of the primitive");
    assert!(flat != lit, "ordinary points are lit");
    std::fs::write(d.join("grid.gltf"), gltf(true)).unwrap();
    let report = build_in(d, manifest);
    assert!(colours("flat") == flat && colours("baked") == flat, "shadeless points keep their colour");
    assert_eq!(report.ran(Kind::PointFrame), 2, "both clouds of the edited file re-run");
}

#[test]
fn lit_point_colours_read_the_environment_map_whatever_the_images_shading() {
    // The same lit cloud under `pbr` images and under unlit ones: both bake the manifest's map (before, unlit
    // images' clouds baked the built-in studio map, prefiltered inside the light action, and ignored the map).
    use vvgen::plan::actions::Kind;
    let dir = lit_project();
    let d = dir.path();
    let outputs = "[output.baked]\nwriter = \"ply-sequence\"\ndir = \"baked\"\npoints = 3000\ncolor = \"lit\"\n";
    let pbr = format!("{}{outputs}", lit_manifest(""));
    let unlit = pbr.replace("shading = \"pbr\"", "shading = \"unlit\"");
    assert_ne!(pbr, unlit);
    let read = || std::fs::read(d.join("out/baked/m_0000.ply")).unwrap();
    build_in(d, &pbr);
    let lit_images = read();
    let report = build_in(d, &unlit);
    assert_eq!(report.ran(Kind::Environment), 0, "the map's prefiltering is the pbr build's, cached");
    assert!(read() == lit_images, "the unlit images' cloud differs from the lit images' cloud");
}

#[test]
fn a_ground_plane_lights_what_stands_on_it_from_below() {
    // A sky of radiance 1 above the horizon, black below. Over a 0.8 ground, a white sphere's underside faces
    // the ground, which reflects L = 0.8·π/π = 0.8: a face looking straight down receives E = π·0.8 and shows
    // 0.8 (sRGB 231). Without the ground it faces the black half of the map.
    let (w, h) = (64u32, 32u32);
    let texels = (0..h).flat_map(|y| (0..w).map(move |_| Vec3::splat(if y < h / 2 { 1.0 } else { 0.0 }))).collect();
    let sky = EnvMap { width: w, height: h, texels };
    let plane = vvgen::scene::input::Ground { size: [6.0, 6.0], color: [0.8; 3], z: None };
    let ball = sphere(0.4, Vec3::new(0.0, 0.0, 1.0), lambert(1.0));
    let scene = merged(&[vvgen::scene::source::ground(&plane, 0.0), ball.clone()]);
    // From low beside the ball, looking up at its underside: the point whose normal leans 15° off straight down.
    let c = cam(96, 300.0, Camera::look_at(Vec3::new(2.0, 0.0, 0.35), Vec3::new(0.0, 0.0, 0.75), Vec3::Z));
    let n = Vec3::new(15f32.to_radians().sin(), 0.0, -15f32.to_radians().cos());
    let q = c.c2w.inverse().transform_point3((Vec3::new(0.0, 0.0, 1.0) + n * 0.4).as_dvec3());
    let (x, y) = ((c.cx + c.fx * q.x / -q.z) as u32, (c.cy - c.fy * q.y / -q.z) as u32);
    let grounded = rgb(&lit(&scene, &c, sky.clone(), 0.0, false, &[]), x, y);
    let alone = ball;
    let floating = rgb(&lit(&alone, &c, sky, 0.0, false, &[]), x, y);
    assert_eq!((grounded[3], floating[3]), (255, 255), "the point is on the ball");
    // π·0.8·(1 + cos 15°)/2 from the ground and a sliver of sky: about 0.8 linear.
    assert!((215..=240).contains(&grounded[0]), "lit from the ground: {grounded:?}");
    assert!(floating[0] < 90, "no ground, nothing from below: {floating:?}");
}

#[test]
fn the_ground_darkens_under_a_caster_in_the_environments_light_alone() {
    // The plane is two triangles; its occlusion is a grid over it. Under a uniform sky, the ground beside a ball
    // hovering 0.6 m over it sees about a tenth of its sky hidden (a 20° disk 60° up), far away none.
    let scene = ground_and_caster();
    let c = cam(128, 110.0, Camera::look_at(Vec3::new(0.0, -0.01, 6.0), Vec3::ZERO, Vec3::Y));
    let f = lit(&scene, &c, uniform(1.0), 0.0, false, &[]);
    let project = |p: Vec3| {
        let q = c.c2w.inverse().transform_point3(p.as_dvec3());
        ((c.cx + c.fx * q.x / -q.z) as u32, (c.cy - c.fy * q.y / -q.z) as u32)
    };
    let (nx, ny) = project(Vec3::new(0.6, 0.0, 0.0));
    let (fx, fy) = project(Vec3::new(-1.8, -1.8, 0.0));
    let (near, far) = (rgb(&f, nx, ny), rgb(&f, fx, fy));
    // Far from it: the ground's albedo 0.8 under radiance 1, 0.8 linear.
    let open = vvgen::scene::material::linear_to_srgb8(0.8);
    assert!(far[0].abs_diff(open) <= 2, "{far:?} vs {open}");
    assert!(near[0] + 6 < far[0] && near[0] > far[0] - 40, "{near:?} vs {far:?}");
    // Smooth across the grid: neighbouring pixels along the shadow's falloff differ by little.
    let row: Vec<u8> = (nx..nx + 12).map(|x| rgb(&f, x, ny)[0]).collect();
    assert!(row.windows(2).all(|w| w[0].abs_diff(w[1]) <= 3), "{row:?}");
}

/// Exposure is Blender's: the lit image's linear light times 2^stops. It keys the lit pass alone.
#[test]
fn exposure_scales_the_lit_light_and_re_renders_the_lit_pass_only() {
    use vvgen::plan::actions::Kind;
    let dir = lit_project();
    let d = dir.path();
    // Dim enough that one stop up saturates nothing.
    let dim = dim_lit_manifest();
    build_in(d, &dim);
    let read = |f: &str| dataset_image(d, f);
    let (base, albedo) = (read("train/r_0000.png"), read("albedo/train/r_0000.png"));
    let brighter = dim.replace("shading = \"pbr\"\n", "shading = \"pbr\"\nexposure = 1\n");
    let points = point_colours;
    let base_points = points(d);
    let r = build_in(d, &brighter);
    assert_eq!(
        (r.ran(Kind::RenderPass), r.ran(Kind::Environment), r.ran(Kind::Light)),
        (4, 0, 0),
        "the lit passes alone"
    );
    // Lit point colours are exposed too: where neither is clipped, one stop doubles their linear light.
    let lin8 = |v: u8| srgb8_to_linear(v) as f64;
    let after = points(d);
    let ratios: Vec<f64> = base_points
        .iter()
        .zip(&after)
        .filter(|(a, b)| a[0] > 60 && b[0] < 250)
        .map(|(a, b)| lin8(b[0]) / lin8(a[0]))
        .collect();
    assert!(ratios.len() > 100 && ratios.iter().all(|r| (r - 2.0).abs() < 0.1), "{} {:?}", ratios.len(), ratios);
    let (up, albedo_after) = (read("train/r_0000.png"), read("albedo/train/r_0000.png"));
    assert_eq!(albedo.as_raw(), albedo_after.as_raw());
    let lin = |v: u8| srgb8_to_linear(v) as f64;
    let (mut n, mut worst) = (0, 0.0f64);
    for (a, b) in base.pixels().zip(up.pixels()) {
        for c in 0..3 {
            // Opaque, unsaturated, and bright enough that 8-bit steps are small.
            if a[3] == 255 && a[c] > 40 && b[c] < 250 {
                worst = worst.max((lin(b[c]) / lin(a[c]) - 2.0).abs());
                n += 1;
            }
        }
    }
    assert!(n > 500 && worst < 0.06, "{n} channels, worst ratio off 2 by {worst}");
    // Back to none: the first build's images, from the cache.
    assert_eq!(build_in(d, &dim).ran(Kind::RenderPass), 0);
    assert_eq!(read("train/r_0000.png").as_raw(), base.as_raw());
}

#[test]
fn agx_view_shows_the_lit_light_through_blenders_curve_and_re_renders_the_lit_pass_only() {
    use vvgen::plan::actions::Kind;
    use vvgen::render::agx::Agx;
    let dir = lit_project();
    let d = dir.path();
    // Dim enough that the standard image clips little (its light is recovered from it below).
    let m = dim_lit_manifest();
    build_in(d, &m);
    let read = |f: &str| dataset_image(d, f);
    let points = point_colours;
    let (standard, albedo, standard_points) = (read("train/r_0000.png"), read("albedo/train/r_0000.png"), points(d));
    let agx = m.replace("shading = \"pbr\"\n", "shading = \"pbr\"\nview_transform = \"agx\"\n");
    let r = build_in(d, &agx);
    assert_eq!(
        (r.ran(Kind::RenderPass), r.ran(Kind::Environment), r.ran(Kind::Light)),
        (4, 0, 0),
        "the lit passes alone"
    );
    let (shown, albedo_after) = (read("train/r_0000.png"), read("albedo/train/r_0000.png"));
    assert_eq!(albedo.as_raw(), albedo_after.as_raw());
    // Each opaque pixel is the standard one's light through AgX, give or take the 8-bit steps of the standard
    // image it is recovered from (a code where the curve is steep; more where light was clipped at 1).
    let lin = srgb8_to_linear;
    let code = |v: f32| 255.0 * linear_to_srgb(v);
    let (mut n, mut worst, mut moved) = (0, 0f32, 0);
    for (a, b) in standard.pixels().zip(shown.pixels()) {
        if a[3] != 255 || a.0[..3].iter().any(|c| !(30..=250).contains(c)) {
            continue;
        }
        let want = Agx::get().display(glam::Vec3::new(lin(a[0]), lin(a[1]), lin(a[2])));
        for c in 0..3 {
            worst = worst.max((code(want.to_array()[c]) - b[c] as f32).abs());
        }
        moved += (a.0[..3] != b.0[..3]) as u32;
        n += 1;
    }
    assert!(n > 500 && worst <= 2.5, "{n} pixels, worst {worst} codes");
    assert!(moved * 2 > n, "AgX changed only {moved} of {n} pixels");
    // Lit point colours go through the same view.
    let agx_points = points(d);
    let (mut m, mut off) = (0, 0f32);
    for (a, b) in standard_points.iter().zip(&agx_points) {
        if a[..3].iter().all(|&c| c > 30 && c < 250) {
            let want = Agx::get().display(glam::Vec3::new(lin(a[0]), lin(a[1]), lin(a[2])));
            off = off.max((0..3).map(|c| (code(want.to_array()[c]) - b[c] as f32).abs()).fold(0.0, f32::max));
            m += 1;
        }
    }
    assert!(m > 100 && off <= 2.5, "{m} points, worst {off} codes");
    // Back to the standard view: the first build's bytes, from the cache.
    assert_eq!(build_in(d, &m_standard(&agx)).ran(Kind::RenderPass), 0);
    assert_eq!(read("train/r_0000.png").as_raw(), standard.as_raw());
}

/// `m` with its view transform removed.
fn m_standard(m: &str) -> String {
    m.replace("view_transform = \"agx\"\n", "")
}

/// [`lit_manifest`] dimmed (a sun of 0.3, the map at 0.15) so that its images clip little, with lit point
/// colours beside them.
fn dim_lit_manifest() -> String {
    lit_manifest("")
        .replace("intensity = 2.0", "intensity = 0.3")
        .replace("map = \"sky.hdr\"\n", "map = \"sky.hdr\"\nstrength = 0.15\n")
        + "[output.pts]\nwriter = \"ply-sequence\"\npoints = 3000\ncolor = \"lit\"\n"
}

/// Image `f` of the D-NeRF dataset built in `d`.
fn dataset_image(d: &Path, f: &str) -> image::RgbaImage {
    image::open(d.join("out/m_dnerf").join(f)).unwrap().into_rgba8()
}

/// The lit point colours of frame 0 built in `d`.
fn point_colours(d: &Path) -> Vec<[u8; 4]> {
    vvgen::scene::ply::read_file(&d.join("out/m_points/m_0000.ply")).unwrap().colors.unwrap()
}

#[test]
fn lit_points_on_the_ground_are_the_colour_its_pixels_are() {
    // The same frame in both representations: a lit point cloud's ground points read the frame's light action
    // as the lit images do, so each has the colour of the lit pixel it projects into (where that pixel sees the
    // ground all over), whether the cloud samples the whole frame or the floor alone. Lit points once prepared
    // their own light without the subject's gathered bounce.
    let dir = lit_project();
    let d = dir.path();
    let floor_only = "[output.floor]\nwriter = \"ply-sequence\"\ndir = \"floor\"\nsource = \"floor\"\npoints = 3000\n\
                      color = \"lit\"\n";
    let text = dim_lit_manifest().replace("resolution = [48, 48]", "resolution = [128, 128]") + floor_only;
    build_in(d, &text);
    let meta: serde_json::Value =
        serde_json::from_slice(&std::fs::read(d.join("out/m_dnerf/transforms_train.json")).unwrap()).unwrap();
    let fov = meta["camera_angle_x"].as_f64().unwrap();
    for ply in ["out/m_points/m_0000.ply", "out/floor/m_0000.ply"] {
        let cloud = vvgen::scene::ply::read_file(&d.join(ply)).unwrap();
        let (normals, colours) = (cloud.normals.unwrap(), cloud.colors.unwrap());
        let (mut diffs, mut seen) = (Vec::new(), 0);
        for frame in meta["frames"].as_array().unwrap().iter().filter(|f| f["time"].as_f64() == Some(0.0)) {
            let name = frame["file_path"].as_str().unwrap().trim_start_matches("./");
            let lit = dataset_image(d, &format!("{name}.png"));
            let albedo = dataset_image(d, &format!("albedo/{name}.png"));
            let rows = frame["transform_matrix"].as_array().unwrap();
            let m: Vec<f64> =
                rows.iter().flat_map(|r| r.as_array().unwrap().iter().map(|v| v.as_f64().unwrap())).collect();
            let w2c = DMat4::from_cols_array(&m.try_into().unwrap()).transpose().inverse();
            let (w, h) = (lit.width() as f64, lit.height() as f64);
            let f = 0.5 * w / (0.5 * fov).tan();
            let floor = albedo.get_pixel(0, h as u32 - 1).0;
            for ((p, n), c) in cloud.positions.iter().zip(&normals).zip(&colours) {
                if n[2] < 0.99 {
                    continue; // the ground's top alone
                }
                let q = w2c.transform_point3(glam::DVec3::new(p[0] as f64, p[1] as f64, p[2] as f64));
                let (x, y) = (0.5 * w + f * q.x / -q.z, 0.5 * h - f * q.y / -q.z);
                let (px, py) = (x.floor() as i64, y.floor() as i64);
                if q.z >= 0.0 || px < 1 || py < 1 || px + 1 >= w as i64 || py + 1 >= h as i64 {
                    continue;
                }
                // The pixel and its neighbours show the ground alone (the floor's albedo, opaque).
                let open = (-1..=1)
                    .all(|dy| (-1..=1).all(|dx| albedo.get_pixel((px + dx) as u32, (py + dy) as u32).0 == floor));
                if !open {
                    continue;
                }
                seen += 1;
                let pixel = lit.get_pixel(px as u32, py as u32).0;
                diffs.push((0..3).map(|k| (pixel[k] as i32 - c[k] as i32).abs()).max().unwrap());
            }
        }
        diffs.sort_unstable();
        let (median, p95) = (diffs[diffs.len() / 2], diffs[diffs.len() * 95 / 100]);
        assert!(seen > 300, "{ply}: {seen} ground points seen");
        // (The light prepared apart, without the subject's bounce onto the ground: 1 and 2.)
        assert!(median == 0 && p95 <= 1, "{ply}: a point's colour off its pixel's by {median} (median), {p95} (95th)");
    }
}

/// `s` turned inside out: every triangle wound the other way, every normal reversed (VCG's horse is stored so).
fn inside_out(mut s: PosedScene) -> PosedScene {
    for p in &mut s.primitives {
        p.normals.iter_mut().for_each(|n| *n = -*n);
        p.indices = Arc::new(p.indices.chunks_exact(3).flat_map(|t| [t[0], t[2], t[1]]).collect());
    }
    s
}

/// A two-sided mesh stored inside out (the scan's winding and normals point in) is lit as the same mesh right
/// side out, as Cycles lights it (it turns a back face's normal to the eye): the sides a camera sees gather their
/// own light, the environment's and what the other sphere reflects onto them. Lit by what their inward normals
/// saw, the mesh's own inside, they rendered dark: VCG's horse by 20 %, 12–14 dB from Cycles 4.5 (now 34–36 dB).
#[test]
fn an_inside_out_two_sided_mesh_is_lit_as_the_same_mesh_right_side_out() {
    let two_sided = Material { double_sided: true, ..lambert(0.8) };
    let pair = |turn: bool| {
        let s = [sphere(0.5, Vec3::ZERO, two_sided.clone()), sphere(0.5, Vec3::new(1.1, 0.0, 0.0), two_sided.clone())];
        merged(&s.map(|s| if turn { inside_out(s) } else { s }))
    };
    let sun = Light {
        kind: LightKind::Sun { direction: Vec3::new(-1.0, 0.2, -0.5).normalize(), angle: 0.01 },
        color: Vec3::ONE,
        intensity: 2.0,
        shadows: true,
    };
    let c = cam(96, 190.0, Camera::look_at(Vec3::new(0.55, -4.0, 1.5), Vec3::new(0.55, 0.0, 0.0), Vec3::Z));
    let right = lit(&pair(false), &c, bright_toward_x(), 30.0, false, std::slice::from_ref(&sun));
    let turned = lit(&pair(true), &c, bright_toward_x(), 30.0, false, std::slice::from_ref(&sun));
    let (mut worst, mut sum, mut covered) = (0u8, 0u32, 0);
    for y in 0..96 {
        for x in 0..96 {
            let (a, b) = (rgb(&right, x, y), rgb(&turned, x, y));
            assert_eq!(a[3], b[3], "coverage at ({x}, {y})");
            if a[3] == 255 {
                covered += 1;
                let d = (0..3).map(|k| a[k].abs_diff(b[k])).max().unwrap();
                (worst, sum) = (worst.max(d), sum + d as u32);
            }
        }
    }
    // The same pixels: a back side gathers with its front side's rays, turned about the other way.
    assert!(covered > 2500 && worst == 0, "{covered} pixels, {sum} levels apart in all, worst {worst}");
    // The spheres light each other (what the turned ones read from their back sides): facing each other, a
    // sphere's side gathers a bounce.
    let env = Environment { map: None, strength: 1.0, rotation_deg: 30.0, visible: false };
    let light_of = |scene: &PosedScene| {
        let map = bright_toward_x();
        let env = env.with(Arc::new(prefilter(&map)), Some(Arc::new(map)));
        FrameLight::prepare(scene, std::slice::from_ref(&sun), env, vvgen::render::light::PointCasters::NONE)
            .with_bounce(scene)
    };
    let (scene, light) = (pair(true), light_of(&pair(true)));
    let n = scene.primitives[0].positions.len();
    let facing =
        (0..n).max_by(|&a, &b| scene.primitives[0].positions[a].x.total_cmp(&scene.primitives[0].positions[b].x));
    let back = light.vertex_visibility[0][n + facing.unwrap()];
    assert!(light.vertex_visibility[0].len() == 2 * n && back.bounce.x > 0.01, "{back:?}");
    // A lit point colour on it takes the side the world sees: the outside, as on the sphere right side out.
    let (right, right_light) = (pair(false), light_of(&pair(false)));
    for t in (0..200).map(|t| t * 37) {
        let bake = |s: &PosedScene, l: &FrameLight| {
            let c: [u32; 3] = std::array::from_fn(|k| s.primitives[0].indices[3 * t + k]);
            let p = c.iter().map(|&i| s.primitives[0].positions[i as usize]).sum::<Vec3>() / 3.0;
            let nrm = c.iter().map(|&i| s.primitives[0].normals[i as usize]).sum::<Vec3>().normalize();
            l.bake_on(s, 0, c, [1.0 / 3.0; 3], p, nrm, Vec3::splat(0.8), Vec3::ZERO)
        };
        // (Its corners in another order: the blend sums them so.)
        let (a, b) = (bake(&scene, &light), bake(&right, &right_light));
        assert!((a - b).abs().max_element() < 1e-5, "triangle {t}: {a} vs {b}");
    }
}
