//! PSNR and SSIM of two images, SSIM as Wang et al. (2004) define it and as scikit-image computes it with
//! `structural_similarity(a, b, data_range=1, channel_axis=-1, gaussian_weights=True, sigma=1.5,
//! use_sample_covariance=False)`: local means and (population) variances under an 11-tap Gaussian of σ 1.5
//! (scipy's `gaussian_filter`, radius `int(3.5σ + 0.5)` = 5, borders reflected about the edge pixel), the SSIM map
//! averaged over the pixels 5 or more from every border, then over the channels. Values are in 0 … 1 (sRGB bytes
//! over 255), `K1 = 0.01`, `K2 = 0.03`.

/// SSIM's window radius: the pixels nearer a border than this are left out of the mean, as scikit-image crops
/// them.
pub const RADIUS: usize = 5;

const SIGMA: f64 = 1.5;

/// One channel of an image: `w × h` values, rows top to bottom.
#[derive(Debug, Clone)]
pub struct Plane<'a> {
    /// The values.
    pub v: &'a [f64],
    /// Width.
    pub w: usize,
    /// Height.
    pub h: usize,
}

/// scipy's Gaussian kernel: `exp(−x² / 2σ²)` over `−r … r`, normalized to sum 1.
fn kernel() -> [f64; 2 * RADIUS + 1] {
    let mut k = [0.0; 2 * RADIUS + 1];
    for (i, v) in k.iter_mut().enumerate() {
        let x = i as f64 - RADIUS as f64;
        *v = (-0.5 / (SIGMA * SIGMA) * x * x).exp();
    }
    let sum: f64 = k.iter().sum();
    k.map(|v| v / sum)
}

/// The index `i` (possibly outside `0 … n`) reflected back inside as scipy's `mode="reflect"` does
/// (`d c b a | a b c d | d c b a`).
fn reflect(i: isize, n: usize) -> usize {
    let n = n as isize;
    let period = 2 * n;
    let m = i.rem_euclid(period);
    (if m < n { m } else { period - 1 - m }) as usize
}

/// `src` filtered by the Gaussian along rows, then along columns (scipy's axis order: 0, then 1).
fn blur(src: &[f64], w: usize, h: usize, k: &[f64; 2 * RADIUS + 1]) -> Vec<f64> {
    let r = RADIUS as isize;
    // Axis 0 (down the columns) first, as `gaussian_filter` runs its axes in order.
    let mut tmp = vec![0.0; w * h];
    for y in 0..h {
        for x in 0..w {
            let mut s = 0.0;
            for (t, kv) in k.iter().enumerate() {
                s += kv * src[reflect(y as isize + t as isize - r, h) * w + x];
            }
            tmp[y * w + x] = s;
        }
    }
    let mut out = vec![0.0; w * h];
    for y in 0..h {
        let row = &tmp[y * w..(y + 1) * w];
        for x in 0..w {
            let mut s = 0.0;
            for (t, kv) in k.iter().enumerate() {
                s += kv * row[reflect(x as isize + t as isize - r, w)];
            }
            out[y * w + x] = s;
        }
    }
    out
}

/// The SSIM map of two planes of one size (data range 1).
pub fn ssim_map(a: &Plane, b: &Plane) -> Vec<f64> {
    let (w, h) = (a.w, a.h);
    let k = kernel();
    let prod = |f: &dyn Fn(usize) -> f64| (0..w * h).map(f).collect::<Vec<f64>>();
    let ux = blur(a.v, w, h, &k);
    let uy = blur(b.v, w, h, &k);
    let uxx = blur(&prod(&|i| a.v[i] * a.v[i]), w, h, &k);
    let uyy = blur(&prod(&|i| b.v[i] * b.v[i]), w, h, &k);
    let uxy = blur(&prod(&|i| a.v[i] * b.v[i]), w, h, &k);
    let (c1, c2) = (0.01f64 * 0.01, 0.03f64 * 0.03);
    (0..w * h)
        .map(|i| {
            let (mx, my) = (ux[i], uy[i]);
            let vx = uxx[i] - mx * mx;
            let vy = uyy[i] - my * my;
            let vxy = uxy[i] - mx * my;
            let (a1, a2) = (2.0 * mx * my + c1, 2.0 * vxy + c2);
            let (b1, b2) = (mx * mx + my * my + c1, vx + vy + c2);
            (a1 * a2) / (b1 * b2)
        })
        .collect()
}

/// The mean of `map` over the pixels at least [`RADIUS`] from every border where `keep` holds (all of them when
/// `keep` is `None`); `None` when no pixel is left.
pub fn cropped_mean(map: &[f64], w: usize, h: usize, keep: Option<&[bool]>) -> Option<f64> {
    let (mut sum, mut n) = (0.0, 0usize);
    for y in RADIUS..h.saturating_sub(RADIUS) {
        for x in RADIUS..w.saturating_sub(RADIUS) {
            let i = y * w + x;
            if keep.is_none_or(|k| k[i]) {
                sum += map[i];
                n += 1;
            }
        }
    }
    (n > 0).then(|| sum / n as f64)
}

/// PSNR (data range 1) of a mean squared error: infinite for identical images.
pub fn psnr(mse: f64) -> f64 {
    if mse <= 0.0 {
        f64::INFINITY
    } else {
        -10.0 * mse.log10()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_kernel_is_scipys_and_reflection_repeats_the_edge() {
        let k = kernel();
        assert!((k.iter().sum::<f64>() - 1.0).abs() < 1e-15);
        // scipy.ndimage._gaussian_kernel1d(1.5, 0, 5)[5]
        assert!((k[5] - 0.26601172486179436).abs() < 1e-15, "{}", k[5]);
        let got: Vec<usize> = (-3..7).map(|i| reflect(i, 4)).collect();
        assert_eq!(got, [2, 1, 0, 0, 1, 2, 3, 3, 2, 1]);
    }

    #[test]
    fn identical_planes_score_one() {
        let v: Vec<f64> = (0..400).map(|i| ((i * 37) % 101) as f64 / 100.0).collect();
        let p = Plane { v: &v, w: 20, h: 20 };
        let m = ssim_map(&p, &p);
        assert!((cropped_mean(&m, 20, 20, None).unwrap() - 1.0).abs() < 1e-12);
    }
}
