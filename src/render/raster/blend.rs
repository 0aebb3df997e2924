//! Alpha BLEND surfaces as real transparency: their fragments, kept per sample while a tile is drawn, composited
//! over the opaque result in depth order once every triangle is drawn.

use glam::{Vec3, Vec4};

use super::SampleTile;

/// A sample of a BLEND surface: where, how far, in what order it was drawn, and what it shows.
#[derive(Debug, Clone, Copy)]
pub(super) struct Fragment {
    /// Sample index in the tile.
    pub i: u32,
    /// Triangle id (scene order), for equal depths.
    pub tri: u32,
    /// View depth.
    pub z: f32,
    /// Straight linear RGB and alpha.
    pub color: Vec4,
    /// Interpolated normal, toward the eye.
    pub normal: Vec3,
    /// Object id.
    pub object: u32,
}

/// Composites the tile's BLEND fragments over what is drawn, per sample from the farthest to the nearest (equal
/// depths in scene order), each "over" the result so far, in premultiplied linear light; fragments behind the
/// opaque surface are hidden. A sample that only transparent surfaces cover takes the nearest one's depth,
/// normal and object. The sort makes the result independent of the order tiles or threads produced them.
pub(super) fn composite(t: &mut SampleTile) {
    if t.blend.is_empty() {
        return;
    }
    let mut blend = std::mem::take(&mut t.blend);
    blend.sort_by(|a, b| a.i.cmp(&b.i).then(b.z.total_cmp(&a.z)).then(a.tri.cmp(&b.tri)));
    for f in &blend {
        let i = f.i as usize;
        if f.z >= t.depth[i] && t.object[i] != 0 && t.color[i].w >= 1.0 {
            continue; // behind the opaque surface
        }
        // Nothing drawn yet: the colour buffer holds an earlier tile's value.
        let dst = if t.object[i] == 0 { Vec4::ZERO } else { t.color[i] };
        let a = f.color.w;
        let premult = f.color.truncate() * a + dst.truncate() * dst.w * (1.0 - a);
        let alpha = a + dst.w * (1.0 - a);
        t.color[i] = if alpha > 0.0 { (premult / alpha).extend(alpha) } else { Vec4::ZERO };
        if t.object[i] == 0 || f.z < t.depth[i] && t.color[i].w < 1.0 {
            t.depth[i] = f.z;
            t.normal[i] = f.normal;
            t.object[i] = f.object + 1;
        }
    }
    blend.clear();
    t.blend = blend;
}
