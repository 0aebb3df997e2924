//! Lights of a scene: the manifest's `[light.NAME]` tables and a glTF file's `KHR_lights_punctual` lights, in
//! one form, in Blender's units (what [`crate::render::light`] shades with). A file's lights are converted the way
//! Blender 3.4's glTF importer converts them (its default "Standard" lighting mode), so a scene lit by its own
//! lights looks in vvgen as it does imported into Blender.

use std::f32::consts::PI;

use glam::{Mat4, Vec3};

/// A light of the scene.
#[derive(Debug, Clone, PartialEq)]
pub struct Light {
    /// Where it is and how it spreads.
    pub kind: LightKind,
    /// Linear RGB colour.
    pub color: Vec3,
    /// Sun: irradiance in W/m² (Blender's Strength); point and spot: power in W.
    pub intensity: f32,
    /// Whether it casts shadows.
    pub shadows: bool,
}

/// The kinds of light.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum LightKind {
    /// Parallel light travelling along `direction`, from a disk `angle` radians across (soft shadows).
    Sun {
        /// Unit direction the light travels.
        direction: Vec3,
        /// Angular diameter in radians.
        angle: f32,
    },
    /// Light from a point (a sphere of `radius` for soft shadows).
    Point {
        /// World position.
        position: Vec3,
        /// Radius in world units.
        radius: f32,
    },
    /// A point light limited to a cone.
    Spot {
        /// World position.
        position: Vec3,
        /// Unit axis direction.
        direction: Vec3,
        /// Full cone angle in radians.
        cone: f32,
        /// Blender's spot blend, 0..1.
        blend: f32,
        /// Radius in world units.
        radius: f32,
    },
}

/// Blender's luminous efficacy for converting photometric glTF units: 683 lm/W.
const LUMENS_PER_WATT: f32 = 683.0;
/// The radius Blender gives a new point or spot light (its `shadow_soft_size`), which its glTF importer keeps.
const BLENDER_LIGHT_RADIUS: f32 = 0.25;
/// The angular diameter Blender gives a new sun, which its glTF importer keeps: 0.526°.
const BLENDER_SUN_ANGLE: f32 = 0.526 * PI / 180.0;

impl LightKind {
    /// `sun`, `point` or `spot`.
    pub fn name(&self) -> &'static str {
        match self {
            LightKind::Sun { .. } => "sun",
            LightKind::Point { .. } => "point",
            LightKind::Spot { .. } => "spot",
        }
    }
}

impl Light {
    /// This light moved by `m` (a light of a static mesh placed in the world).
    pub fn transformed(&self, m: Mat4) -> Light {
        let dir = |d: Vec3| m.transform_vector3(d).normalize_or(d);
        let kind = match self.kind {
            LightKind::Sun { direction, angle } => LightKind::Sun { direction: dir(direction), angle },
            LightKind::Point { position, radius } => {
                LightKind::Point { position: m.transform_point3(position), radius }
            }
            LightKind::Spot { position, direction, cone, blend, radius } => LightKind::Spot {
                position: m.transform_point3(position),
                direction: dir(direction),
                cone,
                blend,
                radius,
            },
        };
        Light { kind, ..self.clone() }
    }
}

/// A `KHR_lights_punctual` light as defined in a file, converted to Blender's units: at the origin of its node,
/// pointing down the node's −Z. [`FileLight::place`] puts it where its node is.
#[derive(Debug, Clone, PartialEq)]
pub struct FileLight {
    /// The file's name for it, if any.
    pub name: Option<String>,
    /// The light at its node's origin.
    pub light: Light,
}

impl FileLight {
    /// Converts a glTF light: `intensity` is lux for a directional light and candela for a point or spot light;
    /// `spot` holds the inner and outer cone angles (radians) of a spot light. Blender's importer turns lux into
    /// W/m² by 683 lm/W, candela into watts by 4π/683, a spot's outer angle into its full cone and the inner one
    /// into its blend (1 − inner/outer); its lights keep Blender's default size. `range` is ignored, as Blender
    /// ignores it. Values the extension forbids are errors.
    pub fn from_gltf(
        name: Option<&str>,
        color: [f32; 3],
        intensity: f32,
        kind: GltfLightKind,
    ) -> Result<FileLight, FileLightError> {
        let light = || name.map_or_else(|| "a light".to_string(), |n| format!("light `{n}`"));
        if !(intensity >= 0.0 && intensity.is_finite()) {
            return Err(FileLightError::Intensity { light: light(), intensity });
        }
        if color.iter().any(|c| !(*c >= 0.0 && c.is_finite())) {
            return Err(FileLightError::Color { light: light(), color });
        }
        let watts = intensity * 4.0 * PI / LUMENS_PER_WATT;
        let (position, direction) = (Vec3::ZERO, Vec3::NEG_Z);
        let (kind, intensity) = match kind {
            GltfLightKind::Directional => {
                (LightKind::Sun { direction, angle: BLENDER_SUN_ANGLE }, intensity / LUMENS_PER_WATT)
            }
            GltfLightKind::Point => (LightKind::Point { position, radius: BLENDER_LIGHT_RADIUS }, watts),
            GltfLightKind::Spot { inner, outer } => {
                if !(outer > 0.0 && outer <= PI / 2.0 + 1e-6 && inner >= 0.0 && inner < outer) {
                    return Err(FileLightError::Cone { light: light(), inner, outer });
                }
                let kind = LightKind::Spot {
                    position,
                    direction,
                    cone: 2.0 * outer,
                    blend: 1.0 - inner / outer,
                    radius: BLENDER_LIGHT_RADIUS,
                };
                (kind, watts)
            }
        };
        Ok(FileLight {
            name: name.map(str::to_string),
            light: Light { kind, color: Vec3::from(color), intensity, shadows: true },
        })
    }

    /// The light placed by its node's world matrix `world`.
    pub fn place(&self, world: Mat4) -> Light {
        self.light.transformed(world)
    }
}

/// A `KHR_lights_punctual` light with values the extension forbids (`light` names it: "light `NAME`", or "a
/// light" when it has no name).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FileLightError {
    /// A negative or non-finite intensity.
    #[error("{light} has intensity {intensity} (it must be 0 or more)")]
    Intensity {
        /// The light.
        light: String,
        /// Its intensity.
        intensity: f32,
    },
    /// A negative or non-finite colour component.
    #[error("{light} has colour {color:?} (components must be 0 or more)")]
    Color {
        /// The light.
        light: String,
        /// Its colour.
        color: [f32; 3],
    },
    /// Spot cone angles outside 0 ≤ inner < outer ≤ π/2.
    #[error("{light} has cone angles inner {inner}, outer {outer} (the extension requires 0 ≤ inner < outer ≤ π/2)")]
    Cone {
        /// The light.
        light: String,
        /// `innerConeAngle`.
        inner: f32,
        /// `outerConeAngle`.
        outer: f32,
    },
}

/// The three kinds of `KHR_lights_punctual` light.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum GltfLightKind {
    /// `directional`.
    Directional,
    /// `point`.
    Point,
    /// `spot`, with its cone angles in radians.
    Spot {
        /// `innerConeAngle`.
        inner: f32,
        /// `outerConeAngle`.
        outer: f32,
    },
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn blenders_importer_units() {
        // 683 lux is a sun of 1 W/m²; 683 cd is 4π W; a spot's outer angle is half its cone.
        let sun = FileLight::from_gltf(None, [1.0; 3], 683.0, GltfLightKind::Directional).unwrap();
        assert_eq!(sun.light.intensity, 1.0);
        let point = FileLight::from_gltf(None, [1.0; 3], 683.0, GltfLightKind::Point).unwrap();
        assert!((point.light.intensity - 4.0 * PI).abs() < 1e-5);
        let spot = FileLight::from_gltf(None, [1.0; 3], 1.0, GltfLightKind::Spot { inner: 0.2, outer: 0.4 }).unwrap();
        match spot.light.kind {
            LightKind::Spot { cone, blend, .. } => {
                assert!((cone - 0.8).abs() < 1e-6 && (blend - 0.5).abs() < 1e-6);
            }
            k => panic!("{k:?}"),
        }
        let bad = FileLight::from_gltf(Some("x"), [1.0; 3], 1.0, GltfLightKind::Spot { inner: 0.5, outer: 0.4 });
        assert!(bad.unwrap_err().to_string().contains("light `x`"));
        assert!(FileLight::from_gltf(None, [1.0; 3], -1.0, GltfLightKind::Point).is_err());
    }

    #[test]
    fn a_placed_light_follows_its_node() {
        let spot = FileLight::from_gltf(None, [1.0; 3], 1.0, GltfLightKind::Spot { inner: 0.0, outer: 0.5 }).unwrap();
        let world = Mat4::from_rotation_translation(glam::Quat::from_rotation_x(PI / 2.0), Vec3::new(1.0, 2.0, 3.0));
        match spot.place(world).kind {
            LightKind::Spot { position, direction, .. } => {
                assert!(position.distance(Vec3::new(1.0, 2.0, 3.0)) < 1e-6);
                // −Z turned a quarter about X points along +Y.
                assert!(direction.distance(Vec3::Y) < 1e-6, "{direction}");
            }
            k => panic!("{k:?}"),
        }
    }
}
