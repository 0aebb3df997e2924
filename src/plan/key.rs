//! One keyed walk, two sinks (n2's `hash.rs` and `-d explain`): every action writes the fields that determine
//! its bytes into a [`KeyWriter`]. [`Hashing`] turns them into the action's key; [`Explaining`] records them as
//! `(field, value)` pairs for `plan --explain`. The same code feeds both, so an explanation cannot drift from
//! the key it explains.
//!
//! The encoding is canonical: each field is its name and a typed value, length-prefixed, in the order the walk
//! writes them. Settings structs are destructured without `..` where they are walked, so a new field does not
//! compile until it is either keyed or excluded with a reason.

use crate::cache::Digest;

/// One value of a key field.
#[derive(Debug, Clone, Copy)]
pub enum Value<'a> {
    /// An unsigned integer.
    U64(u64),
    /// A float (keyed by its bits: `-0.0` and `0.0` differ, as they may in the bytes).
    F64(f64),
    /// A flag.
    Bool(bool),
    /// Text (names, enum spellings).
    Str(&'a str),
    /// A content key or blob digest.
    Digest(&'a Digest),
    /// Several floats (a matrix, a colour).
    F64s(&'a [f64]),
}

/// Where a keyed walk writes its fields.
pub trait KeyWriter {
    /// Writes field `name` with `value`.
    fn field(&mut self, name: &str, value: Value<'_>);

    /// An unsigned integer field.
    fn u64(&mut self, name: &str, v: u64) {
        self.field(name, Value::U64(v));
    }
    /// A float field.
    fn f64(&mut self, name: &str, v: f64) {
        self.field(name, Value::F64(v));
    }
    /// A flag field.
    fn bool(&mut self, name: &str, v: bool) {
        self.field(name, Value::Bool(v));
    }
    /// A text field.
    fn str(&mut self, name: &str, v: &str) {
        self.field(name, Value::Str(v));
    }
    /// A digest field.
    fn digest(&mut self, name: &str, v: &Digest) {
        self.field(name, Value::Digest(v));
    }
    /// A field of several floats.
    fn f64s(&mut self, name: &str, v: &[f64]) {
        self.field(name, Value::F64s(v));
    }
    /// An optional float: absent and present are different fields' values.
    fn opt_f64(&mut self, name: &str, v: Option<f64>) {
        match v {
            Some(v) => self.f64(name, v),
            None => self.str(name, "none"),
        }
    }
}

/// The hashing sink: blake3 in derive-key mode over the action kind, then every field.
pub struct Hashing(blake3::Hasher);

impl Hashing {
    /// Starts the key of an action of `kind`.
    pub fn new(kind: &str) -> Hashing {
        Hashing(blake3::Hasher::new_derive_key(&format!("vvgen action {kind}")))
    }

    /// The key.
    pub fn finish(&self) -> Digest {
        Digest(*self.0.finalize().as_bytes())
    }

    fn bytes(&mut self, b: &[u8]) {
        self.0.update(&(b.len() as u64).to_le_bytes());
        self.0.update(b);
    }
}

impl KeyWriter for Hashing {
    fn field(&mut self, name: &str, value: Value<'_>) {
        self.bytes(name.as_bytes());
        match value {
            Value::U64(v) => {
                self.0.update(b"u");
                self.bytes(&v.to_le_bytes());
            }
            Value::F64(v) => {
                self.0.update(b"f");
                self.bytes(&v.to_bits().to_le_bytes());
            }
            Value::Bool(v) => {
                self.0.update(b"b");
                self.bytes(&[v as u8]);
            }
            Value::Str(v) => {
                self.0.update(b"s");
                self.bytes(v.as_bytes());
            }
            Value::Digest(d) => {
                self.0.update(b"d");
                self.bytes(&d.0);
            }
            Value::F64s(v) => {
                self.0.update(b"F");
                let b: Vec<u8> = v.iter().flat_map(|x| x.to_bits().to_le_bytes()).collect();
                self.bytes(&b);
            }
        }
    }
}

/// The explaining sink: the fields as readable `(name, value)` pairs.
#[derive(Debug, Default)]
pub struct Explaining(pub Vec<(String, String)>);

impl KeyWriter for Explaining {
    fn field(&mut self, name: &str, value: Value<'_>) {
        let text = match value {
            Value::U64(v) => v.to_string(),
            Value::F64(v) => ryu::Buffer::new().format(v).to_string(),
            Value::Bool(v) => v.to_string(),
            Value::Str(v) => v.to_string(),
            // Enough of a digest to tell two apart in a listing.
            Value::Digest(d) => d.hex()[..16].to_string(),
            Value::F64s(v) => {
                let parts: Vec<String> = v.iter().map(|x| ryu::Buffer::new().format(*x).to_string()).collect();
                format!("[{}]", parts.join(" "))
            }
        };
        self.0.push((name.to_string(), text));
    }
}

/// What differs between two explanations of the same action: one line per changed, added or removed field.
pub fn diff(before: &[(String, String)], now: &[(String, String)]) -> Vec<String> {
    let mut out = Vec::new();
    for (name, v) in now {
        match before.iter().find(|(n, _)| n == name) {
            Some((_, old)) if old != v => out.push(format!("{name}: {old} → {v}")),
            Some(_) => {}
            None => out.push(format!("{name}: (none) → {v}")),
        }
    }
    for (name, old) in before {
        if !now.iter().any(|(n, _)| n == name) {
            out.push(format!("{name}: {old} → (none)"));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn walk(w: &mut dyn KeyWriter, x: f64) {
        w.str("pass", "depth");
        w.f64("x", x);
        w.bool("exr", true);
    }

    #[test]
    fn the_hash_and_the_explanation_come_from_one_walk() {
        let key = |x: f64| {
            let mut h = Hashing::new("t");
            walk(&mut h, x);
            h.finish()
        };
        assert_eq!(key(1.0), key(1.0));
        assert_ne!(key(1.0), key(2.0));
        assert_ne!(key(0.0), key(-0.0));
        let (mut a, mut b) = (Explaining::default(), Explaining::default());
        walk(&mut a, 1.0);
        walk(&mut b, 2.5);
        assert_eq!(diff(&a.0, &b.0), vec!["x: 1.0 → 2.5".to_string()]);
    }

    #[test]
    fn field_names_are_part_of_the_key() {
        let mut a = Hashing::new("t");
        a.u64("views", 3);
        let mut b = Hashing::new("t");
        b.u64("frames", 3);
        assert_ne!(a.finish(), b.finish());
        let mut c = Hashing::new("u");
        c.u64("views", 3);
        assert_ne!(a.finish(), c.finish());
    }
}
