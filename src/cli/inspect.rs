//! `vvgen inspect`: what the scene of a manifest is, frame by frame, and its posed geometry as PLY.

use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{bail, Context};
use glam::Vec2;

use super::{load_manifest, Ui};
use crate::scene::material::linear_to_srgb;
use crate::scene::ply::{self, PlyOut};
use crate::scene::{Poser, PrimKind, SourceData};

/// Prints the scene summary; with `ply`, writes the posed geometry of `frame`.
pub fn run(
    path: &Path,
    source: Option<&str>,
    frame: usize,
    ply_out: Option<&PathBuf>,
    ui: Ui,
) -> anyhow::Result<ExitCode> {
    let Some(m) = load_manifest(path, ui) else {
        return Ok(ExitCode::from(super::EXIT_INVALID));
    };
    let scene = super::open_scene(&m, ui)?;
    for w in &scene.warnings {
        eprintln!("warning: {w}");
    }
    if frame >= scene.frames.max(1) {
        bail!("frame {frame} is out of range: the scene has {} frames", scene.frames);
    }
    let only = match source {
        Some(name) => match scene.source_index(name) {
            Some(i) => Some(i),
            None => {
                let names: Vec<&str> = scene.sources.iter().map(|s| s.name.as_str()).collect();
                eprintln!("error: no source `{name}` in {}: the sources are {}", path.display(), names.join(", "));
                return Ok(ExitCode::from(super::EXIT_INVALID));
            }
        },
        None => None,
    };
    let mut out = String::new();
    use std::fmt::Write as _;
    for (i, s) in scene.sources.iter().enumerate() {
        if source.is_some_and(|n| n != s.name) {
            continue;
        }
        let _ = writeln!(out, "source `{}`: {} frame(s)", s.name, s.frame_count());
        match &s.data {
            SourceData::Fbx { asset, take, times } => {
                let _ = writeln!(out, "  file: {}", asset.path.display());
                for (ti, t) in asset.takes.iter().enumerate() {
                    let playing = if *take == Some(ti) { " (playing)" } else { "" };
                    let _ = writeln!(out, "  take {ti} `{}`: {:.3} s{playing}", t.name, t.duration());
                }
                if let (Some(a), Some(b)) = (times.first(), times.last()) {
                    let _ = writeln!(out, "  frame times: {a:.4} s … {b:.4} s");
                }
            }
            SourceData::Gltf { asset, clips, times } => {
                let _ = writeln!(out, "  file: {}", asset.path.display());
                for (ci, a) in asset.animations.iter().enumerate() {
                    let playing = if clips.contains(&ci) { " (playing)" } else { "" };
                    let _ = writeln!(
                        out,
                        "  clip {ci} `{}`: {:.3} s, {} channel(s){playing}",
                        a.name.as_deref().unwrap_or(""),
                        a.duration(),
                        a.channels.len()
                    );
                }
                if let (Some(a), Some(b)) = (times.first(), times.last()) {
                    let _ = writeln!(out, "  frame times: {a:.4} s … {b:.4} s");
                }
                for (i, l) in asset.lights.iter().enumerate() {
                    let _ = writeln!(
                        out,
                        "  light {i} `{}`: {} (Blender units: {})",
                        l.name.as_deref().unwrap_or(""),
                        l.light.kind.name(),
                        l.light.intensity
                    );
                }
                for c in &asset.cameras {
                    let _ = writeln!(
                        out,
                        "  camera `{}` on node {} ({}{})",
                        c.name,
                        c.node,
                        c.kind,
                        c.yfov.map(|f| format!(", yfov {f:.4} rad")).unwrap_or_default()
                    );
                }
            }
            SourceData::Static(_) => {
                let _ = writeln!(out, "  static mesh");
            }
            SourceData::Sequence(frames) | SourceData::MeshSequence(frames) => {
                let _ = writeln!(
                    out,
                    "  files: {} … {}",
                    frames[0].path.display(),
                    frames[frames.len() - 1].path.display()
                );
                let digest = s.content_digest(frame, &frames[0].path)?;
                let shown = frames[frame.min(frames.len() - 1)].path.display();
                let _ = writeln!(out, "  frame {frame}: {shown} (blake3 {digest})");
            }
        }
        // The first cloud's voxel sizes the splats unless `[render] splat` says otherwise.
        if let Some((_, v)) = scene.voxel.filter(|(k, _)| *k == i) {
            let how = if v == 1.0 { "its whole-number grid" } else { "9 points in 10 have a neighbour within it" };
            let _ = writeln!(out, "  voxel: {v} source units ({how}); splats default to it");
        }
        let m4 = scene.world_from_source(i).transpose().to_cols_array_2d();
        let _ = writeln!(out, "  source → world (rows):");
        for row in m4 {
            let _ = writeln!(out, "    [{:>10.6}, {:>10.6}, {:>10.6}, {:>10.6}]", row[0], row[1], row[2], row[3]);
        }
    }
    let mut poser = Poser::default();
    let (mut lo, mut hi) = (glam::Vec3::splat(f32::INFINITY), glam::Vec3::splat(f32::NEG_INFINITY));
    for f in 0..scene.frames {
        if let Some((a, b)) = scene.pose(f, &mut poser)?.bounds() {
            lo = lo.min(a);
            hi = hi.max(b);
        }
    }
    // With `--source`, the frame's figures and `--ply` are that source's alone.
    let posed = match only {
        Some(i) => scene.pose_source(i, frame, &mut poser)?,
        None => scene.pose(frame, &mut poser)?,
    };
    let _ = writeln!(
        out,
        "scene: {} frame(s); bounds over all frames {:.4?} … {:.4?}",
        scene.frames,
        lo.to_array(),
        hi.to_array()
    );
    if let Some((a, b)) = posed.bounds() {
        let _ = writeln!(out, "frame {frame}: bounds {:.4?} … {:.4?}", a.to_array(), b.to_array());
    }
    let _ = writeln!(
        out,
        "frame {frame}{}: {} triangle(s), {} point(s), posed-geometry hash {}",
        source.map(|n| format!(" of source `{n}`")).unwrap_or_default(),
        posed.triangle_count(),
        posed.point_count(),
        posed.digest()
    );
    // A splatting file's points are Gaussians: say so, and how their colour varies with the view.
    for g in posed.primitives.iter().filter_map(|p| p.gaussians.as_ref().map(|g| (p.positions.len(), g.data.degree))) {
        let _ = writeln!(
            out,
            "frame {frame}: {} of the points are 3D Gaussians (spherical harmonics of degree {}), drawn as splatting draws them",
            g.0, g.1
        );
    }
    if !ui.quiet {
        print!("{out}");
    }
    if let Some(p) = ply_out {
        write_posed_ply(posed, p)?;
        if !ui.quiet {
            println!("wrote {}", p.display());
        }
    }
    Ok(ExitCode::SUCCESS)
}

/// Writes every vertex (normal, albedo colour) and triangle of a posed scene as one binary PLY.
fn write_posed_ply(posed: &crate::scene::PosedScene, path: &Path) -> anyhow::Result<()> {
    let (mut pos, mut nrm, mut col, mut tris) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    for p in &posed.primitives {
        let base = pos.len() as u32;
        let mat = posed.material(p.material);
        for v in 0..p.positions.len() {
            pos.push(p.positions[v].to_array());
            nrm.push(p.normals[v].to_array());
            let c = mat.albedo(&posed.textures, p.uvs.get(v).copied().map(|u: Vec2| u), p.colors.get(v).copied());
            col.push([0, 1, 2].map(|k| (linear_to_srgb(c[k]) * 255.0).round() as u8));
        }
        if p.kind == PrimKind::Triangles {
            tris.extend(p.indices.iter().map(|i| i + base));
        }
    }
    let bytes = ply::write(&PlyOut {
        positions: &pos,
        normals: Some(&nrm),
        colors: Some(&col),
        triangles: Some(&tris),
        comments: &["posed by vvgen inspect"],
        ..Default::default()
    });
    let tmp = path.with_extension("ply.partial");
    let mut f = std::fs::File::create(&tmp).with_context(|| format!("cannot create {}", tmp.display()))?;
    f.write_all(&bytes)?;
    f.sync_all()?;
    std::fs::rename(&tmp, path).with_context(|| format!("cannot write {}", path.display()))?;
    Ok(())
}
