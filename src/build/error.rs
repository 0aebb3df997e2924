//! The build's error: one enum wrapping each stage's, with the manifest (and output) it concerns, sources
//! chained. [`Error::exit_code`] is where the CLI's 2 (bad input) and 1 (failure) are decided.

use std::path::PathBuf;

use crate::manifest::{Manifest, Report};
use crate::{cache, execute, export, plan, scene};

/// What can go wrong in a build, `status`, `release` or `gc`.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// The manifest is invalid (every problem, with its place, is in the report).
    #[error("{} is invalid ({} error(s))", .0.path.display(), .0.error_count())]
    Manifest(Box<Report>),
    /// A source cannot be opened or posed.
    #[error("{}{hint}", manifest.display())]
    Scene {
        /// The manifest.
        manifest: PathBuf,
        /// Why.
        #[source]
        source: Box<scene::Error>,
        /// A hint for the user, or empty.
        hint: &'static str,
    },
    /// The build cannot be planned.
    #[error("{}", manifest.display())]
    Plan {
        /// The manifest.
        manifest: PathBuf,
        /// Why.
        #[source]
        source: Box<plan::Error>,
    },
    /// An action failed.
    #[error("{}", manifest.display())]
    Execute {
        /// The manifest.
        manifest: PathBuf,
        /// Why.
        #[source]
        source: Box<execute::Error>,
    },
    /// Writing an output failed.
    #[error("{}: output `{output}`", manifest.display())]
    Export {
        /// The manifest.
        manifest: PathBuf,
        /// The output.
        output: String,
        /// Why.
        #[source]
        source: Box<export::Error>,
    },
    /// The cache cannot be read or written.
    #[error("{}: cache", manifest.display())]
    Cache {
        /// The manifest.
        manifest: PathBuf,
        /// Why.
        #[source]
        source: Box<cache::Error>,
    },
    /// A `[dataset] after` manifest failed.
    #[error("`after` manifest {}", manifest.display())]
    After {
        /// The `after` manifest.
        manifest: PathBuf,
        /// Why.
        #[source]
        source: Box<Error>,
    },
    /// The build would render more images than allowed (`--yes` to go ahead).
    #[error("{}: this build would render {images} images, more than {max}: check the view and frame counts (`vvgen plan` lists them), then run again with --yes", manifest.display())]
    TooMuchWork {
        /// The manifest.
        manifest: PathBuf,
        /// Images it would render.
        images: usize,
        /// The limit.
        max: usize,
    },
    /// A dataset file does not hold what the build placed there (changed on disk with its metadata intact, as
    /// bit rot does): `release` will not certify it.
    #[error("{}: does not hold what the build wrote (damaged on disk); it and its cache blob were removed: run `vvgen build`, then `vvgen release` again", path.display())]
    Damaged {
        /// The file.
        path: PathBuf,
    },
    /// Warnings were found and they are errors here: nothing was rendered.
    #[error(
        "{}: {} warning(s), and warnings are errors here (`[dataset] strict` or --deny-warnings):\n  {}",
        manifest.display(),
        warnings.len(),
        warnings.join("\n  ")
    )]
    Warnings {
        /// The manifest.
        manifest: PathBuf,
        /// What was found.
        warnings: Vec<String>,
    },
    /// `release` refuses: actions are not built.
    #[error("{pending} action(s) are not built: run `vvgen build` first (`vvgen plan --explain` says why)")]
    NotBuilt {
        /// Actions that would run.
        pending: usize,
    },
}

impl Error {
    pub(crate) fn plan(m: &Manifest, source: plan::Error) -> Error {
        Error::Plan { manifest: m.path.clone(), source: Box::new(source) }
    }

    pub(crate) fn cache(m: &Manifest, source: cache::Error) -> Error {
        Error::Cache { manifest: m.path.clone(), source: Box::new(source) }
    }

    /// Whether the error is the input's fault (the manifest, a source file): the user must change something.
    pub fn is_bad_input(&self) -> bool {
        match self {
            Error::Manifest(_)
            | Error::Scene { .. }
            | Error::Plan { .. }
            | Error::TooMuchWork { .. }
            | Error::Warnings { .. } => true,
            Error::Execute { source, .. } => match &**source {
                execute::Error::Scene { .. } | execute::Error::Content { .. } => true,
                execute::Error::Sample { source, .. } => matches!(source, crate::sample::Error::TopologyChanged),
                execute::Error::Video { source, .. } => matches!(source, execute::video::Error::TooLarge { .. }),
                // A map that does not decode is the input's fault; a damaged prefiltered blob the cache's.
                execute::Error::Environment { source, .. } => {
                    !matches!(source, crate::render::light::environment::Error::Damaged(_))
                }
                execute::Error::Cache { .. } | execute::Error::Preview { .. } | execute::Error::Interrupted { .. } => {
                    false
                }
            },
            Error::Export { source, .. } => {
                matches!(**source, export::Error::Pattern(_) | export::Error::EmptyScene | export::Error::NonFinite(_))
            }
            Error::After { source, .. } => source.is_bad_input(),
            Error::Cache { .. } | Error::NotBuilt { .. } | Error::Damaged { .. } => false,
        }
    }

    /// The process exit code for this error: 2 for bad input, 1 for any other failure.
    pub fn exit_code(&self) -> u8 {
        if self.is_bad_input() {
            2
        } else {
            1
        }
    }
}
