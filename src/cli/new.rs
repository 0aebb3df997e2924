//! `vvgen new ASSET`: a commented manifest to start from, for a glTF, FBX, `.blend`, PLY, OBJ, STL or Draco file,
//! or a folder of PLY, OBJ, STL or Draco frames. What it can read off the asset (clips, frame count, the up axis)
//! it writes in and says; the rest is the NeRF-synthetic recipe (a ±1.3 box, the hemisphere cameras, D-NeRF's splits).

use std::fmt::Write as _;
use std::path::{Component, Path, PathBuf};
use std::process::ExitCode;

use anyhow::{bail, Context};

use super::up::{cameras_up, obj_up, stl_up, tallest, training_cameras, up_note};
use super::Ui;
use crate::scene;

mod frames;
use frames::{clip_line, first_clip_frames, frames_covering, frames_glob, LONGEST};

/// The writers `--writer` accepts.
pub const WRITERS: [&str; 7] =
    ["dnerf", "nerfstudio", "instant-ngp", "colmap", "dynerf", "static-frames", "ply-sequence"];

/// What the asset is.
enum Asset {
    /// A glTF file and its clips (name, seconds).
    Gltf { clips: Vec<(String, f32)> },
    /// An FBX file and its takes (name, seconds).
    Fbx { takes: Vec<(String, f32)> },
    /// A `.blend` file as Blender exported it.
    Blend { info: scene::blend::Info },
    /// One static mesh (glTF without clips, PLY).
    Mesh,
    /// One file per frame: `ply_sequence` or `mesh_sequence`, with the glob and the frame count.
    Sequence { key: &'static str, glob: String, frames: usize },
}

/// Writes the manifest for `asset` to `out` (default `<asset name>.toml` here).
pub fn run(asset: &Path, writer: &str, out: Option<&Path>, ui: Ui) -> anyhow::Result<ExitCode> {
    // Every problem here is the input's (an asset that cannot be read, a manifest that exists): exit 2.
    write(asset, writer, out, ui).or_else(|e| {
        eprintln!("error: {e:#}");
        Ok(ExitCode::from(super::EXIT_INVALID))
    })
}

fn write(asset: &Path, writer: &str, out: Option<&Path>, ui: Ui) -> anyhow::Result<ExitCode> {
    if !WRITERS.contains(&writer) {
        bail!("unknown writer `{writer}`: one of {}", WRITERS.join(", "));
    }
    // `vvgen new .` names the dataset after the folder, not after `.`.
    let named = if asset.is_dir() { absolute(asset)? } else { asset.to_path_buf() };
    let name = named.file_stem().map(|s| dataset_name(&s.to_string_lossy())).unwrap_or_else(|| "dataset".into());
    let out = out.map(Path::to_path_buf).unwrap_or_else(|| PathBuf::from(format!("{name}.toml")));
    // What the asset is comes first: `vvgen new base.toml` is "not an asset", not "base.toml exists". A .blend
    // is imported into the cache the manifest will use (`cache/` beside it), so its build starts from there.
    let cache = std::env::var_os("VVGEN_CACHE")
        .filter(|p| !p.is_empty())
        .map_or_else(|| crate::manifest::folder_of(&out).join("cache"), PathBuf::from);
    let Described { kind, up, mut note, rest, origin } = describe(asset, &cache, ui)?;
    let flat = flat_colours(&rest);
    // Old FBX exporters (3ds Max's) and some OBJ exporters write opaque surfaces fully transparent as Blender's
    // importer reads them: a manifest that draws nothing of the subject would be no start.
    let opaque =
        !rest.primitives.is_empty() && rest.primitives.iter().all(|p| rest.material(p.material).base_color.w <= 0.0);
    if opaque {
        note.push_str("; every material is fully transparent as Blender reads it: drawn opaque (`opaque = true`)");
    }
    if let Some(o) = origin {
        let _ = write!(note, "; its coordinates are far from zero for its size: read relative to {o:?} (`origin`)");
    }
    match flat {
        Some(0) => note.push_str(
            "; no texture or vertex colours: lit (`shading = \"pbr\"`), since unlit every view is one flat colour",
        ),
        Some(n) => {
            let _ = write!(
                note,
                "; its colours are a palette of {n}, flat patches without shading: lit (`shading = \"pbr\"`), since \
                 unlit every view shows one flat patch per part"
            );
        }
        None => {}
    }
    if out.exists() {
        bail!("{} exists: choose another with -o", out.display());
    }
    let folder = crate::manifest::folder_of(&out);
    std::fs::create_dir_all(folder).with_context(|| format!("creating the folder {}", folder.display()))?;
    let manifest_dir = absolute(folder)?;
    let rel = |p: &Path| -> anyhow::Result<String> { Ok(relative(&manifest_dir, &absolute(p)?)) };
    let cameras = training_cameras(&rest, asset).map(|c| rel(&c)).transpose()?;
    let text = manifest(&name, asset, &kind, up, &note, Look { flat, origin, cameras, opaque }, writer, &rel)?;
    std::fs::write(&out, text).with_context(|| format!("writing {}", out.display()))?;
    if !ui.quiet {
        eprintln!("wrote {}: {note}", out.display());
        eprintln!("next: vvgen check {0} && vvgen build {0}", out.display());
    }
    Ok(ExitCode::SUCCESS)
}

/// What `new` reads off an asset.
struct Described {
    /// Its kind.
    kind: Asset,
    /// Its up axis.
    up: &'static str,
    /// A line saying how those were decided.
    note: String,
    /// Its first frame at rest.
    rest: scene::PosedScene,
    /// A PLY's or OBJ's `origin`, when its coordinates are far from zero for its size ([`far_origin`]).
    origin: Option<[f64; 3]>,
}

/// A PLY or OBJ file at rest, read relative to its `origin` when its coordinates are far from zero for its size.
fn mesh_at_rest(path: &Path) -> anyhow::Result<(scene::PosedScene, Option<[f64; 3]>)> {
    let obj = scene::source::is_obj(path);
    let read = |o: [f64; 3]| if obj { scene::obj::scene_at(path, o) } else { scene::source::ply_scene_at(path, o) };
    let s = read([0.0; 3])?;
    Ok(match far_origin(&s) {
        Some(o) => (read(o)?, Some(o)),
        None => (s, None),
    })
}

/// The asset's kind, its up axis, a line saying how that was decided, its first frame at rest, and a PLY's or
/// OBJ's origin.
fn describe(asset: &Path, cache: &Path, ui: Ui) -> anyhow::Result<Described> {
    let ext = |p: &Path| p.extension().map(|e| e.to_string_lossy().to_ascii_lowercase()).unwrap_or_default();
    if asset.is_dir() {
        // Hidden files left out, as the manifest's glob leaves them (macOS's `._` companions of copied files).
        let hidden = crate::manifest::sequence::hidden;
        let mut files: Vec<PathBuf> = std::fs::read_dir(asset)
            .with_context(|| format!("reading {}", asset.display()))?
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.is_file() && !hidden(p))
            .collect();
        files.sort();
        let count = |e: &str| files.iter().filter(|p| ext(p) == e).count();
        // The kind of frame the folder holds most of (PLY first when as many).
        let (e, n) = ["ply", "obj", "stl", "drc"]
            .map(|e| (e, count(e)))
            .into_iter()
            .rev()
            .max_by_key(|&(_, n)| n)
            .unwrap_or(("ply", 0));
        if n == 0 {
            bail!("{}: no .ply, .obj, .stl or .drc frames in this folder", asset.display());
        }
        let key = if e == "ply" { "ply_sequence" } else { "mesh_sequence" };
        let first = files.iter().find(|p| ext(p) == e).expect("counted above");
        let (frame, origin) =
            if e == "stl" || e == "drc" { (scene::source::mesh_frame(first)?, None) } else { mesh_at_rest(first)? };
        drawable(&frame, first)?;
        let (up, why) = match e {
            "obj" if !points_only(&frame) => obj_up(),
            "stl" => stl_up(),
            _ => tallest(&frame, first),
        };
        let seq = Asset::Sequence { key, glob: frames_glob(&files, e), frames: n };
        let note = format!("{n} {e} frames; {why}");
        return Ok(Described { kind: seq, up, note, rest: frame, origin });
    }
    match ext(asset).as_str() {
        "gltf" | "glb" => {
            let a = scene::gltf::load(asset, None)?;
            if let Some(why) = scene::source::nothing_drawn(asset, a.holds()) {
                bail!("{why}");
            }
            let clips: Vec<(String, f32)> = a
                .animations
                .iter()
                .enumerate()
                .map(|(i, c)| (c.name.clone().unwrap_or_else(|| format!("#{i}")), c.duration()))
                .collect();
            let what = match clips.first() {
                Some((n, d)) => format!("{} clip(s), the first (`{n}`, {d:.2} s) selected", clips.len()),
                None => "no animation: a static mesh".into(),
            };
            let mut rest = scene::PosedScene::default();
            a.pose(&[], 0.0, glam::Mat4::IDENTITY, &mut Default::default(), &mut rest);
            drawable(&rest, asset)?;
            // Posing fills geometry only; the source layer brings the materials and their textures.
            rest.materials = std::sync::Arc::new(a.materials.clone());
            rest.textures = a.textures.clone();
            let kind = if clips.is_empty() { Asset::Mesh } else { Asset::Gltf { clips } };
            // 3D Gaussians keep their trainer's axes through the tools that write them as glTF (splat-transform
            // only turns them 180° about Z): their up is guessed from their extents, as a scan's is.
            let splats = !rest.primitives.is_empty() && rest.primitives.iter().all(|p| p.gaussians.is_some());
            let (up, note) = if splats {
                let (up, why) = tallest(&rest, asset);
                (up, format!("{what}; 3D Gaussians, which keep their trainer's axes in glTF: {why}"))
            } else {
                ("y", format!("{what}; up \"y\": glTF is +Y up by its specification"))
            };
            Ok(Described { kind, up, note, rest, origin: None })
        }
        "fbx" => {
            let a = scene::fbx::load(asset)?;
            if let Some(why) = scene::source::nothing_drawn(asset, a.holds()) {
                bail!("{why}");
            }
            let takes: Vec<(String, f32)> = a.takes.iter().map(|t| (t.name.clone(), t.duration() as f32)).collect();
            let mut rest = scene::PosedScene::default();
            a.pose(None, 0.0, glam::Mat4::IDENTITY, &mut rest)?;
            drawable(&rest, asset)?;
            let what = match takes.first() {
                Some((n, d)) => format!("{} take(s), the first (`{n}`, {d:.2} s) selected", takes.len()),
                None => "no take: a static mesh".into(),
            };
            let note = format!("{what}; in metres and +Z up, as vvgen loads FBX");
            Ok(Described { kind: Asset::Fbx { takes }, up: "z", note, rest, origin: None })
        }
        "blend" => {
            let store = crate::cache::Store::open(cache)?;
            let stat = crate::cache::StatCache::load(&store.root().join("stat").join("new"));
            let say = |what: &str| eprintln!("{what}");
            let note = (!ui.quiet).then_some(&say as &(dyn Fn(&str) + Sync));
            let importer = scene::blend::Importer::new(&store, &stat, note);
            let got = importer.import(asset, &Default::default(), &Default::default())?;
            let _ = stat.save();
            let first = scene::source::mesh_frame(&got.dir.join("frame_00000.gltf"))?;
            drawable(&first, asset)?;
            let info = got.info;
            let what = if info.frames.len() < 2 {
                format!("scene `{}`, no animation: one frame", info.scene)
            } else {
                format!("scene `{}`, frames {}–{} at {} fps", info.scene, info.frame_start, info.frame_end, info.fps)
            };
            let note = format!("{what}; +Z up, as Blender shows it");
            Ok(Described { kind: Asset::Blend { info }, up: "z", note, rest: first, origin: None })
        }
        "ply" => {
            let (s, origin) = mesh_at_rest(asset)?;
            drawable(&s, asset)?;
            let (up, note) = cameras_up(&s, asset).unwrap_or_else(|| tallest(&s, asset));
            Ok(Described { kind: Asset::Mesh, up, note, rest: s, origin })
        }
        "obj" => {
            let (s, origin) = mesh_at_rest(asset)?;
            drawable(&s, asset)?;
            // A point cloud keeps its scanner's axes, as a PLY scan does: its up is guessed as a scan's is.
            let (up, why) = if points_only(&s) { tallest(&s, asset) } else { obj_up() };
            // One OBJ is a static mesh (`mesh`), as one PLY is; a folder of them is a sequence.
            Ok(Described { kind: Asset::Mesh, up, note: why, rest: s, origin })
        }
        // A Draco file is most often a compressed PLY scan or cloud: its up is guessed as a scan's is.
        "drc" => {
            let s = scene::drc::scene(asset)?;
            drawable(&s, asset)?;
            let (up, note) = tallest(&s, asset);
            Ok(Described { kind: Asset::Mesh, up, note, rest: s, origin: None })
        }
        "stl" => {
            let s = scene::stl::scene(asset)?;
            drawable(&s, asset)?;
            let (up, why) = stl_up();
            Ok(Described { kind: Asset::Mesh, up, note: why, rest: s, origin: None })
        }
        _ => match scene::source::way_out_of(asset) {
            Some(way_out) => bail!("{way_out}"),
            None => {
                bail!(
                    "{}: not a glTF, FBX, .blend, PLY, OBJ, STL or Draco file, nor a folder of frames",
                    asset.display()
                )
            }
        },
    }
}

/// Whether a scene is points alone (a point cloud).
fn points_only(s: &scene::PosedScene) -> bool {
    s.triangle_count() == 0 && s.point_count() > 0
}

/// Refuses an asset with nothing the renderer draws (lines only, empty meshes) or nothing to frame (one point): its
/// manifest could not check.
fn drawable(s: &scene::PosedScene, path: &Path) -> anyhow::Result<()> {
    if s.triangle_count() + s.point_count() == 0 {
        bail!(
            "{}: nothing to render: no triangles or points (vvgen draws neither lines nor empty meshes)",
            path.display()
        );
    }
    // One point (MeshLab writes a lone vertex so), or all at one point: no size to frame it by.
    if let Some((lo, _)) = s.bounds().filter(|(lo, hi)| lo == hi) {
        bail!("{}: every vertex is at one point, {lo}: nothing to frame (`fit` needs a size)", path.display());
    }
    Ok(())
}

/// At most this many distinct colours (8-bit RGB) over a subject's vertex colours and base colour textures make
/// a palette: a low-poly model painted by part (three.js' Flamingo has 4 vertex colours, a Poly Pizza alpaca 6,
/// a swatch-atlas texture a few dozen, BoxTextured's flat logo 59 with its antialiased edges), whose unlit views
/// are flat patches, one per part, with nothing of the shape inside them. Scans and painted textures carry their
/// shading in thousands (CesiumMan's texture: 16 762).
const PALETTE: usize = 64;

/// How a subject's surfaces are coloured when no light shows their shape: `Some(n)` when it is triangles only,
/// coloured by their materials and by `n` distinct colours at most [`PALETTE`] among their vertex colours and
/// base colour textures (0: none). Unlit, every view of such a subject is a silhouette filled with flat patches,
/// from which no NeRF learns a shape; lit, its shading shows the shape (the built-in studio light when the
/// manifest names none). `None` when its colours carry shading (a scan's, a painted texture's). Points are left
/// as they are: a cloud without colours has no normals to light either; so are shadeless (`unlit`) surfaces.
fn flat_colours(s: &scene::PosedScene) -> Option<usize> {
    let triangles = |p: &&scene::PosedPrimitive| p.kind == scene::PrimKind::Triangles && !p.indices.is_empty();
    // A shadeless surface shows its colour lit or not: light cannot give it a shape.
    let shaded = |p: &&scene::PosedPrimitive| s.materials.get(p.material as usize).is_none_or(|m| !m.unlit);
    if !s.primitives.iter().filter(shaded).any(|p| triangles(&p))
        || !s.primitives.iter().filter(shaded).all(|p| triangles(&p))
    {
        return None;
    }
    let mut colours: std::collections::HashSet<[u8; 3]> = std::collections::HashSet::new();
    let mut textures = std::collections::BTreeSet::new();
    let q = |v: f32| (v.clamp(0.0, 1.0) * 255.0).round() as u8;
    for p in s.primitives.iter().filter(shaded) {
        let texture = s.materials.get(p.material as usize).and_then(|m| m.base_color_texture);
        if let Some(t) = texture.filter(|_| !p.uvs.is_empty()) {
            textures.insert(t.texture);
        }
        for c in p.colors.iter() {
            colours.insert([q(c.x), q(c.y), q(c.z)]);
            if colours.len() > PALETTE {
                return None;
            }
        }
    }
    for &t in &textures {
        // A texture not at hand is taken to carry shading, as every texture was before palettes were told apart.
        let t = s.textures.get(t as usize).filter(|t| !t.rgba.is_empty())?;
        for texel in t.rgba.chunks_exact(4) {
            colours.insert([texel[0], texel[1], texel[2]]);
            if colours.len() > PALETTE {
                return None;
            }
        }
    }
    // One vertex colour alone is the material's colour over again.
    Some(if colours.len() == 1 && textures.is_empty() { 0 } else { colours.len() })
}

/// The point to read a PLY's or OBJ's coordinates relative to (`origin`), when they lie so far from zero for the
/// subject's size that single precision would step its shape ([`crate::scene::transform::Stats::coarse_step`]):
/// the middle of its bounds, in whole units.
fn far_origin(s: &scene::PosedScene) -> Option<[f64; 3]> {
    let mut stats = crate::scene::transform::Stats::default();
    s.primitives.iter().for_each(|p| stats.add(&p.positions));
    stats.coarse_step()?;
    Some(stats.centre().round().to_array())
}

/// What `new` read off the asset for its manifest besides its kind and axes.
struct Look {
    /// Flat colours, and how many ([`flat_colours`]): written lit.
    flat: Option<usize>,
    /// The PLY's or OBJ's `origin`, when its coordinates are far from zero ([`far_origin`]).
    origin: Option<[f64; 3]>,
    /// A splatting model's training cameras ([`training_cameras`]), relative to the manifest: offered, commented,
    /// as a rig.
    cameras: Option<String>,
    /// Whether every material is fully transparent as read (nothing would show): written `opaque`.
    opaque: bool,
}

#[allow(clippy::too_many_arguments)]
fn manifest(
    name: &str,
    asset: &Path,
    kind: &Asset,
    up: &str,
    note: &str,
    look: Look,
    writer: &str,
    rel: &dyn Fn(&Path) -> anyhow::Result<String>,
) -> anyhow::Result<String> {
    let mut t = String::new();
    let w = &mut t;
    let _ = writeln!(w, "# Written by `vvgen new {}`: {note}.", asset.display());
    let _ =
        writeln!(w, "# Check it with `vvgen check`, build it with `vvgen build`; docs/manifest.md lists every key.\n");
    let _ = writeln!(w, "[dataset]\nname = \"{name}\"\nversion = \"1\"\nout  = \"out/{name}\"\nseed = 0\n");
    let _ = writeln!(w, "[source.{}]", key_name(name));
    let frames = match kind {
        Asset::Gltf { clips } => {
            let _ = writeln!(w, "gltf   = \"{}\"", rel(asset)?);
            let _ = writeln!(w, "# clips in the file (pick with `animation = N`, a name, a list, or \"all\"):");
            for (i, (n, d)) in clips.iter().enumerate() {
                let _ = writeln!(w, "{}", clip_line(i, n, *d));
            }
            let n = frames_covering(clips[0].1);
            let _ = writeln!(w, "animation = 0\n{}", first_clip_frames(n, "clip"));
            n.min(LONGEST)
        }
        Asset::Fbx { takes } => {
            let _ = writeln!(w, "fbx    = \"{}\"", rel(asset)?);
            if takes.is_empty() {
                1
            } else {
                let _ = writeln!(w, "# takes in the file (pick with `animation = N` or a name):");
                for (i, (n, d)) in takes.iter().enumerate() {
                    let _ = writeln!(w, "{}", clip_line(i, n, *d));
                }
                let n = frames_covering(takes[0].1);
                let _ = writeln!(w, "animation = 0\n{}", first_clip_frames(n, "take"));
                n.min(LONGEST)
            }
        }
        Asset::Blend { info } => {
            let _ = writeln!(w, "blend  = \"{}\"   # Blender exports it, once (the cache keeps it)", rel(asset)?);
            let _ = writeln!(
                w,
                "# objects: {} (pick one with `object = \"…\"`, or `collection = \"…\"`)",
                info.objects.join(", ")
            );
            if info.scenes.len() > 1 {
                let _ = writeln!(w, "# scenes: {} (pick with `scene = \"…\"`)", info.scenes.join(", "));
            }
            let (first, last) = (info.frames.first().copied().unwrap_or(1), info.frames.last().copied().unwrap_or(1));
            let _ = writeln!(
                w,
                "frames = {{ start = {first}, end = {last}, fps = {} }}   # Blender's frame numbers: the file's range \
                 and rate",
                info.fps
            );
            info.frames.len().max(1)
        }
        Asset::Mesh => {
            let _ = writeln!(w, "mesh   = \"{}\"", rel(asset)?);
            1
        }
        Asset::Sequence { key, glob, frames } => {
            let dir = if asset.is_dir() { asset.to_path_buf() } else { crate::manifest::folder_of(asset).into() };
            let pattern = format!("{}/{glob}", rel(&dir)?.trim_end_matches('/'));
            let _ = writeln!(w, "{key} = \"{pattern}\"   # {frames} file(s), natural order");
            let _ = writeln!(w, "frames = {{ fps = 30 }}   # recorded in the metadata; set your capture's rate");
            *frames
        }
    };
    if let Some([x, y, z]) = look.origin {
        let _ = writeln!(
            w,
            "origin = [{x}, {y}, {z}]   # subtracted from the file's coordinates as they are read, in double\n\
             \x20                                  # precision: they lie far from zero for the subject's size"
        );
    }
    if look.opaque {
        let _ = writeln!(
            w,
            "opaque = true   # every material is fully transparent as Blender's importer reads it, so nothing\n\
             \x20               # would show: its own opacity is taken as 1 (a texture's alpha still cuts out)"
        );
    }
    let _ = writeln!(w, "\n[transform]\nup     = \"{up}\"    # {}", up_note(note));
    let _ = writeln!(
        w,
        "fit    = \"frame\"   # the whole subject, every frame, inside every camera (5 % margin): within 1.3 of the\n\
         \x20                  # centre, so NeRF-synthetic's near 2 / far 6 hold; its height convention: {{ height = 2.4 }}"
    );
    let _ =
        writeln!(w, "center = \"bbox\"\nover   = \"all-frames\"        # one normalization for the whole sequence\n");
    let _ = writeln!(
        w,
        "[render]\nresolution     = [400, 400]   # D-NeRF's half_res; 800 is NeRF-synthetic's full size\n\
         camera_angle_x = 0.6911112070083618   # Blender's 50 mm lens on a 36 mm sensor\n\
         samples        = 4\npasses         = [\"rgba\", \"depth\"]"
    );
    if let Some(n) = look.flat {
        let why = match n {
            0 => "no texture or vertex colours: unlit, every view would be one flat colour".to_string(),
            n => format!("a palette of {n} flat colours: unlit, every view would be flat patches"),
        };
        let _ = writeln!(
            w,
            "shading        = \"pbr\"   # {why};\n\
             \x20                          # lit by the built-in studio environment ([environment], [light.*] to change)"
        );
    }
    let _ = writeln!(w);
    let dynamic = frames > 1;
    match writer {
        "dynerf" => {
            let _ = writeln!(
                w,
                "[rig.front]\nkind = \"forward-facing\"   # DyNeRF's loaders use NDC: cameras on a plane facing the subject\n\n\
                 [split.test]\nrig   = \"front\"\nviews = 1     # camera 00, the one DyNeRF's loaders hold out\n\n\
                 [split.train]\nrig   = \"front\"\nviews = 6\n"
            );
        }
        "ply-sequence" => {}
        "static-frames" => {
            let _ = writeln!(
                w,
                "[rig.hemi]\nkind = \"hemisphere\"        # the NeRF-synthetic recipe\n\n\
                 [rig.ring]\nkind     = \"orbit\"\nschedule = \"nerf-test\"\n\n\
                 [split.train]\nrig   = \"hemi\"\nviews = 24    # every camera at every frame\n\n\
                 [split.test]\nrig   = \"ring\"\nviews = 8\n"
            );
        }
        _ => {
            let time = if dynamic {
                "time  = \"monocular\"   # D-NeRF style: one camera per frame, times 0 … 1"
            } else {
                "views = 100"
            };
            let test = if dynamic { "time     = \"monocular\"" } else { "views    = 20" };
            let val = if dynamic { "time  = \"monocular\"" } else { "views = 10" };
            let _ = writeln!(
                w,
                "[rig.hemi]\nkind = \"hemisphere\"        # the NeRF-synthetic recipe: radius 4.03, upper hemisphere\n\n\
                 [rig.ring]\nkind     = \"orbit\"\nschedule = \"nerf-test\"   # NeRF-synthetic's test orbit\n\n\
                 [split.train]\nrig   = \"hemi\"\n{time}\n\n\
                 [split.val]\nrig   = \"hemi\"\n{val}\nseed  = 3\n\n\
                 [split.test]\nrig      = \"ring\"\n{test}\n"
            );
            if let Some(file) = &look.cameras {
                let _ = writeln!(
                    w,
                    "# The cameras the splats were trained on, to render them as trained (poses only): they are in the\n\
                     # file's coordinates, so then leave the world as the file's (up = \"z\", no fit or center) and give\n\
                     # [render] their size and lens.\n\
                     # [rig.trained]\n# kind = \"from-file\"\n# file = \"{file}\"\n"
                );
            }
        }
    }
    let _ = writeln!(w, "[output.{}]\nwriter = \"{writer}\"", key_name(writer));
    if writer == "ply-sequence" {
        let _ = writeln!(
            w,
            "points = 200000   # surface samples per frame\nvoxel  = 0.01     # downsampled on a 1 cm grid"
        );
    }
    Ok(t)
}

/// A dataset name from a file's stem that `check` accepts ([`crate::manifest::is_plain_name`]: it names folders
/// on every platform): ASCII letters and digits, each run of anything else one `-` (`人物_walk` is `walk`,
/// `my file.v2` is `my-file-v2`), "dataset" when nothing is left.
fn dataset_name(stem: &str) -> String {
    let mut name = String::new();
    for c in stem.chars() {
        if c.is_ascii_alphanumeric() {
            name.push(c);
        } else if !name.is_empty() && !name.ends_with('-') {
            name.push('-');
        }
    }
    let name = name.trim_end_matches('-');
    if name.is_empty() {
        "dataset".into()
    } else {
        name.into()
    }
}

/// A TOML bare key from a name.
fn key_name(s: &str) -> String {
    let k: String =
        s.chars().map(|c| if c.is_ascii_alphanumeric() || c == '_' || c == '-' { c } else { '_' }).collect();
    if k.is_empty() {
        "main".into()
    } else {
        k
    }
}

fn absolute(p: &Path) -> anyhow::Result<PathBuf> {
    std::fs::canonicalize(p).with_context(|| format!("{}", p.display()))
}

/// `to` relative to the folder `from` (both absolute), with `/` separators.
fn relative(from: &Path, to: &Path) -> String {
    let (a, b): (Vec<Component>, Vec<Component>) = (from.components().collect(), to.components().collect());
    let common = a.iter().zip(&b).take_while(|(x, y)| x == y).count();
    let mut parts: Vec<String> = vec!["..".into(); a.len() - common];
    parts.extend(b[common..].iter().map(|c| c.as_os_str().to_string_lossy().into_owned()));
    if parts.is_empty() {
        ".".into()
    } else {
        parts.join("/")
    }
}
