//! From the manifest's declarations to what the stages take: the renderer's settings, its encoding, its lights
//! and environment, the checks of the inputs only the renderer's readers can make (an environment map's header),
//! and the scene's request ([`scene`]).
//!
//! This is the step between `manifest` (TOML → checked declarations, depending on nothing above it) and the
//! stages that know nothing of manifests (`scene`, `render`): the planner, the CLI and the benches call it,
//! `check` and `build` raise what [`diagnose`] finds.

pub mod scene;

use crate::manifest::light::{Light, LightKind, SUN_ANGLE};
use crate::manifest::render::{
    Background, DepthKind, NormalSpace, Pass, PixelFilter, PngCompression, Render, Shading, SplatShape,
    DEFAULT_FILTER_WIDTH, MAX_FILTER_WIDTH,
};
use crate::manifest::{Diagnostic, Manifest};
use crate::render::light as rl;
use crate::render::{self, encode};
use crate::scene::material::srgb_to_linear;

// The manifest refuses what the renderer would clamp.
const _: () = assert!(MAX_FILTER_WIDTH as f32 == render::filter::MAX_WIDTH);

/// The renderer's settings for `[render]`, without lighting (see [`lighting`]). `voxel` is the world size of one
/// voxel of a point-cloud source, the default splat size; without it, splats default to 1.5 px.
pub fn renderer(r: &Render, voxel: Option<f32>) -> render::RenderSettings {
    use render::{SplatShape as S, SplatSize};
    let lin = |c: [f64; 3]| {
        glam::Vec3::new(srgb_to_linear(c[0] as f32), srgb_to_linear(c[1] as f32), srgb_to_linear(c[2] as f32))
    };
    let background = match r.background.as_ref().map(|b| b.get_ref()) {
        Some(Background::Named(n)) if n == "white" => Some(glam::Vec3::ONE),
        Some(Background::Named(n)) if n == "black" => Some(glam::Vec3::ZERO),
        Some(Background::Rgb(c)) => Some(lin(*c)),
        _ => None,
    };
    let size = match (r.splat.size, r.splat.size_px, voxel) {
        (Some(w), _, _) => SplatSize::World(w as f32),
        (None, Some(px), _) => SplatSize::Pixels(px as f32),
        (None, None, Some(v)) => SplatSize::World(v),
        (None, None, None) => SplatSize::Pixels(1.5),
    };
    let shape = match r.splat.shape {
        SplatShape::Cube => S::Cube,
        SplatShape::Square => S::Square,
        SplatShape::Disk => S::Disk,
        SplatShape::Surfel => S::Surfel,
    };
    render::RenderSettings {
        samples: *r.samples.get_ref(),
        filter: match r.filter {
            PixelFilter::Box => render::PixelFilter::Box,
            PixelFilter::BlackmanHarris => render::PixelFilter::BlackmanHarris {
                width: r.filter_width.as_ref().map_or(DEFAULT_FILTER_WIDTH, |w| *w.get_ref()) as f32,
            },
        },
        shading: match r.shading {
            Shading::Unlit => render::Shading::Unlit,
            Shading::Lambert => render::Shading::Lambert,
            Shading::Pbr => render::Shading::Pbr,
        },
        // Filled in by the caller, which knows the manifest's lights and the environment map's content key.
        lighting: render::Lighting::default(),
        lights: r.lights.iter().map(|l| (glam::DVec3::from(l.direction).as_vec3(), l.intensity as f32)).collect(),
        ambient: r.ambient.unwrap_or(0.3) as f32,
        background,
        depth: match r.depth.kind {
            DepthKind::Planar => render::DepthKind::Planar,
            DepthKind::Ray => render::DepthKind::Ray,
        },
        splat: render::SplatSettings { shape, size, min_px: r.splat.min_px.unwrap_or(1.0) as f32 },
        buffers: render::Buffers {
            depth: r.has_pass(Pass::Depth),
            normal: r.has_pass(Pass::Normal),
            object: r.has_pass(Pass::Instance),
        },
    }
}

/// How `[render]` encodes its passes.
pub fn encoding(r: &Render) -> encode::Encoding {
    encode::Encoding {
        png: match r.png_compression {
            PngCompression::Fast => encode::PngCompression::Fast,
            PngCompression::Default => encode::PngCompression::Default,
            PngCompression::Best => encode::PngCompression::Best,
        },
        normal_space: match r.normal.space {
            NormalSpace::World => encode::NormalSpace::World,
            NormalSpace::Camera => encode::NormalSpace::Camera,
        },
        depth_exr: r.depth.exr,
        normal_exr: r.normal.exr,
    }
}

/// The renderer's light for a `[light.NAME]`.
pub fn light(l: &Light) -> rl::Light {
    let v = |a: [f64; 3]| glam::DVec3::from(a).as_vec3();
    let kind = match l.kind.get_ref() {
        LightKind::Sun => rl::LightKind::Sun {
            direction: v(l.direction.as_ref().map_or([0.0, 0.0, -1.0], |d| *d.get_ref()))
                .normalize_or(glam::Vec3::NEG_Z),
            angle: l.angle_deg.as_ref().map_or(SUN_ANGLE, |a| *a.get_ref()).to_radians() as f32,
        },
        LightKind::Point => rl::LightKind::Point {
            position: v(l.position.as_ref().map_or([0.0; 3], |p| *p.get_ref())),
            radius: l.radius.as_ref().map_or(0.1, |r| *r.get_ref()) as f32,
        },
        LightKind::Spot => {
            let position = v(l.position.as_ref().map_or([0.0; 3], |p| *p.get_ref()));
            let target = v(l.target.as_ref().map_or([0.0; 3], |t| *t.get_ref()));
            rl::LightKind::Spot {
                position,
                direction: (target - position).normalize_or(glam::Vec3::NEG_Z),
                cone: l.cone_deg.as_ref().map_or(45.0, |c| *c.get_ref()).to_radians() as f32,
                blend: l.blend.as_ref().map_or(0.15, |b| *b.get_ref()) as f32,
                radius: l.radius.as_ref().map_or(0.1, |r| *r.get_ref()) as f32,
            }
        }
    };
    rl::Light { kind, color: v(*l.color.get_ref()), intensity: *l.intensity.get_ref() as f32, shadows: l.shadows }
}

/// The renderer's lighting for `m`: its lights, and its environment, the map named by its content key
/// (`environment`).
pub fn lighting(m: &Manifest, environment: Option<crate::cache::Digest>) -> render::Lighting {
    let e = m.environment.as_ref();
    render::Lighting {
        lights: m.lights.values().map(light).collect(),
        environment: render::Environment {
            map: environment.map(|d| d.hex()),
            strength: e.map_or(1.0, |e| e.strength()) as f32,
            rotation_deg: e.map_or(0.0, |e| e.rotation_deg) as f32,
            visible: e.is_some_and(|e| e.visible),
        },
        exposure: m.render.exposure() as f32,
        view: match m.render.view_transform() {
            crate::manifest::render::ViewTransform::Standard => render::ViewTransform::Standard,
            crate::manifest::render::ViewTransform::Agx => render::ViewTransform::Agx,
        },
    }
}

/// What only the renderer's readers can say of `m`'s inputs, at the manifest's places: an `[environment] map`
/// that is not a format vvgen reads, is missing, or whose header does not parse. `check` and `build` both raise
/// them before anything renders.
pub fn diagnose(m: &Manifest) -> Vec<Diagnostic> {
    let mut diags = Vec::new();
    let Some(map) = m.environment.as_ref().and_then(|e| e.map.as_ref()) else { return diags };
    let path = m.resolve(map.get_ref());
    if !rl::environment::is_map_path(&path) {
        diags.push(
            Diagnostic::error(format!("`{}` is not an environment map vvgen reads", map.get_ref()), Some(map.span()))
                .with_help("use an equirectangular `.hdr` (Radiance) or `.exr` (OpenEXR) file"),
        );
    } else if !path.is_file() {
        diags.push(
            Diagnostic::error(format!("file not found: {}", path.display()), Some(map.span()))
                .with_help("paths are relative to the manifest's folder"),
        );
    } else if let Err(e) = rl::environment::header(&path) {
        diags.push(Diagnostic::error(format!("environment map: {e}"), Some(map.span())));
    }
    diags
}

/// [`crate::manifest::load`] with [`diagnose`]'s findings added to its report: what `check` and the CLI load
/// manifests with. An error among them makes the manifest invalid, as a parse error does.
pub fn load(path: &std::path::Path) -> Result<(Manifest, crate::manifest::Report), crate::manifest::Report> {
    let (m, mut report) = crate::manifest::load(path)?;
    report.diagnostics.extend(diagnose(&m));
    if report.error_count() > 0 {
        return Err(report);
    }
    Ok((m, report))
}
