//! Wavefront OBJ frames (with MTL materials and `map_Kd` textures, vertex colours where present), as captured
//! volumetric video is distributed: one textured mesh per frame, the topology changing every frame.
//!
//! Parsing is `tobj`'s. Before it runs, one pass over the lines ([`scan`]) checks what tobj would report without
//! a place (a face index out of range, an `mtllib` or texture that does not exist) and names the file and line;
//! the same pass lists the files a frame depends on (its MTL files and textures), which key the frame.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use glam::{Vec2, Vec3, Vec4};

use super::material::{srgb_to_linear, Material};
use super::mtl;
use super::posed::{PosedPrimitive, PosedScene, PrimKind};
use super::texture::Texture;
use super::Error;

/// Largest texture side accepted (a corrupt header should not allocate gigabytes).
pub(crate) const MAX_TEXTURE_SIDE: u32 = 16_384;

fn at(path: &Path, line: usize, message: String) -> Error {
    Error::Mesh { path: path.to_path_buf(), line: Some(line), message }
}

/// An OBJ's lines with `origin` subtracted from each vertex position (`v x y z …`, the rest of the line kept), in
/// double precision, written back in the shortest decimals that read as the difference: what tobj then parses to
/// single precision is the position relative to `origin`. One line is held at a time.
struct Shifted<R> {
    inner: R,
    origin: [f64; 3],
    line: Vec<u8>,
    at: usize,
}

impl<R: std::io::BufRead> Shifted<R> {
    fn new(inner: R, origin: [f64; 3]) -> Self {
        Shifted { inner, origin, line: Vec::new(), at: 0 }
    }

    /// `line` with its position shifted, when it is a vertex line whose first three values are numbers;
    /// anything else as it was (tobj reports what it cannot read).
    fn shift(&self, line: &[u8]) -> Option<Vec<u8>> {
        let text = std::str::from_utf8(line).ok()?;
        let rest = text.strip_prefix('v')?;
        if !rest.starts_with([' ', '\t']) {
            return None;
        }
        let mut words = rest.split_ascii_whitespace();
        let mut out = String::from("v");
        for o in self.origin {
            let v: f64 = words.next()?.parse().ok()?;
            write!(out, " {}", v - o).expect("BUG: writing to a String cannot fail");
        }
        for w in words {
            out.push(' ');
            out.push_str(w);
        }
        out.push('\n');
        Some(out.into_bytes())
    }
}

impl<R: std::io::BufRead> std::io::Read for Shifted<R> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let got = std::io::BufRead::fill_buf(self)?;
        let n = got.len().min(buf.len());
        buf[..n].copy_from_slice(&got[..n]);
        std::io::BufRead::consume(self, n);
        Ok(n)
    }
}

impl<R: std::io::BufRead> std::io::BufRead for Shifted<R> {
    fn fill_buf(&mut self) -> std::io::Result<&[u8]> {
        if self.at == self.line.len() {
            self.line.clear();
            self.at = 0;
            self.inner.read_until(b'\n', &mut self.line)?;
            if let Some(shifted) = self.shift(&self.line) {
                self.line = shifted;
            }
        }
        Ok(&self.line[self.at..])
    }

    fn consume(&mut self, n: usize) {
        self.at = (self.at + n).min(self.line.len());
    }
}

/// Checks an OBJ's face indices, `mtllib` files and their `map_Kd` textures, naming file and line of the first
/// problem; returns the files the OBJ depends on (MTL files, then textures), in the order named.
pub fn scan(path: &Path) -> Result<Vec<PathBuf>, Error> {
    let text = std::fs::read(path).map_err(|e| Error::Io { path: path.to_path_buf(), source: e })?;
    resolve(path, &libraries(path, &text)?)
}

/// [`scan`], reading the OBJ only when the stat cache does not remember its libraries for its current content:
/// what the OBJ's text decides (face indices in range, which libraries it names) cannot change without its
/// content changing, so a build that keys unchanged frames reads none of them. The libraries and textures are
/// checked every time.
pub fn scan_cached(path: &Path, stat: &crate::cache::StatCache) -> Result<Vec<PathBuf>, Error> {
    let io = |e| Error::Io { path: path.to_path_buf(), source: e };
    let text = stat
        .derived("obj libraries 1", path, || {
            let bytes = std::fs::read(path).map_err(io)?;
            libraries(path, &bytes).map(|l| serde_json::to_string(&l).expect("BUG: a list of names serializes"))
        })
        .map_err(io)??;
    let libs: Vec<(usize, String)> = serde_json::from_str(&text).map_err(|e| Error::Mesh {
        path: path.to_path_buf(),
        line: None,
        message: format!("BUG: remembered libraries do not read back: {e}"),
    })?;
    resolve(path, &libs)
}

/// What an OBJ's text alone decides: every face index is in range (else an error at its line); returns the
/// `mtllib` names with their lines.
fn libraries(path: &Path, text: &[u8]) -> Result<Vec<(usize, String)>, Error> {
    let text = String::from_utf8_lossy(text);
    let (mut v, mut vt, mut vn) = (0i64, 0i64, 0i64);
    let mut libs = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let line_no = i + 1;
        let mut words = line.split_whitespace();
        match words.next() {
            Some("v") => v += 1,
            Some("vt") => vt += 1,
            Some("vn") => vn += 1,
            Some("f") => {
                for corner in words {
                    for (k, part) in corner.split('/').enumerate() {
                        if part.is_empty() {
                            continue;
                        }
                        let (what, n) = match k {
                            0 => ("vertex", v),
                            1 => ("texture coordinate", vt),
                            _ => ("normal", vn),
                        };
                        let idx: i64 = part.parse().map_err(|_| {
                            at(path, line_no, format!("face corner `{corner}`: `{part}` is not an index"))
                        })?;
                        // 1-based, or negative: relative to the last one defined.
                        let resolved = if idx < 0 { n + idx + 1 } else { idx };
                        if idx == 0 || resolved < 1 || resolved > n {
                            return Err(at(
                                path,
                                line_no,
                                format!(
                                    "face corner `{corner}` refers to {what} {idx}, but only {n} are defined above"
                                ),
                            ));
                        }
                    }
                }
            }
            Some("mtllib") => libs.push((line_no, line.trim_start()["mtllib".len()..].trim().to_string())),
            _ => {}
        }
    }
    Ok(libs)
}

/// The MTL files `libs` (named at their OBJ lines), each checked to exist, each followed by its textures.
fn resolve(path: &Path, libs: &[(usize, String)]) -> Result<Vec<PathBuf>, Error> {
    let dir = crate::scene::input::folder_of(path);
    let mut deps = Vec::new();
    for (line_no, name) in libs {
        let mtl = match mtl::locate(dir, name) {
            Ok(mtl) => mtl,
            Err(tried) => {
            let mut message = format!("material library `{name}` not found ({})", tried.display());
            // Libraries get renamed apart from the OBJ that names them: name the ones beside it.
            let beside = libraries_in(dir);
            message += &match beside.as_slice() {
                [] => format!("; put it there, or delete line {line_no} to render without materials"),
                found => format!(
                    "; beside it: {}. Point line {line_no} at one, or delete the line to render without materials",
                    found.iter().map(|f| format!("`{f}`")).collect::<Vec<_>>().join(", ")
                ),
            };
            return Err(at(path, *line_no, message));
            }
        };
        deps.push(mtl.clone());
        deps.extend(scan_mtl(&mtl)?);
    }
    Ok(deps)
}

/// The names of the material libraries (`.mtl`, any case, or a shortened `.mt`) in folder `dir`, sorted; at
/// most five.
fn libraries_in(dir: &Path) -> Vec<String> {
    let mut found: Vec<String> = std::fs::read_dir(dir)
        .into_iter()
        .flatten()
        .flatten()
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| {
            let ext = n.rsplit_once('.').map(|(_, e)| e.to_ascii_lowercase());
            matches!(ext.as_deref(), Some("mtl" | "mt"))
        })
        .collect();
    found.sort();
    found.truncate(5);
    found
}

/// The textures of an MTL file that vvgen reads ([`mtl::MAPS`]), each checked to exist; and the numbers tobj reads, checked here with
/// their line: tobj panics on a colour with fewer than three numbers and names no line for one it cannot parse,
/// and a number that is not finite (which it accepts) would reach the images.
fn scan_mtl(path: &Path) -> Result<Vec<PathBuf>, Error> {
    let text = std::fs::read(path).map_err(|e| Error::Io { path: path.to_path_buf(), source: e })?;
    let text = String::from_utf8_lossy(&text);
    let dir = crate::scene::input::folder_of(path);
    let mut out = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let mut words = line.split_whitespace();
        let key = words.next();
        let count = match key {
            Some(k @ ("Ka" | "Kd" | "Ks" | "Ke")) => Some((k, 3)),
            Some(k @ ("Ns" | "Ni" | "d")) => Some((k, 1)),
            _ => None,
        };
        if let Some((key, n)) = count {
            // tobj reads the first `n` words as numbers and ignores the rest.
            let finite = words.clone().take(n).filter(|w| w.parse::<f32>().is_ok_and(f32::is_finite)).count();
            if finite < n {
                let what = if n == 1 { "a finite number".to_string() } else { format!("{n} finite numbers") };
                return Err(at(path, i + 1, format!("`{key}` needs {what}: `{}`", line.trim())));
            }
        }
        if let Some(key) = key.filter(|k| mtl::MAPS.contains(k)) {
            // Options (`-bm 0.5`, `-s 1 1 1`, …) come first; the rest of the line is the file's name.
            let Some(map) = mtl::TexMap::parse(&line.trim_start()[key.len()..]) else {
                return Err(at(path, i + 1, format!("`{key}` names no file")));
            };
            match mtl::locate(dir, &map.name) {
                Ok(tex) => out.push(tex),
                Err(tried) => {
                    return Err(at(path, i + 1, format!("texture `{}` not found ({})", map.name, tried.display())))
                }
            }
        }
    }
    Ok(out)
}

/// An OBJ frame as a posed scene in source space: one primitive per object, one material per MTL material (as
/// Blender 4.5's importer builds it: [`mtl`]), drawn double-sided (captures rarely wind consistently).
pub fn scene(path: &Path) -> Result<PosedScene, Error> {
    scene_at(path, [0.0; 3])
}

/// [`scene`] with `origin` subtracted from the vertex positions as their lines are read, in double precision:
/// photogrammetry exports (OpenDroneMap's, a drone survey's) write positions in georeferenced metres, whose
/// decimals hold detail that single precision, which positions are held in, steps (0.25 m at 4 000 km).
pub fn scene_at(path: &Path, origin: [f64; 3]) -> Result<PosedScene, Error> {
    scan(path)?;
    let fail = |message: String| Error::Mesh { path: path.to_path_buf(), line: None, message };
    let options = tobj::LoadOptions { single_index: true, triangulate: true, ..Default::default() };
    let dir = crate::scene::input::folder_of(path);
    // Each material's MTL folder, in tobj's order (it appends each library's materials as it loads them): their
    // textures are named relative to it. Libraries are found as `scan` found them.
    let folders = std::cell::RefCell::new(Vec::new());
    let load_library = |name: &Path| {
        let file = mtl::locate(dir, &name.to_string_lossy()).map_err(|_| tobj::LoadError::OpenFileFailed)?;
        let mut reader = std::io::BufReader::new(std::fs::File::open(&file).map_err(|_| tobj::LoadError::OpenFileFailed)?);
        let loaded = tobj::load_mtl_buf(&mut reader)?;
        folders.borrow_mut().extend(std::iter::repeat_n(crate::scene::input::folder_of(&file).to_path_buf(), loaded.0.len()));
        Ok(loaded)
    };
    let reader =
        std::io::BufReader::new(std::fs::File::open(path).map_err(|e| Error::Io { path: path.to_path_buf(), source: e })?);
    let (models, materials) = if origin == [0.0; 3] {
        tobj::load_obj_buf(&mut { reader }, &options, load_library)
    } else {
        tobj::load_obj_buf(&mut Shifted::new(reader, origin), &options, load_library)
    }
    .map_err(|e| fail(e.to_string()))?;
    let materials = materials.map_err(|e| fail(format!("its material library: {e}")))?;
    let folders = folders.into_inner();
    let mut images = mtl::Images::default();
    let mut mats: Vec<Material> = Vec::new();
    for (k, m) in materials.iter().enumerate() {
        mats.push(mtl::material(m, folders.get(k).map_or(dir, |d| d.as_path()), &mut images)?);
    }
    let textures = images.into_textures();
    // Faces without a material: white where the file gives vertex colours, else Blender's grey.
    let plain = mats.len() as u32;
    mats.push(Material { double_sided: true, ..Material::default() });
    mats.push(Material { double_sided: true, ..Material::unassigned() });
    let mut primitives = Vec::new();
    for (object, model) in models.iter().enumerate() {
        let m = &model.mesh;
        let positions: Vec<Vec3> = m.positions.chunks_exact(3).map(|p| Vec3::new(p[0], p[1], p[2])).collect();
        if positions.iter().any(|p| !p.is_finite()) {
            return Err(fail(format!("object `{}` has a vertex that is not finite", model.name)));
        }
        let indices = m.indices.clone();
        let normals = if m.normals.len() == m.positions.len() {
            m.normals.chunks_exact(3).map(|n| Vec3::new(n[0], n[1], n[2]).normalize_or_zero()).collect()
        } else {
            super::gltf::load::smooth_normals(&positions, &indices)
        };
        // OBJ's v runs up from the bottom row; textures here are stored top row first.
        let uvs: Vec<Vec2> = if m.texcoords.len() / 2 == positions.len() {
            m.texcoords.chunks_exact(2).map(|t| Vec2::new(t[0], 1.0 - t[1])).collect()
        } else {
            Vec::new()
        };
        let colors: Vec<Vec4> = if m.vertex_color.len() == m.positions.len() {
            m.vertex_color
                .chunks_exact(3)
                .map(|c| Vec4::new(srgb_to_linear(c[0]), srgb_to_linear(c[1]), srgb_to_linear(c[2]), 1.0))
                .collect()
        } else {
            Vec::new()
        };
        let material = m.material_id.map_or(plain + u32::from(colors.is_empty()), |i| i as u32);
        // A normal map needs tangents, MikkTSpace's as Blender's.
        let normal_map = mats.get(material as usize).is_some_and(|m| m.normal_texture.is_some());
        let tangents = if normal_map && !uvs.is_empty() && !indices.is_empty() {
            super::gltf::mikktspace(&positions, &normals, &uvs, &indices)
        } else {
            Vec::new()
        };
        primitives.push(PosedPrimitive {
            kind: if indices.is_empty() { PrimKind::Points } else { PrimKind::Triangles },
            positions,
            normals,
            tangents,
            uvs: Arc::new(uvs),
            colors: Arc::new(colors),
            indices: Arc::new(indices),
            material,
            object: object as u32,
            gaussians: None,
        });
    }
    Ok(PosedScene { primitives, materials: Arc::new(mats), textures: Arc::new(textures), lights: Vec::new() })
}

/// A warning naming the MTL materials of OBJ `path` that are wholly transparent (`d 0`, no `map_d`): nothing of
/// them shows, as in Blender, and exporters that write `d` as a transparency (`Tr`'s sense) write it for opaque
/// surfaces. Reads the libraries the OBJ names before its first vertex, where exporters write them: the head of
/// the file, not the frame (a build with nothing to do reads no frame in full).
pub fn unseen_materials(path: &Path) -> Result<Vec<String>, Error> {
    use std::io::BufRead;
    let io = |p: &Path| {
        let path = p.to_path_buf();
        move |e| Error::Io { path, source: e }
    };
    let mut head = std::io::BufReader::new(std::fs::File::open(path).map_err(io(path))?);
    let dir = crate::scene::input::folder_of(path);
    let (mut libs, mut line) = (Vec::new(), Vec::new());
    loop {
        line.clear();
        if head.read_until(b'\n', &mut line).map_err(io(path))? == 0 {
            break;
        }
        let text = String::from_utf8_lossy(&line);
        match text.split_whitespace().next() {
            Some("v" | "vt" | "vn" | "f") => break,
            Some("mtllib") => libs.extend(mtl::locate(dir, text.trim_start()["mtllib".len()..].trim()).ok()),
            _ => {}
        }
    }
    let mut unseen = Vec::new();
    for lib in libs {
        let text = std::fs::read(&lib).map_err(io(&lib))?;
        // (name, d ≤ 0, map_d) of each material, in one pass over its lines; the `newmtl` added at the end closes
        // the last one.
        let mut current: Option<(String, bool, bool)> = None;
        for line in String::from_utf8_lossy(&text).lines().chain(["newmtl"]) {
            let mut words = line.split_whitespace();
            match (words.next(), &mut current) {
                (Some("newmtl"), _) => {
                    unseen.extend(current.take().filter(|&(_, zero, map)| zero && !map).map(|(n, ..)| format!("`{n}`")));
                    current = Some((line.trim_start()["newmtl".len()..].trim().to_string(), false, false));
                }
                (Some("d"), Some(m)) => m.1 = words.next().and_then(|w| w.parse::<f32>().ok()).is_some_and(|d| d <= 0.0),
                (Some("map_d"), Some(m)) => m.2 = true,
                _ => {}
            }
        }
    }
    if unseen.is_empty() {
        return Ok(Vec::new());
    }
    let (what, has) = if unseen.len() == 1 { ("material", "has") } else { ("materials", "have") };
    Ok(vec![format!(
        "{}: {what} {} {has} `d 0`, wholly transparent: nothing of it shows, as in Blender. If the file means it \
         opaque (some exporters write `d` as a transparency, `Tr`'s sense), set `d 1` in its MTL",
        path.display(),
        unseen.join(", "),
    )])
}

/// An image file as an sRGB base-colour texture.
pub fn texture(path: &Path) -> Result<Texture, Error> {
    texture_and_alpha(path).map(|(t, _)| t)
}

/// [`texture`], and whether the image has an alpha channel (used or not: importers decide by the channel).
pub fn texture_and_alpha(path: &Path) -> Result<(Texture, bool), Error> {
    let img = image(path)?;
    let alpha = img.color().has_alpha();
    let img = img.into_rgba8();
    Ok((Texture::new(img.width(), img.height(), img.into_raw(), true), alpha))
}

/// An image file, decoded within [`MAX_TEXTURE_SIDE`].
pub(crate) fn image(path: &Path) -> Result<image::DynamicImage, Error> {
    let fail = |message: String| Error::Mesh { path: path.to_path_buf(), line: None, message };
    let mut reader = image::ImageReader::open(path)
        .map_err(|e| Error::Io { path: path.to_path_buf(), source: e })?
        .with_guessed_format()
        .map_err(|e| Error::Io { path: path.to_path_buf(), source: e })?;
    let mut limits = image::Limits::default();
    limits.max_image_width = Some(MAX_TEXTURE_SIDE);
    limits.max_image_height = Some(MAX_TEXTURE_SIDE);
    reader.limits(limits);
    reader.decode().map_err(|e| fail(format!("cannot decode the texture: {e}")))
}
