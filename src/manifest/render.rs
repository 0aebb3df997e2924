//! `[render]`: image size, intrinsics, supersampling, shading, passes, point splats.

use serde::Deserialize;
use toml::Spanned;

use super::diag::Diagnostic;

/// Largest image side accepted.
pub const MAX_RESOLUTION: u32 = 16384;

/// NeRF-synthetic's horizontal field of view: Blender's 50 mm lens on a 36 mm sensor.
pub const NERF_CAMERA_ANGLE_X: f64 = 0.6911112070083618;

/// The `[render]` table. Absent: 800×800, NeRF-synthetic field of view, one sample, unlit, RGBA only.
#[derive(Debug, Clone, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Render {
    /// `[width, height]` in pixels.
    #[serde(default = "default_resolution")]
    #[schemars(with = "[u32; 2]")]
    pub(super) resolution: Spanned<[u32; 2]>,
    /// Horizontal field of view in radians.
    #[schemars(with = "Option<f64>")]
    pub(super) camera_angle_x: Option<Spanned<f64>>,
    /// Focal length in mm (with `sensor_mm`, Blender's sensor width, default 36).
    #[schemars(with = "Option<f64>")]
    pub(super) focal_mm: Option<Spanned<f64>>,
    /// Sensor width in mm (default 36, Blender's).
    pub sensor_mm: Option<f64>,
    /// Focal length in pixels, x.
    #[schemars(with = "Option<f64>")]
    pub(super) fx: Option<Spanned<f64>>,
    /// Focal length in pixels, y (default `fx`).
    pub fy: Option<f64>,
    /// Principal point x in pixels (default width / 2).
    pub cx: Option<f64>,
    /// Principal point y in pixels (default height / 2).
    pub cy: Option<f64>,
    /// Near clip distance (default 0.05).
    pub near: Option<f64>,
    /// Far clip distance (default 1000).
    pub far: Option<f64>,
    /// Supersampling: 1, 4, 9 or 16 samples per pixel.
    #[serde(default = "one")]
    #[schemars(with = "u32")]
    pub(crate) samples: Spanned<u32>,
    /// Pixel filter of the colour passes: `"box"` (default: a pixel is the mean of its samples) or
    /// `"blackman-harris"` (Cycles' default, soft as Blender's renders).
    #[serde(default)]
    pub filter: PixelFilter,
    /// The Blackman-Harris filter's width in pixels, Blender's Film ▸ Pixel Filter ▸ Width (default 1.5).
    #[schemars(with = "Option<f64>")]
    pub(crate) filter_width: Option<Spanned<f64>>,
    /// `"unlit"` (albedo), `"lambert"` or `"pbr"` (lit by `[light.NAME]` and `[environment]`).
    #[serde(default)]
    pub shading: Shading,
    /// `"transparent"` (default), `"white"`, `"black"` or `[r, g, b]` in 0..1 sRGB.
    #[serde(default)]
    #[schemars(with = "Option<Background>")]
    pub(crate) background: Option<Spanned<Background>>,
    /// Which images to write per view: `rgba`, `depth`, `normal`, `mask`.
    #[serde(default = "default_passes")]
    #[schemars(with = "Vec<Pass>")]
    pub(super) passes: Spanned<Vec<Pass>>,
    /// Depth pass options.
    #[serde(default)]
    pub depth: DepthOptions,
    /// Normal pass options.
    #[serde(default)]
    pub normal: NormalOptions,
    /// How points are drawn.
    #[serde(default)]
    pub splat: SplatOptions,
    /// Directional lights for `lambert` (default: a head light).
    #[serde(default)]
    pub lights: Vec<Light>,
    /// Ambient term for `lambert`, 0..1 (default 0.3).
    pub ambient: Option<f64>,
    /// PNG compression: `"fast"` (default), `"default"`, `"best"`.
    #[serde(default)]
    pub png_compression: PngCompression,
    /// `pbr`: whether lights in glTF sources (`KHR_lights_punctual`) light the scene besides `[light.NAME]`
    /// (default true).
    #[serde(default = "yes")]
    pub gltf_lights: bool,
    /// `pbr`: exposure in stops, Blender's Color Management ▸ Exposure: the lit image's linear light (and lit
    /// point colours) times 2^exposure before it is encoded (default 0). What a bright sun's washed-out ground is
    /// brought back with.
    #[schemars(with = "Option<f64>")]
    pub(crate) exposure: Option<Spanned<f64>>,
    /// `pbr`: Blender's Color Management ▸ View Transform for an sRGB display: `"standard"` (default), or
    /// `"agx"`, Blender 4.x's default, whose curve rolls highlights off instead of clipping them.
    #[schemars(with = "Option<ViewTransform>")]
    pub(crate) view_transform: Option<Spanned<ViewTransform>>,
}

fn default_resolution() -> Spanned<[u32; 2]> {
    Spanned::new(0..0, [800, 800])
}
fn yes() -> bool {
    true
}
fn one() -> Spanned<u32> {
    Spanned::new(0..0, 1)
}
fn default_passes() -> Spanned<Vec<Pass>> {
    Spanned::new(0..0, vec![Pass::Rgba])
}

impl Default for Render {
    fn default() -> Self {
        Render {
            resolution: default_resolution(),
            camera_angle_x: None,
            focal_mm: None,
            sensor_mm: None,
            fx: None,
            fy: None,
            cx: None,
            cy: None,
            near: None,
            far: None,
            samples: one(),
            filter: PixelFilter::default(),
            filter_width: None,
            shading: Shading::default(),
            background: None,
            passes: default_passes(),
            depth: DepthOptions::default(),
            normal: NormalOptions::default(),
            splat: SplatOptions::default(),
            lights: Vec::new(),
            ambient: None,
            png_compression: PngCompression::default(),
            gltf_lights: true,
            exposure: None,
            view_transform: None,
        }
    }
}

/// Surface shading.
#[derive(Debug, Clone, Copy, Deserialize, PartialEq, Eq, Default, Hash, schemars::JsonSchema)]
#[serde(rename_all = "lowercase")]
pub enum Shading {
    /// Albedo only: base colour × texture × vertex colour.
    #[default]
    Unlit,
    /// Albedo × (ambient + Σ lights · max(0, n·l)).
    Lambert,
    /// glTF metallic-roughness materials under `[light.NAME]`s and the `[environment]`, with shadows.
    Pbr,
}

/// Pixel filter.
#[derive(Debug, Clone, Copy, Deserialize, PartialEq, Eq, Default, Hash, schemars::JsonSchema)]
#[serde(rename_all = "kebab-case")]
pub enum PixelFilter {
    /// The mean of the pixel's own samples.
    #[default]
    Box,
    /// Cycles' Blackman-Harris filter over ±`filter_width` pixels.
    BlackmanHarris,
}

/// Cycles' default pixel filter width.
pub const DEFAULT_FILTER_WIDTH: f64 = 1.5;

/// The widest Blackman-Harris filter accepted, pixels (the renderer's own limit, `render::filter::MAX_WIDTH`).
pub const MAX_FILTER_WIDTH: f64 = 10.0;

/// Background of the RGBA pass.
#[derive(Debug, Clone, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(untagged)]
pub enum Background {
    /// `"transparent"`, `"white"` or `"black"`.
    Named(String),
    /// sRGB colour in 0..1.
    Rgb([f64; 3]),
}

/// An image pass.
#[derive(Debug, Clone, Copy, Deserialize, PartialEq, Eq, PartialOrd, Ord, Hash, schemars::JsonSchema)]
#[serde(rename_all = "lowercase")]
pub enum Pass {
    /// 8-bit sRGB straight-alpha RGBA.
    Rgba,
    /// Depth in millimetres, 16-bit.
    Depth,
    /// Unit normals remapped to 8-bit.
    Normal,
    /// 8-bit coverage mask.
    Mask,
    /// 16-bit object ids (0 = background, 1 + the source's mesh instance otherwise).
    Instance,
    /// 8-bit sRGB straight-alpha albedo (the unlit image), beside a lit `rgba`.
    Albedo,
}

/// `[render.depth]`.
#[derive(Debug, Clone, Copy, Deserialize, PartialEq, Eq, Default, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct DepthOptions {
    /// `"planar"` z-depth (default, what nerfstudio and instant-ngp read) or `"ray"` distance.
    #[serde(default)]
    pub kind: DepthKind,
    /// Also write a 32-bit float OpenEXR (metres, one channel `Y`) beside each 16-bit PNG.
    #[serde(default)]
    pub exr: bool,
}

/// Depth convention.
#[derive(Debug, Clone, Copy, Deserialize, PartialEq, Eq, Default, Hash, schemars::JsonSchema)]
#[serde(rename_all = "lowercase")]
pub enum DepthKind {
    /// Distance along the optical axis.
    #[default]
    Planar,
    /// Distance along the pixel's ray.
    Ray,
}

/// `[render.normal]`.
#[derive(Debug, Clone, Copy, Deserialize, PartialEq, Eq, Default, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct NormalOptions {
    /// `"world"` (default) or `"camera"` (OpenGL camera axes).
    #[serde(default)]
    pub space: NormalSpace,
    /// Also write a 32-bit float OpenEXR (unit normals in channels `R G B`) beside each 8-bit PNG.
    #[serde(default)]
    pub exr: bool,
}

/// Normal pass coordinate frame.
#[derive(Debug, Clone, Copy, Deserialize, PartialEq, Eq, Default, Hash, schemars::JsonSchema)]
#[serde(rename_all = "lowercase")]
pub enum NormalSpace {
    /// World axes (+Z up).
    #[default]
    World,
    /// Camera axes, OpenGL (+X right, +Y up, +Z back).
    Camera,
}

/// `[render.splat]`: how points are drawn.
#[derive(Debug, Clone, Copy, Deserialize, PartialEq, Default, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct SplatOptions {
    /// `"cube"` (default), `"square"` or `"disk"`.
    #[serde(default)]
    pub shape: SplatShape,
    /// Size in world units (default: the sequence's voxel size).
    pub size: Option<f64>,
    /// Size in pixels instead.
    pub size_px: Option<f64>,
    /// Smallest footprint on screen in pixels (default 1: points never fall between samples; 0 = true size).
    pub min_px: Option<f64>,
}

/// Splat shape.
#[derive(Debug, Clone, Copy, Deserialize, PartialEq, Eq, Default, Hash, schemars::JsonSchema)]
#[serde(rename_all = "lowercase")]
pub enum SplatShape {
    /// A 3D cube of edge `size` centred on the point.
    #[default]
    Cube,
    /// A screen-aligned square.
    Square,
    /// A screen-aligned disk.
    Disk,
    /// A disk of diameter `size` in the plane of the point's normal (facing the camera without one).
    Surfel,
}

/// A directional light.
#[derive(Debug, Clone, Copy, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Light {
    /// Direction the light travels, world space.
    pub direction: [f64; 3],
    /// Intensity (default 1).
    #[serde(default = "unit")]
    pub intensity: f64,
}

fn unit() -> f64 {
    1.0
}

/// How a lit render's light becomes display values (Blender's view transforms).
#[derive(Debug, Clone, Copy, Deserialize, PartialEq, Eq, Default, Hash, schemars::JsonSchema)]
#[serde(rename_all = "lowercase")]
pub enum ViewTransform {
    /// The sRGB encoding alone: light above 1 clips.
    #[default]
    Standard,
    /// AgX, as Blender 4.5 displays it on sRGB.
    Agx,
}

/// PNG compression level.
#[derive(Debug, Clone, Copy, Deserialize, PartialEq, Eq, Default, Hash, schemars::JsonSchema)]
#[serde(rename_all = "lowercase")]
pub enum PngCompression {
    /// fdeflate, ~3 ms per 800² image.
    #[default]
    Fast,
    /// zlib level 6, ~15× slower, ~half the size.
    Default,
    /// zlib level 9.
    Best,
}

impl Render {
    /// `pbr`: the exposure in stops (0 unless given).
    pub fn exposure(&self) -> f64 {
        self.exposure.as_ref().map_or(0.0, |e| *e.get_ref())
    }

    /// `pbr`: the view transform (standard unless given).
    pub fn view_transform(&self) -> ViewTransform {
        self.view_transform.as_ref().map_or(ViewTransform::Standard, |v| *v.get_ref())
    }

    /// `(width, height)`.
    pub fn size(&self) -> (u32, u32) {
        let [w, h] = *self.resolution.get_ref();
        (w, h)
    }

    /// Focal lengths and principal point in pixels: `(fx, fy, cx, cy)`.
    pub fn intrinsics(&self) -> (f64, f64, f64, f64) {
        let (w, h) = self.size();
        let fx = if let Some(fx) = &self.fx {
            *fx.get_ref()
        } else if let Some(f) = &self.focal_mm {
            *f.get_ref() / self.sensor_mm.unwrap_or(36.0) * w as f64
        } else {
            let a = self.camera_angle_x.as_ref().map(|a| *a.get_ref()).unwrap_or(NERF_CAMERA_ANGLE_X);
            0.5 * w as f64 / (0.5 * a).tan()
        };
        let fy = self.fy.unwrap_or(fx);
        (fx, fy, self.cx.unwrap_or(w as f64 / 2.0), self.cy.unwrap_or(h as f64 / 2.0))
    }

    /// Whether a pass is requested.
    pub fn has_pass(&self, p: Pass) -> bool {
        self.passes.get_ref().contains(&p)
    }

    pub(crate) fn validate(&self, diags: &mut Vec<Diagnostic>) {
        if let Some(e) = &self.exposure {
            let v = *e.get_ref();
            if !(v.is_finite() && v.abs() <= 20.0) {
                diags.push(
                    Diagnostic::error(format!("exposure = {v} stops is outside -20 … 20"), Some(e.span()))
                        .with_help("stops, as Blender's exposure: -1 halves the light, 1 doubles it"),
                );
            } else if self.shading != Shading::Pbr {
                diags.push(
                    Diagnostic::warning("`exposure` applies to lit renders only: it is ignored here", Some(e.span()))
                        .with_help("set shading = \"pbr\", or remove it"),
                );
            }
        }
        if let Some(v) = &self.view_transform {
            if self.shading != Shading::Pbr && *v.get_ref() != ViewTransform::Standard {
                diags.push(
                    Diagnostic::warning(
                        "`view_transform` applies to lit renders only: it is ignored here",
                        Some(v.span()),
                    )
                    .with_help("set shading = \"pbr\", or remove it"),
                );
            }
        }
        let [w, h] = *self.resolution.get_ref();
        let rs = Some(self.resolution.span());
        if w == 0 || h == 0 || w > MAX_RESOLUTION || h > MAX_RESOLUTION {
            diags.push(
                Diagnostic::error(format!("resolution {w}×{h} is outside 1..={MAX_RESOLUTION}"), rs)
                    .with_help("e.g. resolution = [800, 800]"),
            );
        }
        let ways = [
            self.camera_angle_x.as_ref().map(|s| s.span()),
            self.focal_mm.as_ref().map(|s| s.span()),
            self.fx.as_ref().map(|s| s.span()),
        ];
        let given: Vec<_> = ways.iter().flatten().collect();
        if given.len() > 1 {
            diags.push(
                Diagnostic::error("the field of view is given more than once", Some(given[1].clone()))
                    .with_help("use one of `camera_angle_x`, `focal_mm` (+ `sensor_mm`), or `fx`/`fy`/`cx`/`cy`"),
            );
        }
        if let Some(a) = &self.camera_angle_x {
            let v = *a.get_ref();
            if !(v > 0.0 && v < std::f64::consts::PI) {
                diags.push(
                    Diagnostic::error(
                        format!("camera_angle_x = {v} is not an angle in (0, π) radians"),
                        Some(a.span()),
                    )
                    .with_help("NeRF-synthetic uses 0.6911112"),
                );
            }
        }
        for (name, v) in [("focal_mm", self.focal_mm.as_ref()), ("fx", self.fx.as_ref())] {
            if let Some(v) = v {
                if !(v.get_ref().is_finite() && *v.get_ref() > 0.0) {
                    diags.push(Diagnostic::error(format!("{name} must be positive"), Some(v.span())));
                }
            }
        }
        let s = *self.samples.get_ref();
        if ![1, 4, 9, 16].contains(&s) {
            diags.push(
                Diagnostic::error(
                    format!("samples = {s} is not a square supersampling count"),
                    Some(self.samples.span()),
                )
                .with_help("use 1, 4, 9 or 16"),
            );
        }
        if let Some(fw) = &self.filter_width {
            let v = *fw.get_ref();
            let max = MAX_FILTER_WIDTH;
            if self.filter != PixelFilter::BlackmanHarris {
                diags.push(
                    Diagnostic::error("`filter_width` is the width of the Blackman-Harris filter", Some(fw.span()))
                        .with_help("add filter = \"blackman-harris\", or remove `filter_width`"),
                );
            } else if !(v > 0.0 && v <= max) {
                diags.push(
                    Diagnostic::error(
                        format!("filter_width = {v} is not a width in (0, {max}] pixels"),
                        Some(fw.span()),
                    )
                    .with_help("Blender's default is 1.5"),
                );
            }
        }
        let (near, far) = (self.near.unwrap_or(0.05), self.far.unwrap_or(1000.0));
        if !(near > 0.0 && far > near) {
            diags.push(Diagnostic::error(format!("near = {near}, far = {far}: need 0 < near < far"), None));
        }
        let passes = self.passes.get_ref();
        if passes.is_empty() {
            diags.push(
                Diagnostic::error("no passes: nothing would be rendered", Some(self.passes.span()))
                    .with_help("e.g. passes = [\"rgba\"]"),
            );
        }
        let mut sorted = passes.clone();
        sorted.sort();
        sorted.dedup();
        if sorted.len() != passes.len() {
            diags.push(Diagnostic::warning("a pass is listed twice", Some(self.passes.span())));
        }
        if let Some(bg) = &self.background {
            match bg.get_ref() {
                Background::Named(n) if !["transparent", "white", "black"].contains(&n.as_str()) => diags.push(
                    Diagnostic::error(format!("unknown background `{n}`"), Some(bg.span()))
                        .with_help("use \"transparent\", \"white\", \"black\" or [r, g, b] in 0..1"),
                ),
                Background::Rgb(c) if c.iter().any(|v| !(0.0..=1.0).contains(v)) => {
                    diags.push(Diagnostic::error("background colour components must be in 0..1", Some(bg.span())))
                }
                _ => {}
            }
        }
        if let (Some(_), Some(_)) = (self.splat.size, self.splat.size_px) {
            diags.push(Diagnostic::error("[render.splat] takes `size` or `size_px`, not both", None));
        }
        for v in [self.splat.size, self.splat.size_px].into_iter().flatten() {
            if !(v.is_finite() && v > 0.0) {
                diags.push(Diagnostic::error(format!("splat size {v} must be positive"), None));
            }
        }
        if let Some(v) = self.splat.min_px {
            if !(0.0..=64.0).contains(&v) {
                diags.push(
                    Diagnostic::error(format!("splat min_px {v} is outside 0..64"), None)
                        .with_help("min_px = 1 keeps every point at least a pixel wide; 0 draws true sizes"),
                );
            }
        }
    }
}

/// Plain values of the fields whose spans stay inside `manifest` (for diagnostics).
impl Render {
    /// `[width, height]`.
    pub fn resolution(&self) -> [u32; 2] {
        *self.resolution.get_ref()
    }

    /// Horizontal field of view in radians, when given.
    pub fn camera_angle_x(&self) -> Option<f64> {
        self.camera_angle_x.as_ref().map(|a| *a.get_ref())
    }

    /// Focal length in millimetres, when given.
    pub fn focal_mm(&self) -> Option<f64> {
        self.focal_mm.as_ref().map(|f| *f.get_ref())
    }

    /// Focal length in pixels, when given.
    pub fn fx(&self) -> Option<f64> {
        self.fx.as_ref().map(|f| *f.get_ref())
    }

    /// Samples per pixel.
    pub fn samples(&self) -> u32 {
        *self.samples.get_ref()
    }

    /// The background, when given.
    pub fn background(&self) -> Option<&Background> {
        self.background.as_ref().map(|b| b.get_ref())
    }

    /// The passes, in manifest order.
    pub fn passes(&self) -> &[Pass] {
        self.passes.get_ref()
    }
}
