//! Hardening (issue 16): what a careless or hostile user types gets a clear error and a non-zero
//! exit, never a panic (exit 101), a hang, or a destroyed file.

use std::path::Path;
use std::sync::Arc;

use embedding::{Model, Surface};
use predicates::prelude::*;

use crate::common::ntori;

/// A model file of `genus` whose every control point is the origin (cheap at any genus: no fit).
fn constant_model(dir: &Path, genus: u32) -> std::path::PathBuf {
    let atlas = Arc::new(charts::Atlas::new(genus).unwrap());
    let settings = embedding::SplineSettings {
        grid: 8,
        ..Default::default()
    };
    let layout = embedding::Layout::new(&atlas, settings).unwrap();
    let model = Model::constant(&layout, embedding::Point3::zeros());
    Surface::from_model(&model).unwrap();
    let path = dir.join(format!("constant-{genus}.json"));
    std::fs::write(&path, serde_json::to_string(&model).unwrap()).unwrap();
    path
}

#[test]
fn render_refuses_a_tessellation_beyond_the_buffer_limit() {
    let dir = tempfile::tempdir().unwrap();
    let model = constant_model(dir.path(), 64);
    let png = dir.path().join("m.png");
    // Genus 64 at T = 256: 83.8 M triangles, 12 GB of vertices; refused before tessellating.
    ntori()
        .arg("render")
        .arg(&model)
        .args(["--tessellation", "256", "-q", "-o"])
        .arg(&png)
        .timeout(std::time::Duration::from_secs(600))
        .assert()
        .code(1)
        .stderr(predicate::str::contains(
            "vertex buffer would take 12060721152 bytes",
        ))
        .stderr(predicate::str::contains("panicked").not());
    assert!(!png.exists());
}
