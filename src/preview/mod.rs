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

/// The folder, dataset-root-relative, the preview is written to.
pub const DIR: &str = "preview";

/// Surface samples of the subject drawn in the rig plot and the viewer (at the middle frame).
pub const POINTS: u64 = 20_000;

/// Version of the preview pictures: bump when a change moves their bytes.
pub const SALT: &str = "preview 2";

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
}

/// The frame whose surface samples stand for the subject: the middle of `frames` (ascending).
pub fn subject_frame(frames: &[usize]) -> usize {
    frames.get(frames.len() / 2).copied().unwrap_or(0)
}

/// The frames of an `n`-frame point sequence its strip shows.
pub fn strip_frames(n: usize) -> Vec<usize> {
    sheet::evenly(n, strip::MOST)
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
    let d = crate::scene::ply::read(ply).map_err(Error::Cloud)?;
    let colors = match d.colors {
        Some(c) => c.iter().map(|c| [c[0], c[1], c[2]]).collect(),
        None => vec![[200, 200, 200]; d.positions.len()],
    };
    Ok(Samples { positions: d.positions, colors })
}
