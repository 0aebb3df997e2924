//! "Did you mean …?" for misspelt keys and names.

/// The candidate closest to `word`, if it is close enough to be a plausible typo.
///
/// Uses optimal string alignment distance (a transposition costs 1, so `veiws` → `views` is one edit) and
/// accepts at most a third of the word's length in edits (at least 1).
pub fn did_you_mean<'a>(word: &str, candidates: impl IntoIterator<Item = &'a str>) -> Option<&'a str> {
    let limit = (word.chars().count() / 3).max(1);
    candidates
        .into_iter()
        .map(|c| (strsim::osa_distance(&word.to_lowercase(), &c.to_lowercase()), c))
        .filter(|(d, _)| *d <= limit)
        .min_by_key(|(d, c)| (*d, *c))
        .map(|(_, c)| c)
}

/// Formats a list of names as `` `a`, `b` or `c` ``.
pub fn one_of(names: &[&str]) -> String {
    let quoted: Vec<String> = names.iter().map(|n| format!("`{n}`")).collect();
    match quoted.len() {
        0 => String::new(),
        1 => quoted[0].clone(),
        n => format!("{} or {}", quoted[..n - 1].join(", "), quoted[n - 1]),
    }
}

/// Reports keys of a table that its kind does not take (`kind = "orbit"` with `rings`, a writer's foreign
/// options). `tag` is the key that selects the kind; `owner` describes the table for the message.
pub fn inapplicable_keys(
    present: &[(&str, std::ops::Range<usize>)],
    tag: &str,
    allowed: &[&str],
    owner: &str,
    diags: &mut Vec<super::diag::Diagnostic>,
) {
    for (key, span) in present {
        if *key == tag || allowed.contains(key) {
            continue;
        }
        let help = match did_you_mean(key, allowed.iter().copied()) {
            Some(s) => format!("did you mean `{s}`?"),
            None => format!("it takes {}", one_of(allowed)),
        };
        diags.push(
            super::diag::Diagnostic::error(format!("key `{key}` does not apply to {owner}"), Some(span.clone()))
                .with_help(help),
        );
    }
}

/// "`what` `name`, which is not defined", with the nearest defined name as help.
pub fn undefined<'a>(
    message: String,
    name: &str,
    known: impl IntoIterator<Item = &'a str>,
    span: std::ops::Range<usize>,
) -> super::diag::Diagnostic {
    let d = super::diag::Diagnostic::error(message, Some(span));
    match did_you_mean(name, known) {
        Some(x) => d.with_help(format!("did you mean `{x}`?")),
        None => d,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn transposition_is_found() {
        assert_eq!(did_you_mean("veiws", ["rig", "views", "time"]), Some("views"));
        assert_eq!(did_you_mean("resolutoin", ["resolution", "samples"]), Some("resolution"));
    }

    #[test]
    fn far_words_are_not_suggested() {
        assert_eq!(did_you_mean("colour", ["rig", "views", "time"]), None);
    }

    #[test]
    fn lists_read_naturally() {
        assert_eq!(one_of(&["a", "b", "c"]), "`a`, `b` or `c`");
    }
}
