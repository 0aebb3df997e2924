//! `vvgen release` and `vvgen verify`.

use std::path::Path;
use std::process::ExitCode;

use super::{cache_dir, load_manifest, Ui, EXIT_INVALID};
use crate::release as rel;

pub fn release(manifest: &Path, ui: Ui) -> anyhow::Result<ExitCode> {
    let Some(m) = load_manifest(manifest, ui) else { return Ok(ExitCode::from(EXIT_INVALID)) };
    for r in rel::release(&m, &cache_dir(&m))? {
        println!("{}", r.join(rel::LOCK).display());
    }
    Ok(ExitCode::SUCCESS)
}

pub fn verify(dir: &Path, _ui: Ui) -> anyhow::Result<ExitCode> {
    let v = rel::verify(dir)?;
    for f in &v.missing {
        println!("missing  {f}");
    }
    for f in &v.modified {
        println!("modified {f}");
    }
    for f in &v.extra {
        println!("extra    {f}");
    }
    if v.ok() {
        println!("{}: {} files match vvgen.lock", dir.display(), v.checked);
        Ok(ExitCode::SUCCESS)
    } else {
        println!(
            "{}: {} missing, {} modified, {} extra",
            dir.display(),
            v.missing.len(),
            v.modified.len(),
            v.extra.len()
        );
        Ok(ExitCode::FAILURE)
    }
}
