//! The `ntori` binary as a user runs it: one module per subcommand. (One test binary for all of
//! them, so the root package's dependencies are linked once.)

#[path = "../common/mod.rs"]
mod common;

mod bench;
mod export;
mod figures;
mod fit;
mod hardening;
mod info;
mod new;
mod render;
mod sculpt;
mod tessellate;
