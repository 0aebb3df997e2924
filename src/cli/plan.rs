//! `vvgen plan` and `vvgen status`: what a build would do, without doing it.

use std::path::Path;
use std::process::ExitCode;

use super::{cache_choice, cache_dir, load_manifest, Ui, EXIT_INVALID};
use crate::build::{self, State};

pub fn run(manifest: &Path, explain: bool, json: bool, verify: bool, ui: Ui) -> anyhow::Result<ExitCode> {
    let Some(m) = load_manifest(manifest, ui) else { return Ok(ExitCode::from(EXIT_INVALID)) };
    let t = std::time::Instant::now();
    let st = build::status_noting(&m, &cache_dir(&m), explain || json, verify, Some(&importing(ui)))?;
    if json {
        println!("{}", serde_json::to_string_pretty(&st)?);
        return Ok(ExitCode::SUCCESS);
    }
    for (kind, k) in &st.kinds {
        let unneeded = if k.unneeded > 0 { format!(", {} not needed", k.unneeded) } else { String::new() };
        println!("{:<14} {:>6} planned: {} cached, {} to run{unneeded}", kind.name(), k.planned, k.cached, k.run);
    }
    println!(
        "{}  (planned in {:.0} ms)",
        if st.up_to_date() { "nothing to do" } else { "work to do" },
        t.elapsed().as_secs_f64() * 1000.0
    );
    if st.images_to_render > 0 {
        println!(
            "{} images to render, at most {} uncompressed",
            st.images_to_render,
            super::human_bytes(st.bytes_upper_bound)
        );
    }
    if let Some(s) = st.seconds_estimate {
        let left_out: Vec<&str> = st.not_estimated.iter().map(|k| k.name()).collect();
        let besides = if left_out.is_empty() {
            String::new()
        } else {
            format!(", besides {} (not timed here yet)", left_out.join(", "))
        };
        println!("about {s:.1} s at the rates the last builds here measured{besides}");
    }
    if explain {
        for a in st.actions.iter().filter(|a| a.state == State::Run) {
            println!("  {}: {}", a.label, a.reasons.join("; "));
        }
    }
    Ok(ExitCode::SUCCESS)
}

pub fn status(manifest: &Path, verify: bool, ui: Ui) -> anyhow::Result<ExitCode> {
    let Some(m) = load_manifest(manifest, ui) else { return Ok(ExitCode::from(EXIT_INVALID)) };
    let (cache, why) = cache_choice(&m);
    let st = build::status_noting(&m, &cache, false, verify, Some(&importing(ui)))?;
    let total: usize = st.kinds.values().map(|k| k.planned).sum();
    let done: usize = st.kinds.values().map(|k| k.cached).sum();
    println!(
        "{}: {done} of {total} actions built{}",
        m.dataset.name(),
        if st.up_to_date() { " (up to date)" } else { "" }
    );
    for (kind, k) in st.kinds.iter().filter(|(_, k)| k.run > 0) {
        println!("  {}: {} to run", kind.name(), k.run);
    }
    if !st.up_to_date() {
        println!("  `vvgen plan --explain` says why");
    }
    for a in st.actions.iter().filter(|a| a.state == State::Run && !a.reasons.is_empty()) {
        println!("  {}: {}", a.label, a.reasons.join("; "));
    }
    let (files, bytes) = dir_size(&cache);
    println!("cache {} ({why}): {files} files, {}", cache.display(), super::human_bytes(bytes));
    Ok(ExitCode::SUCCESS)
}

fn dir_size(p: &Path) -> (u64, u64) {
    let (mut n, mut b) = (0, 0);
    if let Ok(entries) = std::fs::read_dir(p) {
        for e in entries.flatten() {
            match e.metadata() {
                Ok(m) if m.is_dir() => {
                    let (n2, b2) = dir_size(&e.path());
                    n += n2;
                    b += b2;
                }
                Ok(m) => {
                    n += 1;
                    b += m.len();
                }
                Err(_) => {}
            }
        }
    }
    (n, b)
}

/// What `plan` and `status` say while a `.blend` imports before they can count anything (`build` says it too).
fn importing(ui: Ui) -> impl Fn(&str) + Sync {
    move |what: &str| {
        if !ui.quiet {
            eprintln!("{what}");
        }
    }
}
