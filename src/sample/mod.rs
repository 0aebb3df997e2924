//! Surface sampling: a posed scene → points with normals and colours. Triangles are sampled area-uniformly
//! (stratified over the cumulative area, √r barycentrics); colours come from the material exactly as the
//! unlit renderer shades it (base colour × texture × COLOR_0). Point primitives pass through. Draws come from
//! streams keyed by (seed, frame, chunk), so the result does not depend on the thread count.

pub mod voxel;

use glam::{Vec2, Vec3, Vec4};
use rayon::prelude::*;

use crate::rig::random::Keyed;
use crate::scene::material::Srgb8;
use crate::scene::{PosedScene, PrimKind};

/// What can go wrong reading or re-evaluating samples.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A cached point blob is not in [`Points::to_bytes`] form.
    #[error("not a vvgen point blob (the cache entry is damaged)")]
    Damaged,
    /// Correspondence draws refer to triangles the frame does not have.
    #[error("the mesh's topology changed between frames: correspondence needs fixed triangles")]
    TopologyChanged,
}

/// Samples drawn per keyed chunk (the unit of parallel work).
const CHUNK: usize = 1 << 16;

/// First bytes of [`Points::to_bytes`] (version 2: normals and colours as binary16).
const RAW_MAGIC: &[u8; 8] = b"vvgenPT2";

/// Bytes per point in a blob: a position as three f32, a normal and a colour as three binary16 each.
const POINT_BYTES: usize = 12 + 6 + 6;

/// Values converted to or from binary16 at a time (on the stack: no blob-sized temporary).
const HALF_CHUNK: usize = 1024;

/// Sampled points.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Points {
    /// World positions.
    pub positions: Vec<[f32; 3]>,
    /// Unit normals (zero where unknown).
    pub normals: Vec<[f32; 3]>,
    /// Linear RGB colours.
    pub colors: Vec<[f32; 3]>,
}

impl Points {
    /// Number of points.
    pub fn len(&self) -> usize {
        self.positions.len()
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.positions.is_empty()
    }

    /// Appends `other`.
    pub fn extend(&mut self, other: &Points) {
        self.positions.extend_from_slice(&other.positions);
        self.normals.extend_from_slice(&other.normals);
        self.colors.extend_from_slice(&other.colors);
    }

    /// A compact binary form for the cache: magic, count, then positions as f32 and normals and colours as
    /// binary16 (IEEE half floats), all little-endian. Positions stay exact (they decide voxels); a unit normal
    /// or a linear colour keeps 11 significant bits: at most about a hundredth of a degree, or a thirtieth of an
    /// 8-bit sRGB step, far below what the writers keep. The blob is a third smaller than in f32 (a million
    /// points: 24 MB, not 36), and writing it was most of a point-cloud build's system time. Colours beyond binary16's range
    /// (65 504) are clamped to it, never written as infinities.
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut b = Vec::with_capacity(16 + self.len() * POINT_BYTES);
        b.extend_from_slice(RAW_MAGIC);
        b.extend_from_slice(&(self.len() as u64).to_le_bytes());
        let positions = self.positions.as_flattened();
        // Little-endian floats are their own bytes: one copy (extending a byte at a time was 2 % of a sequence
        // build's instructions).
        #[cfg(target_endian = "little")]
        b.extend_from_slice(bytemuck::cast_slice(positions));
        #[cfg(not(target_endian = "little"))]
        b.extend(positions.iter().flat_map(|c| c.to_le_bytes()));
        for v in [&self.normals, &self.colors] {
            put_halves(&mut b, v.as_flattened());
        }
        b
    }

    /// Reads [`Points::to_bytes`].
    pub fn from_bytes(b: &[u8]) -> Result<Points, Error> {
        let n = b.strip_prefix(RAW_MAGIC).and_then(|r| r.get(..8)).ok_or(Error::Damaged)?;
        let n = u64::from_le_bytes(n.try_into().expect("BUG: 8 bytes taken above")) as usize;
        let body = &b[16..];
        if Some(body.len()) != n.checked_mul(POINT_BYTES) {
            return Err(Error::Damaged);
        }
        let (positions, rest) = body.split_at(12 * n);
        let (normals, colors) = rest.split_at(6 * n);
        // One copy into aligned floats (the blob's bytes need not be aligned).
        #[cfg(target_endian = "little")]
        let positions: Vec<[f32; 3]> = bytemuck::pod_collect_to_vec(positions);
        #[cfg(not(target_endian = "little"))]
        let positions: Vec<[f32; 3]> = positions
            .chunks_exact(12)
            .map(|c| [0, 1, 2].map(|j| f32::from_le_bytes(c[4 * j..4 * j + 4].try_into().expect("BUG: 4 bytes"))))
            .collect();
        Ok(Points { positions, normals: get_halves(normals, n), colors: get_halves(colors, n) })
    }

    /// Colours as 8-bit sRGB.
    pub fn srgb8(&self) -> Vec<[u8; 3]> {
        let srgb = Srgb8::tables();
        self.colors.iter().map(|c| c.map(|v| srgb.encode(v))).collect()
    }
}

/// Appends `v` as little-endian binary16, clamped to its finite range (NaN stays NaN).
fn put_halves(b: &mut Vec<u8>, v: &[f32]) {
    use half::slice::HalfFloatSliceExt;
    let max = half::f16::MAX.to_f32();
    let (mut f, mut h) = ([0f32; HALF_CHUNK], [half::f16::ZERO; HALF_CHUNK]);
    for c in v.chunks(HALF_CHUNK) {
        let (f, h) = (&mut f[..c.len()], &mut h[..c.len()]);
        f.iter_mut().zip(c).for_each(|(d, s)| *d = s.clamp(-max, max));
        // With F16C (detected at run time) the conversion is a few instructions per eight values.
        h.convert_from_f32_slice(f);
        let bits: &[u16] = h.reinterpret_cast();
        #[cfg(target_endian = "little")]
        b.extend_from_slice(bytemuck::cast_slice(bits));
        #[cfg(not(target_endian = "little"))]
        b.extend(bits.iter().flat_map(|x| x.to_le_bytes()));
    }
}

/// Reads `n` triples of little-endian binary16 from `bytes` (of length 6·`n`).
fn get_halves(bytes: &[u8], n: usize) -> Vec<[f32; 3]> {
    use half::slice::{HalfBitsSliceExt, HalfFloatSliceExt};
    let mut out = vec![[0f32; 3]; n];
    let mut bits = [0u16; HALF_CHUNK];
    for (o, c) in out.as_flattened_mut().chunks_mut(HALF_CHUNK).zip(bytes.chunks(2 * HALF_CHUNK)) {
        let bits = &mut bits[..o.len()];
        bits.iter_mut().zip(c.chunks_exact(2)).for_each(|(d, s)| *d = u16::from_le_bytes([s[0], s[1]]));
        bits.reinterpret_cast::<half::f16>().convert_to_f32_slice(o);
    }
    out
}

/// A surface point by identity: a triangle (primitive, first index) and barycentric weights. Re-evaluated on
/// another frame of the same mesh, it is the same material point (temporal correspondence).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Draw {
    prim: u32,
    first: u32,
    bary: [f32; 3],
}

/// `n` area-uniform draws over `scene`'s triangles (none when it has no triangle area); `key` names the
/// random stream.
pub fn draw(scene: &PosedScene, n: usize, key: &[&[u8]]) -> Vec<Draw> {
    let mut tris = Vec::new();
    let mut cdf = Vec::new();
    let mut total = 0f64;
    for (pi, p) in scene.primitives.iter().enumerate() {
        if p.kind != PrimKind::Triangles {
            continue;
        }
        for (t, idx) in p.indices.chunks_exact(3).enumerate() {
            let [a, b, c] = [0, 1, 2].map(|k| p.positions[idx[k] as usize]);
            let area = 0.5 * (b - a).cross(c - a).length() as f64;
            if area > 0.0 {
                total += area;
                cdf.push(total);
                tris.push((pi as u32, 3 * t as u32));
            }
        }
    }
    if tris.is_empty() || n == 0 {
        return Vec::new();
    }
    let mut out = vec![Draw { prim: 0, first: 0, bary: [0.0; 3] }; n];
    out.par_chunks_mut(CHUNK).enumerate().for_each(|(c, chunk)| {
        let mut parts: Vec<&[u8]> = key.to_vec();
        let cb = (c as u64).to_le_bytes();
        parts.push(&cb);
        let mut k = Keyed::new("surface", &parts);
        let mut t = 0;
        for (j, d) in chunk.iter_mut().enumerate() {
            // Stratified: sample i draws from the i-th of n equal slices of the total area. The targets rise
            // with i, so the triangle search walks forward from the last one.
            let i = c * CHUNK + j;
            let u = (i as f64 + k.uniform_f32() as f64) / n as f64 * total;
            if j == 0 {
                t = cdf.partition_point(|&v| v <= u);
            }
            while t < tris.len() - 1 && cdf[t] <= u {
                t += 1;
            }
            t = t.min(tris.len() - 1);
            let (r1, r2) = (k.uniform_f32(), k.uniform_f32());
            let s = r1.sqrt();
            *d = Draw { prim: tris[t].0, first: tris[t].1, bary: [1.0 - s, s * (1.0 - r2), s * r2] };
        }
    });
    out
}

/// Colours a surface point ([`Site`]): lit ("baked") point colours. Without one, a point's colour is its albedo.
pub type Shader<'a> = &'a (dyn Fn(&Site) -> Vec3 + Sync);

/// A point a [`Shader`] colours: where it is and what it is made of.
#[derive(Debug, Clone, Copy)]
pub struct Site {
    /// Position.
    pub pos: Vec3,
    /// Unit normal, zero where unknown.
    pub normal: Vec3,
    /// Linear albedo.
    pub albedo: Vec3,
    /// Emitted radiance.
    pub emission: Vec3,
    /// On a triangle: its primitive (index into the scene's), its corners' vertex indices and the point's
    /// barycentric weights, so that what its vertices hold can be read there. `None` for a point primitive's.
    pub triangle: Option<(usize, [u32; 3], [f32; 3])>,
    /// Its material is shadeless (`KHR_materials_unlit`): lit or not, it keeps its albedo.
    pub shadeless: bool,
}

/// Evaluates `draws` on `scene` (the frame they were drawn on, or another frame of the same meshes).
pub fn evaluate(scene: &PosedScene, draws: &[Draw]) -> Result<Points, Error> {
    evaluate_shaded(scene, draws, None)
}

/// [`evaluate`], coloured by `shader` when given.
pub fn evaluate_shaded(scene: &PosedScene, draws: &[Draw], shader: Option<Shader>) -> Result<Points, Error> {
    let fits =
        |d: &Draw| scene.primitives.get(d.prim as usize).is_some_and(|p| (d.first as usize + 2) < p.indices.len());
    if !draws.par_iter().all(fits) {
        return Err(Error::TopologyChanged);
    }
    let n = draws.len();
    let mut out = Points { positions: vec![[0.0; 3]; n], normals: vec![[0.0; 3]; n], colors: vec![[0.0; 3]; n] };
    out.positions
        .par_chunks_mut(CHUNK)
        .zip(out.normals.par_chunks_mut(CHUNK))
        .zip(out.colors.par_chunks_mut(CHUNK))
        .zip(draws.par_chunks(CHUNK))
        .for_each(|(((pos, nrm), col), d)| {
            for (j, d) in d.iter().enumerate() {
                (pos[j], nrm[j], col[j]) = surface_point(scene, d, shader);
            }
        });
    Ok(out)
}

/// Every point of `scene`'s point primitives.
pub fn points(scene: &PosedScene) -> Points {
    points_shaded(scene, None)
}

/// [`points`], coloured by `shader` when given.
pub fn points_shaded(scene: &PosedScene, shader: Option<Shader>) -> Points {
    let mut out = Points::default();
    for p in scene.primitives.iter().filter(|p| p.kind == PrimKind::Points) {
        for i in 0..p.positions.len() {
            push_point(&mut out, scene, p, i, shader);
        }
    }
    out
}

/// Appends point `i` of point primitive `p`: its position, normal (zero where unknown) and linear albedo, or
/// its colour by `shader`.
#[inline]
fn push_point(
    out: &mut Points,
    scene: &PosedScene,
    p: &crate::scene::PosedPrimitive,
    i: usize,
    shader: Option<Shader>,
) {
    let (pos, n) = (p.positions[i], p.normals.get(i).copied().unwrap_or(Vec3::ZERO));
    out.positions.push(pos.to_array());
    out.normals.push(n.to_array());
    let (m, uv) = (scene.material(p.material), p.uvs.get(i).copied());
    let c = m.albedo(&scene.textures, uv, p.colors.get(i).copied()).truncate();
    let c = match shader {
        Some(shade) => {
            let emission = m.emission(&scene.textures, uv);
            shade(&Site { pos, normal: n, albedo: c, emission, triangle: None, shadeless: m.unlit })
        }
        None => c,
    };
    out.colors.push(c.to_array());
}

/// `n` area-uniform samples of `scene`'s triangles plus every point of its point primitives; `key` names the
/// random stream (e.g. seed and frame).
pub fn sample(scene: &PosedScene, n: usize, key: &[&[u8]]) -> Points {
    sample_shaded(scene, n, key, None)
}

/// [`sample`], coloured by `shader` when given.
pub fn sample_shaded(scene: &PosedScene, n: usize, key: &[&[u8]], shader: Option<Shader>) -> Points {
    let draws = draw(scene, n, key);
    let mut out = evaluate_shaded(scene, &draws, shader).expect("BUG: draws index the scene they were drawn on");
    out.extend(&points_shaded(scene, shader));
    out
}

/// At most `n` surface samples and at most `n` of the scene's points: [`sample`] for a cloud of a given size
/// (an initialization cloud, COLMAP's points3D), which must not grow with the input's point count. Points are
/// chosen uniformly without replacement by a stream keyed by `key`, kept in scene order.
pub fn sample_at_most(scene: &PosedScene, n: usize, key: &[&[u8]]) -> Points {
    let mut out = evaluate(scene, &draw(scene, n, key)).expect("BUG: draws index the scene they were drawn on");
    let total = scene.point_count();
    if total <= n {
        out.extend(&points(scene));
        return out;
    }
    // Floyd's algorithm: n distinct indices in 0..total, each subset equally likely.
    let mut parts: Vec<&[u8]> = vec![b"points"];
    parts.extend_from_slice(key);
    let mut k = Keyed::new("subsample", &parts);
    let mut chosen = std::collections::BTreeSet::new();
    for j in (total - n)..total {
        let t = k.below(j as u64 + 1) as usize;
        if !chosen.insert(t) {
            chosen.insert(j);
        }
    }
    let mut index = 0usize;
    let mut next = chosen.iter().copied().peekable();
    for p in scene.primitives.iter().filter(|p| p.kind == PrimKind::Points) {
        while let Some(&c) = next.peek() {
            let i = c - index;
            if i >= p.positions.len() {
                break;
            }
            next.next();
            push_point(&mut out, scene, p, i, None);
        }
        index += p.positions.len();
    }
    out
}

/// Position, unit normal and linear colour (albedo, or by `shader`) of the surface point `d`.
#[inline]
fn surface_point(scene: &PosedScene, d: &Draw, shader: Option<Shader>) -> ([f32; 3], [f32; 3], [f32; 3]) {
    let (p, b) = (&scene.primitives[d.prim as usize], d.bary);
    let idx = [0, 1, 2].map(|k| p.indices[(d.first + k) as usize] as usize);
    let lerp3 = |v: &[Vec3]| v[idx[0]] * b[0] + v[idx[1]] * b[1] + v[idx[2]] * b[2];
    let pos = lerp3(&p.positions);
    let n = if p.normals.len() == p.positions.len() {
        lerp3(&p.normals).normalize_or_zero()
    } else {
        let [a, bb, c] = idx.map(|i| p.positions[i]);
        (bb - a).cross(c - a).normalize_or_zero()
    };
    let uv: Option<Vec2> =
        (p.uvs.len() == p.positions.len()).then(|| p.uvs[idx[0]] * b[0] + p.uvs[idx[1]] * b[1] + p.uvs[idx[2]] * b[2]);
    let vc: Option<Vec4> = (p.colors.len() == p.positions.len())
        .then(|| p.colors[idx[0]] * b[0] + p.colors[idx[1]] * b[1] + p.colors[idx[2]] * b[2]);
    let m = scene.material(p.material);
    let c = m.albedo(&scene.textures, uv, vc).truncate();
    let c = match shader {
        Some(shade) => shade(&Site {
            pos,
            normal: n,
            albedo: c,
            emission: m.emission(&scene.textures, uv),
            triangle: Some((d.prim as usize, idx.map(|i| i as u32), b)),
            shadeless: m.unlit,
        }),
        None => c,
    };
    (pos.to_array(), n.to_array(), c.to_array())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The blob is the magic, the count, then positions as little-endian f32 and normals and colours as
    /// little-endian binary16, whatever the machine. Positions read back exactly, the others as their nearest
    /// binary16 (also from bytes at an odd address); a colour past binary16's range is clamped, never infinite;
    /// a truncated blob is refused.
    #[test]
    fn point_blobs_keep_positions_exactly_and_the_rest_as_half_floats() {
        let v = |i: u32| [i as f32 * 0.25 - 3.0, f32::from_bits(0x3f80_0001 + i), -0.0];
        let mut pts = Points {
            positions: (0..5).map(v).collect(),
            normals: (5..10).map(v).collect(),
            colors: (10..15).map(v).collect(),
        };
        pts.colors[4] = [1e6, -1e6, 0.2];
        let b = pts.to_bytes();
        let half = |x: f32| half::f16::from_f32(x.clamp(-65504.0, 65504.0));
        let mut expected = RAW_MAGIC.to_vec();
        expected.extend(5u64.to_le_bytes());
        expected.extend(pts.positions.iter().flatten().flat_map(|c| c.to_le_bytes()));
        for a in [&pts.normals, &pts.colors] {
            expected.extend(a.iter().flatten().flat_map(|&c| half(c).to_bits().to_le_bytes()));
        }
        assert_eq!(b, expected);
        assert_eq!(b.len(), 16 + 5 * POINT_BYTES);
        let mut odd = vec![0u8];
        odd.extend(&b);
        let back = Points::from_bytes(&odd[1..]).unwrap();
        let bits = |a: &[[f32; 3]]| a.iter().flatten().map(|c| c.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&back.positions), bits(&pts.positions));
        for (got, sent) in [(&back.normals, &pts.normals), (&back.colors, &pts.colors)] {
            let rounded: Vec<[f32; 3]> = sent.iter().map(|p| p.map(|c| half(c).to_f32())).collect();
            assert_eq!(bits(got), bits(&rounded));
        }
        assert_eq!(back.colors[4], [65504.0, -65504.0, half(0.2).to_f32()]);
        assert!(matches!(Points::from_bytes(&b[..b.len() - 1]), Err(Error::Damaged)));
    }
}
