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
