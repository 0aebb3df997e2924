//! Draco files: the median wall time of `scene::drc::scene` (decoding, then the scene a render draws: normals
//! found for a mesh without them, colours to linear) per file given, one untimed call first. Run:
//! `cargo bench --bench drc_decode -- FILE.drc…`. Its peer, `benches/drc_peer.py`, times DracoPy's `decode`
//! (Google's C++ decoder, to NumPy arrays) on the same files with the same protocol, in the same run.

use std::hint::black_box;
use std::path::Path;

mod common;

fn main() {
    vvgen::alloc::retain_freed_memory();
    // `cargo bench` passes `--bench`; the files are the other arguments.
    for file in std::env::args().skip(1).filter(|a| !a.starts_with("--")) {
        let decode = || vvgen::scene::drc::scene(Path::new(&file)).unwrap_or_else(|e| panic!("{e}"));
        black_box(decode());
        let d = common::median(11, decode);
        println!("vvgen drc {file}: {:.2} ms", d.as_secs_f64() * 1e3);
    }
}
