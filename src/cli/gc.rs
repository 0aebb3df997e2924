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

/// Parses an age like `0`, `90s`, `30m`, `2h` or `1d`.
pub(super) fn parse_age(s: &str) -> Result<std::time::Duration, String> {
    let s = s.trim();
    let (num, unit) = match s.char_indices().last() {
        Some((i, c)) if c.is_ascii_alphabetic() => (&s[..i], c),
        _ => (s, 's'),
    };
    let mult = match unit {
        's' => 1.0,
        'm' => 60.0,
        'h' => 3600.0,
        'd' => 86400.0,
        _ => return Err(format!("`{s}`: give an age like 0, 90s, 30m, 2h or 1d")),
    };
    let v: f64 = num.parse().map_err(|_| format!("`{s}`: give an age like 0, 90s, 30m, 2h or 1d"))?;
    if !(v.is_finite() && v >= 0.0 && v * mult < 1e12) {
        return Err(format!("`{s}` is not an age"));
    }
    Ok(std::time::Duration::from_secs_f64(v * mult))
}

pub fn run(
    manifests: &[PathBuf],
    max_size: Option<u64>,
    min_age: Option<std::time::Duration>,
    cache: Option<PathBuf>,
    ui: Ui,
) -> anyhow::Result<ExitCode> {
    let mut loaded = Vec::new();
    for p in manifests {
        let Some(m) = load_manifest(p, ui) else { return Ok(ExitCode::from(EXIT_INVALID)) };
        loaded.push(m);
    }
    let cache = cache.unwrap_or_else(|| loaded.first().map_or_else(|| PathBuf::from("cache"), cache_dir));
    if loaded.is_empty() && max_size.is_none() {
        anyhow::bail!("nothing to do: give --keep MANIFEST… and/or --max-size");
    }
    let age = min_age.unwrap_or(crate::cache::gc::GRACE);
    let c = build::collect_garbage(&loaded, &cache, max_size, age)?;
    println!(
        "{}: removed {} files ({}), {} left",
        cache.display(),
        c.files,
        super::human_bytes(c.bytes),
        super::human_bytes(c.left)
    );
    if c.young > 0 {
        println!(
            "kept {} file(s) it would have removed, younger than {} s (a build may still be writing them): \
             --min-age 0 removes them too",
            c.young,
            age.as_secs()
        );
    }
    Ok(ExitCode::SUCCESS)
}
