//! `ntori export`: every format through the binary; errors that name the file, exit non-zero and
//! leave nothing behind; help that says what each format carries.

use std::path::{Path, PathBuf};
use std::sync::OnceLock;

use embedding::SplineSettings;
use predicates::prelude::*;

use crate::common::ntori;

/// A small fitted genus-2 model, as JSON text.
fn model_text() -> &'static str {
    static TEXT: OnceLock<String> = OnceLock::new();
    TEXT.get_or_init(|| serde_json::to_string(&crate::common::small_model(2).to_model()).unwrap())
}

/// A temporary directory holding `model.json`.
fn workspace() -> (tempfile::TempDir, PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let model = dir.path().join("model.json");
    std::fs::write(&model, model_text()).unwrap();
    (dir, model)
}

fn entries(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    names
}

#[test]
fn every_format_exports_through_the_binary() {
    let (dir, model) = workspace();
    let cases: [(&str, &[&str], &[u8]); 8] = [
        ("obj", &[], b"# ntori"),
        ("ply", &[], b"ply\nformat binary_little_endian 1.0\n"),
        ("ply", &["--ascii"], b"ply\nformat ascii 1.0\n"),
        ("stl", &[], b"ntori"),
        ("stl", &["--ascii"], b"solid ntori\n"),
        ("glb", &[], b"glTF\x02\0\0\0"),
        ("off", &[], b"OFF\n"),
        ("OBJ", &["--te", "4", "--tr", "8"], b"# ntori"),
    ];
    for (k, (ext, extra, magic)) in cases.iter().enumerate() {
        let out = dir.path().join(format!("surface{k}.{ext}"));
        let assert = ntori()
            .arg("export")
            .arg(&model)
            .arg("-o")
            .arg(&out)
            .args(*extra)
            .assert()
            .success()
            .stdout(predicate::str::contains("wrote").and(predicate::str::contains("genus 2")));
        let bytes = std::fs::read(&out).unwrap();
        assert!(
            bytes.starts_with(magic),
            "{ext} {extra:?}: begins {:?}",
            String::from_utf8_lossy(&bytes[..16])
        );
        let stdout = String::from_utf8_lossy(&assert.get_output().stdout).into_owned();
        // t_e = t_r = 16 by default: 4n·16² + 8n·16·31 triangles at genus 2.
        if extra.is_empty() {
            assert!(stdout.contains("9984 triangles"), "{stdout}");
        }
    }
    // --format overrides the extension; -q prints nothing.
    let out = dir.path().join("surface.mesh");
    ntori()
        .arg("export")
        .arg(&model)
        .args(["--format", "off", "-q", "-o"])
        .arg(&out)
        .assert()
        .success()
        .stdout(predicate::str::is_empty());
    assert!(std::fs::read(&out).unwrap().starts_with(b"OFF\n"));
    // Only the files asked for: no temporary files left over.
    assert_eq!(entries(dir.path()).len(), 1 + cases.len() + 1);
}

/// Runs a failing export and checks the message names `names` and nothing was written.
fn fails(args: &[&std::ffi::OsStr], names: &str, dir: &Path) {
    let before = entries(dir);
    let assert = ntori()
        .arg("export")
        .args(args)
        .assert()
        .failure()
        .stderr(predicate::str::contains(names));
    let stderr = String::from_utf8_lossy(&assert.get_output().stderr).into_owned();
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert_eq!(entries(dir), before, "{args:?} left files behind");
}

#[test]
fn errors_name_the_file_and_leave_nothing_behind() {
    let (dir, model) = workspace();
    let out = dir.path().join("out.obj");
    let os = |s: &Path| s.as_os_str().to_owned();

    // A model file that does not exist.
    let missing = dir.path().join("missing.json");
    fails(
        &[&os(&missing), "-o".as_ref(), &os(&out)],
        "missing.json",
        dir.path(),
    );
    // A file that is not JSON.
    let text = dir.path().join("notes.json");
    std::fs::write(&text, "these are notes, not a model").unwrap();
    fails(
        &[&os(&text), "-o".as_ref(), &os(&out)],
        "notes.json is not a JSON file",
        dir.path(),
    );
    // JSON, but not a model.
    let other = dir.path().join("other.json");
    std::fs::write(&other, r#"{"name": "something else"}"#).unwrap();
    fails(
        &[&os(&other), "-o".as_ref(), &os(&out)],
        "other.json is not an ntori model",
        dir.path(),
    );
    // A model from a newer ntori.
    let future = dir.path().join("future.json");
    let text99 = model_text().replace("\"version\":1", "\"version\":99");
    assert_ne!(text99, model_text());
    std::fs::write(&future, text99).unwrap();
    fails(
        &[&os(&future), "-o".as_ref(), &os(&out)],
        "future.json was written by a newer ntori",
        dir.path(),
    );
    // A model whose control points do not match its settings.
    let short = dir.path().join("short.json");
    let mut value: serde_json::Value = serde_json::from_str(model_text()).unwrap();
    value["control_points"].as_array_mut().unwrap().pop();
    std::fs::write(&short, value.to_string()).unwrap();
    fails(
        &[&os(&short), "-o".as_ref(), &os(&out)],
        "short.json is not a consistent ntori model",
        dir.path(),
    );
    // An output in a directory that does not exist.
    let nowhere = dir.path().join("no/such/dir/out.obj");
    fails(
        &[&os(&model), "-o".as_ref(), &os(&nowhere)],
        "out.obj",
        dir.path(),
    );
    // An extension that names no format.
    let unknown = dir.path().join("out.xyz");
    fails(
        &[&os(&model), "-o".as_ref(), &os(&unknown)],
        "out.xyz has no known extension",
        dir.path(),
    );
    // Resolutions out of range.
    for args in [
        ["--te", "0"],
        ["--tr", "0"],
        ["--te", "513"],
        ["--tr", "-1"],
    ] {
        let mut all = vec![os(&model), "-o".into(), os(&out)];
        all.extend(args.iter().map(Into::into));
        let refs: Vec<&std::ffi::OsStr> = all.iter().map(|s| s.as_os_str()).collect();
        fails(&refs, args[0], dir.path());
    }
    // --ascii where the format has no text variant.
    fails(
        &[&os(&model), "-o".as_ref(), &os(&out), "--ascii".as_ref()],
        "--ascii applies to PLY and STL",
        dir.path(),
    );
    // The model file itself as the output.
    fails(
        &[
            &os(&model),
            "-o".as_ref(),
            &os(&model),
            "--format".as_ref(),
            "obj".as_ref(),
        ],
        "it is the input",
        dir.path(),
    );
    assert_eq!(std::fs::read_to_string(&model).unwrap(), model_text());
}

#[test]
fn too_many_triangles_are_refused_before_any_work() {
    let dir = tempfile::tempdir().unwrap();
    // A genus-64 model need not be fitted to be refused: the count comes from t_e and t_r alone,
    // checked right after the model is read. Build a consistent (constant) genus-64 model.
    let atlas = std::sync::Arc::new(charts::Atlas::new(64).unwrap());
    let count = embedding::Layout::new(&atlas, SplineSettings::default())
        .unwrap()
        .control_count();
    let control = vec![embedding::Point3::origin(); count];
    let model = embedding::Surface::new(atlas, SplineSettings::default(), control).unwrap();
    let path = dir.path().join("big.json");
    ntori::io::model_file::save(&path, &model).unwrap();
    let out = dir.path().join("big.stl");
    // "Before any work" shows in the message (the count, from t_e and t_r alone); the timeout only
    // catches a run that meshes 10⁸ triangles, with room for a slow, shared machine (a tight
    // wall-clock bound is what fails when other jobs load the machine).
    ntori()
        .arg("export")
        .arg(&path)
        .args(["--te", "512", "--tr", "512", "-o"])
        .arg(&out)
        .timeout(std::time::Duration::from_secs(300))
        .assert()
        .failure()
        .stderr(predicate::str::contains("triangles").and(predicate::str::contains("lower t_e")));
    assert!(!out.exists());
}

#[test]
fn a_failed_export_keeps_the_existing_file() {
    let (dir, _model) = workspace();
    let out = dir.path().join("out.obj");
    std::fs::write(&out, "an earlier export").unwrap();
    ntori()
        .arg("export")
        .arg(dir.path().join("missing.json"))
        .arg("-o")
        .arg(&out)
        .assert()
        .failure();
    assert_eq!(std::fs::read_to_string(&out).unwrap(), "an earlier export");
}

#[test]
fn help_says_what_each_format_carries() {
    ntori()
        .args(["export", "--help"])
        .assert()
        .success()
        .stdout(
            predicate::str::contains(".obj")
                .and(predicate::str::contains(".ply"))
                .and(predicate::str::contains(".stl"))
                .and(predicate::str::contains(".glb"))
                .and(predicate::str::contains(".off"))
                .and(predicate::str::contains("_CHART"))
                .and(predicate::str::contains("TEXCOORD_0"))
                .and(predicate::str::contains("face normal"))
                .and(predicate::str::contains("--ascii"))
                .and(predicate::str::contains("--te")),
        );
    ntori()
        .arg("--help")
        .assert()
        .success()
        .stdout(predicate::str::contains("export"));
}
