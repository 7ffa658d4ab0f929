//! # ntori
//!
//! The application layer: the command line (and, in later work, the model file, meshes, export, the
//! renderer and the editor) over the [`charts`] and [`embedding`] crates.

pub mod bench;
pub mod cell_complex;
pub mod editor;
pub mod export;
pub mod figures;
pub mod files;
pub mod info;
pub mod mesh;
pub mod model_file;
pub mod new;
pub mod palette;
pub mod render;
pub mod spatial;
pub mod tessellate;

pub use charts;
pub use embedding;
