//! `vvgen compare`: scoring a model's renders or a codec's output against the ground truth vvgen made.
//! Images by PSNR and SSIM ([`images`], [`ssim`]); point clouds by MPEG's D1, D2 and colour PSNR ([`clouds`]).
//! What is compared is told by the paths: two folders or files of PLY clouds are clouds, anything else images.

pub mod clouds;
pub mod images;
mod kdtree;
pub mod ssim;

use std::path::{Path, PathBuf};

use crate::manifest::sequence::natural_cmp;

/// Why a comparison cannot be made. Every variant is a problem with the input (exit 2 at the CLI).
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A file or folder cannot be read.
    #[error("{}: cannot read", path.display())]
    Io {
        /// The path.
        path: PathBuf,
        /// Why.
        #[source]
        source: std::io::Error,
    },
    /// An image does not decode.
    #[error("{}: {message}", path.display())]
    Image {
        /// The file.
        path: PathBuf,
        /// Why.
        message: String,
    },
    /// A point cloud does not read.
    #[error("{}: {message}", path.display())]
    Cloud {
        /// The file.
        path: PathBuf,
        /// Why.
        message: String,
    },
    /// The two sides do not pair up (missing counterparts, counts or sizes that differ).
    #[error("{0}")]
    Pairing(String),
}

/// Whether `p` is a PLY file, or a folder whose files include PLY files and no images.
pub fn is_clouds(p: &Path) -> bool {
    let ply = |f: &Path| f.extension().is_some_and(|e| e.eq_ignore_ascii_case("ply"));
    if p.is_file() {
        return ply(p);
    }
    std::fs::read_dir(p).is_ok_and(|d| {
        let names: Vec<PathBuf> = d.filter_map(|e| e.ok().map(|e| e.path())).collect();
        names.iter().any(|f| ply(f))
            && !names
                .iter()
                .any(|f| f.extension().is_some_and(|e| ["png", "jpg", "jpeg"].contains(&e.to_string_lossy().as_ref())))
    })
}

/// The pairs of cloud files to score: two files, or the PLY files of two folders paired in natural name order
/// (frame by frame: a codec's decoded frames are rarely named as the originals).
pub fn cloud_pairs(reference: &Path, test: &Path) -> Result<Vec<(String, PathBuf, PathBuf)>, Error> {
    if reference.is_file() != test.is_file() {
        return Err(Error::Pairing(format!(
            "{} and {}: compare two PLY files or two folders of them",
            reference.display(),
            test.display()
        )));
    }
    if reference.is_file() {
        let name = reference.file_name().map_or_else(String::new, |n| n.to_string_lossy().into_owned());
        return Ok(vec![(name, reference.to_path_buf(), test.to_path_buf())]);
    }
    let (a, b) = (plys(reference)?, plys(test)?);
    if a.is_empty() || a.len() != b.len() {
        return Err(Error::Pairing(format!(
            "{} holds {} PLY files and {} holds {}: frames pair up in name order, so the counts must match",
            reference.display(),
            a.len(),
            test.display(),
            b.len()
        )));
    }
    Ok(a.into_iter().zip(b).map(|(x, y)| (x.clone(), reference.join(x), test.join(y))).collect())
}

fn plys(dir: &Path) -> Result<Vec<String>, Error> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .map_err(|e| Error::Io { path: dir.to_path_buf(), source: e })?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.is_file() && p.extension().is_some_and(|e| e.eq_ignore_ascii_case("ply")))
        .filter_map(|p| p.file_name().map(|n| n.to_string_lossy().into_owned()))
        .collect();
    v.sort_by(|a, b| natural_cmp(a, b));
    Ok(v)
}

/// The mean of the finite values of `v`, their worst (lowest), and how many are infinite (a PSNR of identical
/// images, left out so one perfect frame cannot make a mean infinite; the count is told beside). Both are
/// infinite when every value is; `None` when there is no value.
pub fn summary(v: impl Iterator<Item = f64>) -> Option<(f64, f64, usize)> {
    let (mut sum, mut n, mut worst, mut perfect) = (0.0, 0usize, f64::INFINITY, 0usize);
    for x in v {
        if x.is_finite() {
            sum += x;
            n += 1;
            worst = worst.min(x);
        } else if x > 0.0 {
            perfect += 1;
        }
    }
    match (n, perfect) {
        (0, 0) => None,
        (0, _) => Some((f64::INFINITY, f64::INFINITY, perfect)),
        _ => Some((sum / n as f64, worst, perfect)),
    }
}
