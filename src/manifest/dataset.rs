//! `[dataset]`: name, version, output root, seed, cache location.

use serde::Deserialize;
use toml::Spanned;

use super::diag::Diagnostic;

/// The `[dataset]` table.
#[derive(Debug, Clone, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Dataset {
    /// Dataset name; used in default output directory names.
    #[schemars(with = "String")]
    pub(super) name: Spanned<String>,
    /// Free-form version string, recorded in metadata.
    #[serde(default)]
    pub version: Option<String>,
    /// Output root, relative to the manifest's directory.
    #[schemars(with = "String")]
    pub(super) out: Spanned<String>,
    /// Root of every random stream (camera draws, point samples).
    #[serde(default)]
    pub seed: u64,
    /// Every warning is an error: `check` exits 2 and `build` stops before rendering (as `--deny-warnings`).
    #[serde(default)]
    pub strict: bool,
    /// Cache directory, relative to the manifest (default `cache/` beside the manifest, wherever the command
    /// runs; `VVGEN_CACHE` overrides both).
    #[serde(default)]
    #[schemars(with = "Option<String>")]
    pub(super) cache: Option<Spanned<String>>,
    /// Manifests (manifest-relative) that `vvgen build` builds before this one, e.g. the one writing the
    /// point-cloud sequence a `ply_sequence` source here renders.
    #[serde(default)]
    #[schemars(with = "Vec<String>")]
    pub(super) after: Vec<Spanned<String>>,
    /// Write a preview beside each dataset (`preview/`: contact sheets, rig plot, point-cloud strip, HTML viewer);
    /// `vvgen build --no-preview` turns it off for one build.
    #[serde(default = "yes")]
    pub preview: bool,
}

fn yes() -> bool {
    true
}

impl Dataset {
    pub(crate) fn validate(&self, diags: &mut Vec<Diagnostic>) {
        let name = self.name.get_ref();
        if !super::is_plain_name(name) {
            diags.push(
                Diagnostic::error(format!("dataset name `{name}` is not a plain file name"), Some(self.name.span()))
                    .with_help("use letters, digits, `-`, `_` and `.` only (not dots alone); it names output folders"),
            );
        }
        if self.out.get_ref().trim().is_empty() {
            diags.push(
                Diagnostic::error("`out` is empty", Some(self.out.span())).with_help("e.g. out = \"out/my-dataset\""),
            );
        }
    }
}

/// Plain values of the fields whose spans stay inside `manifest` (for diagnostics).
impl Dataset {
    /// The dataset's name.
    pub fn name(&self) -> &str {
        self.name.get_ref()
    }

    /// The output root, manifest-relative.
    pub fn out(&self) -> &str {
        self.out.get_ref()
    }

    /// The cache directory, manifest-relative, when given.
    pub fn cache(&self) -> Option<&str> {
        self.cache.as_ref().map(|c| c.get_ref().as_str())
    }

    /// The `after` manifests, manifest-relative.
    pub fn after(&self) -> Vec<&str> {
        self.after.iter().map(|a| a.get_ref().as_str()).collect()
    }
}
