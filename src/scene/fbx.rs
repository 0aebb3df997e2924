//! FBX sources (`fbx = "character.fbx"`), read and evaluated by ufbx (the C library, vendored by the `ufbx`
//! crate): ascii and binary FBX 6100–7700, polygons triangulated, normals, UV set 0, vertex colours, node
//! animation with FBX's pivots, pre/post rotations and rotation orders, linear-blend skinning and blend shapes,
//! several takes. ufbx converts units to metres and axes to the world's (+Z up, −Y forward, as Blender's
//! importer does), so an FBX source needs no `up`.
//!
//! What is loaded once: the file, and per mesh instance and material the triangle corners with their static
//! attributes (UVs, colours). What each frame poses: ufbx evaluates the take at the frame's time (nodes, blend
//! shapes, skinning) and the corners' positions and normals are read off the evaluated meshes. Rotations that
//! animation layers blend as quaternions are blended as Maya blends them first (`fbx_layers`).
//!
//! Hostile files: ufbx refuses malformed input with an error (never a crash), and both its allocators are
//! capped ([`MAX_MEMORY`], [`MAX_ALLOCATIONS`]), so an absurd count is an error, not an unbounded allocation.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use glam::{Mat4, Vec2, Vec3, Vec4};

use super::fbx_materials::Shading;
use super::input::{Clip, Clips};
use super::material::Material;
use super::posed::{PosedPrimitive, PosedScene, PrimKind};
use super::texture::Texture;
use super::Error;

/// The most memory ufbx may take for one file or one evaluated frame.
pub const MAX_MEMORY: usize = 1 << 30;
/// The most allocations ufbx may make for one file or one evaluated frame.
pub const MAX_ALLOCATIONS: usize = 50_000_000;
/// The most triangles one FBX source may have (what the posed frame holds, three corners each).
pub const MAX_TRIANGLES: usize = 50_000_000;

/// One take (FBX animation stack).
#[derive(Debug, Clone)]
pub struct Take {
    /// Its name (`Take 001`, `Armature|Walk`).
    pub name: String,
    /// Its first and last time, seconds.
    pub begin: f64,
    /// Its last time, seconds.
    pub end: f64,
}

impl Take {
    /// Its length in seconds.
    pub fn duration(&self) -> f64 {
        (self.end - self.begin).max(0.0)
    }
}

/// One mesh instance's triangles of one material.
#[derive(Debug)]
struct Part {
    /// The node, by its index among the scene's nodes.
    node: usize,
    /// The mesh's face-corner index of every triangle corner.
    corners: Vec<u32>,
    uvs: Arc<Vec<Vec2>>,
    colors: Arc<Vec<Vec4>>,
    indices: Arc<Vec<u32>>,
    material: u32,
    object: u32,
}

/// A loaded FBX file.
pub struct FbxAsset {
    /// The file.
    pub path: PathBuf,
    scene: ufbx::SceneRoot,
    /// Its takes, in file order.
    pub takes: Vec<Take>,
    parts: Vec<Part>,
    materials: Arc<Vec<Material>>,
    textures: Arc<Vec<Texture>>,
    /// Whether some mesh has blend shapes (ufbx then evaluates the skinning, with them).
    blend_shapes: bool,
    /// Nodes whose layered rotation is blended as Maya blends it, not as ufbx does ([`super::fbx_layers`]).
    layered: Vec<super::fbx_layers::Layered>,
    /// What the user should know about how it loaded: textures it names but neither holds nor has beside it.
    pub warnings: Vec<String>,
    /// Warnings naming the materials Blender's importer reads as fully transparent (nothing of them shows), said
    /// unless the source takes the materials as opaque (`opaque`).
    pub unseen: Vec<String>,
}

impl FbxAsset {
    /// What the file holds: whether it draws anything (some mesh has a triangle; an animation-only export, a
    /// skeleton and its takes, has none) and, for the error when it does not, what it has instead.
    pub fn holds(&self) -> super::source::Holds {
        super::source::Holds {
            draws: self.parts.iter().any(|p| !p.indices.is_empty()),
            // ufbx lists the scene's root as a node.
            nodes: self.scene.nodes.len().saturating_sub(1),
            meshes: !self.scene.meshes.is_empty(),
            clips: self.takes.len(),
            clip: "take",
            skeleton: !self.scene.bones.is_empty(),
            curves: self.scene.nurbs_curves.len() + self.scene.nurbs_surfaces.len() + self.scene.line_curves.len(),
        }
    }

    /// The file's materials as the renderer's, by name, in file order (the two defaults for faces with none are
    /// not listed).
    pub fn named_materials(&self) -> Vec<(String, &Material)> {
        self.scene.materials.iter().map(|m| m.element.name.to_string()).zip(self.materials.iter()).collect()
    }
}

impl std::fmt::Debug for FbxAsset {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("FbxAsset").field("path", &self.path).field("takes", &self.takes).finish_non_exhaustive()
    }
}

fn capped() -> ufbx::AllocatorOpts {
    ufbx::AllocatorOpts { memory_limit: MAX_MEMORY, allocation_limit: MAX_ALLOCATIONS, ..Default::default() }
}

pub(super) fn err(path: &Path, message: impl Into<String>) -> Error {
    Error::Fbx { path: path.to_path_buf(), message: message.into() }
}

fn v3(v: ufbx::Vec3) -> Vec3 {
    Vec3::new(v.x as f32, v.y as f32, v.z as f32)
}

fn mat(m: &ufbx::Matrix) -> Mat4 {
    Mat4::from_cols_array(&[
        m.m00 as f32,
        m.m10 as f32,
        m.m20 as f32,
        0.0,
        m.m01 as f32,
        m.m11 as f32,
        m.m21 as f32,
        0.0,
        m.m02 as f32,
        m.m12 as f32,
        m.m22 as f32,
        0.0,
        m.m03 as f32,
        m.m13 as f32,
        m.m23 as f32,
        1.0,
    ])
}

/// Loads `path`: the scene in metres and the world's axes, its takes, materials and textures, and every mesh
/// instance's triangles.
pub fn load(path: &Path) -> Result<FbxAsset, Error> {
    let file = path.to_str().ok_or_else(|| err(path, "the path is not UTF-8"))?;
    if !path.is_file() {
        return Err(Error::Io { path: path.to_path_buf(), source: std::io::ErrorKind::NotFound.into() });
    }
    let scene = ufbx::load_file(file, options()).map_err(|e| {
        let mut head = [0u8; 23];
        let read = std::fs::File::open(path).and_then(|mut f| std::io::Read::read_exact(&mut f, &mut head));
        unreadable(path, read.map_or(&[][..], |()| &head[..]), &e)
    })?;
    finish(path, scene)
}

/// The error for a file ufbx cannot load, `head` being its first bytes. A binary FBX whose signature is damaged
/// (`Kaydara FBX Binary` then two spaces, a NUL, 0x1A and a NUL) says so: a transfer in text mode turns those
/// bytes into others, and ufbx says only "Not an FBX file".
fn unreadable(path: &Path, head: &[u8], e: &ufbx::Error) -> Error {
    let signature = b"Kaydara FBX Binary  \x00\x1a\x00";
    if head.starts_with(b"Kaydara FBX Binary") && !head.starts_with(signature) {
        return err(
            path,
            "a binary FBX whose signature is damaged (its first bytes are not `Kaydara FBX Binary  \\0\\x1a\\0`), \
             as a transfer in text mode leaves it: copy or download the file again in binary mode"
                .to_string(),
        );
    }
    err(path, format!("not a readable FBX file: {}", e.description))
}

/// [`load`] of a file's bytes (`path` names it and locates the textures beside it).
pub fn load_slice(bytes: &[u8], path: &Path) -> Result<FbxAsset, Error> {
    let scene = ufbx::load_memory(bytes, options()).map_err(|e| unreadable(path, bytes, &e))?;
    finish(path, scene)
}

/// How ufbx loads: capped, in the world's axes and metres, no external files but textures (read by vvgen).
fn options() -> ufbx::LoadOpts<'static> {
    ufbx::LoadOpts {
        temp_allocator: capped(),
        result_allocator: capped(),
        // Textures are read by vvgen itself (inside the file's folder); nothing else external is followed.
        load_external_files: false,
        ignore_missing_external_files: true,
        generate_missing_normals: true,
        target_axes: ufbx::CoordinateAxes {
            right: ufbx::CoordinateAxis::PositiveX,
            up: ufbx::CoordinateAxis::PositiveZ,
            front: ufbx::CoordinateAxis::NegativeY,
        },
        target_unit_meters: 1.0,
        ..Default::default()
    }
}

/// The asset of a loaded scene.
fn finish(path: &Path, scene: ufbx::SceneRoot) -> Result<FbxAsset, Error> {
    let takes = scene
        .anim_stacks
        .iter()
        .map(|s| Take { name: s.element.name.to_string(), begin: s.time_begin, end: s.time_end })
        .collect();
    let Shading { materials, textures, warnings, unseen } = super::fbx_materials::materials(path, &scene)?;
    // The first of the two defaults for faces without a material (white, then unassigned grey).
    let fallback = materials.len() as u32 - 2;
    let mut parts = Vec::new();
    let mut triangles = 0usize;
    for (ni, node) in scene.nodes.iter().enumerate() {
        let Some(mesh) = node.mesh.as_ref() else { continue };
        triangles += mesh.num_triangles;
        if triangles > MAX_TRIANGLES {
            return Err(err(path, format!("more than {MAX_TRIANGLES} triangles")));
        }
        // Triangles grouped by the material of their face, in face order.
        let mut by_material: std::collections::BTreeMap<u32, Vec<u32>> = Default::default();
        let mut tri = vec![0u32; mesh.max_face_triangles * 3];
        for (fi, face) in mesh.faces.iter().enumerate() {
            let n = mesh.triangulate_face(&mut tri, *face) as usize;
            let slot = mesh.face_material.get(fi).copied().unwrap_or(0);
            by_material.entry(slot).or_default().extend_from_slice(&tri[..n * 3]);
        }
        for (slot, corners) in by_material {
            // The node's material in that slot (instances may override the mesh's), else the mesh's.
            let m = node.materials.get(slot as usize).or_else(|| mesh.materials.get(slot as usize));
            let material = m.map_or(fallback + u32::from(!mesh.vertex_color.exists), |m| m.element.typed_id);
            let uvs: Vec<Vec2> = if mesh.vertex_uv.exists {
                // FBX's v runs up, the renderer's (glTF's) down.
                corners
                    .iter()
                    .map(|&c| mesh.vertex_uv[c as usize])
                    .map(|t| Vec2::new(t.x as f32, 1.0 - t.y as f32))
                    .collect()
            } else {
                Vec::new()
            };
            let colors: Vec<Vec4> = if mesh.vertex_color.exists {
                corners
                    .iter()
                    .map(|&c| mesh.vertex_color[c as usize])
                    .map(|c| Vec4::new(c.x as f32, c.y as f32, c.z as f32, c.w as f32))
                    .collect()
            } else {
                Vec::new()
            };
            let n = corners.len() as u32;
            parts.push(Part {
                node: ni,
                corners,
                uvs: Arc::new(uvs),
                colors: Arc::new(colors),
                indices: Arc::new((0..n).collect()),
                material,
                object: ni as u32,
            });
        }
    }
    let blend_shapes = scene.meshes.iter().any(|m| !m.blend_deformers.is_empty());
    let layered = super::fbx_layers::find(&scene);
    let path = path.to_path_buf();
    Ok(FbxAsset { path, scene, takes, parts, materials, textures, blend_shapes, layered, warnings, unseen })
}

impl FbxAsset {
    /// Poses take `take` (none: the file at rest) at `t` seconds from the take's start, through `post`, into
    /// `out`.
    pub fn pose(&self, take: Option<usize>, t: f64, post: Mat4, out: &mut PosedScene) -> Result<(), Error> {
        let evaluated = self.evaluated(take, t)?;
        let scene: &ufbx::Scene = evaluated.as_deref().unwrap_or(&self.scene);
        out.materials = Arc::clone(&self.materials);
        out.textures = Arc::clone(&self.textures);
        out.lights.clear();
        out.primitives.resize_with(self.parts.len(), || PosedPrimitive {
            kind: PrimKind::Triangles,
            positions: Vec::new(),
            normals: Vec::new(),
            tangents: Vec::new(),
            uvs: Arc::default(),
            colors: Arc::default(),
            indices: Arc::default(),
            material: 0,
            object: 0,
            gaussians: None,
        });
        let normal_post = glam::Mat3::from_mat4(post).inverse().transpose();
        // One mesh node may hold several parts (one per material): pose its vertices once.
        let mut posed_node = usize::MAX;
        let (mut points, mut turns) = (Vec::new(), Vec::new());
        for (p, part) in out.primitives.iter_mut().zip(&self.parts) {
            let node = &scene.nodes[part.node];
            let mesh = node.mesh.as_ref().ok_or_else(|| err(&self.path, "a mesh node lost its mesh"))?;
            if posed_node != part.node {
                posed_vertices(node, mesh, self.blend_shapes && take.is_some(), &mut points, &mut turns);
                posed_node = part.node;
            }
            let vertex = |c: u32| mesh.vertex_indices[c as usize] as usize;
            p.positions.clear();
            p.positions.extend(part.corners.iter().map(|&c| post.transform_point3(points[vertex(c)])));
            p.normals.clear();
            if mesh.vertex_normal.exists {
                p.normals.extend(part.corners.iter().map(|&c| {
                    (normal_post * (turns[vertex(c)] * v3(mesh.vertex_normal[c as usize]))).normalize_or_zero()
                }));
            } else {
                p.normals.resize(part.corners.len(), Vec3::ZERO);
            }
            if let Some(bad) = p.positions.iter().position(|v| !v.is_finite()) {
                return Err(err(&self.path, format!("node `{}`: vertex {bad} is not finite", node.element.name)));
            }
            p.kind = PrimKind::Triangles;
            p.tangents.clear();
            p.uvs = Arc::clone(&part.uvs);
            p.colors = Arc::clone(&part.colors);
            p.indices = Arc::clone(&part.indices);
            p.material = part.material;
            p.object = part.object;
        }
        Ok(())
    }
}

impl FbxAsset {
    /// Every mesh node's control points (the file's own vertices, which Blender's importer keeps as its mesh
    /// vertices, in order) posed at `t` seconds into take `take`, in the world's axes and metres before any
    /// `[transform]`: what a comparison with another importer matches vertex for vertex. By node name, in node
    /// order.
    pub fn control_points(&self, take: Option<usize>, t: f64) -> Result<Vec<(String, Vec<Vec3>)>, Error> {
        let evaluated = self.evaluated(take, t)?;
        let scene: &ufbx::Scene = evaluated.as_deref().unwrap_or(&self.scene);
        let mut out = Vec::new();
        let mut turns = Vec::new();
        for node in scene.nodes.iter() {
            let Some(mesh) = node.mesh.as_ref() else { continue };
            let mut points = Vec::new();
            posed_vertices(node, mesh, self.blend_shapes && take.is_some(), &mut points, &mut turns);
            out.push((node.element.name.to_string(), points));
        }
        Ok(out)
    }

    /// The scene evaluated at `t` seconds into take `take` (none: the file at rest, nothing to evaluate).
    fn evaluated(&self, take: Option<usize>, t: f64) -> Result<Option<ufbx::SceneRoot>, Error> {
        let Some(i) = take else { return Ok(None) };
        let stack = &self.scene.anim_stacks[i];
        let opts = ufbx::EvaluateOpts {
            temp_allocator: capped(),
            result_allocator: capped(),
            // Skinning is done here (`posed_vertices`): ufbx's evaluates every attribute of a whole copy of each
            // mesh, 25 times the cost of the rest of the frame. Blend shapes are left to it, in-betweens and all.
            evaluate_skinning: self.blend_shapes,
            ..Default::default()
        };
        let time = stack.time_begin + t;
        let failed =
            |e: ufbx::Error| err(&self.path, format!("take `{}` at {t} s: {}", stack.element.name, e.description));
        let overrides = super::fbx_layers::overrides(&self.scene, &self.layered, i, time);
        if overrides.is_empty() {
            return ufbx::evaluate_scene(&self.scene, &stack.anim, time, opts).map(Some).map_err(failed);
        }
        // Maya's blend of layered rotations, handed to ufbx as this instant's property values.
        let descs: Vec<ufbx::PropOverrideDesc> = overrides
            .into_iter()
            .map(|(element_id, r)| ufbx::PropOverrideDesc {
                element_id,
                prop_name: ufbx::StringOpt::Ref("Lcl Rotation"),
                value: ufbx::Vec4 { x: r.x, y: r.y, z: r.z, w: 0.0 },
                ..Default::default()
            })
            .collect();
        let layer_ids: Vec<u32> = stack.layers.iter().map(|l| l.element.typed_id).collect();
        let anim = ufbx::create_anim(
            &self.scene,
            ufbx::AnimOpts {
                layer_ids: ufbx::ListOpt::Ref(&layer_ids),
                prop_overrides: ufbx::ListOpt::Ref(&descs),
                result_allocator: capped(),
                ..Default::default()
            },
        )
        .map_err(failed)?;
        ufbx::evaluate_scene(&self.scene, &anim, time, opts).map(Some).map_err(failed)
    }
}

/// Every vertex of `node`'s `mesh` posed in world space, and in `turns` each vertex's normal matrix: its skin's
/// linear blend of its clusters' evaluated matrices (as Blender's importer skins), or the node's placement when
/// it has none. Where ufbx evaluated the skinning (`skinned`: files with blend shapes, whose in-between shapes
/// it interpolates), the positions are ufbx's.
fn posed_vertices(
    node: &ufbx::Node,
    mesh: &ufbx::Mesh,
    skinned: bool,
    points: &mut Vec<Vec3>,
    turns: &mut Vec<glam::Mat3>,
) {
    points.clear();
    turns.clear();
    let skin = mesh.skin_deformers.first();
    for v in 0..mesh.num_vertices {
        let m = match skin {
            Some(s) => mat(&ufbx::get_skin_vertex_matrix(s, v, &node.geometry_to_world)),
            None => mat(&node.geometry_to_world),
        };
        points.push(m.transform_point3(v3(mesh.vertices[v])));
        turns.push(glam::Mat3::from_mat4(m).inverse().transpose());
    }
    if skinned && mesh.skinned_position.exists {
        let place = if mesh.skinned_is_local { mat(&node.geometry_to_world) } else { Mat4::IDENTITY };
        for (corner, &v) in mesh.vertex_indices.iter().enumerate() {
            if let Some(p) = points.get_mut(v as usize) {
                *p = place.transform_point3(v3(mesh.skinned_position[corner]));
            }
        }
    }
}

/// Which take plays for source `name`: one take, by index or by name; the first by default (none when the
/// file has no take).
pub(crate) fn select_take(asset: &FbxAsset, name: &str, sel: &Clips) -> Result<Option<usize>, Error> {
    let n = asset.takes.len();
    let names = || asset.takes.iter().map(|t| format!("`{}`", t.name)).collect::<Vec<_>>().join(", ");
    let refuse = |message: String| Error::Clip { name: name.to_string(), message };
    let file = asset.path.display();
    match sel {
        Clips::First => Ok((n > 0).then_some(0)),
        Clips::These(one) => match one.as_slice() {
            [Clip::Index(i)] if *i < n => Ok(Some(*i)),
            [Clip::Index(i)] => Err(refuse(format!("{file}: there is no take {i} (the file has {n}: {})", names()))),
            [Clip::Name(s)] => asset
                .takes
                .iter()
                .position(|t| t.name == *s)
                .map(Some)
                .ok_or_else(|| refuse(format!("{file}: no take named `{s}` (takes: {})", names()))),
            _ => Err(refuse(format!("{file}: an FBX source plays one take: name one (takes: {})", names()))),
        },
        // `"all"` names no take of the file, as a name it would.
        Clips::All => Err(refuse(format!("{file}: no take named `all` (takes: {})", names()))),
    }
}
