//! glTF loading, compressed or not: the median wall time of `scene::gltf::load` (decoding included: Draco,
//! meshopt, images) per file given. Run: `cargo bench --bench gltf_load -- FILE…`. Its peer,
//! `benches/gltf_transform_read.mjs`, times glTF-Transform's `NodeIO.read` (Google's draco3dgltf and
//! meshoptimizer's WebAssembly decoder, as three.js decodes) on the same files in the same run; a codec's cost
//! is a compressed file's time minus its plain twin's, on each side. For KTX2 textures the peer is
//! `benches/basis_transcode.mjs` (three.js's Basis transcoder) and vvgen's cost is a KTX2 file's time minus that of
//! the same file without textures.

use std::hint::black_box;
use std::path::Path;
use std::time::Duration;

mod common;

/// Median wall time of `runs` loads after one untimed load (the peer's protocol).
fn median(runs: usize, path: &Path) -> Duration {
    let load = || vvgen::scene::gltf::load(path, None).unwrap_or_else(|e| panic!("{e}"));
    black_box(load());
    common::median(runs, load)
}

fn main() {
    vvgen::alloc::retain_freed_memory();
    // `cargo bench` passes `--bench`; the files are the other arguments.
    for file in std::env::args().skip(1).filter(|a| !a.starts_with("--")) {
        let d = median(11, Path::new(&file));
        println!("vvgen load {file}: {:.1} ms", d.as_secs_f64() * 1e3);
    }
}
