//! Percentage-closer filtering: how a shadow map's lookups ([`super::shadow::ShadowMap`]) read its depths. A
//! bilinear lookup compares the four texels about a point against the receiver's plane there and blends the
//! answers ([`bilinear`]); a soft shadow's filter makes that lookup at each point of an N × N grid and averages
//! them ([`filter`]).

use glam::{Vec2, Vec3};

use crate::scene::texture::floor;

/// A square depth map as the lookups read it: nearest caster depth per texel, row by row.
#[derive(Debug, Clone, Copy)]
pub(super) struct Depths<'a> {
    pub(super) depth: &'a [f32],
    pub(super) size: u32,
}

impl Depths<'_> {
    /// Nearest caster depth at texel (x, y); outside the map, nothing.
    #[inline]
    pub(super) fn at(&self, x: i64, y: i64) -> f32 {
        if x < 0 || y < 0 || x >= self.size as i64 || y >= self.size as i64 {
            return f32::INFINITY;
        }
        self.depth[(y as u32 * self.size + x as u32) as usize]
    }

    /// Nearest caster depth at texel (x, y), which lies in the map.
    #[inline]
    pub(super) fn texel(&self, x: i64, y: i64) -> f32 {
        self.depth[(y * self.size as i64 + x) as usize]
    }

    /// Whether texels `x0..=x1` × `y0..=y1` all lie in the map.
    #[inline]
    pub(super) fn holds(&self, x0: i64, y0: i64, x1: i64, y1: i64) -> bool {
        let n = self.size as i64;
        x0 >= 0 && y0 >= 0 && x1 < n && y1 < n
    }
}

/// One axis of a bilinear percentage-closer lookup at light-space coordinate `c`: the lower of the two texels
/// read, the upper one's weight, and the receiver plane's offset (`slope` per texel) at the two texels' centres
/// from `c`.
#[derive(Debug, Clone, Copy)]
pub(super) struct PcfAxis {
    pub(super) texel: i64,
    weight: f32,
    plane: [f32; 2],
}

impl PcfAxis {
    #[inline]
    pub(super) fn new(c: f32, slope: f32) -> PcfAxis {
        let f = c - 0.5;
        let texel = floor(f);
        let plane = [slope * (texel as f32 + 0.5 - c), slope * ((texel + 1) as f32 + 0.5 - c)];
        PcfAxis { texel, weight: f - texel as f32, plane }
    }
}

/// The bilinear percentage-closer lookup of one column and row against the receiver's depth `recv` at their
/// point; `inside` when its four texels lie in the map.
#[inline]
pub(super) fn bilinear(d: Depths, col: &PcfAxis, row: &PcfAxis, recv: f32, inside: bool) -> f32 {
    let tap = |dx: usize, dy: usize| {
        let (x, y) = (col.texel + dx as i64, row.texel + dy as i64);
        let depth = if inside { d.texel(x, y) } else { d.at(x, y) };
        if depth < recv + (col.plane[dx] + row.plane[dy]) {
            0.0
        } else {
            1.0
        }
    };
    let (l00, l10, l01, l11) = (tap(0, 0), tap(1, 0), tap(0, 1), tap(1, 1));
    let top = l00 + (l10 - l00) * col.weight;
    let bottom = l01 + (l11 - l01) * col.weight;
    top + (bottom - top) * row.weight
}

/// The mean of [`bilinear`] lookups at the points of an N × N grid about light-space `q`, offsets `r` along each
/// axis, against the receiver's plane through depth `recv` at `q` with `slope` per texel; each column's and row's
/// texels, weights and plane offsets are found once.
#[inline]
pub(super) fn filter<const N: usize>(d: Depths, q: Vec3, recv: f32, slope: Vec2, r: &[f32; N]) -> f32 {
    let cols = r.map(|o| PcfAxis::new(q.x + o, slope.x));
    let rows = r.map(|o| PcfAxis::new(q.y + o, slope.y));
    let inside = d.holds(cols[0].texel, rows[0].texel, cols[N - 1].texel + 1, rows[N - 1].texel + 1);
    let mut lit = 0.0;
    for (j, row) in rows.iter().enumerate() {
        for (i, col) in cols.iter().enumerate() {
            lit += bilinear(d, col, row, recv + (slope.x * r[i] + slope.y * r[j]), inside);
        }
    }
    lit / (N * N) as f32
}
