//! vvgen builds datasets of dynamic 6-DoF content (multi-view images with exact cameras, and point-cloud
//! sequences) from declarative TOML manifests.
//!
//! The pipeline, one module per stage: `manifest` (TOML → checked tables) → `scene` (sources, animation,
//! transforms) → `rig` (camera poses) → `plan` (the images, and the graph of every action with its key) →
//! `execute` (run what the cache lacks: `render`, `sample`) → `cache` (blobs and action records) → `export`
//! (place blobs, write metadata); `settings` turns the manifest's declarations into the renderer's. [`build`]
//! runs the chain and is the entry point for Rust callers ([`build::Build`]); `camera` is the one camera model;
//! [`cli`] is the command-line front end. ARCHITECTURE.md is the map.

#![deny(missing_docs)]
// Outside tests, a value that cannot be missing says why (`expect`), and one that can is an error.
#![cfg_attr(not(test), deny(clippy::unwrap_used))]
// Without `testing`, the stages are crate-private: what only tests and benches call (or re-export) is unused.
#![cfg_attr(not(feature = "testing"), allow(dead_code, unused_imports))]

//! # The public API
//!
//! [`build`] (a [`build::Build`] of a manifest file: run it, ask its status, read its report), the manifest
//! types a caller may hold ([`Manifest`], its [`ManifestReport`] of diagnostics), the action kinds a report counts
//! ([`Kind`]), [`cli`] (the command line, for the binary) and [`alloc`] (the binary's allocator setting). The
//! stages themselves are crate-private; the `testing` feature makes them public for the crate's own tests and
//! benches (they enable it through a dev-dependency on the crate itself). CI counts the public items rustdoc lists
//! without it, so the API cannot silently grow.

pub mod alloc;
pub mod build;
pub mod cli;

pub use manifest::{Diagnostic, Manifest, Report as ManifestReport, Severity};
pub use plan::actions::Kind;

/// Declares stage modules public with the `testing` feature and crate-private without it.
macro_rules! stages {
    ($($(#[$doc:meta])* $name:ident;)*) => {$(
        $(#[$doc])*
        #[cfg(feature = "testing")]
        pub mod $name;
        $(#[$doc])*
        #[cfg(not(feature = "testing"))]
        pub(crate) mod $name;
    )*};
}

stages! {
    atomic;
    cache;
    camera;
    compare;
    execute;
    export;
    manifest;
    plan;
    preview;
    release;
    render;
    rig;
    sample;
    scene;
    settings;
}
