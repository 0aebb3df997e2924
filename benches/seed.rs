//! The seed-scale dataset (issue 17): the 6-DoF toolkit's standard multi-view video set, built cold through the
//! engine as `vvgen build` runs it: CesiumMan, 60 frames, 80 training and 20 test views on the NeRF-synthetic
//! hemisphere, 800², 4 samples, RGBA + 16-bit depth (6 000 images, a D-NeRF layout with its init cloud), plus a
//! 60-frame point-cloud sequence (1M surface samples per frame, 5 mm voxels). Previews off (the workload as
//! the issue defines it). Prints the wall time, per-kind times and ms per image. `benches/seed_peers.sh` builds
//! the same set with `vvgen` binaries (today's beside an older one) and times Blender on the same images in the
//! same run (see docs/benchmarks.md).
//!
//! Run: `cargo bench --bench seed [-- OUT_DIR]` (default `target/bench-seed`; about 2 GB written).

use std::path::PathBuf;
use std::time::Instant;

use vvgen::build::{self, Silent};

fn main() {
    vvgen::alloc::retain_freed_memory();
    let dir: PathBuf = std::env::args()
        .skip(1)
        .find(|a| !a.starts_with('-'))
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from("target/bench-seed"));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let glb = std::fs::canonicalize("tests/data/gltf/CesiumMan/CesiumMan.glb").unwrap();
    let text = format!(
        "[dataset]\nname = \"seed\"\nout = \"out\"\ncache = \"cache\"\npreview = false\n\
         [source.man]\ngltf = \"{}\"\nframes = {{ count = 60, fps = 30 }}\n\
         [transform]\nup = \"y\"\nfit = {{ height = 2.4 }}\ncenter = \"bbox\"\nover = \"all-frames\"\n\
         [render]\nresolution = [800, 800]\nsamples = 4\npasses = [\"rgba\", \"depth\"]\n\
         [rig.hemi]\nkind = \"hemisphere\"\n\
         [split.train]\nrig = \"hemi\"\nviews = 80\ntime = \"all\"\n\
         [split.test]\nrig = \"hemi\"\nviews = 20\ntime = \"all\"\n\
         [output.d]\nwriter = \"dnerf\"\n\
         [output.p]\nwriter = \"ply-sequence\"\npoints = 1000000\nvoxel = 0.005\n",
        glb.display()
    );
    std::fs::write(dir.join("seed.toml"), text).unwrap();
    let (m, _) = vvgen::manifest::load(&dir.join("seed.toml")).unwrap_or_else(|r| panic!("{}", r.render(false)));
    let t = Instant::now();
    let r = build::build(&m, &dir.join("cache"), Default::default(), &Silent).unwrap();
    let secs = t.elapsed().as_secs_f64();
    println!("seed-scale dataset, cold, {} threads: {secs:.1} s in all", rayon::current_num_threads());
    println!("  {} images: {:.2} ms per image of wall time", r.images, secs * 1e3 / r.images as f64);
    for (kind, c) in &r.actions {
        if c.ran > 0 && kind.cached() {
            println!("  {:<14} {:>5} in {:6.1} s", kind.name(), c.ran, c.seconds);
        }
    }
}
