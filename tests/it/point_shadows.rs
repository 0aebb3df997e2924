//! Points cast shadows in lit builds: a point cloud, or a file of 3D Gaussians, over a lit ground darkens it
//! where the sun cannot reach past it, as the triangles it samples would (they floated over an evenly lit
//! ground before), and the frames that hold points are keyed apart.

use std::path::Path;

use crate::common::{load, tree};

/// A square sheet 0.6 m wide at height 0.5, sampled every centimetre: as plain points (`x y z`, a normal up and a
/// colour) or
/// as flat round Gaussians (3D Gaussian splatting's layout: log scales, an opacity logit, a unit quaternion).
fn sheet_ply(gaussians: bool) -> String {
    let n = 61;
    let props = if gaussians {
        "property float f_dc_0\nproperty float f_dc_1\nproperty float f_dc_2\nproperty float opacity\n\
         property float scale_0\nproperty float scale_1\nproperty float scale_2\n\
         property float rot_0\nproperty float rot_1\nproperty float rot_2\nproperty float rot_3\n"
    } else {
        "property float nx\nproperty float ny\nproperty float nz\nproperty uchar red\nproperty uchar green\nproperty uchar blue\n"
    };
    let mut out = format!("ply\nformat ascii 1.0\nelement vertex {}\nproperty float x\nproperty float y\nproperty float z\n{props}end_header\n", n * n);
    for j in 0..n {
        for i in 0..n {
            let (x, y) = (-0.3 + i as f32 * 0.01, -0.3 + j as f32 * 0.01);
            if gaussians {
                // σ = 1 cm across, a hundredth of it through; opacity logit 4.6 (0.99).
                let (across, through) = (0.01f32.ln(), 0.0001f32.ln());
                out.push_str(&format!("{x} {y} 0.5 0.5 0.1 0.1 4.6 {across} {across} {through} 1 0 0 0\n"));
            } else {
                out.push_str(&format!("{x} {y} 0.5 0 0 1 200 40 40\n"));
            }
        }
    }
    out
}

/// A lit build of `sheet.ply` over a 3 m ground under a sun 45° from overhead along +x, seen from straight
/// above; the sun's `shadows` as given.
fn manifest(shadows: bool) -> String {
    format!(
        "[dataset]\nname = \"s\"\nout = \"out\"\ncache = \"cache\"\npreview = false\n\
         [source.sheet]\nmesh = \"sheet.ply\"\n\
         [source.ground]\nplane = {{ size = [3, 3], color = [0.5, 0.5, 0.5], z = 0 }}\n\
         [render]\nresolution = [64, 64]\nsamples = 1\nshading = \"pbr\"\ncamera_angle_x = 1.2\n\
         [environment]\nstrength = 0.3\n\
         [light.sun]\nkind = \"sun\"\ndirection = [1, 0, -1]\nintensity = 3\nangle_deg = 1\nshadows = {shadows}\n\
         [rig.top]\nkind = \"explicit\"\nposes = [{{ c2w = [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 3], [0, 0, 0, 1]] }}]\n\
         [split.train]\nrig = \"top\"\n[output.d]\nwriter = \"dnerf\"\n"
    )
}

fn build(dir: &Path, text: &str) -> (vvgen::build::Report, Vec<u8>) {
    std::fs::write(dir.join("m.toml"), text).unwrap();
    let report =
        vvgen::build::build(&load(&dir.join("m.toml")), &dir.join("cache"), Default::default(), &vvgen::build::Silent)
            .unwrap();
    let files = tree(&dir.join("out"));
    let png = files.get("s_dnerf/train/r_0000.png").expect("the image");
    (report, image::load_from_memory(png).unwrap().into_rgba8().into_raw())
}

/// The pixel the camera (3 m over the origin, 64² with a horizontal field of 1.2 rad) shows ground point (x, y).
fn pixel(x: f32, y: f32) -> usize {
    let f = 32.0 / 0.6f32.tan();
    let (px, py) = ((32.0 + f * x / 3.0) as usize, (32.0 - f * y / 3.0) as usize);
    (py * 64 + px) * 4
}

#[test]
fn a_point_cloud_and_gaussians_shadow_the_ground_where_the_sun_cannot_reach_past_them() {
    for gaussians in [false, true] {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        std::fs::write(d.join("sheet.ply"), sheet_ply(gaussians)).unwrap();
        let (_, lit) = build(d, &manifest(false));
        let (_, shadowed) = build(d, &manifest(true));
        // The sun along (1, 0, −1) moves the sheet's shadow 0.5 m along +x: x in 0.2..0.8, y in −0.3..0.3. Seen
        // from above, the ground from x = 0.45 out to 0.8 is the shadow (the sheet, nearer the camera, hides the
        // ground out to x = 0.36, and the Gaussians' tails a little farther).
        let what = if gaussians { "Gaussians" } else { "points" };
        for (x, y) in [(0.5, 0.0), (0.7, 0.2), (0.55, -0.2)] {
            let (open, under) = (lit[pixel(x, y)], shadowed[pixel(x, y)]);
            assert!(under + 60 < open, "{what}: the ground at ({x}, {y}) is {under} in the shadow, {open} without it");
        }
        // Out of the shadow the ground is as lit with the sun's shadows as without (past the sheet's contact:
        // its occlusion of the sky reaches a little way).
        for (x, y) in [(1.2, 0.0), (0.5, 0.9), (-1.0, -1.0)] {
            let (open, out) = (lit[pixel(x, y)], shadowed[pixel(x, y)]);
            assert!(open.abs_diff(out) <= 2, "{what}: the ground at ({x}, {y}) is {out}, {open} without shadows");
        }
    }
}

#[test]
fn the_light_of_frames_with_points_is_keyed_by_the_splats_that_cast() {
    use vvgen::plan::actions::Kind;
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(d.join("sheet.ply"), sheet_ply(false)).unwrap();
    let text = manifest(true);
    let (first, _) = build(d, &text);
    assert_eq!(first.ran(Kind::Light), 1);
    assert_eq!(build(d, &text).0.ran(Kind::Light), 0, "nothing changed");
    // Wider splats cast a wider shadow: the frame's light runs again, and the lit pass with it.
    let wider = text.replace("camera_angle_x = 1.2", "camera_angle_x = 1.2\nsplat = { size = 0.1 }");
    let (again, image) = build(d, &wider);
    assert_eq!((again.ran(Kind::Light), again.ran(Kind::RenderPass)), (1, 1));
    // The shadow reaches about 10 cm farther past its far edge (x = 0.8): the pixel 6.5 cm past it is shaded now.
    let (_, narrow) = build(d, &text);
    let at = pixel(0.865, 0.0);
    assert!(image[at] + 30 < narrow[at], "{} vs {}", image[at], narrow[at]);
}

#[test]
fn a_points_lit_colour_is_not_shadowed_by_its_neighbours() {
    // The sheet's points face the sun with nothing above them: their baked colours are the same with the sun's
    // shadows as without. (Drawn into the maps at their centres' depths, a point's neighbours stood in front of
    // it on a curved or tilted cloud and darkened the sunlit side of a ball by 40 %.)
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    std::fs::write(d.join("sheet.ply"), sheet_ply(false)).unwrap();
    let outputs = "[output.baked]\nwriter = \"ply-sequence\"\ndir = \"baked\"\npoints = 3721\ncolor = \"lit\"\n\
                   source = \"sheet\"\n";
    let colours = |shadows: bool| {
        let text = manifest(shadows).replace("[output.d]", &format!("{outputs}[output.d]"));
        build(d, &text);
        let cloud = vvgen::scene::ply::read_file(&d.join("out/baked/s_0000.ply")).unwrap();
        assert_eq!(cloud.positions.len(), 3721);
        cloud.colors.expect("lit colours")
    };
    let (lit, shadowed) = (colours(false), colours(true));
    assert_eq!(lit, shadowed);
}
