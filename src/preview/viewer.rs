//! The HTML viewer (`preview/index.html`): the dataset's cameras as frusta around the subject's surface samples
//! in three.js, a time slider, and a click on a camera showing its image. It is one HTML file with its data
//! inline and three.js beside it (`three.min.js`, vendored at 0.159.0, the last release with a classic-script
//! build: module scripts do not load from `file://`), so it opens from disk with no network.

use std::collections::BTreeMap;

use base64::Engine;
use glam::Vec3;
use serde_json::json;

use super::rig_plot::SPLIT_COLORS;
use crate::camera::Camera;

/// three.js 0.159.0, `build/three.min.js` from the npm package, unmodified (`vendor/three.LICENSE`: MIT).
pub const THREE_JS: &[u8] = include_bytes!("vendor/three-0.159.0.min.js");
const TEMPLATE: &str = include_str!("viewer.html");
/// The line of the page that says where the dataset's files are, relative to the page.
const ROOT_LINE: &str = "const ROOT = \"..\";";

/// One image of the dataset, for the viewer.
pub struct ViewerImage<'a> {
    /// Split name.
    pub split: &'a str,
    /// Split index (for its colour).
    pub split_index: usize,
    /// View within the split.
    pub view: u32,
    /// Scene frame.
    pub frame: usize,
    /// Normalized time.
    pub time: f64,
    /// The camera.
    pub camera: &'a Camera,
    /// The image file, dataset-root-relative.
    pub path: &'a str,
}

/// Points the viewer draws at one frame: the subject's samples (image datasets: one, at the middle frame), or a
/// frame of a point-cloud sequence.
pub struct Cloud<'a> {
    /// Scene frame.
    pub frame: usize,
    /// Normalized time.
    pub time: f64,
    /// World positions.
    pub positions: &'a [[f32; 3]],
    /// sRGB colours.
    pub colors: &'a [[u8; 3]],
}

/// The page for `images` (none for a point-cloud sequence) around `clouds` (the slider steps through the
/// images' frames, or the clouds' when there are no images) and `bounds`; `of_frames` is the sequence's frame
/// count when the clouds shown are some of its frames (the status line says "24 of 103 frames").
pub fn html(
    title: &str,
    load: &str,
    images: &[ViewerImage],
    clouds: &[Cloud],
    bounds: Option<(Vec3, Vec3)>,
    of_frames: Option<usize>,
) -> String {
    // Cameras: one per (split, view), with the images it took.
    let mut cameras: BTreeMap<(usize, u32), (serde_json::Value, Vec<serde_json::Value>)> = BTreeMap::new();
    let mut splits: BTreeMap<usize, (&str, usize)> = BTreeMap::new();
    let mut frames: BTreeMap<usize, f64> = BTreeMap::new();
    for im in images {
        let c = im.camera;
        let e = cameras.entry((im.split_index, im.view)).or_insert_with(|| {
            splits.entry(im.split_index).or_insert((im.split, 0)).1 += 1;
            let rows = c.c2w.transpose().to_cols_array_2d();
            (
                json!({"w": c.width, "h": c.height, "fx": c.fx, "fy": c.fy, "cx": c.cx, "cy": c.cy, "c2w": rows}),
                Vec::new(),
            )
        });
        e.1.push(json!([im.frame, im.path]));
        frames.insert(im.frame, im.time);
    }
    if images.is_empty() {
        frames.extend(clouds.iter().map(|c| (c.frame, c.time)));
    }
    let split_ids: Vec<usize> = splits.keys().copied().collect();
    let cams: Vec<serde_json::Value> = cameras
        .into_iter()
        .map(|((s, view), (mut v, imgs))| {
            v["split"] = json!(split_ids.iter().position(|&x| x == s));
            v["view"] = json!(view);
            v["images"] = json!(imgs);
            v
        })
        .collect();
    let split_list: Vec<serde_json::Value> = splits
        .iter()
        .map(|(&i, (name, n))| {
            let [r, g, b] = SPLIT_COLORS[i % SPLIT_COLORS.len()];
            json!({"name": name, "cameras": n, "color": format!("#{r:02x}{g:02x}{b:02x}")})
        })
        .collect();
    // The scene's centre and size, for the orbit: bounds when known, else the cameras.
    let mut lo = Vec3::splat(f32::INFINITY);
    let mut hi = Vec3::splat(f32::NEG_INFINITY);
    match bounds {
        Some((a, b)) => (lo, hi) = (a, b),
        None => {
            let cameras = images.iter().map(|im| im.camera.c2w.w_axis.truncate().as_vec3());
            let points = clouds.iter().flat_map(|c| c.positions.iter().map(|p| Vec3::from_array(*p)));
            for p in cameras.chain(points).filter(|p| p.is_finite()) {
                lo = lo.min(p);
                hi = hi.max(p);
            }
        }
    }
    let (centre, radius) =
        if lo.x <= hi.x { ((lo + hi) * 0.5, ((hi - lo).length() * 0.5).max(1e-3)) } else { (Vec3::ZERO, 1.0) };
    let mut everything = (lo.min(Vec3::ZERO), hi.max(Vec3::ZERO));
    for im in images {
        let p = im.camera.c2w.w_axis.truncate().as_vec3();
        everything = (everything.0.min(p), everything.1.max(p));
    }
    let extent = (everything.1 - everything.0).max_element().max(1e-3);
    let b64 = base64::engine::general_purpose::STANDARD;
    let data = json!({
        "cameras": cams,
        "splits": split_list,
        "images": images.len(),
        "frames": frames.keys().collect::<Vec<_>>(),
        "of_frames": of_frames,
        "time": frames.values().collect::<Vec<_>>(),
        "clouds": clouds.iter().map(|c| json!({
            "frame": c.frame,
            "positions": b64.encode(bytemuck::cast_slice::<[f32; 3], u8>(c.positions)),
            "colors": b64.encode(c.colors.iter().flatten().copied().collect::<Vec<u8>>()),
        })).collect::<Vec<_>>(),
        "bounds": bounds.map(|(a, b)| json!([a.to_array(), b.to_array()])),
        "centre": centre.to_array(),
        "radius": radius,
        "extent": extent,
    });
    // Inside a <script>, `</` would end it early: JSON allows `<\/` for the same string.
    let data = data.to_string().replace("</", "<\\/");
    TEMPLATE.replace("__TITLE__", &escape(title)).replace("__LOAD__", &escape(load)).replace("__DATA__", &data)
}

/// The page, with the dataset's files found at `root` (a path or URL) instead of beside the `preview/` folder.
pub fn relocate(html: &str, root: &str) -> String {
    html.replacen(
        ROOT_LINE,
        &format!("const ROOT = {};", serde_json::Value::String(root.into()).to_string().replace("</", "<\\/")),
        1,
    )
}

/// `s` as HTML text.
fn escape(s: &str) -> String {
    s.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;").replace('"', "&quot;")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_page_carries_its_data_and_can_move() {
        let c = Camera {
            width: 4,
            height: 3,
            fx: 4.0,
            fy: 4.0,
            cx: 2.0,
            cy: 1.5,
            near: 0.1,
            far: 10.0,
            c2w: Camera::look_at(Vec3::new(0.0, -3.0, 1.0), Vec3::ZERO, Vec3::Z),
        };
        let images = [
            ViewerImage {
                split: "train",
                split_index: 0,
                view: 0,
                frame: 0,
                time: 0.0,
                camera: &c,
                path: "train/r_0.png",
            },
            ViewerImage {
                split: "train",
                split_index: 0,
                view: 0,
                frame: 1,
                time: 1.0,
                camera: &c,
                path: "train/r_1.png",
            },
            ViewerImage {
                split: "te</script>",
                split_index: 1,
                view: 0,
                frame: 1,
                time: 1.0,
                camera: &c,
                path: "test/r_0.png",
            },
        ];
        let cloud = Cloud { frame: 1, time: 1.0, positions: &[[0.0, 0.0, 0.0]], colors: &[[255, 0, 0]] };
        let page = html("a & b", "load it", &images, &[cloud], None, None);
        assert!(page.contains("<title>vvgen · a &amp; b</title>"));
        assert_eq!(page.matches("</script>").count(), 3, "the data cannot close its script");
        assert!(page.contains(r#""frames":[0,1]"#) && page.contains(r#""images":3"#));
        assert!(page.contains(ROOT_LINE));
        let moved = relocate(&page, "/data/set");
        assert!(moved.contains(r#"const ROOT = "/data/set";"#) && !moved.contains(ROOT_LINE));
    }
}
