//! `ply-sequence`: one PLY per frame of surface samples from the posed scene (x y z, nx ny nz float; red green
//! blue uchar), optionally voxel-downsampled on a lattice anchored at the world origin (the same for every
//! frame), or quantized into a 2^vox integer grid fixed over the sequence (8i's vox10 layout: float x y z with
//! integer values, uchar colours). With `correspondence`, the samples are drawn once on the first frame and
//! re-evaluated on every frame, so point i is the same surface point throughout (`point_id`, and `motion_x/y/z`
//! to the next frame with `motion = true`).

use super::{Export, Files};
use crate::cache::{key, Digest};
use crate::manifest::output::{ColorAverage, Output, PlyFormat, Reduce};
use crate::manifest::sequence::format_frame;
use crate::plan::keys::SAMPLE_SALT;
use crate::sample::{self, voxel, Draw, Points};
use crate::scene::material::{linear_to_srgb, srgb_to_linear};
use crate::scene::ply::{self, PlyOut};
use crate::scene::{PosedScene, Poser, SourceData};

/// Default file name pattern; `{name}` is the dataset name.
pub const DEFAULT_PATTERN: &str = "{name}_{frame:04}.ply";

/// The integer grid of `vox`: origin and cell edge, fixed for the whole sequence.
#[derive(Debug, Clone, Copy)]
struct Grid {
    lo: [f32; 3],
    cell: f32,
    max: f32,
}

pub fn sequence(x: &Export, out: &Output, files: &mut Files) -> Result<(), String> {
    if !matches!(out.reduce.unwrap_or_default(), Reduce::Mean) {
        return Err("ply-sequence: only reduce = \"mean\" is implemented yet".to_string());
    }
    let n = out.points.as_ref().map_or(0, |p| *p.get_ref()) as usize;
    let pattern = out.pattern.as_ref().map_or(DEFAULT_PATTERN, |p| p.get_ref().as_str());
    let pattern = pattern.replace("{name}", x.manifest.dataset.name.get_ref());
    let seed = x.manifest.dataset.seed.to_le_bytes();
    let only = match &out.source {
        Some(s) => Some(x.scene.source_index(s.get_ref()).ok_or_else(|| format!("no source `{}`", s.get_ref()))?),
        None => None,
    };
    // Correspondence needs one topology over time: meshes, not per-frame point clouds.
    let fixed_topology = x.scene.sources.iter().all(|s| !matches!(s.data, SourceData::Sequence(_)));
    let corr = out.correspondence.unwrap_or(fixed_topology && x.plan.frames > 1);
    if corr && !fixed_topology {
        return Err("ply-sequence: `correspondence` needs mesh sources (a PLY sequence has no fixed surface)".into());
    }
    if out.motion && (!corr || out.voxel.is_some() || out.vox.is_some()) {
        return Err(
            "ply-sequence: `motion` needs correspondence and no `voxel`/`vox` (merged points have no track)".into()
        );
    }
    let frames: Vec<usize> = (0..x.plan.frames).collect();
    let grid = match &out.vox {
        Some(v) => {
            let (lo, hi) = super::bounds(x, &frames)?.ok_or("the scene is empty")?;
            let size = (1u32 << *v.get_ref()) as f32;
            Some(Grid { lo: lo.to_array(), cell: (hi - lo).max_element().max(1e-9) / size, max: size - 1.0 })
        }
        None => None,
    };
    // Everything but the file name shapes the bytes.
    let settings = format!(
        "{n}|{:?}|{:?}|{:?}|{:?}|{only:?}|{corr}|{}|{:?}",
        out.voxel.as_ref().map(|v| *v.get_ref()),
        out.color_average,
        out.format,
        out.reduce,
        out.motion,
        out.vox.as_ref().map(|v| *v.get_ref()),
    );
    let all_frames = key("all frames", &x.frame_keys.iter().map(|k| &k.0[..]).collect::<Vec<_>>());
    let mut poser = Poser::default();
    let mut draws: Option<Vec<Draw>> = None;
    for f in 0..x.plan.frames {
        let mut parts: Vec<&[u8]> = vec![SAMPLE_SALT, &x.frame_keys[f].0, &seed, settings.as_bytes()];
        if corr {
            parts.push(&x.frame_keys[0].0);
        }
        if out.motion && f + 1 < x.plan.frames {
            parts.push(&x.frame_keys[f + 1].0);
        }
        if grid.is_some() {
            parts.push(&all_frames.0);
        }
        let k = key("ply sequence frame", &parts);
        let d: Digest = x.cached(k, || {
            let mut pose = |frame: usize| -> Result<PosedScene, String> {
                Ok(match only {
                    Some(i) => x.scene.pose_source(i, frame, &mut poser)?.clone(),
                    None => x.scene.pose(frame, &mut poser)?.clone(),
                })
            };
            let posed = pose(f)?;
            let (pts, motion) = if corr {
                let d = match &draws {
                    Some(d) => d.clone(),
                    None => {
                        let first = pose(0)?;
                        let d = sample::draw(&first, n, &[b"sequence corr", &seed]);
                        draws = Some(d.clone());
                        d
                    }
                };
                let mut pts = sample::evaluate(&posed, &d)?;
                let motion = if out.motion {
                    let next = if f + 1 < x.plan.frames { sample::evaluate(&pose(f + 1)?, &d)? } else { pts.clone() };
                    Some(
                        pts.positions
                            .iter()
                            .zip(&next.positions)
                            .map(|(a, b)| [b[0] - a[0], b[1] - a[1], b[2] - a[2]])
                            .collect(),
                    )
                } else {
                    None
                };
                pts.extend(&sample::points(&posed));
                (pts, motion)
            } else {
                (sample::sample(&posed, n, &[b"sequence", &seed, &(f as u64).to_le_bytes()]), None)
            };
            Ok(encode(pts, motion, out, grid, corr, f))
        })?;
        files.blob(&format_frame(&pattern, f as i64)?, d)?;
    }
    Ok(())
}

/// Reduces and encodes one frame.
fn encode(
    mut pts: Points,
    motion: Option<Vec<[f32; 3]>>,
    out: &Output,
    grid: Option<Grid>,
    corr: bool,
    f: usize,
) -> Vec<u8> {
    let srgb_mean = out.color_average == Some(ColorAverage::Srgb);
    let reduce = |pts: &Points, size: f32| {
        if srgb_mean {
            // Average the stored sRGB values (Open3D's behaviour) by averaging in that space.
            let mut p = pts.clone();
            p.colors.iter_mut().for_each(|c| *c = c.map(linear_to_srgb));
            let mut r = voxel::downsample(&p, size);
            r.colors.iter_mut().for_each(|c| *c = c.map(srgb_to_linear));
            r
        } else {
            voxel::downsample(pts, size)
        }
    };
    let mut comments = vec![format!("vvgen frame {f}")];
    let mut merged = false;
    if let Some(g) = grid {
        // Into grid units, merged per integer cell, then each point at its cell's integer corner (8i style).
        for p in &mut pts.positions {
            for (c, lo) in p.iter_mut().zip(g.lo) {
                *c = ((*c - lo) / g.cell).floor().clamp(0.0, g.max) + 0.5;
            }
        }
        pts = reduce(&pts, 1.0);
        pts.positions.iter_mut().for_each(|p| *p = p.map(f32::floor));
        comments.push(format!("vvgen grid origin {} {} {} cell {}", g.lo[0], g.lo[1], g.lo[2], g.cell));
        merged = true;
    } else if let Some(v) = &out.voxel {
        pts = reduce(&pts, *v.get_ref() as f32);
        merged = true;
    }
    let colors = pts.srgb8();
    let ids: Vec<u32> = if corr && !merged { (0..pts.len() as u32).collect() } else { Vec::new() };
    let (mx, my, mz): (Vec<f32>, Vec<f32>, Vec<f32>) = match &motion {
        Some(m) => {
            (m.iter().map(|v| v[0]).collect(), m.iter().map(|v| v[1]).collect(), m.iter().map(|v| v[2]).collect())
        }
        None => Default::default(),
    };
    let mut extra_u32: Vec<(&str, &[u32])> = Vec::new();
    if !ids.is_empty() {
        extra_u32.push(("point_id", &ids));
    }
    let extra_f32: Vec<(&str, &[f32])> = if motion.is_some() && mx.len() == pts.len() {
        vec![("motion_x", &mx), ("motion_y", &my), ("motion_z", &mz)]
    } else {
        Vec::new()
    };
    let comment_refs: Vec<&str> = comments.iter().map(String::as_str).collect();
    ply::write(&PlyOut {
        positions: &pts.positions,
        normals: if grid.is_some() { None } else { Some(&pts.normals) },
        colors: Some(&colors),
        extra_u32: &extra_u32,
        extra_f32: &extra_f32,
        triangles: None,
        comments: &comment_refs,
        ascii: out.format == Some(PlyFormat::Ascii),
    })
}
