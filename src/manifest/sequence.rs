//! Resolving a `ply_sequence` string (a `{frame}` pattern or a glob) to the list of frame files.
//!
//! This is the one place in `manifest` that looks at the file system: checking a manifest means checking
//! that its inputs exist.

use std::path::{Path, PathBuf};

use super::frames::{Frames, MAX_FRAMES};
use super::source::is_pattern;

/// One frame of a sequence: its number (pattern) or position (glob), and its file.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SequenceFrame {
    /// Frame number substituted into the pattern, or position in the sorted glob.
    pub number: i64,
    /// The file.
    pub path: PathBuf,
}

/// Why a sequence's frames cannot be listed.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum Error {
    /// The `{frame}` pattern is malformed.
    #[error("`{pattern}`: {why}")]
    Pattern {
        /// The pattern.
        pattern: String,
        /// What is wrong.
        why: &'static str,
    },
    /// The frame range is empty.
    #[error("empty frame range {start}..={end}")]
    EmptyRange {
        /// First frame.
        start: i64,
        /// Last frame.
        end: i64,
    },
    /// More frames than a sequence may have.
    #[error("more than {MAX_FRAMES} frames")]
    TooMany,
    /// A frame's file does not exist.
    #[error("frame {frame} is missing: {}", path.display())]
    Missing {
        /// The frame number.
        frame: i64,
        /// The file that should hold it.
        path: PathBuf,
    },
    /// The glob is malformed.
    #[error("bad glob `{spec}`: {why}")]
    Glob {
        /// The glob.
        spec: String,
        /// What is wrong.
        why: String,
    },
    /// The glob matches no file.
    #[error("no file matches `{}`", pattern.display())]
    NoMatch {
        /// The glob, resolved.
        pattern: PathBuf,
    },
    /// Fewer files match than frames are asked for.
    #[error("frames up to position {last} requested, but only {found} files match `{spec}`")]
    TooFew {
        /// Last position asked for.
        last: i64,
        /// Files found.
        found: usize,
        /// The glob.
        spec: String,
    },
}

/// Substitutes `n` into a `{frame}` / `{frame:04}` pattern.
pub fn format_frame(pattern: &str, n: i64) -> Result<String, Error> {
    let bad = |why| Error::Pattern { pattern: pattern.to_string(), why };
    let start = pattern.find("{frame").ok_or_else(|| bad("has no {frame}"))?;
    let rest = &pattern[start + 6..];
    let close = rest.find('}').ok_or_else(|| bad("unclosed {frame"))?;
    let spec = &rest[..close];
    let width = if spec.is_empty() {
        0
    } else {
        let digits = spec
            .strip_prefix(":0")
            .or_else(|| spec.strip_prefix(':'))
            .ok_or_else(|| bad("expected {frame} or {frame:04}"))?;
        digits.parse::<usize>().map_err(|_| bad("expected {frame} or {frame:04}"))?.min(32)
    };
    let num = if n < 0 { format!("-{:0width$}", -n, width = width.saturating_sub(1)) } else { format!("{n:0width$}") };
    Ok(format!("{}{}{}", &pattern[..start], num, &rest[close + 1..]))
}

/// Lists the frames of a sequence, `dir`-relative, applying `frames`. Errors name the first missing file.
pub fn resolve(dir: &Path, spec: &str, frames: &Frames) -> Result<Vec<SequenceFrame>, Error> {
    let step = frames.step() as i64;
    if is_pattern(spec) {
        let start = frames.start.unwrap_or(0);
        let end = match (frames.end, frames.count) {
            (Some(e), _) => e,
            (None, Some(c)) => start + (c as i64 - 1) * step,
            (None, None) => return scan_pattern(dir, spec, start, step),
        };
        if end < start {
            return Err(Error::EmptyRange { start, end });
        }
        if ((end - start) / step) as u64 >= MAX_FRAMES {
            return Err(Error::TooMany);
        }
        let mut out = Vec::new();
        let mut n = start;
        while n <= end {
            let path = dir.join(format_frame(spec, n)?);
            if !path.is_file() {
                return Err(Error::Missing { frame: n, path });
            }
            out.push(SequenceFrame { number: n, path });
            n += step;
        }
        Ok(out)
    } else {
        let full = dir.join(spec);
        let pattern = full.to_string_lossy().to_string();
        // As a shell globs: a hidden file is matched only by a name that starts with its dot (the `._frame_0001.ply`
        // macOS writes beside every file it copies to another file system, 4 KB of metadata, would be a frame that
        // is no PLY). The crate's `require_literal_leading_dot` refuses them even then: their names are filtered.
        let hidden_asked = hidden(Path::new(spec));
        let mut paths: Vec<PathBuf> = glob::glob(&pattern)
            .map_err(|e| Error::Glob { spec: spec.to_string(), why: e.to_string() })?
            .filter_map(Result::ok)
            .filter(|p| p.is_file() && (hidden_asked || !hidden(p)))
            .collect();
        paths.sort_by(|a, b| natural_cmp(&a.to_string_lossy(), &b.to_string_lossy()));
        if paths.is_empty() {
            return Err(Error::NoMatch { pattern: full });
        }
        let first = frames.start.unwrap_or(0).max(0);
        let last = match (frames.end, frames.count) {
            (Some(e), _) => e,
            (None, Some(c)) => first + (c as i64 - 1) * step,
            (None, None) => paths.len() as i64 - 1,
        };
        if last >= paths.len() as i64 {
            return Err(Error::TooFew { last, found: paths.len(), spec: spec.to_string() });
        }
        Ok((first..=last)
            .step_by(step as usize)
            .map(|i| SequenceFrame { number: i, path: paths[i as usize].clone() })
            .collect())
    }
}

/// Whether the file at `p` is hidden (its name starts with a dot), as a shell's `*` leaves it out.
pub fn hidden(p: &Path) -> bool {
    p.file_name().is_some_and(|n| n.to_string_lossy().starts_with('.'))
}

/// With no end or count: consecutive numbers from `start` until the first missing file.
fn scan_pattern(dir: &Path, spec: &str, start: i64, step: i64) -> Result<Vec<SequenceFrame>, Error> {
    let mut out = Vec::new();
    let mut n = start;
    loop {
        let path = dir.join(format_frame(spec, n)?);
        if !path.is_file() {
            break;
        }
        out.push(SequenceFrame { number: n, path });
        if out.len() as u64 >= MAX_FRAMES {
            break;
        }
        n += step;
    }
    if out.is_empty() {
        return Err(Error::Missing { frame: start, path: dir.join(format_frame(spec, start)?) });
    }
    Ok(out)
}

/// Natural order: digit runs compare as numbers (`f2` < `f10`).
pub fn natural_cmp(a: &str, b: &str) -> std::cmp::Ordering {
    use std::cmp::Ordering;
    let (mut a, mut b) = (a.as_bytes(), b.as_bytes());
    while !a.is_empty() && !b.is_empty() {
        if a[0].is_ascii_digit() && b[0].is_ascii_digit() {
            let la = a.iter().take_while(|c| c.is_ascii_digit()).count();
            let lb = b.iter().take_while(|c| c.is_ascii_digit()).count();
            let (da, db) = (trim_zeros(&a[..la]), trim_zeros(&b[..lb]));
            let ord = da.len().cmp(&db.len()).then(da.cmp(db)).then(la.cmp(&lb));
            if ord != Ordering::Equal {
                return ord;
            }
            a = &a[la..];
            b = &b[lb..];
        } else {
            if a[0] != b[0] {
                return a[0].cmp(&b[0]);
            }
            a = &a[1..];
            b = &b[1..];
        }
    }
    a.len().cmp(&b.len())
}

fn trim_zeros(d: &[u8]) -> &[u8] {
    let z = d.iter().take_while(|&&c| c == b'0').count();
    &d[z.min(d.len().saturating_sub(1))..]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn patterns_pad() {
        assert_eq!(format_frame("loot_vox10_{frame:04}.ply", 7).unwrap(), "loot_vox10_0007.ply");
        assert_eq!(format_frame("f{frame}.ply", 1051).unwrap(), "f1051.ply");
        assert!(format_frame("f{frame:x}.ply", 1).is_err());
    }

    #[test]
    fn a_glob_leaves_hidden_files_out_as_a_shell_does() {
        // Frames copied from a Mac: each beside its `._` companion (AppleDouble metadata, no PLY).
        let d = tempfile::tempdir().unwrap();
        for f in ["f1.ply", "f2.ply", "._f1.ply", "._f2.ply", ".f3.ply"] {
            std::fs::write(d.path().join(f), b"ply").unwrap();
        }
        let names = |spec: &str| -> Vec<String> {
            let frames = resolve(d.path(), spec, &Frames::default()).unwrap();
            frames.iter().map(|f| f.path.file_name().unwrap().to_string_lossy().into_owned()).collect()
        };
        assert_eq!(names("*.ply"), ["f1.ply", "f2.ply"]);
        // Named with its dot, a hidden file is matched.
        assert_eq!(names(".f*.ply"), [".f3.ply"]);
    }

    #[test]
    fn natural_order() {
        let mut v = vec!["f10.ply", "f2.ply", "f1.ply", "f02.ply"];
        v.sort_by(|a, b| natural_cmp(a, b));
        assert_eq!(v, ["f1.ply", "f2.ply", "f02.ply", "f10.ply"]);
    }
}
