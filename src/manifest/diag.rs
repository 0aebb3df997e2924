//! Diagnostics: one problem in a manifest, with where it is and how to fix it.
//!
//! A [`Diagnostic`] holds a byte span into the manifest text; [`Report`] renders every diagnostic of a file as
//! `file:line:column` plus a caret snippet (annotate-snippets), plain or coloured.

use std::fmt::Write as _;
use std::ops::Range;
use std::path::{Path, PathBuf};

/// How bad a diagnostic is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Severity {
    /// The manifest cannot be used.
    Error,
    /// The manifest works, but something is probably not what the user wants.
    Warning,
}

/// One problem found in a manifest.
#[derive(Debug, Clone, PartialEq)]
pub struct Diagnostic {
    /// Error or warning.
    pub severity: Severity,
    /// What is wrong, in one line.
    pub message: String,
    /// Byte range in the manifest text, when the problem has a place.
    pub span: Option<Range<usize>>,
    /// How to fix it (shown as `help: …`).
    pub help: Option<String>,
}

impl Diagnostic {
    /// An error at `span`.
    pub fn error(message: impl Into<String>, span: Option<Range<usize>>) -> Self {
        Diagnostic { severity: Severity::Error, message: message.into(), span, help: None }
    }

    /// A warning at `span`.
    pub fn warning(message: impl Into<String>, span: Option<Range<usize>>) -> Self {
        Diagnostic { severity: Severity::Warning, message: message.into(), span, help: None }
    }

    /// Adds a `help:` line.
    pub fn with_help(mut self, help: impl Into<String>) -> Self {
        self.help = Some(help.into());
        self
    }

    /// Whether this diagnostic makes the manifest unusable.
    pub fn is_error(&self) -> bool {
        self.severity == Severity::Error
    }
}

/// The diagnostics of one manifest file, with the text they point into.
#[derive(Debug, Clone)]
pub struct Report {
    /// The manifest file.
    pub path: PathBuf,
    /// Its text.
    pub source: String,
    /// Everything found, in the order found.
    pub diagnostics: Vec<Diagnostic>,
}

impl Report {
    /// Number of errors (warnings excluded).
    pub fn error_count(&self) -> usize {
        self.diagnostics.iter().filter(|d| d.is_error()).count()
    }

    /// 1-based (line, column) of a byte offset; columns count characters.
    pub fn line_col(&self, offset: usize) -> (usize, usize) {
        line_col(&self.source, offset)
    }

    /// Renders every diagnostic; `color` selects ANSI styling.
    pub fn render(&self, color: bool) -> String {
        let mut out = String::new();
        for d in &self.diagnostics {
            out.push_str(&render_one(&self.path, &self.source, d, color));
            out.push('\n');
        }
        let errors = self.error_count();
        let warnings = self.diagnostics.len() - errors;
        if errors > 0 {
            let _ = writeln!(
                out,
                "{}: {} error{}{}",
                self.path.display(),
                errors,
                if errors == 1 { "" } else { "s" },
                if warnings > 0 { format!(", {warnings} warning(s)") } else { String::new() }
            );
        }
        out
    }
}

/// 1-based (line, column) of a byte offset in `src`.
pub fn line_col(src: &str, offset: usize) -> (usize, usize) {
    let offset = offset.min(src.len());
    let before = &src[..floor_char_boundary(src, offset)];
    let line = before.matches('\n').count() + 1;
    let col = before.rsplit('\n').next().map(|s| s.chars().count()).unwrap_or(0) + 1;
    (line, col)
}

fn floor_char_boundary(s: &str, mut i: usize) -> usize {
    while i > 0 && !s.is_char_boundary(i) {
        i -= 1;
    }
    i
}

fn render_one(path: &Path, src: &str, d: &Diagnostic, color: bool) -> String {
    use annotate_snippets::{Level, Renderer, Snippet};
    let level = match d.severity {
        Severity::Error => Level::Error,
        Severity::Warning => Level::Warning,
    };
    // annotate-snippets appends `:line:column` to the origin itself.
    let origin = path.display().to_string();
    let renderer = if color { Renderer::styled() } else { Renderer::plain() };
    let help = d.help.clone().unwrap_or_default();
    let mut msg = level.title(&d.message);
    if let Some(span) = &d.span {
        // An empty span (end of file) still needs one character to point at.
        let mut span = span.clone();
        if span.is_empty() {
            span.end = (span.start + 1).min(src.len());
            if span.is_empty() && span.start > 0 {
                span.start -= 1;
            }
        }
        msg = msg.snippet(Snippet::source(src).line_start(1).origin(&origin).fold(true).annotation(level.span(span)));
    }
    if d.help.is_some() {
        msg = msg.footer(Level::Help.title(&help));
    }
    let text = renderer.render(msg).to_string();
    if d.span.is_some() {
        return text;
    }
    // No place in the text (a problem of the inputs, or of the whole file): name the file under the title, not
    // an empty `| |` frame.
    let (title, rest) = text.split_once('\n').unwrap_or((&text, ""));
    let sep = if rest.is_empty() { "" } else { "\n" };
    format!("{title}\n  --> {origin}{sep}{rest}")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn line_col_counts_from_one() {
        let s = "a = 1\nbb = 2\n";
        assert_eq!(line_col(s, 0), (1, 1));
        assert_eq!(line_col(s, 6), (2, 1));
        assert_eq!(line_col(s, 9), (2, 4));
    }
}
