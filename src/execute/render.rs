//! Image actions: render passes and composites. Each frame is posed once and shared by every view of that
//! frame; views render and encode in parallel (PNG encoding costs as much as rendering, so it must not
//! serialize on one thread). One render serves every pass of an image that must run.

use std::collections::BTreeMap;

use glam::Vec3;
use rayon::prelude::*;

use super::{Error, Inputs, Made};
use crate::cache::Digest;
use crate::manifest::render::Pass;
use crate::plan::actions::Action;
use crate::plan::graph::{ActionId, Graph};
use crate::render::encode::{self, Encoding, NormalSpace};
use crate::render::light::environment::{self, EnvMap, Prefiltered};
use crate::render::light::{EnvLight, FrameLight, Gathered, GatheredError, PointCasters};
use crate::render::{self, Frame, RenderSettings, Shading};
use crate::scene::Poser;
use std::sync::Arc;

/// Runs the environment action: reads the map (the built-in studio map when the manifest names none) and
/// prefilters it.
pub(super) fn environment(g: &Graph, x: &Inputs, ids: &[ActionId], done: &(dyn Fn() + Sync)) -> Result<Made, Error> {
    x.each(g, ids, done, |id| Ok(environment::prefilter(&load_map(g, x, id)?).encode()))
}

/// The environment map: the manifest's, or the built-in studio map.
fn load_map(g: &Graph, x: &Inputs, id: ActionId) -> Result<EnvMap, Error> {
    if g.keying.render.lighting.environment.map.is_none() {
        return Ok(environment::studio());
    }
    let label = || g.node(id).label.clone();
    let path =
        x.environment.ok_or_else(|| Error::Content { action: label(), message: "BUG: no environment map".into() })?;
    environment::load(path).map_err(|source| Error::Environment { action: label(), source })
}

/// The environment lit renders read: the prefiltered map from the environment action (the dep of their frames'
/// light actions: the manifest's map or the built-in studio map, prefiltered by that action), with the map itself
/// when it is the visible background; `None` when no pass of `ids` renders lit (no light action among their deps).
fn env_light(
    g: &Graph,
    x: &Inputs,
    blobs: &[Option<Vec<Digest>>],
    ids: &[ActionId],
) -> Result<Option<EnvLight>, Error> {
    if g.keying.render.shading != Shading::Pbr {
        return Ok(None);
    }
    let Some(light) = ids.iter().find_map(|&id| g.node(id).deps.first().copied()) else { return Ok(None) };
    let visible = g.keying.render.lighting.environment.visible;
    environment_light(g, x, blobs, light, visible).map(Some)
}

/// Runs the light actions `ids`: per frame, the lights and environment prepared at the vertices and over the
/// ground, and what the subject reflects gathered ([`FrameLight::gather`]), kept for every lit view of the frame.
pub(super) fn lights(
    g: &Graph,
    x: &Inputs,
    blobs: &[Option<Vec<Digest>>],
    ids: &[ActionId],
    done: &(dyn Fn() + Sync),
) -> Result<Made, Error> {
    let Some(&first) = ids.first() else { return Ok(Vec::new()) };
    let env = environment_light(g, x, blobs, first, false)?;
    // Frames side by side: a frame's preparation has parts on one thread (a sun's map, the gather's tree), which
    // another frame's fill. Each result depends on its frame alone.
    ids.par_iter()
        .filter_map(|&id| match g.node(id).action {
            Action::Light { frame } => Some((id, frame)),
            _ => None,
        })
        .map_init(Poser::default, |poser, (id, frame)| {
            let label = &g.node(id).label;
            let posed = x.scene.pose(frame, poser).map_err(|source| Error::Scene { action: label.clone(), source })?;
            super::check_posed(posed, label)?;
            let casters = PointCasters::of(&g.keying.render.splat);
            let gathered =
                FrameLight::prepare(posed, &g.keying.render.lighting.lights, env.clone(), casters).gather(posed);
            let stored = x.store(g, id, &[gathered.encode()])?;
            done();
            Ok((id, stored))
        })
        .collect()
}

/// The environment as light action `light_id` reads it: the prefiltered map of its environment action (its
/// first dep, planned for every light action, the built-in studio map's too), with the full map as the
/// `background` when asked (read again only for that). A light action planned without one is an error, not a
/// studio map prefiltered here: that would be work no action keys.
pub(super) fn environment_light(
    g: &Graph,
    x: &Inputs,
    blobs: &[Option<Vec<Digest>>],
    light_id: ActionId,
    background: bool,
) -> Result<EnvLight, Error> {
    let light = g.node(light_id);
    let env_id =
        light.deps.first().copied().filter(|&id| g.node(id).action == Action::Environment).ok_or_else(|| {
            Error::Content { action: light.label.clone(), message: "BUG: no environment action".into() }
        })?;
    let label = g.node(env_id).label.clone();
    let pre = Prefiltered::decode(&x.read(g, blobs, env_id, 0)?)
        .map_err(|source| Error::Environment { action: label.clone(), source })?;
    let map = if background { Some(Arc::new(load_map(g, x, env_id)?)) } else { None };
    Ok(g.keying.render.lighting.environment.with(Arc::new(pre), map))
}

/// Runs the render-pass actions `ids`.
pub(super) fn passes(
    g: &Graph,
    x: &Inputs,
    blobs: &[Option<Vec<Digest>>],
    ids: &[ActionId],
    done: &(dyn Fn() + Sync),
) -> Result<Made, Error> {
    let plan = g.keying.plan;
    let env = env_light(g, x, blobs, ids)?;
    let albedo_settings = RenderSettings { shading: render::Shading::Unlit, ..g.keying.render.clone() };
    // Frame → image → its passes to run.
    let mut by_frame: BTreeMap<usize, BTreeMap<usize, Vec<(ActionId, Pass)>>> = BTreeMap::new();
    for &id in ids {
        if let Action::RenderPass { image, pass } = g.node(id).action {
            by_frame.entry(plan.images[image].frame).or_default().entry(image).or_default().push((id, pass));
        }
    }
    let mut poser = Poser::default();
    let mut out = Vec::with_capacity(ids.len());
    for (frame, images) in by_frame {
        let first = images.values().next().and_then(|v| v.first()).map(|(id, _)| *id);
        let label = first.map_or_else(String::new, |id| g.node(id).label.clone());
        let posed = x.scene.pose(frame, &mut poser).map_err(|source| Error::Scene { action: label.clone(), source })?;
        super::check_posed(posed, &label)?;
        let images: Vec<(usize, Vec<(ActionId, Pass)>)> = images.into_iter().collect();
        // The lights' shadow maps, once for every view of the frame that renders lit, beside what its light action
        // found (the vertices' and the ground's light, the bounce).
        let gathered = images.iter().flat_map(|(_, todo)| todo).find_map(|(id, _)| g.node(*id).deps.first().copied());
        let light = match (&env, gathered) {
            (Some(env), Some(light_id)) => {
                let content = |e: GatheredError| Error::Content { action: label.clone(), message: e.to_string() };
                let gathered = Gathered::decode(&x.read(g, blobs, light_id, 0)?).map_err(content)?;
                let casters = PointCasters::of(&g.keying.render.splat);
                let light =
                    FrameLight::from_gathered(posed, &g.keying.render.lighting.lights, env.clone(), casters, gathered)
                        .map_err(content)?;
                Some(light.with_exposure(g.keying.render.lighting.exposure))
            }
            _ => None,
        };
        let made: Vec<Result<Made, Error>> = images
            .par_iter()
            .map(|(image, todo)| {
                let camera = &plan.images[*image].camera;
                let f = needs_main(todo).then(|| render::render_lit(posed, camera, &g.keying.render, light.as_ref()));
                // The albedo pass is the unlit image: its own render when the main one is lit.
                let albedo = todo.iter().any(|(_, p)| *p == Pass::Albedo).then(|| match &f {
                    Some(f) if g.keying.render.shading == render::Shading::Unlit => f.clone(),
                    _ => render::render(posed, camera, &albedo_settings),
                });
                let mut v = Vec::with_capacity(todo.len());
                for &(id, pass) in todo {
                    let frame = match (pass, &f, &albedo) {
                        (Pass::Albedo, _, Some(a)) => a,
                        (_, Some(f), _) => f,
                        _ => unreachable!("a frame is rendered for every pass asked"),
                    };
                    let bytes = encode_pass(frame, pass, &g.keying.encoding, &camera.c2w);
                    v.push((id, x.store(g, id, &bytes)?));
                    done();
                }
                Ok(v)
            })
            .collect();
        for m in made {
            out.extend(m?);
        }
    }
    Ok(out)
}

/// Whether an image's passes need its main render (every pass but albedo reads it).
fn needs_main(todo: &[(ActionId, Pass)]) -> bool {
    todo.iter().any(|(_, p)| *p != Pass::Albedo)
}

/// Runs the composite actions `ids`: the RGBA blob over an opaque background (sRGB bytes, as loaders
/// composite), as an RGB PNG, for consumers that do not read alpha (COLMAP, DyNeRF).
pub(super) fn composites(
    g: &Graph,
    x: &Inputs,
    blobs: &[Option<Vec<Digest>>],
    ids: &[ActionId],
    done: &(dyn Fn() + Sync),
) -> Result<Made, Error> {
    x.each(g, ids, done, |id| {
        let n = g.node(id);
        let Action::Composite { background: bg, .. } = n.action else { unreachable!("a composite") };
        let png = x.read(g, blobs, n.deps[0], 0)?;
        let damaged = |e: image::ImageError| Error::Content { action: n.label.clone(), message: e.to_string() };
        let img = image::load_from_memory_with_format(&png, image::ImageFormat::Png).map_err(damaged)?.into_rgba8();
        let (w, h) = img.dimensions();
        let rgb: Vec<u8> = img
            .pixels()
            .flat_map(|p| {
                let a = p[3] as u32;
                [0, 1, 2].map(|k| ((p[k] as u32 * a + bg[k] as u32 * (255 - a) + 127) / 255) as u8)
            })
            .collect();
        Ok(encode::rgb_png(&rgb, w, h, g.keying.encoding.png))
    })
}

/// The files of one pass: its PNG, then its EXR (depth, normal) where asked.
fn encode_pass(f: &Frame, pass: Pass, e: &Encoding, c2w: &glam::DMat4) -> Vec<Vec<u8>> {
    let (w, h, c) = (f.width, f.height, e.png);
    match pass {
        Pass::Rgba | Pass::Albedo => vec![encode::rgba_png(&f.rgba, w, h, c)],
        Pass::Depth => {
            let mut v = vec![encode::depth_mm_png(&f.depth, w, h, c)];
            if e.depth_exr {
                v.push(encode::f32_exr(&[("Y", &f.depth)], w, h, c));
            }
            v
        }
        Pass::Normal => {
            // Camera space: the inverse rotation of the (orthonormal) camera-to-world.
            let rot = glam::DMat3::from_mat4(*c2w).transpose().as_mat3();
            let normals: Vec<Vec3> = match e.normal_space {
                NormalSpace::Camera => f.normal.iter().map(|n| rot * *n).collect(),
                NormalSpace::World => f.normal.clone(),
            };
            let rgb: Vec<u8> = normals
                .iter()
                .flat_map(|n| {
                    if *n == Vec3::ZERO {
                        return [0, 0, 0];
                    }
                    n.to_array().map(|v| ((v + 1.0) * 0.5 * 255.0).round().clamp(0.0, 255.0) as u8)
                })
                .collect();
            let mut v = vec![encode::rgb_png(&rgb, w, h, c)];
            if e.normal_exr {
                let axis = |i: usize| normals.iter().map(|n| n[i]).collect::<Vec<f32>>();
                let (nx, ny, nz) = (axis(0), axis(1), axis(2));
                v.push(encode::f32_exr(&[("R", &nx), ("G", &ny), ("B", &nz)], w, h, c));
            }
            v
        }
        Pass::Mask => vec![encode::gray8_png(&f.coverage, w, h, c)],
        Pass::Instance => {
            let ids: Vec<u16> = f.object.iter().map(|&o| o.min(u16::MAX as u32) as u16).collect();
            vec![encode::gray16_png(&ids, w, h, c)]
        }
    }
}
