//! Wavefront OBJ frames (with MTL materials and `map_Kd` textures, vertex colours where present), as captured
//! volumetric video is distributed: one textured mesh per frame, the topology changing every frame.
//!
//! Parsing is `tobj`'s, of the text as [`obj_text`] hands it on (UTF-8, edited where tobj and Blender's importer
//! disagree). Before it runs, one pass over the lines ([`scan`]) checks what tobj would report without a place (a
//! face index out of range) and names the file and line (a number tobj cannot parse is looked for once it has
//! failed); the same pass lists the files a frame depends on (its MTL files and textures), which key the frame.
//! A library or texture named and missing is left out, as Blender's importer leaves it, and said ([`missing`]).

use std::path::{Path, PathBuf};
use std::sync::Arc;

use glam::{Vec2, Vec3, Vec4};

use super::material::{srgb_to_linear, Material};
use super::mtl;
use super::obj_text::{self, Edit, Lines};
use super::posed::{PosedPrimitive, PosedScene, PrimKind};
use super::texture::Texture;
use super::Error;

/// Largest texture side accepted (a corrupt header should not allocate gigabytes).
pub(crate) const MAX_TEXTURE_SIDE: u32 = 16_384;

fn at(path: &Path, line: usize, message: String) -> Error {
    Error::Mesh { path: path.to_path_buf(), line: Some(line), message }
}

/// Checks an OBJ's face indices, `mtllib` files and their `map_Kd` textures, naming file and line of
/// the first problem; returns the files the OBJ depends on (MTL files, then textures), in the order named.
pub fn scan(path: &Path) -> Result<Vec<PathBuf>, Error> {
    scan_text(path).map(|(deps, ..)| deps.files)
}

/// [`scan`], what the OBJ's text says of its vertices' colours, and its bytes.
fn scan_text(path: &Path) -> Result<(Deps, Text, Vec<u8>), Error> {
    let bytes = std::fs::read(path).map_err(|e| Error::Io { path: path.to_path_buf(), source: e })?;
    let text = read_text(path, &bytes)?;
    Ok((resolve(path, &text.libs)?, text, bytes))
}

/// [`scan`], reading the OBJ only when the stat cache does not remember its libraries for its current content:
/// what the OBJ's text decides (face indices in range, which libraries it names) cannot change without its
/// content changing, so a build that keys unchanged frames reads none of them. The libraries and textures are
/// checked every time.
pub fn scan_cached(path: &Path, stat: &crate::cache::StatCache) -> Result<Vec<PathBuf>, Error> {
    let (libs, ..) = remembered(path, stat)?;
    resolve(path, &libs).map(|d| d.files)
}

/// Whether OBJ `path` has polylines of three or more vertices, remembered as [`scan_cached`] remembers its
/// libraries: tobj filled them as polygons until "obj polylines 1", so a frame with them is keyed apart.
pub fn polylines_cached(path: &Path, stat: &crate::cache::StatCache) -> Result<bool, Error> {
    remembered(path, stat).map(|(_, polylines, _)| polylines)
}

/// Whether OBJ `path` is a point cloud (vertices alone: [`scene_at`] draws them as points), remembered as
/// [`scan_cached`] remembers its libraries: a sequence's frames are keyed before they are read, and whether they
/// hold points keys their light.
pub fn cloud_cached(path: &Path, stat: &crate::cache::StatCache) -> Result<bool, Error> {
    remembered(path, stat).map(|(.., cloud)| cloud)
}

/// What the stat cache remembers of an OBJ's content: its `mtllib` names with their lines, whether it has
/// polylines of three or more vertices, and whether it is a point cloud.
type Remembered = (Vec<(usize, String)>, bool, bool);

/// The `mtllib` names (with their lines) of OBJ `path`, whether it has polylines of three or more vertices and
/// whether it is a point cloud, from the stat cache for its current content, else read.
fn remembered(path: &Path, stat: &crate::cache::StatCache) -> Result<Remembered, Error> {
    let io = |e| Error::Io { path: path.to_path_buf(), source: e };
    let text = stat
        // "3": the scan has checked numbers, counted polylines, read the text as `obj_text` decodes it, and told a
        // point cloud.
        .derived("obj libraries 3", path, || {
            let bytes = std::fs::read(path).map_err(io)?;
            read_text(path, &bytes).map(|t| {
                serde_json::to_string(&(&t.libs, t.polylines > 0, t.cloud())).expect("BUG: a list of names serializes")
            })
        })
        .map_err(io)??;
    serde_json::from_str(&text).map_err(|e| Error::Mesh {
        path: path.to_path_buf(),
        line: None,
        message: format!("BUG: remembered libraries do not read back: {e}"),
    })
}

/// What an OBJ's text alone decides, once checked.
struct Text {
    /// The `mtllib` names with their lines.
    libs: Vec<(usize, String)>,
    /// Whether some vertices have a colour and others not (see [`Edit::Obj`]).
    partial_colours: bool,
    /// How many vertices (`v`), faces (`f`) and polylines (`l`) it has, and how many of those have three or more
    /// vertices (tobj filled them as polygons until [`Edit::Obj`] dropped them).
    vertices: i64,
    faces: usize,
    lines: usize,
    polylines: usize,
    /// Whether a face corner's texture coordinate or normal index is out of range (see [`Edit::Obj`]).
    bad_corners: bool,
}

impl Text {
    /// Whether it is a point cloud: vertices and nothing else drawn from them (MeshLab and CloudCompare write
    /// clouds so).
    fn cloud(&self) -> bool {
        self.vertices > 0 && self.faces == 0 && self.lines == 0
    }
}

/// Reads an OBJ's text (decoded as tobj will be given it: [`obj_text`]): every face's vertex index is in range,
/// else an error at the line.
fn read_text(path: &Path, bytes: &[u8]) -> Result<Text, Error> {
    let text = obj_text::decode(bytes);
    let (mut v, mut vt, mut vn) = (0i64, 0i64, 0i64);
    let (mut coloured, mut plain) = (false, false);
    let (mut libs, mut faces, mut lines, mut polylines, mut bad_corners) = (Vec::new(), 0, 0, 0, false);
    for (i, line) in text.lines().enumerate() {
        let line_no = i + 1;
        let mut words = line.split_whitespace();
        let key = words.next();
        if key == Some("v") {
            // x y z, then w or a colour (tobj reads either).
            let count = words.clone().take(6).count();
            coloured |= count == 6;
            plain |= count == 3;
        }
        match key {
            Some("v") => v += 1,
            Some("vt") => vt += 1,
            Some("vn") => vn += 1,
            Some(k @ ("f" | "l")) => {
                if k == "f" {
                    faces += 1;
                } else {
                    lines += 1;
                    polylines += usize::from(words.clone().count() >= 3);
                }
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
                        // A texture coordinate or normal out of range is dropped, as Blender drops it.
                        if k > 0 && (idx == 0 || resolved < 1 || resolved > n) {
                            bad_corners = true;
                            continue;
                        }
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
    Ok(Text { libs, partial_colours: coloured && plain, vertices: v, faces, lines, polylines, bad_corners })
}

/// The first number of a vertex, texture coordinate or normal in OBJ `path` that does not parse as tobj parses it
/// (which names no line), as an error at its line; `None` if all do. Looked for only once tobj has failed: the
/// good path parses each number once.
fn bad_number(path: &Path) -> Option<Error> {
    let bytes = std::fs::read(path).ok()?;
    for (i, line) in obj_text::decode(&bytes).lines().enumerate() {
        let mut words = line.split_whitespace();
        let (k, needed, most) = match words.next() {
            Some(k @ "v") => (k, 3, 6),
            Some(k @ "vt") => (k, 2, 2),
            Some(k @ "vn") => (k, 3, 3),
            _ => continue,
        };
        let numbers: Vec<&str> = words.take(most).collect();
        if let Some(bad) = numbers.iter().find(|w| w.parse::<f32>().is_err()) {
            return Some(at(path, i + 1, format!("`{bad}` is not a number, in `{}`", line.trim())));
        }
        if numbers.len() < needed {
            return Some(at(path, i + 1, format!("`{k}` needs {needed} numbers: `{}`", line.trim())));
        }
    }
    None
}

/// The files an OBJ reads besides itself, and what it names that is missing.
struct Deps {
    /// The MTL files `libs` names that exist, each followed by the textures it names that exist.
    files: Vec<PathBuf>,
    /// A warning for each library or texture named and missing, naming file and line ([`missing`]).
    missing: Vec<String>,
}

/// The MTL files `libs` (named at their OBJ lines) and their textures, as [`Deps`]. A missing library or texture
/// is left out, as Blender's importer leaves it (the OBJ renders without the library's materials, a material
/// without the texture), and said.
fn resolve(path: &Path, libs: &[(usize, String)]) -> Result<Deps, Error> {
    let dir = crate::scene::input::folder_of(path);
    let mut deps = Deps { files: Vec::new(), missing: Vec::new() };
    for (line_no, name) in libs {
        let mtl = match mtl::locate(dir, name) {
            Ok(mtl) => mtl,
            Err(tried) => {
                let mut message = format!(
                    "material library `{name}` not found ({}), so what it would colour renders in Blender's grey, \
                     as in Blender",
                    tried.display()
                );
                // Libraries get renamed apart from the OBJ that names them: name the ones beside it.
                message += &match libraries_in(dir).as_slice() {
                    [] => "; put it there to use it".to_string(),
                    found => format!(
                        "; beside it: {}. Point line {line_no} at one to use it",
                        found.iter().map(|f| format!("`{f}`")).collect::<Vec<_>>().join(", ")
                    ),
                };
                deps.missing.push(at(path, *line_no, message).to_string());
                continue;
            }
        };
        deps.files.push(mtl.clone());
        scan_mtl(&mtl, &mut deps)?;
    }
    Ok(deps)
}

/// Warnings for the material libraries and textures OBJ `path` names and that are missing (see [`resolve`]).
pub fn missing(path: &Path) -> Result<Vec<String>, Error> {
    scan_text(path).map(|(deps, ..)| deps.missing)
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

/// Adds to `deps` the textures of an MTL file that vvgen reads ([`mtl::MAPS`]) that exist, and a warning for each
/// that does not; and checks the numbers tobj reads, with their line: tobj panics on a colour with fewer than
/// three numbers and names no line for one it cannot parse, and a number that is not finite (which it accepts)
/// would reach the images.
fn scan_mtl(path: &Path, deps: &mut Deps) -> Result<(), Error> {
    let text = std::fs::read(path).map_err(|e| Error::Io { path: path.to_path_buf(), source: e })?;
    let text = obj_text::decode(&text);
    let dir = crate::scene::input::folder_of(path);
    for (i, line) in text.lines().enumerate() {
        let mut words = line.split_whitespace();
        let key = words.next();
        let count = match key {
            // One number is a grey, as the format reads it (written out for tobj: `Edit::Mtl`).
            Some(k @ ("Ka" | "Kd" | "Ks" | "Ke")) => Some((k, if words.clone().count() == 1 { 1 } else { 3 })),
            Some(k @ ("Ns" | "Ni" | "d")) => Some((k, 1)),
            _ => None,
        };
        if let Some((key, n)) = count {
            // tobj reads the first `n` words as numbers and ignores the rest.
            let finite = words.clone().take(n).filter(|w| w.parse::<f32>().is_ok_and(f32::is_finite)).count();
            if finite < n {
                let what = match (n, key) {
                    (1, "Ns" | "Ni" | "d") => "a finite number",
                    (1, _) => "a finite number (a grey)",
                    _ => "3 finite numbers (or one, a grey)",
                };
                return Err(at(path, i + 1, format!("`{key}` needs {what}: `{}`", line.trim())));
            }
        }
        if let Some(key) = key.filter(|k| mtl::MAPS.contains(k)) {
            // Options (`-bm 0.5`, `-s 1 1 1`, …) come first; the rest of the line is the file's name.
            let Some(map) = mtl::TexMap::parse(&line.trim_start()[key.len()..]) else {
                return Err(at(path, i + 1, format!("`{key}` names no file")));
            };
            match mtl::locate(dir, &map.name) {
                Ok(tex) => deps.files.push(tex),
                Err(tried) => deps.missing.push(
                    at(
                        path,
                        i + 1,
                        format!(
                            "texture `{}` not found ({}), so its material renders without it (Blender shows its \
                             missing-image magenta); put it there to use it",
                            map.name,
                            tried.display()
                        ),
                    )
                    .to_string(),
                ),
            }
        }
    }
    Ok(())
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
    scene_and_missing(path, origin).map(|(scene, _)| scene)
}

/// [`scene_at`], and the warnings [`missing`] gives, from the same reading of the file.
pub(crate) fn scene_and_missing(path: &Path, origin: [f64; 3]) -> Result<(PosedScene, Vec<String>), Error> {
    let (deps, text, bytes) = scan_text(path)?;
    if text.cloud() {
        return Ok((cloud(path, origin, &bytes)?, deps.missing));
    }
    let fail = |message: String| Error::Mesh { path: path.to_path_buf(), line: None, message };
    // Polygons are filled here ([`super::polygon`]): tobj's own fan fills a concave one wrongly.
    let options = tobj::LoadOptions { single_index: true, triangulate: false, ..Default::default() };
    let dir = crate::scene::input::folder_of(path);
    // Each material's MTL folder, in tobj's order (it appends each library's materials as it loads them): their
    // textures are named relative to it. Libraries are found as `scan` found them.
    let folders = std::cell::RefCell::new(Vec::new());
    let load_library = |name: &Path| {
        // A missing library is none (said by `missing`), as in Blender.
        let Ok(file) = mtl::locate(dir, &name.to_string_lossy()) else { return Ok(Default::default()) };
        let opened = std::fs::File::open(&file).map_err(|_| tobj::LoadError::OpenFileFailed)?;
        let loaded = tobj::load_mtl_buf(&mut Lines::new(std::io::BufReader::new(opened), Edit::Mtl))?;
        let folder = crate::scene::input::folder_of(&file).to_path_buf();
        folders.borrow_mut().extend(std::iter::repeat_n(folder, loaded.0.len()));
        Ok(loaded)
    };
    // tobj reads the bytes the scan read, not the file a second time.
    let reader = &bytes[..];
    let edit = Edit::Obj { origin, pad_colours: text.partial_colours, fix_corners: text.bad_corners };
    let (models, materials) =
        tobj::load_obj_buf(&mut Lines::new(reader, edit), &options, load_library).map_err(|e| {
            use tobj::LoadError::{NormalParseError, PositionParseError, TexcoordParseError};
            match e {
                PositionParseError | TexcoordParseError | NormalParseError => bad_number(path),
                _ => None,
            }
            .unwrap_or_else(|| fail(e.to_string()))
        })?;
    let materials = materials.map_err(|e| fail(format!("its material library: {e}")))?;
    if text.faces == 0 && text.vertices > 0 {
        // A wireframe: Blender imports loose vertices and edges, which Cycles does not draw.
        return Err(fail(format!(
            "{} vertices, {} lines and no faces: nothing to draw (vvgen draws no lines; Blender imports them as \
             loose vertices and edges, which it does not render either). Without its `l` lines, vvgen draws its \
             vertices as a point cloud",
            text.vertices, text.lines
        )));
    }
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
    let mut scratch = super::polygon::Scratch::default();
    for (object, model) in models.iter().enumerate() {
        let m = &model.mesh;
        let positions: Vec<Vec3> = m.positions.chunks_exact(3).map(|p| Vec3::new(p[0], p[1], p[2])).collect();
        if positions.iter().any(|p| !p.is_finite()) {
            return Err(fail(format!("object `{}` has a vertex that is not finite", model.name)));
        }
        let indices = if m.face_arities.is_empty() {
            m.indices.clone()
        } else {
            let mut tris = Vec::with_capacity(m.indices.len() * 3 / 2);
            let mut at = 0;
            for &n in &m.face_arities {
                let poly = m.indices.get(at..at + n as usize).unwrap_or(&[]);
                super::polygon::triangulate(&positions, poly, &mut scratch, &mut tris);
                at += n as usize;
            }
            tris
        };
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
        // Colours of NaN mark vertices without one: Blender keeps no colours on an object with such vertices.
        let whole = m.vertex_color.len() == m.positions.len() && !m.vertex_color.iter().any(|c| c.is_nan());
        let colors: Vec<Vec4> = if whole {
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
    let scene = PosedScene { primitives, materials: Arc::new(mats), textures: Arc::new(textures), lights: Vec::new() };
    Ok((scene, deps.missing))
}

/// An OBJ of vertices alone (a point cloud, as MeshLab and CloudCompare write one) as points, drawn as a PLY cloud
/// is (Blender imports them as loose vertices, which it does not render): white, or each vertex's colour when every
/// vertex has one (`v x y z r g b`, sRGB in 0..1). Positions are read in double precision, `origin` subtracted.
fn cloud(path: &Path, origin: [f64; 3], bytes: &[u8]) -> Result<PosedScene, Error> {
    let (mut positions, mut colours, mut every) = (Vec::new(), Vec::new(), true);
    for (i, line) in obj_text::decode(bytes).lines().enumerate() {
        let mut words = line.split_whitespace();
        if words.next() != Some("v") {
            continue;
        }
        // Up to six numbers (x y z, then a colour), without an allocation per vertex (clouds run to millions).
        let (mut read, mut count) = ([0.0f64; 6], 0);
        for (slot, w) in read.iter_mut().zip(words) {
            match w.parse::<f64>() {
                Ok(v) => (*slot, count) = (v, count + 1),
                Err(_) => break,
            }
        }
        let numbers = &read[..count];
        let p = match *numbers {
            [x, y, z, ..] => Vec3::new((x - origin[0]) as f32, (y - origin[1]) as f32, (z - origin[2]) as f32),
            _ => return Err(at(path, i + 1, format!("`v` needs three numbers: `{}`", line.trim()))),
        };
        if !p.is_finite() {
            return Err(at(path, i + 1, format!("a vertex that is not finite: `{}`", line.trim())));
        }
        positions.push(p);
        match *numbers {
            [_, _, _, r, g, b] => {
                let c = |v: f64| srgb_to_linear(v as f32);
                colours.push(Vec4::new(c(r), c(g), c(b), 1.0));
            }
            _ => every = false,
        }
    }
    if !every {
        colours.clear();
    }
    let normals = vec![Vec3::ZERO; positions.len()];
    let material = Material { double_sided: true, ..Material::default() };
    Ok(PosedScene::single(PrimKind::Points, positions, normals, colours, Vec::new(), material))
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
    let head = std::io::BufReader::new(std::fs::File::open(path).map_err(io(path))?);
    let mut head = Lines::new(head, Edit::OBJ_AS_IS);
    let dir = crate::scene::input::folder_of(path);
    let (mut libs, mut text) = (Vec::new(), String::new());
    loop {
        text.clear();
        if head.read_line(&mut text).map_err(io(path))? == 0 {
            break;
        }
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
        for line in obj_text::decode(&text).lines().chain(["newmtl"]) {
            let mut words = line.split_whitespace();
            match (words.next(), &mut current) {
                (Some("newmtl"), _) => {
                    let shows_nothing = current.take().filter(|&(_, zero, map)| zero && !map);
                    unseen.extend(shows_nothing.map(|(n, ..)| format!("`{n}`")));
                    current = Some((line.trim_start()["newmtl".len()..].trim().to_string(), false, false));
                }
                (Some("d"), Some(m)) => {
                    m.1 = words.next().and_then(|w| w.parse::<f32>().ok()).is_some_and(|d| d <= 0.0);
                }
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
         opaque (some exporters write `d` as a transparency, `Tr`'s sense), set `opaque = true` on the source, or \
         `d 1` in its MTL",
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
