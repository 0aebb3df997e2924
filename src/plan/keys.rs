//! Frame content keys: what every action that reads a frame is keyed by. A frame's key covers its posed
//! geometry (evaluated animation, so an edit that moves frames 30–59 changes only their keys), materials and
//! textures, or the bytes of its PLY file, with the source → world transform. Output paths, split and output
//! names, table order, comments and thread counts never enter a key.

use super::Error;
use crate::cache::{key, Digest, StatCache};
use crate::manifest::Manifest;
use crate::render::light::glossy;
use crate::scene::material::AlphaMode;
use crate::scene::source::{is_obj, is_ply, is_stl, ply_facts, PlyFacts};
use crate::scene::{Poser, PrimKind, Scene, SourceData};

/// The keys of every scene frame.
#[derive(Debug, Clone, Default)]
pub struct FrameKeys {
    /// What every action reading frame `f` is keyed by: its geometry, materials and textures.
    pub content: Vec<Digest>,
    /// The lights the sources bring at frame `f` (a glTF's `KHR_lights_punctual`, placed by its animated nodes),
    /// when the scene poses any: what lit shading reads besides the content. `None` when there are none, so
    /// builds without file lights keep their keys.
    pub lights: Vec<Option<Digest>>,
    /// What only lit shading reads of frame `f` besides its content: every material field and texture (metalness,
    /// roughness, normal textures…) and the tangents normal textures are read along. `None` for unlit builds.
    /// Apart from `content` so that switching shading re-runs only what shading shapes (the lit `rgba` pass, lit
    /// point colours), not depth, bounds or samples.
    pub lit: Vec<Option<Digest>>,
    /// Whether frame `f` has points of a point primitive with a shadeless (`KHR_materials_unlit`) material: lit
    /// point colours keep their albedo there since "bake 4" baked them lit, so those frames' lit point colours
    /// are keyed apart and re-run; every other frame keeps its keys.
    pub shadeless_points: Vec<bool>,
    /// Whether frame `f` has a transparent (`BLEND`) surface glossy enough for rays
    /// ([`crate::render::light::glossy`]): its lit `rgba` pass reads its lobes' occlusion from the hemisphere since
    /// "render 7" cast rays per sample and per layer, so those frames' lit passes are keyed apart and re-run;
    /// every other frame keeps its keys. A mesh sequence's frames, keyed by their files and not posed to plan,
    /// count as having it.
    pub glossy_glass: Vec<bool>,
    /// Whether frame `f` has points that may cast shadows (a point primitive, plain or of 3D Gaussians, whose
    /// material casts): they have cast into shadow maps since "points cast 1" (triangles alone did before), so
    /// those frames' light is keyed apart, and with it their lit passes and lit point colours; every other frame
    /// keeps its keys. A PLY sequence's frames, and a mesh sequence's PLY and glTF frames and OBJ point clouds,
    /// keyed by their files and not posed to plan, count as having them.
    pub point_casters: Vec<bool>,
    /// Whether frame `f` has two-sided triangles (a double-sided caster's: every PLY, OBJ, STL and FBX mesh's, a
    /// glTF's that asks): their vertices have gathered light on both sides since "sides 1" (their front sides'
    /// alone before, which lit an inside-out mesh by its inside; a mesh closed and facing out, decided as the
    /// light is gathered, still gathers on its fronts alone), so those frames' light is keyed apart, and with it
    /// their lit passes and lit point colours; every other frame keeps its keys. A mesh sequence's frames,
    /// not posed to plan, count as having them; a PLY sequence's when the file has faces or strips.
    pub two_sided: Vec<bool>,
}

/// What a PLY frame's key adds for how its file is read since it first was. Its polygons were all filled by the fan
/// from their first corner before "ply polygons 1" filled the concave ones (and quads folded along their first
/// diagonal) as Blender does; its triangle strips were dropped (the file read as a point cloud) before "ply strips
/// 1" cut them into triangles as Blender 4.x does; its per-corner texture coordinates were not read (the mesh drawn
/// untextured) before "ply wedge uvs 1"; its texture was multiplied by its vertex colours before "ply texture over
/// colours 1" drew the texture alone. A frame with any of these is keyed apart; every other frame (point clouds,
/// triangles, convex polygons, meshes textured per vertex without colours) keeps its key.
fn ply_reading(facts: &PlyFacts) -> [Option<&'static [u8]>; 4] {
    [
        facts.unfanned.then_some(b"ply polygons 1".as_slice()),
        facts.strips.then_some(b"ply strips 1".as_slice()),
        facts.wedge.then_some(b"ply wedge uvs 1".as_slice()),
        facts.tinted.then_some(b"ply texture over colours 1".as_slice()),
    ]
}

/// The keys of every scene frame. `lit` also keys what only lit shading reads ([`FrameKeys::lit`]).
pub fn frame_keys(scene: &Scene, stat: &StatCache, lit: bool) -> Result<FrameKeys, Error> {
    let mut per_source: Vec<Vec<Digest>> = Vec::new();
    let mut lights_per_source: Vec<Vec<Option<Digest>>> = Vec::new();
    let mut lit_per_source: Vec<Vec<Option<Digest>>> = Vec::new();
    let mut shadeless_per_source: Vec<Vec<bool>> = Vec::new();
    let mut glass_per_source: Vec<Vec<bool>> = Vec::new();
    let mut points_per_source: Vec<Vec<bool>> = Vec::new();
    let mut sides_per_source: Vec<Vec<bool>> = Vec::new();
    let mut poser = Poser::default();
    for (i, src) in scene.sources.iter().enumerate() {
        let world = scene.world_from_source(i).to_cols_array();
        let world: &[u8] = bytemuck::cast_slice(&world);
        // A sequence's frames are keyed by their files' bytes: the `origin` subtracted as they are read shapes
        // the positions too (a source without one keeps its keys).
        let origin: Option<&[u8]> = (src.origin != [0.0; 3]).then(|| bytemuck::cast_slice(&src.origin));
        // Files of 3D Gaussians were drawn as points before "gaussians 1" drew them as splats: a sequence of them
        // re-renders (posed sources' Gaussians are in their geometry digest); other sequences keep their keys.
        let splats: Option<&[u8]> = src.splats.then_some(b"gaussians 1".as_slice());
        // `opaque` changes a sequence's materials as its frames are read (posed sources' materials are in their
        // digest); sequences without it keep their keys.
        let opaque: Option<&[u8]> = src.opaque.then_some(b"opaque".as_slice());
        let keys = match &src.data {
            SourceData::Sequence(files) => {
                points_per_source.push(vec![true; files.len()]);
                let facts = files.iter().map(|f| ply_facts(&f.path, stat)).collect::<Result<Vec<_>, _>>()?;
                sides_per_source.push(facts.iter().map(|f| f.surface).collect());
                files
                    .iter()
                    .zip(facts)
                    .map(|(f, facts)| {
                        let d = stat.digest(&f.path).map_err(|e| Error::Input { path: f.path.clone(), source: e })?;
                        // A textured mesh's textures, by content (a cloud has none: its key reads no more).
                        let textures = facts
                            .texture_files(&f.path)?
                            .iter()
                            .map(|p| stat.digest(p).map_err(|e| Error::Input { path: p.clone(), source: e }))
                            .collect::<Result<Vec<_>, _>>()?;
                        let mut bytes: Vec<&[u8]> = vec![world, &d.0];
                        bytes.extend(origin);
                        bytes.extend(splats);
                        bytes.extend(opaque);
                        bytes.extend(ply_reading(&facts).into_iter().flatten());
                        bytes.extend(textures.iter().map(|d| &d.0[..]));
                        Ok(key("frame ply", &bytes))
                    })
                    .collect::<Result<Vec<_>, Error>>()?
            }
            SourceData::MeshSequence(files) => {
                // Its frames are not posed to plan: whether one holds glossy glass is not known, so each counts as
                // holding it (an OBJ's or a `.blend`'s transparent materials may be glossy).
                glass_per_source.push(vec![true; files.len()]);
                sides_per_source.push(vec![true; files.len()]);
                // Nor whether one holds points: an STL never does, an OBJ when it is a point cloud (remembered by
                // the stat cache for its content).
                let points = files.iter().map(|f| match f.path.as_path() {
                    p if is_obj(p) => crate::scene::obj::cloud_cached(p, stat),
                    p => Ok(!is_stl(p)),
                });
                points_per_source.push(points.collect::<Result<_, _>>()?);
                files
                    .iter()
                    .map(|f| {
                        // The frame's file and what it reads besides (MTL files, textures), each by content.
                        let mut parts: Vec<Digest> = Vec::new();
                        // A PLY's textures come with its facts: one lookup for both.
                        let facts = is_ply(&f.path).then(|| ply_facts(&f.path, stat)).transpose()?;
                        let deps = match &facts {
                            Some(facts) => facts.texture_files(&f.path)?,
                            None => crate::scene::source::mesh_frame_deps_cached(&f.path, stat)?,
                        };
                        for p in std::iter::once(&f.path).chain(&deps) {
                            parts.push(stat.digest(p).map_err(|e| Error::Input { path: p.clone(), source: e })?);
                        }
                        let mut bytes: Vec<&[u8]> = vec![world];
                        bytes.extend(origin);
                        bytes.extend(splats);
                        bytes.extend(opaque);
                        // An OBJ's MTL materials were read as Kd and map_Kd alone before "mtl 1" read them as Blender
                        // 4.5's importer does: frames with a material library re-render, others keep their keys.
                        bytes.extend((is_obj(&f.path) && !deps.is_empty()).then_some(b"mtl 1".as_slice()));
                        // An OBJ's polylines of three or more vertices were filled as polygons (tobj's reading) before
                        // "obj polylines 1" dropped them, as Blender draws no lines: frames with them re-render, others
                        // keep their keys.
                        if is_obj(&f.path) && crate::scene::obj::polylines_cached(&f.path, stat)? {
                            bytes.push(b"obj polylines 1");
                        }
                        if let Some(facts) = &facts {
                            bytes.extend(ply_reading(facts).into_iter().flatten());
                        }
                        bytes.extend(parts.iter().map(|d| &d.0[..]));
                        Ok(key("frame mesh", &bytes))
                    })
                    .collect::<Result<Vec<_>, Error>>()?
            }
            SourceData::Gltf { .. } | SourceData::Fbx { .. } | SourceData::Static(_) => {
                let n = src.frame_count();
                let mut keys = Vec::with_capacity(n);
                let mut materials = None;
                let mut lit_materials = None;
                let mut lights = Vec::new();
                let mut lit_keys = Vec::new();
                let mut shadeless = Vec::new();
                let mut glass = Vec::new();
                let mut points = Vec::new();
                let mut sides = Vec::new();
                for f in 0..n {
                    let posed = scene.pose_source(i, f, &mut poser)?;
                    glass.push(posed.primitives.iter().any(|p| {
                        let m = posed.material(p.material);
                        p.kind == PrimKind::Triangles && m.alpha_mode == AlphaMode::Blend && !m.unlit && glossy(m)
                    }));
                    shadeless.push(
                        posed.primitives.iter().any(|p| p.kind == PrimKind::Points && posed.material(p.material).unlit),
                    );
                    points.push(posed.primitives.iter().any(|p| {
                        let m = posed.material(p.material);
                        p.kind == PrimKind::Points && m.casts_shadows && !m.unlit
                    }));
                    sides.push(posed.primitives.iter().any(|p| crate::render::light::two_sided(posed, p)));
                    let m = *materials.get_or_insert_with(|| posed.material_digest());
                    let geometry = posed.geometry_digest();
                    let mut parts: Vec<&[u8]> = vec![geometry.as_bytes(), m.as_bytes()];
                    // Alpha BLEND surfaces have been composited in depth order since the renderer's "render 6"
                    // (drawn as MASK before): frames with them re-render; others keep their keys.
                    if posed.materials.iter().any(|m| m.alpha_mode == crate::scene::material::AlphaMode::Blend) {
                        parts.push(b"alpha blend composited");
                    }
                    // Shadeless (`KHR_materials_unlit`) surfaces ignore Lambert's lights since they were read:
                    // frames with them re-render; others keep their keys.
                    if posed.materials.iter().any(|m| m.unlit) {
                        parts.push(b"unlit materials shadeless");
                    }
                    keys.push(key("frame posed", &parts));
                    // Every material field and the tangents (posed for normal textures): lit shading's alone.
                    lit_keys.push(lit.then(|| {
                        let all = *lit_materials.get_or_insert_with(|| posed.lit_material_digest());
                        let tangents = posed.tangents_digest();
                        let mut parts: Vec<&[u8]> = vec![all.as_bytes()];
                        if let Some(t) = &tangents {
                            parts.push(t.as_bytes());
                        }
                        key("frame lit", &parts)
                    }));
                    // The file's lights, posed only for lit builds (see `Scene::file_lights`).
                    lights.push((!posed.lights.is_empty()).then(|| Digest(*posed.lights_digest().as_bytes())));
                }
                lights_per_source.push(lights);
                lit_per_source.push(lit_keys);
                shadeless_per_source.push(shadeless);
                glass_per_source.push(glass);
                points_per_source.push(points);
                sides_per_source.push(sides);
                keys
            }
        };
        per_source.push(keys);
    }
    // Shorter sources hold their last frame, as when posing.
    let at = |k: &[Digest], f: usize| k[f.min(k.len() - 1)];
    let content = (0..scene.frames)
        .map(|f| {
            let parts: Vec<Digest> = per_source.iter().map(|k| at(k, f)).collect();
            key("frame", &parts.iter().map(|d| &d.0[..]).collect::<Vec<_>>())
        })
        .collect();
    // Per frame, the parts some sources bring (shorter sources hold their last frame), or `None` when none does.
    let gather = |per: &[Vec<Option<Digest>>], what: &str| -> Vec<Option<Digest>> {
        (0..scene.frames)
            .map(|f| {
                let parts: Vec<Digest> =
                    per.iter().filter_map(|l| l.get(f.min(l.len().max(1) - 1)).copied().flatten()).collect();
                (!parts.is_empty()).then(|| key(what, &parts.iter().map(|d| &d.0[..]).collect::<Vec<_>>()))
            })
            .collect()
    };
    let lights = gather(&lights_per_source, "frame lights");
    let lit = gather(&lit_per_source, "frame lit");
    // Per frame, whether any source's frame (shorter sources hold their last) has it.
    let any = |per: &[Vec<bool>]| -> Vec<bool> {
        (0..scene.frames).map(|f| per.iter().any(|s| s.get(f.min(s.len().max(1) - 1)) == Some(&true))).collect()
    };
    let (shadeless_points, glossy_glass) = (any(&shadeless_per_source), any(&glass_per_source));
    let (point_casters, two_sided) = (any(&points_per_source), any(&sides_per_source));
    Ok(FrameKeys { content, lights, lit, shadeless_points, glossy_glass, point_casters, two_sided })
}

/// The content key of `m`'s `[environment] map`, when it names one.
pub fn environment_key(m: &Manifest, stat: &StatCache) -> Result<Option<Digest>, Error> {
    let Some(map) = m.environment.as_ref().and_then(|e| e.map()) else { return Ok(None) };
    let path = m.resolve(map);
    stat.digest(&path).map(Some).map_err(|e| Error::Input { path, source: e })
}
