//! What each writer's consumers cannot read, decided before anything renders: per writer, about that writer's
//! own consumers only (../shared/specs/consumer-formats.md §10 lists what was seen in their loaders' code).
//!
//! `diagnose` needs the manifest alone and runs inside [`super::parse`], so `vvgen check` and `build` raise
//! the same errors and warnings. [`frame_diagnostic`] needs the number of frames an output shows (the frames its
//! splits select of the scene's), which `check` and `build` both take from the plan.

use super::diag::Diagnostic;
use super::output::{Output, Writer};
use super::render::{DepthKind, Pass};
use super::Manifest;

/// The loaders that take one focal length from `camera_angle_x` for both axes and assume a centred principal
/// point: what reads a NeRF-synthetic transforms file.
const DNERF_ONE_FOCAL: &str =
    "D-NeRF (load_blender.py), 3DGS, 4DGaussians and Deformable-3DGS (Blender path) and nerfstudio's blender-data / dnerf-data";
const STATIC_ONE_FOCAL: &str = "NeRF's load_blender.py, 3DGS (Blender path) and nerfstudio's blender-data";
const DYNERF_LOADERS: &str = "K-Planes (Video360Dataset), 4DGaussians (Neural3D) and Deformable-3DGS (plenoptic)";

/// The splits output `out` writes: its `splits`, or every split of the manifest.
pub(crate) fn selected_splits<'a>(m: &'a Manifest, out: &'a Output) -> Vec<&'a str> {
    match &out.splits {
        Some(s) => s.iter().map(|s| s.get_ref().as_str()).collect(),
        None => m.splits.keys().map(String::as_str).collect(),
    }
}

/// Every consumer problem of every output that the manifest alone decides.
pub(crate) fn diagnose(m: &Manifest, diags: &mut Vec<Diagnostic>) {
    for (name, out) in &m.outputs {
        let mut d = Writing { m, name, out, diags };
        match *out.writer.get_ref() {
            Writer::Dnerf => d.dnerf(),
            Writer::StaticFrames => d.static_frames(),
            Writer::Nerfstudio => d.nerfstudio(),
            Writer::InstantNgp => d.instant_ngp(),
            Writer::Colmap => d.colmap(),
            Writer::Dynerf => d.dynerf(),
            Writer::PlySequence => {}
        }
    }
}

/// The consumer problem of output `name` that depends on the number of frames it shows (its splits' frames,
/// [`crate::plan::Plan::output_frames`]), if any.
pub fn frame_diagnostic(name: &str, out: &Output, frames: usize) -> Option<Diagnostic> {
    let at = Some(out.writer.span());
    match *out.writer.get_ref() {
        // No count suits both 4DGaussians (300) and Deformable-3DGS (24).
        Writer::Dynerf => {
            let mut said = Vec::new();
            if frames != 300 {
                said.push(
                    "4DGaussians maps frame i to time i/300 and K-Planes to i/299 (both read at most 300 frames)",
                );
            }
            if frames != 24 {
                said.push("Deformable-3DGS reads the first 24 frames and maps frame i to i/23");
            }
            let mut help = format!("{}: their times will be off", said.join("; "));
            // What the user sees first: run on our sets, K-Planes' `dynerf_ist_weight` stops with a size mismatch
            // below 25 frames (issue 46).
            if frames < 25 {
                help = format!("K-Planes crashes on fewer than 25 frames (dynerf_ist_weight: a size mismatch); {help}");
            }
            Some(Diagnostic::warning(format!("output `{name}` (dynerf) has {frames} frames"), at).with_help(help))
        }
        Writer::InstantNgp if frames > 1 => {
            Some(Diagnostic::warning(format!("output `{name}` (instant-ngp) has {frames} frames"), at).with_help(
                "instant-ngp has no time: each transforms file mixes every frame of the motion (use \
                 `static-frames` for one static set per time step)",
            ))
        }
        _ => None,
    }
}

/// The checks of one output.
struct Writing<'a, 'd> {
    m: &'a Manifest,
    name: &'a str,
    out: &'a Output,
    diags: &'d mut Vec<Diagnostic>,
}

impl Writing<'_, '_> {
    /// A warning at the output's `writer`: "output `NAME` (WRITER)" followed by `what` (` with …`, `: …`).
    fn warn(&mut self, what: impl AsRef<str>, help: impl Into<String>) {
        let d = Diagnostic::warning(self.message(what.as_ref()), Some(self.out.writer.span())).with_help(help);
        self.diags.push(d);
    }

    /// An error, worded as [`Writing::warn`].
    fn error(&mut self, what: impl AsRef<str>, help: impl Into<String>) {
        let d = Diagnostic::error(self.message(what.as_ref()), Some(self.out.writer.span())).with_help(help);
        self.diags.push(d);
    }

    fn message(&self, what: &str) -> String {
        let sep = if what.starts_with(':') { "" } else { " " };
        format!("output `{}` ({}){sep}{what}", self.name, self.out.writer.get_ref().name())
    }

    /// The dataset root as the consumers see it (absolute when the manifest's folder is).
    fn root(&self) -> String {
        let dir = self.out.dir_name(self.m.dataset.name.get_ref());
        self.m.out_dir().join(dir).to_string_lossy().into_owned()
    }

    /// fx ≠ fy and an off-centre principal point, for writers whose consumers read one focal length (`focal`
    /// names them and the key they read, when that applies) or assume the image centre (`centre` names them, and
    /// `fix` says what to do): each said with the pixels the reader will be off by.
    fn focal_and_centre(&mut self, focal: Option<&str>, centre: &str, fix: &str) {
        let (fx, fy, cx, cy) = self.m.render.intrinsics();
        let (w, h) = self.m.render.size();
        if let Some(loaders) = focal.filter(|_| (fx - fy).abs() > 1e-9 * fx.abs().max(1.0)) {
            // A point v px from the principal point vertically projects to v·fx/fy: worst at the farther edge.
            let off = cy.max(h as f64 - cy) * (fx - fy).abs() / fy;
            self.warn(
                format!("with fx = {fx} ≠ fy = {fy} (non-square pixels)"),
                format!("{loaders}: points land up to {off:.1} px off at the top or bottom edge; set `fy` equal to fx"),
            );
        }
        let (dx, dy) = (w as f64 / 2.0 - cx, h as f64 / 2.0 - cy);
        if dx.abs() > 1e-9 || dy.abs() > 1e-9 {
            self.warn(
                format!("with an off-centre principal point ({cx}, {cy}) in a {w}×{h} image"),
                format!("{centre}: every point lands ({dx:+.1}, {dy:+.1}) px from where it is; {fix}"),
            );
        }
    }

    /// [`Writing::focal_and_centre`] for the loaders of a NeRF-synthetic transforms file.
    fn one_focal_and_centre(&mut self, loaders: &str) {
        self.focal_and_centre(
            Some(&format!("{loaders} take one focal length for both axes (from camera_angle_x) and ignore fl_y")),
            &format!("{loaders} project about the image centre and ignore cx, cy"),
            "leave `cx`, `cy` unset",
        );
    }

    fn dnerf(&mut self) {
        let (w, h) = self.m.render.size();
        if w != h {
            let (w, h) = (w as f64, h as f64);
            // Deformable-3DGS: FovX ↔ FovY scales x by W/H and y by H/W about the centre (worst at a corner);
            // 4DGaussians: the 800×800 image keeps FovX for both axes, so y is scaled by H/W (docs/consumers.md).
            let deformable = (w / 2.0 * (w / h - 1.0)).hypot(h / 2.0 * (h / w - 1.0));
            let gaussians = h / 2.0 * (w - h).abs() / w;
            self.warn(
                format!("with non-square {w}×{h} images"),
                format!(
                    "K-Planes resizes each {w}×{h} image to {h}×{w} (its rays take that shape: the images are \
                     stretched); Deformable-3DGS swaps FovX and FovY: points land up to {deformable:.1} px off at the \
                     corners; 4DGaussians resizes to 800×800 and takes FovY = FovX: up to {gaussians:.1} px off (of \
                     these images) at the top and bottom; D-NeRF's half_res (its configs' default) stops with a \
                     ValueError (cv2.resize to (H, W)): use square images"
                ),
            );
        }
        self.one_focal_and_centre(DNERF_ONE_FOCAL);
        let selected = selected_splits(self.m, self.out);
        for split in selected.iter().filter(|s| s.contains("_r")) {
            self.error(
                format!("writes split `{split}`, whose name contains `_r`"),
                "K-Planes splits D-NeRF file paths at `_r` (fetch_360vid_info): rename the split",
            );
        }
        for needed in ["train", "val", "test"] {
            if !selected.contains(&needed) {
                self.warn(
                    format!("has no `{needed}` split"),
                    "D-NeRF opens transforms_train/val/test.json unconditionally and nerfstudio's dnerf-data needs \
                     val while training",
                );
            }
        }
        let root = self.root();
        let dir = self.out.dir_name(self.m.dataset.name.get_ref());
        if !dir.contains("dnerf") && !dir.contains("lego") {
            self.warn(
                format!(": directory `{dir}` does not contain \"dnerf\""),
                format!("K-Planes picks its D-NeRF loader by that substring in the path ({root})"),
            );
        }
    }

    fn static_frames(&mut self) {
        let (w, h) = self.m.render.size();
        if w != h {
            self.warn(
                format!("with non-square {w}×{h} images"),
                "NeRF's load_blender.py (bmild/nerf) with half_res resizes every image to 400×400 while its rays \
                 keep H/2 × W/2: it trains on the wrong pixels",
            );
        }
        self.one_focal_and_centre(STATIC_ONE_FOCAL);
    }

    fn nerfstudio(&mut self) {
        // nerfstudio-data reads fl_x, fl_y, cx, cy, w, h exactly: no intrinsics caveat.
        if self.m.render.has_pass(Pass::Depth) && self.m.render.depth.kind == DepthKind::Ray {
            self.warn(
                "writes ray-distance depth",
                "nerfstudio's depth-nerfacto reads planar z-depth unless run with \
                 `--pipeline.model.is-euclidean-depth True`; transforms.json has no key to say so (vvgen/dataset.json \
                 records the kind): pass that flag, or use depth = { kind = \"planar\" }",
            );
        }
        let selected = selected_splits(self.m, self.out);
        if !selected.iter().any(|s| *s == "val" || *s == "test") {
            self.warn("has no `val` or `test` split", "nerfstudio's eval lists will be empty");
        }
    }

    fn instant_ngp(&mut self) {
        if self.m.render.has_pass(Pass::Depth) && self.m.render.depth.kind == DepthKind::Ray {
            self.error(
                "with ray-distance depth",
                "instant-ngp supervises with planar z-depth (target = |ray.d| · depth, camera z = 1) and its \
                 format has no key for another kind: use depth = { kind = \"planar\" }, or a separate output for \
                 the ray depth",
            );
        }
    }

    fn colmap(&mut self) {
        // fx ≠ fy is fine: 3DGS turns fx and fy into two FoVs; nerfstudio's colmap parser reads all four.
        self.focal_and_centre(
            None,
            "3DGS's COLMAP reader (and 4DGaussians' and Deformable-3DGS' copies) use only the focal lengths and \
             project about the image centre",
            "nerfstudio's colmap parser reads cx, cy: leave `cx`, `cy` unset for 3DGS",
        );
    }

    fn dynerf(&mut self) {
        self.focal_and_centre(
            Some(&format!("poses_bounds.npy holds one focal length (fx): {DYNERF_LOADERS} use it for both axes")),
            &format!("poses_bounds.npy has no principal point: {DYNERF_LOADERS} assume the image centre"),
            "leave `cx`, `cy` unset",
        );
        let (w, h) = self.m.render.size();
        if (w, h) != (2704, 2028) {
            // It resizes every frame to 1352×1014 and takes focal / 2 (the file's focal over 2704 / 1352): a point
            // u px from the centre of those frames projects to u·W/2704 across and v·H/2028 down (worst at a corner).
            let off = (676.0 * (1.0 - w as f64 / 2704.0)).hypot(507.0 * (1.0 - h as f64 / 2028.0));
            self.warn(
                format!("with {w}×{h} images"),
                format!(
                    "4DGaussians hard-codes DyNeRF's 2704×2028 (every frame resized to 1352×1014, the focal halved): \
                     at {w}×{h} its cameras are off by up to {off:.0} px of those frames at the corners; K-Planes and \
                     Deformable-3DGS read any size"
                ),
            );
        }
        if w % 2 == 1 || h % 2 == 1 {
            self.warn(
                format!("with odd-sized {w}×{h} images"),
                format!(
                    "H.264 4:2:0 has only even sizes: camNN.mp4 is {}×{} (the last column or row repeated); the PNG \
                     frames keep {w}×{h}",
                    w.next_multiple_of(2),
                    h.next_multiple_of(2)
                ),
            );
        }
        let root = self.root();
        if root.contains("dnerf") || root.contains("lego") {
            self.warn(
                format!(": the path {root} contains `dnerf` or `lego`"),
                "K-Planes reads a path containing `dnerf` or `lego` as D-NeRF data: choose another `dir`",
            );
        }
        if root.contains('.') {
            self.warn(
                format!(": the path {root} contains a `.`"),
                "4DGaussians takes everything before the first `.` of a video's path as its frame folder: keep dots \
                 out of the path it is given",
            );
        }
    }
}
