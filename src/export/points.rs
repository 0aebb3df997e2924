//! `ply-sequence`: one PLY per frame of surface samples from the posed scene (x y z, nx ny nz float; red green
//! blue uchar), optionally voxel-downsampled on a lattice anchored at the world origin, the same for every frame.

use super::{Export, Files};
use crate::cache::key;
use crate::manifest::output::{ColorAverage, Output, PlyFormat, Reduce};
use crate::manifest::sequence::format_frame;
use crate::plan::keys::SAMPLE_SALT;
use crate::sample::{self, voxel};
use crate::scene::material::{linear_to_srgb, srgb_to_linear};
use crate::scene::ply::{self, PlyOut};
use crate::scene::{PosedScene, Poser};

/// Default file name pattern; `{name}` is the dataset name.
pub const DEFAULT_PATTERN: &str = "{name}_{frame:04}.ply";

pub fn sequence(x: &Export, out: &Output, files: &mut Files) -> Result<(), String> {
    if out.vox.is_some() || out.motion || out.correspondence == Some(true) {
        return Err("ply-sequence: `vox`, `motion` and `correspondence` are not implemented yet".to_string());
    }
    if !matches!(out.reduce.unwrap_or_default(), Reduce::Mean) {
        return Err("ply-sequence: only reduce = \"mean\" is implemented yet".to_string());
    }
    let n = out.points.as_ref().map_or(0, |p| *p.get_ref()) as usize;
    let pattern = out.pattern.as_ref().map_or(DEFAULT_PATTERN, |p| p.get_ref().as_str());
    let pattern = pattern.replace("{name}", x.manifest.dataset.name.get_ref());
    let seed = x.manifest.dataset.seed.to_le_bytes();
    let srgb_mean = out.color_average == Some(ColorAverage::Srgb);
    let only = match &out.source {
        Some(s) => Some(x.scene.source_index(s.get_ref()).ok_or_else(|| format!("no source `{}`", s.get_ref()))?),
        None => None,
    };
    let mut poser = Poser::default();
    // Everything but the file name shapes the bytes.
    let settings = format!(
        "{n}|{:?}|{:?}|{:?}|{:?}|{only:?}",
        out.voxel.as_ref().map(|v| *v.get_ref()),
        out.color_average,
        out.format,
        out.reduce
    );
    for f in 0..x.plan.frames {
        let k = key("ply sequence frame", &[SAMPLE_SALT, &x.frame_keys[f].0, &seed, settings.as_bytes()]);
        let d = x.cached(k, || {
            let posed = match only {
                Some(i) => x.scene.pose_source(i, f, &mut poser)?,
                None => x.scene.pose(f, &mut poser)?,
            };
            Ok(frame_ply(posed, out, n, &seed, f, srgb_mean))
        })?;
        files.blob(&format_frame(&pattern, f as i64)?, d)?;
    }
    Ok(())
}

/// Samples, reduces and encodes one frame.
fn frame_ply(posed: &PosedScene, out: &Output, n: usize, seed: &[u8], f: usize, srgb_mean: bool) -> Vec<u8> {
    let mut pts = sample::sample(posed, n, &[b"sequence", seed, &(f as u64).to_le_bytes()]);
    if let Some(v) = &out.voxel {
        if srgb_mean {
            // Average the stored sRGB values (Open3D's behaviour) by averaging in that space.
            pts.colors.iter_mut().for_each(|c| *c = c.map(linear_to_srgb));
            pts = voxel::downsample(&pts, *v.get_ref() as f32);
            pts.colors.iter_mut().for_each(|c| *c = c.map(srgb_to_linear));
        } else {
            pts = voxel::downsample(&pts, *v.get_ref() as f32);
        }
    }
    let colors = pts.srgb8();
    let comment = format!("vvgen frame {f}");
    ply::write(&PlyOut {
        positions: &pts.positions,
        normals: Some(&pts.normals),
        colors: Some(&colors),
        extra_u32: &[],
        extra_f32: &[],
        triangles: None,
        comments: &[&comment],
        ascii: out.format == Some(PlyFormat::Ascii),
    })
}
