//! `[source.NAME]`: where geometry comes from (animated glTF, static mesh, PLY point-cloud sequence, mesh
//! sequence).

use serde::Deserialize;
use toml::Spanned;

use super::diag::Diagnostic;
use super::frames::Frames;
use super::transform::Transform;

/// One `[source.NAME]` table. Exactly one of `gltf`, `fbx`, `blend`, `mesh`, `ply_sequence`, `mesh_sequence`,
/// `plane` is set.
#[derive(Debug, Clone, Default, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Source {
    /// An animated (or static) glTF 2.0 file, `.gltf` or `.glb`.
    #[schemars(with = "Option<String>")]
    pub(super) gltf: Option<Spanned<String>>,
    /// An animated (or static) FBX file, ascii or binary (6100–7700): skinning, blend shapes, takes.
    #[schemars(with = "Option<String>")]
    pub(super) fbx: Option<Spanned<String>>,
    /// A Blender file, imported by running Blender headless (`VVGEN_BLENDER`, else `blender` on the PATH) once
    /// per content of the file and what it links, through the cache; animation baked per frame.
    #[schemars(with = "Option<String>")]
    pub(super) blend: Option<Spanned<String>>,
    /// A `.blend` source's object to import (with its children and the armatures that deform them); default:
    /// every object the scene renders.
    pub object: Option<String>,
    /// A `.blend` source's collection to import (with its child collections).
    pub collection: Option<String>,
    /// A static mesh or cloud: glTF, PLY, OBJ (with MTL and textures), STL or Draco (`.drc`).
    #[schemars(with = "Option<String>")]
    pub(super) mesh: Option<Spanned<String>>,
    /// A PLY sequence: a pattern with `{frame}` / `{frame:04}`, or a glob (`*`, `?`, `[…]`).
    #[schemars(with = "Option<String>")]
    pub(super) ply_sequence: Option<Spanned<String>>,
    /// A mesh sequence, one file per frame (OBJ with MTL and textures, textured PLY, STL, or glTF), with the same
    /// patterns and globs as `ply_sequence`; the topology may change every frame.
    #[schemars(with = "Option<String>")]
    pub(super) mesh_sequence: Option<Spanned<String>>,
    /// A built-in ground: a double-sided diffuse rectangle in the world's XY plane, centred on the origin,
    /// that receives shadows and casts none (world units: `[transform]` does not apply to it).
    #[schemars(with = "Option<Plane>")]
    pub(super) plane: Option<Spanned<Plane>>,
    /// Which glTF animation clips play: an index, a name, a list of them, or `"all"`. Default: the first clip.
    #[schemars(with = "Option<AnimationSel>")]
    pub(super) animation: Option<Spanned<AnimationSel>>,
    /// Which scene: a glTF scene by index (default: the file's default scene, else all scenes), or a `.blend`
    /// file's scene by name (default: the scene the file was saved with).
    pub scene: Option<SceneSel>,
    /// Frame times (glTF) or frame numbers (PLY sequences).
    #[schemars(with = "Option<Frames>")]
    pub(super) frames: Option<Spanned<Frames>>,
    /// A transform applied to this source alone, before the global `[transform]`.
    pub transform: Option<Transform>,
    /// A point subtracted from a PLY or OBJ file's coordinates as they are read, in double precision: a scan in
    /// georeferenced coordinates (millions of metres from the origin) read relative to a point near it keeps
    /// detail that single precision, which positions are held in, would step (0.25 m at 4 000 km). For PLY and
    /// OBJ files: `mesh`, `ply_sequence`, and `mesh_sequence` of `.ply` or `.obj` frames.
    #[schemars(with = "Option<[f64; 3]>")]
    pub(super) origin: Option<Spanned<[f64; 3]>>,
    /// Takes every material's own opacity as 1 (an FBX's `Opacity` or `TransparentColor`, an MTL's `d`, a glTF's
    /// base colour alpha), for files whose exporter wrote opaque surfaces as transparent: Blender's importer reads
    /// them as transparent, so Cycles (and vvgen, by default) draws nothing of them. A texture's alpha still cuts
    /// out. `vvgen new` sets it when nothing of a file would show otherwise.
    #[schemars(with = "Option<bool>")]
    pub(super) opaque: Option<Spanned<bool>>,
}

/// `plane = { size = [w, d], color = [r, g, b], z = … }`.
#[derive(Debug, Clone, Copy, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Plane {
    /// Width along X and depth along Y, world units.
    pub size: [f64; 2],
    /// Linear RGB albedo, as glTF's `baseColorFactor` (default 0.8, Blender's default grey).
    #[serde(default = "grey")]
    pub color: [f64; 3],
    /// Height; default: the lowest point of the other sources over all frames (the subject stands on it).
    pub z: Option<f64>,
}

fn grey() -> [f64; 3] {
    [0.8; 3]
}

/// `scene = 0` (glTF) or `scene = "Scene.001"` (`.blend`).
#[derive(Debug, Clone, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(untagged)]
pub enum SceneSel {
    /// A scene by index (glTF).
    Index(u32),
    /// A scene by name (`.blend`).
    Name(String),
}

/// What kind of source a table describes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SourceKind {
    /// `gltf = …`
    Gltf,
    /// `fbx = …`
    Fbx,
    /// `blend = …`
    Blend,
    /// `mesh = …`
    Mesh,
    /// `ply_sequence = …`
    PlySequence,
    /// `mesh_sequence = …`
    MeshSequence,
}

impl SourceKind {
    /// Whether the source is one file per frame.
    pub fn is_sequence(self) -> bool {
        matches!(self, SourceKind::PlySequence | SourceKind::MeshSequence)
    }
}

/// Clip selection: `animation = 0`, `"Walk"`, `[0, "Wave"]` or `"all"`.
#[derive(Debug, Clone, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(untagged)]
pub enum AnimationSel {
    /// A clip by index.
    Index(u32),
    /// A clip by name, or `"all"`.
    Name(String),
    /// Several clips playing together.
    Many(Vec<ClipRef>),
}

/// One clip reference inside a list.
#[derive(Debug, Clone, Deserialize, PartialEq, schemars::JsonSchema)]
#[serde(untagged)]
pub enum ClipRef {
    /// By index.
    Index(u32),
    /// By name.
    Name(String),
}

impl Source {
    /// Where `animation` is written, for an error about the clip it names.
    pub fn animation_span(&self) -> Option<std::ops::Range<usize>> {
        self.animation.as_ref().map(|a| a.span())
    }
}

impl Source {
    /// The kind and the path string, if exactly one kind is set.
    pub(super) fn kind_spanned(&self) -> Option<(SourceKind, &Spanned<String>)> {
        let set = [
            (SourceKind::Gltf, &self.gltf),
            (SourceKind::Fbx, &self.fbx),
            (SourceKind::Blend, &self.blend),
            (SourceKind::Mesh, &self.mesh),
            (SourceKind::PlySequence, &self.ply_sequence),
            (SourceKind::MeshSequence, &self.mesh_sequence),
        ];
        let mut given = set.into_iter().filter_map(|(k, p)| p.as_ref().map(|p| (k, p)));
        match (given.next(), given.next()) {
            (Some(one), None) => Some(one),
            _ => None,
        }
    }

    pub(crate) fn validate(&self, name: &str, table_span: std::ops::Range<usize>, diags: &mut Vec<Diagnostic>) {
        let mut set: Vec<std::ops::Range<usize>> =
            [&self.gltf, &self.fbx, &self.blend, &self.mesh, &self.ply_sequence, &self.mesh_sequence]
                .into_iter()
                .flatten()
                .map(|s| s.span())
                .collect();
        set.extend(self.plane.as_ref().map(|p| p.span()));
        set.sort_by_key(|s| s.start);
        match set.len() {
            0 => diags.push(
                Diagnostic::error(format!("source `{name}` names no file"), Some(table_span.clone())).with_help(
                    "add one of `gltf = \"…\"`, `fbx = \"…\"`, `blend = \"…\"`, `mesh = \"…\"`, `ply_sequence = \"…\"`, \
                     `mesh_sequence = \"…\"` or \
                     `plane = { size = [w, d] }`",
                ),
            ),
            1 => {}
            _ => diags.push(
                Diagnostic::error(
                    format!(
                        "source `{name}` sets more than one of `gltf`, `fbx`, `blend`, `mesh`, `ply_sequence`, \
                         `mesh_sequence`, `plane`"
                    ),
                    Some(set[1].clone()),
                )
                .with_help("one source is one file or sequence; declare another `[source.…]` for the second"),
            ),
        }
        if let Some(p) = &self.plane {
            let v = p.get_ref();
            if !v.size.iter().all(|s| *s > 0.0 && *s <= 1e6) {
                diags.push(
                    Diagnostic::error("a plane's `size` must be two positive extents", Some(p.span()))
                        .with_help("e.g. plane = { size = [6, 6] }"),
                );
            }
            if v.color.iter().any(|c| !(0.0..=1.0).contains(c)) {
                diags.push(Diagnostic::error("a plane's `color` components must be in 0..1", Some(p.span())));
            }
            for (key, set) in [
                ("animation", self.animation.is_some()),
                ("frames", self.frames.is_some()),
                ("transform", self.transform.is_some()),
                ("scene", self.scene.is_some()),
                ("opaque", self.opaque.is_some()),
            ] {
                if set {
                    diags.push(
                        Diagnostic::error(format!("`{key}` does not apply to a `plane`"), Some(table_span.clone()))
                            .with_help("a plane is static and placed in world units"),
                    );
                }
            }
        }
        if let (Some(o), Some((kind, file))) = (&self.origin, self.kind_spanned()) {
            let decimals = |f: &str| [".ply", ".obj"].iter().any(|e| f.to_ascii_lowercase().ends_with(e));
            let reads_decimals = match kind {
                SourceKind::PlySequence => true,
                SourceKind::Mesh | SourceKind::MeshSequence => decimals(file.get_ref()),
                _ => false,
            };
            if !o.get_ref().iter().all(|v| v.is_finite()) {
                diags.push(Diagnostic::error("`origin` must be three finite numbers", Some(o.span())));
            } else if !reads_decimals {
                diags.push(
                    Diagnostic::error(
                        "`origin` applies to PLY and OBJ files, whose coordinates may hold more digits than single \
                         precision; this source reads neither",
                        Some(o.span()),
                    )
                    .with_help("to move this source, use `transform = { translate = [x, y, z] }`"),
                );
            }
        }
        if let Some((kind, _)) = self.kind() {
            if !matches!(kind, SourceKind::Gltf | SourceKind::Fbx) {
                if let Some(a) = &self.animation {
                    let help = if kind == SourceKind::Blend {
                        "a `.blend` plays every action its objects have, as Blender does; choose the frames with \
                         `frames = { start = …, end = … }` (Blender's frame numbers)"
                    } else {
                        "remove it"
                    };
                    diags.push(
                        Diagnostic::error("`animation` applies only to `gltf` and `fbx` sources", Some(a.span()))
                            .with_help(help),
                    );
                }
            }
            match (&self.scene, kind) {
                (None, _)
                | (Some(SceneSel::Index(_)), SourceKind::Gltf)
                | (Some(SceneSel::Name(_)), SourceKind::Blend) => {}
                (Some(SceneSel::Name(n)), SourceKind::Gltf) => diags.push(
                    Diagnostic::error(
                        format!("`scene = \"{n}\"`: a glTF file's scene is chosen by index"),
                        Some(table_span.clone()),
                    )
                    .with_help("e.g. scene = 0 (`vvgen inspect` lists the file's scenes)"),
                ),
                (Some(SceneSel::Index(i)), SourceKind::Blend) => diags.push(
                    Diagnostic::error(
                        format!("`scene = {i}`: a `.blend` file's scene is chosen by name"),
                        Some(table_span.clone()),
                    )
                    .with_help("e.g. scene = \"Scene\" (the vvgen error for a wrong name lists the file's scenes)"),
                ),
                (Some(_), _) => diags.push(Diagnostic::error(
                    "`scene` applies only to `gltf` and `blend` sources",
                    Some(table_span.clone()),
                )),
            }
            if kind != SourceKind::Blend {
                for (key, set) in [("object", self.object.is_some()), ("collection", self.collection.is_some())] {
                    if set {
                        diags.push(Diagnostic::error(
                            format!("`{key}` applies only to `blend` sources"),
                            Some(table_span.clone()),
                        ));
                    }
                }
            } else if self.object.is_some() && self.collection.is_some() {
                diags.push(
                    Diagnostic::error("set `object` or `collection`, not both", Some(table_span.clone()))
                        .with_help("an object brings its children; a collection brings its child collections"),
                );
            }
            if kind == SourceKind::Mesh {
                if let Some(f) = &self.frames {
                    diags.push(
                        Diagnostic::error("a static `mesh` has no frames", Some(f.span()))
                            .with_help("remove `frames`, or use `gltf = …` for an animated file"),
                    );
                }
            }
            if kind.is_sequence() {
                if let Some(f) = &self.frames {
                    if f.get_ref().count.is_some()
                        && f.get_ref().start.is_none()
                        && self.kind().is_some_and(|(_, p)| is_pattern(p))
                    {
                        diags.push(
                            Diagnostic::error("a `{frame}` pattern needs `start` with `count`", Some(f.span()))
                                .with_help("e.g. frames = { start = 1000, count = 300 }"),
                        );
                    }
                }
            }
        }
        if let Some(f) = &self.frames {
            Frames::validate(f, diags);
        }
        if let Some(a) = &self.animation {
            if let AnimationSel::Many(v) = a.get_ref() {
                if v.is_empty() {
                    diags.push(
                        Diagnostic::error("empty animation list", Some(a.span()))
                            .with_help("name at least one clip, or remove `animation` for the first clip"),
                    );
                }
            }
        }
        if let Some(t) = &self.transform {
            t.validate(diags);
        }
    }
}

/// Whether a `ply_sequence` string is a `{frame}` pattern (as opposed to a glob).
pub fn is_pattern(s: &str) -> bool {
    s.contains("{frame")
}

/// Plain values of the fields whose spans stay inside `manifest` (for diagnostics).
impl Source {
    /// The glTF file, when given.
    pub fn gltf(&self) -> Option<&str> {
        self.gltf.as_ref().map(|f| f.get_ref().as_str())
    }

    /// The FBX file, when given.
    pub fn fbx(&self) -> Option<&str> {
        self.fbx.as_ref().map(|f| f.get_ref().as_str())
    }

    /// The `.blend` file, when given.
    pub fn blend(&self) -> Option<&str> {
        self.blend.as_ref().map(|f| f.get_ref().as_str())
    }

    /// The glTF scene index, when given.
    pub fn scene_index(&self) -> Option<usize> {
        match self.scene {
            Some(SceneSel::Index(i)) => Some(i as usize),
            _ => None,
        }
    }

    /// The `.blend` scene name, when given.
    pub fn scene_name(&self) -> Option<&str> {
        match &self.scene {
            Some(SceneSel::Name(n)) => Some(n),
            _ => None,
        }
    }

    /// The mesh file, when given.
    pub fn mesh(&self) -> Option<&str> {
        self.mesh.as_ref().map(|f| f.get_ref().as_str())
    }

    /// `opaque = true`: every material's own opacity taken as 1.
    pub fn opaque(&self) -> bool {
        self.opaque.as_ref().is_some_and(|o| *o.get_ref())
    }

    /// `origin = [x, y, z]`: the point subtracted from its PLY files' coordinates as they are read.
    pub fn origin(&self) -> Option<[f64; 3]> {
        self.origin.as_ref().map(|o| *o.get_ref())
    }

    /// The PLY sequence pattern or glob, when given.
    pub fn ply_sequence(&self) -> Option<&str> {
        self.ply_sequence.as_ref().map(|f| f.get_ref().as_str())
    }

    /// The mesh sequence pattern or glob, when given.
    pub fn mesh_sequence(&self) -> Option<&str> {
        self.mesh_sequence.as_ref().map(|f| f.get_ref().as_str())
    }

    /// The ground plane, when this source is one.
    pub fn plane(&self) -> Option<&Plane> {
        self.plane.as_ref().map(|p| p.get_ref())
    }

    /// The animation selection, when given.
    pub fn animation(&self) -> Option<&AnimationSel> {
        self.animation.as_ref().map(|a| a.get_ref())
    }

    /// The frame selection, when given.
    pub fn frames(&self) -> Option<&Frames> {
        self.frames.as_ref().map(|f| f.get_ref())
    }

    /// The source's kind and its file (manifest-relative).
    pub fn kind(&self) -> Option<(SourceKind, &str)> {
        self.kind_spanned().map(|(k, p)| (k, p.get_ref().as_str()))
    }
}
