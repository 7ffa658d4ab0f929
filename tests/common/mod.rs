//! Helpers shared by the test binaries (`tests/cli`, `tests/library`, `tests/editor.rs`), each of
//! which includes this file as `mod common`. Not every binary uses every helper.
#![allow(dead_code)]

use std::sync::OnceLock;

use embedding::fit::{FitSettings, initial_model};
use embedding::{SplineSettings, Surface};

/// The `ntori` binary that Cargo built for these tests.
pub fn ntori() -> assert_cmd::Command {
    assert_cmd::Command::cargo_bin("ntori").expect("the ntori binary is built")
}

/// The genera [`small_model`] caches.
pub const SMALL_MODEL_GENERA: u32 = 9;

/// A small fitted model of genus 0 to 8 (an 8×8 grid per chart fitted to a resolution-16 mesh:
/// seconds, not minutes), fitted once per test binary and genus.
pub fn small_model(genus: u32) -> &'static Surface {
    static MODELS: [OnceLock<Surface>; SMALL_MODEL_GENERA as usize] =
        [const { OnceLock::new() }; SMALL_MODEL_GENERA as usize];
    MODELS[genus as usize].get_or_init(|| {
        let settings = SplineSettings {
            grid: 8,
            ..SplineSettings::default()
        };
        initial_model(genus, 16, settings, FitSettings::default())
            .expect("the small model fits")
            .surface
    })
}
