//! `vvgen compare`: a table (or JSON) of scores, per image or frame and over all of them.

use std::path::Path;
use std::process::ExitCode;

use crate::compare::{self, clouds, images, summary};

/// What `--background` names: `white`, `black` or `R,G,B` in 0 … 1.
fn background(s: &str) -> anyhow::Result<[f64; 3]> {
    match s {
        "white" => Ok([1.0; 3]),
        "black" => Ok([0.0; 3]),
        _ => {
            let v: Vec<f64> =
                s.split(',').map(|c| c.trim().parse::<f64>()).collect::<Result<_, _>>().map_err(|_| {
                    compare::Error::Pairing(format!("--background {s}: use white, black or R,G,B in 0 … 1"))
                })?;
            match v.as_slice() {
                [r, g, b] if v.iter().all(|c| (0.0..=1.0).contains(c)) => Ok([*r, *g, *b]),
                _ => {
                    Err(compare::Error::Pairing(format!("--background {s}: use white, black or R,G,B in 0 … 1")).into())
                }
            }
        }
    }
}

fn db(v: f64) -> String {
    if v.is_finite() {
        format!("{v:.3}")
    } else {
        "inf".into()
    }
}

/// Runs `vvgen compare`.
pub fn run(
    reference: &Path,
    test: &Path,
    frames: Option<&Path>,
    bg: &str,
    peak: Option<f64>,
    normals: Option<&Path>,
    json: bool,
) -> anyhow::Result<ExitCode> {
    if let Some(p) = peak.filter(|p| !(p.is_finite() && *p > 0.0)) {
        return Err(compare::Error::Pairing(format!("--peak {p}: give a positive number, e.g. 1023 for vox10")).into());
    }
    for p in [reference, test] {
        if !p.exists() {
            return Err(compare::Error::Io {
                path: p.to_path_buf(),
                source: std::io::Error::new(std::io::ErrorKind::NotFound, "no such file or folder"),
            }
            .into());
        }
    }
    if compare::is_clouds(reference) {
        let pairs = compare::cloud_pairs(reference, test)?;
        // The reference's normals from beside it: a file, or a folder of one per frame, in the same order.
        let normal_files = match normals {
            Some(n) => compare::cloud_pairs(reference, n)?.into_iter().map(|(_, _, f)| Some(f)).collect(),
            None => vec![None; pairs.len()],
        };
        let mut scores = Vec::with_capacity(pairs.len());
        for ((name, a, b), n) in pairs.iter().zip(normal_files) {
            let (ra, rb) = rayon::join(|| clouds::Cloud::read(a), || clouds::Cloud::read(b));
            let ra = match n {
                Some(f) => ra?.with_normals_of(clouds::Cloud::read(&f)?, &f)?,
                None => ra?,
            };
            scores.push(clouds::score(name, &ra, &rb?, peak));
        }
        if json {
            let mean = |f: &dyn Fn(&clouds::Score) -> Option<f64>| summary(scores.iter().filter_map(f)).map(|s| s.0);
            let doc = serde_json::json!({
                "kind": "point clouds",
                "frames": scores,
                "mean": {
                    "d1_psnr": mean(&|s| Some(s.d1_psnr)),
                    "d2_psnr": mean(&|s| s.d2_psnr),
                    "y_psnr": mean(&|s| s.color_psnr.map(|c| c[0])),
                    "cb_psnr": mean(&|s| s.color_psnr.map(|c| c[1])),
                    "cr_psnr": mean(&|s| s.color_psnr.map(|c| c[2])),
                },
            });
            println!("{}", serde_json::to_string_pretty(&doc)?);
            return Ok(ExitCode::SUCCESS);
        }
        println!(
            "{:<28} {:>9} {:>9} {:>9} {:>8} {:>8} {:>8}",
            "frame", "peak", "D1 dB", "D2 dB", "Y dB", "Cb dB", "Cr dB"
        );
        for s in &scores {
            let c = |k: usize| s.color_psnr.map_or("—".to_string(), |c| db(c[k]));
            println!(
                "{:<28} {:>9.3} {:>9} {:>9} {:>8} {:>8} {:>8}",
                s.name,
                s.peak,
                db(s.d1_psnr),
                s.d2_psnr.map_or("—".to_string(), db),
                c(0),
                c(1),
                c(2)
            );
        }
        if scores.len() > 1 {
            let m = |f: &dyn Fn(&clouds::Score) -> Option<f64>| {
                summary(scores.iter().filter_map(f)).map_or("—".to_string(), |s| db(s.0))
            };
            println!(
                "{:<28} {:>9} {:>9} {:>9} {:>8} {:>8} {:>8}",
                format!("mean of {}", scores.len()),
                "",
                m(&|s| Some(s.d1_psnr)),
                m(&|s| s.d2_psnr),
                m(&|s| s.color_psnr.map(|c| c[0])),
                m(&|s| s.color_psnr.map(|c| c[1])),
                m(&|s| s.color_psnr.map(|c| c[2]))
            );
        }
        return Ok(ExitCode::SUCCESS);
    }
    let options = images::Options { background: background(bg)? };
    let pairs = images::pairs(reference, test, frames)?;
    let scores = images::compare(&pairs, options)?;
    let psnr = summary(scores.iter().map(|s| s.psnr));
    let ssim = summary(scores.iter().map(|s| s.ssim));
    let psnr_m = summary(scores.iter().filter_map(|s| s.psnr_masked));
    let ssim_m = summary(scores.iter().filter_map(|s| s.ssim_masked));
    if json {
        let agg = |s: Option<(f64, f64, usize)>| {
            s.map(|(mean, worst, perfect)| serde_json::json!({ "mean": mean, "worst": worst, "identical": perfect }))
        };
        let doc = serde_json::json!({
            "kind": "images",
            "images": scores,
            "psnr": agg(psnr),
            "ssim": agg(ssim),
            "psnr_masked": agg(psnr_m),
            "ssim_masked": agg(ssim_m),
        });
        println!("{}", serde_json::to_string_pretty(&doc)?);
        return Ok(ExitCode::SUCCESS);
    }
    println!("{:<32} {:>9} {:>8} {:>11} {:>11}", "image", "PSNR dB", "SSIM", "PSNR in α", "SSIM in α");
    for s in &scores {
        println!(
            "{:<32} {:>9} {:>8.5} {:>11} {:>11}",
            s.name,
            db(s.psnr),
            s.ssim,
            s.psnr_masked.map_or("—".to_string(), db),
            s.ssim_masked.map_or("—".to_string(), |v| format!("{v:.5}"))
        );
    }
    let cell = |s: Option<(f64, f64, usize)>, f: &dyn Fn(f64) -> String| s.map_or("—".to_string(), |s| f(s.0));
    let worst = |s: Option<(f64, f64, usize)>, f: &dyn Fn(f64) -> String| s.map_or("—".to_string(), |s| f(s.1));
    let five = |v: f64| format!("{v:.5}");
    println!(
        "{:<32} {:>9} {:>8} {:>11} {:>11}",
        format!("mean of {}", scores.len()),
        cell(psnr, &db),
        cell(ssim, &five),
        cell(psnr_m, &db),
        cell(ssim_m, &five)
    );
    println!(
        "{:<32} {:>9} {:>8} {:>11} {:>11}",
        "worst",
        worst(psnr, &db),
        worst(ssim, &five),
        worst(psnr_m, &db),
        worst(ssim_m, &five)
    );
    if let Some((_, _, n)) = psnr.filter(|p| p.2 > 0) {
        println!("{n} image(s) identical to the ground truth (PSNR inf) are left out of the PSNR mean");
    }
    Ok(ExitCode::SUCCESS)
}
