//! 3D Gaussians drawn as 3D Gaussian splatting draws them: graphdeco-inria's rasterizer
//! (`diff-gaussian-rasterization`, whose arithmetic gsplat's "classic" mode shares), the one the files were
//! trained against, so that vvgen's images of a trained file look as the trainer's own renders do.
//!
//! Per view, each Gaussian is projected (the EWA approximation: its covariance through the projection's
//! Jacobian at its centre, plus 3DGS's 0.3 px² low-pass), coloured by its spherical harmonics along the view
//! direction, and evaluated at the centre of every pixel of the 16 × 16 tiles its 3σ square reaches; each pixel
//! blends its Gaussians front to back by the depth of their centres, with 3DGS's cut-offs (opacity at most 0.99,
//! contributions under 1/255 skipped, stopping before transmittance would fall under 10⁻⁴). The blend happens in
//! the values the spherical harmonics give, which are display (sRGB) values: 3DGS fits them to the images as they
//! are stored, and blends them so.
//!
//! Gaussians are drawn after everything else and composited over it: a pixel's Gaussians stop at the depth of the
//! surface drawn there, and what shows through them is that surface's pixel. They are one sample per pixel
//! whatever `samples` asks (3DGS's low-pass is its anti-aliasing) and take no light: a radiance field carries its
//! own. Ties in depth go to the Gaussian first in the scene, so the image depends on nothing but the scene and the
//! camera.

use glam::{Mat3, Vec2, Vec3};
use rayon::prelude::*;

use super::bin::Binned;
use super::{DepthKind, Frame};
use crate::camera::Camera;
use crate::scene::gaussians::Gaussians;
use crate::scene::PosedScene;

/// 3DGS's tile side: a Gaussian is evaluated at every pixel of the tiles its 3σ square reaches, with no cut-off
/// per pixel, so its faint tails end at tile edges as in the images it was fitted to.
const TILE: i64 = 16;
/// 3DGS's low-pass filter, added to each projected covariance's diagonal (px²).
const DILATION: f32 = 0.3;
/// The most one Gaussian covers of a pixel.
const MAX_ALPHA: f32 = 0.99;
/// Contributions under this are skipped.
const MIN_ALPHA: f32 = 1.0 / 255.0;
/// A pixel stops before its transmittance would fall under this.
const MIN_TRANSMITTANCE: f32 = 1e-4;

/// Whether `scene` has Gaussians to draw.
pub(super) fn any(scene: &PosedScene) -> bool {
    scene.primitives.iter().any(|p| p.gaussians.is_some())
}

/// One Gaussian as one view sees it.
#[derive(Clone, Copy)]
struct Projected {
    /// Centre in continuous pixel coordinates (pixel (i, j)'s centre at (i + 0.5, j + 0.5)).
    mean: Vec2,
    /// The inverse of its projected covariance (a, b, c of [[a, b], [b, c]]).
    conic: [f32; 3],
    opacity: f32,
    /// A power under which its contribution is surely under [`MIN_ALPHA`] (ln(MIN_ALPHA / opacity), less a
    /// margin for rounding): most of a tile's pixels are far in a Gaussian's tail, where `exp` would underflow
    /// slowly to give what this test tells at once. Powers above it are tested exactly.
    cut: f32,
    /// Half the sides of the box around `mean` where the power can reach `cut`, a pixel wider.
    extent: Vec2,
    /// Display colour along the view direction.
    color: Vec3,
    /// Planar depth of its centre.
    depth: f32,
    /// Object id + 1.
    object: u32,
    /// The tiles it reaches: columns `x0..x1`, rows `y0..y1`.
    tiles: [u32; 4],
}

/// The view's camera in the form projection needs: OpenCV axes (+Z forward, +Y down).
struct View {
    rot: Mat3,
    trans: Vec3,
    eye: Vec3,
    fx: f32,
    fy: f32,
    cx: f32,
    cy: f32,
    /// 3DGS's clamp on x/z and y/z when linearizing (1.3 × the half field of view, off-centre principal points
    /// as gsplat takes them): a Gaussian far outside the view is not stretched without bound.
    lim_x: (f32, f32),
    lim_y: (f32, f32),
    near: f32,
    far: f32,
    tiles: (u32, u32),
}

impl View {
    fn of(cam: &Camera) -> View {
        let w2c = (crate::camera::GL_TO_CV * cam.w2c()).as_mat4();
        let (w, h) = (cam.width as f32, cam.height as f32);
        let (fx, fy, cx, cy) = (cam.fx as f32, cam.fy as f32, cam.cx as f32, cam.cy as f32);
        let (tan_x, tan_y) = (0.5 * w / fx, 0.5 * h / fy);
        View {
            rot: Mat3::from_mat4(w2c),
            trans: w2c.w_axis.truncate(),
            eye: cam.c2w.w_axis.truncate().as_vec3(),
            fx,
            fy,
            cx,
            cy,
            lim_x: (cx / fx + 0.3 * tan_x, (w - cx) / fx + 0.3 * tan_x),
            lim_y: (cy / fy + 0.3 * tan_y, (h - cy) / fy + 0.3 * tan_y),
            near: cam.near as f32,
            far: cam.far as f32,
            tiles: (cam.width.div_ceil(TILE as u32), cam.height.div_ceil(TILE as u32)),
        }
    }

    /// Gaussian `i` of `g` centred at world `p`, as this view sees it; `None` where 3DGS draws nothing of it
    /// (behind the near plane, degenerate, or reaching no tile).
    /// `to_file` is `g.to_world`'s inverse, found once per primitive.
    fn project(&self, g: &Gaussians, to_file: &Mat3, i: usize, p: Vec3, object: u32) -> Option<Projected> {
        let t = self.rot * p + self.trans;
        if !(t.z > self.near && t.z < self.far) {
            return None;
        }
        let (fx, fy) = (self.fx, self.fy);
        let z = t.z;
        let tx = z * (t.x / z).clamp(-self.lim_x.0, self.lim_x.1);
        let ty = z * (t.y / z).clamp(-self.lim_y.0, self.lim_y.1);
        // J·W, row by row: the projection's Jacobian at the centre times the view's rotation.
        let (r0, r1, r2) = (self.rot.row(0), self.rot.row(1), self.rot.row(2));
        let j0 = r0 * (fx / z) - r2 * (fx * tx / (z * z));
        let j1 = r1 * (fy / z) - r2 * (fy * ty / (z * z));
        // Σ = (L·M)(L·M)ᵀ, so (J·W)·Σ·(J·W)ᵀ needs only (L·M)ᵀ·(J·W)ᵀ's two columns.
        let f = g.to_world * g.data.factors[i];
        let (u0, u1) = (f.transpose() * j0, f.transpose() * j1);
        let a = u0.dot(u0) + DILATION;
        let b = u0.dot(u1);
        let c = u1.dot(u1) + DILATION;
        let det = a * c - b * b;
        if det.is_nan() || det <= 0.0 {
            return None;
        }
        let conic = [c / det, -b / det, a / det];
        let mean = Vec2::new(fx * t.x / z + self.cx, fy * t.y / z + self.cy);
        // The 3σ radius of the larger eigenvalue, and the tiles its square reaches in 3DGS's pixel coordinates
        // (a pixel's centre at its integer index): C's truncating casts, clamped to the grid.
        let mid = 0.5 * (a + c);
        let spread = (mid * mid - det).max(0.1).sqrt();
        let radius = (3.0 * (mid + spread).max(mid - spread).sqrt()).ceil();
        let at = mean - Vec2::splat(0.5);
        let tile = |v: f32, n: u32| ((v / TILE as f32) as i64).clamp(0, n as i64) as u32;
        let t16 = TILE as f32 - 1.0;
        let tiles = [
            tile(at.x - radius, self.tiles.0),
            tile(at.y - radius, self.tiles.1),
            tile(at.x + radius + t16, self.tiles.0),
            tile(at.y + radius + t16, self.tiles.1),
        ];
        if tiles[0] >= tiles[2] || tiles[1] >= tiles[3] || !mean.is_finite() || !conic.iter().all(|v| v.is_finite()) {
            return None;
        }
        // Its colour along the view direction, taken back into the file's axes where it was fitted.
        let dir = *to_file * (p - self.eye);
        let per = g.data.per_gaussian();
        let color = sh_color(g.data.degree, &g.data.sh[i * per..(i + 1) * per], dir.normalize_or_zero());
        let opacity = g.data.opacities[i];
        let cut = (MIN_ALPHA / opacity).ln() - 1e-3;
        // The power −dᵀ·Σ⁻¹·d / 2 is at least `cut` inside the ellipse dᵀ·Σ⁻¹·d ≤ −2·cut, whose box has half
        // sides √(−2·cut·Σₓₓ) and √(−2·cut·Σᵧᵧ).
        let reach = (-2.0 * cut).max(0.0);
        let extent = Vec2::new((reach * a).sqrt(), (reach * c).sqrt()) + Vec2::ONE;
        Some(Projected { mean, conic, opacity, cut, extent, color, depth: z, object: object + 1, tiles })
    }
}

/// 3DGS's `computeColorFromSH`: the real spherical harmonics up to `degree` along unit `d`, plus 0.5, clamped
/// at zero (not at one: the blend may exceed one, the image is clamped when stored).
fn sh_color(degree: usize, sh: &[Vec3], d: Vec3) -> Vec3 {
    const C0: f32 = 0.282_094_8;
    const C1: f32 = 0.488_602_5;
    const C2: [f32; 5] = [1.092_548_4, -1.092_548_4, 0.315_391_57, -1.092_548_4, 0.546_274_2];
    const C3: [f32; 7] =
        [-0.590_043_6, 2.890_611_4, -0.457_045_8, 0.373_176_33, -0.457_045_8, 1.445_305_7, -0.590_043_6];
    let mut c = C0 * sh[0];
    if degree > 0 {
        let (x, y, z) = (d.x, d.y, d.z);
        c = c - C1 * y * sh[1] + C1 * z * sh[2] - C1 * x * sh[3];
        if degree > 1 {
            let (xx, yy, zz, xy, yz, xz) = (x * x, y * y, z * z, x * y, y * z, x * z);
            c = c
                + C2[0] * xy * sh[4]
                + C2[1] * yz * sh[5]
                + C2[2] * (2.0 * zz - xx - yy) * sh[6]
                + C2[3] * xz * sh[7]
                + C2[4] * (xx - yy) * sh[8];
            if degree > 2 {
                c = c
                    + C3[0] * y * (3.0 * xx - yy) * sh[9]
                    + C3[1] * xy * z * sh[10]
                    + C3[2] * y * (4.0 * zz - xx - yy) * sh[11]
                    + C3[3] * z * (2.0 * zz - 3.0 * xx - 3.0 * yy) * sh[12]
                    + C3[4] * x * (4.0 * zz - xx - yy) * sh[13]
                    + C3[5] * z * (xx - yy) * sh[14]
                    + C3[6] * x * (xx - 3.0 * yy) * sh[15];
            }
        }
    }
    (c + Vec3::splat(0.5)).max(Vec3::ZERO)
}

/// Gaussians projected per chunk in parallel (enough to spread a large file's projection over the workers).
const CHUNK: usize = 16 * 1024;

/// Draws `scene`'s Gaussians over `f`, a view already drawn of everything else (its `depth`, planar or ray as
/// `depth_kind` says, stops them; 0 where nothing is drawn).
pub(super) fn draw(scene: &PosedScene, cam: &Camera, depth_kind: DepthKind, f: &mut Frame) {
    let view = View::of(cam);
    // Projected in scene order, then sorted by depth, first in the scene among equals.
    let mut seen: Vec<(u32, u32, Projected)> = Vec::new();
    let mut first = 0u32;
    for p in &scene.primitives {
        let Some(g) = &p.gaussians else { continue };
        let to_file = g.to_world.inverse();
        let n = p.positions.len().min(g.data.opacities.len());
        let chunks: Vec<Vec<(u32, u32, Projected)>> = p.positions[..n]
            .par_chunks(CHUNK)
            .enumerate()
            .map(|(c, ps)| {
                ps.iter()
                    .enumerate()
                    .filter_map(|(k, &pos)| {
                        let i = c * CHUNK + k;
                        let q = view.project(g, &to_file, i, pos, p.object)?;
                        // Positive depths order as their bits do.
                        Some((q.depth.to_bits(), first + i as u32, q))
                    })
                    .collect()
            })
            .collect();
        seen.extend(chunks.into_iter().flatten());
        first += n as u32;
    }
    if seen.is_empty() {
        return;
    }
    seen.par_sort_unstable_by_key(|&(d, i, _)| (d, i));
    let gs: Vec<Projected> = seen.into_iter().map(|(_, _, q)| q).collect();
    // Each band of tile rows' Gaussians, front to back. (Per band, not per tile: a Gaussian is listed once for each
    // band it reaches, at most the image's height in tiles, where a list per tile would hold a large one the
    // image's area in tiles over.) The rectangles are inclusive; a Gaussian's tiles are never empty.
    let (tw, th) = view.tiles;
    let by_band =
        Binned::sort(&gs, 1, th as usize, |q| [0, q.tiles[1] as usize, 0, q.tiles[3] as usize - 1], |k, _| k as u32);
    let w = cam.width as usize;
    let rows = TILE as usize * w;
    let Frame { rgba, depth, normal, object, coverage, .. } = f;
    // One band of tile rows per task; buffers not made give empty slices.
    let mut dep = depth.chunks_mut(rows);
    let mut nor = normal.chunks_mut(rows);
    let mut obj = object.chunks_mut(rows);
    let bands: Vec<_> = rgba
        .chunks_mut(rows * 4)
        .zip(coverage.chunks_mut(rows))
        .map(|(c, a)| {
            (c, a, dep.next().unwrap_or_default(), nor.next().unwrap_or_default(), obj.next().unwrap_or_default())
        })
        .collect();
    let ray = depth_kind == DepthKind::Ray;
    bands.into_par_iter().enumerate().for_each_init(
        || (Vec::new(), Vec::new()),
        |(local, pixels), (ty, (rgba, cov, depth, normal, object))| {
            let h = cov.len() / w;
            // The band's list split by tile, as the whole list was split by band.
            let by_tile = Binned::sort(
                by_band.cell(ty),
                tw as usize,
                tw as usize,
                |&k| [gs[k as usize].tiles[0] as usize, 0, gs[k as usize].tiles[2] as usize - 1, 0],
                |_, &k| k,
            );
            for tx in 0..tw as usize {
                // The tile's Gaussians copied together, front to back, as the GPU's shared memory holds them.
                local.clear();
                local.extend(by_tile.cell(tx).iter().map(|&k| gs[k as usize]));
                let (x0, x1) = (tx * TILE as usize, ((tx + 1) * TILE as usize).min(w));
                pixels.clear();
                for ly in 0..h {
                    for x in x0..x1 {
                        let centre = Vec2::new(x as f32 + 0.5, (ty * TILE as usize + ly) as f32 + 0.5);
                        // The depth buffer's value as a planar depth: a ray distance shrinks by the ray's length.
                        let stretch = if ray {
                            Vec2::new((centre.x - view.cx) / view.fx, (centre.y - view.cy) / view.fy)
                                .extend(1.0)
                                .length()
                        } else {
                            1.0
                        };
                        let stop = depth.get(ly * w + x).filter(|&&d| d > 0.0).map_or(f32::INFINITY, |d| d / stretch);
                        pixels.push(Blend { centre, stretch, stop, t: 1.0, c: Vec3::ZERO, done: false, half: None });
                    }
                }
                blend(local, pixels, (x0, x1 - x0), (ty * TILE as usize, h));
                for (k, p) in pixels.iter().enumerate() {
                    if p.t == 1.0 {
                        continue;
                    }
                    let i = (k / (x1 - x0)) * w + x0 + k % (x1 - x0);
                    // Over what was drawn there, as 3DGS blends over its background: in display values.
                    let px = &mut rgba[i * 4..i * 4 + 4];
                    let under = px[3] as f32 / 255.0;
                    let premul = p.c + Vec3::new(px[0] as f32, px[1] as f32, px[2] as f32) * (p.t * under / 255.0);
                    let a = (1.0 - p.t) + p.t * under;
                    let straight = premul / a;
                    for (o, v) in px.iter_mut().zip(straight.to_array()) {
                        *o = (v.clamp(0.0, 1.0) * 255.0).round() as u8;
                    }
                    px[3] = (a.clamp(0.0, 1.0) * 255.0).round() as u8;
                    cov[i] = px[3];
                    // Where the Gaussians reach half opacity in front of the surface, they are what the pixel
                    // shows: the depth there (their median depth), their object, and no normal.
                    if let Some(q) = p.half.map(|k| &local[k as usize]) {
                        if let Some(d) = depth.get_mut(i) {
                            *d = q.depth * p.stretch;
                        }
                        if let Some(o) = object.get_mut(i) {
                            *o = q.object;
                        }
                        if let Some(n) = normal.get_mut(i) {
                            *n = Vec3::ZERO;
                        }
                    }
                }
            }
        },
    );
}

/// One pixel's blend so far.
struct Blend {
    centre: Vec2,
    /// A ray distance over the planar depth along this pixel's ray (1 for planar depth buffers).
    stretch: f32,
    /// The planar depth of the surface drawn here, where Gaussians stop (infinite where nothing is).
    stop: f32,
    /// Transmittance and premultiplied colour.
    t: f32,
    c: Vec3,
    /// Whether transmittance ran out.
    done: bool,
    /// The Gaussian (in the tile's list) at which transmittance fell to one half.
    half: Option<u32>,
}

/// Blends a tile's Gaussians, front to back, into its `pixels` (`cols` = (first column, width), `rows` = (first
/// row, height)). The result is each pixel's own front-to-back loop over the whole list, as 3DGS runs it: a
/// Gaussian is looked at only over the pixels where its contribution can reach [`MIN_ALPHA`] (the box of the
/// ellipse its `cut` bounds, a pixel wider), which are the only pixels that loop would not skip it at; a pixel
/// whose surface is nearer skips it as that loop stops there (later Gaussians are no nearer).
fn blend(list: &[Projected], pixels: &mut [Blend], cols: (usize, usize), rows: (usize, usize)) {
    let mut live = pixels.len();
    for (k, q) in list.iter().enumerate() {
        let span = |m: f32, e: f32, (first, n): (usize, usize)| {
            let lo = ((m - 0.5 - e).floor() as i64).max(first as i64);
            let hi = ((m - 0.5 + e).ceil() as i64).min((first + n) as i64 - 1);
            (lo - first as i64, hi - first as i64)
        };
        let (xl, xh) = span(q.mean.x, q.extent.x, cols);
        let (yl, yh) = span(q.mean.y, q.extent.y, rows);
        for y in yl.max(0)..=yh {
            for x in xl.max(0)..=xh {
                let p = &mut pixels[y as usize * cols.1 + x as usize];
                if p.done || q.depth >= p.stop {
                    continue;
                }
                let d = q.mean - p.centre;
                let [ca, cb, cc] = q.conic;
                let power = -0.5 * (ca * d.x * d.x + cc * d.y * d.y) - cb * d.x * d.y;
                if power > 0.0 || power < q.cut {
                    continue;
                }
                let alpha = (q.opacity * power.exp()).min(MAX_ALPHA);
                if alpha < MIN_ALPHA {
                    continue;
                }
                let next = p.t * (1.0 - alpha);
                if next < MIN_TRANSMITTANCE {
                    p.done = true;
                    live -= 1;
                    continue;
                }
                p.c += q.color * (alpha * p.t);
                p.t = next;
                if p.half.is_none() && p.t <= 0.5 {
                    p.half = Some(k as u32);
                }
            }
        }
        if live == 0 {
            break;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::{render, RenderSettings};
    use super::*;
    use crate::scene::gaussians::GaussianData;
    use crate::scene::material::Material;
    use crate::scene::PrimKind;
    use glam::{Mat4, Vec4};

    /// Gaussians at `centres` (standard deviations `sigma`, opacity `opacity`, band-0 colour `dc`, band 1 `b1`),
    /// as a file would give them, placed by `m`.
    fn file(centres: &[Vec3], sigma: Vec3, opacity: f32, dc: Vec3, b1: [Vec3; 3], m: Mat4) -> PosedScene {
        let n = centres.len();
        let data = GaussianData {
            factors: vec![Mat3::from_diagonal(sigma); n],
            opacities: vec![opacity; n],
            degree: 1,
            sh: (0..n).flat_map(|_| [dc, b1[0], b1[1], b1[2]]).collect(),
        };
        let mut scene = PosedScene::single(
            PrimKind::Points,
            centres.iter().map(|&c| m.transform_point3(c)).collect(),
            vec![Vec3::ZERO; n],
            vec![Vec4::ONE; n],
            Vec::new(),
            Material::default(),
        );
        scene.primitives[0].gaussians = Some(Gaussians::new(data).transformed(Mat3::from_mat4(m)));
        scene
    }

    /// A 64² camera (focal 64 px) at `eye` looking at the origin.
    fn camera(eye: Vec3) -> Camera {
        Camera {
            width: 64,
            height: 64,
            fx: 64.0,
            fy: 64.0,
            cx: 32.0,
            cy: 32.0,
            near: 0.05,
            far: 100.0,
            c2w: Camera::look_at(eye, Vec3::ZERO, Vec3::Y),
        }
    }

    fn pixel(f: &Frame, x: usize, y: usize) -> [u8; 4] {
        let i = (y * f.width as usize + x) * 4;
        f.rgba[i..i + 4].try_into().unwrap()
    }

    /// One round Gaussian facing the camera: a disc of standard deviation fx·σ/z pixels, widened by the 0.3 px²
    /// low-pass, its alpha at each pixel centre o·exp(−d²/2(s² + 0.3)), its colour its band 0 plus 0.5.
    #[test]
    fn a_round_gaussian_is_its_formula_at_every_pixel_centre() {
        let (sigma, z, opacity) = (0.05, 4.0, 0.8);
        let dc = Vec3::new(0.4, -0.2, 0.1) / 0.282_094_8;
        let scene = file(&[Vec3::ZERO], Vec3::splat(sigma), opacity, dc, [Vec3::ZERO; 3], Mat4::IDENTITY);
        let f = render(&scene, &camera(Vec3::new(0.0, 0.0, z)), &RenderSettings::default());
        let s2 = (64.0 * sigma / z).powi(2) + 0.3;
        let colour = [0.9f32, 0.3, 0.6].map(|c| (c * 255.0).round() as u8);
        let mut shown = 0;
        for y in 0..64 {
            for x in 0..64 {
                let d2 = (x as f32 + 0.5 - 32.0).powi(2) + (y as f32 + 0.5 - 32.0).powi(2);
                let alpha = opacity * (-0.5 * d2 / s2).exp();
                let want = if alpha < 1.0 / 255.0 { 0 } else { (alpha * 255.0).round() as u8 };
                let got = pixel(&f, x, y);
                assert!(got[3].abs_diff(want) <= 1, "({x}, {y}): alpha {} against {want}", got[3]);
                if got[3] > 0 {
                    shown += 1;
                    // Straight colour is the blend divided by its alpha again: within a level.
                    assert!((0..3).all(|c| got[c].abs_diff(colour[c]) <= 1), "({x}, {y}): {got:?} against {colour:?}");
                    assert_eq!(f.depth[y * 64 + x] > 0.0, alpha >= 0.5, "({x}, {y}): depth where half covered");
                }
            }
        }
        assert!(shown > 20, "{shown} pixels");
    }

    /// A surface in front of a Gaussian hides it; behind it, the Gaussian is blended over the surface's pixel.
    #[test]
    fn gaussians_stop_at_the_surface_drawn_in_front_of_them() {
        let wall = |z: f32| {
            let p =
                [Vec3::new(-1.0, -1.0, z), Vec3::new(1.0, -1.0, z), Vec3::new(1.0, 1.0, z), Vec3::new(-1.0, 1.0, z)];
            let m = Material { base_color: Vec4::new(0.0, 0.0, 1.0, 1.0), double_sided: true, ..Material::default() };
            PosedScene::quad(p, Vec3::Z, m)
        };
        let blob = file(
            &[Vec3::ZERO],
            Vec3::splat(0.3),
            0.99,
            Vec3::splat(0.5 / 0.282_094_8),
            [Vec3::ZERO; 3],
            Mat4::IDENTITY,
        );
        let cam = camera(Vec3::new(0.0, 0.0, 4.0));
        let s = RenderSettings {
            buffers: super::super::Buffers { depth: false, ..Default::default() },
            ..Default::default()
        };
        for (z, hidden) in [(0.5, true), (-0.5, false)] {
            let mut scene = wall(z);
            crate::scene::merge(&[scene.clone(), blob.clone()], &mut scene);
            let f = render(&scene, &cam, &s);
            let centre = pixel(&f, 32, 32);
            assert_eq!(centre[3], 255);
            if hidden {
                assert_eq!(centre, [0, 0, 255, 255], "the wall in front");
            } else {
                // 0.99 of the Gaussian's white over the blue wall.
                assert!(centre[0] > 240 && centre[2] == 255, "{centre:?}");
            }
            assert!(f.depth.is_empty(), "depth was not asked for");
        }
    }

    /// View-dependent colour is read in the file's axes: a file turned by the source → world transform shows,
    /// from the camera turned with it, the colour it shows untransformed.
    #[test]
    fn view_dependent_colour_turns_with_the_file() {
        // Band 1's x coefficient: bright seen from −x, dark from +x.
        let b1 = [Vec3::ZERO, Vec3::ZERO, Vec3::splat(-0.6)];
        // A quarter turn about y takes the file's x to the world's −z.
        let turn = Mat4::from_rotation_y(std::f32::consts::FRAC_PI_2) * Mat4::from_scale(Vec3::splat(2.0));
        let dc = Vec3::ZERO;
        let plain = file(&[Vec3::ZERO], Vec3::splat(0.1), 0.9, dc, b1, Mat4::IDENTITY);
        let turned = file(&[Vec3::ZERO], Vec3::splat(0.1), 0.9, dc, b1, turn);
        let s = RenderSettings::default();
        let from = |scene: &PosedScene, eye: Vec3| pixel(&render(scene, &camera(eye), &s), 32, 32);
        let (left, right) = (from(&plain, Vec3::new(-4.0, 0.0, 0.0)), from(&plain, Vec3::new(4.0, 0.0, 0.0)));
        assert!(left[0] > right[0] + 100, "{left:?} {right:?}");
        let near = |a: [u8; 4], b: [u8; 4]| (0..4).all(|c| a[c].abs_diff(b[c]) <= 1);
        let (l, r) =
            (turn.transform_point3(Vec3::new(-4.0, 0.0, 0.0)), turn.transform_point3(Vec3::new(4.0, 0.0, 0.0)));
        assert!(
            near(from(&turned, l), left) && near(from(&turned, r), right),
            "{:?} {:?}",
            from(&turned, l),
            from(&turned, r)
        );
    }

    #[test]
    fn band_one_turns_the_colour_with_the_view_and_band_zero_does_not() {
        let mut sh = vec![Vec3::ZERO; 16];
        sh[0] = Vec3::splat(1.0);
        let flat = sh_color(3, &sh, Vec3::X);
        assert!((flat - Vec3::splat(0.5 + 0.282_094_8)).abs().max_element() < 1e-6);
        // Coefficient 3 is −C1·x: looking along +x darkens, along −x brightens, and nothing goes below zero.
        sh[3] = Vec3::new(1.0, 0.0, 0.0);
        assert!(sh_color(1, &sh, Vec3::X).x < flat.x && sh_color(1, &sh, -Vec3::X).x > flat.x);
        sh[3] = Vec3::splat(-10.0);
        assert_eq!(sh_color(1, &sh, -Vec3::X), Vec3::ZERO);
        // Degree 0 reads only band 0.
        assert_eq!(sh_color(0, &sh, Vec3::X), flat);
    }
}
