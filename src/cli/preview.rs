//! `vvgen preview`: a build with previews on (whatever `[dataset] preview` says), then, with `--out`, a copy
//! of each output's `preview/` elsewhere (a shared folder, a laptop), its viewer pointed at the dataset.

use std::path::Path;
use std::process::ExitCode;

use anyhow::Context;

use super::{build::build_and_report, load_manifest, Ui, EXIT_INVALID};
use crate::preview::{viewer, DIR};

pub fn run(manifest: &Path, out: Option<&Path>, jobs: Option<usize>, ui: Ui) -> anyhow::Result<ExitCode> {
    let Some(mut m) = load_manifest(manifest, ui) else { return Ok(ExitCode::from(EXIT_INVALID)) };
    m.dataset.preview = true;
    let report = build_and_report(&m, jobs, Default::default(), ui)?;
    let Some(out) = out else { return Ok(ExitCode::SUCCESS) };
    for (name, w) in report.after.iter().chain(&report.outputs) {
        // `after` outputs are named `file.toml/output`: one folder per output either way.
        let dest = out.join(name.replace('/', "_"));
        let prefix = format!("{DIR}/");
        for (rel, _) in w.files.iter().filter(|(f, _)| f.starts_with(&prefix)) {
            let (src, to) = (w.root.join(rel), dest.join(&rel[prefix.len()..]));
            let mut bytes = std::fs::read(&src).with_context(|| format!("reading {}", src.display()))?;
            if rel.ends_with("index.html") {
                // The copy links the dataset's images where they are, not beside it.
                let root = std::fs::canonicalize(&w.root).unwrap_or_else(|_| w.root.clone());
                let page = String::from_utf8_lossy(&bytes);
                bytes = viewer::relocate(&page, &root.to_string_lossy()).into_bytes();
            }
            if let Some(dir) = to.parent() {
                std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
            }
            crate::atomic::write(&to, &bytes).with_context(|| format!("writing {}", to.display()))?;
        }
        if !ui.quiet {
            eprintln!("{name}: preview copied to {}", dest.display());
        }
    }
    Ok(ExitCode::SUCCESS)
}
