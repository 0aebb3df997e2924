//! A PLY file as a posed scene in source space: a cloud's points (a 3D Gaussian splatting file's with their
//! Gaussians), or a mesh's triangles with its colours or texture; and what a PLY's header says before its body is
//! read (whether it holds Gaussians, whether `check` can refuse it).

use std::collections::HashMap;
use std::path::PathBuf;
use std::sync::Arc;

use glam::{Vec2, Vec3, Vec4};

use super::input::folder_of;
use super::material::{srgb_to_linear, Material};
use super::posed::{PosedPrimitive, PosedScene, PrimKind};
use super::texture::{Texture, TextureRef};
use super::{ply, Error};

/// The textures a PLY's `comment TextureFile NAME` comments name, in order (a face's `texnumber` counts them from
/// 0), each beside the PLY and checked to exist.
fn texture_files(comments: &[String], path: &std::path::Path) -> Result<Vec<PathBuf>, Error> {
    let names = comments.iter().filter_map(|c| ply::texture_comment(c));
    // Found as an MTL's textures are: Windows-authored names (`\`), absolute ones, or a base name beside it.
    names
        .map(|name| {
            let file = this_replaced(name, path);
            super::mtl::locate(folder_of(path), &file).map_err(|tried| Error::Mesh {
                path: path.to_path_buf(),
                line: None,
                message: format!(
                    "`comment TextureFile {name}`: not found ({}): the mesh's texture, which MeshLab and OpenMVS write \
                     beside it; put the image there",
                    tried.display()
                ),
            })
        })
        .collect()
}

/// A `TextureFile` name with each `<this>` (any case) replaced by the PLY's file name without its `.ply`, as
/// MeshLab's library reads it (its samples name `<this>_A.png`, so that a renamed mesh keeps its textures).
fn this_replaced(name: &str, path: &std::path::Path) -> String {
    let stem = match path.extension() {
        Some(e) if e.eq_ignore_ascii_case("ply") => path.file_stem(),
        _ => path.file_name(),
    };
    let stem = stem.map(|s| s.to_string_lossy()).unwrap_or_default();
    // ASCII lower case keeps every byte where it was: the matches' offsets are the name's.
    let (mut out, mut last) = (String::with_capacity(name.len()), 0);
    for (at, _) in name.to_ascii_lowercase().match_indices("<this>") {
        out.push_str(&name[last..at]);
        out.push_str(&stem);
        last = at + "<this>".len();
    }
    out.push_str(&name[last..]);
    out
}

/// The `TextureFile` comments of the PLY with `header` that its surface is drawn with: all of them when it has a
/// surface and texture coordinates to read them by ([`ply::texturing`]), else none (a cloud's or an untextured
/// mesh's comment names a file that nothing reads).
fn texture_comments(header: &ply::Header) -> Vec<String> {
    let surface = header.elements.iter().any(|e| (e.name == "face" || e.name == "tristrips") && e.count > 0);
    let read = surface && ply::texturing(header).textured;
    header.comments.iter().filter(|c| read && ply::texture_comment(c).is_some()).cloned().collect()
}

/// The textures the PLY file at `path` is drawn with (its `TextureFile` comments, when it has a surface and texture
/// coordinates to read them by), checked to exist; its header checked as [`checked_ply`] checks it.
pub fn ply_textures(path: &std::path::Path) -> Result<Vec<PathBuf>, Error> {
    texture_files(&texture_comments(&checked_ply(path)?), path)
}

/// [`ply_textures`] for keying: the comments, which the header decides, come with the file's [`ply_facts`]; the
/// files they name are found and checked every time.
pub fn ply_textures_cached(path: &std::path::Path, stat: &crate::cache::StatCache) -> Result<Vec<PathBuf>, Error> {
    ply_facts(path, stat)?.texture_files(path)
}

/// Whether the PLY at `path` holds 3D Gaussians drawn as splats (with their scales and rotations), and what a
/// user should know when it holds Gaussians without their shapes: those are drawn as points.
pub(super) fn splats_of(path: &std::path::Path) -> Result<(bool, Option<String>), Error> {
    let header = checked_ply(path)?;
    let splatted = ply::holds_gaussian_shapes(&header);
    let note = (ply::holds_gaussian_splats(&header) && !splatted).then(|| {
        format!(
            "{}: holds 3D Gaussians' colours and opacities (3D Gaussian splatting's `f_dc_*`, `opacity`) but not \
             their shapes (`scale_0..2`, `rot_0..3`): vvgen draws each as a point at its centre in its base colour \
             (spherical-harmonic band 0, as 3DGS's tools colour a cloud), and leaves out those too faint to show \
             anywhere (opacity under 1/255). A file with its scales and rotations is drawn as splatting draws it",
            path.display()
        )
    });
    Ok((splatted, note))
}

/// A PLY file as a posed scene in source space: triangles if it has faces, else points.
pub fn ply_scene(path: &std::path::Path) -> Result<PosedScene, Error> {
    ply_scene_at(path, [0.0; 3])
}

/// [`ply_scene`] with `origin` subtracted from the coordinates as they are read, in double precision.
pub fn ply_scene_at(path: &std::path::Path, origin: [f64; 3]) -> Result<PosedScene, Error> {
    // Streamed from the file where its layout allows (`ply::read_file`): a sequence's frames are read this way.
    ply_posed(ply::read_file_at(path, origin).map_err(|e| file_error(path, e))?, path)
}

/// The header of the PLY file at `path`, after what its header and size decide is checked (`ply::check_file`):
/// what `vvgen check` can refuse in a frame without reading its body.
pub fn checked_ply(path: &std::path::Path) -> Result<ply::Header, Error> {
    ply::check_file(path).map_err(|e| file_error(path, e))
}

/// What keying knows of a PLY file besides its bytes' digest ([`ply_facts`]).
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct PlyFacts {
    /// It has a surface (a `face` or `tristrips` element with rows) rather than points alone.
    pub surface: bool,
    /// It has triangle strips (a `tristrips` element with rows). Such a file read as its vertices alone, a point
    /// cloud, until "ply strips 1" cut its strips into triangles, so a sequence's frame with them is keyed apart.
    pub strips: bool,
    /// It has a polygon filled otherwise than by the fan from its first corner (a concave one, or a quad folded
    /// along its first diagonal: [`ply::PlyData::unfanned`]). Every polygon was fanned until "ply polygons 1", so a
    /// sequence's frame with such a polygon is keyed apart.
    pub unfanned: bool,
    /// It is textured by per-corner coordinates (a face `texcoord` list and `comment TextureFile`), which were
    /// read as an untextured mesh until "ply wedge uvs 1", so a sequence's frame with them is keyed apart.
    pub wedge: bool,
    /// It is textured and its vertices have colours too: the texture was multiplied by them until "ply texture
    /// over colours 1" drew the texture alone, so a sequence's frame with both is keyed apart.
    pub tinted: bool,
    /// The `TextureFile` comments its surface is drawn with, in order (none for a cloud or an untextured mesh):
    /// the textures that key it besides its bytes ([`PlyFacts::texture_files`]).
    pub textures: Vec<String>,
}

impl PlyFacts {
    /// The files [`PlyFacts::textures`] name, beside the PLY at `path`, checked to exist.
    pub fn texture_files(&self, path: &std::path::Path) -> Result<Vec<PathBuf>, Error> {
        texture_files(&self.textures, path)
    }
}

/// The [`PlyFacts`] of the PLY file at `path`, remembered by the stat cache for its content as one fact: its
/// header read once, and its body only when it has faces (a point cloud is answered from its header alone).
pub fn ply_facts(path: &std::path::Path, stat: &crate::cache::StatCache) -> Result<PlyFacts, Error> {
    let io = |e| Error::Io { path: path.to_path_buf(), source: e };
    // A line of bits, then the texture comments, one a line.
    let fact = stat
        .derived("ply facts 3", path, || {
            let header = checked_ply(path)?;
            let has = |name: &str| header.elements.iter().any(|e| e.name == name && e.count > 0);
            let (faces, strips) = (has("face"), has("tristrips"));
            let unfanned = faces && ply::read_file(path).map_err(|e| file_error(path, e))?.unfanned;
            let t = ply::texturing(&header);
            let bits = [faces || strips, strips, unfanned, t.wedge, t.textured && t.colours && (faces || strips)];
            let mut fact: String = bits.map(|b| if b { '1' } else { '0' }).iter().collect();
            for c in texture_comments(&header) {
                fact.push('\n');
                fact.push_str(&c);
            }
            Ok::<_, Error>(fact)
        })
        .map_err(io)??;
    let mut lines = fact.lines();
    let bits = lines.next().unwrap_or_default().as_bytes();
    let bit = |k: usize| bits.get(k) == Some(&b'1');
    let textures = lines.map(str::to_string).collect();
    Ok(PlyFacts { surface: bit(0), strips: bit(1), unfanned: bit(2), wedge: bit(3), tinted: bit(4), textures })
}

fn file_error(path: &std::path::Path, e: ply::FileError) -> Error {
    match e {
        ply::FileError::Io(source) => Error::Io { path: path.to_path_buf(), source },
        ply::FileError::Ply(source) => Error::Ply { path: path.to_path_buf(), source },
    }
}

/// [`ply_scene`] from the file's bytes; `path` names it in errors.
pub fn ply_scene_slice(bytes: &[u8], path: &std::path::Path) -> Result<PosedScene, Error> {
    ply_posed(ply::read(bytes).map_err(|e| Error::Ply { path: path.to_path_buf(), source: e })?, path)
}

/// A decoded PLY as a posed scene in source space; `path` finds its textures and names it in errors.
fn ply_posed(d: ply::PlyData, path: &std::path::Path) -> Result<PosedScene, Error> {
    let ply::PlyData {
        positions, normals, colors, uvs, corner_uvs, texnumbers, triangles, comments, gaussians, ..
    } = d;
    let kind = if triangles.is_empty() { PrimKind::Points } else { PrimKind::Triangles };
    // In place: `[f32; 3]` and `Vec3` have one size and alignment, so the collect reuses the allocation.
    let positions: Vec<Vec3> = positions.into_iter().map(Vec3::from).collect();
    let normals = match (normals, kind) {
        (Some(n), _) => n.into_iter().map(|n| Vec3::from(n).normalize_or_zero()).collect(),
        (None, PrimKind::Triangles) => super::gltf::load::smooth_normals(&positions, &triangles),
        (None, PrimKind::Points) => vec![Vec3::ZERO; positions.len()],
    };
    // A textured mesh (MeshLab's and OpenMVS's convention: `comment TextureFile`, texture coordinates per vertex
    // or per face corner). The texture takes the place of vertex colours, as trimesh reads such a file: MeshLab
    // writes its default grey with a texture, and a scan's colours beside its texture would darken it twice.
    let textures = match kind {
        PrimKind::Triangles if uvs.is_some() || corner_uvs.is_some() => texture_files(&comments, path)?,
        _ => Vec::new(),
    };
    if !textures.is_empty() {
        // Each file decoded once, however many comments name it: per comment, its image's place in `images`.
        let mut distinct: Vec<&PathBuf> = Vec::new();
        let image: Vec<u32> = textures
            .iter()
            .map(|t| {
                let at = distinct.iter().position(|d| *d == t).unwrap_or_else(|| {
                    distinct.push(t);
                    distinct.len() - 1
                });
                at as u32
            })
            .collect();
        let images = distinct.into_iter().map(|t| super::obj::texture(t)).collect::<Result<Vec<_>, _>>()?;
        let textured = Textured { materials: image.into_iter().map(textured_material).collect(), images };
        let mesh = Mesh { positions: &positions, normals: &normals, triangles: &triangles };
        return Ok(match (corner_uvs, uvs) {
            (Some(corners), _) => wedge_textured(mesh, &corners, texnumbers.as_deref(), textured),
            (None, Some(uvs)) => vertex_textured(mesh, &uvs, textured),
            (None, None) => unreachable!("textures are read only with coordinates"),
        });
    }
    let colors: Vec<Vec4> = colors
        .map(|c| {
            c.iter()
                .map(|c| {
                    Vec4::new(
                        srgb_to_linear(c[0] as f32 / 255.0),
                        srgb_to_linear(c[1] as f32 / 255.0),
                        srgb_to_linear(c[2] as f32 / 255.0),
                        c[3] as f32 / 255.0,
                    )
                })
                .collect()
        })
        .unwrap_or_default();
    // A mesh with neither colours nor a texture is Blender's grey (points stay white: Blender draws none).
    let plain = kind == PrimKind::Triangles && colors.is_empty();
    let base = if plain { Material::unassigned() } else { Material::default() };
    // Scans rarely have consistent winding: draw both sides.
    let material = Material { double_sided: true, ..base };
    let mut scene = PosedScene::single(kind, positions, normals, colors, triangles, material);
    if kind == PrimKind::Points {
        let g = gaussians.as_ref().map(super::gaussians::GaussianData::from_columns);
        scene.primitives[0].gaussians = g.map(super::gaussians::Gaussians::new);
    }
    Ok(scene)
}

/// A PLY mesh's welded vertices and triangles (normals found on the welded mesh, so a texture seam is no crease).
#[derive(Clone, Copy)]
struct Mesh<'m> {
    positions: &'m [Vec3],
    normals: &'m [Vec3],
    triangles: &'m [u32],
}

/// A textured PLY's materials, one per `TextureFile` comment, and the images they read (one per distinct file).
struct Textured {
    materials: Vec<Material>,
    images: Vec<Texture>,
}

/// The material of a textured PLY's texture `t` (of its decoded images): that image as base colour, both sides
/// drawn (scans rarely have consistent winding).
fn textured_material(t: u32) -> Material {
    Material { double_sided: true, base_color_texture: Some(TextureRef::new(t)), ..Material::default() }
}

/// A textured primitive of material `material`.
fn textured_primitive(
    positions: Vec<Vec3>,
    normals: Vec<Vec3>,
    uvs: Vec<Vec2>,
    indices: Vec<u32>,
    material: usize,
) -> PosedPrimitive {
    PosedPrimitive {
        kind: PrimKind::Triangles,
        positions,
        normals,
        tangents: Vec::new(),
        // v runs up from the bottom row; textures are stored top row first.
        uvs: Arc::new(uvs.into_iter().map(|t| Vec2::new(t.x, 1.0 - t.y)).collect()),
        colors: Arc::new(Vec::new()),
        indices: Arc::new(indices),
        material: material as u32,
        object: 0,
        gaussians: None,
    }
}

/// A mesh textured by per-vertex coordinates `uvs`, by its first texture (one set of coordinates reads one).
fn vertex_textured(mesh: Mesh<'_>, uvs: &[[f32; 2]], textured: Textured) -> PosedScene {
    let uvs = uvs.iter().map(|&t| Vec2::from(t)).collect();
    let p = textured_primitive(mesh.positions.to_vec(), mesh.normals.to_vec(), uvs, mesh.triangles.to_vec(), 0);
    let Textured { materials, images } = textured;
    PosedScene { primitives: vec![p], materials: Arc::new(materials), textures: Arc::new(images), lights: Vec::new() }
}

/// A mesh textured by per-corner coordinates `corners` (one pair per entry of its triangles), each triangle by the
/// texture `texnumbers` gives it (the first without): one primitive per texture with triangles, in file order,
/// whose vertices are the mesh's split where a vertex has more than one pair (a seam), numbered in order of first
/// use, so the same file gives the same primitives. Each triangle and vertex is visited once whatever the count
/// of textures.
fn wedge_textured(mesh: Mesh<'_>, corners: &[[f32; 2]], texnumbers: Option<&[u32]>, textured: Textured) -> PosedScene {
    let Textured { materials, images } = textured;
    // The triangles of each texture, in file order (`read` checked every number against the comments).
    let mut per: Vec<Vec<u32>> = vec![Vec::new(); materials.len()];
    for tri in 0..mesh.triangles.len() / 3 {
        let t = texnumbers.and_then(|n| n.get(tri)).map_or(0, |&t| t as usize);
        if let Some(p) = per.get_mut(t) {
            p.push(tri as u32);
        }
    }
    let mut primitives = Vec::new();
    // Most vertices have one pair: a vertex's first (its new index, in `first`) is found without hashing; only a
    // seam's further pairs are looked up in `more`. A texture's vertices are unmarked after it (`touched`).
    let mut first = vec![u32::MAX; mesh.positions.len()];
    let mut more: HashMap<(u32, [u32; 2]), u32> = HashMap::new();
    let mut touched: Vec<u32> = Vec::new();
    for (t, tris) in per.iter().enumerate().filter(|(_, tris)| !tris.is_empty()) {
        let (mut positions, mut normals, mut uvs, mut indices) =
            (Vec::new(), Vec::new(), Vec::<Vec2>::new(), Vec::with_capacity(3 * tris.len()));
        for &tri in tris {
            let at = 3 * tri as usize..3 * tri as usize + 3;
            for (&v, &uv) in mesh.triangles[at.clone()].iter().zip(&corners[at]) {
                let bits = uv.map(f32::to_bits);
                let known = match first[v as usize] {
                    u32::MAX => None,
                    f if uvs[f as usize].to_array().map(f32::to_bits) == bits => Some(f),
                    _ => more.get(&(v, bits)).copied(),
                };
                let i = known.unwrap_or_else(|| {
                    positions.push(mesh.positions[v as usize]);
                    normals.push(mesh.normals[v as usize]);
                    uvs.push(Vec2::from(uv));
                    let i = (positions.len() - 1) as u32;
                    match first[v as usize] {
                        u32::MAX => {
                            first[v as usize] = i;
                            touched.push(v);
                        }
                        _ => _ = more.insert((v, bits), i),
                    }
                    i
                });
                indices.push(i);
            }
        }
        for v in touched.drain(..) {
            first[v as usize] = u32::MAX;
        }
        more.clear();
        primitives.push(textured_primitive(positions, normals, uvs, indices, t));
    }
    PosedScene { primitives, materials: Arc::new(materials), textures: Arc::new(images), lights: Vec::new() }
}
