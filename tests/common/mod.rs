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

/// Runs `ntori ARGS`, which must succeed (else the test fails with its stderr), and parses what it
/// printed as JSON.
pub fn ntori_json<S: AsRef<std::ffi::OsStr>>(args: &[S]) -> serde_json::Value {
    let out = ntori().args(args).output().expect("ntori runs");
    assert!(
        out.status.success(),
        "ntori {:?}: {}",
        args.iter()
            .map(|a| a.as_ref().to_owned())
            .collect::<Vec<_>>(),
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("ntori prints valid JSON")
}

/// Where the example models live (see assets/README.md).
pub fn asset(name: &str) -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("assets")
        .join(name)
}

/// The genera of the example models in `assets/models/`.
pub const SMALL_MODEL_GENERA: std::ops::RangeInclusive<u32> = 0..=3;

/// The small fitted model of genus 0 to 3 from `assets/models/` (an 8×8 grid per chart, 10×10 in
/// genus 3's disk charts, fitted to a resolution-16 mesh), loaded once per test binary and genus.
/// `tests/library/assets.rs` checks that the files are what the fit makes.
pub fn small_model(genus: u32) -> &'static Surface {
    static MODELS: [OnceLock<Surface>; 4] = [const { OnceLock::new() }; 4];
    assert!(
        SMALL_MODEL_GENERA.contains(&genus),
        "no example model of genus {genus}"
    );
    MODELS[genus as usize].get_or_init(|| {
        let path = asset(&format!("models/genus-{genus}.json"));
        ntori::io::model_file::load(&path).expect("the example model loads")
    })
}

/// The settings and input resolution the example models were fitted with.
pub fn small_model_fit(genus: u32) -> Surface {
    // Genus 3's plate is wider than genus 2's and at 8×8 throughout its disk charts took a
    // spike (|κ| 8.8× the input's) that turned quads of the quad tessellation.
    let settings = SplineSettings {
        grid: 8,
        disk_grid: (genus == 3).then_some(10),
        ..SplineSettings::default()
    };
    initial_model(genus, 16, settings, FitSettings::default())
        .expect("the small model fits")
        .surface
}
