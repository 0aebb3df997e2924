//! Engine benchmark: the no-op path. A 6 000-image dataset (CesiumMan, 3 000 views × 2 frames, 16², RGBA, an
//! init cloud) is built once; then the median of 5 no-op builds (plan the graph, look every action up, place
//! every file, write nothing) and of 5 `status` calls. The target: a no-op build of 6 000 images under 0.5 s.
//! Run: `cargo bench --bench engine [-- OUT_DIR]` (default `target/bench-engine`).

use std::path::PathBuf;
use std::time::Instant;

use vvgen::build::{self, Silent};
use vvgen::plan::actions::Kind;

mod common;
use common::median;

fn main() {
    vvgen::alloc::retain_freed_memory();
    let dir: PathBuf = std::env::args()
        .skip(1)
        .find(|a| !a.starts_with('-'))
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from("target/bench-engine"));
    std::fs::create_dir_all(&dir).unwrap();
    let glb = std::path::absolute("tests/data/gltf/CesiumMan/CesiumMan.glb").unwrap();
    let text = format!(
        "[dataset]\nname = \"n\"\nout = \"out\"\ncache = \"cache\"\n\
         [source.man]\ngltf = \"{}\"\nframes = {{ count = 2, fps = 4 }}\n\
         [transform]\nup = \"y\"\nfit = {{ height = 2.4 }}\ncenter = \"bbox\"\n\
         [render]\nresolution = [16, 16]\n[rig.s]\nkind = \"fibonacci\"\n\
         [split.train]\nrig = \"s\"\nviews = 3000\n[output.d]\nwriter = \"dnerf\"\ninit_points = 1000\n",
        glb.display()
    );
    std::fs::write(dir.join("m.toml"), text).unwrap();
    let (m, _) = vvgen::manifest::load(&dir.join("m.toml")).unwrap_or_else(|r| panic!("{}", r.render(false)));
    let cache = dir.join("cache");
    let t = Instant::now();
    let first = build::build(&m, &cache, Default::default(), &Silent).unwrap();
    println!("first build: {} images, {} rendered in {:.2} s", first.images, first.renders, t.elapsed().as_secs_f64());
    let noop = median(5, || {
        let r = build::build(&m, &cache, Default::default(), &Silent).unwrap();
        assert!(r.nothing_to_do() && r.actions[&Kind::RenderPass].cached == 6000);
    });
    let status = median(5, || {
        assert!(build::status(&m, &cache, false).unwrap().up_to_date());
    });
    println!("no-op build of 6000 images: {:8.1} ms (target < 500 ms)", noop.as_secs_f64() * 1e3);
    println!("status of 6000 images:      {:8.1} ms", status.as_secs_f64() * 1e3);
}
