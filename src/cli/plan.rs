//! `vvgen plan` and `vvgen status`: what a build would do, without doing it.

use std::path::Path;
use std::process::ExitCode;

use super::{load_manifest, Ui, EXIT_INVALID};
use crate::build;

pub fn run(manifest: &Path, explain: bool, json: bool, ui: Ui) -> anyhow::Result<ExitCode> {
    let Some(m) = load_manifest(manifest, ui) else { return Ok(ExitCode::from(EXIT_INVALID)) };
    let t = std::time::Instant::now();
    let st = build::status(&m, &build::cache_dir(&m)).map_err(anyhow::Error::msg)?;
    if json {
        println!("{}", serde_json::to_string_pretty(&st)?);
        return Ok(ExitCode::SUCCESS);
    }
    println!(
        "render: {} images: {} fresh, {} stale, {} new  (planned in {:.0} ms)",
        st.images,
        st.fresh,
        st.stale.len(),
        st.new.len(),
        t.elapsed().as_secs_f64() * 1000.0
    );
    if explain {
        for (id, why) in &st.stale {
            println!("  stale {id}: {}", why.join("; "));
        }
        if !st.new.is_empty() {
            println!("  new: {}", summarize(&st.new));
        }
    }
    for d in &st.damaged_outputs {
        println!("  output {d}");
    }
    Ok(ExitCode::SUCCESS)
}

/// The first few and a count.
fn summarize(ids: &[String]) -> String {
    let head: Vec<&str> = ids.iter().take(5).map(String::as_str).collect();
    if ids.len() > head.len() {
        format!("{} … ({} in all)", head.join(", "), ids.len())
    } else {
        head.join(", ")
    }
}

pub fn status(manifest: &Path, ui: Ui) -> anyhow::Result<ExitCode> {
    let Some(m) = load_manifest(manifest, ui) else { return Ok(ExitCode::from(EXIT_INVALID)) };
    let cache = build::cache_dir(&m);
    let st = build::status(&m, &cache).map_err(anyhow::Error::msg)?;
    let built = st.stale.is_empty() && st.new.is_empty() && st.damaged_outputs.is_empty();
    println!(
        "{}: {} of {} images built{}",
        m.dataset.name.get_ref(),
        st.fresh,
        st.images,
        if built { " (up to date)" } else { "" }
    );
    if !st.stale.is_empty() || !st.new.is_empty() {
        println!("  {} stale, {} new: `vvgen plan --explain` says why", st.stale.len(), st.new.len());
    }
    for d in &st.damaged_outputs {
        println!("  output {d}");
    }
    let (files, bytes) = dir_size(&cache);
    println!("cache {}: {files} files, {:.1} MB", cache.display(), bytes as f64 / 1e6);
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
