//! Frame selection shared by sources (`frames = {…}`) and splits (frame subsets).

use serde::Deserialize;
use toml::Spanned;

use super::diag::Diagnostic;

/// Largest number of frames one source may have; beyond it a typo is likelier than a real sequence.
pub const MAX_FRAMES: u64 = 1_000_000;

/// `frames = { count, fps }` or `frames = { start, end, step, fps }` on a source.
///
/// For glTF sources, frame `i` is at time `clip_start + i / fps`; `start`/`end` are frame numbers at `fps`
/// (end inclusive). For PLY sequences, `start`/`end` are the numbers substituted into the pattern (or
/// positions in the sorted glob), end inclusive.
#[derive(Debug, Clone, Deserialize, Default, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Frames {
    /// Number of frames (from `start`, default 0).
    pub count: Option<u64>,
    /// Frames per second (default 30).
    pub fps: Option<f64>,
    /// First frame number.
    pub start: Option<i64>,
    /// Last frame number, inclusive.
    pub end: Option<i64>,
    /// Take every `step`-th frame (default 1).
    pub step: Option<u64>,
}

impl Frames {
    /// Frames per second, default 30.
    pub fn fps(&self) -> f64 {
        self.fps.unwrap_or(30.0)
    }

    /// The step, default 1.
    pub fn step(&self) -> u64 {
        self.step.unwrap_or(1).max(1)
    }

    pub(crate) fn validate(this: &Spanned<Frames>, diags: &mut Vec<Diagnostic>) {
        let f = this.get_ref();
        let span = Some(this.span());
        if let Some(fps) = f.fps {
            if !(fps.is_finite() && fps > 0.0 && fps <= 10_000.0) {
                diags.push(
                    Diagnostic::error(format!("fps = {fps} is not a frame rate"), span.clone())
                        .with_help("use a positive number such as 30"),
                );
            }
        }
        if f.step == Some(0) {
            diags.push(
                Diagnostic::error("step = 0 selects no frames", span.clone()).with_help("use step = 1 for every frame"),
            );
        }
        match f.count {
            Some(0) => diags.push(
                Diagnostic::error("count = 0: the frame range is empty", span.clone()).with_help("use count ≥ 1"),
            ),
            Some(c) if c > MAX_FRAMES => {
                diags.push(Diagnostic::error(format!("count = {c} frames is more than {MAX_FRAMES}"), span.clone()))
            }
            _ => {}
        }
        if f.count.is_some() && f.end.is_some() {
            diags.push(Diagnostic::error("give either `count` or `end`, not both", span.clone()));
        }
        if let (Some(s), Some(e)) = (f.start, f.end) {
            if e < s {
                diags.push(
                    Diagnostic::error(format!("empty frame range: end = {e} is before start = {s}"), span.clone())
                        .with_help("`end` is inclusive and must be ≥ `start`"),
                );
            } else if (e - s) as u64 / f.step() > MAX_FRAMES {
                diags.push(Diagnostic::error(
                    format!("{} frames is more than {MAX_FRAMES}", (e - s) as u64 / f.step() + 1),
                    span,
                ));
            }
        }
    }
}

/// A split's frame subset: a list of frame positions, or `{ start, end, every }` over the source's frames.
#[derive(Debug, Clone, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(untagged)]
pub enum FrameSubset {
    /// Explicit frame positions (0-based, into the source's selected frames).
    List(Vec<u64>),
    /// A range of positions, end inclusive, every n-th.
    Range {
        /// First position (default 0).
        #[serde(default)]
        start: u64,
        /// Last position, inclusive (default: the last frame).
        #[serde(default)]
        end: Option<u64>,
        /// Take every n-th (default 1).
        #[serde(default)]
        every: Option<u64>,
    },
}

impl FrameSubset {
    pub(crate) fn validate(this: &Spanned<FrameSubset>, diags: &mut Vec<Diagnostic>) {
        let span = Some(this.span());
        match this.get_ref() {
            FrameSubset::List(l) if l.is_empty() => diags.push(Diagnostic::error("empty frame list", span)),
            FrameSubset::Range { every: Some(0), .. } => {
                diags.push(Diagnostic::error("every = 0 selects no frames", span))
            }
            FrameSubset::Range { start, end: Some(e), .. } if e < start => {
                diags.push(Diagnostic::error(format!("empty frame range: end = {e} is before start = {start}"), span))
            }
            _ => {}
        }
    }

    /// The selected positions among `n` frames.
    pub fn select(&self, n: u64) -> Vec<u64> {
        match self {
            FrameSubset::List(l) => l.iter().copied().filter(|&i| i < n).collect(),
            FrameSubset::Range { start, end, every } => {
                let end = end.unwrap_or(n.saturating_sub(1)).min(n.saturating_sub(1));
                if n == 0 || *start > end {
                    return Vec::new();
                }
                (*start..=end).step_by(every.unwrap_or(1).max(1) as usize).collect()
            }
        }
    }
}
