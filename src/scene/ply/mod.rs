//! PLY reading and writing: ascii, binary little and big endian; every scalar type and alias; list
//! properties with any count type; LF, CRLF and CR headers; any property order; extra elements read past.
//!
//! Reading never trusts the header: element counts are checked against what the remaining bytes could hold
//! before anything is allocated, and every read is bounds-checked, so a malformed file gives an error, never a
//! panic or an unbounded allocation.
//!
//! [`parse_header`] parses the header (formats, scalar types, elements and properties); [`read()`] decodes a file's
//! bytes into [`PlyData`]; [`read_file`] reads a file from disk, streaming the common binary cloud layouts
//! (the `columns` module's one-pass decoder) and giving the same data and errors as [`read()`] of its bytes;
//! [`write()`] encodes points and triangles.

mod columns;
mod file;
mod header;
mod read;
mod write;

pub use file::{check_file, read_file, read_file_at, FileError};
pub use header::{parse_header, Element, Format, Header, Property, Scalar};
pub use read::{
    gaussian_splats, holds_gaussian_shapes, holds_gaussian_splats, read, read_at, GaussianColumns, PlyData,
};
pub(crate) use read::{texture_comment, texturing};
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

    /// A file in `format` with the given float and uchar columns in that order (ascii goes through the general
    /// path, so it is the binary fast path's reference).
    fn columns(props: &[&str], rows: &[Vec<f32>], format: Format) -> Vec<u8> {
        let is_byte = |p: &str| ["red", "green", "blue"].contains(&p);
        let name = match format {
            Format::Ascii => "ascii",
            Format::BinaryLe => "binary_little_endian",
            Format::BinaryBe => "binary_big_endian",
        };
        let mut b = format!("ply\nformat {name} 1.0\nelement vertex {}\n", rows.len());
        for p in props {
            b += &format!("property {} {p}\n", if is_byte(p) { "uchar" } else { "float" });
        }
        let mut b = (b + "end_header\n").into_bytes();
        for row in rows {
            for (p, &v) in props.iter().zip(row) {
                match (is_byte(p), format) {
                    // Shortest round-trip decimals (and `NaN`, `inf`): the same f32 back.
                    (true, Format::Ascii) => b.extend_from_slice(format!("{} ", v as u8).as_bytes()),
                    (false, Format::Ascii) => b.extend_from_slice(format!("{v} ").as_bytes()),
                    (true, _) => b.push(v as u8),
                    (false, Format::BinaryLe) => b.extend_from_slice(&v.to_le_bytes()),
                    (false, Format::BinaryBe) => b.extend_from_slice(&v.to_be_bytes()),
                }
            }
            if format == Format::Ascii {
                b.push(b'\n');
            }
        }
        b
    }

    #[test]
    fn every_fast_layout_reads_as_the_general_path_and_rejects_non_finite_positions() {
        let layouts: [&[&str]; 6] = [
            &["x", "y", "z"],
            &["x", "y", "z", "red", "green", "blue"],
            &["red", "green", "blue", "x", "y", "z"],
            &["x", "y", "z", "nx", "ny", "nz"],
            &["nx", "ny", "nz", "x", "y", "z", "red", "green", "blue"],
            &["x", "y", "z", "red", "green", "blue", "nx", "ny", "nz"],
        ];
        let formats = [Format::BinaryLe, Format::BinaryBe, Format::Ascii];
        for props in layouts {
            let rows: Vec<Vec<f32>> =
                (0..37).map(|i| (0..props.len()).map(|k| (i * 7 + k * 31) as f32 * 0.75 % 255.0).collect()).collect();
            let general = read(&columns(props, &rows, Format::Ascii)).unwrap();
            for format in [Format::BinaryLe, Format::BinaryBe] {
                let fast = read(&columns(props, &rows, format)).unwrap();
                assert_eq!(fast, general, "{props:?} {format:?}");
                assert_eq!(fast.positions.len(), 37);
                assert_eq!(fast.normals.is_some(), props.contains(&"nx"), "{props:?}");
                assert_eq!(fast.colors.is_some(), props.contains(&"red"), "{props:?}");
            }
            // A NaN or infinity in any position component of any row is refused and named by its row.
            for (row, bad) in [(0, f32::NAN), (19, f32::INFINITY), (36, f32::NEG_INFINITY)] {
                for k in ["x", "y", "z"] {
                    let mut r = rows.clone();
                    r[row][props.iter().position(|p| *p == k).unwrap()] = bad;
                    for format in formats {
                        let e = read(&columns(props, &r, format)).unwrap_err();
                        assert!(matches!(e, PlyError::Body { row: r, .. } if r == row), "{props:?} {k} {row}: {e}");
                    }
                }
            }
            // Non-finite normals pass (they are not positions): the same as the general path.
            if let Some(k) = props.iter().position(|p| *p == "nx") {
                let mut r = rows.clone();
                r[3][k] = f32::NAN;
                for format in formats {
                    assert!(read(&columns(props, &r, format)).unwrap().normals.unwrap()[3][0].is_nan());
                }
            }
        }
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
