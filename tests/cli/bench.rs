//! `ntori bench` prints well-formed JSON with positive, finite figures.

use predicates::prelude::*;

use crate::common::{ntori, ntori_json};

#[test]
fn bench_prints_json_figures() {
    let v = ntori_json(&["bench", "--quiet", "--vertices", "3000", "--genus", "3"]);
    assert!(v["copy_bandwidth_bytes_per_second"].as_f64().unwrap() > 1e8);
    assert!(
        v["copy_bandwidth_all_cores_bytes_per_second"]
            .as_f64()
            .unwrap()
            > 1e8
    );
    assert!(v["threads"].as_u64().unwrap() >= 1);
    let figures = v["figures"].as_array().unwrap();
    let names: Vec<&str> = figures
        .iter()
        .map(|f| f["name"].as_str().unwrap())
        .collect();
    assert_eq!(
        names,
        [
            "tessellate",
            "locate_chart_point",
            "stencil_build",
            "stencil_build_full",
            "stencil_build_full_all_cores",
            "reembed",
            "reembed_all_cores",
            "reembed_full_f64",
            "stencil_build_tangents",
            "reembed_tangents",
            "reembed_tangents_portable",
            "reembed_tangents_all_cores",
            "reembed_tangents_full_f64",
            "drag_event"
        ]
    );
    assert!(
        v.get("gpu_adapter").is_none(),
        "no GPU figures unless asked"
    );
    for f in figures {
        let rate = f["per_second"].as_f64().unwrap();
        assert!(rate.is_finite() && rate > 0.0, "{f}");
    }
    for f in figures[5..8].iter().chain(&figures[9..13]) {
        let fraction = f["fraction_of_copy_bandwidth"].as_f64().unwrap();
        assert!(
            fraction > 0.0 && fraction < 5.0,
            "re-embedding cannot beat memory by much: {f}"
        );
    }
}

/// With `--gpu` (lavapipe in CI): the GPU's figures, its adapter, and its results against the CPU's.
#[test]
fn bench_on_the_gpu_agrees_with_the_cpu() {
    let v = ntori_json(&["bench", "--quiet", "--vertices", "3000", "--gpu"]);
    assert!(!v["gpu_adapter"].as_str().unwrap().is_empty());
    let agreement = &v["gpu_agreement"];
    assert!(agreement["position_of_diagonal"].as_f64().unwrap() <= 1e-6);
    assert!(agreement["tangent_of_largest"].as_f64().unwrap() <= 1e-5);
    let gpu: Vec<&serde_json::Value> = v["figures"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|f| f["name"].as_str().unwrap().contains("gpu"))
        .collect();
    let names: Vec<&str> = gpu.iter().map(|f| f["name"].as_str().unwrap()).collect();
    assert_eq!(
        names,
        [
            "reembed_gpu",
            "reembed_gpu_tangents",
            "reembed_gpu_tangents_round_trip"
        ]
    );
    for f in gpu {
        assert!(f["per_second"].as_f64().unwrap() > 0.0, "{f}");
    }
}

#[test]
fn bench_refuses_absurd_sizes() {
    ntori().args(["bench", "--vertices", "0"]).assert().code(2);
    // A genus beyond the charts' 64 is a usage error, as a negative one is.
    ntori()
        .args(["bench", "--genus", "99", "--quiet"])
        .assert()
        .code(2)
        .stderr(predicate::str::contains("genus 99 is not supported"));
}
