//! `ntori new`: writes a model that loads, refuses to overwrite, reports bad parameters clearly.

use predicates::prelude::*;

use crate::common::ntori;

#[test]
fn new_writes_a_valid_model_and_passes_its_checks() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("torus.json");
    let out = ntori()
        .args(["new", "--genus", "1", "--resolution", "16", "--json", "-o"])
        .arg(&path)
        .assert()
        .success()
        .get_output()
        .stdout
        .clone();
    let report: serde_json::Value = serde_json::from_slice(&out).unwrap();
    assert_eq!(report["passed"], true);
    assert_eq!(report["folded_triangles"], 0);
    let model: embedding::Model =
        serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    let atlas = charts::Atlas::new(1).unwrap();
    let layout = embedding::Layout::new(&atlas, model.settings).unwrap();
    model.validate(&layout).unwrap();
    // A second run does not replace the file without --force.
    let before = std::fs::read(&path).unwrap();
    ntori()
        .args(["new", "--genus", "1", "-o"])
        .arg(&path)
        .assert()
        .failure()
        .stderr(predicate::str::contains("--force"));
    assert_eq!(std::fs::read(&path).unwrap(), before);
}

#[test]
fn new_rejects_impossible_parameters() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("m.json");
    for args in [
        vec!["--genus", "65"],
        vec!["--smoothness", "-1"],
        vec!["--smoothness", "NaN"],
        vec!["--grid", "2"],
        vec!["--resolution", "3"],
    ] {
        ntori()
            .arg("new")
            .args(&args)
            .arg("-o")
            .arg(&path)
            .assert()
            .failure()
            .stderr(predicate::str::is_empty().not());
        assert!(!path.exists(), "{args:?} left a file");
    }
}
