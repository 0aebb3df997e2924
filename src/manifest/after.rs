//! `[dataset] after`: manifests built before this one. The one use that needs it is the round trip: a
//! manifest renders, as a `ply_sequence` source, the point-cloud sequence another manifest writes. Checking
//! such a manifest on a fresh clone must not fail because that sequence is not built yet, so the files a
//! prerequisite *will* write count as present; a typo in the path still fails, since it then matches no
//! prerequisite's output.

use std::path::{Component, Path, PathBuf};

use super::output::Writer;
use super::{parse_with, Manifest};

/// Deepest chain of prerequisites (a guard against pathological nesting; cycles are reported as such).
const MAX_DEPTH: usize = 16;

/// Loads prerequisite `rel` (relative to `dir`). `stack` holds the manifests being loaded, outermost first,
/// so a cycle is named rather than followed.
pub(crate) fn load(dir: &Path, rel: &str, stack: &mut Vec<PathBuf>) -> Result<Manifest, String> {
    let path = dir.join(rel);
    let text = std::fs::read_to_string(&path).map_err(|e| format!("cannot read `{}`: {e}", path.display()))?;
    let id = identity(&path);
    if let Some(i) = stack.iter().position(|p| *p == id) {
        let chain: Vec<String> = stack[i..].iter().chain([&id]).map(|p| p.display().to_string()).collect();
        return Err(format!("`after` cycle: {}", chain.join(" → ")));
    }
    if stack.len() >= MAX_DEPTH {
        return Err(format!("more than {MAX_DEPTH} nested `after` manifests"));
    }
    stack.push(id);
    let result = parse_with(&text, &path, stack);
    stack.pop();
    result.map(|(m, _)| m).map_err(|report| {
        let n = report.error_count();
        let first = report.diagnostics.iter().find(|d| d.is_error()).map_or(String::new(), |d| {
            let at = d.span.as_ref().map_or(String::new(), |s| {
                let (line, col) = report.line_col(s.start);
                format!(":{line}:{col}")
            });
            format!("; first: {}{at}: {}", path.display(), d.message)
        });
        format!("`{}` has {n} error(s){first}", path.display())
    })
}

/// How a manifest is recognized on the `after` stack: its canonical path when it exists.
pub(crate) fn identity(path: &Path) -> PathBuf {
    std::fs::canonicalize(path).unwrap_or_else(|_| lexical(path))
}

/// The file patterns (`{frame}` left in) of every `ply-sequence` output of `after` and of their own
/// prerequisites, as normalized absolute paths.
pub(crate) fn produced_sequences(after: &[Manifest]) -> Vec<PathBuf> {
    let mut out = Vec::new();
    for m in after {
        let name = m.dataset.name.get_ref();
        for o in m.outputs.values().filter(|o| *o.writer.get_ref() == Writer::PlySequence) {
            out.push(lexical(&m.out_dir().join(o.dir_name(name)).join(o.file_pattern(name))));
        }
        out.extend(produced_sequences(&m.after));
    }
    out
}

/// `p` made absolute with `.` and `..` folded away, without touching the file system (the files may not
/// exist yet).
pub(crate) fn lexical(p: &Path) -> PathBuf {
    let abs = std::path::absolute(p).unwrap_or_else(|_| p.to_path_buf());
    let mut out = PathBuf::new();
    for c in abs.components() {
        match c {
            Component::CurDir => {}
            Component::ParentDir => {
                out.pop();
            }
            c => out.push(c),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lexical_folds_dots() {
        assert_eq!(lexical(Path::new("/a/b/../c/./d.ply")), PathBuf::from("/a/c/d.ply"));
    }
}
