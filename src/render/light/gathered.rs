//! What a frame's light action keeps ([`Gathered`]), and its bytes in the cache: written by
//! [`Gathered::encode`], read back by [`Gathered::decode`], which refuses bytes it cannot have written.

use glam::Vec3;

use super::penumbra::SunShade;
use super::{plane_grid, Visibility};

/// What a frame's light action keeps ([`super::FrameLight::gather`]): per primitive, per vertex, its [`Visibility`] with
/// the bounce gathered (none for points), and per ground plane its grids. Encoded for the cache by
/// [`Gathered::encode`].
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Gathered {
    pub(super) vertices: Vec<Vec<Visibility>>,
    pub(super) planes: Vec<plane_grid::PlaneGrids>,
}

impl Gathered {
    /// The bytes of the cache's blob, little-endian u32 counts and f32 values: the number of primitives, then per
    /// primitive its vertex count and each vertex's environment visibility, radiance from below and bounce;
    /// then the number of planes and per plane its four grids, each as a count and values, and the number of its
    /// suns' shadow lattices and each lattice ([`SunShade::encode`]).
    pub fn encode(&self) -> Vec<u8> {
        let mut out = Vec::new();
        let u32s = |out: &mut Vec<u8>, n: usize| out.extend((n as u32).to_le_bytes());
        let f32s = |out: &mut Vec<u8>, v: &[f32]| v.iter().for_each(|f| out.extend(f.to_le_bytes()));
        u32s(&mut out, self.vertices.len());
        for prim in &self.vertices {
            u32s(&mut out, prim.len());
            for v in prim {
                f32s(&mut out, &[v.env]);
                f32s(&mut out, &v.below.to_array());
                f32s(&mut out, &v.bounce.to_array());
            }
        }
        u32s(&mut out, self.planes.len());
        for g in &self.planes {
            u32s(&mut out, g.vis.len());
            f32s(&mut out, &g.vis);
            u32s(&mut out, g.sun.len());
            f32s(&mut out, &g.sun);
            for grid in [&g.lamps, &g.bounce] {
                u32s(&mut out, grid.len());
                grid.iter().for_each(|c| f32s(&mut out, &c.to_array()));
            }
            u32s(&mut out, g.shades.len());
            g.shades.iter().for_each(|s| s.encode(&mut out));
        }
        out
    }

    /// Reads back what [`Gathered::encode`] wrote: an error for bytes it cannot have written (truncated,
    /// trailing, a grid of another size, a value that is not finite), and never an allocation larger than the
    /// bytes.
    pub fn decode(bytes: &[u8]) -> Result<Gathered, GatheredError> {
        let mut r = Reader { bytes, at: 0 };
        let prims = r.count(4)?;
        let mut vertices = Vec::with_capacity(prims);
        for _ in 0..prims {
            let n = r.count(28)?;
            let f = r.f32s(n * 7)?;
            let v3 = |c: &[f32]| Vec3::new(c[0], c[1], c[2]);
            vertices.push(
                f.chunks_exact(7)
                    .map(|c| Visibility { env: c[0], below: v3(&c[1..4]), bounce: v3(&c[4..7]) })
                    .collect(),
            );
        }
        let planes = r.count(16)?;
        let mut grids = Vec::with_capacity(planes);
        for _ in 0..planes {
            let n = r.count(4)?;
            let vis = r.f32s(n)?;
            let n = r.count(4)?;
            let sun = r.f32s(n)?;
            let mut colours = [Vec::new(), Vec::new()];
            for c in &mut colours {
                let n = r.count(12)?;
                *c = r.f32s(n * 3)?.chunks_exact(3).map(|c| Vec3::new(c[0], c[1], c[2])).collect();
            }
            let [lamps, bounce] = colours;
            let sized = |len: usize| len == 0 || len == plane_grid::GRID_POINTS;
            if vis.len() != plane_grid::GRID_POINTS || !sized(sun.len()) || !sized(lamps.len()) || !sized(bounce.len())
            {
                return Err(GatheredError::Damaged("a ground grid of another size"));
            }
            let n = r.count(12)?;
            let mut shades = Vec::with_capacity(n);
            for _ in 0..n {
                let side = r.u32()? as usize;
                let block = r.n_u32()?;
                let vis = r.n_u16()?;
                let cells = plane_grid::PLANE_CELLS * plane_grid::PLANE_CELLS;
                shades.push(SunShade::from_parts(side, block, vis, cells).map_err(GatheredError::Damaged)?);
            }
            grids.push(plane_grid::PlaneGrids { vis, sun, lamps, bounce, shades });
        }
        if r.at != bytes.len() {
            return Err(GatheredError::Damaged("trailing bytes"));
        }
        Ok(Gathered { vertices, planes: grids })
    }
}

/// Why a frame's gathered light read back from the cache cannot light it (a damaged or stale cache).
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum GatheredError {
    /// The bytes are not what [`Gathered::encode`] writes.
    #[error("damaged gathered light: {0}")]
    Damaged(&'static str),
    /// It was gathered for a scene of another shape.
    #[error("the frame's gathered light does not fit its scene (another frame's, or a stale cache)")]
    OtherScene,
}

/// A cursor over a [`Gathered`] blob.
struct Reader<'b> {
    bytes: &'b [u8],
    at: usize,
}

impl Reader<'_> {
    /// A count of items of at least `size` bytes each, refused when the bytes left cannot hold that many (so a
    /// corrupt count never sizes an allocation).
    fn count(&mut self, size: usize) -> Result<usize, GatheredError> {
        let n = self.u32()? as usize;
        if n > (self.bytes.len() - self.at) / size {
            return Err(GatheredError::Damaged("truncated"));
        }
        Ok(n)
    }

    /// One u32.
    fn u32(&mut self) -> Result<u32, GatheredError> {
        let b = self.take(4)?;
        Ok(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    }

    /// A count and that many u32s.
    fn n_u32(&mut self) -> Result<Vec<u32>, GatheredError> {
        let n = self.count(4)?;
        let b = self.take(4 * n)?;
        Ok(b.chunks_exact(4).map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]])).collect())
    }

    /// A count and that many u16s.
    fn n_u16(&mut self) -> Result<Vec<u16>, GatheredError> {
        let n = self.count(2)?;
        let b = self.take(2 * n)?;
        Ok(b.chunks_exact(2).map(|c| u16::from_le_bytes([c[0], c[1]])).collect())
    }

    /// The next `len` bytes.
    fn take(&mut self, len: usize) -> Result<&[u8], GatheredError> {
        let b = self.bytes.get(self.at..self.at + len).ok_or(GatheredError::Damaged("truncated"))?;
        self.at += len;
        Ok(b)
    }

    /// `n` finite f32s.
    fn f32s(&mut self, n: usize) -> Result<Vec<f32>, GatheredError> {
        let b = self.take(4 * n)?;
        let v: Vec<f32> = b.chunks_exact(4).map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]])).collect();
        if v.iter().all(|f| f.is_finite()) {
            Ok(v)
        } else {
            Err(GatheredError::Damaged("a value that is not finite"))
        }
    }
}
