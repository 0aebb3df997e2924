//! Rotations blended across animation layers "by layer" (FBX `RotationAccumulationMode` 0, quaternions), as Maya
//! blends them: Maya converts each layer's Euler angles to quaternions, and the blend back to Euler angles, in XYZ
//! order whatever the node's own rotation order (its blend nodes' rotate order is not the node's), then applies
//! the resulting angles in the node's order. ufbx converts in the node's order, which agrees with Maya for XYZ
//! nodes only.
//!
//! The reference is Maya's own: ufbx keeps `maya_anim_layers_over_acc_orders_18.obj`, Maya's export of six cubes
//! with one layered animation and the six rotation orders, and every cube in it is posed by the same XYZ-blended
//! angles applied in its own order (the FBX's static `Lcl Rotation`, written by Maya at that frame, is that same
//! triple on every node). The blend here mirrors ufbx's `ufbxi_evaluate_props` (start from the property's value;
//! the first layer replaces it; later layers add, or blend by their weight, or replace) for `Lcl Rotation` alone,
//! and the result reaches ufbx's evaluation as a property override, so pivots, pre/post rotations and everything
//! else stay ufbx's.

/// A node whose rotation some layer after the first blends by layer, and whose rotation order is not XYZ: the
/// nodes ufbx poses differently from Maya.
#[derive(Debug, Clone, Copy)]
pub(super) struct Layered {
    /// The node (index into the scene's nodes).
    node: usize,
    /// The take (animation stack).
    take: usize,
}

/// The nodes of `scene` whose layered rotation needs Maya's blend, per take.
pub(super) fn find(scene: &ufbx::Scene) -> Vec<Layered> {
    let mut found = Vec::new();
    for (take, stack) in scene.anim_stacks.iter().enumerate() {
        for (index, node) in scene.nodes.iter().enumerate() {
            if node.rotation_order == ufbx::RotationOrder::Xyz {
                continue;
            }
            // ufbx (and Maya) start from the property's value; the stack's first layer replaces it, and every
            // later one combines with what is below.
            let by_layer = stack.layers.iter().skip(1).any(|l| {
                l.compose_rotation && l.blended && ufbx::find_anim_prop(l, &node.element, "Lcl Rotation").is_some()
            });
            if by_layer {
                found.push(Layered { node: index, take });
            }
        }
    }
    found
}

/// The `Lcl Rotation` overrides that make ufbx pose the `layered` nodes of take `take` at `time` (the stack's
/// time, seconds) as Maya does.
pub(super) fn overrides(scene: &ufbx::Scene, layered: &[Layered], take: usize, time: f64) -> Vec<(u32, ufbx::Vec3)> {
    let stack = &scene.anim_stacks[take];
    layered
        .iter()
        .filter(|l| l.take == take)
        .map(|l| {
            let node = &scene.nodes[l.node];
            let rest = ufbx::find_prop(&node.element.props, "Lcl Rotation").map_or(
                ufbx::Vec3 { x: 0.0, y: 0.0, z: 0.0 },
                |p| ufbx::Vec3 { x: p.value_vec4.x, y: p.value_vec4.y, z: p.value_vec4.z },
            );
            (node.element.element_id, blend(stack, &node.element, rest, time))
        })
        .collect()
}

/// Maya's by-layer blend of `element`'s `Lcl Rotation` over `stack`'s layers at `time`, from `value` (the
/// property's own value).
fn blend(stack: &ufbx::AnimStack, element: &ufbx::Element, mut value: ufbx::Vec3, time: f64) -> ufbx::Vec3 {
    const XYZ: ufbx::RotationOrder = ufbx::RotationOrder::Xyz;
    for (i, layer) in stack.layers.iter().enumerate() {
        let Some(prop) = ufbx::find_anim_prop(layer, element, "Lcl Rotation") else { continue };
        let v = ufbx::evaluate_anim_value_vec3(&prop.anim_value, time);
        if i == 0 {
            value = v;
            continue;
        }
        let mut weight = layer.weight;
        if layer.weight_is_animated && layer.blended {
            if let Some(w) = ufbx::find_anim_prop(layer, &layer.element, "Weight") {
                weight = (ufbx::evaluate_anim_value_real(&w.anim_value, time) / 100.0).clamp(0.0, 1.0);
                if weight > 0.99999 {
                    weight = 1.0;
                }
            }
        }
        value = match (layer.additive, layer.blended, layer.compose_rotation) {
            (true, _, true) => {
                let below = ufbx::euler_to_quat(value, XYZ);
                let add = ufbx::quat_slerp(IDENTITY, ufbx::euler_to_quat(v, XYZ), weight);
                ufbx::quat_to_euler(ufbx::quat_mul(below, add), XYZ)
            }
            (true, _, false) => add(value, v, weight),
            (false, true, true) => {
                let q = ufbx::quat_slerp(ufbx::euler_to_quat(value, XYZ), ufbx::euler_to_quat(v, XYZ), weight);
                ufbx::quat_to_euler(q, XYZ)
            }
            (false, true, false) => add(scale(value, 1.0 - weight), v, weight),
            (false, false, _) => v,
        };
    }
    value
}

const IDENTITY: ufbx::Quat = ufbx::Quat { x: 0.0, y: 0.0, z: 0.0, w: 1.0 };

/// `a + b·w`, per channel.
fn add(a: ufbx::Vec3, b: ufbx::Vec3, w: f64) -> ufbx::Vec3 {
    ufbx::Vec3 { x: a.x + b.x * w, y: a.y + b.y * w, z: a.z + b.z * w }
}

/// `a·s`, per channel.
fn scale(a: ufbx::Vec3, s: f64) -> ufbx::Vec3 {
    ufbx::Vec3 { x: a.x * s, y: a.y * s, z: a.z * s }
}
