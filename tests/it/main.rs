//! The integration tests, as one crate (one link instead of a dozen on two cores). Each module is one area;
//! `common` holds the fixtures they share. (The allocation-counting test is its own crate: it installs a global
//! allocator.)

mod blend;
mod build;
mod common;
mod compare;
mod consumers;
mod corpus;
mod engine;
mod fbx;
mod first_try;
mod fuzz;
mod fuzz_structure;
mod gltf_extensions;
mod gltf_lights;
mod graph;
mod hostile_gltf;
mod layers;
mod lit;
mod manifest;
mod meshseq;
mod new;
mod normal_maps;
mod path;
mod ply;
mod points;
mod preview;
mod render;
mod rigs;
mod scene;
mod schema;
mod slurm;
mod transform;
mod transparency;
mod video;
mod writers;
