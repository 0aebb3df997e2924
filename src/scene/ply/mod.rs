//! PLY reading and writing: ascii, binary little and big endian; every scalar type and alias; list
//! properties with any count type; LF, CRLF and CR headers; any property order; extra elements read past.
//!
//! Reading never trusts the header: element counts are checked against what the remaining bytes could hold
//! before anything is allocated, and every read is bounds-checked, so a malformed file gives an error, never a
//! panic or an unbounded allocation.
//!
//! [`parse_header`] parses the header (formats, scalar types, elements and properties); [`read()`] decodes a body into
//! [`PlyData`]; [`write()`] encodes points and triangles.

mod header;
mod read;
mod write;

pub use header::{parse_header, Element, Format, Header, Property, Scalar};
pub use read::{read, PlyData};
pub use write::{write, PlyOut};

use thiserror::Error;

/// A PLY problem, with the line (header) or element row (body) where it was found.
#[derive(Debug, Error, PartialEq)]
pub enum PlyError {
    /// The file does not start with `ply`.
    #[error("not a PLY file (it does not start with `ply`)")]
    NotPly,
    /// The header never ends.
    #[error("the header has no `end_header` line")]
    NoEndHeader,
    /// A header line that cannot be understood.
    #[error("header line {line}: {msg}")]
    Header {
        /// 1-based header line.
        line: usize,
        /// What is wrong.
        msg: String,
    },
    /// The body is shorter than the header says.
    #[error("the file ends early: {0}")]
    Truncated(String),
    /// A bad value in the body.
    #[error("element `{element}` row {row}: {msg}")]
    Body {
        /// Element name.
        element: String,
        /// 0-based row.
        row: usize,
        /// What is wrong.
        msg: String,
    },
    /// Valid PLY, but not something vvgen can use.
    #[error("{0}")]
    Unusable(String),
}

#[cfg(test)]
mod tests {
    use super::*;

    type Cloud = (Vec<[f32; 3]>, Vec<[f32; 3]>, Vec<[u8; 3]>);

    fn cloud() -> Cloud {
        let p: Vec<[f32; 3]> = (0..100).map(|i| [i as f32 * 0.5, -(i as f32), 1e-3 * i as f32]).collect();
        let n: Vec<[f32; 3]> = (0..100).map(|i| [0.0, (i % 2) as f32, 1.0 - (i % 2) as f32]).collect();
        let c: Vec<[u8; 3]> = (0..100).map(|i| [i as u8, 255 - i as u8, 7]).collect();
        (p, n, c)
    }

    #[test]
    fn round_trip_binary_and_ascii() {
        let (p, n, c) = cloud();
        let tris = [0u32, 1, 2, 2, 3, 0];
        for ascii in [false, true] {
            let bytes = write(&PlyOut {
                positions: &p,
                normals: Some(&n),
                colors: Some(&c),
                triangles: Some(&tris),
                ascii,
                ..Default::default()
            });
            let d = read(&bytes).unwrap();
            assert_eq!(d.positions, p);
            assert_eq!(d.normals.unwrap(), n);
            assert_eq!(d.colors.unwrap().iter().map(|c| [c[0], c[1], c[2]]).collect::<Vec<_>>(), c);
            assert_eq!(d.triangles, tris);
        }
    }

    #[test]
    fn big_endian_and_lone_cr_headers() {
        let mut b = b"ply\rformat binary_big_endian 1.0\relement vertex 1\rproperty double x\rproperty short y\rproperty uint z\rend_header\r".to_vec();
        b.extend_from_slice(&1.5f64.to_be_bytes());
        b.extend_from_slice(&(-2i16).to_be_bytes());
        b.extend_from_slice(&7u32.to_be_bytes());
        assert_eq!(read(&b).unwrap().positions, [[1.5, -2.0, 7.0]]);
    }

    #[test]
    fn absurd_counts_fail_before_allocating() {
        let b = b"ply\nformat binary_little_endian 1.0\nelement vertex 4000000000000\nproperty float x\nproperty float y\nproperty float z\nend_header\n\0\0\0\0";
        assert!(matches!(read(b), Err(PlyError::Truncated(_))));
        let b = b"ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\nproperty float z\nend_header\n1 2 3\n4 5\n";
        assert!(matches!(read(b), Err(PlyError::Truncated(_))), "{:?}", read(b));
        let b = b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\nend_header\n1 2 zz\n";
        assert!(matches!(read(b), Err(PlyError::Body { .. })));
    }
}
