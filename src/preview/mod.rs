//! Previews: pictures of a dataset that answer "does it look right?" before anyone trains on it. Each output
//! gets a `preview/` folder: a contact sheet per split ([`sheet`]), a rig plot of every camera around the
//! subject ([`rig_plot`]), a strip of point-cloud frames for `ply-sequence` outputs ([`strip`]), and an HTML
//! viewer ([`viewer`]). The pictures are cached actions of the graph like any other (`preview-sheet`,
//! `preview-rig`, `preview-strip`); the page is written with the dataset's metadata, from the plan and the
//! placed files. No consumer scans `preview/` (the instant-ngp `*.json` rule reads the root only).

pub mod canvas;
pub mod rig_plot;
pub mod sheet;
pub mod strip;
pub mod viewer;

// What each preview shows is the plan's to decide (it keys the preview actions by it).
pub use crate::plan::preview::{point_frames, strip_frames, subject_frame, viewer_frames, POINTS, SALT};

/// The folder, dataset-root-relative, the preview is written to.
pub const DIR: &str = "preview";

/// Why a preview picture cannot be drawn.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A render the contact sheet shows does not decode.
    #[error(transparent)]
    Sheet(#[from] sheet::Error),
    /// A point-cloud frame the strip shows does not read back.
    #[error(transparent)]
    Strip(#[from] strip::Error),
    /// The subject's samples do not read back.
    #[error("the subject's surface samples do not read back")]
    Cloud(#[source] crate::scene::ply::PlyError),
    /// The viewer's thinned point frames do not read back.
    #[error("the viewer's thinned point frames do not read back (a damaged cache blob)")]
    Thinned,
    /// A point-cloud frame the viewer shows does not read back.
    #[error("frame {frame}: the point-cloud file does not read back")]
    Frame {
        /// The frame.
        frame: usize,
        /// Why.
        #[source]
        source: crate::scene::ply::PlyError,
    },
}

/// Points of each frame the viewer draws, at most (every k-th point of the file).
const VIEWER_POINTS: usize = 8_000;

/// A point-cloud frame thinned for the viewer: every k-th point, at most 8 000 (`VIEWER_POINTS`).
pub fn thin(ply: &[u8]) -> Result<Samples, crate::scene::ply::PlyError> {
    let d = crate::scene::ply::read(ply)?;
    let step = d.positions.len().div_ceil(VIEWER_POINTS).max(1);
    Ok(every(&d, step))
}

/// Every `step`-th point of `d`, light grey where the file has no colours.
fn every(d: &crate::scene::ply::PlyData, step: usize) -> Samples {
    let positions: Vec<[f32; 3]> = d.positions.iter().step_by(step).copied().collect();
    let colors = match &d.colors {
        Some(c) => c.iter().step_by(step).map(|c| [c[0], c[1], c[2]]).collect(),
        None => vec![[200, 200, 200]; positions.len()],
    };
    Samples { positions, colors }
}

/// Frames of thinned clouds as one blob: per frame, its number and point count (u32 LE), then positions
/// (3 × f32 LE) and colours (3 × u8) per point.
pub fn encode_clouds(clouds: &[(usize, Samples)]) -> Vec<u8> {
    let mut out = Vec::new();
    for (frame, s) in clouds {
        out.extend((*frame as u32).to_le_bytes());
        out.extend((s.positions.len() as u32).to_le_bytes());
        out.extend(bytemuck::cast_slice::<[f32; 3], u8>(&s.positions));
        out.extend(s.colors.iter().flatten());
    }
    out
}

/// The clouds of [`encode_clouds`]; `None` for bytes it did not write (a damaged cache).
pub fn decode_clouds(mut b: &[u8]) -> Option<Vec<(usize, Samples)>> {
    let mut out = Vec::new();
    let u32_at = |b: &[u8], at: usize| {
        b.get(at..at + 4).map(|x| u32::from_le_bytes(x.try_into().expect("BUG: 4 bytes")) as usize)
    };
    while !b.is_empty() {
        let (frame, n) = (u32_at(b, 0)?, u32_at(b, 4)?);
        let body = b.get(8..8 + n.checked_mul(15)?)?;
        let positions = body[..12 * n].chunks_exact(12).map(bytemuck::pod_read_unaligned::<[f32; 3]>).collect();
        let colors = body[12 * n..].chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
        out.push((frame, Samples { positions, colors }));
        b = &b[8 + 15 * n..];
    }
    Some(out)
}

/// The subject's surface samples, as the rig plot and the viewer draw them.
pub struct Samples {
    /// World positions.
    pub positions: Vec<[f32; 3]>,
    /// sRGB colours.
    pub colors: Vec<[u8; 3]>,
}

/// The samples of an init-cloud PLY.
pub fn cloud(ply: &[u8]) -> Result<Samples, Error> {
    Ok(every(&crate::scene::ply::read(ply).map_err(Error::Cloud)?, 1))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn thinned_clouds_round_trip_and_damage_is_refused() {
        let a = Samples { positions: vec![[1.0, 2.0, 3.0], [-1.0, 0.5, 9.0]], colors: vec![[1, 2, 3], [4, 5, 6]] };
        let b = Samples { positions: vec![], colors: vec![] };
        let bytes = encode_clouds(&[(3, a), (7, b)]);
        let back = decode_clouds(&bytes).unwrap();
        assert_eq!(back.iter().map(|(f, s)| (*f, s.positions.len())).collect::<Vec<_>>(), [(3, 2), (7, 0)]);
        assert_eq!(back[0].1.positions[1], [-1.0, 0.5, 9.0]);
        assert_eq!(back[0].1.colors[1], [4, 5, 6]);
        assert!(decode_clouds(&bytes[..bytes.len() - 9]).is_none());
        assert!(decode_clouds(&[0xff; 8]).is_none(), "an absurd count is refused, not allocated");
    }
}
