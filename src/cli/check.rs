//! `vvgen check`: validate manifests and print every diagnostic.

use std::path::PathBuf;
use std::process::ExitCode;

use super::{Ui, EXIT_INVALID};
use crate::manifest::{consumers, Diagnostic};
use crate::plan::{coverage, Plan};
use crate::scene;

/// Checks each manifest; exit 2 if any has an error.
pub fn run(paths: &[PathBuf], deny_warnings: bool, ui: Ui) -> anyhow::Result<ExitCode> {
    let mut invalid = 0;
    for path in paths {
        match crate::settings::load(path) {
            Ok((m, mut report)) => {
                // What the inputs decide, as the build would find it: each source loads (a malformed file is
                // an error here, not mid-build), the planner places every camera of every split, and the frame
                // count meets the consumers' limits.
                let planned = if m.reads_produced_inputs() {
                    // Its `after` manifests write its inputs: `build` plans it once they exist.
                    Ok((0, None))
                } else {
                    super::open_scene(&m, ui).and_then(|scene| {
                        // The scene as the build opens it (transforms resolved, a frame fit sized), so the
                        // framing of every planned image is measured here too; and every frame file checked.
                        scene.check_frame_files()?;
                        let frames = scene.frames;
                        let plan = Plan::new(&m, frames)?;
                        // What the build would refuse before planning an action.
                        crate::plan::graph::refusals(&m, &scene, &plan)?;
                        let crops = coverage::measure(&m, &scene, &plan, None)?;
                        let mut warnings = scene.warnings.clone();
                        warnings.extend(plan.warnings.iter().cloned());
                        warnings.extend(coverage::warnings(&m, &plan, &crops));
                        warnings.extend(coverage::misread_warnings(&m, &plan, &crops));
                        warnings.extend(coverage::small_warnings(&m, &plan, &crops));
                        // The consumers' frame-count limits, on the frames each output's splits select.
                        let mut diags = Vec::new();
                        for (name, out) in &m.outputs {
                            diags.extend(consumers::frame_diagnostic(name, out, plan.output_frames(out)?));
                        }
                        diags.extend(warnings.into_iter().map(|w| Diagnostic::warning(w, None)));
                        Ok((frames, Some(diags)))
                    })
                };
                match planned {
                    Ok((_, Some(diags))) => report.diagnostics.extend(diags),
                    Ok((_, None)) => {}
                    Err(e) => {
                        invalid += 1;
                        // A clip the file lacks is pointed at where the manifest names it.
                        let at = match e.downcast_ref::<scene::Error>() {
                            Some(scene::Error::Clip { name, message }) => {
                                m.sources.get(name).and_then(|s| s.animation_span()).map(|span| (span, message))
                            }
                            _ => None,
                        };
                        if let Some((span, message)) = at {
                            report.diagnostics.push(Diagnostic::error(message.clone(), Some(span)).with_help(
                                "name one of the file's clips (by name or index), a list of them, or \"all\"",
                            ));
                            eprint!("{}", report.render(ui.color));
                        } else {
                            eprint!("{}", report.render(ui.color));
                            eprintln!("error: {}: {e:#}", path.display());
                        }
                        continue;
                    }
                }
                let warned = report.diagnostics.len();
                if (deny_warnings || m.dataset.strict) && warned > 0 {
                    invalid += 1;
                    eprint!("{}", report.render(ui.color));
                    eprintln!(
                        "{}: {warned} warning(s), and warnings are errors here (`[dataset] strict` or --deny-warnings)",
                        path.display()
                    );
                    continue;
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
