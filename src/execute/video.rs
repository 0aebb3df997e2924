//! Video actions: one camera's composites as an H.264 MP4, what DyNeRF's loaders open (`camNN.mp4`: K-Planes
//! decodes it with PyAV, 4DGaussians asserts it exists).
//!
//! The codec is Cisco's OpenH264 (the `openh264` crate, built from its bundled source) and the container the
//! `mp4` crate's writer: nothing hand-written but the colour conversion and the Annex B → AVCC repacking. The
//! stream is what every H.264 decoder reads: constrained baseline, 4:2:0, BT.601 limited range (signalled in
//! the VUI, and the default a decoder assumes without it), every frame at the encoder's finest quantizer under
//! rate control (QP 12), one encoder thread so the bytes do not depend on scheduling.
//!
//! 4:2:0 is the limit: colour is kept at half resolution, so sharp colour edges (a textured subject's
//! silhouette against the background) lose what no quantizer gives back, the more the smaller the image. Chroma
//! is each 2×2 block's mean; luma is then chosen per pixel so that, with the block's chroma, the pixel decodes
//! nearest its RGB (least squares, the decoder's clipping included), which takes back 0.3–0.6 dB of RGB PSNR.
//! Measured per size by `benches/video_psnr.sh` (docs/benchmarks.md): 38.7 dB at 64², 44.6 dB at 676×508 on
//! CesiumMan, within 0.1–1.3 dB of what 4:2:0 alone allows. The PNG frames stay in the dataset (4DGaussians and
//! Deformable-3DGS read them); only K-Planes trains on the video.

use bytes::Bytes;
use mp4::{AvcConfig, FourCC, MediaConfig, Mp4Config, Mp4Sample, Mp4Writer, TrackConfig, TrackType};
use openh264::encoder::{
    BitRate, Encoder, EncoderConfig, FrameRate, IntraFramePeriod, QpRange, RateControlMode, UsageType, VuiConfig,
};
use openh264::formats::YUVBuffer;
use openh264::OpenH264API;

use super::{Inputs, Made};
use crate::cache::Digest;
use crate::plan::graph::{ActionId, Graph};

/// The finest quantizer OpenH264's rate control allows (its `GOM_MIN_QP_MODE`; lower minimums are raised to it).
const QP: u8 = 12;
/// An I frame every this many frames, so a reader can seek (and a damaged frame heals).
const GOP: u32 = 30;
/// Ticks per second of the video track.
const TIMESCALE: u32 = 90_000;

/// What can go wrong encoding a video.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A frame's bytes do not match its size.
    #[error("a {width}×{height} frame of {bytes} bytes")]
    FrameSize {
        /// Width.
        width: u32,
        /// Height.
        height: u32,
        /// Bytes given.
        bytes: usize,
    },
    /// A frame is larger than MP4 can describe (65 535 pixels a side).
    #[error("{width}×{height} is larger than MP4 can describe")]
    TooLarge {
        /// Width.
        width: u32,
        /// Height.
        height: u32,
    },
    /// A frame of another size than the first.
    #[error("a frame of {got:?} in a {want:?} video")]
    SizeChanged {
        /// The frame's size.
        got: (u32, u32),
        /// The video's size.
        want: (u32, u32),
    },
    /// The video has no frames.
    #[error("no frames were encoded")]
    Empty,
    /// A composite is not a PNG.
    #[error("a frame")]
    Decode(#[from] image::ImageError),
    /// OpenH264 failed.
    #[error("the H.264 encoder")]
    Encoder(#[from] openh264::Error),
    /// The MP4 writer failed.
    #[error("the MP4 writer")]
    Container(#[from] mp4::Error),
}

/// Runs the video actions `ids`, in parallel; each encodes its frames in order.
pub(super) fn videos(
    g: &Graph,
    x: &Inputs,
    blobs: &[Option<Vec<Digest>>],
    ids: &[ActionId],
    done: &(dyn Fn() + Sync),
) -> Result<Made, super::Error> {
    x.each(g, ids, done, |id| {
        let n = g.node(id);
        let fail = |source: Error| super::Error::Video { action: n.label.clone(), source };
        let mut video = Video::new(g.keying.video_fps_milli as f64 / 1000.0);
        for &d in &n.deps {
            let png = x.read(g, blobs, d, 0)?;
            let img = image::load_from_memory_with_format(&png, image::ImageFormat::Png)
                .map_err(|e| fail(e.into()))?
                .into_rgb8();
            let (w, h) = img.dimensions();
            video.push(img.as_raw(), w, h).map_err(fail)?;
        }
        video.finish().map_err(fail)
    })
}

/// An MP4 being encoded, frame by frame.
pub struct Video {
    fps: f64,
    encoder: Option<Encoder>,
    size: (u32, u32),
    /// Sequence and picture parameter sets (from the first frame).
    sps: Vec<u8>,
    pps: Vec<u8>,
    /// Each frame's NAL units in AVCC form (4-byte big-endian lengths), and whether it is an IDR frame.
    samples: Vec<(Vec<u8>, bool)>,
}

impl Video {
    /// A video at `fps` frames per second.
    pub fn new(fps: f64) -> Video {
        Video { fps, encoder: None, size: (0, 0), sps: Vec::new(), pps: Vec::new(), samples: Vec::new() }
    }

    /// Appends a frame of packed 8-bit sRGB (`w·h·3` bytes). Every frame has the first one's size; odd sizes
    /// are padded to even (4:2:0 has no odd sizes) by repeating the last column and row.
    pub fn push(&mut self, rgb: &[u8], w: u32, h: u32) -> Result<(), Error> {
        if rgb.len() != w as usize * h as usize * 3 || w == 0 || h == 0 {
            return Err(Error::FrameSize { width: w, height: h, bytes: rgb.len() });
        }
        if self.encoder.is_none() {
            if w >= u16::MAX as u32 || h >= u16::MAX as u32 {
                return Err(Error::TooLarge { width: w, height: h });
            }
            let config = EncoderConfig::new()
                .usage_type(UsageType::CameraVideoRealTime)
                .rate_control_mode(RateControlMode::Bufferbased)
                .qp(QpRange::new(QP, QP))
                .bitrate(BitRate::from_bps(200_000_000))
                .skip_frames(false)
                .max_frame_rate(FrameRate::from_hz(self.fps as f32))
                .intra_frame_period(IntraFramePeriod::from_num_frames(GOP))
                .num_threads(1)
                .vui(VuiConfig::bt601());
            self.encoder = Some(Encoder::with_api_config(OpenH264API::from_source(), config)?);
            self.size = (w, h);
        } else if self.size != (w, h) {
            return Err(Error::SizeChanged { got: (w, h), want: self.size });
        }
        let (ew, eh) = (w.next_multiple_of(2) as usize, h.next_multiple_of(2) as usize);
        let frame = YUVBuffer::from_vec(rgb_to_i420(rgb, w as usize, h as usize), ew, eh);
        let encoder = self.encoder.as_mut().expect("BUG: made above");
        let stream = encoder.encode(&frame)?.to_vec();
        let (mut sample, mut idr) = (Vec::new(), false);
        for nal in openh264::nal_units(&stream) {
            let nal = strip_start_code(nal);
            let Some(&header) = nal.first() else { continue };
            match header & 0x1f {
                7 if self.sps.is_empty() => self.sps = nal.to_vec(),
                8 if self.pps.is_empty() => self.pps = nal.to_vec(),
                // Parameter sets repeat before each IDR frame; the container carries them once.
                7 | 8 => {}
                t => {
                    idr |= t == 5;
                    sample.extend_from_slice(&(nal.len() as u32).to_be_bytes());
                    sample.extend_from_slice(nal);
                }
            }
        }
        self.samples.push((sample, idr));
        Ok(())
    }

    /// The MP4 file.
    pub fn finish(self) -> Result<Vec<u8>, Error> {
        if self.samples.is_empty() || self.sps.is_empty() || self.pps.is_empty() {
            return Err(Error::Empty);
        }
        let brand = |s: &str| s.parse::<FourCC>().expect("BUG: a four-letter brand");
        let config = Mp4Config {
            major_brand: brand("isom"),
            minor_version: 512,
            compatible_brands: ["isom", "iso2", "avc1", "mp41"].map(brand).to_vec(),
            timescale: 1000,
        };
        let mut w = Mp4Writer::write_start(std::io::Cursor::new(Vec::new()), &config)?;
        let (width, height) = (self.size.0.next_multiple_of(2) as u16, self.size.1.next_multiple_of(2) as u16);
        w.add_track(&TrackConfig {
            track_type: TrackType::Video,
            timescale: TIMESCALE,
            language: "und".into(),
            media_conf: MediaConfig::AvcConfig(AvcConfig {
                width,
                height,
                seq_param_set: self.sps,
                pic_param_set: self.pps,
            }),
        })?;
        // Frame i starts at round(i · timescale / fps): no drift over long videos at fractional rates.
        let start = |i: usize| (i as f64 * TIMESCALE as f64 / self.fps).round() as u64;
        for (i, (bytes, is_sync)) in self.samples.into_iter().enumerate() {
            let duration = (start(i + 1) - start(i)).max(1) as u32;
            let sample =
                Mp4Sample { start_time: start(i), duration, rendering_offset: 0, is_sync, bytes: Bytes::from(bytes) };
            w.write_sample(1, &sample)?;
        }
        w.write_end()?;
        Ok(w.into_writer().into_inner())
    }
}

/// A NAL unit without its Annex B start code (`00 00 01` or `00 00 00 01`).
fn strip_start_code(nal: &[u8]) -> &[u8] {
    let zeros = nal.iter().take_while(|&&b| b == 0).count();
    if zeros >= 2 && nal.get(zeros) == Some(&1) {
        &nal[zeros + 1..]
    } else {
        nal
    }
}

/// Packed sRGB → planar I420, BT.601 limited range, rounded; chroma is the mean of each 2×2 block, luma the
/// best for it ([`luma_for`]). Odd sizes are padded to even by repeating the last column and row.
fn rgb_to_i420(rgb: &[u8], w: usize, h: usize) -> Vec<u8> {
    let (ew, eh) = (w.next_multiple_of(2), h.next_multiple_of(2));
    let (cw, ch) = (ew / 2, eh / 2);
    let mut out = vec![0u8; ew * eh + 2 * cw * ch];
    let px = |x: usize, y: usize| {
        let i = (y.min(h - 1) * w + x.min(w - 1)) * 3;
        [rgb[i] as f32, rgb[i + 1] as f32, rgb[i + 2] as f32]
    };
    let (luma, chroma) = out.split_at_mut(ew * eh);
    let (u, v) = chroma.split_at_mut(cw * ch);
    for cy in 0..ch {
        for cx in 0..cw {
            let mut s = [0f32; 3];
            for (dx, dy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                let p = px(2 * cx + dx, 2 * cy + dy);
                (0..3).for_each(|k| s[k] += p[k] / 4.0);
            }
            let [r, g, b] = s;
            u[cy * cw + cx] = (128.0 - 0.148_223 * r - 0.290_993 * g + 0.439_216 * b).round().clamp(0.0, 255.0) as u8;
            v[cy * cw + cx] = (128.0 + 0.439_216 * r - 0.367_788 * g - 0.071_427 * b).round().clamp(0.0, 255.0) as u8;
        }
    }
    for y in 0..eh {
        for x in 0..ew {
            let c = (y / 2) * cw + x / 2;
            luma[y * ew + x] = luma_for(px(x, y), u[c], v[c]);
        }
    }
    out
}

/// The luma that, with the block's chroma `u`, `v`, decodes nearest `rgb` (least squares over R, G and B, the
/// decoder's clipping to 0…255 included): chroma shared by four pixels is off for each, and luma, which is per
/// pixel, takes back what it can of that error.
fn luma_for(rgb: [f32; 3], u: u8, v: u8) -> u8 {
    let (du, dv) = (u as f32 - 128.0, v as f32 - 128.0);
    let chroma = [1.596_027 * dv, -0.391_762 * du - 0.812_968 * dv, 2.017_232 * du];
    let err = |y: f32| -> f32 {
        (0..3).map(|k| ((1.164_383 * (y - 16.0) + chroma[k]).round().clamp(0.0, 255.0) - rgb[k]).powi(2)).sum()
    };
    let guess = 16.0 + (0..3).map(|k| rgb[k] - chroma[k]).sum::<f32>() / 3.0 / 1.164_383;
    let g = guess.round().clamp(0.0, 255.0);
    let mut best = (err(g), g);
    for d in [-2.0, -1.0, 1.0, 2.0] {
        let y = (g + d).clamp(0.0, 255.0);
        let e = err(y);
        if e < best.0 {
            best = (e, y);
        }
    }
    best.1 as u8
}

#[cfg(test)]
mod tests {
    use super::*;

    /// I420 back to packed RGB as a decoder without chroma filtering does (each chroma sample over its 2×2
    /// block), BT.601 limited range, clipped.
    fn i420_to_rgb(yuv: &[u8], w: usize, h: usize) -> Vec<f32> {
        let cw = w / 2;
        let (luma, chroma) = yuv.split_at(w * h);
        let (u, v) = chroma.split_at(cw * (h / 2));
        let mut out = Vec::with_capacity(w * h * 3);
        for y in 0..h {
            for x in 0..w {
                let (yy, du, dv) = (
                    luma[y * w + x] as f32 - 16.0,
                    u[y / 2 * cw + x / 2] as f32 - 128.0,
                    v[y / 2 * cw + x / 2] as f32 - 128.0,
                );
                let rgb = [
                    1.164_383 * yy + 1.596_027 * dv,
                    1.164_383 * yy - 0.391_762 * du - 0.812_968 * dv,
                    1.164_383 * yy + 2.017_232 * du,
                ];
                out.extend(rgb.map(|c| c.round().clamp(0.0, 255.0)));
            }
        }
        out
    }

    /// Least-squares luma decodes colour edges nearer their RGB than BT.601's own luma does with the same chroma
    /// (on this checker, where chroma dominates the error, by 15 %).
    #[test]
    fn luma_takes_back_what_shared_chroma_loses() {
        // A saturated checker of red, green, blue and grey, one pixel per cell: every block mixes colours.
        let (w, h) = (16, 16);
        let colours = [[230u8, 20, 20], [20, 200, 40], [30, 40, 220], [128, 128, 128]];
        let rgb: Vec<u8> = (0..w * h).flat_map(|i| colours[(i % w + i / w * 3) % 4]).collect();
        let ours = rgb_to_i420(&rgb, w, h);
        let mut plain = ours.clone();
        for (i, p) in rgb.chunks(3).enumerate() {
            let [r, g, b] = [p[0], p[1], p[2]].map(f32::from);
            plain[i] = (16.0 + 0.256_788 * r + 0.504_129 * g + 0.097_906 * b).round() as u8;
        }
        let mse = |yuv: &[u8]| -> f32 {
            let back = i420_to_rgb(yuv, w, h);
            back.iter().zip(&rgb).map(|(a, &b)| (a - b as f32).powi(2)).sum::<f32>() / back.len() as f32
        };
        let (ours, plain) = (mse(&ours), mse(&plain));
        assert!(ours < 0.9 * plain, "least-squares luma {ours} vs BT.601 luma {plain}");
    }
}
