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

/// A FIFO at `path` (through mkfifo(1), which every Unix has).
fn mkfifo(path: &Path) {
    let status = std::process::Command::new("mkfifo")
        .arg(path)
        .status()
        .unwrap();
    assert!(status.success());
}

fn is_fifo(path: &Path) -> bool {
    use std::os::unix::fs::FileTypeExt as _;
    std::fs::symlink_metadata(path)
        .unwrap()
        .file_type()
        .is_fifo()
}

#[test]
fn outputs_never_overwrite_an_input() {
    let dir = tempfile::tempdir().unwrap();
    let model = constant_model(dir.path(), 1);
    let before = std::fs::read(&model).unwrap();
    let link = dir.path().join("link.json");
    std::os::unix::fs::symlink(&model, &link).unwrap();
    for out in [&model, &link] {
        ntori()
            .arg("render")
            .arg(&model)
            .args(["--tessellation", "2", "-q", "-o"])
            .arg(out)
            .assert()
            .code(1)
            .stderr(predicate::str::contains("it is the input"))
            .stderr(predicate::str::contains(model.display().to_string()));
        ntori()
            .arg("export")
            .arg(&model)
            .args(["--format", "obj", "-o"])
            .arg(out)
            .assert()
            .code(1)
            .stderr(predicate::str::contains("it is the input"));
    }
    assert_eq!(std::fs::read(&model).unwrap(), before);
    assert!(
        std::fs::symlink_metadata(&link)
            .unwrap()
            .file_type()
            .is_symlink()
    );
}

#[test]
fn special_files_are_refused_as_outputs() {
    let dir = tempfile::tempdir().unwrap();
    let model = constant_model(dir.path(), 1);
    let fifo = dir.path().join("fifo");
    mkfifo(&fifo);
    let subdir = dir.path().join("sub");
    std::fs::create_dir(&subdir).unwrap();
    let link_to_fifo = dir.path().join("to-fifo.obj");
    std::os::unix::fs::symlink(&fifo, &link_to_fifo).unwrap();
    for (out, kind) in [
        (&fifo, "FIFO"),
        (&subdir, "directory"),
        (&link_to_fifo, "FIFO"),
    ] {
        let runs: [Vec<std::ffi::OsString>; 4] = [
            vec![
                "render".into(),
                model.clone().into(),
                "--tessellation".into(),
                "2".into(),
            ],
            vec![
                "export".into(),
                model.clone().into(),
                "--format".into(),
                "obj".into(),
            ],
            vec![
                "tessellate".into(),
                "-g".into(),
                "2".into(),
                "--svg".into(),
                out.into(),
            ],
            vec![
                "new".into(),
                "-g".into(),
                "1".into(),
                "--force".into(),
                "-q".into(),
            ],
        ];
        for mut args in runs {
            if args[0] != "tessellate" {
                args.extend(["-o".into(), out.into()]);
            }
            ntori()
                .args(&args)
                .timeout(std::time::Duration::from_secs(120))
                .assert()
                .code(1)
                .stderr(predicate::str::contains(format!("it is a {kind}")));
        }
    }
    assert!(is_fifo(&fifo));
    assert!(subdir.is_dir());
    assert!(
        std::fs::symlink_metadata(&link_to_fifo)
            .unwrap()
            .file_type()
            .is_symlink()
    );
    // /dev/null is a device: refused, whoever runs the test (as root it would have been replaced).
    ntori()
        .args(["tessellate", "-g", "2", "--svg", "/dev/null"])
        .assert()
        .code(1)
        .stderr(predicate::str::contains("it is a device"));
}

#[test]
fn outputs_write_through_symlinks() {
    let dir = tempfile::tempdir().unwrap();
    let real = dir.path().join("real");
    std::fs::create_dir(&real).unwrap();
    let target = real.join("drawing.svg");
    std::fs::write(&target, "old").unwrap();
    let link = dir.path().join("drawing.svg");
    // A relative link, resolved against the link's directory.
    std::os::unix::fs::symlink("real/drawing.svg", &link).unwrap();
    ntori()
        .args(["tessellate", "-g", "2", "--te", "1", "--tr", "1", "--svg"])
        .arg(&link)
        .assert()
        .success();
    assert!(
        std::fs::symlink_metadata(&link)
            .unwrap()
            .file_type()
            .is_symlink()
    );
    let svg = std::fs::read_to_string(&target).unwrap();
    assert!(svg.contains("<svg"), "{svg}");
    // A dangling link: its target is created.
    std::fs::remove_file(&target).unwrap();
    ntori()
        .args(["tessellate", "-g", "2", "--te", "1", "--tr", "1", "--svg"])
        .arg(&link)
        .assert()
        .success();
    assert!(std::fs::read_to_string(&target).unwrap().contains("<svg"));
    assert!(
        std::fs::symlink_metadata(&link)
            .unwrap()
            .file_type()
            .is_symlink()
    );
}

#[test]
fn new_checks_its_output_before_fitting() {
    let dir = tempfile::tempdir().unwrap();
    // This fit would take minutes (genus 8, resolution 1024); the missing directory is found first,
    // so the command ends long before the timeout.
    let out = dir.path().join("missing").join("m.json");
    ntori()
        .args(["new", "-g", "8", "--resolution", "512", "-q", "-o"])
        .arg(&out)
        .timeout(std::time::Duration::from_secs(60))
        .assert()
        .code(1)
        .stderr(predicate::str::contains("does not exist"))
        .stderr(predicate::str::contains("missing"));
    let existing = dir.path().join("m.json");
    std::fs::write(&existing, "mine").unwrap();
    ntori()
        .args(["new", "-g", "8", "--resolution", "512", "-q", "-o"])
        .arg(&existing)
        .timeout(std::time::Duration::from_secs(60))
        .assert()
        .code(1)
        .stderr(predicate::str::contains("it exists; pass --force"));
    assert_eq!(std::fs::read_to_string(&existing).unwrap(), "mine");
}
