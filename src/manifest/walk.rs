//! Turning the spanned TOML tree into typed tables while collecting *every* error.
//!
//! serde stops at the first error of a value. To report all of them, each table entry is deserialized on its
//! own, and when an entry fails at a key, that key is removed and the entry is deserialized again (at most
//! [`MAX_RETRIES`] times), so one misspelt key does not hide the next. The raw tree keeps absolute byte spans,
//! so every error points into the manifest text.

use std::ops::Range;

use serde::de::DeserializeOwned;
use toml::de::{DeTable, DeValue, ValueDeserializer};
use toml::Spanned;

use super::diag::Diagnostic;
use super::suggest::{did_you_mean, one_of};

/// How many errors one table entry may report before the rest are left for the next run.
const MAX_RETRIES: usize = 16;

/// A raw spanned value of the manifest.
pub type Raw<'i> = Spanned<DeValue<'i>>;

/// Deserializes `value` into `T`, pushing one diagnostic per problem.
///
/// After an error the offending key is dropped and the rest deserialized again, so the value returned may
/// lack keys that were in error (their defaults stand in); it exists so later checks can still run. `None` if
/// the value could not be recovered at all (e.g. a required key is wrong).
pub fn typed<T: DeserializeOwned>(value: &Raw<'_>, diags: &mut Vec<Diagnostic>) -> Option<T> {
    let mut value = value.clone();
    let mut removed: Vec<String> = Vec::new();
    for _ in 0..MAX_RETRIES {
        match T::deserialize(ValueDeserializer::from(value.clone())) {
            Ok(v) => return Some(v),
            Err(e) => {
                let span = e.span().unwrap_or_else(|| value.span());
                let message = e.message().trim().to_string();
                // A key we removed to keep going must not come back as "missing", nor leave a one-key (enum)
                // table empty and complain of that.
                let follow_on = removed.iter().any(|k| message == format!("missing field `{k}`"))
                    || (!removed.is_empty() && message == "wanted exactly 1 element, found 0 elements");
                if !follow_on {
                    diags.push(translate(&message, span.clone()));
                }
                match remove_key_at(&mut value, &span) {
                    Some(key) => removed.push(key),
                    None => return None,
                }
            }
        }
    }
    None
}

/// Rewrites serde's wording into the manifest's ("unknown key … did you mean …").
pub fn translate(message: &str, span: Range<usize>) -> Diagnostic {
    if let Some(rest) = message.strip_prefix("unknown field `") {
        let (word, expected) = split_expected(rest);
        let suggestion = did_you_mean(word, expected.iter().copied());
        let (message, help) = match suggestion {
            Some(s) => (format!("unknown key `{word}`, did you mean `{s}`?"), format!("did you mean `{s}`?")),
            None if expected.is_empty() => (format!("unknown key `{word}`"), "this table takes no keys".to_string()),
            None => (format!("unknown key `{word}`"), format!("valid keys here: {}", one_of(&expected))),
        };
        return Diagnostic::error(message, Some(span)).with_help(help);
    }
    if let Some(rest) = message.strip_prefix("unknown variant `") {
        let (word, expected) = split_expected(rest);
        let text = match did_you_mean(word, expected.iter().copied()) {
            Some(s) => format!("unknown value `{word}`, did you mean `{s}`?"),
            None => format!("unknown value `{word}`"),
        };
        return Diagnostic::error(text, Some(span)).with_help(format!("expected {}", one_of(&expected)));
    }
    if let Some(rest) = message.strip_prefix("missing field `") {
        let key = rest.trim_end_matches('`');
        return Diagnostic::error(format!("missing required key `{key}`"), Some(span))
            .with_help(format!("add `{key} = …` to this table"));
    }
    if let Some(rest) = message.strip_prefix("invalid type: ") {
        let (found, expected) = rest.split_once(", expected ").unwrap_or((rest, ""));
        let want = in_words(expected);
        return Diagnostic::error(format!("wrong type: {found} where {want} is expected"), Some(span))
            .with_help(format!("write {want} here"));
    }
    if let Some(name) = message.strip_prefix("data did not match any variant of untagged enum ") {
        // serde names the Rust type; say what the key takes, in the manifest's words.
        let (what, example) = match name.trim() {
            "AnimationSel" => (
                "`animation` takes a clip index, a clip name, a list of them, or \"all\"",
                "animation = 0, animation = \"Walk\", animation = [0, \"Wave\"] or animation = \"all\"",
            ),
            "ClipRef" => ("a clip in an `animation` list is an index or a name", "animation = [0, \"Wave\"]"),
            "Scale" => ("`scale` takes a number or one per axis", "scale = 2 or scale = [1, 1, 2]"),
            "FrameSubset" => (
                "a split's `frames` takes a list of positions or a range",
                "frames = [0, 5, 10] or frames = { start = 0, end = 20, every = 2 }",
            ),
            "Background" => (
                "`background` takes a name or an sRGB colour",
                "background = \"white\" or background = [0.5, 0.5, 0.5]",
            ),
            other => return Diagnostic::error(format!("this value has none of the forms {other} takes"), Some(span)),
        };
        return Diagnostic::error(what, Some(span)).with_help(format!("e.g. {example}"));
    }
    Diagnostic::error(message.to_string(), Some(span))
}

/// serde's name of an expected type, in words a manifest's author knows.
fn in_words(expected: &str) -> String {
    let e = expected.trim();
    match e {
        "u8" | "u16" | "u32" | "u64" | "usize" => "a whole number, 0 or more (e.g. 80)".into(),
        "i8" | "i16" | "i32" | "i64" | "isize" => "a whole number (e.g. 0)".into(),
        "f32" | "f64" => "a number (e.g. 2.4)".into(),
        "a boolean" => "true or false".into(),
        "a string" => "a quoted string (e.g. \"name\")".into(),
        "a sequence" => "a list (e.g. [1, 2, 3])".into(),
        _ if e.starts_with("an array of length ") => format!("a list of {} numbers", &e["an array of length ".len()..]),
        _ if e.starts_with("struct ") => "a table (e.g. { key = value })".into(),
        "" => "another type".into(),
        other => other.to_string(),
    }
}

/// Splits "word`, expected one of `a`, `b`" into ("word", ["a", "b"]).
fn split_expected(rest: &str) -> (&str, Vec<&str>) {
    let (word, tail) = rest.split_once('`').unwrap_or((rest, ""));
    let expected = tail.split('`').skip(1).step_by(2).collect();
    (word, expected)
}

/// Removes the key whose key or value span best matches `span`, returning its name.
fn remove_key_at(value: &mut Raw<'_>, span: &Range<usize>) -> Option<String> {
    match value.get_mut() {
        DeValue::Table(table) => remove_in_table(table, span),
        DeValue::Array(array) => array.iter_mut().find_map(|v| remove_key_at(v, span)),
        _ => None,
    }
}

fn remove_in_table(table: &mut DeTable<'_>, span: &Range<usize>) -> Option<String> {
    // Descend first: the innermost key containing the span is the culprit.
    for (_, v) in table.iter_mut() {
        let vs = v.span();
        if vs.start <= span.start && span.end <= vs.end && vs != *span {
            if let Some(k) = remove_key_at(v, span) {
                return Some(k);
            }
        }
    }
    let hit = table
        .iter()
        .find(|(k, v)| {
            let (ks, vs) = (k.span(), v.span());
            let inside = |s: &Range<usize>| s.start <= span.start && span.end <= s.end;
            ks == *span || vs == *span || inside(&ks) || inside(&vs)
        })
        .map(|(k, _)| k.clone())?;
    table.remove(&hit);
    Some(hit.get_ref().to_string())
}

/// The entries of a table value, or an error if it is not a table.
pub fn entries<'a, 'i>(
    value: &'a Raw<'i>,
    what: &str,
    diags: &mut Vec<Diagnostic>,
) -> Vec<(&'a str, Range<usize>, &'a Raw<'i>)> {
    match value.get_ref() {
        DeValue::Table(t) => t.iter().map(|(k, v)| (k.get_ref().as_ref(), k.span(), v)).collect(),
        _ => {
            diags.push(Diagnostic::error(format!("`{what}` must be a table"), Some(value.span())));
            Vec::new()
        }
    }
}

/// Keys present in a raw table value, with their spans.
pub fn keys<'a>(value: &'a Raw<'_>) -> Vec<(&'a str, Range<usize>)> {
    match value.get_ref() {
        DeValue::Table(t) => t.iter().map(|(k, _)| (k.get_ref().as_ref(), k.span())).collect(),
        _ => Vec::new(),
    }
}
