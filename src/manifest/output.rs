//! `[output.NAME]`: a dataset writer and its options.

use std::ops::Range;

use serde::Deserialize;
use toml::Spanned;

use super::diag::Diagnostic;
use super::suggest::inapplicable_keys;

/// Most points per frame a point-cloud writer may ask for.
pub const MAX_POINTS: u64 = 100_000_000;

/// One `[output.NAME]` table.
#[derive(Debug, Clone, Deserialize, schemars::JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Output {
    /// The writer.
    #[schemars(with = "Writer")]
    pub(super) writer: Spanned<Writer>,
    /// Directory under `[dataset] out` (default depends on the writer, e.g. `<name>_dnerf`).
    #[schemars(with = "Option<String>")]
    pub(super) dir: Option<Spanned<String>>,
    /// Splits to write (default: all).
    #[schemars(with = "Option<Vec<String>>")]
    pub(super) splits: Option<Vec<Spanned<String>>>,
    /// Which source (default: all sources together).
    #[schemars(with = "Option<String>")]
    pub(super) source: Option<Spanned<String>>,
    /// Image writers: points in the `points3d.ply` / `fused.ply` initialization cloud (default 100 000; 0 = none).
    #[schemars(with = "Option<u64>")]
    pub(super) init_points: Option<Spanned<u64>>,
    /// `instant-ngp`: aabb_scale (power of two, 1..=128).
    #[schemars(with = "Option<u32>")]
    pub(super) aabb_scale: Option<Spanned<u32>>,
    /// `ply-sequence`: surface samples per frame.
    #[schemars(with = "Option<u64>")]
    pub(super) points: Option<Spanned<u64>>,
    /// `ply-sequence`: voxel edge for downsampling, world units.
    #[schemars(with = "Option<f64>")]
    pub(super) voxel: Option<Spanned<f64>>,
    /// `ply-sequence`: quantize to a 2^vox integer grid (8..=16), like 8i's vox10.
    #[schemars(with = "Option<u32>")]
    pub(super) vox: Option<Spanned<u32>>,
    /// `ply-sequence`: keep point identity across frames (default true for animated sources).
    pub correspondence: Option<bool>,
    /// `ply-sequence`: write per-point motion vectors to the next frame.
    #[serde(default)]
    pub motion: bool,
    /// `ply-sequence`: voxel reduction, `"mean"` (default), `"nearest"` or `"first"`.
    pub reduce: Option<Reduce>,
    /// `ply-sequence`: where a voxel's point goes, `"points"` (the reduction's position, default) or `"center"`.
    pub position: Option<VoxelPosition>,
    /// `ply-sequence`: colour averaging space, `"linear"` (default) or `"srgb"`.
    pub color_average: Option<ColorAverage>,
    /// `ply-sequence`: point colours, `"albedo"` (default: the surface colour) or `"lit"` (baked: diffuse
    /// lighting and shadows from `[light.NAME]`, the file's lights and the `[environment]`).
    pub color: Option<PointColor>,
    /// `ply-sequence`: file name pattern (default `{name}_{frame:04}.ply`).
    #[schemars(with = "Option<String>")]
    pub(super) pattern: Option<Spanned<String>>,
    /// `ply-sequence`: `"binary"` (default) or `"ascii"`.
    pub format: Option<PlyFormat>,
}

/// Default `ply-sequence` file name pattern; `{name}` is the dataset name.
pub const DEFAULT_PATTERN: &str = "{name}_{frame:04}.ply";

impl Output {
    /// The output's directory name under `[dataset] out`: `dir`, else `<dataset>_<writer suffix>`.
    pub fn dir_name(&self, dataset: &str) -> String {
        if let Some(d) = &self.dir {
            return d.get_ref().clone();
        }
        let suffix = match *self.writer.get_ref() {
            Writer::Dnerf => "dnerf",
            Writer::Nerfstudio => "nerfstudio",
            Writer::InstantNgp => "ngp",
            Writer::Colmap => "colmap",
            Writer::Dynerf => "dynerf",
            Writer::StaticFrames => "static",
            Writer::PlySequence => "points",
        };
        format!("{dataset}_{suffix}")
    }

    /// A `ply-sequence` output's file name pattern with `{name}` substituted (`{frame}` left for each frame).
    pub fn file_pattern(&self, dataset: &str) -> String {
        let pattern = self.pattern.as_ref().map_or(DEFAULT_PATTERN, |p| p.get_ref().as_str());
        pattern.replace("{name}", dataset)
    }
}

/// Dataset writers.
#[derive(Debug, Clone, Copy, Deserialize, PartialEq, Eq, Hash, PartialOrd, Ord, schemars::JsonSchema)]
#[serde(rename_all = "kebab-case")]
pub enum Writer {
    /// D-NeRF / NeRF-synthetic transforms_{train,val,test}.json (+ points3d.ply, fused.ply).
    Dnerf,
    /// nerfstudio transforms.json.
    Nerfstudio,
    /// instant-ngp transforms per split.
    InstantNgp,
    /// COLMAP text model (PINHOLE).
    Colmap,
    /// DyNeRF / LLFF poses_bounds.npy with per-camera frame folders.
    Dynerf,
    /// One NeRF-synthetic dataset per time step.
    StaticFrames,
    /// Point-cloud sequence sampled from the posed scene.
    PlySequence,
}

impl Writer {
    /// Manifest spelling.
    pub fn name(self) -> &'static str {
        match self {
            Writer::Dnerf => "dnerf",
            Writer::Nerfstudio => "nerfstudio",
            Writer::InstantNgp => "instant-ngp",
            Writer::Colmap => "colmap",
            Writer::Dynerf => "dynerf",
            Writer::StaticFrames => "static-frames",
            Writer::PlySequence => "ply-sequence",
        }
    }

    /// Whether the writer needs rendered images.
    pub fn renders_images(self) -> bool {
        self != Writer::PlySequence
    }

    /// Keys this writer accepts besides `writer`.
    pub fn allowed_keys(self) -> &'static [&'static str] {
        match self {
            Writer::PlySequence => &[
                "dir",
                "source",
                "points",
                "voxel",
                "vox",
                "correspondence",
                "motion",
                "reduce",
                "position",
                "color_average",
                "color",
                "pattern",
                "format",
            ],
            Writer::InstantNgp => &["dir", "splits", "init_points", "aabb_scale"],
            _ => &["dir", "splits", "init_points"],
        }
    }
}

/// What a `ply-sequence`'s point colours are.
#[derive(Debug, Clone, Copy, Deserialize, PartialEq, Eq, Hash, Default, schemars::JsonSchema)]
#[serde(rename_all = "lowercase")]
pub enum PointColor {
    /// The surface's albedo (base colour × texture × vertex colour), unlit.
    #[default]
    Albedo,
    /// The albedo lit, view-independently: diffuse light from every light and the environment, with shadows and
    /// the environment's occlusion, plus emission (the 6-DoF toolkit's "baked" colours).
    Lit,
}

/// Voxel reduction.
#[derive(Debug, Clone, Copy, Deserialize, PartialEq, Eq, Hash, Default, schemars::JsonSchema)]
#[serde(rename_all = "lowercase")]
pub enum Reduce {
    /// Mean position and colour.
    #[default]
    Mean,
    /// The point nearest the voxel centre.
    Nearest,
    /// The first point (in sample order).
    First,
}

/// Where a voxel's representative point is placed.
#[derive(Debug, Clone, Copy, Deserialize, PartialEq, Eq, Hash, Default, schemars::JsonSchema)]
#[serde(rename_all = "lowercase")]
pub enum VoxelPosition {
    /// The reduction's own position: the mean, or the chosen point's.
    #[default]
    Points,
    /// The voxel centre.
    Center,
}

/// Colour averaging space.
#[derive(Debug, Clone, Copy, Deserialize, PartialEq, Eq, Hash, Default, schemars::JsonSchema)]
#[serde(rename_all = "lowercase")]
pub enum ColorAverage {
    /// Average in linear light.
    #[default]
    Linear,
    /// Average the stored sRGB values (what Open3D does).
    Srgb,
}

/// PLY encoding.
#[derive(Debug, Clone, Copy, Deserialize, PartialEq, Eq, Hash, Default, schemars::JsonSchema)]
#[serde(rename_all = "lowercase")]
pub enum PlyFormat {
    /// binary_little_endian.
    #[default]
    Binary,
    /// ascii.
    Ascii,
}

impl Output {
    pub(crate) fn validate(&self, name: &str, present: &[(&str, Range<usize>)], diags: &mut Vec<Diagnostic>) {
        let w = *self.writer.get_ref();
        let owner = format!("output `{name}` (writer = \"{}\")", w.name());
        inapplicable_keys(present, "writer", w.allowed_keys(), &owner, diags);
        if let Some(d) = &self.dir {
            check_relative(d, "dir", diags);
        }
        if let Some(p) = &self.pattern {
            check_relative(p, "pattern", diags);
            if !p.get_ref().contains("{frame") {
                diags.push(
                    Diagnostic::error(
                        "`pattern` has no `{frame}`: every frame would overwrite the last",
                        Some(p.span()),
                    )
                    .with_help("e.g. pattern = \"{name}_vox10_{frame:04}.ply\""),
                );
            }
        }
        if let Some(p) = &self.points {
            let n = *p.get_ref();
            if n == 0 || n > MAX_POINTS {
                diags.push(Diagnostic::error(format!("points = {n} is outside 1..={MAX_POINTS}"), Some(p.span())));
            }
        }
        if let Some(p) = &self.init_points {
            if *p.get_ref() > MAX_POINTS {
                diags.push(Diagnostic::error(
                    format!("init_points = {} is more than {MAX_POINTS}", p.get_ref()),
                    Some(p.span()),
                ));
            }
        }
        if let Some(v) = &self.voxel {
            if !(v.get_ref().is_finite() && *v.get_ref() > 0.0) {
                diags.push(Diagnostic::error(format!("voxel = {} must be positive", v.get_ref()), Some(v.span())));
            }
        }
        if let Some(v) = &self.vox {
            if !(8..=16).contains(v.get_ref()) {
                diags.push(
                    Diagnostic::error(format!("vox = {} is outside 8..=16", v.get_ref()), Some(v.span()))
                        .with_help("8i's sequences use vox = 10"),
                );
            }
        }
        if let Some(spanned) = &self.aabb_scale {
            let a = *spanned.get_ref();
            if !a.is_power_of_two() || a > 128 {
                diags.push(Diagnostic::error(
                    format!("aabb_scale = {a} must be a power of two in 1..=128"),
                    Some(spanned.span()),
                ));
            }
        }
        if w == Writer::PlySequence && self.points.is_none() {
            diags.push(
                Diagnostic::error(format!("output `{name}` (ply-sequence) needs `points`"), Some(self.writer.span()))
                    .with_help("e.g. points = 1000000"),
            );
        }
    }
}

/// A path inside the output root: relative, and no `..` that climbs out.
pub(crate) fn check_relative(p: &Spanned<String>, key: &str, diags: &mut Vec<Diagnostic>) {
    let s = p.get_ref();
    let path = std::path::Path::new(s);
    let mut depth: i64 = 0;
    let mut escapes = path.is_absolute() || s.starts_with('/') || s.starts_with('\\');
    for c in path.components() {
        match c {
            std::path::Component::ParentDir => depth -= 1,
            std::path::Component::Normal(_) => depth += 1,
            std::path::Component::Prefix(_) | std::path::Component::RootDir => escapes = true,
            std::path::Component::CurDir => {}
        }
        if depth < 0 {
            escapes = true;
        }
    }
    if escapes {
        diags.push(
            Diagnostic::error(format!("`{key}` = \"{s}\" escapes the dataset's `out` directory"), Some(p.span()))
                .with_help("use a relative path without leading `..`; move `[dataset] out` to write elsewhere"),
        );
    }
}

/// Plain values of the fields whose spans stay inside `manifest` (for diagnostics).
impl Output {
    /// The writer.
    pub fn writer(&self) -> Writer {
        *self.writer.get_ref()
    }

    /// Directory under `[dataset] out`, when given.
    pub fn dir(&self) -> Option<&str> {
        self.dir.as_ref().map(|d| d.get_ref().as_str())
    }

    /// The splits to write, when given (default: all).
    pub fn splits(&self) -> Option<Vec<&str>> {
        self.splits.as_ref().map(|v| v.iter().map(|s| s.get_ref().as_str()).collect())
    }

    /// The one source to sample, when given (default: all).
    pub fn source(&self) -> Option<&str> {
        self.source.as_ref().map(|s| s.get_ref().as_str())
    }

    /// Points in the initialization cloud, when given.
    pub fn init_points(&self) -> Option<u64> {
        self.init_points.as_ref().map(|p| *p.get_ref())
    }

    /// instant-ngp's `aabb_scale`, when given.
    pub fn aabb_scale(&self) -> Option<u32> {
        self.aabb_scale.as_ref().map(|a| *a.get_ref())
    }

    /// Surface samples per frame, when given.
    pub fn points(&self) -> Option<u64> {
        self.points.as_ref().map(|p| *p.get_ref())
    }

    /// Voxel edge for downsampling, when given.
    pub fn voxel(&self) -> Option<f64> {
        self.voxel.as_ref().map(|v| *v.get_ref())
    }

    /// The `2^vox` grid, when given.
    pub fn vox(&self) -> Option<u32> {
        self.vox.as_ref().map(|v| *v.get_ref())
    }

    /// The file name pattern, when given.
    pub fn pattern(&self) -> Option<&str> {
        self.pattern.as_ref().map(|p| p.get_ref().as_str())
    }
}
