//! DyNeRF's videos: `camNN.mp4` beside the PNG frames, decoded the way its consumers decode them (the MP4
//! demuxed and the H.264 decoded by OpenH264 here, and by ffmpeg, which K-Planes' PyAV wraps, where installed),
//! compared with the PNG frames they were encoded from; the frame folders and init clouds each loader looks for.

use std::path::{Path, PathBuf};
use std::process::Command;

use openh264::decoder::Decoder;
use openh264::formats::YUVSource;

use crate::common::cesium_head;

/// A CesiumMan DyNeRF dataset: forward-facing, 3 train cameras and 1 test camera over 6 frames, 4:3, opaque.
fn built(dir: &Path) -> PathBuf {
    let text = format!(
        "{}\n[render]\nresolution = [320, 240]\nsamples = 4\nbackground = [0.9, 0.9, 0.9]\n\
         [rig.ff]\nkind = \"forward-facing\"\n\
         [split.train]\nrig = \"ff\"\nviews = 3\n[split.test]\nrig = \"ff\"\nviews = 1\n\
         [output.llff]\nwriter = \"dynerf\"\ninit_points = 300\n",
        // Every second frame of a 48 fps timeline: six frames 1/24 s apart, so 24 fps videos.
        cesium_head(6, 24, 2.4, "", "")
            .replace("frames = { count = 6, fps = 24 }", "frames = { start = 0, end = 10, step = 2, fps = 48 }")
    );
    std::fs::write(dir.join("m.toml"), text).unwrap();
    let m = crate::common::load(&dir.join("m.toml"));
    vvgen::build::build(&m, &dir.join("cache"), Default::default(), &vvgen::build::Silent).unwrap();
    dir.join("out/m_dynerf")
}

/// The frames of an MP4's video track as packed RGB (BT.601 limited range, chroma repeated per 2×2 block),
/// with the track's frame rate.
fn decode_mp4(path: &Path) -> (Vec<Vec<u8>>, (usize, usize), f64) {
    let bytes = std::fs::read(path).unwrap();
    let size = bytes.len() as u64;
    let mut r = mp4::Mp4Reader::read_header(std::io::Cursor::new(bytes), size).unwrap();
    let track = r.tracks().values().find(|t| t.track_type().unwrap() == mp4::TrackType::Video).unwrap();
    let (id, count, fps) = (track.track_id(), track.sample_count(), track.frame_rate());
    let annex_b = |nal: &[u8]| [&[0u8, 0, 0, 1][..], nal].concat();
    let mut stream = annex_b(track.sequence_parameter_set().unwrap());
    stream.extend(annex_b(track.picture_parameter_set().unwrap()));
    let mut decoder = Decoder::new().unwrap();
    let mut frames = Vec::new();
    let mut dims = (0, 0);
    for s in 1..=count {
        let sample = r.read_sample(id, s).unwrap().unwrap();
        let mut data: &[u8] = &sample.bytes;
        while data.len() >= 4 {
            let n = u32::from_be_bytes(data[..4].try_into().unwrap()) as usize;
            stream.extend(annex_b(&data[4..4 + n]));
            data = &data[4 + n..];
        }
        if let Some(yuv) = decoder.decode(&stream).unwrap() {
            dims = yuv.dimensions();
            frames.push(to_rgb(&yuv));
        }
        stream.clear();
    }
    (frames, dims, fps)
}

fn to_rgb(yuv: &impl YUVSource) -> Vec<u8> {
    let ((w, h), (sy, su, sv)) = (yuv.dimensions(), yuv.strides());
    let mut out = Vec::with_capacity(w * h * 3);
    for y in 0..h {
        for x in 0..w {
            let l = 1.164_383 * (yuv.y()[y * sy + x] as f64 - 16.0);
            let u = yuv.u()[(y / 2) * su + x / 2] as f64 - 128.0;
            let v = yuv.v()[(y / 2) * sv + x / 2] as f64 - 128.0;
            let rgb = [l + 1.596_027 * v, l - 0.391_762 * u - 0.812_968 * v, l + 2.017_232 * u];
            out.extend(rgb.map(|c| c.round().clamp(0.0, 255.0) as u8));
        }
    }
    out
}

/// PSNR of RGB and of BT.601 luma between two packed RGB images.
fn psnr(a: &[u8], b: &[u8]) -> (f64, f64) {
    let luma = |p: &[u8]| 0.299 * p[0] as f64 + 0.587 * p[1] as f64 + 0.114 * p[2] as f64;
    let (mut rgb, mut y) = (0.0, 0.0);
    for (p, q) in a.chunks(3).zip(b.chunks(3)) {
        rgb += p.iter().zip(q).map(|(s, t)| (*s as f64 - *t as f64).powi(2)).sum::<f64>();
        y += (luma(p) - luma(q)).powi(2);
    }
    let n = (a.len() / 3) as f64;
    let db = |mse: f64| 10.0 * (255.0f64 * 255.0 / mse.max(1e-12)).log10();
    (db(rgb / (3.0 * n)), db(y / n))
}

fn png_rgb(p: &Path) -> Vec<u8> {
    image::open(p).unwrap().into_rgb8().into_raw()
}

#[test]
fn dynerf_videos_decode_to_the_png_frames() {
    let tmp = tempfile::tempdir().unwrap();
    let root = built(tmp.path());
    let mut cams: Vec<String> = std::fs::read_dir(&root)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with("cam") && n.ends_with(".mp4"))
        .collect();
    cams.sort();
    // As many videos as poses_bounds.npy rows (K-Planes and 4DGaussians assert it): 4 cameras.
    assert_eq!(cams, ["cam00.mp4", "cam01.mp4", "cam02.mp4", "cam03.mp4"]);
    let ffmpeg = Command::new("ffmpeg").arg("-version").output().is_ok_and(|o| o.status.success());
    if !ffmpeg {
        eprintln!("skipping the ffmpeg decode: ffmpeg is not installed (apt install ffmpeg; .ci/run installs it)");
    }
    let mut worst = (f64::INFINITY, f64::INFINITY);
    for (c, name) in cams.iter().enumerate() {
        let (frames, dims, fps) = decode_mp4(&root.join(name));
        assert_eq!(dims, (320, 240), "{name}");
        assert!((fps - 24.0).abs() < 1e-6, "{name}: {fps} fps");
        assert_eq!(frames.len(), 6, "{name}");
        for (i, f) in frames.iter().enumerate() {
            let png = root.join(format!("frames/cam{c:02}/{i:04}.png"));
            // 4DGaussians' folder holds the same frames.
            let images = root.join(format!("cam{c:02}/images/{i:04}.png"));
            assert_eq!(std::fs::read(&png).unwrap(), std::fs::read(&images).unwrap());
            let (rgb, luma) = psnr(f, &png_rgb(&png));
            worst = (worst.0.min(rgb), worst.1.min(luma));
        }
        if ffmpeg {
            let out = Command::new("ffmpeg")
                .args(["-v", "error", "-i"])
                .arg(root.join(name))
                .args(["-f", "rawvideo", "-pix_fmt", "rgb24", "-"])
                .output()
                .unwrap();
            assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
            let frame = 320 * 240 * 3;
            assert_eq!(out.stdout.len(), 6 * frame, "ffmpeg decodes 6 frames of 320×240");
            for (i, f) in out.stdout.chunks(frame).enumerate() {
                let (rgb, luma) = psnr(f, &png_rgb(&root.join(format!("frames/cam{c:02}/{i:04}.png"))));
                worst = (worst.0.min(rgb), worst.1.min(luma));
            }
            // The measure a user runs: ffmpeg's psnr filter, video against the PNG frames (compared in the
            // video's YUV 4:2:0, the codec's own loss).
            let out = Command::new("ffmpeg")
                .args(["-v", "info", "-i"])
                .arg(root.join(name))
                .args(["-framerate", "24", "-i"])
                .arg(root.join(format!("frames/cam{c:02}/%04d.png")))
                .args([
                    "-lavfi",
                    "[0:v]settb=1/24,setpts=N[a];[1:v]settb=1/24,setpts=N[b];[a][b]psnr",
                    "-f",
                    "null",
                    "-",
                ])
                .output()
                .unwrap();
            let log = String::from_utf8_lossy(&out.stderr);
            let min: f64 = log
                .split("min:")
                .nth(1)
                .and_then(|t| t.split_whitespace().next())
                .and_then(|v| v.parse().ok())
                .unwrap_or_else(|| panic!("no psnr in ffmpeg's log: {log}"));
            eprintln!("{name}: ffmpeg's psnr filter (YUV 4:2:0), worst frame {min:.2} dB");
            assert!(min >= 45.0, "{name}: ffmpeg's psnr filter, worst frame {min} dB");
        }
    }
    eprintln!("worst frame: RGB PSNR {:.2} dB, luma PSNR {:.2} dB", worst.0, worst.1);
    // Luma is near-lossless; RGB is bounded by 4:2:0's half-resolution colour (see execute::video).
    assert!(worst.1 >= 45.0, "luma PSNR {:.2} dB", worst.1);
    assert!(worst.0 >= 38.0, "RGB PSNR {:.2} dB", worst.0);
    // Deformable-3DGS' init cloud is the same cloud as 4DGaussians'.
    assert_eq!(
        std::fs::read(root.join("points3D.ply")).unwrap(),
        std::fs::read(root.join("points3D_downsample2.ply")).unwrap()
    );
}

/// Videos are actions: a second build encodes nothing, and the encoding is deterministic.
#[test]
fn videos_are_cached_and_deterministic() {
    let (a, b) = (tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap());
    let (ra, rb) = (built(a.path()), built(b.path()));
    assert_eq!(std::fs::read(ra.join("cam01.mp4")).unwrap(), std::fs::read(rb.join("cam01.mp4")).unwrap());
    let m = crate::common::load(&a.path().join("m.toml"));
    let r = vvgen::build::build(&m, &a.path().join("cache"), Default::default(), &vvgen::build::Silent).unwrap();
    assert!(r.nothing_to_do());
}

/// Sharded builds render a DyNeRF dataset's images between them and leave the videos (which read every frame of
/// a camera) to the final unsharded build, which then renders nothing; the result is the single-process one.
#[test]
fn shards_leave_the_videos_to_the_final_build() {
    use vvgen::build::{build as run, Options};
    use vvgen::execute::Shard;
    use vvgen::plan::actions::Kind;
    let (one, sharded) = (tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap());
    let single = built(one.path());
    // The same manifest, built in two shards and then once more.
    std::fs::copy(one.path().join("m.toml"), sharded.path().join("m.toml")).unwrap();
    let m = crate::common::load(&sharded.path().join("m.toml"));
    let cache = sharded.path().join("cache");
    let mut renders = 0;
    for index in 0..2 {
        let r = run(
            &m,
            &cache,
            Options { shard: Some(Shard { index, count: 2 }), ..Default::default() },
            &vvgen::build::Silent,
        )
        .unwrap();
        assert_eq!(r.ran(Kind::Video), 0, "shard {index} encoded a video");
        renders += r.ran(Kind::RenderPass);
    }
    assert_eq!(renders, 24, "4 cameras × 6 frames, each rendered once");
    let r = run(&m, &cache, Options::default(), &vvgen::build::Silent).unwrap();
    assert_eq!((r.ran(Kind::RenderPass), r.ran(Kind::Video)), (0, 4));
    let root = sharded.path().join("out/m_dynerf");
    for c in 0..4 {
        let name = format!("cam{c:02}.mp4");
        assert_eq!(std::fs::read(root.join(&name)).unwrap(), std::fs::read(single.join(&name)).unwrap(), "{name}");
    }
}
