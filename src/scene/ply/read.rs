//! Decoding a PLY body into [`PlyData`]: the common binary cloud layouts through the one-pass decoder of the
//! `columns` module, other fixed-size binary rows (any scalar type) read straight from the row, and a general
//! path for everything else (ascii, lists).

use super::columns::{Columns, Layout};
use super::header::{parse_header, Element, Format, Scalar};
use super::PlyError;

mod faces;

pub(crate) use faces::{texture_comment, texturing};

/// What vvgen takes from a PLY: points with optional normals and colours, and triangles.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct PlyData {
    /// Vertex positions.
    pub positions: Vec<[f32; 3]>,
    /// Vertex normals, when the file has nx/ny/nz.
    pub normals: Option<Vec<[f32; 3]>>,
    /// Vertex colours as sRGB bytes (float colours in 0..1 are converted), when the file has them; a 3D Gaussian
    /// splatting file's are its Gaussians' base colours ([`gaussian_splats`]).
    pub colors: Option<Vec<[u8; 4]>>,
    /// Per-vertex texture coordinates (`texture_u`/`texture_v`, `s`/`t` or `u`/`v`; v up), when the file has them.
    pub uvs: Option<Vec<[f32; 2]>>,
    /// Triangles, indices into `positions`: polygons filled as Blender fills them (a convex one as the fan from its
    /// first corner, a concave one or a folded quad otherwise: [`crate::scene::polygon`]), and triangle strips cut
    /// into triangles as Blender 4.x cuts them.
    pub triangles: Vec<u32>,
    /// Per triangle corner (one pair per entry of `triangles`), its wedge texture coordinates (v up): a face
    /// element's `texcoord` list, when it has one and the header names a texture (`comment TextureFile`).
    pub corner_uvs: Option<Vec<[f32; 2]>>,
    /// Per triangle, which of the header's `TextureFile` comments (counted from 0) it is textured by: a face
    /// element's `texnumber` (OpenMVS's, with more than one texture), when it has one and the header names a
    /// texture.
    pub texnumbers: Option<Vec<u32>>,
    /// Whether some polygon was filled otherwise than by the fan from its first corner, which every polygon was
    /// until "ply polygons 1" (sequences' frames with such polygons are keyed apart).
    pub unfanned: bool,
    /// Header comments.
    pub comments: Vec<String>,
    /// A 3D Gaussian splatting file's Gaussians beside their centres (`positions`), as the file stores them, when
    /// it has their shapes ([`GaussianColumns`]).
    pub gaussians: Option<GaussianColumns>,
}

/// 3D Gaussians as graphdeco-inria's `save_ply` writes them, one row per point kept in [`PlyData::positions`]:
/// the raw stored values, before the activations (`exp` of the scales, the sigmoid of the opacity, the
/// quaternion's normalization) that [`crate::scene::gaussians`] applies.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct GaussianColumns {
    /// `scale_0..2`: log standard deviations along the Gaussian's own axes.
    pub scales: Vec<[f32; 3]>,
    /// `rot_0..3`: its rotation as a quaternion (w, x, y, z), not necessarily of unit length.
    pub rotations: Vec<[f32; 4]>,
    /// `opacity`: the logit of its peak opacity.
    pub opacities: Vec<f32>,
    /// Spherical-harmonic degree: 0 to 3, from how many `f_rest_*` the file has (0, 9, 24 or 45).
    pub degree: usize,
    /// Per Gaussian, its `(degree + 1)²` colour coefficients, band 0 (`f_dc_*`) first, each an (r, g, b).
    /// The file stores the higher bands channel by channel (`f_rest_k` is red's coefficient `k + 1` for k below
    /// `(degree + 1)² − 1`, then green's, then blue's); this is them regrouped per coefficient.
    pub sh: Vec<[f32; 3]>,
}

pub(super) const SLOT_X: usize = 0;
pub(super) const SLOT_NX: usize = 3;
pub(super) const SLOT_R: usize = 6;
pub(super) const SLOT_A: usize = 9;
pub(super) const SLOT_U: usize = 10;
/// A 3D Gaussian's colour at band 0 of its spherical harmonics (`f_dc_0`, `_1`, `_2`), and its opacity's logit.
pub(super) const SLOT_DC: usize = 12;
pub(super) const SLOT_OPACITY: usize = 15;
/// Its log scales (`scale_0..2`), rotation (`rot_0..3`) and higher spherical-harmonic bands (`f_rest_0..44`).
const SLOT_SCALE: usize = 16;
const SLOT_ROT: usize = 19;
const SLOT_REST: usize = 23;
/// The most `f_rest_*` a file can hold: degree 3, 15 coefficients per channel.
const REST: usize = 45;
const SLOTS: usize = SLOT_REST + REST;
pub(super) const NO_SLOT: usize = usize::MAX;

/// Where a vertex property's value goes (`SLOT_*`), or [`NO_SLOT`] for one vvgen does not read.
pub(super) fn slot(name: &str) -> usize {
    match name {
        "x" => 0,
        "y" => 1,
        "z" => 2,
        "nx" => 3,
        "ny" => 4,
        "nz" => 5,
        "red" | "r" | "diffuse_red" => 6,
        "green" | "g" | "diffuse_green" => 7,
        "blue" | "b" | "diffuse_blue" => 8,
        "alpha" | "a" | "diffuse_alpha" => 9,
        "texture_u" | "s" | "u" => 10,
        "texture_v" | "t" | "v" => 11,
        "f_dc_0" => 12,
        "f_dc_1" => 13,
        "f_dc_2" => 14,
        "opacity" => 15,
        "scale_0" => SLOT_SCALE,
        "scale_1" => SLOT_SCALE + 1,
        "scale_2" => SLOT_SCALE + 2,
        "rot_0" => SLOT_ROT,
        "rot_1" => SLOT_ROT + 1,
        "rot_2" => SLOT_ROT + 2,
        "rot_3" => SLOT_ROT + 3,
        _ => match name.strip_prefix("f_rest_").and_then(|k| k.parse::<usize>().ok()) {
            // `f_rest_7`, not `f_rest_07`: only the names 3DGS writes.
            Some(k) if k < REST && name == format!("f_rest_{k}") => SLOT_REST + k,
            _ => NO_SLOT,
        },
    }
}

/// The spherical-harmonic degree of a Gaussian element: the highest whose `f_rest_*` it has in full (3DGS
/// writes none, 9, 24 or 45 of them).
fn sh_degree(has: impl Fn(usize) -> bool) -> usize {
    let mut degree = 0;
    for d in 1..=3 {
        let n = 3 * ((d + 1) * (d + 1) - 1);
        if (0..n).all(|k| has(SLOT_REST + k)) {
            degree = d;
        }
    }
    degree
}

/// Whether a Gaussian element also has its shape: `scale_0..2` and `rot_0..3`, beside what
/// [`gaussian_splats`] asks. Without them (a cloud of coloured centres) it is read as points.
fn gaussian_shapes(el: &Element) -> bool {
    let has = |s: usize| el.props.iter().any(|p| p.list.is_none() && slot(&p.name) == s);
    gaussian_splats(el) && (SLOT_SCALE..SLOT_ROT + 4).all(has)
}

/// Whether a vertex element holds 3D Gaussians as 3D Gaussian splatting writes them (graphdeco-inria's
/// `save_ply`, and the trainers and editors that share its layout): a colour at band 0 of spherical harmonics
/// (`f_dc_0`, `f_dc_1`, `f_dc_2`) and an `opacity`, and no `red`, `green`, `blue` (a file with both keeps its
/// colours). vvgen reads each Gaussian as a point at its centre: its colour the band-0 colour as 3DGS's own
/// conversion gives it (`0.5 + C0 · f_dc`, clamped to 0..1, times 255 rounded down: what its tools write as a
/// cloud's colours), and a Gaussian whose opacity never reaches 1/255 (the least alpha 3DGS's rasterizer blends) is
/// left out, since nothing of it shows in any view. Its size, orientation, view-dependent colour (`f_rest_*`) and
/// translucency are not read.
pub fn gaussian_splats(el: &Element) -> bool {
    let has = |s: usize| el.props.iter().any(|p| p.list.is_none() && slot(&p.name) == s);
    (SLOT_DC..SLOT_DC + 3).all(has) && has(SLOT_OPACITY) && !(SLOT_R..SLOT_R + 3).all(has)
}

/// Whether the points of the file with `header` are 3D Gaussians ([`gaussian_splats`]).
pub fn holds_gaussian_splats(header: &super::Header) -> bool {
    let points = points_element(header);
    header.elements.iter().find(|e| e.name == points).is_some_and(gaussian_splats)
}

/// Whether the points of the file with `header` are 3D Gaussians with their shapes (scales and rotations), which
/// [`read`] gives in [`PlyData::gaussians`].
pub fn holds_gaussian_shapes(header: &super::Header) -> bool {
    let points = points_element(header);
    header.elements.iter().find(|e| e.name == points).is_some_and(gaussian_shapes)
}

/// The constant of band 0 of the real spherical harmonics, 1 / (2 √π), as 3DGS writes it.
const SH_C0: f64 = 0.28209479177387814;

/// A Gaussian's sRGB colour bytes from its band-0 coefficients (`v[SLOT_DC..]`): 3DGS's `SH2RGB`, clamped, as its
/// tools turn a Gaussian file into a coloured cloud.
#[inline]
fn splat_rgba8(v: &[f64; SLOTS]) -> [u8; 4] {
    let q = |c: f64| ((0.5 + SH_C0 * c).clamp(0.0, 1.0) * 255.0).floor() as u8;
    [q(v[SLOT_DC]), q(v[SLOT_DC + 1]), q(v[SLOT_DC + 2]), 255]
}

/// Whether a Gaussian of opacity logit `o` shows anywhere: its peak alpha, sigmoid(o), reaches 1/255 (3DGS's
/// rasterizer skips any smaller contribution). A NaN is kept: the positions' check names bad rows, not this.
#[inline]
fn splat_shows(o: f64) -> bool {
    o.is_nan() || 1.0 / (1.0 + (-o).exp()) >= 1.0 / 255.0
}

/// Reads a PLY from memory.
pub fn read(bytes: &[u8]) -> Result<PlyData, PlyError> {
    read_at(bytes, [0.0; 3])
}

/// [`read`] with `origin` subtracted from the positions as they are decoded, in double precision: a file's
/// double coordinates far from zero keep the detail near `origin` that single precision would lose.
pub fn read_at(bytes: &[u8], origin: [f64; 3]) -> Result<PlyData, PlyError> {
    let header = parse_header(bytes)?;
    let body = &bytes[header.body_start..];
    let mut out = PlyData { comments: header.comments.clone(), ..Default::default() };
    let mut cursor = Cursor { body, pos: 0, format: header.format };
    let mut vertex_seen = false;
    let points = points_element(&header);
    for el in &header.elements {
        match el.name.as_str() {
            name if name == points && !vertex_seen => {
                vertex_seen = true;
                let checked = read_vertices(&mut cursor, el, &mut out, origin)?;
                check_finite(&out.positions, checked, points)?;
            }
            "face" => faces::read(&mut cursor, el, &mut out)?,
            "tristrips" => faces::read_strips(&mut cursor, el, &out.positions, &mut out.triangles)?,
            _ => cursor.skip_element(el)?,
        }
    }
    // Triangles from elsewhere than the faces (strips beside them) have no wedge coordinates of their own.
    if let Some(uvs) = &mut out.corner_uvs {
        uvs.resize(out.triangles.len(), [0.0; 2]);
    }
    if let Some(n) = &mut out.texnumbers {
        n.resize(out.triangles.len() / 3, 0);
    }
    if !vertex_seen {
        return Err(PlyError::Unusable("no `vertex` (or `point`) element".into()));
    }
    Ok(out)
}

/// Subtracts `origin` from single-precision positions (a layout read as f32), in double precision; returns
/// whether it moved them (and so whether their finiteness must be checked again: a far origin can overflow).
pub(super) fn shift(positions: &mut [[f32; 3]], origin: [f64; 3]) -> bool {
    if origin == [0.0; 3] {
        return false;
    }
    for p in positions {
        *p = [0, 1, 2].map(|k| (f64::from(p[k]) - origin[k]) as f32);
    }
    true
}

/// Refuses positions with a NaN or an infinity (they would reach fits, bounds, cameras and images as garbage),
/// naming the first such row of `element`. `known_finite`: the decoder already checked them on the way; otherwise
/// a branch-free pass runs first, and the search for the row only when something is not finite.
pub(super) fn check_finite(positions: &[[f32; 3]], known_finite: bool, element: &str) -> Result<(), PlyError> {
    let finite = known_finite
        || positions.iter().fold(true, |ok, p| ok & p[0].is_finite() & p[1].is_finite() & p[2].is_finite());
    match (!finite).then(|| positions.iter().position(|p| !p.iter().all(|c| c.is_finite()))).flatten() {
        Some(row) => {
            let msg = format!("position {:?} is not finite", positions[row]);
            Err(PlyError::Body { element: element.into(), row, msg })
        }
        None => Ok(()),
    }
}

/// The fewest bytes a row of `el` can take: its scalars and list counts in binary; in ascii, a character and a
/// separator per property.
pub(super) fn min_row(el: &Element, format: Format) -> usize {
    match format {
        Format::Ascii => 2 * el.props.len().max(1),
        _ => el.props.iter().map(|p| p.list.map_or(p.ty.size(), |c| c.size())).sum::<usize>().max(1),
    }
}

/// `el` declares more rows than the `remaining` bytes of the file can hold.
pub(super) fn too_many_rows(el: &Element, remaining: u64) -> PlyError {
    PlyError::Truncated(format!(
        "element `{}` declares {} rows, more than the remaining {remaining} bytes can hold",
        el.name, el.count
    ))
}

/// The element the points are read from: `vertex`, else `point` (some writers' name).
pub(super) fn points_element(header: &super::Header) -> &'static str {
    if header.elements.iter().any(|e| e.name == "vertex") {
        "vertex"
    } else {
        "point"
    }
}

/// Refuses a point element without `x`, `y` and `z` scalars.
pub(super) fn require_xyz(el: &Element) -> Result<(), PlyError> {
    let has = |s: usize| el.props.iter().any(|p| p.list.is_none() && slot(&p.name) == s);
    if !(has(SLOT_X) && has(SLOT_X + 1) && has(SLOT_X + 2)) {
        if el.props.iter().any(|p| p.name == "packed_position") {
            // SuperSplat's and PlayCanvas's compressed layout: positions quantized within chunks.
            return Err(PlyError::Unusable(
                "a compressed Gaussian splatting PLY (SuperSplat's `packed_position` layout), which vvgen does not \
                 read: `npx @playcanvas/splat-transform in.compressed.ply out.ply` writes the plain 3DGS layout, \
                 which vvgen reads"
                    .into(),
            ));
        }
        return Err(PlyError::Unusable("the vertex element has no x, y, z".into()));
    }
    Ok(())
}

struct Cursor<'a> {
    body: &'a [u8],
    pos: usize,
    format: Format,
}

impl<'a> Cursor<'a> {
    fn remaining(&self) -> usize {
        self.body.len() - self.pos
    }

    /// Rejects counts the rest of the file cannot hold, before allocating for them.
    fn check_count(&self, el: &Element) -> Result<(), PlyError> {
        if el.count.checked_mul(min_row(el, self.format)).is_none_or(|n| n > self.remaining()) {
            return Err(too_many_rows(el, self.remaining() as u64));
        }
        Ok(())
    }

    #[inline]
    fn token(&mut self) -> Option<&'a [u8]> {
        let b = self.body;
        let mut i = self.pos;
        while i < b.len() && b[i].is_ascii_whitespace() {
            i += 1;
        }
        let s = i;
        while i < b.len() && !b[i].is_ascii_whitespace() {
            i += 1;
        }
        self.pos = i;
        (i > s).then(|| &b[s..i])
    }

    /// Ends an ASCII row: values left on the line its last value was on are skipped. Every writer puts a row on a
    /// line; VCGLIB (MeshLab's library) writes face rows with more values than their header declares, which
    /// Blender's importer and trimesh ignore, as here (a row may still run over several lines).
    #[inline]
    fn end_row(&mut self) {
        if self.format != Format::Ascii {
            return;
        }
        let b = self.body;
        let mut i = self.pos;
        while i < b.len() && b[i] != b'\n' && b[i] != b'\r' {
            i += 1;
        }
        self.pos = i;
    }

    /// One value of type `ty`.
    #[inline]
    fn value(&mut self, ty: Scalar, el: &Element, row: usize) -> Result<f64, PlyError> {
        match self.format {
            Format::Ascii => {
                let t = self
                    .token()
                    .ok_or_else(|| PlyError::Truncated(format!("element `{}` row {row} is incomplete", el.name)))?;
                parse_number(t).ok_or_else(|| PlyError::Body {
                    element: el.name.clone(),
                    row,
                    msg: format!("`{}` is not a number", String::from_utf8_lossy(t)),
                })
            }
            f => {
                let n = ty.size();
                if self.remaining() < n {
                    return Err(PlyError::Truncated(format!("element `{}` row {row} is incomplete", el.name)));
                }
                let v = ty.read(&self.body[self.pos..], f == Format::BinaryBe);
                self.pos += n;
                Ok(v)
            }
        }
    }

    fn list_len(&mut self, count_ty: Scalar, el: &Element, row: usize) -> Result<usize, PlyError> {
        let v = self.value(count_ty, el, row)?;
        if !(v >= 0.0 && v.fract() == 0.0 && v <= u32::MAX as f64) {
            return Err(PlyError::Body {
                element: el.name.clone(),
                row,
                msg: format!("list length {v} is not a count"),
            });
        }
        Ok(v as usize)
    }

    fn skip_element(&mut self, el: &Element) -> Result<(), PlyError> {
        self.check_count(el)?;
        for row in 0..el.count {
            for p in &el.props {
                match p.list {
                    None => {
                        self.value(p.ty, el, row)?;
                    }
                    Some(c) => {
                        let n = self.list_len(c, el, row)?;
                        if self.format != Format::Ascii {
                            let bytes = n.checked_mul(p.ty.size()).filter(|&b| b <= self.remaining());
                            self.pos += bytes.ok_or_else(|| {
                                PlyError::Truncated(format!("element `{}` row {row}: list of {n} items", el.name))
                            })?;
                        } else {
                            for _ in 0..n {
                                self.value(p.ty, el, row)?;
                            }
                        }
                    }
                }
            }
            self.end_row();
        }
        Ok(())
    }
}

/// Parses an ascii number; integers take a fast path (8i frames are all integers).
#[inline]
fn parse_number(t: &[u8]) -> Option<f64> {
    let (neg, digits) = match t.first()? {
        b'-' => (true, &t[1..]),
        b'+' => (false, &t[1..]),
        _ => (false, t),
    };
    if !digits.is_empty() && digits.len() <= 15 && digits.iter().all(u8::is_ascii_digit) {
        let v = digits.iter().fold(0u64, |a, &d| a * 10 + (d - b'0') as u64) as f64;
        return Some(if neg { -v } else { v });
    }
    std::str::from_utf8(t).ok()?.parse::<f64>().ok()
}

/// Reads the vertex element into `out`; returns whether the positions were already found finite on the way (the
/// fast path checks as it reads; otherwise the caller checks).
fn read_vertices(c: &mut Cursor<'_>, el: &Element, out: &mut PlyData, origin: [f64; 3]) -> Result<bool, PlyError> {
    c.check_count(el)?;
    require_xyz(el)?;
    let n = el.count;
    if let Some(layout) = Layout::of(el, c.format) {
        // `check_count` made sure the body holds the rows.
        let data = &c.body[c.pos..c.pos + n * layout.row_size];
        let mut cols = Columns::new(&layout, n);
        layout.append(&mut cols, data);
        c.pos += data.len();
        let finite = cols.finish(out);
        return Ok(!shift(&mut out.positions, origin) && finite);
    }
    let slots: Vec<usize> = el.props.iter().map(|p| if p.list.is_some() { NO_SLOT } else { slot(&p.name) }).collect();
    let has = |s: usize| slots.contains(&s);
    let has_n = has(SLOT_NX) && has(SLOT_NX + 1) && has(SLOT_NX + 2);
    let has_c = has(SLOT_R) && has(SLOT_R + 1) && has(SLOT_R + 2);
    let has_uv = has(SLOT_U) && has(SLOT_U + 1);
    let splats = gaussian_splats(el);
    let mut gaussians = gaussian_shapes(el).then(|| GaussianColumns { degree: sh_degree(has), ..Default::default() });
    // Float colours are 0..1; integer colours scale by their type's maximum.
    let color_scale = el
        .props
        .iter()
        .zip(&slots)
        .find(|(_, &s)| s == SLOT_R)
        .map(|(p, _)| match p.ty {
            Scalar::F32 | Scalar::F64 => 255.0,
            Scalar::U16 | Scalar::I16 => 255.0 / 65535.0,
            _ => 1.0,
        })
        .unwrap_or(1.0);
    out.positions = Vec::with_capacity(n);
    let mut normals = Vec::with_capacity(if has_n { n } else { 0 });
    let mut colors = Vec::with_capacity(if has_c || splats { n } else { 0 });
    let mut uvs = Vec::with_capacity(if has_uv { n } else { 0 });
    let fixed: Option<Vec<usize>> =
        (c.format != Format::Ascii && el.props.iter().all(|p| p.list.is_none())).then(|| {
            let mut off = 0;
            el.props
                .iter()
                .map(|p| {
                    let o = off;
                    off += p.ty.size();
                    o
                })
                .collect()
        });
    let mut v = [0f64; SLOTS];
    v[SLOT_A] = 255.0;
    // The file's row being read, and the first Gaussian whose shape, opacity or colour is not a number.
    let (mut row, mut not_finite) = (0usize, None);
    // One row's values (by slot) onto the columns the element has.
    let mut push = |v: &[f64; SLOTS]| {
        row += 1;
        if splats && !splat_shows(v[SLOT_OPACITY]) {
            return;
        }
        out.positions.push([(v[0] - origin[0]) as f32, (v[1] - origin[1]) as f32, (v[2] - origin[2]) as f32]);
        if has_n {
            normals.push([v[3] as f32, v[4] as f32, v[5] as f32]);
        }
        if has_c {
            colors.push(to_rgba8(v, color_scale));
        } else if splats {
            colors.push(splat_rgba8(v));
        }
        if has_uv {
            uvs.push([v[SLOT_U] as f32, v[SLOT_U + 1] as f32]);
        }
        if let Some(g) = &mut gaussians {
            let per = (g.degree + 1) * (g.degree + 1) - 1;
            // An infinite opacity logit is a peak opacity of exactly 1 (or 0): what splat-transform writes for
            // quantized opacities at the ends, and what 3DGS's sigmoid makes of it. Anything else must be finite.
            let read = [SLOT_DC..SLOT_DC + 3, SLOT_SCALE..SLOT_ROT + 4, SLOT_REST..SLOT_REST + 3 * per];
            let finite = read.into_iter().flatten().all(|s| v[s].is_finite()) && !v[SLOT_OPACITY].is_nan();
            if not_finite.is_none() && !finite {
                not_finite = Some(row - 1);
            }
            g.scales.push([0, 1, 2].map(|k| v[SLOT_SCALE + k] as f32));
            g.rotations.push([0, 1, 2, 3].map(|k| v[SLOT_ROT + k] as f32));
            g.opacities.push(v[SLOT_OPACITY] as f32);
            g.sh.push([0, 1, 2].map(|c| v[SLOT_DC + c] as f32));
            for k in 0..per {
                g.sh.push([0, 1, 2].map(|c| v[SLOT_REST + c * per + k] as f32));
            }
        }
    };
    if let Some(offsets) = fixed {
        // Fixed-size rows: one bounds check for the whole element, then straight reads.
        let row_size: usize = el.props.iter().map(|p| p.ty.size()).sum();
        let total = row_size * n;
        if c.remaining() < total {
            return Err(PlyError::Truncated(format!("vertex data needs {total} bytes, {} remain", c.remaining())));
        }
        let be = c.format == Format::BinaryBe;
        let data = &c.body[c.pos..c.pos + total];
        let mapped: Vec<(usize, Scalar, usize)> = el
            .props
            .iter()
            .zip(&offsets)
            .zip(&slots)
            .filter(|(_, &s)| s != NO_SLOT)
            .map(|((p, &o), &s)| (o, p.ty, s))
            .collect();
        // (The common cloud layouts took the `columns` path above; this is any other mix of scalar types.)
        for row in data.chunks_exact(row_size) {
            for &(o, t, s) in &mapped {
                v[s] = t.read(&row[o..], be);
            }
            push(&v);
        }
        c.pos += total;
    } else {
        for row in 0..n {
            for (p, &s) in el.props.iter().zip(&slots) {
                match p.list {
                    None => {
                        let x = c.value(p.ty, el, row)?;
                        if s != NO_SLOT {
                            v[s] = x;
                        }
                    }
                    Some(ct) => {
                        let len = c.list_len(ct, el, row)?;
                        for _ in 0..len {
                            c.value(p.ty, el, row)?;
                        }
                    }
                }
            }
            c.end_row();
            push(&v);
        }
    }
    out.normals = has_n.then_some(normals);
    out.uvs = has_uv.then_some(uvs);
    out.colors = (has_c || splats).then_some(colors);
    if let Some(row) = not_finite {
        let msg =
            "a Gaussian's opacity, scale, rotation or colour (`opacity`, `scale_*`, `rot_*`, `f_dc_*`, `f_rest_*`) \
                   is not a finite number (an opacity may be infinite: a peak opacity of 1 or 0)"
                .into();
        return Err(PlyError::Body { element: el.name.clone(), row, msg });
    }
    out.gaussians = gaussians;
    Ok(false)
}

#[inline]
fn to_rgba8(v: &[f64; SLOTS], scale: f64) -> [u8; 4] {
    let q = |x: f64| (x * scale).round().clamp(0.0, 255.0) as u8;
    [q(v[6]), q(v[7]), q(v[8]), q(v[9])]
}
