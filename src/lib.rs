//! # ntori
//!
//! The application layer: the command line (and, in later work, the model file, meshes, export, the
//! renderer and the editor) over the [`charts`] and [`embedding`] crates.

pub mod editor;
pub mod figures;
pub mod io;
pub mod render;

pub use charts;
pub use embedding;
pub use mesh;
