//! Which sides of a mesh gather light. A camera may see a double-sided surface from behind, and Cycles lights
//! what it sees there as a front (it turns a back face's normal to the eye): a scan stored inside out shows
//! nothing but back faces, and lit by what its inward normals saw, the mesh's own inside, VCG's horse rendered
//! 20 % dark. So a double-sided caster's vertices gather on both sides, but for a mesh that closes a volume its
//! fronts face out of: no camera outside it sees a back face, and the rays from its insides, which all meet the
//! mesh, cost most (CesiumMan's light took 2.6 times as long).

use std::collections::HashMap;

use super::is_caster;
use crate::scene::{PosedPrimitive, PosedScene};

/// Whether primitive `p` may gather on both sides: a caster of a double-sided material (every PLY, OBJ, STL and
/// FBX mesh's, a glTF's that asks). What keys a frame's light apart (see `plan::keys`).
pub fn two_sided(scene: &PosedScene, p: &PosedPrimitive) -> bool {
    is_caster(scene, p) && scene.materials.get(p.material as usize).is_some_and(|m| m.double_sided)
}

/// How many sides of primitive `p`'s vertices gather light: two when it is [`two_sided`] and does not close a
/// volume its fronts face out of ([`closed_outward`]), else one. A two-sided primitive's back sides follow its
/// front sides in [`super::FrameLight::vertex_visibility`] and in the gather, which read it off their lengths.
pub(super) fn sides(scene: &PosedScene, p: &PosedPrimitive) -> usize {
    if two_sided(scene, p) && !closed_outward(p) {
        2
    } else {
        1
    }
}

/// Whether `p`'s triangles close a volume (corners welded where they lie at the same point, as seams split
/// them: every edge met once each way, by two triangles turning opposite ways along it) and their fronts face
/// out of it (a positive signed volume). A closed mesh facing in (a scan inside out, or a room seen from inside)
/// is not: either side may be the one seen.
pub(super) fn closed_outward(p: &PosedPrimitive) -> bool {
    let mut weld: HashMap<[u32; 3], u32> = HashMap::with_capacity(p.positions.len());
    let ids: Vec<u32> = p
        .positions
        .iter()
        .map(|v| {
            let next = weld.len() as u32;
            *weld.entry(v.to_array().map(f32::to_bits)).or_insert(next)
        })
        .collect();
    // Directed edges as a < 2³² pairs, sorted: 8 bytes an edge (a scan's millions of them), no hashing.
    let mut edges: Vec<u64> = Vec::with_capacity(p.indices.len());
    let mut volume = 0.0f64;
    for t in p.indices.chunks_exact(3) {
        let [a, b, c] = [0, 1, 2].map(|k| ids.get(t[k] as usize).copied());
        let (Some(a), Some(b), Some(c)) = (a, b, c) else { return false };
        if a == b || b == c || a == c {
            continue;
        }
        edges.extend([(a, b), (b, c), (c, a)].map(|(x, y)| (u64::from(x) << 32) | u64::from(y)));
        let [pa, pb, pc] = [0, 1, 2].map(|k| p.positions[t[k] as usize].as_dvec3());
        volume += pa.dot(pb.cross(pc));
    }
    edges.sort_unstable();
    let once = edges.windows(2).all(|w| w[0] != w[1]);
    let reversed = |e: &u64| edges.binary_search(&(e.rotate_left(32))).is_ok();
    !edges.is_empty() && volume > 0.0 && once && edges.iter().all(reversed)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::material::Material;
    use crate::scene::PrimKind;
    use glam::Vec3;

    /// A unit cube of 24 corners (four per face, split at its edges as seams split a textured mesh), its faces
    /// turning counter-clockwise seen from outside.
    fn cube() -> PosedScene {
        let (mut positions, mut normals, mut indices) = (Vec::new(), Vec::new(), Vec::new());
        for axis in 0..3 {
            for sign in [-1.0f32, 1.0] {
                let n = Vec3::AXES[axis] * sign;
                let (u, v) = (Vec3::AXES[(axis + 1) % 3], Vec3::AXES[(axis + 2) % 3]);
                let (u, v) = if sign > 0.0 { (u, v) } else { (v, u) };
                let k = positions.len() as u32;
                for (a, b) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
                    positions.push((n + u * a + v * b) * 0.5);
                    normals.push(n);
                }
                indices.extend([k, k + 1, k + 2, k, k + 2, k + 3]);
            }
        }
        let material = Material { double_sided: true, ..Material::default() };
        PosedScene::single(PrimKind::Triangles, positions, normals, Vec::new(), indices, material)
    }

    #[test]
    fn a_mesh_closed_and_facing_out_gathers_on_its_fronts_alone() {
        let s = cube();
        assert!(closed_outward(&s.primitives[0]));
        assert_eq!(sides(&s, &s.primitives[0]), 1);
        // Inside out: both sides (seen from outside, its backs are what shows).
        let mut turned = s.clone();
        let p = &mut turned.primitives[0];
        p.indices = std::sync::Arc::new(p.indices.chunks_exact(3).flat_map(|t| [t[0], t[2], t[1]]).collect());
        assert!(!closed_outward(&turned.primitives[0]));
        assert_eq!(sides(&turned, &turned.primitives[0]), 2);
        // With a face missing (a hole to look in through): both sides.
        let mut open = s.clone();
        let p = &mut open.primitives[0];
        p.indices = std::sync::Arc::new(p.indices[6..].to_vec());
        assert_eq!(sides(&open, &open.primitives[0]), 2);
        // One-sided: its fronts alone, whatever its shape.
        let mut single = open.clone();
        single.materials = std::sync::Arc::new(vec![Material::default()]);
        assert_eq!(sides(&single, &single.primitives[0]), 1);
    }
}
