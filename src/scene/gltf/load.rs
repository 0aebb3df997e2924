//! Loading a glTF file into [`GltfAsset`]: buffers (GLB chunk, side-car files, `data:` URIs; never outside
//! the file's folder), decoded textures, materials, rest-pose primitives, nodes, skins and animations.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use glam::{Mat4, Quat, Vec2, Vec3, Vec4};
use gltf::mesh::Mode;

use super::accessor::{read_f32, read_u32};
use super::anim::{Animation, Channel, Interp, Sampler, Target};
use super::instancing;
use super::materials::{linear_data_textures, material, unread_looks};
use crate::scene::light::{FileLight, GltfLightKind};
use crate::scene::material::Material;
use crate::scene::posed::PrimKind;
use crate::scene::texture::Texture;

/// A loaded glTF: everything needed to pose it at any time, with no further I/O.
#[derive(Debug, Clone)]
pub struct GltfAsset {
    /// The file.
    pub path: PathBuf,
    /// Materials (index = glTF material index), then the two a primitive without one gets: white for one with
    /// COLOR_0 (its colours are its colour), [`Material::unassigned`] for one without.
    pub materials: Vec<Material>,
    /// Decoded textures (index = glTF texture index), shared with every posed frame (so their mip chains are
    /// built once per build, not once per frame or per poser).
    pub textures: Arc<Vec<Texture>>,
    /// Meshes: rest-pose primitives.
    pub meshes: Vec<Vec<Primitive>>,
    /// Nodes.
    pub nodes: Vec<Node>,
    /// Skins.
    pub skins: Vec<Skin>,
    /// Animation clips.
    pub animations: Vec<Animation>,
    /// Root nodes of the scenes in use.
    pub roots: Vec<usize>,
    /// `KHR_lights_punctual` lights (index = the extension's light index), in Blender's units.
    pub lights: Vec<FileLight>,
    /// Cameras in the file: (node name, vertical fov in radians, aspect ratio) of perspective cameras.
    pub cameras: Vec<FileCamera>,
    /// Non-fatal problems (skipped line primitives, normalized quaternions).
    pub warnings: Vec<String>,
    /// Nodes reachable from the roots, parents first, with their parents (see [`GltfAsset::traversal`]).
    pub order: Vec<(usize, Option<usize>)>,
}

/// A camera found in the file.
#[derive(Debug, Clone, PartialEq)]
pub struct FileCamera {
    /// Node index.
    pub node: usize,
    /// Camera name.
    pub name: String,
    /// `perspective` or `orthographic`.
    pub kind: &'static str,
    /// Vertical field of view (perspective), radians.
    pub yfov: Option<f32>,
}

/// A primitive at rest.
#[derive(Debug, Clone)]
pub struct Primitive {
    /// Triangles or points.
    pub kind: PrimKind,
    /// POSITION.
    pub positions: Vec<Vec3>,
    /// NORMAL (generated when absent).
    pub normals: Vec<Vec3>,
    /// The TEXCOORD set the base colour texture reads (empty when untextured).
    pub uvs: Vec<Vec2>,
    /// COLOR_0, linear RGBA (empty means white).
    pub colors: Vec<Vec4>,
    /// Tangents (xyz toward +u, w the handedness) for the material's normal texture: TANGENT, else generated
    /// by MikkTSpace. Empty without a normal texture.
    pub tangents: Vec<Vec4>,
    /// Triangle list indices (empty for points).
    pub indices: Vec<u32>,
    /// Material index into [`GltfAsset::materials`].
    pub material: u32,
    /// Influences per vertex (4 × number of JOINTS_n sets), 0 when unskinned.
    pub influences: usize,
    /// Joint indices, `influences` per vertex.
    pub joints: Vec<u16>,
    /// Weights, `influences` per vertex, renormalized to sum 1.
    pub weights: Vec<f32>,
    /// Morph target POSITION deltas (one Vec per target; empty Vec when the target has none).
    pub morph_positions: Vec<Vec<Vec3>>,
    /// Morph target NORMAL deltas.
    pub morph_normals: Vec<Vec<Vec3>>,
    /// The 3D Gaussians of a `KHR_gaussian_splatting` point primitive, one per point ([`super::splats`]).
    pub gaussians: Option<std::sync::Arc<crate::scene::gaussians::GaussianData>>,
}

/// A node.
#[derive(Debug, Clone)]
pub struct Node {
    /// Name, if any.
    pub name: Option<String>,
    /// Children.
    pub children: Vec<usize>,
    /// Rest translation.
    pub translation: Vec3,
    /// Rest rotation.
    pub rotation: Quat,
    /// Rest scale.
    pub scale: Vec3,
    /// A fixed matrix (nodes with `matrix` cannot be animated).
    pub matrix: Option<Mat4>,
    /// Mesh index.
    pub mesh: Option<usize>,
    /// Skin index.
    pub skin: Option<usize>,
    /// Morph weights: node's, else the mesh's defaults, else zeros.
    pub weights: Vec<f32>,
    /// `KHR_lights_punctual` light index.
    pub light: Option<usize>,
    /// `EXT_mesh_gpu_instancing`: where each copy of the mesh lies, relative to the node (empty: one copy, at the
    /// node; always empty for a skinned mesh, drawn once). See [`super::instancing`].
    pub instances: Vec<Mat4>,
}

/// A skin.
#[derive(Debug, Clone)]
pub struct Skin {
    /// Joint node indices.
    pub joints: Vec<usize>,
    /// Inverse bind matrices (identity when absent).
    pub inverse_bind: Vec<Mat4>,
}

fn err(path: &Path, msg: impl std::fmt::Display) -> crate::scene::Error {
    crate::scene::Error::Gltf { path: path.to_path_buf(), message: msg.to_string() }
}

/// Loads a `.gltf` or `.glb`. `scene`: which scene (default: the file's default, else all).
pub fn load(path: &Path, scene: Option<usize>) -> Result<GltfAsset, crate::scene::Error> {
    let bytes = std::fs::read(path).map_err(|e| crate::scene::Error::Io { path: path.to_path_buf(), source: e })?;
    load_slice(&bytes, path, scene)
}

/// [`load`] from the file's bytes; `path` names it in errors and locates its side-car files.
pub fn load_slice(bytes: &[u8], path: &Path, scene: Option<usize>) -> Result<GltfAsset, crate::scene::Error> {
    let (gltf::Gltf { document, blob }, set_aside) = super::document::parse(bytes).map_err(|e| err(path, e))?;
    let dir = crate::scene::input::folder_of(path);
    let mut buffers = super::uri::buffers(&document, blob, dir).map_err(|e| err(path, e))?;
    let mut warnings = set_aside;
    let document = super::meshopt::decode(document, &mut buffers).map_err(|e| err(path, e))?;
    let (document, decoded) = super::draco::decode(document, &mut buffers).map_err(|e| err(path, e))?;
    warnings.extend(decoded);
    let doc = &document;

    // Textures, sRGB as base colour and emissive use them (data textures get linear copies below).
    let mut textures = super::image::textures(doc, &buffers, dir).map_err(|e| err(path, e))?;

    let (mut materials, spec_gloss): (Vec<Material>, Vec<_>) = doc.materials().map(|m| material(&m)).unzip();
    warnings.extend(unread_looks(doc.materials()));
    linear_data_textures(&mut materials, &mut textures);
    // After the linear copies: the baked metallic-roughness images are linear already.
    for (i, (m, sg)) in materials.iter_mut().zip(&spec_gloss).enumerate() {
        if let Some(w) = sg.as_ref().and_then(|sg| sg.apply(m, &mut textures)) {
            warnings.push(format!("materials[{i}]: {w}"));
        }
    }
    let default_material = materials.len() as u32;
    materials.push(Material::default());
    materials.push(Material::unassigned());

    let mut meshes = Vec::new();
    for mesh in doc.meshes() {
        let mut prims = Vec::new();
        for (pi, p) in mesh.primitives().enumerate() {
            match primitive(&p, &buffers, &materials, default_material) {
                Ok(Some(prim)) => prims.push(prim),
                Ok(None) => {
                    warnings.push(format!("mesh {} primitive {pi}: {:?} lines are skipped", mesh.index(), p.mode()))
                }
                Err(e) => return Err(err(path, format!("mesh {} primitive {pi}: {e}", mesh.index()))),
            }
        }
        meshes.push(prims);
    }

    let mut instanced = (0u64, 0u64);
    let nodes: Vec<Node> = doc
        .nodes()
        .map(|n| {
            let (matrix, (t, r, s)) = match n.transform() {
                gltf::scene::Transform::Matrix { matrix } => {
                    (Some(Mat4::from_cols_array_2d(&matrix)), (Vec3::ZERO, Quat::IDENTITY, Vec3::ONE))
                }
                gltf::scene::Transform::Decomposed { translation, rotation, scale } => {
                    (None, (Vec3::from(translation), Quat::from_array(rotation).normalize(), Vec3::from(scale)))
                }
            };
            let n_targets =
                n.mesh().map(|m| m.primitives().map(|p| p.morph_targets().len()).max().unwrap_or(0)).unwrap_or(0);
            let mut weights = n
                .weights()
                .map(<[f32]>::to_vec)
                .or_else(|| n.mesh().and_then(|m| m.weights().map(<[f32]>::to_vec)))
                .unwrap_or_default();
            weights.resize(n_targets, 0.0);
            let vertices = n
                .mesh()
                .and_then(|m| meshes.get(m.index()))
                .map_or(0, |ps: &Vec<Primitive>| ps.iter().map(|p| p.positions.len() as u64).sum::<u64>());
            // A skinned mesh is drawn once: the extension does not say where a skin's copies go.
            let instances = match (n.mesh(), n.skin()) {
                (Some(_), None) => instancing::instances(&n, doc, &buffers, vertices, &mut instanced)
                    .map_err(|e| err(path, format!("node {}: {e}", n.index())))?,
                (Some(_), Some(_)) if n.extensions().is_some_and(|e| e.contains_key("EXT_mesh_gpu_instancing")) => {
                    warnings.push(format!(
                        "node {}: a skinned mesh's EXT_mesh_gpu_instancing copies are drawn once (the extension does \
                         not say where a skin's copies go)",
                        n.index()
                    ));
                    Vec::new()
                }
                _ => Vec::new(),
            };
            Ok(Node {
                name: n.name().map(str::to_string),
                children: n.children().map(|c| c.index()).collect(),
                translation: t,
                rotation: r,
                scale: s,
                matrix,
                mesh: n.mesh().map(|m| m.index()),
                skin: n.skin().map(|s| s.index()),
                weights,
                light: n.light().map(|l| l.index()),
                instances,
            })
        })
        .collect::<Result<_, crate::scene::Error>>()?;

    let mut skins = Vec::new();
    for s in doc.skins() {
        let joints: Vec<usize> = s.joints().map(|j| j.index()).collect();
        let inverse_bind = match s.inverse_bind_matrices() {
            Some(acc) => {
                let v = read_f32(&acc, &buffers).map_err(|e| err(path, e))?;
                if v.len() < joints.len() * 16 {
                    return Err(err(path, format!("skin {} has fewer inverse bind matrices than joints", s.index())));
                }
                v.chunks_exact(16).take(joints.len()).map(Mat4::from_cols_slice).collect()
            }
            None => vec![Mat4::IDENTITY; joints.len()],
        };
        skins.push(Skin { joints, inverse_bind });
    }
    for (ni, node) in nodes.iter().enumerate() {
        if let (Some(m), Some(s)) = (node.mesh, node.skin) {
            let n_joints = skins[s].joints.len();
            if meshes[m].iter().any(|p| p.joints.iter().any(|&j| j as usize >= n_joints)) {
                return Err(err(path, format!("node {ni}: a JOINTS index is beyond skin {s}'s {n_joints} joints")));
            }
        }
    }

    let mut animations = Vec::new();
    for a in doc.animations() {
        let mut channels = Vec::new();
        for c in a.channels() {
            let s = c.sampler();
            let times =
                read_f32(&s.input(), &buffers).map_err(|e| err(path, format!("animation {}: {e}", a.index())))?;
            let values =
                read_f32(&s.output(), &buffers).map_err(|e| err(path, format!("animation {}: {e}", a.index())))?;
            let node = c.target().node().index();
            let target = match c.target().property() {
                gltf::animation::Property::Translation => Target::Translation,
                gltf::animation::Property::Rotation => Target::Rotation,
                gltf::animation::Property::Scale => Target::Scale,
                gltf::animation::Property::MorphTargetWeights => Target::Weights,
            };
            let width = match target {
                Target::Translation | Target::Scale => 3,
                Target::Rotation => 4,
                Target::Weights => nodes[node].weights.len().max(1),
            };
            let interp = match s.interpolation() {
                gltf::animation::Interpolation::Step => Interp::Step,
                gltf::animation::Interpolation::Linear => Interp::Linear,
                gltf::animation::Interpolation::CubicSpline => Interp::CubicSpline,
            };
            let sampler = Sampler::new(times, values, width, interp, target == Target::Rotation)
                .map_err(|e| err(path, format!("animation {} channel {}: {e}", a.index(), c.index())))?;
            if sampler.normalized_quaternions {
                warnings.push(format!(
                    "animation {} channel {}: rotation keys were not unit quaternions and were normalized",
                    a.index(),
                    c.index()
                ));
            }
            channels.push(Channel { node, target, sampler });
        }
        animations.push(Animation::new(a.name().map(str::to_string), channels));
    }

    let roots: Vec<usize> = match scene {
        Some(i) => doc
            .scenes()
            .nth(i)
            .ok_or_else(|| err(path, format!("there is no scene {i}")))?
            .nodes()
            .map(|n| n.index())
            .collect(),
        None => match doc.default_scene() {
            Some(s) => s.nodes().map(|n| n.index()).collect(),
            // A file without scenes is a library of nodes (the spec leaves what to show to the reader): its
            // root nodes, those no node holds as a child, as Blender's importer shows them.
            None if doc.scenes().len() == 0 => {
                let mut held = vec![false; doc.nodes().len()];
                doc.nodes().flat_map(|n| n.children()).for_each(|c| held[c.index()] = true);
                (0..held.len()).filter(|&i| !held[i]).collect()
            }
            None => doc.scenes().flat_map(|s| s.nodes().map(|n| n.index()).collect::<Vec<_>>()).collect(),
        },
    };
    let cameras = doc
        .nodes()
        .filter_map(|n| {
            n.camera().map(|c| match c.projection() {
                gltf::camera::Projection::Perspective(p) => FileCamera {
                    node: n.index(),
                    name: c.name().unwrap_or("").to_string(),
                    kind: "perspective",
                    yfov: Some(p.yfov()),
                },
                gltf::camera::Projection::Orthographic(_) => FileCamera {
                    node: n.index(),
                    name: c.name().unwrap_or("").to_string(),
                    kind: "orthographic",
                    yfov: None,
                },
            })
        })
        .collect();
    let lights = match doc.lights() {
        Some(lights) => lights
            .map(|l| {
                use gltf::khr_lights_punctual::Kind;
                let kind = match l.kind() {
                    Kind::Directional => GltfLightKind::Directional,
                    Kind::Point => GltfLightKind::Point,
                    Kind::Spot { inner_cone_angle, outer_cone_angle } => {
                        GltfLightKind::Spot { inner: inner_cone_angle, outer: outer_cone_angle }
                    }
                };
                FileLight::from_gltf(l.name(), l.color(), l.intensity(), kind)
                    .map_err(|e| err(path, format!("KHR_lights_punctual.lights[{}]: {e}", l.index())))
            })
            .collect::<Result<Vec<_>, _>>()?,
        None => Vec::new(),
    };
    let mut asset = GltfAsset {
        path: path.to_path_buf(),
        materials,
        textures: Arc::new(textures),
        meshes,
        nodes,
        skins,
        animations,
        roots,
        lights,
        cameras,
        warnings,
        order: Vec::new(),
    };
    asset.order = asset.traversal();
    Ok(asset)
}

fn vec3s(v: Vec<f32>) -> Vec<Vec3> {
    v.chunks_exact(3).map(Vec3::from_slice).collect()
}

fn primitive(
    p: &gltf::Primitive<'_>,
    buffers: &[Vec<u8>],
    materials: &[Material],
    // The first of the two defaults (white, then unassigned grey).
    default_material: u32,
) -> Result<Option<Primitive>, String> {
    let kind = match p.mode() {
        Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan => PrimKind::Triangles,
        Mode::Points => PrimKind::Points,
        Mode::Lines | Mode::LineLoop | Mode::LineStrip => return Ok(None),
    };
    let pos_acc = p.get(&gltf::Semantic::Positions).ok_or("no POSITION attribute")?;
    let positions = vec3s(read_f32(&pos_acc, buffers)?);
    if let Some(i) = positions.iter().position(|v| !v.is_finite()) {
        return Err(format!("POSITION {i} ({}) is not finite", positions[i]));
    }
    let n = positions.len();
    let attr = |sem: gltf::Semantic| -> Result<Option<Vec<f32>>, String> {
        match p.get(&sem) {
            Some(acc) if acc.count() != n => Err(format!("{sem:?} has {} elements, POSITION has {n}", acc.count())),
            Some(acc) => read_f32(&acc, buffers).map(Some),
            None => Ok(None),
        }
    };
    let raw_indices: Vec<u32> = match p.indices() {
        Some(acc) => read_u32(&acc, buffers)?,
        None => (0..n as u32).collect(),
    };
    if let Some(&bad) = raw_indices.iter().find(|&&i| i as usize >= n) {
        return Err(format!("index {bad} is out of range: POSITION has {n} vertices"));
    }
    let indices = match (kind, p.mode()) {
        (PrimKind::Points, _) => Vec::new(),
        (_, Mode::TriangleStrip) => (0..raw_indices.len().saturating_sub(2))
            .flat_map(|i| {
                let (a, b, c) = (raw_indices[i], raw_indices[i + 1], raw_indices[i + 2]);
                if i % 2 == 0 {
                    [a, b, c]
                } else {
                    [b, a, c]
                }
            })
            .collect(),
        (_, Mode::TriangleFan) => (1..raw_indices.len().saturating_sub(1))
            .flat_map(|i| [raw_indices[0], raw_indices[i], raw_indices[i + 1]])
            .collect(),
        _ => {
            let mut v = raw_indices;
            v.truncate(v.len() / 3 * 3);
            v
        }
    };
    let coloured = p.get(&gltf::Semantic::Colors(0)).is_some();
    let material = p.material().index().map_or(default_material + u32::from(!coloured), |i| i as u32);
    // One uv set is carried: the base colour texture's, else the first other texture's (glTF files in practice
    // share TEXCOORD_0 between a material's textures).
    let mut mat = materials[material as usize].clone();
    let tex_coord = mat.texture_refs_mut().next().map(|(t, _)| t.tex_coord);
    let uvs = match tex_coord {
        Some(tc) => attr(gltf::Semantic::TexCoords(tc))?
            .map(|v| v.chunks_exact(2).map(Vec2::from_slice).collect())
            .unwrap_or_default(),
        None => Vec::new(),
    };
    let colors: Vec<Vec4> = match p.get(&gltf::Semantic::Colors(0)) {
        Some(acc) => {
            let comps = acc.dimensions().multiplicity();
            let v = attr(gltf::Semantic::Colors(0))?.unwrap_or_default();
            // COLOR_0 is linear already; VEC3 means alpha 1.
            v.chunks_exact(comps).map(|c| Vec4::new(c[0], c[1], c[2], if comps == 4 { c[3] } else { 1.0 })).collect()
        }
        None => Vec::new(),
    };
    let mut normals = attr(gltf::Semantic::Normals)?.map(vec3s).unwrap_or_default();
    if normals.is_empty() {
        normals = if kind == PrimKind::Triangles { smooth_normals(&positions, &indices) } else { vec![Vec3::ZERO; n] };
    } else {
        for v in &mut normals {
            *v = v.normalize_or_zero();
        }
    }
    // A normal texture needs tangents on the uv set carried (the one its texture reads).
    let normal_map = mat.normal_texture.is_some_and(|(r, _)| Some(r.tex_coord) == tex_coord && !uvs.is_empty());
    let tangents = match attr(gltf::Semantic::Tangents)? {
        _ if !normal_map || kind != PrimKind::Triangles => Vec::new(),
        Some(t) if t.len() == 4 * n => t
            .chunks_exact(4)
            .map(|c| {
                let xyz = Vec3::new(c[0], c[1], c[2]).normalize_or_zero();
                xyz.extend(if c[3] < 0.0 { -1.0 } else { 1.0 })
            })
            .collect(),
        Some(_) => return Err("TANGENT must be VEC4 with one element per vertex".into()),
        None => super::tangents::mikktspace(&positions, &normals, &uvs, &indices),
    };
    // Skinning: every JOINTS_n / WEIGHTS_n set, 4 influences each.
    let mut sets = 0;
    while p.get(&gltf::Semantic::Joints(sets)).is_some() && p.get(&gltf::Semantic::Weights(sets)).is_some() {
        sets += 1;
    }
    let influences = sets as usize * 4;
    let (mut joints, mut weights) = (vec![0u16; n * influences], vec![0f32; n * influences]);
    for s in 0..sets as usize {
        let joints_of = p.get(&gltf::Semantic::Joints(s as u32)).expect("BUG: counted among the sets above");
        let j = read_u32(&joints_of, buffers)?;
        let w = attr(gltf::Semantic::Weights(s as u32))?.unwrap_or_default();
        if j.len() != n * 4 || w.len() != n * 4 {
            return Err(format!("JOINTS_{s}/WEIGHTS_{s} must be VEC4 with one element per vertex"));
        }
        for v in 0..n {
            for k in 0..4 {
                joints[v * influences + s * 4 + k] =
                    u16::try_from(j[v * 4 + k]).map_err(|_| "joint index above 65535")?;
                weights[v * influences + s * 4 + k] = w[v * 4 + k];
            }
        }
    }
    if influences > 0 {
        for w in weights.chunks_exact_mut(influences) {
            let sum: f32 = w.iter().sum();
            if sum > 0.0 {
                w.iter_mut().for_each(|x| *x /= sum);
            }
        }
    }
    let (mut morph_positions, mut morph_normals) = (Vec::new(), Vec::new());
    for t in p.morph_targets() {
        let read = |acc: Option<gltf::Accessor<'_>>| -> Result<Vec<Vec3>, String> {
            match acc {
                Some(a) if a.count() != n => {
                    Err(format!("a morph target has {} elements, POSITION has {n}", a.count()))
                }
                Some(a) => read_f32(&a, buffers).map(vec3s),
                None => Ok(Vec::new()),
            }
        };
        morph_positions.push(read(t.positions())?);
        morph_normals.push(read(t.normals())?);
    }
    let mut prim = Primitive {
        kind,
        positions,
        normals,
        tangents,
        uvs,
        colors,
        indices,
        material,
        influences,
        joints,
        weights,
        morph_positions,
        morph_normals,
        gaussians: None,
    };
    if kind == PrimKind::Points {
        if let Some((data, shows)) = super::splats::read(p, buffers, n)? {
            super::splats::keep(&mut prim, data, &shows);
        }
    }
    Ok(Some(prim))
}

/// Area-weighted vertex normals (cross products are proportional to twice the area). Non-indexed triangles
/// share no vertices, so they come out flat.
pub fn smooth_normals(positions: &[Vec3], indices: &[u32]) -> Vec<Vec3> {
    let mut n = vec![Vec3::ZERO; positions.len()];
    for t in indices.chunks_exact(3) {
        let (a, b, c) = (positions[t[0] as usize], positions[t[1] as usize], positions[t[2] as usize]);
        let f = (b - a).cross(c - a);
        for &i in t {
            n[i as usize] += f;
        }
    }
    n.iter_mut().for_each(|v| *v = v.normalize_or_zero());
    n
}
