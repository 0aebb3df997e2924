//! Blender's AgX view transform (4.x's default): scene-linear Rec.709 light to display-linear sRGB light, as
//! Blender 4.5's OpenColorIO configuration does it for an sRGB display.
//!
//! Blender's chain is: Rec.709 → FilmLight E-Gamut (a matrix), a log2 allocation of −12.47393 … 12.5260688
//! stops (0.18 · 2^−10 … 0.18 · 2^15) onto 0 … 1, a 57³ table read by tetrahedral interpolation, and a 2.4
//! power; the sRGB encoding follows. Its table is the output of Eary Chow's AgX generator ("AgX_LUT_Gen",
//! `AgXBasesRGB.py`, after Troy Sobotka's AgX): per node, the log value is decoded to E-Gamut light, taken to
//! Rec.2020, its negatives lifted with the luminance kept (the lower "guard rail"), inset toward white by a
//! rotated matrix, encoded in log2 over −10 … +6.5 stops around 0.18, shaped by Jed Smith's tunable sigmoid
//! (pivot at middle grey, slope 2.4, powers 1.5), decoded by a 2.4 power, its hue mixed back 60 % toward the
//! hue before the curve, outset, taken to Rec.709, its negatives lifted again, and stored under a 1/2.4 power.
//! This module computes that table itself ([`Agx::table`]) from those published steps, so nothing of Blender's
//! is shipped, and reads it as OpenColorIO does; `benches/agx_reference.sh` compares it with Blender's file and
//! with ramps Blender renders.

// The matrices are written digit for digit as the configurations publish them (f64 rounds the tails).
#![allow(clippy::excessive_precision)]

use std::sync::LazyLock;

use glam::{DMat3, DVec3, Vec3};

/// Nodes along each side of the table, as in Blender's `AgX_Base_sRGB.cube`.
const SIDE: usize = 57;

/// The log2 allocation in front of the table: the input's stops (log2 of linear light), mapped onto 0 … 1.
const ALLOCATION: (f64, f64) = (-12.47393, 12.5260688117);

/// Middle grey, the pivot of the log encodings.
const MIDDLE_GREY: f64 = 0.18;

/// The formation's log2 range around middle grey, in stops.
const FORMATION: (f64, f64) = (-10.0, 6.5);

/// How much of the hue after the curve is kept (the rest is the hue before it).
const HUE_MIX: f64 = 0.4;

/// Row-major 3 × 3 matrices as the published configurations write them.
fn rows(m: [[f64; 3]; 3]) -> DMat3 {
    DMat3::from_cols_array_2d(&m).transpose()
}

/// FilmLight E-Gamut → CIE XYZ (D65).
fn e_gamut_to_xyz() -> DMat3 {
    rows([
        [0.7053968501, 0.1640413283, 0.08101774865],
        [0.2801307241, 0.8202066415, -0.1003373656],
        [-0.1037815116, -0.07290725703, 1.265746519],
    ])
}

/// Rec.2020 → CIE XYZ (D65).
fn rec2020_to_xyz() -> DMat3 {
    rows([
        [0.6369535067850740, 0.1446191846692331, 0.1688558539228734],
        [0.2626983389565560, 0.6780087657728165, 0.0592928952706273],
        [0.0000000000000000, 0.0280731358475570, 1.0608272349505707],
    ])
}

/// CIE XYZ (D65) → Rec.709, as Blender's configuration writes it.
fn xyz_to_rec709() -> DMat3 {
    rows([
        [3.2404373564920070, -1.5371305409000549, -0.4985288240756933],
        [-0.9692674982687597, 1.8760136862977035, 0.0415560804587997],
        [0.0556434463874256, -0.2040259700872272, 1.0572254813610864],
    ])
}

/// The inset: primaries rotated by (3, −1, −2)° and pulled toward white by (0.4, 0.22, 0.13) (Troy Sobotka's
/// SB2383 parameters), in Rec.2020.
fn inset() -> DMat3 {
    rows([
        [0.856627153315983, 0.0951212405381588, 0.0482516061458583],
        [0.137318972929847, 0.761241990602591, 0.101439036467562],
        [0.11189821299995, 0.0767994186031903, 0.811302368396859],
    ])
}

/// The outset: the inverse of an inset by (0.4, 0.22, 0.04) without rotation.
fn outset() -> DMat3 {
    rows([
        [0.899796955911611, 0.0871996192028351, 0.013003424885555],
        [0.11142098895748, 0.875575586156966, 0.0130034248855548],
        [0.11142098895748, 0.0871996192028349, 0.801379391839686],
    ])
    .inverse()
}

/// The luminance weights of Rec.2020 the guard rails keep (CIE 2015 observer, the generator's Blender-era
/// figures).
const LUMINANCE_2020: DVec3 = DVec3::new(0.2658180370250449, 0.59846986045365, 0.1357121025213052);

/// Jed Smith's tunable sigmoid with AgX's parameters: a line of slope 2.4 through the pivot (middle grey's
/// log position, middle grey's 2.4-power encoding), joined on either side by x / (1 + x^1.5)^(1/1.5) curves
/// scaled to meet (0, 0) and (1, 1).
fn sigmoid(x: f64) -> f64 {
    let (slope, power) = (2.4, 1.5);
    let px = -FORMATION.0 / (FORMATION.1 - FORMATION.0);
    let py = MIDDLE_GREY.powf(1.0 / 2.4);
    // The scale that makes the curve from the pivot (tx, ty) meet (1, 1) (toe: mirrored).
    let scale = |tx: f64, ty: f64| {
        let a = (slope * (1.0 - tx)).powf(-power);
        let b = (slope * (1.0 - tx) / (1.0 - ty)).powf(power) - 1.0;
        (a * b).powf(-1.0 / power)
    };
    let curve = |s: f64| {
        let z = slope * (x - px) / s;
        s * (z / (1.0 + z.powf(power)).powf(1.0 / power)) + py
    };
    if x < px {
        curve(-scale(1.0 - px, 1.0 - py))
    } else if x <= px {
        slope * x + (py - slope * px)
    } else {
        curve(scale(px, py))
    }
}

/// RGB → (hue 0 … 1, saturation, value), the EasyRGB formulation colour-science uses.
fn to_hsv(c: DVec3) -> DVec3 {
    let (max, min) = (c.max_element(), c.min_element());
    let delta = max - min;
    if delta == 0.0 {
        return DVec3::new(0.0, 0.0, max);
    }
    let s = if max != 0.0 { delta / max } else { 0.0 };
    let d = |v: f64| ((max - v) / 6.0 + delta / 2.0) / delta;
    let (dr, dg, db) = (d(c.x), d(c.y), d(c.z));
    let mut h = if max == c.z {
        2.0 / 3.0 + dg - dr
    } else if max == c.y {
        1.0 / 3.0 + dr - db
    } else {
        db - dg
    };
    if h < 0.0 {
        h += 1.0;
    }
    if h > 1.0 {
        h -= 1.0;
    }
    DVec3::new(h, s, max)
}

/// (hue, saturation, value) → RGB, the inverse of [`to_hsv`].
fn from_hsv(hsv: DVec3) -> DVec3 {
    let (v, s) = (hsv.z, hsv.y);
    let mut h = hsv.x * 6.0;
    if h == 6.0 {
        h = 0.0;
    }
    let i = h.floor();
    let f = h - i;
    let (j, k, l) = (v * (1.0 - s), v * (1.0 - s * f), v * (1.0 - s * (1.0 - f)));
    match i as i64 {
        0 => DVec3::new(v, l, j),
        1 => DVec3::new(k, v, j),
        2 => DVec3::new(j, v, l),
        3 => DVec3::new(j, k, v),
        4 => DVec3::new(l, j, v),
        5 => DVec3::new(v, j, k),
        _ => DVec3::ZERO,
    }
}

/// The lower guard rail: `rgb` (in a space whose luminance `y` measures) shifted so that no channel is
/// negative, then scaled down where the shift raised its luminance (measured with the opponent colour's, so
/// that a negative luminance counts).
fn lift_negatives(rgb: DVec3, y: impl Fn(DVec3) -> f64, soften: bool) -> DVec3 {
    let opponent = |c: DVec3| {
        let inv = DVec3::splat(c.max_element()) - c;
        inv.max_element() - y(inv) + y(c)
    };
    let (mut before, offset) = (y(rgb), (-rgb.min_element()).max(0.0));
    let shifted = rgb + DVec3::splat(offset);
    let mut after = y(shifted);
    if soften {
        // The sRGB rail lets the opponent's term count only for small luminances (Y^0.08 of the way back); a
        // negative luminance has no such power, and the generator leaves that colour unscaled.
        if before < 0.0 {
            return shifted;
        }
        let lerp = |t: f64, a: f64, b: f64| a + t * (b - a);
        before = lerp(before.powf(0.08).clamp(0.0, 1.0), opponent(rgb), before);
        after = lerp(after.max(0.0).powf(0.08).clamp(0.0, 1.0), opponent(shifted), after);
        let ratio = if after > before { before / after.max(1e-100) } else { 1.0 };
        return shifted * ratio;
    }
    let (before, after) = (opponent(rgb), opponent(shifted));
    let ratio = if after > before { before / after } else { 1.0 };
    shifted * ratio
}

/// The generator's matrices, made once for all the table's nodes.
struct Formation {
    /// E-Gamut → Rec.2020.
    to_2020: DMat3,
    inset: DMat3,
    outset: DMat3,
    /// Rec.2020 → Rec.709 (through XYZ, the generator's matrices), and back.
    to_709: DMat3,
    from_709: DMat3,
}

impl Formation {
    fn new() -> Formation {
        let to_709 = rec709_from_xyz_generator() * rec2020_to_xyz();
        Formation {
            to_2020: rec2020_to_xyz().inverse() * e_gamut_to_xyz(),
            inset: inset(),
            outset: outset(),
            to_709,
            from_709: to_709.inverse(),
        }
    }

    /// The table's value at normalized log input `u` (E-Gamut, per channel): display light under a 1/2.4
    /// power, 0 … 1.
    fn formed(&self, u: DVec3) -> DVec3 {
        let e_gamut = u.map(|u| MIDDLE_GREY * (u * 25.0 - 10.0).exp2());
        let mut c = self.to_2020 * e_gamut;
        c = lift_negatives(c, |c| c.dot(LUMINANCE_2020), false);
        c = self.inset * c;
        let hue_before = to_hsv(c).x;
        let log = c.map(|v| ((v / MIDDLE_GREY).log2() - FORMATION.0) / (FORMATION.1 - FORMATION.0));
        c = log.map(sigmoid).map(|v| v.max(0.0).powf(2.4));
        let mut hsv = to_hsv(c);
        hsv.x = hue_before + HUE_MIX * (hsv.x - hue_before);
        c = self.outset * from_hsv(hsv);
        // To Rec.709, then the sRGB medium's rail.
        c = lift_negatives(self.to_709 * c, |c| (self.from_709 * c).dot(LUMINANCE_2020), true);
        let out = c.map(|v| v.max(0.0).powf(1.0 / 2.4).clamp(0.0, 1.0));
        if out.is_finite() {
            out
        } else {
            DVec3::ZERO
        }
    }
}

/// CIE XYZ (D65) → Rec.709, as the generator writes it.
fn rec709_from_xyz_generator() -> DMat3 {
    rows([
        [3.24100323297635872776822907326277, -1.53739896948878551619088739244035, -0.49861588199636291962590917137277],
        [-0.96922425220251640087809619217296, 1.87592998369517593992839010752505, 0.04155422634008471699518239006466],
        [0.05563941985197547179797794569822, -0.20401120612390993835916219723003, 1.05714897718753331190555400098674],
    ])
}

/// The AgX view transform: its table, made once per process.
pub struct Agx {
    /// Scene-linear Rec.709 → E-Gamut.
    to_e_gamut: glam::Mat3,
    /// SIDE³ nodes, red fastest (the `.cube` order).
    table: Vec<Vec3>,
}

static AGX: LazyLock<Agx> = LazyLock::new(Agx::new);

impl std::fmt::Debug for Agx {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("Agx")
    }
}

impl Agx {
    /// The transform (its table is computed on first use: about 0.1 s).
    pub fn get() -> &'static Agx {
        &AGX
    }

    fn new() -> Agx {
        use rayon::prelude::*;
        let n = SIDE - 1;
        let formation = Formation::new();
        let table = (0..SIDE * SIDE * SIDE)
            .into_par_iter()
            .map(|k| {
                let (r, g, b) = (k % SIDE, (k / SIDE) % SIDE, k / (SIDE * SIDE));
                formation.formed(DVec3::new(r as f64, g as f64, b as f64) / n as f64).as_vec3()
            })
            .collect();
        // Blender: Rec.709 → XYZ (D65, its own matrix) → E-Gamut; the E white point's adaptation there and back
        // cancels.
        let to_e_gamut = (e_gamut_to_xyz().inverse() * xyz_to_rec709().inverse()).as_mat3();
        Agx { to_e_gamut, table }
    }

    /// The table's nodes, red fastest: what `AgX_Base_sRGB.cube` lists.
    pub fn table(&self) -> &[Vec3] {
        &self.table
    }

    /// Scene-linear Rec.709 light `c` as AgX displays it: display-linear light, 0 … 1 (encode it as sRGB).
    pub fn display(&self, c: Vec3) -> Vec3 {
        let e = self.to_e_gamut * c;
        let u = e.to_array().map(|v| {
            let stops = if v > 0.0 { v.log2() } else { f32::NEG_INFINITY };
            ((stops - ALLOCATION.0 as f32) / (ALLOCATION.1 - ALLOCATION.0) as f32).clamp(0.0, 1.0)
        });
        let v = self.tetrahedral(u);
        v.map(|x| x.max(0.0).powf(2.4))
    }

    /// The table read at `u` (0 … 1 per channel) by tetrahedral interpolation, as OpenColorIO reads it.
    fn tetrahedral(&self, u: [f32; 3]) -> Vec3 {
        let n = (SIDE - 1) as f32;
        let p = u.map(|x| x * n);
        let i = p.map(|x| (x as usize).min(SIDE - 2));
        let f = [p[0] - i[0] as f32, p[1] - i[1] as f32, p[2] - i[2] as f32];
        let at =
            |dr: usize, dg: usize, db: usize| self.table[(i[0] + dr) + (i[1] + dg) * SIDE + (i[2] + db) * SIDE * SIDE];
        let (fr, fg, fb) = (f[0], f[1], f[2]);
        let c000 = at(0, 0, 0);
        let c111 = at(1, 1, 1);
        if fr > fg {
            if fg > fb {
                c000 + (at(1, 0, 0) - c000) * fr + (at(1, 1, 0) - at(1, 0, 0)) * fg + (c111 - at(1, 1, 0)) * fb
            } else if fr > fb {
                c000 + (at(1, 0, 0) - c000) * fr + (at(1, 0, 1) - at(1, 0, 0)) * fb + (c111 - at(1, 0, 1)) * fg
            } else {
                c000 + (at(0, 0, 1) - c000) * fb + (at(1, 0, 1) - at(0, 0, 1)) * fr + (c111 - at(1, 0, 1)) * fg
            }
        } else if fb > fg {
            c000 + (at(0, 0, 1) - c000) * fb + (at(0, 1, 1) - at(0, 0, 1)) * fg + (c111 - at(0, 1, 1)) * fr
        } else if fb > fr {
            c000 + (at(0, 1, 0) - c000) * fg + (at(0, 1, 1) - at(0, 1, 0)) * fb + (c111 - at(0, 1, 1)) * fr
        } else {
            c000 + (at(0, 1, 0) - c000) * fg + (at(1, 1, 0) - at(0, 1, 0)) * fr + (c111 - at(1, 1, 0)) * fb
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn middle_grey_is_displayed_as_middle_grey() {
        // The sigmoid's pivot: 0.18 of scene light shows as 0.18 of display light (sRGB code 118), as in
        // Blender's AgX.
        let d = Agx::get().display(Vec3::splat(0.18));
        assert!((d - Vec3::splat(0.18)).abs().max_element() < 2e-3, "{d}");
        // The curve meets its ends and rises between them.
        assert!((sigmoid(0.0)).abs() < 1e-9 && (sigmoid(1.0) - 1.0).abs() < 1e-9);
        let mut last = -1.0;
        for i in 0..=100 {
            let g = Agx::get().display(Vec3::splat(1e-4 * 1.2f32.powi(i))).x;
            assert!(g >= last, "{i}: {g} after {last}");
            last = g;
        }
    }

    #[test]
    fn the_table_is_blenders() {
        // Nodes of Blender 4.5's `AgX_Base_sRGB.cube` (7 decimals), a grey, colours inside and far outside
        // Rec.709, both ends; every node agrees (`benches/agx_reference.rs`).
        let blender = [
            ((0, 0, 0), [0.0000002, 0.0, 0.0000018]),
            ((28, 28, 28), [0.7853074, 0.7853064, 0.7853274]),
            ((56, 56, 56), [1.0, 1.0, 1.0]),
            ((8, 16, 26), [0.0, 0.2971745, 0.6539974]),
            ((40, 10, 5), [1.0, 0.9295653, 0.9159958]),
            ((20, 45, 33), [0.9724532, 1.0, 0.9898309]),
        ];
        let table = Agx::get().table();
        for ((r, g, b), want) in blender {
            let got = table[r + g * SIDE + b * SIDE * SIDE];
            assert!((got - Vec3::from_array(want)).abs().max_element() < 2e-6, "({r}, {g}, {b}): {got} vs {want:?}");
        }
    }

    #[test]
    fn hsv_round_trips() {
        for c in [DVec3::new(0.2, 0.5, 0.9), DVec3::new(0.9, 0.1, 0.3), DVec3::new(0.4, 0.4, 0.1), DVec3::splat(0.3)] {
            let back = from_hsv(to_hsv(c));
            assert!((back - c).abs().max_element() < 1e-12, "{c} → {back}");
        }
    }
}
