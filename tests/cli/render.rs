//! `ntori render`: a PNG from a model file; bad arguments and files are clear errors.

use predicates::prelude::*;

use crate::common::ntori;

#[test]
fn render_writes_a_png_and_refuses_nonsense() {
    let dir = tempfile::tempdir().unwrap();
    let model = dir.path().join("m.json");
    ntori()
        .args([
            "new",
            "--genus",
            "1",
            "--resolution",
            "12",
            "--grid",
            "8",
            "-q",
            "-o",
        ])
        .arg(&model)
        .assert()
        .success();
    let png = dir.path().join("m.png");
    ntori()
        .arg("render")
        .arg(&model)
        .args([
            "--size",
            "200x150",
            "--style",
            "curvature",
            "--tessellation",
            "8",
            "-o",
        ])
        .arg(&png)
        .assert()
        .success()
        .stdout(predicate::str::contains("200×150"));
    let bytes = std::fs::read(&png).unwrap();
    assert_eq!(&bytes[1..4], b"PNG");

    for (args, message) in [
        (vec!["--size", "0x10"], "1 to 8192"),
        (vec!["--size", "big"], "WIDTHxHEIGHT"),
        (vec!["--view", "0,120,4"], "elevation"),
        (vec!["--style", "glossy"], "glossy"),
    ] {
        ntori()
            .arg("render")
            .arg(&model)
            .args(&args)
            .arg("-o")
            .arg(dir.path().join("x.png"))
            .assert()
            .code(2)
            .stderr(predicate::str::contains(message));
    }
    let missing = dir.path().join("nope.json");
    ntori()
        .arg("render")
        .arg(&missing)
        .arg("-o")
        .arg(dir.path().join("x.png"))
        .assert()
        .failure()
        .stderr(predicate::str::contains("nope.json"));
    assert!(!dir.path().join("x.png").exists());
    // An output directory that does not exist: named in the message, nothing written.
    let nowhere = dir.path().join("no-such-dir").join("x.png");
    ntori()
        .arg("render")
        .arg(&model)
        .args(["--size", "64x48", "-o"])
        .arg(&nowhere)
        .assert()
        .failure()
        .stderr(predicate::str::contains("no-such-dir"));
    // A model from a newer ntori is refused as such.
    let future = dir.path().join("future.json");
    let text = std::fs::read_to_string(&model).unwrap();
    std::fs::write(&future, text.replace("\"version\":1", "\"version\":99")).unwrap();
    ntori()
        .arg("render")
        .arg(&future)
        .arg("-o")
        .arg(dir.path().join("x.png"))
        .assert()
        .failure()
        .stderr(predicate::str::contains("future.json").and(predicate::str::contains("99")));
}
