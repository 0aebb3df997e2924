//! An FBX file's materials as Blender's importer makes them, and the textures they use: embedded, beside the
//! file, or missing (a warning saying where to put it).

use std::path::Path;
use std::sync::Arc;

use glam::{Vec3, Vec4};

use super::fbx::err;
use super::material::{AlphaMode, Material};
use super::texture::{Texture, TextureRef};
use super::Error;

/// Materials and the textures they use, with what to say of them.
pub(super) struct Shading {
    pub(super) materials: Arc<Vec<Material>>,
    pub(super) textures: Arc<Vec<Texture>>,
    /// Textures they name that are missing.
    pub(super) warnings: Vec<String>,
    /// Materials read as fully transparent ([`super::fbx::FbxAsset::unseen`]).
    pub(super) unseen: Vec<String>,
}

/// The scene's materials as the renderer's metallic-roughness, mapped from the FBX material's classic properties
/// as Blender's importer maps them (`blen_read_material` in io_scene_fbx, 3.4 to 4.5): base colour
/// `DiffuseColor` (its factor ignored), roughness `1 − √Shininess / 10`, metallic `ReflectionFactor`, specular
/// `2 × SpecularFactor`, alpha `1 − TransparencyFactor` (else the material's own `Opacity`, else
/// `1 − TransparentColor.r`), emission `EmissiveColor × EmissiveFactor`; the `DiffuseColor` texture is the base
/// colour's. Each property comes from the material, else its file's template, else Blender's default. The PBR
/// properties some exporters add (Stingray, 3ds Max physical) are ignored, as Blender ignores them. A default
/// material is last. Every one is drawn on both sides, as Blender draws an imported FBX (FBX has no two-sided
/// flag it reads; Cycles culls nothing): a one-sided quad, a cloth panel or a mirrored part would otherwise
/// vanish from the views behind it.
///
/// A texture the file names but neither embeds nor has beside it (exporters keep the path on the artist's
/// machine; downloads often leave the images out) is a warning, not an error: the material keeps its colour
/// alone, where Blender would show its missing-image magenta. The model still loads, and `--deny-warnings`
/// makes it an error for whoever wants one.
pub(super) fn materials(path: &Path, scene: &ufbx::Scene) -> Result<Shading, Error> {
    let dir = super::input::folder_of(path);
    let mut textures: Vec<Texture> = Vec::new();
    let mut cache: std::collections::HashMap<u32, Option<(u32, bool)>> = Default::default();
    let mut mats = Vec::new();
    let (mut warnings, mut unseen) = (Vec::new(), Vec::new());
    for m in scene.materials.iter() {
        let props = &m.element.props;
        // `find_prop` looks in the template (`props.defaults`) too, as Blender's `elem_props_get_*` do.
        let real = |name: &str, default: f64| props.find_prop(name).map_or(default, |p| p.value_vec4.x);
        let rgb = |name: &str, default: f64| {
            props.find_prop(name).map_or(Vec3::splat(default as f32), |p| {
                let v = p.value_vec4;
                Vec3::new(v.x as f32, v.y as f32, v.z as f32)
            })
        };
        let mut alpha = 1.0 - real("TransparencyFactor", 0.0);
        // Which property the alpha comes from, for the warning about a material nothing of which shows.
        let mut from = "TransparencyFactor";
        if alpha == 1.0 || alpha == 0.0 {
            // The material's own `Opacity` only, not the template's (3ds Max writes it there).
            let own = props.props.iter().find(|p| p.name == "Opacity").map(|p| p.value_vec4.x);
            from = if own.is_some() { "Opacity" } else { "TransparentColor" };
            alpha = own.unwrap_or_else(|| 1.0 - f64::from(rgb("TransparentColor", 0.0).x));
        }
        if alpha <= 0.0 {
            // Blender's reading, kept (Cycles renders the material so), but a surprise: the FBX SDK takes a
            // `TransparencyFactor` of 0 as opaque whatever `TransparentColor` says, and Eevee ignores alpha
            // unless the blend mode says otherwise. A material's own `Opacity` comes first.
            unseen.push(format!(
                "material `{}` is fully transparent as Blender's importer reads it (alpha 0 from its `{from}`), so \
                 nothing drawn in it shows, as in Cycles (Eevee and the FBX SDK draw it opaque); set `opaque = \
                 true` on the source, or give the material an `Opacity` of 1 in the file, to see it",
                m.element.name
            ));
        }
        // Blender's shader inputs hold these in 0 … 1.
        let unit = |v: f64| v.clamp(0.0, 1.0) as f32;
        let diffuse = rgb("DiffuseColor", 1.0);
        let mut mat = Material {
            base_color: diffuse.extend(unit(alpha)),
            metallic: unit(real("ReflectionFactor", 0.0)),
            roughness: unit(1.0 - real("Shininess", 20.0).max(0.0).sqrt() / 10.0),
            specular: unit(real("SpecularFactor", 0.25) * 2.0),
            emissive: rgb("EmissiveColor", 0.0) * real("EmissiveFactor", 1.0) as f32,
            double_sided: true,
            ..Material::default()
        };
        if mat.base_color.w < 1.0 {
            mat.alpha_mode = AlphaMode::Blend;
        }
        let diffuse_map = &m.fbx.diffuse_color;
        if let Some(t) = diffuse_map.texture.as_ref().filter(|_| diffuse_map.texture_enabled) {
            let id = t.element.typed_id;
            let got = match cache.get(&id) {
                Some(got) => *got,
                None => {
                    let got = match texture(path, dir, t)? {
                        Image::Found(tex, alpha) => {
                            textures.push(tex);
                            Some((textures.len() as u32 - 1, alpha))
                        }
                        Image::Missing(missing) => {
                            warnings.push(missing_texture(dir, &m.element.name, &missing));
                            None
                        }
                        Image::Unnamed(kind) => {
                            warnings.push(format!(
                                "material `{}`: its colour's texture `{}` is {kind} that names no image file, which \
                                 vvgen does not read (nor does Blender's importer), so the material renders in its \
                                 colour alone; connect an image file to the diffuse colour before export to use one",
                                m.element.name, t.element.name
                            ));
                            None
                        }
                    };
                    cache.insert(id, got);
                    got
                }
            };
            if let Some((index, alpha)) = got {
                mat.base_color_texture = Some(TextureRef::new(index));
                // Blender takes alpha from a diffuse image that has an alpha channel, and blends.
                if alpha {
                    mat.alpha_mode = AlphaMode::Blend;
                }
            }
        }
        mat.base_color = mat.base_color.clamp(Vec4::ZERO, Vec4::splat(f32::MAX));
        mat.emissive = mat.emissive.max(Vec3::ZERO);
        if !mat.base_color.is_finite() || !mat.emissive.is_finite() {
            return Err(err(path, format!("material `{}` has a colour that is not a number", m.element.name)));
        }
        mats.push(mat);
    }
    // Faces without a material: white where the mesh has vertex colours, else Blender's grey.
    mats.push(Material { double_sided: true, ..Material::default() });
    mats.push(Material { double_sided: true, ..Material::unassigned() });
    Ok(Shading { materials: Arc::new(mats), textures: Arc::new(textures), warnings, unseen })
}

/// The warning for material `material`'s texture `missing` (as the file names it), with where to put it: at
/// that path from the folder `dir` when it is relative, else (a path from another machine) by its name beside
/// the file.
fn missing_texture(dir: &Path, material: &str, missing: &str) -> String {
    let name = Path::new(missing).file_name().map_or_else(|| missing.into(), |n| n.to_string_lossy());
    let relative = !missing.contains(':') && !missing.starts_with('/');
    let place = if relative && missing != name {
        format!("at `{}` or beside the FBX file as `{name}`", dir.join(missing).display())
    } else {
        format!("beside the FBX file as `{}`", dir.join(name.as_ref()).display())
    };
    format!(
        "material `{material}`: texture `{missing}` is neither in the file nor in its folder (searched below it, as \
         Blender's importer searches), so the material renders in its colour alone; put the image {place} to use it"
    )
}

/// What a material's texture reference finds.
enum Image {
    /// The image, and whether it has an alpha channel.
    Found(Texture, bool),
    /// Nothing, embedded or in the folder: the path the file names (see [`materials`]).
    Missing(String),
    /// No image file named at all: what the texture is instead ("a layered texture", "a procedural map", …).
    Unnamed(&'static str),
}

/// A texture: embedded in the file, the file its path names, found by its name below the FBX's folder, or
/// missing. An image that is there but does not decode is an error.
fn texture(path: &Path, dir: &Path, t: &ufbx::Texture) -> Result<Image, Error> {
    let bytes: Vec<u8> = if t.content.size > 0 {
        t.content.to_vec()
    } else if t.relative_filename.is_empty() && t.filename.is_empty() {
        // 3ds Max's OSL and shader maps, Maya's layered textures: no file to look for (joined to the folder, an
        // empty name would name the folder itself).
        return Ok(Image::Unnamed(match t.type_ {
            ufbx::TextureType::Layered => "a layered texture",
            ufbx::TextureType::Procedural => "a procedural map",
            ufbx::TextureType::Shader => "a shader map",
            ufbx::TextureType::File => "a file texture",
        }));
    } else {
        let rel = if t.relative_filename.is_empty() { t.filename.to_string() } else { t.relative_filename.to_string() };
        let rel = rel.replace('\\', "/");
        // Where the file says: relative to its folder (out of it too: `../textures/`, as Blender reads it), or an
        // absolute path that exists here. Only a regular file: a device or a pipe is never read.
        let full = dir.join(&rel);
        if full.is_file() {
            return found(&full);
        }
        // Exporters often keep only an absolute path from another machine: try the name beside the file, then
        // anywhere below it, as Blender's importer searches ("Image Search", on by default).
        let name = Path::new(&rel).file_name().map(|n| dir.join(n));
        return match name.filter(|n| n.is_file()).or_else(|| search_below(dir, &rel)) {
            Some(n) => found(&n),
            None => Ok(Image::Missing(rel)),
        };
    };
    let mut reader = image::ImageReader::new(std::io::Cursor::new(bytes))
        .with_guessed_format()
        .map_err(|e| err(path, format!("embedded texture `{}`: {e}", t.element.name)))?;
    if reader.format().is_none() {
        // TGA has no signature to guess from (3ds Max embeds it): the name the file gives the image says it.
        let named = [&t.relative_filename, &t.filename]
            .into_iter()
            .find_map(|n| image::ImageFormat::from_path(n.as_ref() as &str).ok());
        if let Some(format) = named {
            reader.set_format(format);
        }
    }
    let mut limits = image::Limits::default();
    limits.max_image_width = Some(crate::scene::obj::MAX_TEXTURE_SIDE);
    limits.max_image_height = Some(crate::scene::obj::MAX_TEXTURE_SIDE);
    reader.limits(limits);
    let img = reader
        .decode()
        .map_err(|e| err(path, format!("embedded texture `{}` does not decode: {e}", t.element.name)))?;
    let alpha = img.color().has_alpha();
    let img = img.into_rgba8();
    Ok(Image::Found(Texture::new(img.width(), img.height(), img.into_raw(), true), alpha))
}

/// How deep below the FBX file's folder, and through how many entries, [`search_below`] looks: a file left in
/// a home folder must not walk the disk.
const SEARCH_DEPTH: usize = 8;
const SEARCH_ENTRIES: usize = 20_000;

/// The first file below `dir` named as `named`'s last component, case aside (`Textures/Wood.PNG` finds
/// `textures/wood.png`), as Blender's importer finds a texture whose path is not there (`load_image`'s
/// recursive search). Deterministic where Blender's walk is in directory order: the shallowest first, names
/// sorted; hidden folders, symbolic links to folders, caches (`CACHEDIR.TAG`, as vvgen's own) and vvgen's
/// datasets (`vvgen/dataset.json`) are not entered, so what a build writes beside the file never changes what the
/// next one finds.
fn search_below(dir: &Path, named: &str) -> Option<std::path::PathBuf> {
    let want = Path::new(named).file_name()?.to_string_lossy().to_lowercase();
    let mut level = vec![dir.to_path_buf()];
    let mut seen = 0;
    for _ in 0..=SEARCH_DEPTH {
        let mut next = Vec::new();
        for d in level {
            let Ok(read) = std::fs::read_dir(&d) else { continue };
            let mut entries: Vec<(String, std::path::PathBuf, bool)> = Vec::new();
            for e in read.flatten() {
                seen += 1;
                if seen > SEARCH_ENTRIES {
                    return None;
                }
                // `file_type` does not follow symbolic links: a link to a folder is not a folder here.
                let is_dir = e.file_type().is_ok_and(|t| t.is_dir());
                entries.push((e.file_name().to_string_lossy().into_owned(), e.path(), is_dir));
            }
            entries.sort();
            if let Some((_, p, _)) = entries.iter().find(|(n, p, d)| !d && n.to_lowercase() == want && p.is_file()) {
                return Some(p.clone());
            }
            // (`export::meta::META`, named here since export reads scenes.)
            let ours = |p: &Path| p.join(crate::cache::CACHE_TAG).exists() || p.join("vvgen/dataset.json").exists();
            let enter = |(n, p, d): &(String, std::path::PathBuf, bool)| *d && !n.starts_with('.') && !ours(p);
            next.extend(entries.into_iter().filter(enter).map(|(_, p, _)| p));
        }
        level = next;
    }
    None
}

/// The image file at `file`, read.
fn found(file: &Path) -> Result<Image, Error> {
    crate::scene::obj::texture_and_alpha(file).map(|(t, alpha)| Image::Found(t, alpha))
}
