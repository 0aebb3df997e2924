//! Content keys: blake3 over a canonical, versioned encoding of exactly what determines a task's bytes. A
//! frame's key covers its posed geometry (evaluated animation, so an edit that moves frames 30–59 changes only
//! their keys), materials and textures, or the bytes of its PLY file; an image pass's key adds the camera and
//! the render settings. Output paths, split and output names, table order, comments and thread counts never
//! enter a key.

use crate::cache::{key, Digest, StatCache};
use crate::manifest::render::{Pass, Render};
use crate::plan::Image;
use crate::scene::{Poser, Scene, SourceData};

/// Version of the renderer's output: bump when a change moves rendered bytes.
pub const RENDER_SALT: &[u8] = b"render 6";
/// Version of the point sampler's output.
pub const SAMPLE_SALT: &[u8] = b"sample 2";

/// The key of every scene frame.
pub fn frame_keys(scene: &Scene, stat: &StatCache) -> Result<Vec<Digest>, String> {
    let mut per_source: Vec<Vec<Digest>> = Vec::new();
    let mut poser = Poser::default();
    for (i, src) in scene.sources.iter().enumerate() {
        let world = scene.world_from_source(i).to_cols_array();
        let world: &[u8] = bytemuck::cast_slice(&world);
        let keys = match &src.data {
            SourceData::Sequence(files) => files
                .iter()
                .map(|f| {
                    let d = stat.digest(&f.path).map_err(|e| format!("{}: {e}", f.path.display()))?;
                    Ok(key("frame ply", &[world, &d.0]))
                })
                .collect::<Result<Vec<_>, String>>()?,
            SourceData::Gltf { .. } | SourceData::Static(_) => {
                let n = src.frame_count();
                let mut keys = Vec::with_capacity(n);
                let mut materials = None;
                for f in 0..n {
                    let posed = scene.pose_source(i, f, &mut poser)?;
                    let m = *materials.get_or_insert_with(|| posed.material_digest());
                    keys.push(key("frame posed", &[posed.geometry_digest().as_bytes(), m.as_bytes()]));
                }
                keys
            }
        };
        per_source.push(keys);
    }
    Ok((0..scene.frames)
        .map(|f| {
            // Shorter sources hold their last frame, as when posing.
            let parts: Vec<&[u8]> = per_source.iter().map(|k| &k[f.min(k.len() - 1)].0[..]).collect();
            key("frame", &parts)
        })
        .collect())
}

/// The settings that shape rendered bytes, canonically encoded (every pass shares them).
pub fn render_settings(r: &Render, voxel: Option<f32>) -> Vec<u8> {
    let s = crate::render::RenderSettings::from_manifest(r, voxel);
    format!(
        "{:?}|{:?}|{:?}|{:?}|{:?}|{:?}|{:?}|{:?}|{:?}",
        s.samples, s.shading, s.lights, s.ambient, s.background, s.depth, s.splat, r.png_compression, r.normal.space
    )
    .into_bytes()
}

/// What a pass writes, as it enters the pass's key: the pass, and `+exr` when its float file is asked for (so
/// asking for EXR re-renders only that pass).
pub fn pass_tag(r: &Render, pass: Pass) -> String {
    let exr = match pass {
        Pass::Depth => r.depth.exr,
        Pass::Normal => r.normal.exr,
        Pass::Rgba | Pass::Mask => false,
    };
    format!("{pass:?}{}", if exr { "+exr" } else { "" })
}

/// The key of one pass of one image; `tag` is [`pass_tag`].
pub fn pass_key(frame: &Digest, image: &Image, settings: &[u8], tag: &str) -> Digest {
    let c = &image.camera;
    let mut cam = Vec::with_capacity(8 * 22);
    for v in [c.width as f64, c.height as f64, c.fx, c.fy, c.cx, c.cy, c.near, c.far] {
        cam.extend_from_slice(&v.to_le_bytes());
    }
    for v in c.c2w.to_cols_array() {
        cam.extend_from_slice(&v.to_le_bytes());
    }
    key("render", &[RENDER_SALT, tag.as_bytes(), &frame.0, &cam, settings])
}
