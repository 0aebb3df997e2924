//! Scene sources.
pub mod ply;
