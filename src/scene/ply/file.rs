//! Reading a PLY file from disk. A cloud in the common binary layouts (one `vertex` element of float positions,
//! optionally float normals and uchar colours, either byte order: see [`Layout`]) streams through a buffer that stays in
//! the CPU's cache and is decoded as it arrives; any other file is read whole and decoded by [`read_at`] (what
//! [`read()`](super::read()) runs), so the results and errors are the same either way. [`check_file`] refuses
//! what the header and the file's size decide, reading only the header: what `vvgen check` runs on every frame
//! of a sequence.
//!
//! Why stream: reading a 1M-point, 15 MB frame whole copies it once from the page cache into memory and then
//! reads it back out of memory to decode it. Decoding from a 240 KB buffer saves that round trip, about half of
//! the memory traffic of the read (2.2 ms against 3.3–3.75 ms for the same file in the scene bench).

use std::fs::File;
use std::io::Read;
use std::path::Path;

use super::columns::{Columns, Layout};
use super::read::{check_finite, min_row, points_element, read_at, require_xyz, shift, too_many_rows, PlyData};
use super::{parse_header, Header, PlyError};

/// Reading a PLY file failed.
#[derive(Debug, thiserror::Error)]
pub enum FileError {
    /// The file could not be read.
    #[error(transparent)]
    Io(#[from] std::io::Error),
    /// Its contents are not a PLY vvgen can use.
    #[error(transparent)]
    Ply(#[from] PlyError),
}

/// How much of the file is read first for the header (a header longer than this is read whole).
const HEAD: usize = 64 << 10;

/// Rows decoded per chunk: 240 KB of 15-byte rows, within a core's L2 cache.
const CHUNK_ROWS: usize = 16 << 10;

/// Reads and decodes the PLY file at `path`, as [`read()`](super::read()) decodes its bytes.
pub fn read_file(path: &Path) -> Result<PlyData, FileError> {
    read_file_in(path, HEAD, CHUNK_ROWS, [0.0; 3])
}

/// [`read_file`] with `origin` subtracted from the positions, as [`read_at`] does.
pub fn read_file_at(path: &Path, origin: [f64; 3]) -> Result<PlyData, FileError> {
    read_file_in(path, HEAD, CHUNK_ROWS, origin)
}

/// [`read_file_at`] with the first read's size and the rows per chunk given (the tests make both small).
fn read_file_in(path: &Path, head_len: usize, chunk_rows: usize, origin: [f64; 3]) -> Result<PlyData, FileError> {
    let (mut file, len, head) = open(path, head_len)?;
    // What does not stream is read whole; `read_at` gives its result or its error.
    let whole = |mut bytes: Vec<u8>, mut file: File| -> Result<PlyData, FileError> {
        file.read_to_end(&mut bytes)?;
        Ok(read_at(&bytes, origin)?)
    };
    if (head.len() as u64) >= len {
        return whole(head, file);
    }
    // A header that ends at the very end of `head` might end in a CR whose LF is still in the file.
    let header = match parse_header(&head) {
        Ok(h) if h.body_start < head.len() => h,
        _ => return whole(head, file),
    };
    let layout = match header.elements.as_slice() {
        [el] if el.name == "vertex" || el.name == "point" => Layout::of(el, header.format).map(|l| (el, l)),
        _ => None,
    };
    let Some((el, layout)) = layout else { return whole(head, file) };
    let (n, row) = (el.count, layout.row_size);
    // The rows must fit in the file before anything is allocated for them (`read` words the error).
    if n.checked_mul(row).is_none_or(|total| total as u64 > len - header.body_start as u64) {
        return whole(head, file);
    }
    let mut cols = Columns::new(&layout, n);
    let mut buf = vec![0u8; chunk_rows.min(n).max(1) * row];
    let mut pending = &head[header.body_start..];
    let mut left = n;
    while left > 0 {
        let want = (left * row).min(buf.len());
        // The body's first bytes came with the header; the rest comes from the file.
        let from_head = pending.len().min(want);
        buf[..from_head].copy_from_slice(&pending[..from_head]);
        pending = &pending[from_head..];
        file.read_exact(&mut buf[from_head..want])?;
        layout.append(&mut cols, &buf[..want]);
        left -= want / row;
    }
    let mut out = PlyData { comments: header.comments, ..Default::default() };
    let finite = cols.finish(&mut out);
    let finite = !shift(&mut out.positions, origin) && finite;
    check_finite(&out.positions, finite, &el.name)?;
    Ok(out)
}

/// What reading the PLY file at `path` would refuse that its header and size decide, found without reading its
/// body: not a PLY, a malformed header, no `vertex` (or `point`) element or one without `x`, `y`, `z`, or more
/// rows declared than the file can hold (each row at its smallest). Returns the header. `vvgen check` runs it on
/// every frame of a sequence, which the build reads only when it renders them.
pub fn check_file(path: &Path) -> Result<Header, FileError> {
    let (mut file, len, mut head) = open(path, HEAD)?;
    let header = match parse_header(&head) {
        // A header longer than the first read: read on (the file's size bounds it).
        Err(PlyError::NoEndHeader) if (head.len() as u64) < len => {
            file.read_to_end(&mut head)?;
            parse_header(&head)?
        }
        h => h?,
    };
    let points = points_element(&header);
    let el = header
        .elements
        .iter()
        .find(|e| e.name == points)
        .ok_or_else(|| PlyError::Unusable("no `vertex` (or `point`) element".into()))?;
    require_xyz(el)?;
    // (A header cut at a CR whose LF follows would start the body a byte early: one byte more lenient.)
    let mut remaining = len.saturating_sub(header.body_start as u64);
    for el in &header.elements {
        match (el.count as u64).checked_mul(min_row(el, header.format) as u64) {
            Some(need) if need <= remaining => remaining -= need,
            _ => return Err(too_many_rows(el, remaining).into()),
        }
    }
    Ok(header)
}

/// The file at `path`, its length, and its first `head_len` bytes (all of it when shorter), the file positioned
/// after them.
fn open(path: &Path, head_len: usize) -> std::io::Result<(File, u64, Vec<u8>)> {
    let mut file = File::open(path)?;
    let len = file.metadata()?.len();
    let mut head = Vec::with_capacity(head_len.min(len as usize));
    (&mut file).take(head_len as u64).read_to_end(&mut head)?;
    Ok((file, len, head))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::ply::read;

    fn file(bytes: &[u8]) -> (tempfile::TempDir, std::path::PathBuf) {
        let d = tempfile::tempdir().unwrap();
        let p = d.path().join("f.ply");
        std::fs::write(&p, bytes).unwrap();
        (d, p)
    }

    /// `read_file` and `read` of the same bytes agree: the same data, or the same error.
    fn same(bytes: &[u8]) -> Result<PlyData, PlyError> {
        same_in(bytes, HEAD, CHUNK_ROWS)
    }

    fn same_in(bytes: &[u8], head: usize, chunk_rows: usize) -> Result<PlyData, PlyError> {
        let (_d, p) = file(bytes);
        let whole = read(bytes);
        match read_file_in(&p, head, chunk_rows, [0.0; 3]) {
            Ok(d) => assert_eq!(Ok(&d), whole.as_ref()),
            Err(FileError::Ply(e)) => assert_eq!(Err(&e), whole.as_ref()),
            Err(FileError::Io(e)) => panic!("{e}"),
        }
        whole
    }

    /// A little-endian cloud of `n` rows, `x y z` float + `red green blue` uchar (+ `nx ny nz` float), with
    /// `pad` bytes of comment in the header and `eol` line ends.
    fn cloud(n: usize, normals: bool, pad: usize, eol: &str) -> Vec<u8> {
        let mut h = format!("ply{eol}format binary_little_endian 1.0{eol}");
        if pad > 0 {
            h += &format!("comment {}{eol}", "c".repeat(pad));
        }
        h += &format!("element vertex {n}{eol}property float x{eol}property float y{eol}property float z{eol}");
        h += &format!("property uchar red{eol}property uchar green{eol}property uchar blue{eol}");
        if normals {
            h += &format!("property float nx{eol}property float ny{eol}property float nz{eol}");
        }
        let mut b = (h + &format!("end_header{eol}")).into_bytes();
        for i in 0..n {
            for k in 0..3 {
                b.extend_from_slice(&((i * 3 + k) as f32 * 0.25).to_le_bytes());
            }
            b.extend_from_slice(&[i as u8, (i >> 8) as u8, 7]);
            if normals {
                for k in 0..3 {
                    b.extend_from_slice(&(k as f32 - 1.0).to_le_bytes());
                }
            }
        }
        b
    }

    #[test]
    fn streams_as_read_decodes_across_chunks_and_header_boundaries() {
        // Several chunks and a partial last one, with and without normals.
        for normals in [false, true] {
            let n = CHUNK_ROWS * 2 + 77;
            let d = same(&cloud(n, normals, 0, "\n")).unwrap();
            assert_eq!(d.positions.len(), n);
            let i = CHUNK_ROWS + 5;
            assert_eq!(d.positions[i], [0, 1, 2].map(|k| (i * 3 + k) as f32 * 0.25));
            assert_eq!(d.colors.as_ref().unwrap()[i], [i as u8, (i >> 8) as u8, 7, 255]);
        }
        // Headers ending just before, at and after the first read's end, with LF and CRLF line ends: the body
        // starts where `read` says, even where a CR and its LF fall on both sides of the first read.
        for eol in ["\n", "\r\n"] {
            let plain = cloud(5000, false, 0, eol).len() - 5000 * 15;
            for header in HEAD - 3..=HEAD + 2 {
                let b = cloud(5000, false, header - plain - "comment ".len() - eol.len(), eol);
                assert_eq!(b.len() - 5000 * 15, header);
                same(&b).unwrap();
            }
        }
        // A file smaller than the first read, and a cloud followed by stray bytes.
        same(&cloud(3, true, 0, "\n")).unwrap();
        let mut b = cloud(CHUNK_ROWS + 1, false, 0, "\n");
        b.extend_from_slice(b"trailing");
        same(&b).unwrap();
    }

    #[test]
    fn a_non_finite_position_or_a_short_file_fails_as_read_fails() {
        let n = CHUNK_ROWS * 2 + 10;
        for row in [0, CHUNK_ROWS - 1, CHUNK_ROWS, n - 1] {
            for bad in [f32::NAN, f32::INFINITY] {
                let mut b = cloud(n, false, 0, "\n");
                let at = b.len() - (n - row) * 15 + 4;
                b[at..at + 4].copy_from_slice(&bad.to_le_bytes());
                let e = same(&b).unwrap_err();
                assert!(matches!(e, PlyError::Body { row: r, .. } if r == row), "{e}");
            }
        }
        // Cut short, by a byte and by most of its rows; and a count past any file.
        let b = cloud(n, false, 0, "\n");
        assert!(matches!(same(&b[..b.len() - 1]), Err(PlyError::Truncated(_))));
        assert!(matches!(same(&b[..HEAD + 100]), Err(PlyError::Truncated(_))));
        let mut huge = String::from_utf8_lossy(&b[..200]).replace(&format!("vertex {n}"), "vertex 99999999999999");
        huge.truncate(huge.find("end_header\n").unwrap() + 11);
        let mut huge = huge.into_bytes();
        huge.resize(HEAD * 2, 0);
        assert!(matches!(same(&huge), Err(PlyError::Truncated(_))));
    }

    #[test]
    fn other_files_are_read_whole() {
        // Ascii: read whole, through `read`; big endian streams as little endian does.
        same(b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\nend_header\n1 2 3\n")
            .unwrap();
        let le = cloud(CHUNK_ROWS, false, 0, "\n");
        let body = le.len() - CHUNK_ROWS * 15;
        let mut be = String::from_utf8_lossy(&le[..body]).replace("little", "big").into_bytes();
        be.extend_from_slice(&le[body..]);
        same(&be).unwrap();
        let (_d, p) = file(b"ply\nformat ascii 1.0\nend_header\n");
        assert!(matches!(read_file(&p), Err(FileError::Ply(PlyError::Unusable(_)))));
        let missing = std::env::temp_dir().join("vvgen-no-such-file.ply");
        assert!(matches!(read_file(&missing), Err(FileError::Io(_))));
    }

    /// Mutated files (header and body bytes, counts, cuts) read from disk as their bytes decode, through a
    /// first read and chunks small enough that every mutant streams or falls back somewhere interesting.
    #[test]
    fn mutated_files_read_as_their_bytes_decode() {
        let seeds = [cloud(40, false, 0, "\n"), cloud(40, true, 0, "\r\n"), cloud(40, false, 30, "\n")];
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut next = |n: usize| {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state % n.max(1) as u64) as usize
        };
        let mut streamed = 0;
        for _ in 0..3000 {
            let mut b = seeds[next(seeds.len())].clone();
            for _ in 0..1 + next(3) {
                let header = b.windows(10).position(|w| w == b"end_header").map_or(b.len(), |p| p + 10);
                match next(5) {
                    // A header byte, or a body byte (NaN and infinity among them).
                    0 if header > 0 => {
                        let alphabet = b" \n\r0123456789xyzabcdefghilmnoprstuv";
                        b[next(header)] = alphabet[next(alphabet.len())];
                    }
                    1 if header < b.len() => {
                        let at = header + next(b.len() - header);
                        b[at] = [0, 0x7f, 0x80, 0xff][next(4)];
                    }
                    // A count or size word: another number.
                    2 => {
                        let t = String::from_utf8_lossy(&b[..header]).into_owned();
                        let t = t.replacen("40", ["0", "1", "39", "41", "400", "99999999999"][next(6)], 1);
                        b.splice(..header, t.into_bytes());
                    }
                    3 => b.truncate(next(b.len() + 1)),
                    _ => b.extend_from_slice(&[7; 5][..next(6)]),
                }
            }
            let (head, chunk) = (16 + next(200), 1 + next(12));
            let whole = same_in(&b, head, chunk);
            streamed += usize::from(head < b.len() && whole.is_ok());
        }
        assert!(streamed > 500, "{streamed} mutants streamed");
    }

    #[test]
    fn check_file_refuses_what_the_header_and_size_decide() {
        let check = |bytes: &[u8]| {
            let (_d, p) = file(bytes);
            check_file(&p)
        };
        let b = cloud(1000, true, 0, "\n");
        assert_eq!(check(&b).unwrap().elements[0].count, 1000);
        // A header longer than the first read.
        assert!(check(&cloud(10, false, HEAD + 100, "\n")).is_ok());
        // Cut short by one byte: one row cannot fit.
        let e = check(&b[..b.len() - 1]).unwrap_err();
        assert!(
            matches!(e, FileError::Ply(PlyError::Truncated(ref m)) if m.contains("`vertex` declares 1000 rows")),
            "{e}"
        );
        // Not a PLY, no points, no x y z, a header that never ends.
        assert!(matches!(check(b"solid cube\n"), Err(FileError::Ply(PlyError::NotPly))));
        let no_points = b"ply\nformat ascii 1.0\nelement face 0\nproperty list uchar int vertex_indices\nend_header\n";
        assert!(matches!(check(no_points), Err(FileError::Ply(PlyError::Unusable(_)))));
        let no_z = b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nend_header\n1 2\n";
        assert!(matches!(check(no_z), Err(FileError::Ply(PlyError::Unusable(_)))));
        assert!(matches!(check(b"ply\nformat ascii 1.0\n"), Err(FileError::Ply(PlyError::NoEndHeader))));
        // Faces past what the file holds after its vertices: 9 rows take at least their 9 count bytes.
        let mut mesh = cloud(4, false, 0, "\n");
        let at = mesh.windows(11).position(|w| w == b"end_header\n").unwrap();
        mesh.splice(at..at, b"element face 9\nproperty list uchar int vertex_indices\n".iter().copied());
        mesh.extend_from_slice(&[3, 0, 0, 0, 0]);
        let e = check(&mesh).unwrap_err();
        assert!(matches!(e, FileError::Ply(PlyError::Truncated(ref m)) if m.contains("`face` declares 9 rows")), "{e}");
        // What it passes, reading the whole file finds readable (or refuses for what only the body shows).
        for bytes in [&b[..], &cloud(3, false, 0, "\r\n")[..]] {
            assert!(check(bytes).is_ok() && read(bytes).is_ok());
        }
    }
}
