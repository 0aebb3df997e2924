//! Draco files (`.drc`, as Google's `draco_encoder` writes them: point-cloud compression's usual baseline), meshes
//! and point clouds, decoded by draco-core (the port of Google's decoder that reads glTF's Draco primitives,
//! `super::gltf::draco`) and drawn as the PLY they were most often made from: positions, normals when the file has
//! them (a mesh's found from its triangles otherwise), colours as sRGB, both sides of a surface.

use std::path::Path;

use draco_core::{DataType, DecodeLimits, DecoderBuffer, GeometryAttributeType, Mesh, MeshDecoder, PointCloud};
use draco_core::{PointAttribute, PointCloudDecoder};
use glam::{Vec3, Vec4};

use super::material::{srgb_to_linear, Material};
use super::posed::{PosedScene, PrimKind};
use super::Error;

/// Ceilings on one Draco stream's decoded geometry (a `.drc` file's, or a glTF primitive's: `super::gltf::draco`):
/// 2^26 points, 2^27 triangles, 2 GiB of data. Far above any exported mesh (Draco splits vertices at seams, so a
/// decoded count can exceed its source's), and a bound on what a hostile header can make vvgen allocate
/// (draco-core also refuses reservations its stream cannot back).
pub(crate) fn limits() -> DecodeLimits {
    DecodeLimits::default().with_max_points(1 << 26).with_max_faces(1 << 27).with_max_decoded_bytes(2 << 30)
}

/// Whether a file is a Draco file, by its extension.
pub(crate) fn is_drc(path: &Path) -> bool {
    path.extension().is_some_and(|e| e.eq_ignore_ascii_case("drc"))
}

/// What a Draco header says the file holds.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Holds {
    Points,
    Mesh,
}

/// The file's geometry, from its header: `DRACO`, a version, then the encoder's kind (0 a point cloud, 1 a mesh).
fn holds(bytes: &[u8]) -> Result<Holds, String> {
    if !bytes.starts_with(b"DRACO") {
        return Err("not a Draco file (it does not start with `DRACO`)".into());
    }
    match bytes.get(7) {
        Some(0) => Ok(Holds::Points),
        Some(1) => Ok(Holds::Mesh),
        Some(k) => Err(format!("a Draco file of an unknown kind ({k}: 0 is a point cloud, 1 a mesh)")),
        None => Err("a Draco file cut short in its header".into()),
    }
}

/// What `vvgen check` can refuse in a Draco frame without decoding it (a sequence's frames are decoded when they
/// render): not a Draco file, or one of an unknown kind. Reads its first bytes.
pub(crate) fn check_file(path: &Path) -> Result<(), Error> {
    use std::io::Read;
    let io = |e| Error::Io { path: path.to_path_buf(), source: e };
    let mut head = Vec::with_capacity(8);
    std::fs::File::open(path).map_err(io)?.take(8).read_to_end(&mut head).map_err(io)?;
    holds(&head).map(|_| ()).map_err(|message| mesh_error(path, message))
}

fn mesh_error(path: &Path, message: String) -> Error {
    Error::Mesh { path: path.to_path_buf(), line: None, message }
}

/// A Draco file's mesh or point cloud, at rest in its own coordinates.
pub fn scene(path: &Path) -> Result<PosedScene, Error> {
    let bytes = std::fs::read(path).map_err(|e| Error::Io { path: path.to_path_buf(), source: e })?;
    scene_slice(&bytes, path)
}

/// [`scene`] from the file's bytes; `path` names it in errors.
pub fn scene_slice(bytes: &[u8], path: &Path) -> Result<PosedScene, Error> {
    decoded(bytes).map_err(|message| mesh_error(path, message))
}

/// The scene of a Draco file's bytes, or what is wrong with them.
fn decoded(bytes: &[u8]) -> Result<PosedScene, String> {
    let kind = holds(bytes)?;
    let mut stream = DecoderBuffer::new(bytes).with_limits(limits());
    let damaged = |e| format!("a damaged Draco file: it does not decode ({e}). Way out: encode it again");
    match kind {
        Holds::Points => {
            let mut pc = PointCloud::new();
            PointCloudDecoder::new().decode(&mut stream, &mut pc).map_err(damaged)?;
            posed(&pc, Vec::new())
        }
        Holds::Mesh => {
            let mut mesh = Mesh::new();
            MeshDecoder::new().decode(&mut stream, &mut mesh).map_err(damaged)?;
            let corners = mesh.faces().iter().flat_map(|f| f.map(|p| p.0)).collect();
            posed(&mesh, corners)
        }
    }
}

/// The scene of a decoded point cloud (a mesh's, with its `triangles`' corners).
fn posed(cloud: &PointCloud, triangles: Vec<u32>) -> Result<PosedScene, String> {
    let n = cloud.num_points();
    let position = cloud
        .named_attribute(GeometryAttributeType::Position)
        .ok_or("a Draco file without positions: nothing to draw. Way out: encode it again with its positions")?;
    let positions: Vec<Vec3> = vectors(position, n, 3)?.chunks_exact(3).map(Vec3::from_slice).collect();
    if triangles.iter().any(|&c| c as usize >= n) {
        return Err(format!("a damaged Draco file: a triangle names a point past its {n}"));
    }
    let prim = if triangles.is_empty() { PrimKind::Points } else { PrimKind::Triangles };
    let normals = match (cloud.named_attribute(GeometryAttributeType::Normal), prim) {
        (Some(a), _) => vectors(a, n, 3)?.chunks_exact(3).map(|v| Vec3::from_slice(v).normalize_or_zero()).collect(),
        (None, PrimKind::Triangles) => super::gltf::load::smooth_normals(&positions, &triangles),
        (None, PrimKind::Points) => vec![Vec3::ZERO; n],
    };
    let colors = match cloud.named_attribute(GeometryAttributeType::Color) {
        Some(a) => colours(a, n)?,
        None => Vec::new(),
    };
    // As a PLY is drawn: a mesh with no colours is Blender's grey, points stay white; scans rarely have consistent
    // winding, so both sides.
    let plain = prim == PrimKind::Triangles && colors.is_empty();
    let base = if plain { Material::unassigned() } else { Material::default() };
    let material = Material { double_sided: true, ..base };
    Ok(PosedScene::single(prim, positions, normals, colors, triangles, material))
}

/// `n` values of `components` each of attribute `a` as floats (integers as they are stored), all finite.
fn vectors(a: &PointAttribute, n: usize, components: usize) -> Result<Vec<f32>, String> {
    if (a.num_components() as usize) < components {
        return Err(format!("a Draco attribute has {} components where {components} are needed", a.num_components()));
    }
    let values = a.read_f32s(n, components);
    if values.len() != n * components {
        return Err("a damaged Draco file: an attribute holds fewer values than the file has points".into());
    }
    if let Some(v) = values.iter().find(|v| !v.is_finite()) {
        return Err(format!("a Draco attribute holds a value that is not a number ({v})"));
    }
    Ok(values)
}

/// Colour attribute `a` of `n` points as linear RGBA: integer colours over their type's largest value, float ones
/// as they are, both read as sRGB (a PLY's colours are); alpha linear, 1 where there is none.
fn colours(a: &PointAttribute, n: usize) -> Result<Vec<Vec4>, String> {
    let k = (a.num_components() as usize).clamp(1, 4);
    // Divided, as the PLY reader divides its bytes, so that a `.drc` and the PLY it was made from draw the same.
    let largest: f32 = match a.data_type() {
        DataType::Uint8 => 255.0,
        DataType::Uint16 => 65535.0,
        DataType::Uint32 => 4294967295.0,
        DataType::Float32 | DataType::Float64 => 1.0,
        other => return Err(format!("a Draco colour attribute of {other:?} values, which vvgen does not read")),
    };
    let values = vectors(a, n, k)?;
    Ok(values
        .chunks_exact(k)
        .map(|c| {
            let at = |i: usize| (c.get(i).copied().unwrap_or(c[0]) / largest).clamp(0.0, 1.0);
            let alpha = if k == 4 { at(3) } else { 1.0 };
            Vec4::new(srgb_to_linear(at(0)), srgb_to_linear(at(1)), srgb_to_linear(at(2)), alpha)
        })
        .collect())
}
