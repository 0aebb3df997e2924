//! `ply-sequence`: one PLY per frame of surface samples from the posed scene (x y z, nx ny nz float; red green
//! blue uchar), optionally voxel-downsampled on a lattice anchored at the world origin (the same for every
//! frame), or quantized into a 2^vox integer grid fixed over the sequence (8i's vox10 layout: float x y z with
//! integer values, uchar colours). With `correspondence`, the samples are drawn once on the first frame and
//! re-evaluated on every frame, so point i is the same surface point throughout (`point_id`, and `motion_x/y/z`
//! to the next frame with `motion = true`).

use std::sync::OnceLock;

use rayon::prelude::*;
use serde_json::json;

use super::{Export, Files};
use crate::cache::{key, Digest};
use crate::manifest::output::{ColorAverage, Output, PlyFormat};
use crate::manifest::sequence::format_frame;
use crate::plan::keys::SAMPLE_SALT;
use crate::plan::time_of;
use crate::sample::voxel::{self, Reduction};
use crate::sample::{self, Draw, Points};
use crate::scene::material::{linear_to_srgb, srgb_to_linear};
use crate::scene::ply::{self, PlyOut};
use crate::scene::{PosedScene, Poser, SourceData};

/// The integer grid of `vox`: origin and cell edge, fixed for the whole sequence.
#[derive(Debug, Clone, Copy)]
struct Grid {
    lo: [f32; 3],
    cell: f32,
    max: f32,
}

/// One frame's samples before reduction, and their motion to the next frame.
type Samples = (Points, Option<Vec<[f32; 3]>>);

pub fn sequence(x: &Export, out: &Output, files: &mut Files) -> Result<(), String> {
    let n = out.points.as_ref().map_or(0, |p| *p.get_ref()) as usize;
    let pattern = out.file_pattern(x.manifest.dataset.name.get_ref());
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
    let frames = x.plan.frames;
    let all_frames = key("all frames", &x.frame_keys.iter().map(|k| &k.0[..]).collect::<Vec<_>>());
    let grid = match &out.vox {
        Some(v) => Some(grid(x, *v.get_ref(), &all_frames)?),
        None => None,
    };
    let reduces = grid.is_some() || out.voxel.is_some();
    // What shapes the samples, and (separately) what shapes their reduction and encoding, so a change of voxel
    // size re-runs only the reduction.
    let sample_settings = format!("{n}|{only:?}|{corr}|{}", out.motion);
    let reduce_settings = format!(
        "{:?}|{:?}|{:?}|{:?}|{:?}|{:?}|{:?}",
        out.voxel.as_ref().map(|v| *v.get_ref()),
        out.color_average,
        out.format,
        out.reduce,
        out.position,
        out.vox.as_ref().map(|v| *v.get_ref()),
        grid.map(|g| (g.lo, g.cell)),
    );
    let draws: OnceLock<Result<Vec<Draw>, String>> = OnceLock::new();
    // Frames in parallel: each is an independent cached task with its own poser.
    let made: Vec<Result<(Digest, usize), String>> = (0..frames)
        .into_par_iter()
        .map(|f| {
            let mut parts: Vec<&[u8]> = vec![SAMPLE_SALT, &x.frame_keys[f].0, &seed, sample_settings.as_bytes()];
            if corr {
                parts.push(&x.frame_keys[0].0);
            }
            if out.motion && f + 1 < frames {
                parts.push(&x.frame_keys[f + 1].0);
            }
            let sample_key = key("ply sequence samples", &parts);
            let make = || -> Result<Samples, String> {
                let mut poser = Poser::default();
                let mut pose = |frame: usize| -> Result<PosedScene, String> {
                    Ok(match only {
                        Some(i) => x.scene.pose_source(i, frame, &mut poser)?.clone(),
                        None => x.scene.pose(frame, &mut poser)?.clone(),
                    })
                };
                let posed = pose(f)?;
                if !corr {
                    return Ok((sample::sample(&posed, n, &[b"sequence", &seed, &(f as u64).to_le_bytes()]), None));
                }
                let d = draws
                    .get_or_init(|| Ok(sample::draw(&pose(0)?, n, &[b"sequence corr", &seed])))
                    .as_ref()
                    .map_err(Clone::clone)?;
                let mut pts = sample::evaluate(&posed, d)?;
                let motion = if out.motion {
                    let next = if f + 1 < frames { sample::evaluate(&pose(f + 1)?, d)? } else { pts.clone() };
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
                Ok((pts, motion))
            };
            let k = key("ply sequence frame", &[&sample_key.0, reduce_settings.as_bytes()]);
            let d = x.cached(k, || {
                let (pts, motion) = if reduces {
                    // The unreduced samples are a task of their own (motion is never asked for here).
                    let raw = x.cached(sample_key, || Ok(make()?.0.to_bytes()))?;
                    (Points::from_bytes(&x.store.get(&raw).map_err(|e| format!("cache: {e}"))?)?, None)
                } else {
                    make()?
                };
                Ok(encode(pts, motion, out, grid, corr, f))
            })?;
            Ok((d, vertex_count(x, &d)?))
        })
        .collect();
    let mut entries = Vec::with_capacity(frames);
    for (f, r) in made.into_iter().enumerate() {
        let (d, count) = r?;
        let file = format_frame(&pattern, f as i64)?;
        files.blob(&file, d)?;
        entries.push(json!({ "index": f, "time": time_of(f, frames), "file": file, "points": count }));
    }
    let mut seq = json!({
        "points_sampled": n,
        "correspondence": corr,
        "motion": out.motion,
        "voxel": out.voxel.as_ref().map(|v| *v.get_ref()),
        "reduce": format!("{:?}", out.reduce.unwrap_or_default()).to_lowercase(),
        "position": format!("{:?}", out.position.unwrap_or_default()).to_lowercase(),
        "color_average": format!("{:?}", out.color_average.unwrap_or_default()).to_lowercase(),
        "colors": "8-bit sRGB",
        "frames": entries,
    });
    if let (Some(g), Some(v)) = (grid, &out.vox) {
        let size = 1u32 << *v.get_ref();
        seq["grid"] = json!({
            "vox": v.get_ref(),
            "size": size,
            "origin": g.lo,
            "cell": g.cell,
            "bounds": [g.lo, g.lo.map(|l| l + g.cell * size as f32)],
            "to_world": "world = origin + (integer coordinate + 0.5) * cell",
        });
    }
    files.meta("sequence", seq);
    Ok(())
}

/// The sequence's integer grid: the bounds of every frame, cached under the frames' keys (so a no-op build does
/// not pose the whole sequence again).
fn grid(x: &Export, vox: u32, all_frames: &Digest) -> Result<Grid, String> {
    let k = key("sequence grid", &[&all_frames.0, &vox.to_le_bytes()]);
    let d = x.cached(k, || {
        let frames: Vec<usize> = (0..x.plan.frames).collect();
        let (lo, hi) = super::bounds(x, &frames)?.ok_or("the scene is empty")?;
        let cell = (hi - lo).max_element().max(1e-9) / (1u32 << vox) as f32;
        Ok([lo.x, lo.y, lo.z, cell].iter().flat_map(|v| v.to_le_bytes()).collect())
    })?;
    let b = x.store.get(&d).map_err(|e| format!("cache: {e}"))?;
    let v: Vec<f32> = b.chunks_exact(4).map(|c| f32::from_le_bytes(c.try_into().unwrap())).collect();
    let [lx, ly, lz, cell] = v[..] else { return Err("cache: damaged sequence grid".into()) };
    Ok(Grid { lo: [lx, ly, lz], cell, max: ((1u32 << vox) - 1) as f32 })
}

/// Points in a stored PLY frame, from its header.
fn vertex_count(x: &Export, d: &Digest) -> Result<usize, String> {
    use std::io::Read;
    // The header is at the front; reading the whole frame back would cost as much as the build itself.
    let mut head = Vec::new();
    std::fs::File::open(x.store.object_path(d))
        .and_then(|f| f.take(1 << 16).read_to_end(&mut head))
        .map_err(|e| format!("cache: {e}"))?;
    let h = ply::parse_header(&head).map_err(|e| format!("cache: {e}"))?;
    Ok(h.elements.iter().find(|e| e.name == "vertex").map_or(0, |e| e.count))
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
    let how = Reduction { reduce: out.reduce.unwrap_or_default(), position: out.position.unwrap_or_default() };
    let reduce = |pts: &Points, size: f32| {
        if srgb_mean {
            // Average the stored sRGB values (Open3D's behaviour) by averaging in that space.
            let mut p = pts.clone();
            p.colors.iter_mut().for_each(|c| *c = c.map(linear_to_srgb));
            let mut r = voxel::downsample(&p, size, how);
            r.colors.iter_mut().for_each(|c| *c = c.map(srgb_to_linear));
            r
        } else {
            voxel::downsample(pts, size, how)
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
