//! The glTF 2.0 metallic-roughness BRDF: Lambertian diffuse plus GGX microfacet specular (height-correlated
//! Smith visibility, Schlick Fresnel), the model Blender's glTF importer maps onto its Principled BSDF.

use std::f32::consts::PI;
use std::sync::LazyLock;

use glam::{Vec2, Vec3};

/// A dielectric's reflectance at normal incidence at glTF's default index of refraction, for every channel.
pub const DIELECTRIC: Vec3 = Vec3::splat(crate::scene::material::DIELECTRIC_F0);

/// Smallest roughness shaded: a perfect mirror's lobe is a delta no punctual light can hit.
pub const MIN_ROUGHNESS: f32 = 0.03;

/// A surface point's material, after textures.
#[derive(Debug, Clone, Copy)]
pub struct Surface {
    /// Base colour (linear).
    pub base: Vec3,
    /// Metalness 0..1.
    pub metallic: f32,
    /// Perceptual roughness 0..1.
    pub roughness: f32,
    /// Dielectric specular scale (1: the layer as `f0` gives it; 0: Lambertian).
    pub specular: f32,
    /// A dielectric's reflectance at normal incidence, per channel (0.04 at glTF's default IOR, 1.5).
    pub f0: Vec3,
}

impl Surface {
    /// Normal-incidence reflectance.
    #[inline]
    pub fn f0(&self) -> Vec3 {
        self.f0.lerp(self.base, self.metallic)
    }

    /// The diffuse colour: metals have none.
    #[inline]
    pub fn diffuse(&self) -> Vec3 {
        self.base * (1.0 - self.metallic)
    }

    /// The specular layer's directional albedo seen at n·v = `nv` (the split sum's F0·A + B, times the layer's
    /// weight), multiple scattering included: what it reflects of a uniform environment, and what the diffuse
    /// layer under it does not receive.
    #[inline]
    pub fn specular_albedo(&self, nv: f32) -> Vec3 {
        let ab = dfg(nv, self.roughness);
        (self.f0() * ab.x + Vec3::splat(ab.y)) * self.specular_weight() * multiscatter(self.f0(), ab)
    }

    /// The BRDF times n·l for unit normal `n`, unit direction to the viewer `v` and to the light `l`.
    #[inline]
    pub fn eval(&self, n: Vec3, v: Vec3, l: Vec3) -> Vec3 {
        let nl = n.dot(l);
        if nl <= 0.0 {
            return Vec3::ZERO;
        }
        if self.specular_weight() == 0.0 {
            // No specular layer (the ground): Lambert, as the full expression gives with f = 0.
            return self.diffuse() / PI * nl;
        }
        let nv = n.dot(v).max(1e-4);
        let h = (v + l).normalize_or_zero();
        let (nh, vh) = (n.dot(h).max(0.0), v.dot(h).max(0.0));
        let f = schlick(self.f0(), vh) * self.specular_weight();
        let a = self.roughness.max(MIN_ROUGHNESS).powi(2);
        let spec = f * (ggx_d(nh, a) * smith_v(nl, nv, a));
        // The diffuse layer receives what the specular layer does not reflect.
        let diffuse = self.diffuse() * (Vec3::ONE - f) / PI;
        (diffuse + spec) * nl
    }
}

/// How much more a GGX lobe reflects with the light that bounces between its microfacets, which single scattering
/// (the split sum's A + B, `ab`) loses: 1 + F0·(1 / (A + B) − 1) (Fdez-Agüera, "A multiple-scattering
/// microfacet model for real-time image-based lighting", 2019; Turquin 2019). Blender 4.x's Principled BSDF
/// defaults to Multiscatter GGX, whose rough metals keep their energy; a rough dielectric's specular layer (F0
/// 0.04) gains up to 9 % at roughness 1. Applied to the environment's light (the split sum); a lamp's lobe stays
/// single-scattering, which keeps it reciprocal. Against Cycles, FlightHelmet's worst views rose 0.05–0.2 dB.
#[inline]
pub fn multiscatter(f0: Vec3, ab: Vec2) -> Vec3 {
    Vec3::ONE + f0 * (1.0 / (ab.x + ab.y).max(1e-3) - 1.0)
}

/// Schlick's Fresnel.
#[inline]
pub fn schlick(f0: Vec3, vh: f32) -> Vec3 {
    let m = (1.0 - vh).clamp(0.0, 1.0);
    let m5 = m * m * m * m * m;
    f0 + (Vec3::ONE - f0) * m5
}

/// The GGX (Trowbridge–Reitz) normal distribution for α = roughness².
#[inline]
pub fn ggx_d(nh: f32, a: f32) -> f32 {
    let a2 = a * a;
    let d = nh * nh * (a2 - 1.0) + 1.0;
    a2 / (PI * d * d)
}

/// Height-correlated Smith visibility V = G / (4 n·l n·v).
#[inline]
pub fn smith_v(nl: f32, nv: f32, a: f32) -> f32 {
    let a2 = a * a;
    let gv = nl * (nv * nv * (1.0 - a2) + a2).sqrt();
    let gl = nv * (nl * nl * (1.0 - a2) + a2).sqrt();
    0.5 / (gv + gl).max(1e-8)
}

/// Point `i` of an `n`-point Hammersley set in [0, 1)².
#[inline]
pub fn hammersley(i: u32, n: u32) -> Vec2 {
    Vec2::new((i as f32 + 0.5) / n as f32, i.reverse_bits() as f32 * (1.0 / 4_294_967_296.0))
}

/// A GGX half vector (tangent frame, z = normal) for the sample `xi`.
#[inline]
pub fn ggx_half(xi: Vec2, a: f32) -> Vec3 {
    let phi = 2.0 * PI * xi.y;
    let cos_t = ((1.0 - xi.x) / (1.0 + (a * a - 1.0) * xi.x)).max(0.0).sqrt();
    let sin_t = (1.0 - cos_t * cos_t).max(0.0).sqrt();
    Vec3::new(sin_t * phi.cos(), sin_t * phi.sin(), cos_t)
}

/// Two unit vectors completing `n` to an orthonormal basis (Duff et al.'s branchless construction).
#[inline]
pub fn basis(n: Vec3) -> (Vec3, Vec3) {
    let s = if n.z >= 0.0 { 1.0 } else { -1.0 };
    let a = -1.0 / (s + n.z);
    let b = n.x * n.y * a;
    (Vec3::new(1.0 + s * n.x * n.x * a, s * b, -s * n.x), Vec3::new(b, s + n.y * n.y * a, -n.y))
}

/// Side of the split-sum table.
const DFG_SIDE: usize = 32;

/// The split-sum's second factor: ∫ specular BRDF · n·l = F0·A + B, tabulated over (n·v, roughness) with a fixed
/// sample set (so it is the same on every run).
static DFG: LazyLock<Vec<Vec2>> = LazyLock::new(|| {
    const N: u32 = 256;
    let mut t = Vec::with_capacity(DFG_SIDE * DFG_SIDE);
    for j in 0..DFG_SIDE {
        let rough = (j as f32 / (DFG_SIDE - 1) as f32).max(MIN_ROUGHNESS);
        let a = rough * rough;
        for i in 0..DFG_SIDE {
            let nv = ((i as f32 + 0.5) / DFG_SIDE as f32).max(1e-3);
            let v = Vec3::new((1.0 - nv * nv).sqrt(), 0.0, nv);
            let mut ab = Vec2::ZERO;
            for k in 0..N {
                let h = ggx_half(hammersley(k, N), a);
                let l = 2.0 * v.dot(h) * h - v;
                let (nl, nh, vh) = (l.z, h.z, v.dot(h).max(0.0));
                if nl > 0.0 {
                    // Sampling by D·(n·h) / (4 v·h): weight = V·4·(v·h)·(n·l) / (n·h).
                    let g = smith_v(nl, nv, a) * 4.0 * vh * nl / nh.max(1e-6);
                    let fc = (1.0 - vh).powi(5);
                    ab += Vec2::new((1.0 - fc) * g, fc * g);
                }
            }
            // A + B is the lobe's directional albedo, at most 1; the estimate overshoots by up to 1 % at grazing
            // angles, which would add energy: clamp.
            let ab = ab / N as f32;
            t.push(if ab.x + ab.y > 1.0 { ab / (ab.x + ab.y) } else { ab });
        }
    }
    t
});

/// (A, B) of the split sum at `nv`, `roughness`: the environment's specular is prefiltered · (F0·A + B).
#[inline]
pub fn dfg(nv: f32, roughness: f32) -> Vec2 {
    let x = (nv.clamp(0.0, 1.0) * DFG_SIDE as f32 - 0.5).clamp(0.0, (DFG_SIDE - 1) as f32);
    let y = (roughness.clamp(0.0, 1.0) * (DFG_SIDE - 1) as f32).clamp(0.0, (DFG_SIDE - 1) as f32);
    let (x0, y0) = (x as usize, y as usize);
    let (x1, y1) = ((x0 + 1).min(DFG_SIDE - 1), (y0 + 1).min(DFG_SIDE - 1));
    let (tx, ty) = (x - x0 as f32, y - y0 as f32);
    let at = |x: usize, y: usize| DFG[y * DFG_SIDE + x];
    at(x0, y0).lerp(at(x1, y0), tx).lerp(at(x0, y1).lerp(at(x1, y1), tx), ty)
}

impl Surface {
    /// How much of the Fresnel-weighted specular layer is present: all of it for metals, `specular` for
    /// dielectrics (0 makes a Lambertian surface).
    #[inline]
    pub fn specular_weight(&self) -> f32 {
        self.specular + (1.0 - self.specular) * self.metallic
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_white_rough_metal_keeps_its_energy_and_a_dielectric_gains_little() {
        // Single scattering loses what bounces between microfacets: a white metal of roughness 1 reflects well
        // under all of a uniform environment; with the light that bounces back it reflects all of it.
        let metal = Surface { base: Vec3::ONE, metallic: 1.0, roughness: 1.0, specular: 0.5, f0: DIELECTRIC };
        let plastic = Surface { base: Vec3::ONE, metallic: 0.0, roughness: 1.0, specular: 1.0, f0: DIELECTRIC };
        for nv in [0.1, 0.5, 1.0] {
            let ab = dfg(nv, 1.0);
            assert!(ab.x + ab.y < 0.9, "{nv}: single scattering keeps {}", ab.x + ab.y);
            assert!((metal.specular_albedo(nv) - Vec3::ONE).abs().max_element() < 1e-3, "{nv}");
            let single = plastic.f0() * ab.x + Vec3::splat(ab.y);
            let gain = plastic.specular_albedo(nv).x / single.x;
            assert!(gain > 1.0 && gain < 1.1, "{nv}: {gain}");
        }
        // A mirror loses nothing to begin with.
        let mirror = Surface { roughness: 0.0, ..metal };
        assert!((mirror.specular_albedo(1.0).x - 1.0).abs() < 0.02);
    }

    fn dirs() -> Vec<Vec3> {
        (0..40)
            .map(|i| {
                let z = 0.05 + 0.9 * ((i * 7 % 40) as f32 / 40.0);
                let phi = i as f32 * 2.399_963;
                let r = (1.0 - z * z).sqrt();
                Vec3::new(r * phi.cos(), r * phi.sin(), z)
            })
            .collect()
    }

    #[test]
    fn the_brdf_is_reciprocal() {
        let n = Vec3::Z;
        for s in [
            Surface { base: Vec3::new(0.8, 0.5, 0.2), metallic: 0.0, roughness: 0.4, specular: 1.0, f0: DIELECTRIC },
            Surface { base: Vec3::new(0.9, 0.7, 0.3), metallic: 1.0, roughness: 0.2, specular: 1.0, f0: DIELECTRIC },
            Surface { base: Vec3::ONE, metallic: 0.3, roughness: 0.9, specular: 1.0, f0: DIELECTRIC },
        ] {
            for v in dirs() {
                for l in dirs().iter().rev().take(10) {
                    // f(v, l) = f(l, v): compare the BRDF (eval / n·l) both ways.
                    let a = s.eval(n, v, *l) / n.dot(*l);
                    let b = s.eval(n, *l, v) / n.dot(v);
                    assert!((a - b).abs().max_element() <= 1e-4 * a.max_element().max(1.0), "{a} {b}");
                }
            }
        }
    }

    #[test]
    fn a_surface_reflects_no_more_than_it_receives() {
        // Directional albedo ∫ f·n·l dω ≤ 1 for the whitest surfaces, by a dense quadrature over the hemisphere.
        let n = Vec3::Z;
        for s in [
            Surface { base: Vec3::ONE, metallic: 0.0, roughness: 0.5, specular: 1.0, f0: DIELECTRIC },
            Surface { base: Vec3::ONE, metallic: 1.0, roughness: 0.3, specular: 1.0, f0: DIELECTRIC },
            Surface { base: Vec3::ONE, metallic: 0.0, roughness: 1.0, specular: 0.0, f0: DIELECTRIC },
        ] {
            for v in [Vec3::Z, Vec3::new(0.6, 0.0, 0.8)] {
                let (nt, np) = (256, 512);
                let mut sum = 0.0;
                for i in 0..nt {
                    let t0 = (i as f32 / nt as f32) * PI / 2.0;
                    let t1 = ((i + 1) as f32 / nt as f32) * PI / 2.0;
                    let dw = (t0.cos() - t1.cos()) * 2.0 * PI / np as f32;
                    let t = 0.5 * (t0 + t1);
                    for j in 0..np {
                        let p = (j as f32 + 0.5) / np as f32 * 2.0 * PI;
                        let l = Vec3::new(t.sin() * p.cos(), t.sin() * p.sin(), t.cos());
                        sum += s.eval(n, v, l).x * dw;
                    }
                }
                assert!(sum <= 1.005, "{s:?} {v}: {sum}");
            }
        }
        // A Lambertian white surface reflects everything.
        let lambert = Surface { base: Vec3::ONE, metallic: 0.0, roughness: 1.0, specular: 0.0, f0: DIELECTRIC };
        assert!((lambert.eval(n, Vec3::Z, Vec3::Z).x - 1.0 / PI).abs() < 1e-6);
    }

    #[test]
    fn the_split_sum_table_is_bounded_and_near_one_for_a_white_mirror() {
        for i in 0..=10 {
            for j in 0..=10 {
                let ab = dfg(i as f32 / 10.0, j as f32 / 10.0);
                assert!(ab.x >= 0.0 && ab.y >= 0.0 && ab.x + ab.y <= 1.0 + 1e-6, "{ab}");
            }
        }
        let ab = dfg(1.0, 0.0);
        assert!(ab.x + ab.y > 0.95, "{ab}");
    }
}
