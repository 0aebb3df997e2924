//! glTF 2.0 sources: loading ([`load()`]), accessor decoding, animation sampling and posing.

mod accessor;
pub mod anim;
mod document;
mod draco;
mod image;
mod instancing;
pub mod load;
mod materials;
mod meshopt;
mod pointer;
pub mod pose;
mod spec_gloss;
mod splats;
mod tangents;
pub(crate) use tangents::mikktspace;
mod uri;

pub use load::{load, load_slice, GltfAsset};
pub use pose::PoseScratch;
pub(crate) use uri::side_files;
mod validate;
