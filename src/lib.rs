//! # ntori
//!
//! The application layer over the [`charts`], [`mesh`] and [`embedding`] crates: files and exports
//! ([`io`]), pictures ([`render`]), the paper's figures ([`figures`]) and the editor ([`editor`]).
//! The command line is the binary's (`src/main.rs`, `src/cli/`); this library uses no anyhow.

pub mod editor;
pub mod figures;
pub mod io;
pub mod render;

pub use charts;
pub use embedding;
pub use mesh;
