//! MTL materials as Blender 4.5's OBJ importer builds its Principled BSDF from them (read with `bpy` 4.5.15:
//! `source/blender/io/wavefront_obj/importer/obj_import_mtl.cc`), so that an OBJ renders lit as the Blender
//! pipeline it replaces rendered it, and its texture statements as Blender finds their files.
//!
//! The scalars, with `illum` 2 the "highlight" model, 3–8 the reflective ones, 4, 6, 7 and 9 the transparent
//! ones and 4 and 9 glass:
//!
//! - base colour `Kd` (Blender's 0.8 grey without one); a `map_Kd` *replaces* it, as Blender links the image
//!   in its place (the MTL spec multiplies them; Blender 2.8's exporter wrote `Kd 0.8` beside every image);
//! - roughness 1 − √(Ns / 1000), `Ns` clamped to 0..1000; without `Ns`, 0 under `illum 2`, else 1; `Pr` wins;
//! - Specular IOR Level ℓ, the mean of `Ks`; without `Ks`, 1 under `illum 2`, else 0 (vvgen's layer weight 2ℓ up
//!   to ℓ = ½, above it weight 1 and its reflectance at normal incidence times 2ℓ: Cycles scales that only);
//! - metallic the mean of `Ka` under a reflective `illum` (1 without `Ka`), else 0; `Pm` wins;
//! - IOR `Ni`; without it 1.5, or 1 for a transparent `illum` that is not glass;
//! - alpha `d` (`Tr` is not read, as Blender does not), blended when below 1, under a transparent `illum`, or
//!   with a `map_d`;
//! - emission `Ke` at strength 1; a `map_Ke` replaces its colour.
//!
//! The textures: `map_Kd` (sRGB); `map_d`'s alpha channel (an image without one is opaque, as Blender's Alpha
//! output is); `map_Bump`/`bump` as a tangent-space normal map of strength `-bm` (a grey one is a height map,
//! which vvgen leaves: Blender reads it as a normal map, bending every normal one way); `map_Ke`; roughness from
//! `map_Pr` or `map_Ns`, metallic from `map_Pm` or `map_refl`, each the image's luminance; `-o` and `-s` move
//! and scale the uvs as Blender's Mapping node does. Two choices differ from Blender 4.5 on purpose: its
//! importer reads every image as sRGB, so normal, roughness and metallic maps come out bent and darkened; vvgen
//! reads them as data, as their authors (and Blender's own glTF importer) mean them. And it reads `Tf` (which 3ds
//! Max writes as `Tf 1 1 1` on every material) as full transmission, glass; vvgen, which draws no transmission,
//! leaves it, as the MTL spec's filter colour of a surface that is not transparent. `map_Ks` is not read.
//!
//! A texture statement's file is found as Blender finds it, and then some: options first, the rest of the line
//! is the name (spaces and all, quotes removed); relative to the MTL's folder with `\` read as a separator
//! (Windows-authored files), as an absolute path, or by its base name beside the MTL.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use glam::{Vec2, Vec3, Vec4};

use super::material::{dielectric_f0, AlphaMode, Material, DIELECTRIC_F0};
use super::texture::{Texture, TextureRef};
use super::Error;

/// The texture statements vvgen reads (tobj keeps `map_Bump`, `map_bump` and `bump` as one).
pub(crate) const MAPS: &[&str] =
    &["map_Kd", "map_d", "map_Bump", "map_bump", "bump", "map_Ke", "map_Pr", "map_Ns", "map_Pm", "map_refl"];

/// Options that take arguments and change nothing vvgen draws (Blender skips them too), with their counts.
const SKIPPED: &[(&str, usize)] = &[
    ("-blendu", 1),
    ("-blendv", 1),
    ("-boost", 1),
    ("-cc", 1),
    ("-clamp", 1),
    ("-imfchan", 1),
    ("-mm", 2),
    ("-texres", 1),
    ("-type", 1),
];

/// A texture statement: its file's name as written and the options vvgen applies.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct TexMap {
    /// The file name: the rest of the line after the options, quotes removed.
    pub name: String,
    /// `-bm`: a bump (normal) map's strength.
    pub bm: f32,
    /// `-o` and `-s`: the uv offset and scale (their first two components).
    pub offset: Vec2,
    pub scale: Vec2,
}

impl TexMap {
    /// Reads a texture statement's arguments (`rest`: what follows its key): options, then the name. `None`
    /// when no name is left.
    pub(crate) fn parse(rest: &str) -> Option<TexMap> {
        let mut map = TexMap { name: String::new(), bm: 1.0, offset: Vec2::ZERO, scale: Vec2::ONE };
        let mut rest = rest.trim();
        loop {
            let (word, after) = rest.split_once(char::is_whitespace).unwrap_or((rest, ""));
            let after = after.trim_start();
            rest = match word {
                "-bm" => {
                    let (v, a) = numbers(after, 1);
                    map.bm = v.first().copied().unwrap_or(1.0);
                    a
                }
                "-o" | "-s" | "-t" => {
                    let (v, a) = numbers(after, 3);
                    let get = |i: usize, d: f32| v.get(i).copied().unwrap_or(d);
                    match word {
                        "-o" => map.offset = Vec2::new(get(0, 0.0), get(1, 0.0)),
                        "-s" => map.scale = Vec2::new(get(0, 1.0), get(1, 1.0)),
                        _ => {}
                    }
                    a
                }
                w => match SKIPPED.iter().find(|(o, _)| *o == w) {
                    Some(&(_, n)) => {
                        let mut a = after;
                        for _ in 0..n {
                            a = a.split_once(char::is_whitespace).map_or("", |(_, r)| r.trim_start());
                        }
                        a
                    }
                    None => break,
                },
            };
        }
        let name: String = rest.chars().filter(|&c| c != '"').collect();
        let name = name.trim();
        (!name.is_empty()).then(|| TexMap { name: name.to_string(), ..map })
    }

    /// The uv transform `-o` and `-s` ask for, in vvgen's uvs (v down from the top row): Blender's Mapping node
    /// scales, then offsets, its own (v up).
    fn transform(&self) -> Option<[Vec2; 3]> {
        let (o, s) = (self.offset, self.scale);
        (o != Vec2::ZERO || s != Vec2::ONE)
            .then(|| [Vec2::new(s.x, 0.0), Vec2::new(0.0, s.y), Vec2::new(o.x, 1.0 - s.y - o.y)])
    }
}

/// Where the file a material statement names (`name`, in an MTL or OBJ in folder `dir`) is: relative to `dir`
/// with `\` read as a separator, as an absolute path, or by its base name in `dir`. When none is a file, the
/// error is the first place looked, for the message.
pub(crate) fn locate(dir: &Path, name: &str) -> Result<PathBuf, PathBuf> {
    let slashed = name.replace('\\', "/");
    let base = slashed.rsplit('/').next().unwrap_or(&slashed);
    // (A relative name is never tried against the working directory: a build reads the same files from any
    // folder.)
    let absolute = Some(PathBuf::from(&slashed)).filter(|p| p.is_absolute());
    let first = dir.join(&slashed);
    [Some(first.clone()), absolute, Some(dir.join(base))].into_iter().flatten().find(|p| p.is_file()).ok_or(first)
}

/// Decoded images of one OBJ frame, each read once however many materials use it.
#[derive(Default)]
pub(crate) struct Images {
    textures: Vec<Texture>,
    decoded: HashMap<(PathBuf, bool), u32>,
    rgba: HashMap<PathBuf, image::RgbaImage>,
}

impl Images {
    /// The frame's textures, in the order the materials refer to them.
    pub(crate) fn into_textures(self) -> Vec<Texture> {
        self.textures
    }

    /// Decodes the image at `path` (as 8-bit RGBA), once.
    fn load(&mut self, path: &Path) -> Result<(), Error> {
        if !self.rgba.contains_key(path) {
            let img = super::obj::image(path)?.into_rgba8();
            self.rgba.insert(path.to_path_buf(), img);
        }
        Ok(())
    }

    /// The image at `path`, [`Images::load`]ed before.
    fn get(&self, path: &Path) -> &image::RgbaImage {
        &self.rgba[path]
    }

    /// Adds a texture, returning its index.
    fn push(&mut self, t: Texture) -> u32 {
        self.textures.push(t);
        self.textures.len() as u32 - 1
    }

    /// The image at `path` as a texture (sRGB-decoded or data), added once.
    fn texture(&mut self, path: &Path, srgb: bool) -> Result<u32, Error> {
        if let Some(&i) = self.decoded.get(&(path.to_path_buf(), srgb)) {
            return Ok(i);
        }
        self.load(path)?;
        let img = self.get(path);
        let t = Texture::new(img.width(), img.height(), img.as_raw().clone(), srgb);
        let i = self.push(t);
        self.decoded.insert((path.to_path_buf(), srgb), i);
        Ok(i)
    }
}

/// Up to `n` numbers at the start of `s`, and what follows them.
fn numbers(mut s: &str, n: usize) -> (Vec<f32>, &str) {
    let mut v = Vec::new();
    while v.len() < n {
        let (w, a) = s.split_once(char::is_whitespace).unwrap_or((s, ""));
        match w.parse::<f32>() {
            Ok(x) if x.is_finite() => {
                v.push(x);
                s = a.trim_start();
            }
            _ => break,
        }
    }
    (v, s)
}

/// Reads a material's number parameter kept by tobj among its unknown ones (`Pr`, `Pm`).
fn number(m: &tobj::Material, key: &str) -> Option<f32> {
    m.unknown_param.get(key).and_then(|v| v.split_whitespace().next()?.parse::<f32>().ok()).filter(|v| v.is_finite())
}

/// A texture statement of material `m` (one of [`MAPS`]), parsed and found; tobj keeps some in fields, the rest
/// among its unknown parameters.
fn statement(m: &tobj::Material, key: &str, dir: &Path) -> Option<(TexMap, PathBuf)> {
    let raw = match key {
        "map_Kd" => m.diffuse_texture.as_deref(),
        "map_d" => m.dissolve_texture.as_deref(),
        "map_Bump" => m.normal_texture.as_deref(),
        "map_Ns" => m.shininess_texture.as_deref(),
        k => m.unknown_param.get(k).map(String::as_str),
    }?;
    let map = TexMap::parse(raw)?;
    let path = locate(dir, &map.name).ok()?;
    Some((map, path))
}

/// The material Blender 4.5's importer makes of MTL material `m` (of an MTL in folder `dir`), its images added
/// to `images` (see the module's note).
pub(crate) fn material(m: &tobj::Material, dir: &Path, images: &mut Images) -> Result<Material, Error> {
    let mean = |c: Option<[f32; 3]>| c.map(|c| (c[0] + c[1] + c[2]) / 3.0).filter(|v| *v >= 0.0);
    let illum = m.illumination_model.map_or(-1, i32::from);
    let highlight = illum == 2;
    let reflective = (3..=8).contains(&illum);
    let transparent = matches!(illum, 4 | 6 | 7 | 9);
    let glass = matches!(illum, 4 | 9);
    let level = mean(m.specular).unwrap_or(if highlight { 1.0 } else { 0.0 });
    let roughness = match m.shininess {
        Some(ns) => 1.0 - (ns.clamp(0.0, 1000.0) / 1000.0).sqrt(),
        None if highlight => 0.0,
        None => 1.0,
    };
    let roughness = number(m, "Pr").unwrap_or(roughness).clamp(0.0, 1.0);
    let metallic = if reflective { mean(m.ambient).unwrap_or(1.0) } else { 0.0 };
    let metallic = number(m, "Pm").unwrap_or(metallic).clamp(0.0, 1.0);
    let ior = m.optical_density.filter(|v| *v >= 0.0).unwrap_or(if transparent && !glass { 1.0 } else { 1.5 });
    let f0 = dielectric_f0(ior).unwrap_or(DIELECTRIC_F0);
    // Cycles scales the layer's reflectance at normal incidence by 2ℓ: vvgen's weight scales it at every angle,
    // so it carries ℓ up to ½ and the reflectance the rest.
    let (specular, f0) = if level <= 0.5 { (2.0 * level, f0) } else { (1.0, (f0 * 2.0 * level).min(1.0)) };
    let alpha = m.dissolve.unwrap_or(1.0).clamp(0.0, 1.0);
    let kd = m.diffuse.filter(|c| c.iter().all(|v| *v >= 0.0)).map_or(Vec3::splat(0.8), Vec3::from);
    let mut mat = Material {
        base_color: kd.extend(alpha),
        double_sided: true,
        metallic,
        roughness,
        specular,
        specular_f0: Vec3::splat(f0),
        emissive: m.emissive.filter(|c| c.iter().all(|v| *v >= 0.0)).map_or(Vec3::ZERO, Vec3::from),
        ..Material::default()
    };
    let find = |key: &str| statement(m, key, dir);
    let (kd_map, d_map) = (find("map_Kd"), find("map_d"));
    if alpha < 1.0 || transparent || d_map.is_some() {
        mat.alpha_mode = AlphaMode::Blend;
    }
    // The base colour texture: `map_Kd`'s colour (or Kd) and, when the surface blends, `map_d`'s alpha (or 1).
    let blended = mat.alpha_mode == AlphaMode::Blend;
    for (_, path) in kd_map.iter().chain(&d_map) {
        images.load(path)?;
    }
    let opaque = |path: &Path, images: &Images| images.get(path).pixels().all(|p| p.0[3] == 255);
    let base = match (&kd_map, &d_map) {
        (Some((map, kd)), Some((_, d))) if kd == d => Some((images.texture(kd, true)?, map)),
        (Some((map, kd)), None) if !blended || opaque(kd, images) => Some((images.texture(kd, true)?, map)),
        (Some((map, kd)), d) => {
            let t = with_alpha(images.get(kd), d.as_ref().map(|(_, d)| images.get(d)));
            Some((images.push(t), map))
        }
        (None, Some((map, d))) => {
            let alpha = images.get(d);
            let white = image::RgbaImage::from_pixel(alpha.width(), alpha.height(), image::Rgba([255; 4]));
            // The colour is Kd's: the texture carries alpha alone.
            let t = with_alpha(&white, Some(alpha));
            Some((images.push(t), map))
        }
        (None, None) => None,
    };
    if let Some((i, map)) = base {
        if kd_map.is_some() {
            mat.base_color = Vec4::new(1.0, 1.0, 1.0, alpha);
        }
        mat.base_color_texture = Some(TextureRef { transform: map.transform(), ..TextureRef::new(i) });
    }
    if let Some((map, path)) = find("map_Bump") {
        // A grey image is a height map (Crytek's Sponza ships them as `map_bump`), which vvgen does not draw;
        // read as a normal map, as Blender does, it would bend every normal to one side.
        images.load(&path)?;
        if images.get(&path).pixels().any(|p| p.0[0] != p.0[1] || p.0[1] != p.0[2]) {
            let i = images.texture(&path, false)?;
            let at = TextureRef { transform: map.transform(), ..TextureRef::new(i) };
            mat.normal_texture = Some((at, map.bm.max(0.0)));
        }
    }
    if let Some((map, path)) = find("map_Ke") {
        let i = images.texture(&path, true)?;
        mat.emissive = Vec3::ONE;
        mat.emissive_texture = Some(TextureRef { transform: map.transform(), ..TextureRef::new(i) });
    }
    let rough = find("map_Pr").or_else(|| find("map_Ns"));
    // (Not `refl`: old files name a sphere-mapped reflection of the surroundings with it.)
    let metal = find("map_Pm").or_else(|| find("map_refl"));
    if rough.is_some() || metal.is_some() {
        for (_, path) in rough.iter().chain(&metal) {
            images.load(path)?;
        }
        let map = rough.as_ref().or(metal.as_ref()).map(|(m, _)| m).expect("BUG: one of the two is there");
        let t =
            metallic_roughness(rough.as_ref().map(|(_, p)| images.get(p)), metal.as_ref().map(|(_, p)| images.get(p)));
        // A linked socket ignores its value: the texture carries it, the factor is 1.
        if rough.is_some() {
            mat.roughness = 1.0;
        }
        if metal.is_some() {
            mat.metallic = 1.0;
        }
        let i = images.push(t);
        mat.metallic_roughness_texture = Some(TextureRef { transform: map.transform(), ..TextureRef::new(i) });
    }
    Ok(mat)
}

/// `colour`'s texels with `alpha`'s alpha channel (sampled at the same relative place when the sizes differ),
/// or opaque without it: an sRGB base colour texture.
fn with_alpha(colour: &image::RgbaImage, alpha: Option<&image::RgbaImage>) -> Texture {
    let (w, h) = colour.dimensions();
    let mut rgba = colour.as_raw().clone();
    for (k, px) in rgba.chunks_exact_mut(4).enumerate() {
        let (x, y) = (k as u32 % w, k as u32 / w);
        px[3] = alpha.map_or(255, |a| a.get_pixel(x * a.width() / w, y * a.height() / h).0[3]);
    }
    Texture::new(w, h, rgba, true)
}

/// The luminance (Rec. 709, of the bytes as data) of an image's texel: what Blender's Color output gives a float
/// socket.
fn luminance(p: image::Rgba<u8>) -> u8 {
    let [r, g, b, _] = p.0.map(f32::from);
    (0.2126 * r + 0.7152 * g + 0.0722 * b).round().clamp(0.0, 255.0) as u8
}

/// A glTF-layout metallic-roughness texture (data; roughness in G, metallic in B, at 1 where there is no map)
/// of the size of the roughness map, or else the metallic map; the other is sampled at the same relative place.
fn metallic_roughness(rough: Option<&image::RgbaImage>, metal: Option<&image::RgbaImage>) -> Texture {
    let (w, h) = rough.or(metal).map_or((1, 1), |i| i.dimensions());
    let at = |img: Option<&image::RgbaImage>, x: u32, y: u32| {
        img.map_or(255, |i| luminance(*i.get_pixel(x * i.width() / w, y * i.height() / h)))
    };
    let mut rgba = Vec::with_capacity((w * h * 4) as usize);
    for y in 0..h {
        for x in 0..w {
            rgba.extend_from_slice(&[255, at(rough, x, y), at(metal, x, y), 255]);
        }
    }
    Texture::new(w, h, rgba, false)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_texture_statement_reads_its_options_then_the_rest_of_the_line_as_the_name() {
        let m = TexMap::parse("-bm 0.7 -s 2 3 1 -o 0.25 -clamp on \"my texture.png\"").unwrap();
        assert_eq!(
            (m.name.as_str(), m.bm, m.scale, m.offset),
            ("my texture.png", 0.7, Vec2::new(2.0, 3.0), Vec2::new(0.25, 0.0))
        );
        assert_eq!(TexMap::parse("textures\\red.png").unwrap().name, "textures\\red.png");
        assert_eq!(TexMap::parse("-s 1 1 1 green tex.png").unwrap().name, "green tex.png");
        assert_eq!(TexMap::parse("-bm 2"), None);
        // Blender's Mapping node scales, then offsets, uvs whose v runs up; vvgen's run down.
        let t = m.transform().unwrap();
        let blender = |u: f32, v: f32| Vec2::new(u * 2.0 + 0.25, v * 3.0);
        for (u, v) in [(0.0, 0.0), (0.3, 0.8), (1.0, 1.0)] {
            let ours = t[0] * u + t[1] * (1.0 - v) + t[2];
            let b = blender(u, v);
            assert!((ours - Vec2::new(b.x, 1.0 - b.y)).length() < 1e-6, "{ours} vs {b}");
        }
    }

    #[test]
    fn a_windows_path_and_a_base_name_are_found_as_blender_finds_them() {
        let d = std::env::temp_dir().join(format!("vvgen-mtl-locate-{}", std::process::id()));
        std::fs::create_dir_all(d.join("textures")).unwrap();
        std::fs::write(d.join("textures/red.png"), b"x").unwrap();
        std::fs::write(d.join("beside.png"), b"x").unwrap();
        assert_eq!(locate(&d, "textures\\red.png"), Ok(d.join("textures/red.png")));
        assert_eq!(locate(&d, "C:\\Users\\me\\maps\\beside.png"), Ok(d.join("beside.png")));
        assert_eq!(locate(&d, "maps\\gone.png"), Err(d.join("maps/gone.png")));
        std::fs::remove_dir_all(&d).unwrap();
    }

    #[test]
    fn scalars_follow_blenders_importer() {
        // (MTL text, base, roughness, metallic, specular weight, f0, alpha, blended) as bpy 4.5.15 imports them
        // (Specular IOR Level ℓ → weight and f0 as the module's note says).
        let f0_145 = (0.45f32 / 2.45) * (0.45 / 2.45);
        type Case = (&'static str, [f32; 3], f32, f32, f32, f32, f32, bool);
        let cases: &[Case] = &[
            ("Kd 0.2 0.4 0.6", [0.2, 0.4, 0.6], 1.0, 0.0, 0.0, 0.04, 1.0, false),
            (
                "Ns 225\nKa 1 1 1\nKd 0.8 0.7 0.6\nKs 0.5 0.5 0.5\nNi 1.45\nd 1\nillum 2",
                [0.8, 0.7, 0.6],
                0.5257,
                0.0,
                1.0,
                f0_145,
                1.0,
                false,
            ),
            ("illum 2", [0.8, 0.8, 0.8], 0.0, 0.0, 1.0, 0.08, 1.0, false),
            ("Ns 900\nKa 0.9 0.9 0.9\nKd 0.5 0.5 0.5\nKs 1 1 1\nillum 3", [0.5; 3], 0.0513, 0.9, 1.0, 0.08, 1.0, false),
            ("Kd 1 1 1\nNi 1.33\nd 0.3\nillum 4", [1.0; 3], 1.0, 1.0, 0.0, 0.02006, 0.3, true),
            ("Kd 0.5 0.5 0.5\nTr 0.25", [0.5; 3], 1.0, 0.0, 0.0, 0.04, 1.0, false),
            ("Kd 0.5 0.5 0.5\nNs 0\nKs 0.2 0.2 0.2\nillum 2", [0.5; 3], 1.0, 0.0, 0.4, 0.04, 1.0, false),
            ("Kd 1 1 1\nPr 0.3\nPm 0.8", [1.0; 3], 0.3, 0.8, 0.0, 0.04, 1.0, false),
            (
                "Ns 30\nNi 1.5\nd 1\nTr 0\nTf 1 1 1\nillum 2\nKa 0.588 0.588 0.588\nKd 0.588 0.588 0.588\nKs 0 0 0",
                [0.588; 3],
                0.8268,
                0.0,
                0.0,
                0.04,
                1.0,
                false,
            ),
        ];
        for &(text, base, rough, metal, spec, f0, alpha, blended) in cases {
            let (mats, _) = tobj::load_mtl_buf(&mut format!("newmtl m\n{text}\n").as_bytes()).unwrap();
            let m = material(&mats[0], Path::new("."), &mut Images::default()).unwrap();
            let close = |a: f32, b: f32| (a - b).abs() < 1e-3;
            assert!(
                (m.base_color.truncate() - Vec3::from(base)).abs().max_element() < 1e-6
                    && close(m.roughness, rough)
                    && close(m.metallic, metal)
                    && close(m.specular, spec)
                    && (m.specular_f0.x - f0).abs() < 1e-4
                    && close(m.base_color.w, alpha)
                    && (m.alpha_mode == AlphaMode::Blend) == blended,
                "{text:?}: {m:?}"
            );
        }
        // Emission: Ke at strength 1.
        let (mats, _) =
            tobj::load_mtl_buf(&mut "newmtl e\nKd 0.1 0.1 0.1\nKe 1 0.5 0.25\nillum 2\n".as_bytes()).unwrap();
        let m = material(&mats[0], Path::new("."), &mut Images::default()).unwrap();
        assert_eq!(m.emissive, Vec3::new(1.0, 0.5, 0.25));
    }
}
