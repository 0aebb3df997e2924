//! The text tobj parses, made from an OBJ's or MTL's text as exporters write it.
//!
//! tobj requires every line to be UTF-8 and reports any other as a bare "read error". Exporters write other
//! text: 3ds Max and other Windows tools write names in a legacy single-byte code page (Latin-1), some tools
//! write UTF-16 with a byte-order mark, and some put a UTF-8 byte-order mark before the first line (tobj would
//! read it as part of that line's keyword, and skip the line). Blender's importer reads all of these. So each
//! line is decoded here (UTF-8 where it is valid UTF-8, else Latin-1, each byte one character; UTF-16 where the
//! file starts with its mark) and handed on as UTF-8, edited as [`Edit`] says. The scans that check a file
//! before tobj reads it decode it the same way ([`decode`]), so that names agree with what tobj reads.

use std::borrow::Cow;
use std::fmt::Write as _;

/// How a file's text is encoded, as its first bytes say.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Encoding {
    /// UTF-8 (or, line by line where a line is not UTF-8, Latin-1).
    Bytes,
    Utf16 {
        big_endian: bool,
    },
}

impl Encoding {
    /// The encoding `head` (a file's first bytes) starts with, and the length of its byte-order mark.
    fn of(head: &[u8]) -> (Encoding, usize) {
        match head {
            [0xFE, 0xFF, ..] => (Encoding::Utf16 { big_endian: true }, 2),
            [0xFF, 0xFE, ..] => (Encoding::Utf16 { big_endian: false }, 2),
            [0xEF, 0xBB, 0xBF, ..] => (Encoding::Bytes, 3),
            _ => (Encoding::Bytes, 0),
        }
    }
}

/// One line's bytes as text: UTF-8 where they are, else Latin-1 (every byte is the character of its value).
fn bytes_line(raw: &[u8]) -> Cow<'_, str> {
    match std::str::from_utf8(raw) {
        Ok(s) => Cow::Borrowed(s),
        Err(_) => Cow::Owned(raw.iter().map(|&b| char::from(b)).collect()),
    }
}

/// The UTF-16 code units `raw` (pairs of bytes in the order `big_endian` says) as text, an unpaired surrogate
/// as U+FFFD.
fn utf16_line(raw: &[u8], big_endian: bool) -> String {
    let unit = |p: &[u8]| if big_endian { u16::from_be_bytes([p[0], p[1]]) } else { u16::from_le_bytes([p[0], p[1]]) };
    let units = raw.chunks_exact(2).map(unit);
    char::decode_utf16(units).map(|c| c.unwrap_or(char::REPLACEMENT_CHARACTER)).collect()
}

/// A whole file's text decoded as [`Lines`] decodes it line by line (without its edits): borrowed when it is
/// UTF-8 without a byte-order mark and without continued lines, as most files are. A line continued by a `\\` at
/// its end is joined with the next, and an empty line follows the joined one for each line joined, so that
/// later lines keep their numbers.
pub(super) fn decode(bytes: &[u8]) -> Cow<'_, str> {
    let text = decode_lines(bytes);
    if !text.contains("\\\n") && !text.contains("\\\r\n") {
        return text;
    }
    let mut out = String::with_capacity(text.len());
    let mut joined = 0;
    for line in text.split_inclusive('\n') {
        match continued(line) {
            Some(head) => {
                out.push_str(head);
                out.push(' ');
                joined += 1;
            }
            None => {
                out.push_str(line);
                out.extend(std::iter::repeat_n('\n', joined));
                joined = 0;
            }
        }
    }
    Cow::Owned(out)
}

/// `line` without its `\\` and line end, when it is continued on the next line (OBJ's line continuation, which
/// Blender's importer reads and tobj does not).
fn continued(line: &str) -> Option<&str> {
    line.trim_end_matches(['\n', '\r']).strip_suffix('\\')
}

/// [`decode`] before lines are joined.
fn decode_lines(bytes: &[u8]) -> Cow<'_, str> {
    let (encoding, mark) = Encoding::of(bytes);
    let body = &bytes[mark..];
    match encoding {
        Encoding::Utf16 { big_endian } => Cow::Owned(utf16_line(body, big_endian)),
        Encoding::Bytes => match std::str::from_utf8(body) {
            Ok(s) => Cow::Borrowed(s),
            Err(_) => {
                let mut out = String::with_capacity(body.len());
                for line in body.split_inclusive(|&b| b == b'\n') {
                    out.push_str(&bytes_line(line));
                }
                Cow::Owned(out)
            }
        },
    }
}

/// What [`Lines`] changes in the lines it hands on, besides their encoding.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum Edit {
    /// An OBJ's lines: `origin` subtracted from every vertex position (`v x y z …`, the rest of the line kept),
    /// in double precision, written back in the shortest decimals that read as the difference, so that what tobj
    /// then parses to single precision is the position relative to `origin`. With `pad_colours`, a vertex line
    /// without a colour gets a colour of NaNs: some of the file's vertices have colours and some do not, which
    /// tobj refuses (an index out of bounds) and after which Blender keeps colours only on the objects whose
    /// every vertex has one; the NaNs mark the others. A `usemtl` without a name uses [`UNNAMED`]; a polyline
    /// (`l`) of three or more vertices is dropped, and so is a face without corners.
    /// With `fix_corners`, a face corner's texture coordinate or normal index that is out of range is dropped, as
    /// Blender's importer drops it (tobj refuses the file).
    Obj { origin: [f64; 3], pad_colours: bool, fix_corners: bool },
    /// An MTL's lines: a colour statement of one number (`Kd 0.8`), which the format reads as a grey (`Kd 0.8
    /// 0.8 0.8`) and tobj cannot parse, written out in full; a `newmtl` without a name is [`UNNAMED`].
    Mtl,
}

/// The name given to a material whose name is empty (`newmtl` alone, and `usemtl` alone, which uses it), which
/// tobj refuses and Blender's importer reads as a material like any other.
const UNNAMED: &str = "(unnamed)";

impl Edit {
    /// An OBJ's lines with no option set: what every reading of an OBJ edits (see [`Edit::Obj`]).
    pub(super) const OBJ_AS_IS: Edit = Edit::Obj { origin: [0.0; 3], pad_colours: false, fix_corners: false };

    /// `line` (without its newline) edited, or `None` when it stays as it is (most lines: this is cheap for them).
    /// `seen` counts the texture coordinates and normals above it (kept by [`Lines`] when corners are fixed).
    fn apply(self, line: &str, seen: [i64; 2]) -> Option<String> {
        let mut words = line.split_ascii_whitespace();
        let key = words.next()?;
        match self {
            Edit::Obj { fix_corners: true, .. } if key == "f" && line.contains('/') => fixed_face(words, seen),
            Edit::Obj { .. } if key == "usemtl" => words.next().is_none().then(|| format!("usemtl {UNNAMED}")),
            Edit::Mtl if key == "newmtl" => words.next().is_none().then(|| format!("newmtl {UNNAMED}")),
            // A polyline: tobj fills one of three or more vertices as a polygon; Blender imports its edges, which
            // draw nothing (one of two vertices, which tobj makes a triangle without area, is left as it is).
            Edit::Obj { .. } if key == "l" => (words.count() >= 3).then(String::new),
            // A face without corners: tobj refuses the file ("invalid polygon", no line); Blender skips it.
            Edit::Obj { .. } if key == "f" => words.next().is_none().then(String::new),
            Edit::Obj { origin, pad_colours, .. } => {
                if key != "v" || (origin == [0.0; 3] && !pad_colours) {
                    return None;
                }
                let numbers: Vec<&str> = words.collect();
                let mut out = String::from("v");
                for (k, w) in numbers.iter().enumerate() {
                    match origin.get(k).filter(|_| origin != [0.0; 3]) {
                        Some(o) => write!(out, " {}", w.parse::<f64>().ok()? - o),
                        None => write!(out, " {w}"),
                    }
                    .expect("BUG: writing to a String cannot fail");
                }
                if pad_colours && numbers.len() == 3 {
                    out.push_str(" NaN NaN NaN");
                }
                Some(out)
            }
            Edit::Mtl => {
                let grey = matches!(key, "Ka" | "Kd" | "Ks" | "Ke").then(|| (words.next(), words.next()));
                match grey {
                    Some((Some(v), None)) => Some(format!("{key} {v} {v} {v}")),
                    _ => None,
                }
            }
        }
    }
}

/// A face line's corners with each texture coordinate or normal index that `seen` (the counts of texture
/// coordinates and normals above it) does not hold dropped; `None` when none is.
fn fixed_face<'a>(corners: impl Iterator<Item = &'a str>, seen: [i64; 2]) -> Option<String> {
    let mut out = String::from("f");
    let mut changed = false;
    for corner in corners {
        let mut parts = corner.split('/');
        let v = parts.next().unwrap_or("");
        let mut kept = [""; 2];
        for (k, part) in parts.take(2).enumerate() {
            let i: i64 = part.parse().unwrap_or(0);
            let resolved = if i < 0 { seen[k] + i + 1 } else { i };
            if (1..=seen[k]).contains(&resolved) {
                kept[k] = part;
            } else {
                changed |= !part.is_empty();
            }
        }
        out.push(' ');
        out.push_str(v);
        match kept {
            ["", ""] => {}
            [t, ""] => write!(out, "/{t}").expect("BUG: writing to a String cannot fail"),
            [t, n] => write!(out, "/{t}/{n}").expect("BUG: writing to a String cannot fail"),
        }
    }
    changed.then_some(out)
}

/// A reader of an OBJ's or MTL's text that hands tobj UTF-8 lines, edited as `edit` says; one line is held at
/// a time. The input is read through `inner`'s own buffer.
pub(super) struct Lines<R> {
    inner: R,
    edit: Edit,
    /// `None` until the first bytes have been looked at.
    encoding: Option<Encoding>,
    line: Vec<u8>,
    at: usize,
    /// The texture coordinates and normals read so far (counted when corners are fixed).
    seen: [i64; 2],
}

impl<R: std::io::BufRead> Lines<R> {
    pub(super) fn new(inner: R, edit: Edit) -> Self {
        Lines { inner, edit, encoding: None, line: Vec::new(), at: 0, seen: [0; 2] }
    }

    /// Replaces the held line by the next one, decoded and edited.
    fn next_line(&mut self) -> std::io::Result<()> {
        self.line.clear();
        self.at = 0;
        let encoding = match self.encoding {
            Some(e) => e,
            None => {
                let (e, mark) = Encoding::of(self.inner.fill_buf()?);
                self.inner.consume(mark);
                self.encoding = Some(e);
                e
            }
        };
        let mut text = read_decoded(&mut self.inner, &mut self.line, encoding)?;
        // A continued line is joined with the next (and the next, …), as Blender's importer reads it.
        if let Some(head) = continued(&text) {
            let mut joined = format!("{head} ");
            let mut more = Vec::new();
            loop {
                more.clear();
                let next = read_decoded(&mut self.inner, &mut more, encoding)?;
                match continued(&next) {
                    Some(head) if !next.is_empty() => {
                        joined.push_str(head);
                        joined.push(' ');
                    }
                    _ => {
                        joined.push_str(&next);
                        break;
                    }
                }
            }
            text = Cow::Owned(joined);
        }
        let body = text.trim_end_matches(['\n', '\r']);
        if let Edit::Obj { fix_corners: true, .. } = self.edit {
            match body.split_ascii_whitespace().next() {
                Some("vt") => self.seen[0] += 1,
                Some("vn") => self.seen[1] += 1,
                _ => {}
            }
        }
        let edited = self.edit.apply(body, self.seen);
        // The common case: a UTF-8 line that no edit touches stays in place.
        if edited.is_none() && matches!(text, Cow::Borrowed(_)) {
            return Ok(());
        }
        let mut out = edited.unwrap_or_else(|| body.to_string());
        if text.len() > body.len() {
            out.push('\n');
        }
        self.line = out.into_bytes();
        Ok(())
    }
}

/// Reads the next line of `inner` (newline included) into `line`, in the file's encoding, and decodes it:
/// borrowed from `line` when it is UTF-8.
fn read_decoded<'l>(
    inner: &mut impl std::io::BufRead,
    line: &'l mut Vec<u8>,
    encoding: Encoding,
) -> std::io::Result<Cow<'l, str>> {
    match encoding {
        Encoding::Bytes => {
            inner.read_until(b'\n', line)?;
        }
        Encoding::Utf16 { big_endian } => loop {
            let mut unit = [0u8; 2];
            match std::io::Read::read_exact(inner, &mut unit) {
                Ok(()) => {}
                Err(e) if e.kind() == std::io::ErrorKind::UnexpectedEof => break,
                Err(e) => return Err(e),
            }
            line.extend_from_slice(&unit);
            let newline = if big_endian { [0, b'\n'] } else { [b'\n', 0] };
            if unit == newline {
                break;
            }
        },
    }
    let line: &'l [u8] = line;
    Ok(match encoding {
        Encoding::Bytes => match std::str::from_utf8(line) {
            Ok(s) => Cow::Borrowed(s),
            Err(_) => bytes_line(line),
        },
        Encoding::Utf16 { big_endian } => Cow::Owned(utf16_line(line, big_endian)),
    })
}

impl<R: std::io::BufRead> std::io::Read for Lines<R> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let got = std::io::BufRead::fill_buf(self)?;
        let n = got.len().min(buf.len());
        buf[..n].copy_from_slice(&got[..n]);
        std::io::BufRead::consume(self, n);
        Ok(n)
    }
}

impl<R: std::io::BufRead> std::io::BufRead for Lines<R> {
    fn fill_buf(&mut self) -> std::io::Result<&[u8]> {
        if self.at == self.line.len() {
            self.next_line()?;
        }
        Ok(&self.line[self.at..])
    }

    fn consume(&mut self, n: usize) {
        self.at = (self.at + n).min(self.line.len());
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Read;

    fn through(bytes: &[u8], edit: Edit) -> String {
        let mut out = String::new();
        Lines::new(bytes, edit).read_to_string(&mut out).unwrap();
        out
    }

    const PLAIN: Edit = Edit::OBJ_AS_IS;

    #[test]
    fn utf8_text_passes_unchanged_and_a_byte_order_mark_is_dropped() {
        let text = "# é\nv 1 2 3\r\nf 1 1 1";
        assert_eq!(through(text.as_bytes(), PLAIN), text);
        assert_eq!(through(&[b"\xEF\xBB\xBF".as_slice(), text.as_bytes()].concat(), PLAIN), text);
        assert_eq!(decode(&[b"\xEF\xBB\xBF".as_slice(), text.as_bytes()].concat()), text);
    }

    #[test]
    fn latin1_and_utf16_lines_become_utf8_as_the_scans_read_them() {
        let latin1 = b"usemtl Terraind\xe6k\r\nv 1 2 3\n";
        assert_eq!(through(latin1, PLAIN), "usemtl Terraindæk\nv 1 2 3\n");
        assert_eq!(decode(latin1), "usemtl Terraindæk\r\nv 1 2 3\n");
        let text = "usemtl Ærø\r\nv 1 2 3\n";
        for big_endian in [true, false] {
            let mut bytes = if big_endian { vec![0xFE, 0xFF] } else { vec![0xFF, 0xFE] };
            for u in text.encode_utf16() {
                bytes.extend(if big_endian { u.to_be_bytes() } else { u.to_le_bytes() });
            }
            assert_eq!(through(&bytes, PLAIN), "usemtl Ærø\nv 1 2 3\n");
            assert_eq!(decode(&bytes), text);
        }
    }

    #[test]
    fn vertex_lines_are_shifted_and_padded_and_mtl_greys_written_out() {
        let shift = Edit::Obj { origin: [500000.0, 0.0, 0.0], pad_colours: false, fix_corners: false };
        assert_eq!(through(b"v 500001.5 2 3 0.1 0.2 0.3\nvt 1 2\n", shift), "v 1.5 2 3 0.1 0.2 0.3\nvt 1 2\n");
        let pad = Edit::Obj { origin: [0.0; 3], pad_colours: true, fix_corners: false };
        assert_eq!(through(b"v 1 2 3\nv 1 2 3 0.5 0.5 0.5\n", pad), "v 1 2 3 NaN NaN NaN\nv 1 2 3 0.5 0.5 0.5\n");
        assert_eq!(through(b"Ks 0\nKd 0.1 0.2 0.3\nNs 10\n", Edit::Mtl), "Ks 0 0 0\nKd 0.1 0.2 0.3\nNs 10\n");
        assert_eq!(through(b"newmtl \nnewmtl a\n", Edit::Mtl), "newmtl (unnamed)\nnewmtl a\n");
        assert_eq!(through(b"usemtl\r\nusemtl a\n", PLAIN), "usemtl (unnamed)\nusemtl a\n");
        assert_eq!(through(b"l 1 2 3\nl 1 2\nf 1 2 3\nf\n", PLAIN), "\nl 1 2\nf 1 2 3\n\n");
    }
}
