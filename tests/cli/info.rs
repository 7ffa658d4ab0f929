//! `ntori info` end to end: the binary as a user runs it.

use predicates::prelude::*;

use crate::common::{ntori, ntori_json};

#[test]
fn default_info_describes_genus_two_and_passes_its_self_check() {
    ntori()
        .args(["info", "--points", "5000"])
        .assert()
        .success()
        .stdout(predicate::str::contains("genus 2"))
        .stdout(predicate::str::contains(
            "corners around the vertex: 0 → 3 → 6 → 5 → 4 → 7 → 2 → 1",
        ))
        .stdout(predicate::str::contains("passed"));
}

#[test]
fn json_reports_every_supported_kind_of_genus() {
    for genus in ["0", "1", "2", "7"] {
        let v = ntori_json(&["info", "--json", "--points", "3000", "--genus", genus]);
        let n: u64 = genus.parse().unwrap();
        assert_eq!(v["genus"], n);
        assert_eq!(
            v["charts"].as_array().unwrap().len() as u64,
            if n == 0 { 2 } else { 2 * n + 2 }
        );
        assert_eq!(v["self_check"]["passed"], true);
        assert!(v["self_check"]["coverage"]["min_margin"].as_f64().unwrap() > 0.02);
        assert!(
            v["self_check"]["consistency"]["cocycle_error"]
                .as_f64()
                .unwrap()
                <= 1e-12
        );
    }
}

#[test]
fn unsupported_genus_is_a_clear_error() {
    ntori()
        .args(["info", "--genus", "65"])
        .assert()
        .code(2)
        .stderr(predicate::str::contains("genus 65 is not supported"))
        .stderr(predicate::str::contains("panicked").not());
}

#[test]
fn nonsense_arguments_are_usage_errors() {
    for args in [
        &["info", "--genus", "-1"][..],
        &["info", "--genus", "two"],
        &["info", "--points", "0"],
        &["frobnicate"],
    ] {
        ntori()
            .args(args)
            .assert()
            .code(2)
            .stderr(predicate::str::contains("error"))
            .stderr(predicate::str::contains("panicked").not());
    }
}

#[test]
fn help_explains_the_terms() {
    ntori()
        .args(["info", "--help"])
        .assert()
        .success()
        .stdout(predicate::str::contains("coverage margin"))
        .stdout(predicate::str::contains("cocycle"))
        .stdout(predicate::str::contains("γ"));
}
