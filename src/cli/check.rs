//! `vvgen check`: validate manifests and print every diagnostic.

use std::path::PathBuf;
use std::process::ExitCode;

use super::{Ui, EXIT_INVALID};
use crate::manifest;

/// Checks each manifest; exit 2 if any has an error.
pub fn run(paths: &[PathBuf], ui: Ui) -> anyhow::Result<ExitCode> {
    let mut invalid = 0;
    for path in paths {
        match manifest::load(path) {
            Ok((m, report)) => {
                if !ui.quiet {
                    eprint!("{}", report.render(ui.color));
                    println!(
                        "{}: ok ({} source{}, {} rig{}, {} split{}, {} output{})",
                        path.display(),
                        m.sources.len(),
                        plural(m.sources.len()),
                        m.rigs.len(),
                        plural(m.rigs.len()),
                        m.splits.len(),
                        plural(m.splits.len()),
                        m.outputs.len(),
                        plural(m.outputs.len())
                    );
                }
            }
            Err(report) => {
                invalid += 1;
                eprint!("{}", report.render(ui.color));
            }
        }
    }
    Ok(if invalid > 0 { ExitCode::from(EXIT_INVALID) } else { ExitCode::SUCCESS })
}

fn plural(n: usize) -> &'static str {
    if n == 1 {
        ""
    } else {
        "s"
    }
}
