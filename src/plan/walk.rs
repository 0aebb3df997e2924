//! The keyed walk of each action: exactly the fields that determine its bytes, written once into a
//! [`KeyWriter`] (the hasher for keys, the explainer for `plan --explain`).
//!
//! Settings are walked by destructuring, without `..`: a field added to [`RenderSettings`], [`Encoding`],
//! [`Camera`] or [`PointSettings`] fails to compile here until it is keyed or excluded with a reason.

use super::actions::{
    pass_name, rig_subject_frame, Action, PointSettings, ENCODE_SALT, LIT_SALT, RENDER_SALT, SAMPLE_SALT, SELECTION,
    VIDEO_SALT,
};
use super::key::KeyWriter;
use super::Plan;
use crate::cache::Digest;
use crate::camera::Camera;
use crate::manifest::output::{ColorAverage, PlyFormat, PointColor, Reduce, VoxelPosition};
use crate::manifest::render::Pass;
use crate::render::encode::{Encoding, NormalSpace, PngCompression};
use crate::render::{DepthKind, PixelFilter, RenderSettings, Shading, SplatShape, SplatSize};

/// Everything besides the action itself that keys read.
#[derive(Debug)]
pub struct Keying<'a> {
    /// The image plan.
    pub plan: &'a Plan,
    /// The content key of every scene frame.
    pub frame_keys: &'a [Digest],
    /// The key of the lights the sources bring at every frame, when they bring any (read by lit passes only).
    pub frame_lights: &'a [Option<Digest>],
    /// What only lit shading reads of every frame besides its content ([`super::keys::FrameKeys::lit`]).
    pub frame_lit: &'a [Option<Digest>],
    /// Whether every frame has shadeless point primitives ([`super::keys::FrameKeys::shadeless_points`]).
    pub frame_shadeless_points: &'a [bool],
    /// Whether every frame has glossy transparent surfaces ([`super::keys::FrameKeys::glossy_glass`]).
    pub frame_glossy_glass: &'a [bool],
    /// Whether every frame has points that may cast shadows ([`super::keys::FrameKeys::point_casters`]).
    pub frame_point_casters: &'a [bool],
    /// Whether every frame has two-sided triangles ([`super::keys::FrameKeys::two_sided`]).
    pub frame_two_sided: &'a [bool],
    /// The renderer's settings.
    pub render: RenderSettings,
    /// How passes are encoded.
    pub encoding: Encoding,
    /// `[dataset] seed`.
    pub seed: u64,
    /// blake3 of the manifest text (an output's `vvgen/dataset.json` records it).
    pub manifest: Digest,
    /// `[dataset] name` (previews are titled with it).
    pub dataset: String,
    /// The frame rate of videos, in thousandths of a frame per second (an integer, so it keys exactly): the first
    /// source's `fps` over its `step` (the sources of a scene share one time axis; its frames lie `step / fps`
    /// seconds apart), 30 without one.
    pub video_fps_milli: u64,
    /// Resolved settings of every `ply-sequence` output, by name.
    pub points: std::collections::BTreeMap<String, PointSettings>,
}

impl Action {
    /// Writes every field that determines this action's result; `deps` are the keys of its inputs, in the
    /// order [`Action`] documents.
    pub fn walk(&self, cx: &Keying, deps: &[Digest], w: &mut dyn KeyWriter) {
        match self {
            Action::Environment => {
                w.str("prefilter", crate::render::light::environment::SALT);
                let studio = crate::render::light::environment::STUDIO;
                w.str("map content", cx.render.lighting.environment.map.as_deref().unwrap_or(studio));
            }
            Action::Light { frame } => {
                // What the gather reads: the posed frame, its materials and lights, the manifest's lights and the
                // environment. Not the cameras, the image settings, exposure or the view transform, which shape
                // only the pixels.
                w.str("lit shading", LIT_SALT);
                w.digest("frame content", &cx.frame_keys[*frame]);
                light_fields(w, &cx.render.lighting);
                if let Some(lit) = &cx.frame_lit[*frame] {
                    w.digest("lit materials", lit);
                }
                if let Some(lights) = &cx.frame_lights[*frame] {
                    w.digest("file lights", lights);
                }
                if cx.frame_point_casters.get(*frame) == Some(&true) {
                    // Its points cast as the images draw them: the splats' world size and shape.
                    let p = crate::render::light::PointCasters::of(&cx.render.splat);
                    w.str("point casters", "points cast 1");
                    w.f64("point caster size", p.size.map_or(0.0, f64::from));
                    w.bool("point casters cubes", p.cube);
                }
                if cx.frame_two_sided.get(*frame) == Some(&true) {
                    // Its two-sided triangles' vertices gather light on both sides.
                    w.str("sides", "sides 1");
                }
                if let Some(env) = deps.first() {
                    w.digest("prefiltered environment", env);
                }
            }
            Action::RenderPass { image, pass } => {
                let img = &cx.plan.images[*image];
                w.str("renderer", RENDER_SALT);
                w.str("pass", pass_name(*pass));
                w.digest("frame content", &cx.frame_keys[img.frame]);
                camera(w, &img.camera);
                render_settings(w, &cx.render, *pass);
                if *pass == Pass::Rgba && cx.render.shading == Shading::Pbr {
                    if let Some(lit) = &cx.frame_lit[img.frame] {
                        w.digest("lit materials", lit);
                    }
                    if cx.frame_glossy_glass.get(img.frame) == Some(&true) {
                        w.str("glass lobes", "hemisphere");
                    }
                    if let Some(lights) = &cx.frame_lights[img.frame] {
                        w.digest("file lights", lights);
                    }
                }
                // The frame's light, and through it the prefiltered environment.
                if let Some(light) = deps.first() {
                    w.digest("frame light", light);
                }
                encoding(w, &cx.encoding, *pass);
            }
            Action::Composite { image: _, background } => {
                w.str("encoder", ENCODE_SALT);
                w.digest("rgba", &deps[0]);
                w.f64s("background", &background.map(f64::from));
                png(w, cx.encoding.png);
            }
            Action::Video { split: _, view: _ } => {
                // The frames enter through their composites' keys; which camera they are does not matter.
                w.str("encoder", VIDEO_SALT);
                w.u64("fps (thousandths)", cx.video_fps_milli);
                for d in deps {
                    w.digest("frame", d);
                }
            }
            Action::InitCloud { frames, points } => {
                w.str("sampler", SAMPLE_SALT);
                w.str("selection", SELECTION);
                w.u64("seed", cx.seed);
                w.u64("points", *points);
                for &f in frames {
                    w.u64("frame", f as u64);
                    w.digest("frame content", &cx.frame_keys[f]);
                }
            }
            Action::ColmapPoints { frame, points } => {
                w.str("sampler", SAMPLE_SALT);
                w.str("selection", SELECTION);
                w.str("encoder", ENCODE_SALT);
                w.u64("seed", cx.seed);
                w.u64("points", *points);
                w.u64("frame", *frame as u64);
                w.digest("frame content", &cx.frame_keys[*frame]);
            }
            Action::Bounds { frames } => {
                // Bounds depend on content only, not on which frame index holds it.
                for &f in frames {
                    w.digest("frame content", &cx.frame_keys[f]);
                }
            }
            Action::SampleFrame { output, frame } => samples(w, cx, &cx.points[output], *frame, deps),
            Action::PointFrame { output, frame } => {
                let s = &cx.points[output];
                w.str("encoder", ENCODE_SALT);
                if s.reduces() {
                    w.digest("samples", &deps[0]);
                } else {
                    samples(w, cx, s, *frame, deps);
                }
                reduction(w, s, if s.vox.is_some() { deps.last() } else { None });
            }
            Action::PreviewSheet { split, extras } => {
                let sp = &cx.plan.splits[*split];
                let layout = super::preview::layout(cx.plan, *split);
                w.str("preview", super::preview::SALT);
                png(w, PngCompression::Fast);
                w.str("dataset", &cx.dataset);
                w.str("split", &sp.name);
                w.u64("images in split", sp.images.len() as u64);
                w.u64("columns", layout.columns as u64);
                for p in extras {
                    w.str("also", pass_name(*p));
                }
                // Per thumbnail: its label, then its passes' keys.
                let per = 1 + extras.len();
                for (k, &i) in layout.images.iter().enumerate() {
                    let img = &cx.plan.images[i];
                    w.u64("view", img.view as u64);
                    w.u64("frame", img.frame as u64);
                    w.f64("time", img.time);
                    for d in deps.iter().skip(k * per).take(per) {
                        w.digest("pass", d);
                    }
                }
            }
            Action::PreviewRig { splits } => {
                w.str("preview", super::preview::SALT);
                png(w, PngCompression::Fast);
                w.str("dataset", &cx.dataset);
                w.digest("bounds", &deps[0]);
                w.digest("subject samples", &deps[1]);
                w.u64("subject frame", rig_subject_frame(cx.plan, splits) as u64);
                for &s in splits {
                    let sp = &cx.plan.splits[s];
                    w.str("split", &sp.name);
                    // Every view's camera: the pose, and the intrinsics the crop count projects with.
                    if let Some(&first) = sp.images.first() {
                        let c = cx.plan.images[first].camera;
                        for pose in &sp.poses {
                            camera(w, &crate::camera::Camera { c2w: *pose, ..c });
                        }
                    }
                }
            }
            Action::PreviewStrip { output } => {
                w.str("preview", super::preview::SALT);
                png(w, PngCompression::Fast);
                w.str("dataset", &cx.dataset);
                w.str("output", output);
                for (f, d) in super::preview::point_frames(cx.plan.frames).iter().zip(deps) {
                    w.u64("frame", *f as u64);
                    w.digest("points", d);
                }
            }
            Action::WriteOutput { output } => {
                w.str("tool", env!("CARGO_PKG_VERSION"));
                w.digest("manifest", &cx.manifest);
                w.str("output", output);
                for d in deps {
                    w.digest("input", d);
                }
            }
        }
    }
}

fn camera(w: &mut dyn KeyWriter, c: &Camera) {
    let Camera { width, height, fx, fy, cx, cy, near, far, c2w } = *c;
    w.u64("width", width as u64);
    w.u64("height", height as u64);
    w.f64("fx", fx);
    w.f64("fy", fy);
    w.f64("cx", cx);
    w.f64("cy", cy);
    w.f64("near", near);
    w.f64("far", far);
    w.f64s("c2w", &c2w.to_cols_array());
}

/// The render settings that shape `pass`: geometry settings shape every pass, colour settings only RGBA.
fn render_settings(w: &mut dyn KeyWriter, s: &RenderSettings, pass: Pass) {
    let RenderSettings { samples, filter, shading, lights, ambient, lighting, background, depth, splat, buffers } = s;
    // Which auxiliary buffers are filled never changes the bytes of a pass (it only skips unused work).
    let _ = buffers;
    w.u64("samples", *samples as u64);
    let crate::render::SplatSettings { shape, size, min_px } = splat;
    // Zero where the scene draws no points (graph::Graph::new), and then not keyed: scenes without points keep
    // their keys, and a footprint of 0 is what drawing did before the minimum existed.
    if *min_px > 0.0 {
        w.f64("splat min px", *min_px as f64);
    }
    w.str(
        "splat shape",
        match shape {
            SplatShape::Cube => "cube",
            SplatShape::Square => "square",
            SplatShape::Disk => "disk",
            SplatShape::Surfel => "surfel",
        },
    );
    match size {
        SplatSize::World(v) => w.f64("splat size (world)", *v as f64),
        SplatSize::Pixels(v) => w.f64("splat size (px)", *v as f64),
    }
    // The colour passes' background and pixel filter (a box is what every pass had before filters: not keyed).
    let background = |w: &mut dyn KeyWriter| {
        match background {
            Some(c) => w.f64s("background", &[c.x as f64, c.y as f64, c.z as f64]),
            None => w.str("background", "transparent"),
        }
        match filter {
            PixelFilter::Box => {}
            PixelFilter::BlackmanHarris { width } => {
                w.str("pixel filter", "blackman-harris");
                w.f64("pixel filter width", *width as f64);
            }
        }
    };
    match pass {
        Pass::Rgba => {
            w.str(
                "shading",
                match shading {
                    Shading::Unlit => "unlit",
                    Shading::Lambert => "lambert",
                    Shading::Pbr => "pbr",
                },
            );
            for (dir, intensity) in lights {
                w.f64s("light", &[dir.x as f64, dir.y as f64, dir.z as f64, *intensity as f64]);
            }
            w.f64("ambient", *ambient as f64);
            // Only lit renders read the lighting: unlit and Lambert datasets keep their keys.
            if *shading == Shading::Pbr {
                lighting_fields(w, lighting);
            }
            background(w);
        }
        // The unlit image: albedo needs no lights.
        Pass::Albedo => background(w),
        Pass::Depth => w.str(
            "depth kind",
            match depth {
                DepthKind::Planar => "planar",
                DepthKind::Ray => "ray",
            },
        ),
        Pass::Normal | Pass::Mask | Pass::Instance => {}
    }
}

/// What lights a `pbr` render: every light, and the environment's settings (its map enters through the
/// prefiltered environment's key, a dep).
fn lighting_fields(w: &mut dyn KeyWriter, l: &crate::render::Lighting) {
    light_fields(w, l);
    // The lights and the rest of the environment are `light_fields`'.
    let crate::render::Lighting { lights: _, environment, exposure, view } = l;
    // Whether the map shows behind the subject shapes pixels only.
    w.bool("environment visible", environment.visible);
    // Keyed only when set: an exposure of 0 changes no byte, and lit datasets made before it keep their keys.
    if *exposure != 0.0 {
        w.f64("exposure (stops)", *exposure as f64);
    }
    // The same for the view transform: the standard one is the encoding lit datasets always had.
    if *view == crate::render::ViewTransform::Agx {
        w.str("view transform", "agx (Blender 4.5's AgX Base sRGB)");
    }
}

/// The lights and the environment: what lights a scene before exposure and the view transform (not whether the
/// map shows as the background, which lights nothing: [`lighting_fields`] keys that).
fn light_fields(w: &mut dyn KeyWriter, l: &crate::render::Lighting) {
    use crate::render::light::{Light, LightKind};
    // Exposure and the view transform shape pixels only: `lighting_fields` keys them.
    let crate::render::Lighting { lights, environment, exposure: _, view: _ } = l;
    w.str("lit shading", LIT_SALT);
    for Light { kind, color, intensity, shadows } in lights {
        let v = |a: glam::Vec3| [a.x as f64, a.y as f64, a.z as f64];
        match *kind {
            LightKind::Sun { direction, angle } => {
                w.str("light", "sun");
                w.f64s("direction", &v(direction));
                w.f64("angle", angle as f64);
            }
            LightKind::Point { position, radius } => {
                w.str("light", "point");
                w.f64s("position", &v(position));
                w.f64("radius", radius as f64);
            }
            LightKind::Spot { position, direction, cone, blend, radius } => {
                w.str("light", "spot");
                w.f64s("position", &v(position));
                w.f64s("direction", &v(direction));
                w.f64("cone", cone as f64);
                w.f64("blend", blend as f64);
                w.f64("radius", radius as f64);
            }
        }
        w.f64s("color", &v(*color));
        w.f64("intensity", *intensity as f64);
        w.bool("shadows", *shadows);
    }
    let crate::render::Environment { map, strength, rotation_deg, visible: _ } = environment;
    // Which map it is enters through the environment action's key (the light action's dep).
    w.str("environment", if map.is_some() { "map" } else { "studio" });
    w.f64("environment strength", *strength as f64);
    w.f64("environment rotation (deg)", *rotation_deg as f64);
}

fn encoding(w: &mut dyn KeyWriter, e: &Encoding, pass: Pass) {
    let Encoding { png: compression, normal_space, depth_exr, normal_exr } = e;
    png(w, *compression);
    match pass {
        Pass::Depth => w.bool("exr", *depth_exr),
        Pass::Normal => {
            w.str(
                "normal space",
                match normal_space {
                    NormalSpace::World => "world",
                    NormalSpace::Camera => "camera",
                },
            );
            w.bool("exr", *normal_exr);
        }
        Pass::Rgba | Pass::Mask | Pass::Instance | Pass::Albedo => {}
    }
}

/// What shapes a PNG's bytes besides its pixels: the compression asked for and the encoder's version. Every
/// action that writes a PNG keys it (previews always write `fast`).
fn png(w: &mut dyn KeyWriter, compression: PngCompression) {
    w.str("png compression", png_name(compression));
    w.str("png encoder", crate::render::encode::PNG_SALT);
}

fn png_name(p: PngCompression) -> &'static str {
    match p {
        PngCompression::Fast => "fast",
        PngCompression::Default => "default",
        PngCompression::Best => "best",
    }
}

/// What shapes one frame's surface samples.
/// `deps` are the action's: for lit colours its frame's light action first ([`PointSettings::light_dep`]).
fn samples(w: &mut dyn KeyWriter, cx: &Keying, s: &PointSettings, f: usize, deps: &[Digest]) {
    let frames = cx.frame_keys.len();
    w.str("sampler", SAMPLE_SALT);
    w.u64("seed", cx.seed);
    // The random stream is keyed by the frame index, so two frames of equal content still differ.
    w.u64("frame", f as u64);
    w.digest("frame content", &cx.frame_keys[f]);
    w.u64("points", s.points);
    w.str("source", s.source.as_ref().map_or("*", |(_, n)| n.as_str()));
    w.bool("correspondence", s.correspondence);
    if s.correspondence {
        w.digest("first frame content", &cx.frame_keys[0]);
    }
    w.bool("motion", s.motion);
    if s.motion && f + 1 < frames {
        w.digest("next frame content", &cx.frame_keys[f + 1]);
    }
    // Lit colours read the lighting (and the file's lights at this frame); albedo ones keep their keys.
    if s.color == PointColor::Lit {
        w.str("color", "lit");
        w.str("baking", crate::render::light::BAKE_SALT);
        lighting_fields(w, &cx.render.lighting);
        if let Some(lit) = &cx.frame_lit[f] {
            w.digest("lit materials", lit);
        }
        if cx.frame_shadeless_points.get(f) == Some(&true) {
            w.str("shadeless points", "keep their colour");
        }
        if let Some(lights) = &cx.frame_lights[f] {
            w.digest("file lights", lights);
        }
        // The frame's light action: what the whole frame gathered, under the lights and the environment.
        if let Some(light) = deps.first() {
            w.digest("frame light", light);
        }
    }
}

/// What shapes a frame's reduction and encoding (not its samples).
fn reduction(w: &mut dyn KeyWriter, s: &PointSettings, bounds: Option<&Digest>) {
    let PointSettings {
        points: _,      // in the samples
        source: _,      // in the samples
        correspondence, // point ids are written only without a reduction
        motion: _,      // in the samples
        color: _,       // in the samples
        voxel,
        vox,
        reduce,
        position,
        color_average,
        format,
        pattern: _, // the file's name, not its bytes
    } = s;
    w.bool("point ids", *correspondence && !s.reduces());
    w.opt_f64("voxel", *voxel);
    match (vox, bounds) {
        (Some(v), Some(b)) => {
            w.u64("vox", *v as u64);
            w.digest("sequence bounds", b);
        }
        _ => w.str("vox", "none"),
    }
    if s.reduces() {
        w.str(
            "reduce",
            match reduce {
                Reduce::Mean => "mean",
                Reduce::Nearest => "nearest",
                Reduce::First => "first",
            },
        );
        w.str(
            "position",
            match position {
                VoxelPosition::Points => "points",
                VoxelPosition::Center => "center",
            },
        );
        w.str(
            "color average",
            match color_average {
                ColorAverage::Linear => "linear",
                ColorAverage::Srgb => "srgb",
            },
        );
    }
    w.str(
        "format",
        match format {
            PlyFormat::Binary => "binary",
            PlyFormat::Ascii => "ascii",
        },
    );
}
