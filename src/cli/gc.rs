//! `vvgen gc`: cache garbage collection.

use std::path::PathBuf;
use std::process::ExitCode;

use super::{cache_dir, load_manifest, Ui, EXIT_INVALID};
use crate::build;

/// Parses a size like `500M`, `20G` or `1048576`.
pub(super) fn parse_size(s: &str) -> Result<u64, String> {
    let s = s.trim();
    let (num, mult) = match s.chars().last() {
        Some('K' | 'k') => (&s[..s.len() - 1], 1u64 << 10),
        Some('M' | 'm') => (&s[..s.len() - 1], 1 << 20),
        Some('G' | 'g') => (&s[..s.len() - 1], 1 << 30),
        Some('T' | 't') => (&s[..s.len() - 1], 1 << 40),
        _ => (s, 1),
    };
    let v: f64 = num.parse().map_err(|_| format!("`{s}` is not a size (e.g. 500M, 20G)"))?;
    if !(v.is_finite() && v >= 0.0) {
        return Err(format!("`{s}` is not a size"));
    }
    Ok((v * mult as f64) as u64)
}

pub fn run(manifests: &[PathBuf], max_size: Option<u64>, cache: Option<PathBuf>, ui: Ui) -> anyhow::Result<ExitCode> {
    let mut loaded = Vec::new();
    for p in manifests {
        let Some(m) = load_manifest(p, ui) else { return Ok(ExitCode::from(EXIT_INVALID)) };
        loaded.push(m);
    }
    let cache = cache.unwrap_or_else(|| loaded.first().map_or_else(|| PathBuf::from("cache"), cache_dir));
    if loaded.is_empty() && max_size.is_none() {
        anyhow::bail!("nothing to do: give --keep MANIFEST… and/or --max-size");
    }
    let c = build::collect_garbage(&loaded, &cache, max_size)?;
    println!(
        "{}: removed {} files ({:.1} MB), {:.1} MB left",
        cache.display(),
        c.files,
        c.bytes as f64 / 1e6,
        c.left as f64 / 1e6
    );
    Ok(ExitCode::SUCCESS)
}
