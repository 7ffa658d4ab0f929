//! `ntori new`: writes a model that loads, refuses to overwrite, reports bad parameters clearly.

use predicates::prelude::*;

use crate::common::{ntori, ntori_json};

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
    // The torus has no flat faces to report.
    assert!(report["shape"]["flat_faces"].is_null(), "{report}");
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
        vec!["--agreement", "-0.5"],
        vec!["--agreement", "inf"],
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
    // A grid a sphere may have is refused at genus 64, at once and by its size.
    ntori()
        .args(["new", "--genus", "64", "--grid", "160", "-o"])
        .arg(&path)
        .timeout(std::time::Duration::from_secs(30))
        .assert()
        .failure()
        .stderr(predicate::str::contains(
            "a grid of 160 (1280 in the disk charts) at genus 64 makes 6553600 control points",
        ));
    assert!(!path.exists());
}

#[test]
fn a_rippled_fit_fails_its_shape_checks_though_its_residual_passes() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("coarse.json");
    // Genus 2 on an 8 × 8 grid: close to the mesh at its vertices (residual under 1%) but its
    // patches disagree by about 3% of the diagonal and its normals turn 9° at the 90th
    // percentile; topology (folds, Gauss–Bonnet) cannot see it.
    let out = ntori()
        .args(["new", "--genus", "2", "--resolution", "16", "--grid", "8"])
        .args(["--json", "-o"])
        .arg(&path)
        .assert()
        .code(3)
        .get_output()
        .stdout
        .clone();
    let report: serde_json::Value = serde_json::from_slice(&out).unwrap();
    let number = |k: &str| {
        report[k]
            .as_f64()
            .unwrap_or_else(|| panic!("{k}: {report}"))
    };
    assert!(number("max_residual") <= 0.01, "{report}");
    assert_eq!(report["folded_triangles"], 0, "{report}");
    assert!(number("curvature_error") <= 1e-3, "{report}");
    let shape = &report["shape"];
    let verdict = &report["shape_verdict"];
    assert!(
        shape["patch_disagreement"].as_f64().unwrap() > 0.01,
        "{report}"
    );
    assert_eq!(verdict["disagreement"], false, "{report}");
    assert!(
        shape["normal_deviation_p90"].as_f64().unwrap() > 5.0,
        "{report}"
    );
    assert_eq!(verdict["normals"], false, "{report}");
    assert_eq!(report["passed"], false, "{report}");
    assert!(!path.exists(), "a failed model was written");
    // The default grid on a finer mesh fits the same genus well: every shape check passes.
    let mut args: Vec<std::ffi::OsString> = ["new", "--genus", "2", "--resolution", "24", "--json"]
        .map(Into::into)
        .to_vec();
    args.extend(["-o".into(), path.clone().into()]);
    let report = ntori_json(&args);
    assert_eq!(
        report["shape_verdict"],
        serde_json::json!({"disagreement": true, "curvature": true, "normals": true, "embedded": true}),
        "{report}"
    );
}

#[test]
fn a_model_that_fails_its_checks_is_written_only_when_asked() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("flat.json");
    // So much smoothing that the fit misses the mesh: the residual check fails.
    let failing = ["new", "--genus", "0", "--resolution", "8", "--grid", "4"];
    let out = ntori()
        .args(failing)
        .args(["--smoothness", "1e6", "--json", "-o"])
        .arg(&path)
        .assert()
        .code(3)
        .get_output()
        .stdout
        .clone();
    let report: serde_json::Value = serde_json::from_slice(&out).unwrap();
    assert_eq!(report["passed"], false);
    assert!(report["max_residual"].as_f64().unwrap() > 0.01);
    assert!(!path.exists(), "a failed model was written");
    ntori()
        .args(failing)
        .args(["--smoothness", "1e6", "-o"])
        .arg(&path)
        .assert()
        .code(3)
        .stdout(
            predicate::str::contains("not written").and(predicate::str::contains("--keep-failed")),
        );
    assert!(!path.exists());
    // Asked for explicitly: written, and still exit status 3.
    ntori()
        .args(failing)
        .args(["--smoothness", "1e6", "--keep-failed", "-o"])
        .arg(&path)
        .assert()
        .code(3)
        .stdout(predicate::str::contains("wrote"));
    assert!(path.exists());
}

#[test]
fn the_default_genus_3_plate_has_fair_rims() {
    // The smoothness term in arc length (`plate_surface_smoothness`) smooths the swirls of mean
    // curvature on the rims round the holes: measured largest |κ| 1.18× the input's and normals
    // 0.22° off at the 90th percentile, against 1.32× and 0.29° with the grids' term; with the
    // rims sampled finer and smooth (`holed::RIM_REFINEMENT`, `holed::Profile::Smooth`), 1.12×
    // and 0.11°; with the rims' bands wider than the plate is thick (`holed::PLATE_BAND`), 1.13×
    // and 0.13°.
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("three.json");
    let report = ntori_json(&[
        "new".as_ref(),
        "--genus".as_ref(),
        "3".as_ref(),
        "--json".as_ref(),
        "-q".as_ref(),
        "-o".as_ref(),
        path.as_os_str(),
    ]);
    let shape = &report["shape"];
    let ratio = shape["curvature_ratio"].as_f64().unwrap();
    assert!(ratio < 1.25, "{shape}");
    // Measured against the smooth rims' own peak, 4.85 in closed form, not the mesh's estimate of
    // it (4.76 on this mesh).
    assert_eq!(shape["curvature_from"], "intended", "{shape}");
    let reference = shape["input_max_principal_curvature"].as_f64().unwrap();
    assert!((reference - 4.85).abs() < 0.005, "{shape}");
    let normals = shape["normal_deviation_p90"].as_f64().unwrap();
    assert!(normals < 0.2, "{shape}");
    assert!(
        shape["patch_disagreement"].as_f64().unwrap() < 2e-4,
        "{shape}"
    );
    // Its flat faces lie flat (issue 12: |H| times the plate's half-thickness at most 0.02 at the
    // 90th percentile; measured 0.0112 with the eased rims, 0.0067 with the smooth ones, 0.0030
    // on the wide bands).
    let flat = &shape["flat_faces"];
    let number = |k: &str| flat[k].as_f64().unwrap_or_else(|| panic!("{k}: {flat}"));
    assert!(number("vertices") > 1000.0, "{flat}");
    assert!(
        number("mean_curvature_p90_times_half_thickness") < 0.006,
        "{flat}"
    );
    assert_eq!(number("half_thickness"), 0.35, "{flat}");
    assert!(number("mean_curvature_median") <= number("mean_curvature_p90"));
    assert!(number("normal_p90") < 0.5, "{flat}");
    // And between the vertices, at the curvature quadrature's points (about a million; measured
    // 0.0017 at 90%, 0.0086 at 99.9%, 0.0142 at most, as the README shows; on the narrow bands
    // 0.0037, 0.0171 and 0.038, where the fringes at the bands' edges lifted the tail).
    let dense = &flat["dense"];
    let dense_number = |k: &str| dense[k].as_f64().unwrap_or_else(|| panic!("{k}: {dense}"));
    assert!(dense_number("points") > 100_000.0, "{dense}");
    assert!(dense_number("p90") < 0.004, "{dense}");
    assert!(dense_number("p999") < 0.015, "{dense}");
    let quantiles = ["p90", "p99", "p999", "max"].map(dense_number);
    assert!(quantiles.windows(2).all(|w| w[0] <= w[1]), "{dense}");
}

/// High genus, where the charts barely overlap: with disk charts of 128 and no agreement rows
/// `new` refused genus 28 (its largest |κ| 3.31× the input's, a ridge along a chart's fringe);
/// with disk charts of 256 and the agreement rows genus 28 read 1.81× and was written. Genus 24,
/// one of issue 12's genera, is held to its 1.5×: 1.73× with the rims sampled finer
/// (`holed::RIM_REFINEMENT`) at λ = 2e-3, 1.42× at the plates' 1e-2 (`fit::PLATE_SMOOTHNESS_UP_TO`),
/// 1.27× on the finer mesh that a budget of 300 000 triangles allows (`fit::DEFAULT_FIT_TRIANGLES`:
/// 251 246 triangles), 1.31× with its smooth rims and edge samples (`fit::PLATE_EDGE_SAMPLE_GENERA`;
/// about 47 s and 5.2 GB here in release).
#[test]
fn genus_24_passes_its_checks_within_one_and_a_half_times_the_inputs_curvature() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("twenty-four.json");
    let report = ntori_json(&[
        "new".as_ref(),
        "--genus".as_ref(),
        "24".as_ref(),
        "--json".as_ref(),
        "-q".as_ref(),
        "-o".as_ref(),
        path.as_os_str(),
    ]);
    assert!(path.exists());
    assert_eq!(
        report["agreement"].as_f64(),
        Some(0.3),
        "{}",
        report["agreement"]
    );
    assert_eq!(report["settings"]["disk_grid"].as_u64(), Some(256));
    // Every edge's sample but those along the holes' and the outer rim's circles: about three
    // per vertex.
    let (samples, vertices) = (
        report["edge_samples"].as_u64().unwrap(),
        report["mesh_vertices"].as_u64().unwrap(),
    );
    assert!(
        (5 * vertices / 2..3 * vertices).contains(&samples),
        "{samples} for {vertices}"
    );
    let shape = &report["shape"];
    let ratio = shape["curvature_ratio"].as_f64().unwrap();
    assert!(ratio < 1.5, "{shape}");
    // The patches agree within a quarter of issue 12's 0.2% of the diagonal (0.035%: the samples
    // between the vertices pull them apart a little, 0.006% without).
    assert!(
        shape["patch_disagreement"].as_f64().unwrap() < 5e-4,
        "{shape}"
    );
    // No hairlines on the flat faces between the vertices: |H| times the half-thickness at the
    // curvature quadrature's points there, 99.9th percentile by area, 0.041 (largest 0.090);
    // without the edge samples 0.140 (largest 0.476), while the vertices' 90th percentile read
    // 0.0070 even then.
    let dense = &shape["flat_faces"]["dense"];
    let p999 = dense["p999"].as_f64().unwrap_or_else(|| panic!("{dense}"));
    assert!(p999 < 0.08, "{dense}");
}

#[test]
fn the_report_measures_the_shape() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("sphere.json");
    let out = ntori()
        .args([
            "new",
            "--genus",
            "0",
            "--resolution",
            "16",
            "--grid",
            "10",
            "--json",
            "-o",
        ])
        .arg(&path)
        .assert()
        .success()
        .get_output()
        .stdout
        .clone();
    let shape = &serde_json::from_slice::<serde_json::Value>(&out).unwrap()["shape"];
    let number = |k: &str| shape[k].as_f64().unwrap_or_else(|| panic!("{k}: {shape}"));
    // The input is the unit sphere (bounding-box diagonal 2√3): a closed surface inside a ball of
    // radius R has |κ| ≥ 1/R somewhere, and the grid-10 fit is near round.
    assert!(
        (1.0..3.0).contains(&number("max_principal_curvature")),
        "{shape}"
    );
    assert!(number("normal_deviation_median") <= number("normal_deviation_p90"));
    assert!(number("normal_deviation_p90") < 10.0, "{shape}");
    // Measured against the sphere's exact normals, and the same as the library measures there.
    assert_eq!(shape["normals_from"], "intended", "{shape}");
    let surface = ntori::io::model_file::load(&path).unwrap();
    let made = embedding::fit::initial_model(
        0,
        16,
        surface.settings(),
        embedding::fit::FitSettings::default(),
    )
    .unwrap();
    let direct = embedding::quality::normal_deviation_from(
        &surface,
        &made.parameterization.points,
        &made.mesh.normals,
    );
    assert!(
        (number("normal_deviation_p90") - direct.p90).abs() < 1e-6,
        "{shape}"
    );
    // The disagreement is the library's, measured on the model as written (16×16 tessellation).
    assert!(number("patch_disagreement_rms") <= number("patch_disagreement"));
    let surface = ntori::io::model_file::load(&path).unwrap();
    let points = embedding::quality::sample_points(&surface, 16).unwrap();
    let direct = embedding::quality::patch_disagreement(&surface, &points, 0.1);
    let diagonal = 2.0 * 3f64.sqrt();
    assert!(
        (number("patch_disagreement") - direct.max / diagonal).abs() < 1e-3,
        "{shape} vs {}",
        direct.max / diagonal
    );
}

#[test]
fn the_input_mesh_is_written_for_comparison() {
    let dir = tempfile::tempdir().unwrap();
    let (model, input) = (dir.path().join("torus.json"), dir.path().join("input.obj"));
    let out = ntori()
        .args([
            "new",
            "--genus",
            "1",
            "--resolution",
            "16",
            "--grid",
            "8",
            "--json",
            "-o",
        ])
        .arg(&model)
        .arg("--input-mesh")
        .arg(&input)
        .assert()
        .success()
        .get_output()
        .stdout
        .clone();
    let report: serde_json::Value = serde_json::from_slice(&out).unwrap();
    let (obj, _) = tobj::load_obj(&input, &tobj::GPU_LOAD_OPTIONS).unwrap();
    let mesh = &obj[0].mesh;
    assert_eq!(
        mesh.positions.len() / 3,
        report["mesh_vertices"].as_u64().unwrap() as usize
    );
    assert_eq!(
        mesh.indices.len() / 3,
        report["mesh_triangles"].as_u64().unwrap() as usize
    );
    assert_eq!(mesh.texcoords.len(), mesh.positions.len() / 3 * 2);
    let topology =
        mesh::HalfEdgeMesh::from_polygons(mesh.positions.len() / 3, mesh.indices.chunks(3))
            .unwrap()
            .topology();
    assert!(topology.closed && topology.manifold && topology.orientable);
    assert_eq!(topology.euler_characteristic, 0);
    // An unknown extension is refused before the fit, and nothing is written.
    let (model2, bad) = (dir.path().join("m2.json"), dir.path().join("input.xyz"));
    ntori()
        .args(["new", "--genus", "1", "-o"])
        .arg(&model2)
        .arg("--input-mesh")
        .arg(&bad)
        .assert()
        .failure()
        .stderr(predicate::str::contains("input.xyz"));
    assert!(!model2.exists() && !bad.exists());
}
