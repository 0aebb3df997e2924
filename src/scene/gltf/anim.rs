//! Animation samplers: STEP, LINEAR (quaternions slerped on the shortest path) and CUBICSPLINE (the spec's
//! Hermite form with in/out tangents, quaternions renormalized). Times before the first key clamp to it,
//! after the last to the last.

use glam::{Quat, Vec4};

/// Interpolation.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Interp {
    /// Hold the previous key.
    Step,
    /// Linear (slerp for rotations).
    Linear,
    /// Cubic Hermite spline with tangents.
    CubicSpline,
}

/// What a channel animates.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Target {
    /// Node translation.
    Translation,
    /// Node rotation.
    Rotation,
    /// Node scale.
    Scale,
    /// Morph weights.
    Weights,
}

/// One sampler: key times and values (`width` floats per value; CUBICSPLINE stores in-tangent, value,
/// out-tangent per key).
#[derive(Debug, Clone)]
pub struct Sampler {
    times: Vec<f32>,
    values: Vec<f32>,
    width: usize,
    interp: Interp,
    rotation: bool,
    /// Whether rotation keys had to be normalized on load.
    pub normalized_quaternions: bool,
}

impl Sampler {
    /// Checks the key layout (its message is wrapped into [`crate::scene::Error::Gltf`] by the loader).
    pub(crate) fn new(
        times: Vec<f32>,
        mut values: Vec<f32>,
        width: usize,
        interp: Interp,
        rotation: bool,
    ) -> Result<Sampler, String> {
        if times.is_empty() {
            return Err("sampler has no keys".into());
        }
        if times.iter().any(|t| !t.is_finite()) || times.windows(2).any(|w| w[1] < w[0]) {
            return Err("sampler key times must be finite and increasing".into());
        }
        let per_key = if interp == Interp::CubicSpline { 3 * width } else { width };
        if interp == Interp::CubicSpline && times.len() < 2 {
            return Err("a CUBICSPLINE sampler needs at least 2 keyframes".into());
        }
        if values.len() != times.len() * per_key {
            return Err(format!(
                "sampler output has {} values, {} keys × {per_key} expected",
                values.len(),
                times.len()
            ));
        }
        let mut normalized = false;
        if rotation {
            for (k, q) in values.chunks_exact_mut(4).enumerate() {
                // Tangents of a cubic spline are not unit quaternions; only values are.
                if interp == Interp::CubicSpline && k % 3 != 1 {
                    continue;
                }
                let len = (q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]).sqrt();
                if (len - 1.0).abs() > 1e-3 {
                    if len == 0.0 {
                        return Err("a rotation key is the zero quaternion".into());
                    }
                    normalized = true;
                    q.iter_mut().for_each(|c| *c /= len);
                }
            }
        }
        Ok(Sampler { times, values, width, interp, rotation, normalized_quaternions: normalized })
    }

    /// Time of the last key.
    pub fn end(&self) -> f32 {
        *self.times.last().expect("BUG: a sampler has keys (Sampler::new refuses none)")
    }

    /// Time of the first key.
    pub fn start(&self) -> f32 {
        self.times[0]
    }

    fn value(&self, k: usize) -> &[f32] {
        let w = self.width;
        match self.interp {
            Interp::CubicSpline => &self.values[(3 * k + 1) * w..(3 * k + 2) * w],
            _ => &self.values[k * w..(k + 1) * w],
        }
    }

    /// Evaluates at time `t` into `out` (`width` floats). Allocation-free.
    pub fn sample(&self, t: f32, out: &mut [f32]) {
        let w = self.width;
        let n = self.times.len();
        if t <= self.times[0] || n == 1 {
            out[..w].copy_from_slice(self.value(0));
            return;
        }
        if t >= self.times[n - 1] {
            out[..w].copy_from_slice(self.value(n - 1));
            return;
        }
        // First key strictly after t; t lies in [k, k+1).
        let k = self.times.partition_point(|&x| x <= t) - 1;
        let (t0, t1) = (self.times[k], self.times[k + 1]);
        let td = t1 - t0;
        let s = if td > 0.0 { (t - t0) / td } else { 0.0 };
        match self.interp {
            Interp::Step => out[..w].copy_from_slice(self.value(k)),
            Interp::Linear => {
                let (a, b) = (self.value(k), self.value(k + 1));
                if self.rotation {
                    let qa = Quat::from_slice(a);
                    let mut qb = Quat::from_slice(b);
                    if qa.dot(qb) < 0.0 {
                        qb = -qb;
                    }
                    out[..4].copy_from_slice(&qa.slerp(qb, s).normalize().to_array());
                } else {
                    for ((o, &x), &y) in out[..w].iter_mut().zip(a).zip(b) {
                        *o = x + (y - x) * s;
                    }
                }
            }
            Interp::CubicSpline => {
                let (s2, s3) = (s * s, s * s * s);
                let (h00, h10, h01, h11) =
                    (2.0 * s3 - 3.0 * s2 + 1.0, s3 - 2.0 * s2 + s, -2.0 * s3 + 3.0 * s2, s3 - s2);
                let base0 = 3 * k * w;
                let base1 = 3 * (k + 1) * w;
                for (i, o) in out[..w].iter_mut().enumerate() {
                    let p0 = self.values[base0 + w + i];
                    let m0 = self.values[base0 + 2 * w + i] * td; // out-tangent of key k
                    let p1 = self.values[base1 + w + i];
                    let m1 = self.values[base1 + i] * td; // in-tangent of key k+1
                    *o = h00 * p0 + h10 * m0 + h01 * p1 + h11 * m1;
                }
                if self.rotation {
                    let q = Vec4::from_slice(&out[..4]).normalize_or_zero();
                    out[..4].copy_from_slice(&q.to_array());
                }
            }
        }
    }
}

/// One channel: a sampler driving one node property.
#[derive(Debug, Clone)]
pub struct Channel {
    /// Target node.
    pub node: usize,
    /// Property.
    pub target: Target,
    /// Keys.
    pub sampler: Sampler,
}

/// An animation clip.
#[derive(Debug, Clone)]
pub struct Animation {
    /// Name, if any.
    pub name: Option<String>,
    /// Channels.
    pub channels: Vec<Channel>,
    /// Earliest key time.
    pub start: f32,
    /// Latest key time.
    pub end: f32,
}

impl Animation {
    /// A clip from its channels.
    pub fn new(name: Option<String>, channels: Vec<Channel>) -> Animation {
        let start = channels.iter().map(|c| c.sampler.start()).fold(f32::INFINITY, f32::min);
        let end = channels.iter().map(|c| c.sampler.end()).fold(f32::NEG_INFINITY, f32::max);
        let (start, end) = if channels.is_empty() { (0.0, 0.0) } else { (start, end) };
        Animation { name, channels, start, end }
    }

    /// Duration in seconds (from time 0, as players do; a clip whose first key is late holds its first pose).
    pub fn duration(&self) -> f32 {
        self.end.max(0.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn linear_and_step_and_clamping() {
        let s = Sampler::new(vec![1.0, 2.0], vec![0.0, 0.0, 0.0, 10.0, 20.0, 30.0], 3, Interp::Linear, false).unwrap();
        let mut o = [0f32; 3];
        s.sample(1.5, &mut o);
        assert_eq!(o, [5.0, 10.0, 15.0]);
        s.sample(0.0, &mut o);
        assert_eq!(o, [0.0; 3]);
        s.sample(9.0, &mut o);
        assert_eq!(o, [10.0, 20.0, 30.0]);
        let s = Sampler::new(vec![1.0, 2.0], vec![0.0, 0.0, 0.0, 10.0, 20.0, 30.0], 3, Interp::Step, false).unwrap();
        s.sample(1.99, &mut o);
        assert_eq!(o, [0.0; 3]);
    }

    #[test]
    fn cubic_spline_hermite() {
        // One component, keys (0, 0) and (1, 1), out-tangent 0 and in-tangent 0: smoothstep.
        let s =
            Sampler::new(vec![0.0, 1.0], vec![0.0, 0.0, 0.0, 0.0, 1.0, 0.0], 1, Interp::CubicSpline, false).unwrap();
        let mut o = [0f32];
        s.sample(0.5, &mut o);
        assert!((o[0] - 0.5).abs() < 1e-6);
        s.sample(0.25, &mut o);
        assert!((o[0] - (3.0 * 0.0625 - 2.0 * 0.015625)).abs() < 1e-6);
    }

    #[test]
    fn malformed_samplers_are_refused() {
        assert!(Sampler::new(vec![0.0], vec![0.0; 3], 1, Interp::CubicSpline, false)
            .unwrap_err()
            .contains("CUBICSPLINE"));
        assert!(Sampler::new(vec![0.0, 1.0], vec![0.0; 5], 3, Interp::Linear, false).is_err());
        assert!(Sampler::new(vec![1.0, 0.0], vec![0.0; 2], 1, Interp::Linear, false).is_err());
        assert!(Sampler::new(vec![0.0], vec![0.0; 4], 4, Interp::Linear, true).is_err());
    }

    #[test]
    fn slerp_takes_the_short_way() {
        let a = Quat::IDENTITY;
        let b = -Quat::from_rotation_z(0.5); // same rotation as +, opposite sign
        let v = [a.to_array(), b.to_array()].concat();
        let s = Sampler::new(vec![0.0, 1.0], v, 4, Interp::Linear, true).unwrap();
        let mut o = [0f32; 4];
        s.sample(0.5, &mut o);
        let q = Quat::from_slice(&o);
        assert!(q.angle_between(Quat::from_rotation_z(0.25)) < 1e-4, "{q:?}");
    }
}
