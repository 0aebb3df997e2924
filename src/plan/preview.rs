//! What each preview shows: the images of a split's contact sheet, the frames of a point sequence's strip and
//! viewer, the frame and sample count that stand for the subject. The planner keys the preview actions by
//! exactly these choices, and `preview` draws them.

use super::Plan;
use crate::manifest::render::Pass;
use crate::manifest::split::TimeMode;

/// Surface samples of the subject drawn in the rig plot and the viewer (at the middle frame).
pub const POINTS: u64 = 20_000;

/// Version of the preview pictures: bump when a change moves their bytes.
pub const SALT: &str = "preview 3";

/// Most thumbnails on a sheet.
const MOST: usize = 32;
/// Most frames (columns) and views (rows) of a multi-view video sheet.
const MOST_FRAMES: usize = 8;
const MOST_VIEWS: usize = 4;
/// Frames of a point sequence's strip, at most.
pub const STRIP_FRAMES: usize = 6;

/// What a sheet shows: images of the plan in reading order, and the number of columns.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Layout {
    /// Plan image indices, row by row.
    pub images: Vec<usize>,
    /// Columns of the grid.
    pub columns: usize,
}

/// `k` indices spread evenly over `0..n`, first and last included (all of them when `n ≤ k`).
pub fn evenly(n: usize, k: usize) -> Vec<usize> {
    if n <= k {
        return (0..n).collect();
    }
    if k <= 1 {
        return vec![0];
    }
    (0..k).map(|i| i * (n - 1) / (k - 1)).collect()
}

/// The images split `s`'s sheet shows.
pub fn layout(plan: &Plan, s: usize) -> Layout {
    let split = &plan.splits[s];
    if split.time == TimeMode::All && split.frames.len() > 1 {
        // Rows are views, columns frames; images of a synchronized split are frame-major.
        let views = split.poses.len();
        let rows = evenly(views, MOST_VIEWS);
        let cols = evenly(split.frames.len(), MOST_FRAMES);
        let images = rows.iter().flat_map(|&v| cols.iter().map(move |&f| split.images[f * views + v])).collect();
        return Layout { images, columns: cols.len() };
    }
    let mut order = split.images.clone();
    // Time-major: by frame, then view (a random split's pairs come in draw order).
    order.sort_by_key(|&i| (plan.images[i].frame, plan.images[i].view, i));
    let images: Vec<usize> = evenly(order.len(), MOST).into_iter().map(|k| order[k]).collect();
    let columns = images.len().clamp(1, MOST_FRAMES);
    Layout { images, columns }
}

/// The frame whose surface samples stand for the subject: the middle of `frames` (ascending).
pub fn subject_frame(frames: &[usize]) -> usize {
    frames.get(frames.len() / 2).copied().unwrap_or(0)
}

/// The frames of an `n`-frame point sequence its strip shows.
pub fn strip_frames(n: usize) -> Vec<usize> {
    evenly(n, STRIP_FRAMES)
}

/// Frames of a point sequence its viewer steps through, at most.
const VIEWER_FRAMES: usize = 24;

/// The frames of an `n`-frame point sequence its viewer steps through.
pub fn viewer_frames(n: usize) -> Vec<usize> {
    evenly(n, VIEWER_FRAMES)
}

/// The frames a point sequence's preview reads: the strip's and the viewer's, ascending.
pub fn point_frames(n: usize) -> Vec<usize> {
    let mut f = strip_frames(n);
    f.extend(viewer_frames(n));
    f.sort_unstable();
    f.dedup();
    f
}

/// The passes a sheet shows besides RGBA, of those rendered.
pub fn extra_passes(passes: &[Pass]) -> Vec<Pass> {
    [Pass::Depth, Pass::Mask].into_iter().filter(|p| passes.contains(p)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn evenly_keeps_both_ends() {
        assert_eq!(evenly(3, 8), vec![0, 1, 2]);
        assert_eq!(evenly(60, 8), vec![0, 8, 16, 25, 33, 42, 50, 59]);
        assert_eq!(evenly(10, 1), vec![0]);
    }
    #[test]
    fn the_viewer_reads_the_strips_frames_and_its_own() {
        assert_eq!(point_frames(3), [0, 1, 2]);
        let f = point_frames(300);
        assert!(strip_frames(300).iter().chain(&viewer_frames(300)).all(|x| f.contains(x)));
        assert_eq!(viewer_frames(300).len(), 24);
    }
}
