//! `EXT_mesh_gpu_instancing`: a node that draws its mesh many times, each copy placed by a row of its
//! `TRANSLATION`, `ROTATION` and `SCALE` accessors (scale, then rotation, then translation, relative to the node).
//! Written by gltfpack (`-mi`), glTF-Transform's `instance`, Blender's exporter ("GPU Instances") and web scene
//! tools for forests, crowds and repeated parts; a reader that ignores it draws one copy at the node. vvgen poses
//! every copy as its own primitives (the renderer draws posed triangles, not instances), so the copies' vertices
//! count against a bound: a file cannot make vvgen pose billions of them.

use glam::{Mat4, Quat, Vec3};

use super::accessor::read_f32;

/// The most vertices a file's instanced nodes may pose in all (every copy of every primitive: 33 M, a forest of
/// ten thousand 3 000-vertex trees; about 1.5 GB posed), and the most copies: past either the file is refused,
/// not allocated for (a few bytes of JSON can ask for millions of copies of accessors without data).
pub(super) const MAX_INSTANCED_VERTICES: u64 = 1 << 25;
pub(super) const MAX_INSTANCES: u64 = 1 << 20;

/// The transforms (relative to the node) of `node`'s instances, empty when it has none; `vertices` is its mesh's
/// vertex count, `so_far` the file's instances and instanced vertices counted so far (raised by this node's). An
/// error names the accessor or the count that is wrong.
pub(super) fn instances(
    node: &gltf::Node<'_>,
    doc: &gltf::Document,
    buffers: &[Vec<u8>],
    vertices: u64,
    so_far: &mut (u64, u64),
) -> Result<Vec<Mat4>, String> {
    let Some(ext) = node.extensions().and_then(|e| e.get("EXT_mesh_gpu_instancing")) else { return Ok(Vec::new()) };
    let attributes = ext.get("attributes").and_then(|a| a.as_object());
    let accessor = |name: &str, width: usize| -> Result<Option<gltf::Accessor<'_>>, String> {
        let Some(index) = attributes.and_then(|a| a.get(name)) else { return Ok(None) };
        let acc = index
            .as_u64()
            .and_then(|i| doc.accessors().nth(i as usize))
            .ok_or_else(|| format!("EXT_mesh_gpu_instancing's {name} names no accessor ({index})"))?;
        if acc.dimensions().multiplicity() != width {
            return Err(format!("EXT_mesh_gpu_instancing's {name} (accessor {}) is not a VEC{width}", acc.index()));
        }
        Ok(Some(acc))
    };
    let (t, r, s) = (accessor("TRANSLATION", 3)?, accessor("ROTATION", 4)?, accessor("SCALE", 3)?);
    let counts: Vec<usize> = [&t, &r, &s].into_iter().flatten().map(|a| a.count()).collect();
    let Some(&n) = counts.first() else {
        return Err("EXT_mesh_gpu_instancing has none of TRANSLATION, ROTATION and SCALE".into());
    };
    if counts.iter().any(|&c| c != n) {
        return Err(format!("EXT_mesh_gpu_instancing's attributes count different instances ({counts:?})"));
    }
    // Counted before anything is read: an accessor without data reads as zeros and can be millions long.
    so_far.0 = so_far.0.saturating_add(n as u64);
    so_far.1 = so_far.1.saturating_add((n as u64).saturating_mul(vertices));
    if so_far.0 > MAX_INSTANCES || so_far.1 > MAX_INSTANCED_VERTICES {
        return Err(format!(
            "EXT_mesh_gpu_instancing draws its mesh of {vertices} vertices {n} times: with the file's other \
             instances, more than the {MAX_INSTANCES} copies or {MAX_INSTANCED_VERTICES} vertices vvgen poses (it \
             draws every copy); keep fewer instances in the tool that wrote the file"
        ));
    }
    let read = |acc: Option<gltf::Accessor<'_>>, name: &str| {
        acc.map(|a| read_f32(&a, buffers).map_err(|e| format!("EXT_mesh_gpu_instancing's {name}: {e}"))).transpose()
    };
    let (t, r, s) = (read(t, "TRANSLATION")?, read(r, "ROTATION")?, read(s, "SCALE")?);
    (0..n)
        .map(|i| {
            let translation = t.as_ref().map_or(Vec3::ZERO, |t| Vec3::from_slice(&t[3 * i..]));
            // Normalized as a node's rotation is (`load`), so that a copy placed by the extension and a node
            // placed by the same numbers pose alike.
            let rotation = r.as_ref().map_or(Quat::IDENTITY, |r| Quat::from_slice(&r[4 * i..]).normalize());
            let scale = s.as_ref().map_or(Vec3::ONE, |s| Vec3::from_slice(&s[3 * i..]));
            let m = Mat4::from_scale_rotation_translation(scale, rotation, translation);
            match m.is_finite() {
                true => Ok(m),
                false => Err(format!(
                    "EXT_mesh_gpu_instancing's instance {i} is not a transform (translation {translation}, rotation \
                     {rotation}, scale {scale}: a zero or non-finite rotation?)"
                )),
            }
        })
        .collect()
}
