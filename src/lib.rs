//! vvgen builds datasets of dynamic 6-DoF content (multi-view images with exact cameras, and point-cloud
//! sequences) from declarative TOML manifests.
//!
//! The pipeline, one module per stage: [`manifest`] (TOML → checked tables) → scene (sources, animation,
//! transforms) → rig/splits → plan (tasks and keys) → execute (render, sample) → cache → export (writers).
//! [`cli`] is the command-line front end.

#![deny(missing_docs)]

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
pub mod release;
pub mod render;
pub mod rig;
pub mod sample;
pub mod scene;
