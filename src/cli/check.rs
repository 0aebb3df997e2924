//! `vvgen check`: validate manifests and print every diagnostic.

use std::path::PathBuf;
use std::process::ExitCode;

use super::{Ui, EXIT_INVALID};
use crate::manifest::{self, consumers};
use crate::plan::Plan;
use crate::scene;

/// Checks each manifest; exit 2 if any has an error.
pub fn run(paths: &[PathBuf], ui: Ui) -> anyhow::Result<ExitCode> {
    let mut invalid = 0;
    for path in paths {
        match manifest::load(path) {
            Ok((m, mut report)) => {
                // What the inputs decide, as the build would find it: each source loads (a malformed file is
                // an error here, not mid-build), the planner places every camera of every split, and the frame
                // count meets the consumers' limits.
                let planned = if m.reads_produced_inputs() {
                    // Its `after` manifests write its inputs: `build` plans it once they exist.
                    Ok((0, None))
                } else {
                    scene::frame_count(&m)
                        .map_err(anyhow::Error::from)
                        .and_then(|frames| Ok((frames, Some(Plan::new(&m, frames)?))))
                };
                match planned {
                    Ok((frames, Some(_))) => report.diagnostics.extend(consumers::frame_diagnostics(&m, frames)),
                    Ok((_, None)) => {}
                    Err(e) => {
                        invalid += 1;
                        eprint!("{}", report.render(ui.color));
                        eprintln!("error: {}: {e:#}", path.display());
                        continue;
                    }
                }
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
