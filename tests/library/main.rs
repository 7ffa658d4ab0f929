//! The root package as a library: export formats read back by other parsers and tools, the
//! figures, the fit, offscreen rendering and the tessellation. (One test binary, so wgpu is linked once.)

#[path = "../common/mod.rs"]
mod common;

mod assets;
mod export;
mod export_tools;
mod figures;
mod fit;
mod hardening;
mod import;
mod render;
mod tessellation;
