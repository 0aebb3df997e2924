//! Four points projected at once, in SSE2 (part of x86-64's baseline): squares, disks and cubes, the splats of a
//! dense cloud. Projecting was half of an 800k-point cube render, one point at a time: a transform, five
//! divisions (a cube's screen box is four) and the box's rounding, each of which takes the same time for four
//! lanes as for one.
//!
//! Every lane goes through the same IEEE operations in the same order as [`project`], so the splats are the same
//! bits (a test compares the two on every kind of point): products and sums as `project` groups them, `x / 2` as
//! `x · 0.5` (both the correctly rounded half), and [`snap`]'s rounding as SSE2's
//! conversion under the default rounding mode (both to nearest, ties to even; the product by 256 is exact in
//! `f32` as in `f64`). SSE2's `min`, `max` and conversion treat NaN otherwise than Rust's scalar ones, so a lane
//! with anything not finite is handed to [`project`] itself, as are surfels (they read their normals).

use std::arch::x86_64::{
    __m128, __m128i, _mm_add_epi32, _mm_add_ps, _mm_and_ps, _mm_and_si128, _mm_andnot_ps, _mm_andnot_si128,
    _mm_castps_si128, _mm_castsi128_ps, _mm_cmpge_ps, _mm_cmpgt_epi32, _mm_cmpgt_ps, _mm_cmple_ps, _mm_cmplt_ps,
    _mm_cvtps_epi32, _mm_div_ps, _mm_max_ps, _mm_min_ps, _mm_movemask_ps, _mm_mul_ps, _mm_or_ps, _mm_or_si128,
    _mm_set1_epi32, _mm_set1_ps, _mm_setr_ps, _mm_srai_epi32, _mm_sub_epi32, _mm_sub_ps, _mm_xor_ps,
};
use std::ops::{Add, BitAnd, Div, Mul, Neg, Sub};

use glam::Vec3;

use super::{key, project, Flat, Footprint, Sink, Size, Solid, CLAMPED, WHOLE};
use crate::render::raster::{snap, Projection, SUBPIXEL};

/// A view's projection constants, each in four lanes.
pub(super) struct Lanes {
    /// The view matrix's first three rows: `m[r][c]` is column `c`'s component `r`.
    m: [[F4; 4]; 3],
    near: F4,
    far: F4,
    /// The sample grid's reach, as `project`'s `fixed` clamps to it.
    lim: f32,
    fx: F4,
    fy: F4,
    cx: F4,
    cy: F4,
    shape: Kind,
}

/// What differs between cubes and screen-aligned splats.
enum Kind {
    Cube {
        /// The half edge times √3: nearer than this to the near plane, a cube is dropped.
        reach: F4,
        /// The half extents of its view-space bounding box.
        extent: [F4; 3],
        /// The half edge times fx: its inscribed disk's radius in samples at unit depth.
        radius: F4,
        /// The radius below which it is drawn as a flat square, when there is a minimum footprint.
        small: Option<F4>,
        /// Half the minimum footprint, in samples.
        min_half: F4,
    },
    Flat {
        /// Half the size: in samples at unit depth (world sizes, divided by the depth), or in samples.
        half: Half,
        /// Half the minimum footprint, in samples.
        min_half: F4,
        /// The half size of a splat drawn at the minimum footprint.
        clamped_r: i32,
    },
}

/// A screen-aligned splat's half size.
enum Half {
    /// Samples at unit depth.
    World(F4),
    /// Samples, whatever the depth.
    Pixels(F4),
}

impl Lanes {
    /// The lanes for splats of `s` under `p`; `None` for surfels, which [`project`] draws one at a time (and for
    /// grids too large for 32-bit lanes).
    pub(super) fn new(p: &Projection, s: &Footprint) -> Option<Lanes> {
        let lim = (p.size.0.max(p.size.1) + 2) as f32;
        // Fixed-point boxes are 32-bit lanes here: a grid whose reach, 256 times over and doubled, would not fit
        // (millions of samples a side, far past any image) goes one point at a time.
        if s.surfel || lim > (1 << 22) as f32 {
            return None;
        }
        let [fx, fy, cx, cy] = p.f;
        let c = p.w2c.to_cols_array_2d();
        let splat = F4::splat;
        // Each constant computed as `project` computes it.
        let shape = match (s.cube, s.size) {
            (Some(h), _) => Kind::Cube {
                reach: splat(h * 3f32.sqrt()),
                extent: s.extent.to_array().map(splat),
                radius: splat(h * fx),
                small: (s.min_half > 0.0).then(|| splat(s.min_half.max(std::f32::consts::FRAC_1_SQRT_2))),
                min_half: splat(s.min_half),
            },
            (None, size) => Kind::Flat {
                half: match size {
                    Size::World(w) => Half::World(splat(0.5 * w * fx)),
                    Size::Pixels(px) => Half::Pixels(splat(0.5 * px * s.k)),
                },
                min_half: splat(s.min_half),
                clamped_r: snap(s.min_half.clamp(-lim, lim) as f64) as i32 + 1,
            },
        };
        Some(Lanes {
            m: std::array::from_fn(|r| std::array::from_fn(|col| splat(c[col][r]))),
            near: splat(p.near),
            far: splat(p.far),
            lim,
            fx: splat(fx),
            fy: splat(fy),
            cx: splat(cx),
            cy: splat(cy),
            shape,
        })
    }

    /// Projects the four points `pos`, the first of which is point `point`, into `sink` in order: what [`project`]
    /// gives each (whose steps these follow, line by line).
    #[inline]
    pub(super) fn project4(&self, pos: &[Vec3; 4], point: u32, p: &Projection, s: &Footprint, sink: &mut Sink) {
        let axis = |i: usize| F4::new(pos.map(|v| v[i]));
        let (px, py, pz) = (axis(0), axis(1), axis(2));
        // As glam's `transform_point3`: ((c0·x + c1·y) + c2·z) + c3 (each sum's order aside: IEEE sums commute).
        let m = &self.m;
        let row = |r: usize| m[r][0] * px + m[r][1] * py + m[r][2] * pz + m[r][3];
        let (vx, vy, z) = (row(0), row(1), -row(2));
        let seen = z.ge(self.near) & z.le(self.far);
        let iz = F4::splat(1.0) / z;
        let fixed = |v: F4| v.fixed(self.lim);
        let size = (I4::splat(p.size.0 as i32 - 1), I4::splat(p.size.1 as i32 - 1));
        match &self.shape {
            Kind::Cube { reach, extent: [ex, ey, ez], radius, small, min_half } => {
                let seen = seen.and_not((z - *reach).lt(self.near));
                let (near_z, far_z) = (z - *ez, z + *ez);
                let zero = F4::splat(0.0);
                let ratio =
                    |lo: F4, hi: F4| (lo / lo.ge(zero).pick(far_z, near_z), hi / hi.ge(zero).pick(near_z, far_z));
                let (x0, x1) = ratio(vx - *ex, vx + *ex);
                let (y0, y1) = ratio(vy - *ey, vy + *ey);
                let (sx0, sx1) = (self.cx + self.fx * x0, self.cx + self.fx * x1);
                let (sy0, sy1) = (self.cy - self.fy * y1, self.cy - self.fy * y0);
                // `/ 2.0` as `· 0.5`: both are the correctly rounded half.
                let half = F4::splat(0.5);
                let (mx, my) = ((sx0 + sx1) * half, (sy0 + sy1) * half);
                let (wx, wy) = ((sx1 - sx0) * half, (sy1 - sy0) * half);
                let flat = small.map_or(Mask::NONE, |t| (*radius * iz).lt(t));
                let finite = F4::finite(&[near_z, mx, my, wx, wy]);
                let (x, y) = (fixed(mx), fixed(my));
                // A flat square's half size, or a solid's half width and height; one fixed-point unit more.
                let one = I4::splat(1);
                let r = fixed(min_half.max(wx.min(wy))) + one;
                let (rx, ry) = (flat.pick_i(r, fixed(wx) + one), flat.pick_i(r, fixed(wy) + one));
                let b = bbox(x, y, rx, ry, size);
                let shown = seen.bits() & finite & (rx.gt(I4::splat(0)) & b.shown).bits();
                // The face a flat cube shows: the one turned most towards the eye, as in `project`.
                let eye = s.eye;
                let (dx, dy, dz) = (px - F4::splat(eye.x), py - F4::splat(eye.y), pz - F4::splat(eye.z));
                let (ax, ay, az) = (dx.abs(), dy.abs(), dz.abs());
                // `max_position`: the first of the greatest.
                let y_over_x = ay.gt(ax);
                let z_over = az.gt(y_over_x.pick(ay, ax));
                let axis = z_over.pick(F4::splat(2.0), y_over_x.pick(F4::splat(1.0), zero));
                let negative = z_over.pick(dz, y_over_x.pick(dy, dx)).lt(zero).pick(F4::splat(1.0), zero);
                let face = (axis + axis + negative).to_ints();
                let (x, y, rx, ry, near_z) = (x.lanes(), y.lanes(), rx.lanes(), ry.lanes(), near_z.lanes());
                let ((y0, y1), flat, one) = (b.rows(), flat.bits(), seen.bits() & !finite);
                for l in 0..4 {
                    let (bit, id) = (1 << l, point + l as u32);
                    let rows = [y0[l] as i64, y1[l] as i64];
                    if shown & bit != 0 && flat & bit != 0 {
                        let small = face[l] as u8;
                        sink.flat(Flat { x: x[l], y: y[l], r: rx[l], small, key: key(near_z[l], id) }, rows);
                    } else if shown & bit != 0 {
                        let (rx, ry, centre) = (rx[l], ry[l], pos[l] - s.eye);
                        sink.solid(Solid { x: x[l], y: y[l], rx, ry, z: near_z[l], point: id, centre }, rows);
                    } else if one & bit != 0 {
                        sink.push(project(pos[l], Vec3::ZERO, p, s, id));
                    }
                }
            }
            Kind::Flat { half, min_half, clamped_r } => {
                let half = match half {
                    Half::World(c) => *c * iz,
                    Half::Pixels(h) => *h,
                };
                let clamped = half.lt(*min_half);
                let r = clamped.pick_i(I4::splat(*clamped_r), fixed(half.min(F4::splat(self.lim))));
                let sx = self.cx + self.fx * vx * iz;
                let sy = self.cy - self.fy * vy * iz;
                let finite = F4::finite(&[half, sx, sy]);
                let (x, y) = (fixed(sx), fixed(sy));
                let b = bbox(x, y, r, r, size);
                let shown = seen.bits() & finite & (r.gt(I4::splat(0)) & b.shown).bits();
                let (x, y, r, z, (y0, y1)) = (x.lanes(), y.lanes(), r.lanes(), z.lanes(), b.rows());
                let (clamped, one) = (clamped.bits(), seen.bits() & !finite);
                for l in 0..4 {
                    let (bit, id) = (1 << l, point + l as u32);
                    if shown & bit != 0 {
                        let small = if clamped & bit != 0 { CLAMPED } else { WHOLE };
                        let rows = [y0[l] as i64, y1[l] as i64];
                        sink.flat(Flat { x: x[l], y: y[l], r: r[l], small, key: key(z[l], id) }, rows);
                    } else if one & bit != 0 {
                        sink.push(project(pos[l], Vec3::ZERO, p, s, id));
                    }
                }
            }
        }
    }
}

/// [`super::bbox`] in four lanes: the first and last sample rows of each box, and whether it holds a sample.
struct Boxes {
    y0: I4,
    y1: I4,
    shown: Mask,
}

impl Boxes {
    /// Each lane's first and last row.
    #[inline(always)]
    fn rows(&self) -> ([i32; 4], [i32; 4]) {
        (self.y0.lanes(), self.y1.lanes())
    }
}

/// [`super::bbox`] of boxes centred at (`x`, `y`) with half sizes `rx`, `ry` (fixed point) on a grid whose last
/// column and row are `last`, and whether each is not empty. (In 32 bits: fixed-point coordinates are clamped to
/// the grid's reach, which [`Lanes::new`] bounds.)
#[inline(always)]
fn bbox(x: I4, y: I4, rx: I4, ry: I4, last: (I4, I4)) -> Boxes {
    let zero = I4::splat(0);
    let first = |a: I4| zero - (I4::splat((SUBPIXEL / 2) as i32) - a).shr8();
    let end = |b: I4| (b - I4::splat((SUBPIXEL / 2 + 1) as i32)).shr8();
    let (x0, y0) = (first(x - rx).max(zero), first(y - ry).max(zero));
    let (x1, y1) = (end(x + rx).min(last.0), end(y + ry).min(last.1));
    Boxes { y0, y1, shown: x0.gt(x1).or(y0.gt(y1)).not() }
}

// Four-lane values and their operations, an SSE2 instruction or two each. SAFETY, for every `unsafe` block below:
// SSE2 is part of x86-64's baseline, so its instructions exist on every machine this code is compiled for.

/// Four f32 lanes.
#[derive(Clone, Copy)]
struct F4(__m128);

/// A lane mask (all ones or all zeros per lane), from a comparison.
#[derive(Clone, Copy)]
struct Mask(__m128);

impl F4 {
    #[inline(always)]
    fn new(v: [f32; 4]) -> F4 {
        F4(unsafe { _mm_setr_ps(v[0], v[1], v[2], v[3]) })
    }

    #[inline(always)]
    fn splat(v: f32) -> F4 {
        F4(unsafe { _mm_set1_ps(v) })
    }

    #[inline(always)]
    fn lanes(self) -> [f32; 4] {
        // SAFETY: four f32 lanes are their array, bit for bit.
        unsafe { std::mem::transmute::<__m128, [f32; 4]>(self.0) }
    }

    #[inline(always)]
    fn lt(self, o: F4) -> Mask {
        Mask(unsafe { _mm_cmplt_ps(self.0, o.0) })
    }

    #[inline(always)]
    fn le(self, o: F4) -> Mask {
        Mask(unsafe { _mm_cmple_ps(self.0, o.0) })
    }

    #[inline(always)]
    fn ge(self, o: F4) -> Mask {
        Mask(unsafe { _mm_cmpge_ps(self.0, o.0) })
    }

    #[inline(always)]
    fn gt(self, o: F4) -> Mask {
        Mask(unsafe { _mm_cmpgt_ps(self.0, o.0) })
    }

    /// The magnitude per lane (the sign bit cleared, as `f32::abs`).
    #[inline(always)]
    fn abs(self) -> F4 {
        F4(unsafe { _mm_andnot_ps(_mm_set1_ps(-0.0), self.0) })
    }

    /// Whole-valued lanes as integers.
    #[inline(always)]
    fn to_ints(self) -> [i32; 4] {
        I4(unsafe { _mm_cvtps_epi32(self.0) }).lanes()
    }

    /// The lesser per lane (as `f32::min` where neither is NaN).
    #[inline(always)]
    fn min(self, o: F4) -> F4 {
        F4(unsafe { _mm_min_ps(self.0, o.0) })
    }

    /// The greater per lane (as `f32::max` where neither is NaN).
    #[inline(always)]
    fn max(self, o: F4) -> F4 {
        F4(unsafe { _mm_max_ps(self.0, o.0) })
    }

    /// `project`'s `fixed` for finite lanes: clamped to ±`lim` and rounded to the fixed-point grid, ties to even.
    #[inline(always)]
    fn fixed(self, lim: f32) -> I4 {
        let v = self.min(F4::splat(lim)).max(F4::splat(-lim)) * F4::splat(SUBPIXEL as f32);
        I4(unsafe { _mm_cvtps_epi32(v.0) })
    }

    /// The lanes (as mask bits) in which every one of `vs` is finite.
    #[inline(always)]
    fn finite(vs: &[F4]) -> i32 {
        let inf = F4::splat(f32::INFINITY);
        // |v| < ∞ is false for ±∞ and NaN.
        vs.iter().fold(0b1111, |m, v| m & v.abs().lt(inf).bits())
    }
}

impl Mask {
    /// No lane set.
    // SAFETY: any bits are a valid vector.
    const NONE: Mask = Mask(unsafe { std::mem::transmute::<[u32; 4], __m128>([0; 4]) });

    /// `a` where set, else `b`.
    #[inline(always)]
    fn pick(self, a: F4, b: F4) -> F4 {
        F4(unsafe { _mm_or_ps(_mm_and_ps(self.0, a.0), _mm_andnot_ps(self.0, b.0)) })
    }

    /// `a` where set, else `b`.
    #[inline(always)]
    fn pick_i(self, a: I4, b: I4) -> I4 {
        let m = unsafe { _mm_castps_si128(self.0) };
        I4(unsafe { _mm_or_si128(_mm_and_si128(m, a.0), _mm_andnot_si128(m, b.0)) })
    }

    /// Set where either is.
    #[inline(always)]
    fn or(self, o: Mask) -> Mask {
        Mask(unsafe { _mm_or_ps(self.0, o.0) })
    }

    /// Set where `self` is not.
    #[inline(always)]
    fn not(self) -> Mask {
        Mask(unsafe { _mm_xor_ps(self.0, _mm_castsi128_ps(_mm_set1_epi32(-1))) })
    }

    /// Set where `self` is and `o` is not.
    #[inline(always)]
    fn and_not(self, o: Mask) -> Mask {
        Mask(unsafe { _mm_andnot_ps(o.0, self.0) })
    }

    /// One bit per lane, lane 0 lowest.
    #[inline(always)]
    fn bits(self) -> i32 {
        unsafe { _mm_movemask_ps(self.0) }
    }
}

/// Four i32 lanes.
#[derive(Clone, Copy)]
struct I4(__m128i);

impl I4 {
    #[inline(always)]
    fn splat(v: i32) -> I4 {
        I4(unsafe { _mm_set1_epi32(v) })
    }

    #[inline(always)]
    fn lanes(self) -> [i32; 4] {
        // SAFETY: four i32 lanes are their array, bit for bit.
        unsafe { std::mem::transmute::<__m128i, [i32; 4]>(self.0) }
    }

    /// An arithmetic shift right by 8: the floor of a division by 256, as `>>` on `i64`.
    #[inline(always)]
    fn shr8(self) -> I4 {
        I4(unsafe { _mm_srai_epi32::<8>(self.0) })
    }

    #[inline(always)]
    fn gt(self, o: I4) -> Mask {
        Mask(unsafe { _mm_castsi128_ps(_mm_cmpgt_epi32(self.0, o.0)) })
    }

    /// The greater per lane (SSE2 has no `pmaxsd`: a comparison and a select).
    #[inline(always)]
    fn max(self, o: I4) -> I4 {
        self.gt(o).pick_i(self, o)
    }

    /// The lesser per lane.
    #[inline(always)]
    fn min(self, o: I4) -> I4 {
        o.gt(self).pick_i(self, o)
    }
}

/// `impl $op for $t` as one SSE2 instruction, lane by lane.
macro_rules! lanewise {
    ($($t:ident: $op:ident::$f:ident = $intrinsic:ident;)*) => {$(
        impl $op for $t {
            type Output = $t;
            #[inline(always)]
            fn $f(self, o: $t) -> $t {
                $t(unsafe { $intrinsic(self.0, o.0) })
            }
        }
    )*};
}

lanewise! {
    I4: Add::add = _mm_add_epi32;
    I4: Sub::sub = _mm_sub_epi32;
    Mask: BitAnd::bitand = _mm_and_ps;
    F4: Add::add = _mm_add_ps;
    F4: Sub::sub = _mm_sub_ps;
    F4: Mul::mul = _mm_mul_ps;
    F4: Div::div = _mm_div_ps;
}

impl Neg for F4 {
    type Output = F4;
    /// The sign flipped, as scalar negation (not `0 − x`, which differs at zero).
    #[inline(always)]
    fn neg(self) -> F4 {
        F4(unsafe { _mm_xor_ps(self.0, _mm_set1_ps(-0.0)) })
    }
}

#[cfg(test)]
mod tests {
    use glam::{Mat4, Vec4};

    use super::*;
    use crate::render::splat::{Projected, Shape, SplatSettings};

    /// The view matrix of a camera at `eye` looking at `target`, y up (OpenGL's: −z forward).
    fn look_at(eye: Vec3, target: Vec3) -> Mat4 {
        let f = (target - eye).normalize();
        let r = f.cross(Vec3::Y).normalize();
        let u = r.cross(f);
        Mat4::from_cols(
            Vec4::new(r.x, u.x, -f.x, 0.0),
            Vec4::new(r.y, u.y, -f.y, 0.0),
            Vec4::new(r.z, u.z, -f.z, 0.0),
            Vec4::new(-r.dot(eye), -u.dot(eye), f.dot(eye), 1.0),
        )
    }

    /// Four lanes at a time give what one point at a time gives, bit for bit, for every shape and size, near and
    /// far planes, sizes on either side of the minimum footprint, and points no lane can draw (behind the eye,
    /// huge, infinite, NaN).
    #[test]
    fn four_lanes_project_as_one_point_at_a_time() {
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut unit = || {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            (state >> 40) as f32 / (1u64 << 24) as f32
        };
        let settings = [
            (Shape::Cube, Size::World(0.004), 1.0),
            (Shape::Cube, Size::World(0.004), 0.0),
            (Shape::Cube, Size::World(0.05), 1.0),
            (Shape::Cube, Size::Pixels(1.5), 2.5),
            (Shape::Square, Size::Pixels(1.0), 1.0),
            (Shape::Square, Size::World(0.004), 1.0),
            (Shape::Square, Size::World(0.02), 0.0),
            (Shape::Disk, Size::World(0.01), 2.0),
        ];
        let mut seen = [0usize; 3];
        for (case, &(shape, size, min_px)) in settings.iter().enumerate() {
            // Two random eyes, and two on diagonals, whose points below are exactly as far from them along x as
            // along z or y (a cube's face is chosen by the first of the greatest).
            let eyes = [
                (1i64, Vec3::new(3.0 * unit() - 1.5, 2.0 * unit() + 0.5, 4.0)),
                (2, Vec3::new(3.0 * unit() - 1.5, 2.0 * unit() + 0.5, 4.0)),
                (1, Vec3::new(2.0, 1.0, 2.0)),
                (1, Vec3::new(2.0, 3.0, 0.0)),
            ];
            for (k, eye) in eyes {
                let w2c = look_at(eye, Vec3::new(0.0, 1.0, 0.0));
                let (w, h) = (800 - 100 * case as i64, 600);
                let p = Projection {
                    w2c,
                    f: [900.0 * k as f32, 900.0 * k as f32, 400.0 * k as f32, 300.0 * k as f32],
                    near: 0.5,
                    far: 6.0,
                    size: (w * k, h * k),
                };
                let s = SplatSettings { shape, size, min_px };
                // The eye as given, rather than as inverting the view recovers it, so that the ties below are exact.
                let foot = Footprint { eye, ..Footprint::new(&p, &s, k as f32) };
                let lanes = Lanes::new(&p, &foot).expect("lanes for every shape but surfels");
                let forward = (Vec3::new(0.0, 1.0, 0.0) - eye).normalize();
                let mut points: Vec<Vec3> = (0..40_000)
                    .map(|i| match i % 8 {
                        // Around the near and far planes (and a cube's reach past the near one).
                        0 => eye + forward * (0.45 + 0.1 * unit()),
                        1 => eye + forward * (5.95 + 0.1 * unit()) + Vec3::X * (unit() - 0.5),
                        // Behind the eye.
                        2 => eye - forward * unit(),
                        // Far off to a side: clamped to the grid's reach.
                        3 => eye + forward + Vec3::X * 1e4 * (unit() - 0.5),
                        _ => Vec3::new(unit() - 0.5, 2.0 * unit(), unit() - 0.5) * 3.0,
                    })
                    .collect();
                points.extend((1..200).flat_map(|i| {
                    let (a, b) = (i as f32 / 64.0, (i % 9) as f32 / 32.0 - 0.125);
                    [eye + Vec3::new(-a, b, -a), eye + Vec3::new(-a, -a, b), eye + Vec3::new(-a, -b, -a)]
                }));
                points.extend([
                    Vec3::new(f32::NAN, 1.0, 0.0),
                    Vec3::new(f32::INFINITY, 1.0, 0.0),
                    Vec3::new(0.0, f32::NEG_INFINITY, 0.0),
                    Vec3::new(1e30, 1.0, 0.0),
                ]);
                // Each sample row its own band, so that the bands say the rows.
                let band_of: Vec<u32> = (0..p.size.1 as u32).collect();
                let sink = |flat, solid| Sink { flat, solid, band_of: &band_of };
                let (mut flat, mut solid, mut flat_one, mut solid_one) = (vec![], vec![], vec![], vec![]);
                let mut four_at_once = sink(&mut flat, &mut solid);
                for (q, four) in points.chunks_exact(4).enumerate() {
                    lanes.project4(four.try_into().unwrap(), 4 * q as u32, &p, &foot, &mut four_at_once);
                }
                let mut one_by_one = sink(&mut flat_one, &mut solid_one);
                for (i, pos) in points.iter().enumerate().take(points.len() / 4 * 4) {
                    let one = project(*pos, Vec3::ZERO, &p, &foot, i as u32);
                    seen[match &one {
                        None => 0,
                        Some((Projected::Flat(_), _)) => 1,
                        Some((Projected::Solid(_), _)) => 2,
                    }] += 1;
                    one_by_one.push(one);
                }
                assert_eq!((flat.len(), solid.len()), (flat_one.len(), solid_one.len()), "case {case}, k {k}");
                for (a, b) in flat.iter().zip(&flat_one) {
                    assert_eq!(format!("{a:?}"), format!("{b:?}"), "case {case}, k {k}");
                }
                for (a, b) in solid.iter().zip(&solid_one) {
                    assert_eq!(format!("{a:?}"), format!("{b:?}"), "case {case}, k {k}");
                }
            }
        }
        // Every outcome was compared, many times over.
        assert!(seen.iter().all(|&n| n > 1000), "{seen:?}");
    }
}
