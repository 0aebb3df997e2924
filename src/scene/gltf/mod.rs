//! glTF 2.0 sources: loading ([`load()`]), accessor decoding, animation sampling and posing.

mod accessor;
pub mod anim;
pub mod load;
pub mod pose;
mod tangents;

pub use load::{load, load_slice, GltfAsset};
pub use pose::PoseScratch;
mod validate;
