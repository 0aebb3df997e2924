//! Posing a loaded glTF at a time: animate node TRS and morph weights, compute world matrices, blend morph
//! targets, skin (linear blend, normals by the cofactor of the blended matrix), and write world-space
//! primitives. Scratch buffers live in [`PoseScratch`] and the output's buffers are reused, so posing after
//! the first frame allocates nothing.

use std::sync::Arc;

use glam::{Mat3, Mat4, Quat, Vec3, Vec4};

use super::anim::Target;
use super::load::{GltfAsset, Primitive};
use crate::scene::gaussians::Gaussians;
use crate::scene::posed::{PosedPrimitive, PosedScene};

/// Reusable per-pose state.
#[derive(Debug, Default, Clone)]
pub struct PoseScratch {
    trs: Vec<(Vec3, Quat, Vec3)>,
    weights: Vec<Vec<f32>>,
    world: Vec<Mat4>,
    joints: Vec<Mat4>,
    value: Vec<f32>,
}

/// Cofactor matrix of the upper 3×3: transforms normals like the inverse-transpose, up to a positive scale
/// for proper transforms (and works for singular ones).
#[inline]
pub fn normal_matrix(m: &Mat4) -> Mat3 {
    let (c0, c1, c2) = (m.x_axis.truncate(), m.y_axis.truncate(), m.z_axis.truncate());
    let cof = Mat3::from_cols(c1.cross(c2), c2.cross(c0), c0.cross(c1));
    // A mirroring matrix has a negative determinant; keep normals on the same side of the surface.
    if c0.dot(c1.cross(c2)) < 0.0 {
        -cof
    } else {
        cof
    }
}

/// Tangent `t` (xyz, handedness w) moved by `m`: along the surface like a position difference, its handedness
/// flipped by a mirroring `m` (so that w·(n × t) stays the bitangent `m` carries).
#[inline]
pub fn tangent(m: &Mat4, t: Vec4) -> Vec4 {
    let (c0, c1, c2) = (m.x_axis.truncate(), m.y_axis.truncate(), m.z_axis.truncate());
    let w = if c0.dot(c1.cross(c2)) < 0.0 { -t.w } else { t.w };
    m.transform_vector3(t.truncate()).normalize_or_zero().extend(w)
}

impl GltfAsset {
    /// What the selected scene holds: whether it has something to draw or light (a node with a mesh of
    /// triangles or points, or a light; an animation-only export, a skeleton and its clips, has neither) and, for
    /// the error when it does not, what it has instead.
    pub fn holds(&self) -> crate::scene::source::Holds {
        let drawn = |m: usize| self.meshes.get(m).is_some_and(|ps| ps.iter().any(|p| !p.positions.is_empty()));
        crate::scene::source::Holds {
            draws: self.order.iter().any(|&(n, _)| {
                let node = &self.nodes[n];
                node.mesh.is_some_and(drawn) || node.light.is_some()
            }),
            nodes: self.nodes.len(),
            meshes: self.order.iter().any(|&(n, _)| self.nodes[n].mesh.is_some()),
            clips: self.animations.len(),
            clip: "animation",
            // An animation-only glTF keeps no skin (it has no mesh to bind): a hierarchy of nodes is taken for one.
            skeleton: self.nodes.len() > 1 || self.nodes.iter().any(|n| n.skin.is_some()),
            curves: 0,
        }
    }

    /// Nodes reachable from the roots, parents before children, each with its parent.
    pub fn traversal(&self) -> Vec<(usize, Option<usize>)> {
        let mut out = Vec::new();
        let mut seen = vec![false; self.nodes.len()];
        let mut stack: Vec<(usize, Option<usize>)> = self.roots.iter().rev().map(|&r| (r, None)).collect();
        while let Some((n, parent)) = stack.pop() {
            if n >= self.nodes.len() || seen[n] {
                continue; // cycles and duplicates are ignored (gltf validation rejects most)
            }
            seen[n] = true;
            out.push((n, parent));
            for &c in self.nodes[n].children.iter().rev() {
                stack.push((c, Some(n)));
            }
        }
        out
    }

    /// Poses clips `clips` at time `t` (seconds), applies `post` (source → world) and writes into `out`,
    /// whose primitives are reused when it was posed from this asset before.
    pub fn pose(&self, clips: &[usize], t: f32, post: Mat4, scratch: &mut PoseScratch, out: &mut PosedScene) {
        let s = scratch;
        s.trs.clear();
        s.trs.extend(self.nodes.iter().map(|n| (n.translation, n.rotation, n.scale)));
        s.weights.resize(self.nodes.len(), Vec::new());
        for (w, n) in s.weights.iter_mut().zip(&self.nodes) {
            w.clear();
            w.extend_from_slice(&n.weights);
        }
        for &c in clips {
            for ch in &self.animations[c].channels {
                let width = match ch.target {
                    Target::Rotation => 4,
                    Target::Weights => s.weights[ch.node].len().max(1),
                    _ => 3,
                };
                s.value.resize(width, 0.0);
                ch.sampler.sample(t, &mut s.value);
                let v = &s.value;
                let trs = &mut s.trs[ch.node];
                match ch.target {
                    Target::Translation => trs.0 = Vec3::from_slice(v),
                    Target::Rotation => trs.1 = Quat::from_slice(v).normalize(),
                    Target::Scale => trs.2 = Vec3::from_slice(v),
                    Target::Weights => {
                        let w = &mut s.weights[ch.node];
                        let k = w.len().min(v.len());
                        w[..k].copy_from_slice(&v[..k]);
                    }
                }
            }
        }
        s.world.resize(self.nodes.len(), Mat4::IDENTITY);
        for &(n, parent) in &self.order {
            let node = &self.nodes[n];
            let local = node.matrix.unwrap_or_else(|| {
                let (t, r, sc) = s.trs[n];
                Mat4::from_scale_rotation_translation(sc, r, t)
            });
            s.world[n] = match parent {
                Some(p) => s.world[p] * local,
                None => local,
            };
        }
        out.lights.clear();
        for &(n, _) in &self.order {
            if let Some(light) = self.nodes[n].light.and_then(|l| self.lights.get(l)) {
                out.lights.push(light.place(post * s.world[n]));
            }
        }
        let mut slot = 0;
        for (object, &(n, _)) in self.order.iter().enumerate() {
            let node = &self.nodes[n];
            let Some(mesh) = node.mesh else { continue };
            let skin = node.skin.map(|si| &self.skins[si]);
            if let Some(skin) = skin {
                s.joints.clear();
                s.joints.extend(skin.joints.iter().zip(&skin.inverse_bind).map(|(&j, ibm)| post * s.world[j] * *ibm));
            }
            // One copy at the node, or one per `EXT_mesh_gpu_instancing` instance.
            for copy in 0..node.instances.len().max(1) {
                let model = match node.instances.get(copy) {
                    Some(inst) => post * s.world[n] * *inst,
                    None => post * s.world[n],
                };
                let joints = skin.map(|_| &s.joints[..]);
                for prim in &self.meshes[mesh] {
                    if slot == out.primitives.len() {
                        out.primitives.push(PosedPrimitive {
                            kind: prim.kind,
                            positions: Vec::with_capacity(prim.positions.len()),
                            normals: Vec::with_capacity(prim.positions.len()),
                            tangents: Vec::with_capacity(prim.tangents.len()),
                            uvs: Arc::new(prim.uvs.clone()),
                            colors: Arc::new(prim.colors.clone()),
                            indices: Arc::new(prim.indices.clone()),
                            material: prim.material,
                            object: object as u32,
                            gaussians: None,
                        });
                    }
                    pose_primitive(prim, &s.weights[n], joints, &model, &mut out.primitives[slot]);
                    // Gaussians are placed by their node's transform (the extension defines no skinning).
                    out.primitives[slot].gaussians = prim
                        .gaussians
                        .as_ref()
                        .map(|data| Gaussians { data: Arc::clone(data), to_world: glam::Mat3::from_mat4(model) });
                    slot += 1;
                }
            }
        }
        out.primitives.truncate(slot);
    }
}

/// Writes `prim` posed into `o`: its morph targets blended by `w`, then skinned by `joints` (the skin's joint
/// matrices, when the node has a skin and the primitive influences) or placed by `model`.
fn pose_primitive(prim: &Primitive, w: &[f32], joints: Option<&[Mat4]>, model: &Mat4, o: &mut PosedPrimitive) {
    let nmat = normal_matrix(model);
    o.positions.clear();
    o.normals.clear();
    o.tangents.clear();
    let tangents = !prim.tangents.is_empty();
    let morphing = w.iter().any(|&x| x != 0.0) && !prim.morph_positions.is_empty();
    for v in 0..prim.positions.len() {
        let (mut p, mut nr) = (prim.positions[v], prim.normals[v]);
        if morphing {
            for (k, &wk) in w.iter().enumerate() {
                if wk == 0.0 {
                    continue;
                }
                if let Some(d) = prim.morph_positions.get(k).and_then(|d| d.get(v)) {
                    p += *d * wk;
                }
                if let Some(d) = prim.morph_normals.get(k).and_then(|d| d.get(v)) {
                    nr += *d * wk;
                }
            }
        }
        match (joints, prim.influences) {
            (Some(joints), k) if k > 0 => {
                let js = &prim.joints[v * k..(v + 1) * k];
                let ws = &prim.weights[v * k..(v + 1) * k];
                let mut m = Mat4::ZERO;
                for (&j, &wj) in js.iter().zip(ws) {
                    if wj != 0.0 {
                        m += joints[j as usize] * wj;
                    }
                }
                o.positions.push(m.transform_point3(p));
                o.normals.push((normal_matrix(&m) * nr).normalize_or_zero());
                if tangents {
                    o.tangents.push(tangent(&m, prim.tangents[v]));
                }
            }
            _ => {
                o.positions.push(model.transform_point3(p));
                o.normals.push((nmat * nr).normalize_or_zero());
                if tangents {
                    o.tangents.push(tangent(model, prim.tangents[v]));
                }
            }
        }
    }
}
