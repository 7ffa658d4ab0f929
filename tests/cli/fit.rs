//! `ntori fit`: a user's mesh becomes a model with new's checks; bad meshes get located errors and
//! nothing is written.

use predicates::prelude::*;

use crate::common::{asset, ntori};

#[test]
fn fit_writes_a_model_of_the_mesh_genus_that_passes_its_checks() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("plate.json");
    let out = ntori()
        .arg("fit")
        .arg(asset("meshes/plate-genus-3.obj"))
        .args(["--json", "-q", "-o"])
        .arg(&path)
        .assert()
        .success()
        .get_output()
        .stdout
        .clone();
    let report: serde_json::Value = serde_json::from_slice(&out).unwrap();
    assert_eq!(report["fit"]["passed"], true);
    assert_eq!(report["fit"]["genus"], 3);
    assert_eq!(report["fit"]["folded_triangles"], 0);
    // A user's mesh has no intended shape beyond itself: its own normals are the reference.
    assert_eq!(report["fit"]["shape"]["normals_from"], "mesh");
    assert_eq!(report["loops"]["loop_edges"].as_array().unwrap().len(), 6);
    assert!(report["fit"]["max_residual"].as_f64().unwrap() < 0.01);
    let model: embedding::Model =
        serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    let atlas = charts::Atlas::new(3).unwrap();
    let layout = embedding::Layout::new(&atlas, model.settings).unwrap();
    model.validate(&layout).unwrap();
}

#[test]
fn fit_refuses_an_open_mesh_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("m.json");
    // An open square (two triangles).
    let open = dir.path().join("open.obj");
    std::fs::write(
        &open,
        "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3\nf 1 3 4\n",
    )
    .unwrap();
    ntori()
        .arg("fit")
        .arg(&open)
        .arg("-o")
        .arg(&out)
        .assert()
        .failure()
        .stderr(predicate::str::contains(
            "the mesh is not closed: it has 1 hole",
        ))
        .stderr(predicate::str::contains("open.obj"));
    assert!(!out.exists());
}

#[test]
fn fit_maps_a_genus_zero_mesh_onto_the_sphere() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("dumbbell.json");
    let out = ntori()
        .arg("fit")
        .arg(asset("meshes/dumbbell-genus-0.obj"))
        .args(["--json", "-q", "-o"])
        .arg(&path)
        .assert()
        .success()
        .get_output()
        .stdout
        .clone();
    let report: serde_json::Value = serde_json::from_slice(&out).unwrap();
    assert_eq!(report["fit"]["passed"], true);
    assert_eq!(report["fit"]["genus"], 0);
    assert_eq!(report["fit"]["folded_triangles"], 0);
    assert!(report["loops"]["loop_edges"].as_array().unwrap().is_empty());
    assert!(report["fit"]["max_residual"].as_f64().unwrap() < 0.01);
    let model: embedding::Model =
        serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
    let atlas = charts::Atlas::new(0).unwrap();
    let layout = embedding::Layout::new(&atlas, model.settings).unwrap();
    model.validate(&layout).unwrap();
}

#[test]
fn a_missing_mesh_is_named_before_the_output_is_checked() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("model.json"), "kept").unwrap();
    ntori()
        .current_dir(dir.path())
        .args(["fit", "missing.obj"])
        .assert()
        .code(1)
        .stderr(predicate::str::contains(
            "cannot read missing.obj: no such file",
        ))
        .stderr(predicate::str::contains("exists").not());
    assert_eq!(
        std::fs::read_to_string(dir.path().join("model.json")).unwrap(),
        "kept"
    );
}
