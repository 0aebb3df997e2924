//! 3D Gaussians stored in glTF (`KHR_gaussian_splatting`, as splat-transform, Cesium, Babylon and PlayCanvas
//! write them): a `POINTS` primitive whose attributes `KHR_gaussian_splatting:ROTATION` (a unit quaternion,
//! xyzw), `:SCALE` (linear standard deviations), `:OPACITY` (the activated opacity) and `:SH_DEGREE_ℓ_COEF_n`
//! (RGB, m from −ℓ up) describe one Gaussian per point, drawn as a 3D Gaussian splatting PLY's are
//! ([`crate::scene::gaussians`]). The node's transform places them (covariance M·Σ·Mᵀ, the colours read in the
//! primitive's own axes), as the extension specifies.
//!
//! gltf 1.4 refuses the attributes' names ("invalid semantic name"), so [`rename`] moves them to application
//! names (`_KHR_GS_…`) before its validation, and [`read`] reads them back from there.

use std::sync::Arc;

use glam::{Mat3, Quat, Vec3, Vec4};

use super::accessor::read_f32;
use super::load::Primitive;
use crate::scene::gaussians::GaussianData;
use crate::scene::material::srgb_to_linear;

/// The extension's attribute prefix, and what [`rename`] turns it into.
const PREFIX: &str = "KHR_gaussian_splatting:";
const RENAMED: &str = "KHR_GS_";

/// Renames the extension's attributes of every primitive to application names gltf 1.4 accepts, and refuses
/// what vvgen cannot draw as the file means it (another kernel or colour space). Returns whether anything was
/// renamed.
pub(super) fn rename(doc: &mut serde_json::Value) -> Result<bool, String> {
    let mut changed = false;
    let Some(meshes) = doc.get_mut("meshes").and_then(|m| m.as_array_mut()) else { return Ok(false) };
    for (mi, mesh) in meshes.iter_mut().enumerate() {
        let Some(prims) = mesh.get_mut("primitives").and_then(|p| p.as_array_mut()) else { continue };
        for (pi, prim) in prims.iter_mut().enumerate() {
            if let Some(ext) = prim.pointer("/extensions/KHR_gaussian_splatting") {
                let field = |k: &str| ext.get(k).and_then(|v| v.as_str()).map(str::to_string);
                let at = format!("meshes[{mi}].primitives[{pi}]");
                if let Some(kernel) = field("kernel").filter(|k| k != "ellipse") {
                    return Err(format!(
                        "{at} holds 3D Gaussians of kernel `{kernel}`, which vvgen does not draw (it draws `ellipse`, \
                         3D Gaussian splatting's)"
                    ));
                }
                if let Some(space) = field("colorSpace").filter(|c| c != "srgb_rec709_display") {
                    return Err(format!(
                        "{at} holds 3D Gaussians in colour space `{space}`, which vvgen does not draw (it draws \
                         `srgb_rec709_display`, 3D Gaussian splatting's)"
                    ));
                }
            }
            let Some(attrs) = prim.get_mut("attributes").and_then(|a| a.as_object_mut()) else { continue };
            let names: Vec<String> = attrs.keys().filter(|k| k.starts_with(PREFIX)).cloned().collect();
            for name in names {
                let value = attrs.remove(&name).expect("BUG: a key just listed");
                attrs.insert(format!("_{RENAMED}{}", &name[PREFIX.len()..]), value);
                changed = true;
            }
        }
    }
    Ok(changed)
}

/// A primitive's Gaussians, read from the attributes [`rename`] renamed (`n` points), or `None` when it has
/// none. The spherical harmonics go to the highest degree whose coefficients and all lower ones are there; a
/// Gaussian that never reaches alpha 1/255 is marked to be left out, as a PLY's are (3DGS's rasterizer never
/// blends it), in the returned mask.
pub(super) fn read(
    p: &gltf::Primitive<'_>,
    buffers: &[Vec<u8>],
    n: usize,
) -> Result<Option<(GaussianData, Vec<bool>)>, String> {
    let get = |name: &str| -> Result<Option<Vec<f32>>, String> {
        let sem = gltf::Semantic::Extras(format!("{RENAMED}{name}"));
        match p.get(&sem) {
            Some(acc) if acc.count() != n => {
                Err(format!("{PREFIX}{name} has {} elements, POSITION has {n}", acc.count()))
            }
            Some(acc) => read_f32(&acc, buffers).map(Some),
            None => Ok(None),
        }
    };
    let (Some(rot), Some(scale), Some(opacity)) = (get("ROTATION")?, get("SCALE")?, get("OPACITY")?) else {
        return Ok(None);
    };
    if rot.len() != 4 * n || scale.len() != 3 * n || opacity.len() != n {
        return Err(format!("{PREFIX}ROTATION, SCALE and OPACITY must be VEC4, VEC3 and SCALAR"));
    }
    // Band by band, as long as every coefficient of the band is there.
    let mut bands: Vec<Vec<f32>> = Vec::new();
    'degrees: for degree in 0..=3usize {
        let mut band = Vec::new();
        for coef in 0..2 * degree + 1 {
            match get(&format!("SH_DEGREE_{degree}_COEF_{coef}"))? {
                Some(v) if v.len() == 3 * n => band.push(v),
                Some(_) => return Err(format!("{PREFIX}SH_DEGREE_{degree}_COEF_{coef} must be VEC3")),
                None => break 'degrees,
            }
        }
        bands.extend(band);
    }
    if bands.is_empty() {
        return Err(format!("3D Gaussians without {PREFIX}SH_DEGREE_0_COEF_0, their colour"));
    }
    let degree = [1, 4, 9, 16].iter().rposition(|&k| k <= bands.len()).expect("BUG: band 0 is there");
    let per = (degree + 1) * (degree + 1);
    let mut sh = Vec::with_capacity(n * per);
    for i in 0..n {
        sh.extend(bands[..per].iter().map(|b| Vec3::from_slice(&b[3 * i..3 * i + 3])));
    }
    if let Some(i) = (0..n).find(|&i| {
        !(rot[4 * i..4 * i + 4].iter().chain(&scale[3 * i..3 * i + 3]).all(|v| v.is_finite()) && opacity[i].is_finite())
    }) {
        return Err(format!("Gaussian {i}'s rotation, scale or opacity is not finite"));
    }
    if let Some(i) = (0..n * per).find(|&i| !sh[i].is_finite()) {
        return Err(format!("Gaussian {}'s spherical harmonics are not finite", i / per));
    }
    let factors = (0..n)
        .map(|i| {
            let q = Quat::from_slice(&rot[4 * i..4 * i + 4]);
            // Unit quaternions by the extension; a zero one (no rotation can be read from it) is the identity.
            let q = if q.length_squared() > 0.0 { q.normalize() } else { Quat::IDENTITY };
            Mat3::from_quat(q) * Mat3::from_diagonal(Vec3::from_slice(&scale[3 * i..3 * i + 3]).abs())
        })
        .collect();
    let opacities: Vec<f32> = opacity.iter().map(|o| o.clamp(0.0, 1.0)).collect();
    let shows = opacities.iter().map(|&o| o >= 1.0 / 255.0).collect();
    Ok(Some((GaussianData { factors, opacities, degree, sh }, shows)))
}

/// Makes `prim` (a point primitive) the Gaussians `data` that `shows` keeps: its points their centres, coloured
/// by their band-0 colour, neither skinned nor morphed (the extension defines neither).
pub(super) fn keep(prim: &mut Primitive, mut data: GaussianData, shows: &[bool]) {
    let per = data.per_gaussian();
    let keep = |i: &usize| shows[*i];
    let kept: Vec<usize> = (0..shows.len()).filter(keep).collect();
    prim.positions = kept.iter().map(|&i| prim.positions[i]).collect();
    prim.normals = vec![Vec3::ZERO; kept.len()];
    prim.colors = kept.iter().map(|&i| point_colour(data.sh[i * per])).collect();
    prim.uvs.clear();
    (prim.influences, prim.joints, prim.weights) = (0, Vec::new(), Vec::new());
    (prim.morph_positions, prim.morph_normals) = (Vec::new(), Vec::new());
    data.factors = kept.iter().map(|&i| data.factors[i]).collect();
    data.opacities = kept.iter().map(|&i| data.opacities[i]).collect();
    data.sh = kept.iter().flat_map(|&i| data.sh[i * per..(i + 1) * per].iter().copied()).collect();
    prim.gaussians = Some(Arc::new(data));
}

/// The colour of a point that stands for a Gaussian of band-0 coefficients `dc`: 3DGS's `SH2RGB`, clamped and
/// quantized as a PLY's Gaussians are read, then linear, as vertex colours are.
pub(super) fn point_colour(dc: Vec3) -> Vec4 {
    const SH_C0: f64 = 0.28209479177387814;
    let q = |c: f32| ((0.5 + SH_C0 * f64::from(c)).clamp(0.0, 1.0) * 255.0).floor() as f32 / 255.0;
    Vec4::new(srgb_to_linear(q(dc.x)), srgb_to_linear(q(dc.y)), srgb_to_linear(q(dc.z)), 1.0)
}
