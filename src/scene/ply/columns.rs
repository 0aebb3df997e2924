//! The fast path for what every writer of large clouds emits: binary rows (either byte order) of `x y z` float,
//! optionally `nx ny nz` float and `red green blue` uchar, each group's three properties side by side.
//! [`Layout::of`] says whether an element has that shape; [`Layout::append`] decodes rows of it in one pass, from
//! a whole body ([`read()`](super::read())) or chunk by chunk as a file streams in
//! ([`read_file`](super::read_file)).

use super::header::{Element, Format, Scalar};
use super::read::{slot, NO_SLOT, SLOT_A, SLOT_DC, SLOT_NX, SLOT_R, SLOT_U, SLOT_X};
use super::PlyData;

/// Where the groups sit in a row of a fast-path element.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) struct Layout {
    /// Bytes per row.
    pub row_size: usize,
    /// Offset of `x` (then `y`, `z`), f32.
    xyz: usize,
    /// Offset of `nx` (then `ny`, `nz`), f32, when the element has normals.
    nxyz: Option<usize>,
    /// Offset of `red` (then `green`, `blue`), u8, when the element has colours.
    rgb: Option<usize>,
    /// Big-endian rows.
    be: bool,
}

impl Layout {
    /// The element's layout, when it is binary, has no lists, texture coordinates, alpha or Gaussians' colours
    /// (`f_dc_*`: see [`gaussian_splats`](super::read::gaussian_splats)), and its position,
    /// normal and colour properties (those it has) are each three adjacent properties of one type: f32 for
    /// positions and normals, u8 for colours. Anything else takes the general path.
    pub fn of(el: &Element, format: Format) -> Option<Layout> {
        if format == Format::Ascii || el.props.iter().any(|p| p.list.is_some()) {
            return None;
        }
        // (offset, type, slot) of each property vvgen reads; the first of a repeated name wins.
        let mut mapped = Vec::with_capacity(el.props.len());
        let mut row_size = 0;
        for p in &el.props {
            let s = slot(&p.name);
            if s != NO_SLOT {
                mapped.push((row_size, p.ty, s));
            }
            row_size += p.ty.size();
        }
        let at = |s: usize| mapped.iter().find(|m| m.2 == s);
        let has = |s: usize| at(s).is_some();
        let group = |first: usize, ty: Scalar| -> Option<usize> {
            let (a, b, c) = (at(first)?, at(first + 1)?, at(first + 2)?);
            (a.1 == ty && b.1 == ty && c.1 == ty && b.0 == a.0 + ty.size() && c.0 == b.0 + ty.size()).then_some(a.0)
        };
        if has(SLOT_U) && has(SLOT_U + 1) || has(SLOT_A) || has(SLOT_DC) {
            return None;
        }
        let xyz = group(SLOT_X, Scalar::F32)?;
        let nxyz = match has(SLOT_NX) && has(SLOT_NX + 1) && has(SLOT_NX + 2) {
            true => Some(group(SLOT_NX, Scalar::F32)?),
            false => None,
        };
        let rgb = match has(SLOT_R) && has(SLOT_R + 1) && has(SLOT_R + 2) {
            true => Some(group(SLOT_R, Scalar::U8)?),
            false => None,
        };
        Some(Layout { row_size, xyz, nxyz, rgb, be: format == Format::BinaryBe })
    }

    /// Decodes the whole rows of `data` (a multiple of [`Layout::row_size`] bytes) onto the ends of `cols`.
    pub fn append(&self, cols: &mut Columns, data: &[u8]) {
        match self.be {
            false => self.append_in::<false>(cols, data),
            true => self.append_in::<true>(cols, data),
        }
    }

    /// [`Layout::append`] in one byte order.
    fn append_in<const BE: bool>(&self, cols: &mut Columns, data: &[u8]) {
        let (size, xyz) = (self.row_size, self.xyz);
        match (self.nxyz, self.rgb) {
            (None, None) => fill::<BE, false, false>(cols, data, size, [xyz, 0, 0]),
            // `x y z` float + `red green blue` uchar, the common capture layout: a copy with the row's size and
            // the offsets as constants, 17 % faster than the general one.
            (None, Some(12)) if xyz == 0 && size == 15 => fill::<BE, false, true>(cols, data, 15, [0, 0, 12]),
            (None, Some(c)) => fill::<BE, false, true>(cols, data, size, [xyz, 0, c]),
            (Some(nx), None) => fill::<BE, true, false>(cols, data, size, [xyz, nx, 0]),
            (Some(nx), Some(c)) => fill::<BE, true, true>(cols, data, size, [xyz, nx, c]),
        }
    }
}

/// The columns a [`Layout`] decodes into.
pub(super) struct Columns {
    positions: Vec<[f32; 3]>,
    normals: Option<Vec<[f32; 3]>>,
    colors: Option<Vec<[u8; 4]>>,
    /// Non-zero once a position with a NaN or infinity was decoded.
    bad: u32,
}

impl Columns {
    /// Empty columns with room for `n` rows of `layout`.
    pub fn new(layout: &Layout, n: usize) -> Columns {
        Columns {
            positions: Vec::with_capacity(n),
            normals: layout.nxyz.map(|_| Vec::with_capacity(n)),
            colors: layout.rgb.map(|_| Vec::with_capacity(n)),
            bad: 0,
        }
    }

    /// Moves the columns into `out`; returns whether every position is finite.
    pub fn finish(self, out: &mut PlyData) -> bool {
        out.positions = self.positions;
        out.normals = self.normals;
        out.colors = self.colors;
        out.uvs = None;
        self.bad == 0
    }
}

/// [`Layout::append`]'s loop, one copy per byte order and set of groups; `at` holds the offsets of `x`, `nx` and `red`. One pass
/// over the rows writes straight into the vectors' spare capacity and tests the positions' exponents for NaN and
/// infinity on the way: a 1M-point cloud in 1.6 ms instead of 2.45 ms with a `collect` per column (each reading
/// the rows again) and a second pass over the positions for the check.
#[inline(always)]
fn fill<const BE: bool, const NORMALS: bool, const COLORS: bool>(
    cols: &mut Columns,
    data: &[u8],
    row_size: usize,
    at: [usize; 3],
) {
    assert_eq!(data.len() % row_size, 0, "BUG: whole rows only");
    let n = data.len() / row_size;
    let empty = (&mut Vec::new(), &mut Vec::new());
    let (positions, normals, colors) = (
        &mut cols.positions,
        if NORMALS { cols.normals.as_mut().expect("BUG: the layout has normals") } else { empty.0 },
        if COLORS { cols.colors.as_mut().expect("BUG: the layout has colours") } else { empty.1 },
    );
    positions.reserve(n);
    normals.reserve(if NORMALS { n } else { 0 });
    colors.reserve(if COLORS { n } else { 0 });
    // A group of three f32 as bytes (a plain load in the machine's own byte order).
    let group = |r: &[u8], o: usize| -> [u8; 12] { r[o..o + 12].try_into().expect("BUG: the row holds the group") };
    let bits = |b: &[u8; 12], k: usize| {
        let w = [b[k], b[k + 1], b[k + 2], b[k + 3]];
        if BE {
            u32::from_be_bytes(w)
        } else {
            u32::from_le_bytes(w)
        }
    };
    // (Spelled out: `[0, 4, 8].map(…)` here made the loop 4× slower.)
    let floats = |b: [u8; 12]| -> [f32; 3] {
        [f32::from_bits(bits(&b, 0)), f32::from_bits(bits(&b, 4)), f32::from_bits(bits(&b, 8))]
    };
    // An f32 is NaN or infinite exactly when its exponent bits are all ones.
    let not_finite = |b: &[u8; 12], k: usize| (bits(b, k) & 0x7f80_0000 == 0x7f80_0000) as u32;
    let mut bad = 0u32;
    {
        let p = &mut positions.spare_capacity_mut()[..n];
        let nrm = &mut normals.spare_capacity_mut()[..if NORMALS { n } else { 0 }];
        let col = &mut colors.spare_capacity_mut()[..if COLORS { n } else { 0 }];
        for (i, r) in data.chunks_exact(row_size).enumerate() {
            let b = group(r, at[0]);
            bad |= not_finite(&b, 0) | not_finite(&b, 4) | not_finite(&b, 8);
            p[i].write(floats(b));
            if NORMALS {
                nrm[i].write(floats(group(r, at[1])));
            }
            if COLORS {
                let c: &[u8; 3] = r[at[2]..at[2] + 3].try_into().expect("BUG: the row holds the group");
                col[i].write([c[0], c[1], c[2], 255]);
            }
        }
    }
    // SAFETY: `data` holds exactly `n` whole rows, so the loop wrote the `n` spare slots after each vector's
    // length: the positions', and the normals' and colours' where their groups exist (otherwise those vectors
    // are the empty stand-ins and stay empty).
    unsafe {
        positions.set_len(positions.len() + n);
        normals.set_len(normals.len() + if NORMALS { n } else { 0 });
        colors.set_len(colors.len() + if COLORS { n } else { 0 });
    }
    cols.bad |= bad;
}
