//! Scene benchmarks: PLY read/write (1M points, binary and ascii; an 800k-point 8i-style ascii frame; 1M 3D
//! Gaussians read as points, and the spacing that sizes their splats; `benches/splat_peer.py` times plyfile on the
//! same file) and glTF
//! frame evaluation (CesiumMan). Run: `cargo bench --bench scene [-- OUT_DIR]`. The PLY files are left in
//! OUT_DIR (default `target/bench-data`) so peers (plyfile, Open3D) can time the same bytes in the same run.

use std::hint::black_box;
use std::path::{Path, PathBuf};
use std::time::Duration;

use glam::Mat4;
use vvgen::scene::gltf::{self, PoseScratch};
use vvgen::scene::ply::{self, PlyOut};
use vvgen::scene::PosedScene;

mod common;

/// Median wall time of `runs` calls after one untimed call, the protocol of the peers' script
/// (`bench_python.py`: one warm call, then the median of the timed ones): the first call faults in the memory the
/// later ones reuse.
fn time<T>(runs: usize, mut f: impl FnMut() -> T) -> Duration {
    black_box(f());
    common::median(runs, f)
}

fn ms(d: Duration) -> String {
    format!("{:8.3} ms", d.as_secs_f64() * 1e3)
}

fn main() {
    // As the `vvgen` binary does: freed buffers are reused, not faulted in again per read.
    vvgen::alloc::retain_freed_memory();
    let out: PathBuf = std::env::args()
        .skip(1)
        .find(|a| !a.starts_with('-'))
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from("target/bench-data"));
    std::fs::create_dir_all(&out).unwrap();

    // 1M points, xyz float + rgb uchar: the common capture layout.
    let n = 1_000_000;
    let mut s = 0x9E3779B97F4A7C15u64;
    let mut rnd = move || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        (s >> 40) as f32 / (1u64 << 24) as f32
    };
    let pos: Vec<[f32; 3]> = (0..n).map(|_| [rnd() * 2.0 - 1.0, rnd() * 2.0 - 1.0, rnd() * 2.0]).collect();
    let col: Vec<[u8; 3]> = (0..n).map(|i| [(i % 251) as u8, (i % 241) as u8, (i % 239) as u8]).collect();
    let cloud = PlyOut { positions: &pos, colors: Some(&col), ..Default::default() };

    println!("PLY, 1M points (x y z float, red green blue uchar):");
    let bin = ply::write(&cloud);
    std::fs::write(out.join("pc_1m_bin.ply"), &bin).unwrap();
    println!("  write binary        {}", ms(time(5, || ply::write(&cloud))));
    println!("  read  binary        {}", ms(time(5, || ply::read(&bin).unwrap())));
    // What plyfile is timed on: the file, read and decoded into arrays (as `vvgen` reads a sequence frame).
    let file = out.join("pc_1m_bin.ply");
    println!("  read  binary file   {}", ms(time(7, || ply::read_file(&file).unwrap())));
    let txt = ply::write(&PlyOut { ascii: true, ..cloud });
    std::fs::write(out.join("pc_1m_ascii.ply"), &txt).unwrap();
    println!("  write ascii         {}", ms(time(3, || ply::write(&PlyOut { ascii: true, ..cloud }))));
    println!("  read  ascii         {}", ms(time(3, || ply::read(&txt).unwrap())));

    // An 8i vox10 frame: 800k points with integer coordinates in 0..1024, written as 8i does (ascii).
    let vox: Vec<[f32; 3]> = pos
        .iter()
        .take(800_000)
        .map(|p| [((p[0] + 1.0) * 511.0).round(), ((p[1] + 1.0) * 511.0).round(), (p[2] * 511.0).round()])
        .collect();
    let vox_txt =
        ply::write(&PlyOut { positions: &vox, colors: Some(&col[..800_000]), ascii: true, ..Default::default() });
    std::fs::write(out.join("vox10_800k_ascii.ply"), &vox_txt).unwrap();
    println!("  read  8i-style ascii frame, 800k points   {}", ms(time(5, || ply::read(&vox_txt).unwrap())));

    // 1M 3D Gaussians in the layout Mip-Splatting writes (SH band 0: x y z, f_dc_0..2, opacity, scale_0..2,
    // rot_0..3, all float): read as points of their base colours, the faint ones left out.
    let props = ["x", "y", "z", "f_dc_0", "f_dc_1", "f_dc_2", "opacity", "scale_0", "scale_1", "scale_2"];
    let props: Vec<&str> = props.into_iter().chain(["rot_0", "rot_1", "rot_2", "rot_3"]).collect();
    let mut gs = format!("ply\nformat binary_little_endian 1.0\nelement vertex {n}\n").into_bytes();
    props.iter().for_each(|p| gs.extend(format!("property float {p}\n").bytes()));
    gs.extend(b"end_header\n");
    for p in &pos {
        let row = [p[0], p[1], p[2], rnd() * 4.0 - 2.0, rnd() * 4.0 - 2.0, rnd() * 4.0 - 2.0, rnd() * 12.0 - 6.0];
        let rest = [-5.0, -5.0, -6.0, 1.0, 0.0, 0.0, 0.0];
        row.iter().chain(&rest).for_each(|v| gs.extend(v.to_le_bytes()));
    }
    let gs_file = out.join("gaussians_1m.ply");
    std::fs::write(&gs_file, &gs).unwrap();
    println!("3D Gaussian splatting PLY, 1M Gaussians (SH band 0, 56 bytes each):");
    println!("  read  file as points            {}", ms(time(5, || ply::read_file(&gs_file).unwrap())));
    let centres: Vec<glam::Vec3> =
        ply::read_file(&gs_file).unwrap().positions.iter().map(|p| glam::Vec3::from(*p)).collect();
    println!(
        "  their spacing (the default voxel, {} points)  {}",
        centres.len(),
        ms(time(5, || vvgen::scene::spacing::typical(&centres)))
    );

    let man = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/gltf/CesiumMan/CesiumMan.glb");
    let asset = gltf::load(&man, None).unwrap();
    let mut scratch = PoseScratch::default();
    let mut posed = PosedScene::default();
    asset.pose(&[0], 0.0, Mat4::IDENTITY, &mut scratch, &mut posed);
    let mut t = 0.0f32;
    let d = time(201, || {
        t = (t + 1.0 / 30.0) % 2.0;
        asset.pose(&[0], t, Mat4::IDENTITY, &mut scratch, &mut posed);
    });
    println!(
        "glTF: CesiumMan frame evaluation ({} vertices, 19 joints)  {}",
        posed.primitives.iter().map(|p| p.positions.len()).sum::<usize>(),
        ms(d)
    );
    println!("files for peers: {}", out.display());
}
