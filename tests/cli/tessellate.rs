//! `ntori tessellate` end to end.

use predicates::prelude::*;

use crate::common::{ntori, ntori_json};

#[test]
fn reports_counts_and_checks_as_json() {
    for (genus, te, tr) in [(0, 2, 2), (1, 3, 1), (2, 1, 1), (3, 4, 2)] {
        let v = ntori_json(&[
            "tessellate",
            "--json",
            "--genus",
            &genus.to_string(),
            "--te",
            &te.to_string(),
            "--tr",
            &tr.to_string(),
        ]);
        assert_eq!(v["euler_characteristic"], 2 - 2 * genus);
        assert_eq!(v["topology"]["genus"], genus);
        assert_eq!(v["topology"]["components"], 1);
        assert_eq!(v["vertices"], v["expected_vertices"]);
        assert_eq!(v["faces"], v["expected_faces"]);
        assert_eq!(v["passed"], true);
    }
}

#[test]
fn draws_an_svg_of_the_polygon() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("figure7.svg");
    ntori()
        .args([
            "tessellate",
            "--genus",
            "2",
            "--te",
            "2",
            "--tr",
            "2",
            "--svg",
        ])
        .arg(&path)
        .assert()
        .success()
        .stdout(predicate::str::contains("χ = V − E + F = -2"));
    let svg = std::fs::read_to_string(&path).unwrap();
    assert!(svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"));
    // One filled path per triangle at least (triangles across the polygon's edges are drawn twice).
    assert!(svg.matches("<path d=").count() >= 4 * 2 * 2 * 2 * 2 + 2 * 8 * 2 * 3);
    // Nothing left behind but the figure.
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
}

#[test]
fn an_unwritable_path_is_a_clear_error() {
    ntori()
        .args(["tessellate", "--svg", "/nonexistent-dir/x.svg"])
        .assert()
        .code(1)
        .stderr(predicate::str::contains(
            "cannot write /nonexistent-dir/x.svg",
        ));
}

#[test]
fn impossible_resolutions_are_errors() {
    for args in [
        ["--te", "0"],
        ["--tr", "0"],
        ["--te", "5000"],
        ["--te", "-2"],
    ] {
        let assert = ntori().arg("tessellate").args(args).assert();
        let out = assert.get_output();
        assert!(!out.status.success(), "{args:?}");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(
            err.contains("error") && !err.contains("panicked"),
            "{args:?}: {err}"
        );
    }
}
