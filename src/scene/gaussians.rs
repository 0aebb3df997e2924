//! 3D Gaussians (a 3D Gaussian splatting file's): what each Gaussian of a point primitive is beside its centre,
//! activated as graphdeco-inria's trainer activates what it stores, and carried through the source → world
//! transform so that the renderer (`render::gaussians`) draws them as that trainer's rasterizer does.

use std::sync::Arc;

use glam::{Mat3, Quat, Vec3};

use super::ply::GaussianColumns;

/// A file's Gaussians in its own axes, shared by every frame and view that draws them.
#[derive(Debug, Clone, PartialEq)]
pub struct GaussianData {
    /// Per Gaussian, R·S: its rotation times the diagonal of its standard deviations, so that its covariance is
    /// (R·S)(R·S)ᵀ (3DGS's `build_covariance_from_scaling_rotation`).
    pub factors: Vec<Mat3>,
    /// Per Gaussian, its peak opacity: the sigmoid of the stored logit.
    pub opacities: Vec<f32>,
    /// Spherical-harmonic degree, 0 to 3.
    pub degree: usize,
    /// Per Gaussian, `(degree + 1)²` colour coefficients (band 0 first), as the file stores them.
    pub sh: Vec<Vec3>,
}

impl GaussianData {
    /// The Gaussians a PLY's columns describe, activated as 3DGS activates them: `exp` of the log scales, the
    /// sigmoid of the opacity logit, the quaternion (w, x, y, z) normalized. A zero quaternion (no rotation can
    /// be read from it) is the identity, as a normalized zero would be NaN.
    pub fn from_columns(c: &GaussianColumns) -> GaussianData {
        let factors = c
            .scales
            .iter()
            .zip(&c.rotations)
            .map(|(s, &[w, x, y, z])| {
                let q = Quat::from_xyzw(x, y, z, w);
                let q = if q.length_squared() > 0.0 { q.normalize() } else { Quat::IDENTITY };
                Mat3::from_quat(q) * Mat3::from_diagonal(Vec3::from(*s).exp())
            })
            .collect();
        let opacities = c.opacities.iter().map(|&o| 1.0 / (1.0 + (-o).exp())).collect();
        GaussianData { factors, opacities, degree: c.degree, sh: c.sh.iter().map(|&v| Vec3::from(v)).collect() }
    }

    /// Coefficients per Gaussian: `(degree + 1)²`.
    pub fn per_gaussian(&self) -> usize {
        (self.degree + 1) * (self.degree + 1)
    }

    /// Feeds every value that shapes how the Gaussians look into `h` (a frame's geometry digest).
    pub fn hash_into(&self, h: &mut blake3::Hasher) {
        h.update(b"gaussians v1");
        h.update(&(self.degree as u64).to_le_bytes());
        // `Mat3` and `Vec3` are their floats in column order: the bytes of `to_cols_array` and `to_array`.
        for part in [bytemuck::cast_slice::<Mat3, u8>(&self.factors), bytemuck::cast_slice(&self.opacities)] {
            h.update(&(part.len() as u64).to_le_bytes());
            h.update(part);
        }
        h.update(bytemuck::cast_slice::<Vec3, u8>(&self.sh));
    }
}

/// The Gaussians of a point primitive, one per point: the file's (shared), and how the source → world transform
/// that placed the points maps the file's axes.
#[derive(Debug, Clone, PartialEq)]
pub struct Gaussians {
    /// What the file holds, in its axes.
    pub data: Arc<GaussianData>,
    /// The linear part of the transform from the file's axes to the world: a Gaussian's world covariance is
    /// L·Σ·Lᵀ, and its colour is read along the view direction taken back into the file's axes (L⁻¹·d), where
    /// its spherical harmonics were fitted.
    pub to_world: Mat3,
}

impl Gaussians {
    /// A file's Gaussians in its own axes.
    pub fn new(data: GaussianData) -> Gaussians {
        Gaussians { data: Arc::new(data), to_world: Mat3::IDENTITY }
    }

    /// The same Gaussians after the linear map `m` (the positions are moved by the caller).
    pub fn transformed(&self, m: Mat3) -> Gaussians {
        Gaussians { data: self.data.clone(), to_world: m * self.to_world }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn activations_are_3dgs_own() {
        let c = GaussianColumns {
            scales: vec![[0.0, 1.0f32.ln(), 2.0f32.ln()], [0.0; 3]],
            // 90° about z, stored unnormalized (w, x, y, z); then a zero quaternion.
            rotations: vec![[2.0, 0.0, 0.0, 2.0], [0.0; 4]],
            opacities: vec![0.0, 2.0],
            degree: 0,
            sh: vec![[0.1, 0.2, 0.3], [0.0; 3]],
        };
        let g = GaussianData::from_columns(&c);
        let cov = g.factors[0] * g.factors[0].transpose();
        // Standard deviations 1, 1, 2 along x, y, z; x and y swap under the quarter turn, z keeps 2² = 4.
        assert!((cov - Mat3::from_diagonal(Vec3::new(1.0, 1.0, 4.0))).abs_diff_eq(Mat3::ZERO, 1e-6), "{cov}");
        assert!((g.opacities[0] - 0.5).abs() < 1e-7 && (g.opacities[1] - 0.880_797).abs() < 1e-6);
        assert_eq!(g.factors[1], Mat3::IDENTITY);
        assert_eq!(g.per_gaussian(), 1);
    }
}
