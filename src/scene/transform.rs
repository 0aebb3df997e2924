//! Resolving a [`Placement`] to one 4×4 matrix from the bounds of the frames it covers.
//!
//! `world = translate · rotate · scale · fit · center · up · matrix`. The caller gathers [`Stats`] of the
//! geometry after `up · matrix` ([`pre`]) over the frames `over` selects, once per sequence.

use glam::{DMat4, DVec3, Mat4, Vec3};

use super::input::{Center, Fit, Placement, Reach, UpAxis};

/// Bounds and centroid accumulator.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Stats {
    /// Minimum corner.
    pub lo: DVec3,
    /// Maximum corner.
    pub hi: DVec3,
    /// Sum of points (for the centroid).
    pub sum: DVec3,
    /// Number of points.
    pub count: u64,
    /// The distance of the farthest point from the centre the transform moves to the origin: a frame fit's
    /// measure, gathered in a second pass once that centre is known ([`frame_centre`]).
    pub far: f64,
}

impl Default for Stats {
    fn default() -> Self {
        Stats {
            lo: DVec3::splat(f64::INFINITY),
            hi: DVec3::splat(f64::NEG_INFINITY),
            sum: DVec3::ZERO,
            count: 0,
            far: 0.0,
        }
    }
}

impl Stats {
    /// Adds points.
    pub fn add(&mut self, points: &[Vec3]) {
        for p in points {
            let d = p.as_dvec3();
            self.lo = self.lo.min(d);
            self.hi = self.hi.max(d);
            self.sum += d;
        }
        self.count += points.len() as u64;
    }

    /// Whether no point was added.
    pub fn is_empty(&self) -> bool {
        self.count == 0
    }

    /// The spacing of single precision, which positions are held in, where the points lie, when it resolves
    /// fewer than 10 000 steps across them: a scan in georeferenced coordinates (at 4 000 km from the origin,
    /// steps of 0.25 m). `None` when the points are near enough zero for their size.
    pub fn coarse_step(&self) -> Option<f64> {
        let extent = (self.hi - self.lo).max_element();
        let reach = self.lo.abs().max(self.hi.abs()).max_element();
        if self.is_empty() || extent.is_nan() || extent <= 0.0 || !reach.is_finite() || reach == 0.0 {
            return None;
        }
        let step = 2f64.powi(reach.log2().floor() as i32 - 23);
        (step * 10_000.0 > extent).then_some(step)
    }

    /// The middle of the bounds.
    pub fn centre(&self) -> DVec3 {
        (self.lo + self.hi) * 0.5
    }

    /// The warning for points whose [`Stats::coarse_step`] is too coarse, with the way out: the `origin` to set
    /// on a PLY or OBJ source (the middle of the bounds in whole units; `to_file` maps the points' space back to the
    /// file's), else moving the file near zero where it is made.
    pub fn far_from_origin(&self, to_file: DMat4) -> Option<String> {
        let step = self.coarse_step()?;
        let extent = (self.hi - self.lo).max_element();
        let c = self.centre();
        let o = to_file.transform_point3(c).round();
        Some(format!(
            "its coordinates lie around ({:.1}, {:.1}, {:.1}) and span {extent:.3}: in single precision, which \
             vvgen (like Blender) holds positions in, they are {step} apart there ({:.2} % of that span), so its \
             shape comes in steps. A PLY file of doubles or an OBJ: set `origin = [{:.0}, {:.0}, {:.0}]` on the source, \
             subtracted as it is read; otherwise move it near the origin where it is made (CloudCompare offers a \
             global shift on import)",
            c.x,
            c.y,
            c.z,
            100.0 * step / extent,
            o.x,
            o.y,
            o.z,
        ))
    }
}

/// `up · matrix`: the part of the transform that does not depend on bounds.
pub fn pre(t: &Placement, up: UpAxis) -> DMat4 {
    let m = t.matrix.map_or(DMat4::IDENTITY, |m| DMat4::from_cols_array_2d(&m).transpose());
    // The rotation taking the source's up to +Z, about X where the up lies in YZ (so x stays x), about Y for ±X;
    // the new axes exactly (columns: where x, y and z go).
    let axes = |x: [f64; 3], y: [f64; 3], z: [f64; 3]| {
        DMat4::from_cols(
            glam::DVec3::from(x).extend(0.0),
            glam::DVec3::from(y).extend(0.0),
            glam::DVec3::from(z).extend(0.0),
            glam::DVec4::W,
        )
    };
    let up_m = match up {
        // +Y up → +Z up: +90° about X maps (x, y, z) to (x, -z, y).
        UpAxis::Y => DMat4::from_rotation_x(std::f64::consts::FRAC_PI_2),
        UpAxis::Z => DMat4::IDENTITY,
        // (x, y, z) → (x, z, −y).
        UpAxis::NegY => axes([1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]),
        // (x, y, z) → (x, −y, −z).
        UpAxis::NegZ => axes([1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, -1.0]),
        // (x, y, z) → (−z, y, x).
        UpAxis::X => axes([0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]),
        // (x, y, z) → (z, y, −x).
        UpAxis::NegX => axes([0.0, 0.0, -1.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0]),
    };
    up_m * m
}

/// Why a transform cannot be resolved.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum Error {
    /// Fitting or centring was asked of a source with no geometry.
    #[error("cannot fit or centre: the source has no triangles or points (lines are not drawn)")]
    NoGeometry,
    /// A frame fit has no camera to size the subject for.
    #[error(
        "`fit = \"frame\"` sizes the subject for the splits' cameras, and no split uses a rig that places them \
         around a target: use fit = {{ height = … }} or fit = {{ radius = … }}"
    )]
    NoFraming,
    /// A frame fit's cameras cannot hold any subject whole.
    #[error(
        "`fit = \"frame\"`: rig `{rig}`'s cameras cannot see a sphere about the origin whole (its target is too far \
         off-centre, or its cameras too close): move its target nearer the origin or raise its radius"
    )]
    NoRoom {
        /// The rig.
        rig: String,
    },
    /// The measure a fit scales to is zero.
    #[error("cannot fit {what}: the geometry's {what} is zero")]
    ZeroExtent {
        /// `height`, `radius` or `extent`.
        what: &'static str,
    },
}

/// Whether the transform needs bounds at all.
pub fn needs_stats(t: &Placement) -> bool {
    t.fit.is_some() || matches!(t.center, Some(Center::Bbox | Center::Centroid))
}

/// The centring rule: `center`, else the bounding box's centre for a frame fit (the cameras aim at the
/// origin), else none.
fn center_rule(t: &Placement) -> Center {
    t.center.unwrap_or(if matches!(t.fit, Some(Fit::Frame { .. })) { Center::Bbox } else { Center::None })
}

/// The point the transform moves to the origin, in the space after [`pre`].
fn centre_of(t: &Placement, stats: &Stats) -> DVec3 {
    match center_rule(t) {
        Center::None => DVec3::ZERO,
        Center::Bbox => (stats.lo + stats.hi) * 0.5,
        Center::Centroid => stats.sum / stats.count.max(1) as f64,
    }
}

/// For a frame fit: the centre whose farthest point [`Stats::far`] must be gathered before [`resolve`] (a second
/// pass over the frames: the centre is known only once the first has seen them all).
pub fn frame_centre(t: &Placement, stats: &Stats) -> Option<DVec3> {
    matches!(t.fit, Some(Fit::Frame { .. })).then(|| centre_of(t, stats))
}

/// The full matrix, given stats gathered after [`pre`] and, for a frame fit, the reach of the cameras
/// ([`Reach`]). Errors when a fit is asked of empty or flat geometry, or a frame fit
/// of cameras with no room.
pub fn resolve(t: &Placement, up: UpAxis, stats: &Stats, reach: Option<&Reach>) -> Result<Mat4, Error> {
    let pre = pre(t, up);
    let center = centre_of(t, stats);
    if needs_stats(t) && stats.is_empty() {
        return Err(Error::NoGeometry);
    }
    let mut s = 1.0;
    if let Some(f) = t.fit {
        let size = stats.hi - stats.lo;
        let (measure, target, what) = match f {
            Fit::Frame { margin } => {
                let reach = reach.ok_or(Error::NoFraming)?;
                if reach.radius <= 0.0 {
                    return Err(Error::NoRoom { rig: reach.rig.clone() });
                }
                (stats.far, reach.radius * (1.0 - margin), "size")
            }
            Fit::Height(h) => (size.z, h, "height"),
            Fit::Radius(r) => {
                let far = (0..8)
                    .map(|i| {
                        DVec3::new(
                            pick(i & 1, stats.lo.x, stats.hi.x),
                            pick(i & 2, stats.lo.y, stats.hi.y),
                            pick(i & 4, stats.lo.z, stats.hi.z),
                        )
                        .distance(center)
                    })
                    .fold(0.0, f64::max);
                (far, r, "radius")
            }
            Fit::Extent(e) => (size.max_element(), e, "extent"),
        };
        if measure.is_nan() || measure <= 1e-12 {
            return Err(Error::ZeroExtent { what });
        }
        s = target / measure;
    }
    let extra = DVec3::from(t.scale);
    let [x, y, z] = t.rotate_deg;
    let r = DMat4::from_rotation_z(z.to_radians())
        * DMat4::from_rotation_y(y.to_radians())
        * DMat4::from_rotation_x(x.to_radians());
    let tr = DMat4::from_translation(DVec3::from(t.translate));
    let m =
        tr * r * DMat4::from_scale(extra) * DMat4::from_scale(DVec3::splat(s)) * DMat4::from_translation(-center) * pre;
    Ok(m.as_mat4())
}

fn pick(bit: usize, lo: f64, hi: f64) -> f64 {
    if bit != 0 {
        hi
    } else {
        lo
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_up_axis_turns_to_z_and_keeps_handedness() {
        let t = Placement::default();
        for (up, axis) in [
            (UpAxis::Y, glam::DVec3::Y),
            (UpAxis::Z, glam::DVec3::Z),
            (UpAxis::NegY, -glam::DVec3::Y),
            (UpAxis::NegZ, -glam::DVec3::Z),
            (UpAxis::X, glam::DVec3::X),
            (UpAxis::NegX, -glam::DVec3::X),
        ] {
            let m = pre(&t, up);
            assert!((m.transform_vector3(axis) - glam::DVec3::Z).length() < 1e-12, "{up:?}");
            assert!((glam::DMat3::from_mat4(m).determinant() - 1.0).abs() < 1e-12, "{up:?}: a rotation");
        }
    }

    #[test]
    fn y_up_becomes_z_up_and_fits() {
        let t = Placement { fit: Some(Fit::Height(2.0)), center: Some(Center::Bbox), ..Placement::default() };
        let mut st = Stats::default();
        // A column 4 tall along source Y, from y=1 to y=5: after up it spans z=1..5.
        let p = pre(&t, UpAxis::Y).as_mat4();
        st.add(&[p.transform_point3(Vec3::new(0.0, 1.0, 0.0)), p.transform_point3(Vec3::new(1.0, 5.0, 0.0))]);
        let m = resolve(&t, UpAxis::Y, &st, None).unwrap();
        let top = m.transform_point3(Vec3::new(1.0, 5.0, 0.0));
        let bottom = m.transform_point3(Vec3::new(0.0, 1.0, 0.0));
        assert!((top.z - 1.0).abs() < 1e-6 && (bottom.z + 1.0).abs() < 1e-6, "{top} {bottom}");
    }
}
