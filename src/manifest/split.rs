//! `[split.NAME]`: which rig, how many views, how views meet time.

use serde::Deserialize;
use toml::Spanned;

use super::diag::Diagnostic;
use super::frames::FrameSubset;

/// Most views one split may ask for.
pub const MAX_VIEWS: u32 = 1_000_000;

/// One `[split.NAME]` table.
#[derive(Debug, Clone, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Split {
    /// The rig whose cameras this split uses.
    #[schemars(with = "String")]
    pub(super) rig: Spanned<String>,
    /// Number of camera poses (not needed for `explicit`/`from-file` rigs).
    #[schemars(with = "Option<u32>")]
    pub(super) views: Option<Spanned<u32>>,
    /// How views meet frames (default `"all"`).
    #[serde(default)]
    pub time: TimeMode,
    /// `time = "random"`: how many (view, frame) pairs.
    #[schemars(with = "Option<u32>")]
    pub(super) pairs: Option<Spanned<u32>>,
    /// Which of the source frames this split uses (default all).
    #[schemars(with = "Option<FrameSubset>")]
    pub(super) frames: Option<Spanned<FrameSubset>>,
    /// Seed of this split's random streams (default: derived from the dataset seed and the split name).
    pub seed: Option<u64>,
    /// Allow this split to share camera poses with another split (default false: a warning).
    #[serde(default)]
    pub allow_shared_poses: bool,
}

/// How views meet time.
#[derive(Debug, Clone, Copy, Deserialize, PartialEq, Eq, Default, Hash, schemars::JsonSchema)]
#[serde(rename_all = "lowercase")]
pub enum TimeMode {
    /// Every view renders every selected frame (synchronized multi-view video).
    #[default]
    All,
    /// One view per frame (D-NeRF capture style); views cycle if fewer than frames.
    Monocular,
    /// `pairs` seeded (view, frame) pairs.
    Random,
}

impl Split {
    pub(crate) fn validate(&self, diags: &mut Vec<Diagnostic>) {
        if let Some(v) = &self.views {
            let n = *v.get_ref();
            if n == 0 {
                diags.push(
                    Diagnostic::error("views = 0: the split would be empty", Some(v.span())).with_help("use views ≥ 1"),
                );
            } else if n > MAX_VIEWS {
                diags.push(Diagnostic::error(format!("views = {n} is more than {MAX_VIEWS}"), Some(v.span())));
            }
        }
        match (self.time, &self.pairs) {
            (TimeMode::Random, None) => diags.push(
                Diagnostic::error("time = \"random\" needs `pairs`", Some(self.rig.span()))
                    .with_help("e.g. pairs = 200"),
            ),
            (TimeMode::Random, Some(p)) if *p.get_ref() == 0 => {
                diags.push(Diagnostic::error("pairs = 0: the split would be empty", Some(p.span())))
            }
            (TimeMode::Random, Some(p)) if *p.get_ref() > MAX_VIEWS => diags
                .push(Diagnostic::error(format!("pairs = {} is more than {MAX_VIEWS}", p.get_ref()), Some(p.span()))),
            (TimeMode::All | TimeMode::Monocular, Some(p)) => {
                diags.push(Diagnostic::error("`pairs` applies only to time = \"random\"", Some(p.span())))
            }
            _ => {}
        }
        if let Some(f) = &self.frames {
            FrameSubset::validate(f, diags);
        }
    }
}

/// Plain values of the fields whose spans stay inside `manifest` (for diagnostics).
impl Split {
    /// The rig's name.
    pub fn rig(&self) -> &str {
        self.rig.get_ref()
    }

    /// Cameras, when given.
    pub fn views(&self) -> Option<u32> {
        self.views.as_ref().map(|v| *v.get_ref())
    }

    /// Random (frame, view) pairs, when given.
    pub fn pairs(&self) -> Option<u32> {
        self.pairs.as_ref().map(|p| *p.get_ref())
    }

    /// The frame subset, when given.
    pub fn frames(&self) -> Option<&FrameSubset> {
        self.frames.as_ref().map(|f| f.get_ref())
    }
}
