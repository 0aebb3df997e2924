//! `ply-sequence`: places one PLY per frame (the graph's point-frame actions made them: surface samples of
//! the posed scene, optionally voxel-downsampled or quantized into an 8i-style `2^vox` grid) and describes the
//! sequence in `vvgen/dataset.json`: per-frame times and counts, and the grid that maps integer coordinates back to
//! the world.

use serde_json::json;

use super::{Error, Export, Files};
use crate::cache::Digest;
use crate::execute::Grid;
use crate::manifest::sequence::format_frame;
use crate::plan::actions::Action;
use crate::plan::time_of;
use crate::scene::ply;

/// Places the frames of point output `name` and adds the `sequence` section of its metadata.
pub fn sequence(x: &Export, name: &str, files: &mut Files) -> Result<(), Error> {
    let s = &x.graph.keying.points[name];
    let frames = x.plan.frames;
    let mut entries = Vec::with_capacity(frames);
    for f in 0..frames {
        let d = x.blob(&Action::PointFrame { output: name.to_string(), frame: f })?;
        let file = format_frame(&s.pattern, f as i64)?;
        files.blob(&file, d)?;
        let count = vertex_count(x, &d)?;
        entries.push(json!({ "index": f, "time": time_of(f, frames), "file": file, "points": count }));
    }
    let lower = |v: String| v.to_lowercase();
    let mut seq = json!({
        "points_sampled": s.points,
        "correspondence": s.correspondence,
        "motion": s.motion,
        "voxel": s.voxel,
        "reduce": lower(format!("{:?}", s.reduce)),
        "position": lower(format!("{:?}", s.position)),
        "color_average": lower(format!("{:?}", s.color_average)),
        "colors": "8-bit sRGB",
        "frames": entries,
    });
    if let Some(vox) = s.vox {
        let all: Vec<usize> = (0..frames).collect();
        let (lo, hi) = x.bounds(&all)?.ok_or(Error::EmptyScene)?;
        let g = Grid::new(lo, hi, vox);
        let size = 1u32 << vox;
        seq["grid"] = json!({
            "vox": vox,
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

/// Points in a stored PLY frame, from its header.
fn vertex_count(x: &Export, d: &Digest) -> Result<usize, Error> {
    use std::io::Read;
    // The header is at the front; reading the whole frame back would cost as much as the build itself.
    let path = x.store.object_path(d);
    let mut head = Vec::new();
    std::fs::File::open(&path)
        .and_then(|f| f.take(1 << 16).read_to_end(&mut head))
        .map_err(|e| crate::cache::Error::io(&path, e))?;
    let h =
        ply::parse_header(&head).map_err(|e| crate::cache::Error::Damaged { digest: d.hex(), why: e.to_string() })?;
    Ok(h.elements.iter().find(|e| e.name == "vertex").map_or(0, |e| e.count))
}
