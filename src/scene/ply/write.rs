//! Encoding points (and triangles) as PLY: binary little endian or ascii.

use std::fmt::Write as _;
use std::io::Write;

/// Points (and optional triangles) to write.
#[derive(Debug, Clone, Copy, Default)]
pub struct PlyOut<'a> {
    /// Positions.
    pub positions: &'a [[f32; 3]],
    /// Normals (`nx ny nz` float).
    pub normals: Option<&'a [[f32; 3]]>,
    /// Colours (`red green blue` uchar).
    pub colors: Option<&'a [[u8; 3]]>,
    /// Extra per-vertex `uint` properties, e.g. `point_id`.
    pub extra_u32: &'a [(&'a str, &'a [u32])],
    /// Extra per-vertex `float` properties, e.g. motion vectors.
    pub extra_f32: &'a [(&'a str, &'a [f32])],
    /// Triangles (`face` element, `list uchar int vertex_indices`).
    pub triangles: Option<&'a [u32]>,
    /// `comment` lines.
    pub comments: &'a [&'a str],
    /// Write `ascii` instead of `binary_little_endian`.
    pub ascii: bool,
}

/// Encodes a PLY; the header lists exactly the properties written.
pub fn write(out: &PlyOut<'_>) -> Vec<u8> {
    let n = out.positions.len();
    let mut h = String::from("ply\n");
    h.push_str(if out.ascii { "format ascii 1.0\n" } else { "format binary_little_endian 1.0\n" });
    for c in out.comments {
        let _ = writeln!(h, "comment {c}");
    }
    let _ = writeln!(h, "element vertex {n}");
    h.push_str("property float x\nproperty float y\nproperty float z\n");
    if out.normals.is_some() {
        h.push_str("property float nx\nproperty float ny\nproperty float nz\n");
    }
    if out.colors.is_some() {
        h.push_str("property uchar red\nproperty uchar green\nproperty uchar blue\n");
    }
    for (name, _) in out.extra_u32 {
        let _ = writeln!(h, "property uint {name}");
    }
    for (name, _) in out.extra_f32 {
        let _ = writeln!(h, "property float {name}");
    }
    let tris = out.triangles.unwrap_or(&[]);
    if out.triangles.is_some() {
        let _ = writeln!(h, "element face {}\nproperty list uchar int vertex_indices", tris.len() / 3);
    }
    h.push_str("end_header\n");
    let mut buf = Vec::with_capacity(h.len() + n * 40);
    buf.extend_from_slice(h.as_bytes());
    if out.ascii {
        let mut fmt = ryu::Buffer::new();
        let mut put = |buf: &mut Vec<u8>, v: f32| {
            // Integer values (8i's vox10 coordinates) are written as integers, like 8i's files; others in the
            // shortest form that reads back to the same f32.
            if v.fract() == 0.0 && v.abs() < 1e7 {
                let _ = write!(buf, "{}", v as i64);
            } else {
                buf.extend_from_slice(fmt.format(v).as_bytes());
            }
        };
        for i in 0..n {
            let mut first = true;
            let mut sep = |buf: &mut Vec<u8>| {
                if !first {
                    buf.push(b' ');
                }
                first = false;
            };
            for v in out.positions[i] {
                sep(&mut buf);
                put(&mut buf, v);
            }
            if let Some(nr) = out.normals {
                for v in nr[i] {
                    sep(&mut buf);
                    put(&mut buf, v);
                }
            }
            if let Some(c) = out.colors {
                for v in c[i] {
                    sep(&mut buf);
                    let _ = write!(buf, "{v}");
                }
            }
            for (_, v) in out.extra_u32 {
                sep(&mut buf);
                let _ = write!(buf, "{}", v[i]);
            }
            for (_, v) in out.extra_f32 {
                sep(&mut buf);
                put(&mut buf, v[i]);
            }
            buf.push(b'\n');
        }
        for t in tris.chunks_exact(3) {
            let _ = writeln!(buf, "3 {} {} {}", t[0], t[1], t[2]);
        }
    } else {
        // Exact-size rows filled in place: no per-value capacity checks.
        let row = 12
            + out.normals.map_or(0, |_| 12)
            + out.colors.map_or(0, |_| 3)
            + 4 * (out.extra_u32.len() + out.extra_f32.len());
        let start = buf.len();
        buf.resize(start + row * n, 0);
        let rows = buf[start..].chunks_exact_mut(row);
        if out.normals.is_none() && out.extra_u32.is_empty() && out.extra_f32.is_empty() {
            // The common layouts (x y z [red green blue]) with fixed offsets, so the loop compiles to plain stores.
            for (i, r) in rows.enumerate() {
                let p = out.positions[i];
                r[0..4].copy_from_slice(&p[0].to_le_bytes());
                r[4..8].copy_from_slice(&p[1].to_le_bytes());
                r[8..12].copy_from_slice(&p[2].to_le_bytes());
                if let Some(c) = out.colors {
                    r[12..15].copy_from_slice(&c[i]);
                }
            }
        } else {
            for (i, r) in rows.enumerate() {
                let mut o = 0;
                let mut put = |bytes: &[u8]| {
                    r[o..o + bytes.len()].copy_from_slice(bytes);
                    o += bytes.len();
                };
                for v in out.positions[i] {
                    put(&v.to_le_bytes());
                }
                if let Some(nr) = out.normals {
                    for v in nr[i] {
                        put(&v.to_le_bytes());
                    }
                }
                if let Some(c) = out.colors {
                    put(&c[i]);
                }
                for (_, v) in out.extra_u32 {
                    put(&v[i].to_le_bytes());
                }
                for (_, v) in out.extra_f32 {
                    put(&v[i].to_le_bytes());
                }
            }
        }
        for t in tris.chunks_exact(3) {
            buf.push(3);
            for &i in t {
                buf.extend_from_slice(&(i as i32).to_le_bytes());
            }
        }
    }
    buf
}
