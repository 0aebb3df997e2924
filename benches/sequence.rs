//! Long point-cloud sequences in bounded memory: the `vvgen` binary builds 20, 40 and 80 binary frames of 800k
//! points (4 hemisphere views at 400², cubes, a 100k-point init cloud) and this reports each build's peak RSS
//! (the child's own, from `wait4`) and the share of its wall time spent outside rendering.
//!
//! `cargo bench --bench sequence` (writes about 1 GB of frames to `target/bench-data/seq800k` once). `VVGEN=path`
//! builds with another `vvgen` binary (an older one, for a before and after in one run).

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use vvgen::scene::ply::{self, PlyOut};

/// Points per frame.
const POINTS: usize = 800_000;

/// A deterministic sphere-shell cloud, shifted a little per frame (so every frame's file differs).
fn frame(f: usize) -> Vec<u8> {
    let mut state = 0x9e37_79b9_7f4a_7c15u64;
    let mut next = || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f32 / (1u64 << 53) as f32
    };
    let (mut pos, mut col) = (Vec::with_capacity(POINTS), Vec::with_capacity(POINTS));
    for _ in 0..POINTS {
        let (z, a) = (next() * 2.0 - 1.0, next() * std::f32::consts::TAU);
        let s = (1.0 - z * z).sqrt();
        let p = [0.6 * s * a.cos() + 0.01 * f as f32, 0.6 * s * a.sin(), 0.6 * z + 0.6];
        col.push([0, 1, 2].map(|k| ((p[k] + 1.0) * 127.0) as u8));
        pos.push(p);
    }
    ply::write(&PlyOut { positions: &pos, colors: Some(&col), ..Default::default() })
}

fn frames(dir: &Path, n: usize) {
    std::fs::create_dir_all(dir).unwrap();
    for f in 0..n {
        let path = dir.join(format!("f_{f:04}.ply"));
        if !path.exists() {
            let tmp = dir.join(format!(".tmp_{f:04}.ply"));
            std::fs::File::create(&tmp).unwrap().write_all(&frame(f)).unwrap();
            std::fs::rename(&tmp, &path).unwrap();
        }
    }
}

/// Runs `vvgen build` on `manifest`; its peak RSS (kB), wall and render seconds.
// The child is reaped by `wait4`, which also returns its own resource usage (`Child::wait` does not).
#[allow(clippy::zombie_processes)]
fn build(manifest: &Path) -> (i64, f64, f64) {
    let bin = std::env::var_os("VVGEN").unwrap_or_else(|| env!("CARGO_BIN_EXE_vvgen").into());
    let child =
        Command::new(bin).arg("build").arg(manifest).stdout(Stdio::null()).stderr(Stdio::piped()).spawn().unwrap();
    let pid = child.id() as libc::pid_t;
    let mut stderr = child.stderr.unwrap();
    let mut log = String::new();
    std::io::Read::read_to_string(&mut stderr, &mut log).unwrap();
    let (mut status, mut usage) = (0, unsafe { std::mem::zeroed::<libc::rusage>() });
    // SAFETY: waits for our own child and fills `usage`, both owned here.
    let waited = unsafe { libc::wait4(pid, &mut status, 0, &mut usage) };
    assert!(waited == pid && status == 0, "vvgen build failed:\n{log}");
    // "N images: … rendered in R s (…); T s in all"
    let line = log.lines().find(|l| l.contains("rendered in")).unwrap_or_else(|| panic!("{log}"));
    let num = |after: &str, before: &str| -> f64 {
        line.split(after).nth(1).and_then(|t| t.split(before).next()).unwrap().trim().parse().unwrap()
    };
    (usage.ru_maxrss, num("; ", " s in all"), num("rendered in ", " s ("))
}

fn main() {
    let data = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("target/bench-data");
    let seq = data.join("seq800k");
    frames(&seq, 80);
    println!("{POINTS}-point binary frames, 4 views at 400², cubes, 100k-point init cloud (cold builds):");
    for n in [20, 40, 80] {
        let dir = data.join(format!("seq-build-{n}"));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let text = format!(
            "[dataset]\nname = \"seq\"\nout = \"out\"\ncache = \"cache\"\n\
             [source.pc]\nply_sequence = \"{}/f_{{frame:04}}.ply\"\nframes = {{ start = 0, count = {n} }}\n\
             [transform]\nfit = {{ height = 2.0 }}\ncenter = \"bbox\"\nover = \"all-frames\"\n\
             [render]\nresolution = [400, 400]\nsplat = {{ shape = \"cube\", size = 0.004 }}\n\
             [rig.h]\nkind = \"hemisphere\"\n[split.train]\nrig = \"h\"\nviews = 4\n\
             [output.d]\nwriter = \"dnerf\"\ninit_points = 100000\n",
            seq.display()
        );
        let manifest = dir.join("m.toml");
        std::fs::write(&manifest, text).unwrap();
        let (rss, wall, render) = build(&manifest);
        println!(
            "  {n:>3} frames: peak RSS {:>5.0} MB, {wall:>6.2} s in all, {render:>6.2} s rendering, non-render share {:>4.1} %",
            rss as f64 / 1024.0,
            100.0 * (wall - render) / wall
        );
        let _ = std::fs::remove_dir_all(&dir);
    }
}
