//! Images against their ground truth: pairing the files, compositing, PSNR and SSIM per image, whole and
//! inside the ground truth's alpha.
//!
//! Pairing: by relative path (a test image may have another image extension: `r_000.png` against
//! `r_000.jpg`), or, given a transforms.json, its frames' images in the file's order against the test folder's
//! images in natural name order (`00000.png`, `00001.png`, … as trainers write their renders).
//!
//! Colour: both images as sRGB values in 0 … 1. A ground truth with alpha is composited over the background
//! (white by default, NeRF-synthetic's), and so is a test image with alpha; SSIM then sees what PSNR sees.
//! Masked scores keep the pixels the ground truth covers (alpha > 0): PSNR over their channels, SSIM as the mean
//! of its map over them (inside the border SSIM leaves out).

use std::path::{Path, PathBuf};

use rayon::prelude::*;

use super::ssim::{self, Plane};
use super::Error;
use crate::manifest::sequence::natural_cmp;

/// How images are compared.
#[derive(Debug, Clone, Copy)]
pub struct Options {
    /// What transparent pixels are composited over, linear 0 … 1 per channel of sRGB values.
    pub background: [f64; 3],
}

impl Default for Options {
    fn default() -> Self {
        Options { background: [1.0; 3] }
    }
}

/// One image's scores.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Score {
    /// The ground truth's path, relative to its folder.
    pub name: String,
    /// PSNR, dB (infinite for identical images).
    #[serde(serialize_with = "finite_or_null")]
    pub psnr: f64,
    /// SSIM.
    pub ssim: f64,
    /// PSNR over the pixels the ground truth covers, when it has alpha and covers any.
    #[serde(serialize_with = "opt_finite_or_null")]
    pub psnr_masked: Option<f64>,
    /// SSIM over the pixels the ground truth covers.
    pub ssim_masked: Option<f64>,
}

fn finite_or_null<S: serde::Serializer>(v: &f64, s: S) -> Result<S::Ok, S::Error> {
    if v.is_finite() {
        s.serialize_f64(*v)
    } else {
        s.serialize_none()
    }
}

fn opt_finite_or_null<S: serde::Serializer>(v: &Option<f64>, s: S) -> Result<S::Ok, S::Error> {
    match v {
        Some(v) => finite_or_null(v, s),
        None => s.serialize_none(),
    }
}

/// The image pairs to compare: (name, ground truth, test).
pub fn pairs(gt: &Path, test: &Path, frames: Option<&Path>) -> Result<Vec<(String, PathBuf, PathBuf)>, Error> {
    if let Some(file) = frames {
        let listed = frame_images(file)?;
        let tests = images_under(test)?;
        if listed.len() != tests.len() {
            return Err(Error::Pairing(format!(
                "{} lists {} frames and {} holds {} images: give the folder of one split's renders",
                file.display(),
                listed.len(),
                test.display(),
                tests.len()
            )));
        }
        let base = crate::scene::input::folder_of(file);
        return Ok(listed
            .into_iter()
            .zip(tests)
            .map(|(rel, t)| (rel.clone(), base.join(&rel), test.join(t)))
            .collect());
    }
    let gts = images_under(gt)?;
    if gts.is_empty() {
        return Err(Error::Pairing(format!("{} holds no PNG or JPEG image", gt.display())));
    }
    let mut out = Vec::with_capacity(gts.len());
    let mut missing = Vec::new();
    for rel in gts {
        let same = test.join(&rel);
        let found = if same.is_file() {
            Some(same)
        } else {
            ["png", "jpg", "jpeg"].iter().map(|e| test.join(&rel).with_extension(e)).find(|p| p.is_file())
        };
        match found {
            Some(t) => out.push((rel.clone(), gt.join(&rel), t)),
            None => missing.push(rel),
        }
    }
    if !missing.is_empty() {
        return Err(Error::Pairing(format!(
            "{} of {} ground-truth images have no counterpart in {} (first: {}); name renders as the ground truth \
             names them, or pass --frames transforms_SPLIT.json to pair by order",
            missing.len(),
            out.len() + missing.len(),
            test.display(),
            missing[0]
        )));
    }
    Ok(out)
}

/// The images a transforms.json's frames name, relative to its folder (`.png` added where `file_path` has no
/// extension, as NeRF-synthetic's loaders do).
fn frame_images(file: &Path) -> Result<Vec<String>, Error> {
    let text = std::fs::read_to_string(file).map_err(|e| Error::Io { path: file.to_path_buf(), source: e })?;
    let doc: serde_json::Value =
        serde_json::from_str(&text).map_err(|e| Error::Pairing(format!("{}: {e}", file.display())))?;
    let frames =
        doc["frames"].as_array().ok_or_else(|| Error::Pairing(format!("{}: no `frames` list", file.display())))?;
    frames
        .iter()
        .enumerate()
        .map(|(i, f)| {
            let p = f["file_path"]
                .as_str()
                .ok_or_else(|| Error::Pairing(format!("{}: frame {i} has no `file_path`", file.display())))?;
            let p = p.strip_prefix("./").unwrap_or(p);
            Ok(if Path::new(p).extension().is_some() { p.to_string() } else { format!("{p}.png") })
        })
        .collect()
}

/// PNG and JPEG files under `dir`, relative, in natural order.
fn images_under(dir: &Path) -> Result<Vec<String>, Error> {
    let mut out = Vec::new();
    let mut todo = vec![dir.to_path_buf()];
    while let Some(d) = todo.pop() {
        let entries = std::fs::read_dir(&d).map_err(|e| Error::Io { path: d.clone(), source: e })?;
        for e in entries {
            let p = e.map_err(|e| Error::Io { path: d.clone(), source: e })?.path();
            if p.is_dir() {
                todo.push(p);
            } else if p
                .extension()
                .is_some_and(|e| ["png", "jpg", "jpeg"].contains(&e.to_string_lossy().to_ascii_lowercase().as_str()))
            {
                if let Ok(rel) = p.strip_prefix(dir) {
                    out.push(rel.to_string_lossy().replace('\\', "/"));
                }
            }
        }
    }
    out.sort_by(|a, b| natural_cmp(a, b));
    Ok(out)
}

/// An image as sRGB values in 0 … 1, composited over `bg` when it has alpha, and its alpha coverage.
struct Decoded {
    w: usize,
    h: usize,
    /// Three planes, R, G, B.
    rgb: [Vec<f64>; 3],
    /// Alpha > 0, when the image has alpha.
    covered: Option<Vec<bool>>,
}

fn decode(path: &Path, bg: [f64; 3]) -> Result<Decoded, Error> {
    let img = image::ImageReader::open(path)
        .and_then(|r| r.with_guessed_format())
        .map_err(|e| Error::Io { path: path.to_path_buf(), source: e })?
        .decode()
        .map_err(|e| Error::Image { path: path.to_path_buf(), message: e.to_string() })?;
    let has_alpha = img.color().has_alpha();
    let (w, h) = (img.width() as usize, img.height() as usize);
    let (values, scale): (Vec<f64>, f64) = if img.color().bytes_per_pixel() / img.color().channel_count() > 1 {
        (img.into_rgba16().into_raw().into_iter().map(f64::from).collect(), 65535.0)
    } else {
        (img.into_rgba8().into_raw().into_iter().map(f64::from).collect(), 255.0)
    };
    let mut rgb = [vec![0.0; w * h], vec![0.0; w * h], vec![0.0; w * h]];
    let mut covered = has_alpha.then(|| vec![false; w * h]);
    for (i, px) in values.chunks_exact(4).enumerate() {
        let a = px[3] / scale;
        for c in 0..3 {
            let v = px[c] / scale;
            rgb[c][i] = if has_alpha { v * a + bg[c] * (1.0 - a) } else { v };
        }
        if let Some(cov) = covered.as_mut() {
            cov[i] = px[3] > 0.0;
        }
    }
    Ok(Decoded { w, h, rgb, covered })
}

/// The scores of one pair.
fn score(name: &str, gt: &Path, test: &Path, o: Options) -> Result<Score, Error> {
    let a = decode(gt, o.background)?;
    let b = decode(test, o.background)?;
    if (a.w, a.h) != (b.w, b.h) {
        return Err(Error::Pairing(format!(
            "{} is {}×{} and {} is {}×{}: render at the ground truth's size",
            gt.display(),
            a.w,
            a.h,
            test.display(),
            b.w,
            b.h
        )));
    }
    let (w, h) = (a.w, a.h);
    if w <= 2 * ssim::RADIUS || h <= 2 * ssim::RADIUS {
        return Err(Error::Pairing(format!("{}: {w}×{h} is too small for SSIM's 11×11 window", gt.display())));
    }
    let mask = a.covered.as_deref();
    let (mut se, mut se_in, mut n_in) = (0.0, 0.0, 0usize);
    let (mut s, mut s_in) = (0.0, 0.0);
    for c in 0..3 {
        for i in 0..w * h {
            let d = a.rgb[c][i] - b.rgb[c][i];
            se += d * d;
            if mask.is_some_and(|m| m[i]) {
                se_in += d * d;
                n_in += 1;
            }
        }
        let map = ssim::ssim_map(&Plane { v: &a.rgb[c], w, h }, &Plane { v: &b.rgb[c], w, h });
        s += ssim::cropped_mean(&map, w, h, None).unwrap_or(1.0);
        s_in += mask.and_then(|m| ssim::cropped_mean(&map, w, h, Some(m))).unwrap_or(f64::NAN);
    }
    let psnr_masked = (n_in > 0).then(|| ssim::psnr(se_in / n_in as f64));
    Ok(Score {
        name: name.to_string(),
        psnr: ssim::psnr(se / (3 * w * h) as f64),
        ssim: s / 3.0,
        psnr_masked,
        ssim_masked: (s_in.is_finite() && psnr_masked.is_some()).then(|| s_in / 3.0),
    })
}

/// Every pair's scores, in the pairs' order (computed in parallel).
pub fn compare(pairs: &[(String, PathBuf, PathBuf)], o: Options) -> Result<Vec<Score>, Error> {
    pairs.par_iter().map(|(n, g, t)| score(n, g, t, o)).collect()
}
