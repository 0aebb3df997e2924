//! Posing a frame after the first allocates nothing (a counting global allocator checks it).

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};

use glam::Mat4;
use vvgen::scene::gltf::{self, PoseScratch};
use vvgen::scene::PosedScene;

struct Counting;
static ALLOCS: AtomicUsize = AtomicUsize::new(0);

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, l: Layout) -> *mut u8 {
        ALLOCS.fetch_add(1, Ordering::SeqCst);
        unsafe { System.alloc(l) }
    }
    unsafe fn dealloc(&self, p: *mut u8, l: Layout) {
        unsafe { System.dealloc(p, l) }
    }
    unsafe fn realloc(&self, p: *mut u8, l: Layout, n: usize) -> *mut u8 {
        ALLOCS.fetch_add(1, Ordering::SeqCst);
        unsafe { System.realloc(p, l, n) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

#[test]
fn posing_after_the_first_frame_does_not_allocate() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/gltf/CesiumMan/CesiumMan.glb");
    let asset = gltf::load(&path, None).unwrap();
    let (mut scratch, mut posed) = (PoseScratch::default(), PosedScene::default());
    asset.pose(&[0], 0.0, Mat4::IDENTITY, &mut scratch, &mut posed);
    let before = ALLOCS.load(Ordering::SeqCst);
    for f in 1..30 {
        asset.pose(&[0], f as f32 / 30.0, Mat4::IDENTITY, &mut scratch, &mut posed);
    }
    assert_eq!(ALLOCS.load(Ordering::SeqCst) - before, 0);
    assert!(posed.triangle_count() > 4000);
}
