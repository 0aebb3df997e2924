//! vvgen builds datasets of dynamic 6-DoF content (multi-view images with exact cameras, and point-cloud
//! sequences) from declarative TOML manifests.
//!
//! The pipeline, one module per stage: [`manifest`] (TOML → checked tables) → [`scene`] (sources, animation,
//! transforms) → [`rig`] (camera poses) → [`plan`] (the images, and the graph of every action with its key) →
//! [`execute`] (run what the cache lacks: [`render`], [`sample`]) → [`cache`] (blobs and action records) →
//! [`export`] (place blobs, write metadata). [`build`] runs the chain and is the entry point for Rust callers
//! ([`build::Build`]); [`camera`] is the one camera model; [`cli`] is the command-line front end.

#![deny(missing_docs)]
// Outside tests, a value that cannot be missing says why (`expect`), and one that can is an error.
#![cfg_attr(not(test), deny(clippy::unwrap_used))]

pub mod alloc;
pub mod atomic;
pub mod build;
pub mod cache;
pub mod camera;
pub mod cli;
pub mod execute;
pub mod export;
pub mod manifest;
pub mod plan;
pub mod preview;
pub mod release;
pub mod render;
pub mod rig;
pub mod sample;
pub mod scene;
pub mod settings;
