//! A PLY file as a posed scene in source space: a cloud's points (a 3D Gaussian splatting file's with their
//! Gaussians), or a mesh's triangles with its colours or texture; and what a PLY's header says before its body is
//! read (whether it holds Gaussians, whether `check` can refuse it).

use std::path::PathBuf;
use std::sync::Arc;

use glam::{Vec3, Vec4};

use super::input::folder_of;
use super::material::{srgb_to_linear, Material};
use super::posed::{PosedScene, PrimKind};
use super::{ply, Error};

/// The texture a PLY's `comment TextureFile NAME` names, beside the PLY, checked to exist.
pub(super) fn texture_file(comments: &[String], path: &std::path::Path) -> Result<Option<PathBuf>, Error> {
    let Some(name) = comments.iter().find_map(|c| c.trim().strip_prefix("TextureFile").map(str::trim)) else {
        return Ok(None);
    };
    // Found as an MTL's textures are: Windows-authored names (`\`), absolute ones, or a base name beside it.
    match super::mtl::locate(folder_of(path), name) {
        Ok(tex) => Ok(Some(tex)),
        Err(tried) => Err(Error::Mesh {
            path: path.to_path_buf(),
            line: None,
            message: format!("`comment TextureFile {name}`: not found ({})", tried.display()),
        }),
    }
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
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
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
}

/// The [`PlyFacts`] of the PLY file at `path`, remembered by the stat cache for its content as one fact: its
/// header read once, and its body only when it has faces (a point cloud is answered from its header alone).
pub fn ply_facts(path: &std::path::Path, stat: &crate::cache::StatCache) -> Result<PlyFacts, Error> {
    let io = |e| Error::Io { path: path.to_path_buf(), source: e };
    let fact = stat
        .derived("ply facts 1", path, || {
            let header = checked_ply(path)?;
            let has = |name: &str| header.elements.iter().any(|e| e.name == name && e.count > 0);
            let (faces, strips) = (has("face"), has("tristrips"));
            let unfanned = faces && ply::read_file(path).map_err(|e| file_error(path, e))?.unfanned;
            Ok::<_, Error>([faces || strips, strips, unfanned].map(|b| if b { '1' } else { '0' }).iter().collect())
        })
        .map_err(io)??;
    let bit = |k: usize| fact.as_bytes().get(k) == Some(&b'1');
    Ok(PlyFacts { surface: bit(0), strips: bit(1), unfanned: bit(2) })
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

/// A decoded PLY as a posed scene in source space; `path` finds its texture and names it in errors.
fn ply_posed(d: ply::PlyData, path: &std::path::Path) -> Result<PosedScene, Error> {
    let ply::PlyData { positions, normals, colors, uvs, triangles, comments, gaussians, .. } = d;
    let kind = if triangles.is_empty() { PrimKind::Points } else { PrimKind::Triangles };
    // In place: `[f32; 3]` and `Vec3` have one size and alignment, so the collect reuses the allocation.
    let positions: Vec<Vec3> = positions.into_iter().map(Vec3::from).collect();
    let normals = match (normals, kind) {
        (Some(n), _) => n.into_iter().map(|n| Vec3::from(n).normalize_or_zero()).collect(),
        (None, PrimKind::Triangles) => super::gltf::load::smooth_normals(&positions, &triangles),
        (None, PrimKind::Points) => vec![Vec3::ZERO; positions.len()],
    };
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
    // A textured mesh (MeshLab's convention: per-vertex texture_u/v or s/t, `comment TextureFile`).
    let texture = match (&uvs, kind) {
        (Some(_), PrimKind::Triangles) => texture_file(&comments, path)?,
        _ => None,
    };
    // A mesh with neither colours nor a texture is Blender's grey (points stay white: Blender draws none).
    let plain = kind == PrimKind::Triangles && colors.is_empty() && texture.is_none();
    let base = if plain { Material::unassigned() } else { Material::default() };
    // Scans rarely have consistent winding: draw both sides.
    let mut material = Material { double_sided: true, ..base };
    let mut scene = PosedScene::single(kind, positions, normals, colors, triangles, material.clone());
    if kind == PrimKind::Points {
        let g = gaussians.as_ref().map(super::gaussians::GaussianData::from_columns);
        scene.primitives[0].gaussians = g.map(super::gaussians::Gaussians::new);
    }
    if let (Some(tex), Some(uvs)) = (texture, &uvs) {
        material.base_color_texture = Some(super::texture::TextureRef::new(0));
        scene.materials = Arc::new(vec![material]);
        scene.textures = Arc::new(vec![super::obj::texture(&tex)?]);
        // v runs up from the bottom row; textures are stored top row first.
        scene.primitives[0].uvs = Arc::new(uvs.iter().map(|t| glam::Vec2::new(t[0], 1.0 - t[1])).collect());
    }
    Ok(scene)
}
