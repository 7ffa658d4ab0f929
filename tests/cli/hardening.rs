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
    let model = Model::constant(&layout, embedding::Point3::origin());
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
            "vertex buffer would take 31388073984 bytes",
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
    // The link's target exists: it is refused without --force, and replaced with it.
    ntori()
        .args(["tessellate", "-g", "2", "--te", "1", "--tr", "1", "--svg"])
        .arg(&link)
        .assert()
        .code(1)
        .stderr(predicate::str::contains("it exists; pass --force"));
    assert_eq!(std::fs::read_to_string(&target).unwrap(), "old");
    ntori()
        .args(["tessellate", "-g", "2", "--te", "1", "--tr", "1"])
        .args(["--force", "--svg"])
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

/// A small valid model's JSON, as a tree to break.
fn model_json(dir: &Path) -> serde_json::Value {
    let path = constant_model(dir, 1);
    let mut value: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    // Points that differ, so the surface is not degenerate.
    for (i, p) in value["control_points"]
        .as_array_mut()
        .unwrap()
        .iter_mut()
        .enumerate()
    {
        p[0] = (i as f64).into();
    }
    value
}

#[test]
fn bad_model_files_get_one_clear_message() {
    let dir = tempfile::tempdir().unwrap();
    let good = model_json(dir.path());
    let text = serde_json::to_string(&good).unwrap();
    let edit = |f: &dyn Fn(&mut serde_json::Value)| {
        let mut v = good.clone();
        f(&mut v);
        serde_json::to_string(&v).unwrap()
    };
    let cases: Vec<(&str, String, &str)> = vec![
        (
            "null.json",
            edit(&|v| v["control_points"][17][1] = serde_json::Value::Null),
            "control_points[17].y: invalid type: null, expected f64 (line 1, column",
        ),
        (
            "unknown.json",
            edit(&|v| v["colour"] = "red".into()),
            "unknown field `colour`",
        ),
        (
            "version0.json",
            edit(&|v| v["version"] = 0.into()),
            "its version is 0",
        ),
        (
            "duplicate.json",
            text.replacen("{\"", "{\"genus\":3,\"", 1),
            "duplicate field `genus`",
        ),
        (
            "huge-string.json",
            edit(&|v| v["genus"] = "y".repeat(1_000_000).into()),
            "… (1000000 characters)",
        ),
        (
            "truncated.json",
            text[..100].to_owned(),
            "is not a JSON file: invalid number (line 1, column 100)",
        ),
    ];
    for (name, contents, expected) in cases {
        let path = dir.path().join(name);
        std::fs::write(&path, contents).unwrap();
        let out = ntori()
            .arg("export")
            .arg(&path)
            .args(["-o"])
            .arg(dir.path().join("x.obj"))
            .assert()
            .code(1)
            .stderr(predicate::str::contains(expected))
            .stderr(predicate::str::contains("panicked").not());
        let stderr = String::from_utf8_lossy(&out.get_output().stderr).into_owned();
        assert!(
            stderr.len() < 600,
            "{name}: a short message, got {} bytes",
            stderr.len()
        );
        assert_eq!(
            stderr.matches(name).count(),
            1,
            "{name}: the file once: {stderr}"
        );
    }
}

#[test]
fn model_inputs_must_be_regular_files_of_bounded_size() {
    let dir = tempfile::tempdir().unwrap();
    let fifo = dir.path().join("fifo.json");
    mkfifo(&fifo);
    let out = dir.path().join("x.obj");
    // Each would block or read forever if opened: refused from the file's type and size alone.
    for (input, expected) in [
        (fifo.as_path(), "it is a FIFO"),
        (Path::new("/dev/zero"), "it is a device"),
        (dir.path(), "it is a directory"),
    ] {
        ntori()
            .arg("export")
            .arg(input)
            .arg("-o")
            .arg(&out)
            .timeout(std::time::Duration::from_secs(60))
            .assert()
            .code(1)
            .stderr(predicate::str::contains(expected));
    }
    // A sparse file just past the cap: refused before a byte is read.
    let big = dir.path().join("big.json");
    let file = std::fs::File::create(&big).unwrap();
    file.set_len(ntori::io::model_file::MAX_MODEL_BYTES + 1)
        .unwrap();
    ntori()
        .arg("render")
        .arg(&big)
        .arg("-o")
        .arg(dir.path().join("x.png"))
        .timeout(std::time::Duration::from_secs(60))
        .assert()
        .code(1)
        .stderr(predicate::str::contains(format!(
            "a model file may have at most {}",
            ntori::io::model_file::MAX_MODEL_BYTES
        )));
}

#[test]
fn sizes_beyond_the_memory_caps_are_refused_before_any_work() {
    // tessellate: genus 2 at t_e = 1000 would take 3.4 GB.
    ntori()
        .args(["tessellate", "-g", "2", "--te", "1000"])
        .timeout(std::time::Duration::from_secs(60))
        .assert()
        .code(1)
        .stderr(predicate::str::contains(
            "genus 2 at t_e = 1000, t_r = 4 makes 8368000 triangles, about 4.7 GB",
        ))
        .stderr(predicate::str::contains("at most 4000000 triangles"));
    // new: genus 8 at resolution 1024 ran 15 minutes to 10.9 GB; now refused while meshing.
    let dir = tempfile::tempdir().unwrap();
    ntori()
        .args(["new", "-g", "8", "--resolution", "1024", "-q", "-o"])
        .arg(dir.path().join("m.json"))
        .timeout(std::time::Duration::from_secs(120))
        .assert()
        .code(1)
        .stderr(predicate::str::contains("makes more than"))
        .stderr(predicate::str::contains("lower the resolution"));
    assert!(!dir.path().join("m.json").exists());
    // render: genus 64 at T = 64 is 5.2 million triangles (within the buffer cap, over the
    // triangle cap; a device with less than 750 MB per buffer says so first).
    let model = constant_model(dir.path(), 64);
    ntori()
        .arg("render")
        .arg(&model)
        .args(["--tessellation", "64", "-q", "-o"])
        .arg(dir.path().join("m.png"))
        .timeout(std::time::Duration::from_secs(120))
        .assert()
        .code(1)
        .stderr(
            predicate::str::contains(
                "makes 13598720 triangles; a picture may have at most 4000000",
            )
            .or(predicate::str::contains("max_buffer_size")),
        );
}

/// The small fitted torus with every control point multiplied by `scale` (and point 0 moved to
/// `outlier` where given), written to `dir/name`.
fn scaled_model(dir: &Path, name: &str, scale: f64, outlier: Option<f64>) -> std::path::PathBuf {
    let mut model = crate::common::small_model(1).to_model();
    for p in &mut model.control_points {
        *p = p.map(|x| x * scale);
    }
    if let Some(o) = outlier {
        model.control_points[0] = [o, o, o];
    }
    let path = dir.join(name);
    std::fs::write(&path, serde_json::to_string(&model).unwrap()).unwrap();
    path
}

#[test]
fn numbers_that_do_not_survive_f32_are_refused_not_written() {
    let dir = tempfile::tempdir().unwrap();
    // Models beyond ±1e9 (embedding::model::MAX_COORDINATE) are refused when they are read.
    let huge = scaled_model(dir.path(), "huge.json", 1e39, None);
    let outlier = scaled_model(dir.path(), "outlier.json", 1.0, Some(1e155));
    let tiny = scaled_model(dir.path(), "tiny.json", 1e-46, None);
    let fine = scaled_model(dir.path(), "fine.json", 1.0, None);
    for ext in ["obj", "ply", "stl", "glb", "3mf", "off"] {
        let out = dir.path().join(format!("m.{ext}"));
        for (model, scale, expected) in [
            (&huge, "1", "beyond the ±1e9 a model may hold"),
            (&outlier, "1", "control point 0 has a coordinate of 1e155"),
            (&tiny, "1", "below what the 32-bit floats"),
            // A scale (times the unit) past f32's range, or below its resolution.
            (&fine, "1e42", "beyond the 32-bit floats"),
            (&fine, "1e-44", "below what the 32-bit floats"),
        ] {
            ntori()
                .arg("export")
                .arg(model)
                .args(["--te", "4", "--tr", "4", "-q", "--scale", scale, "-o"])
                .arg(&out)
                .assert()
                .code(1)
                .stderr(predicate::str::contains(expected));
            assert!(!out.exists(), "{ext}: nothing written");
        }
        // The same surface at a sane scale exports.
        ntori()
            .arg("export")
            .arg(&fine)
            .args(["--te", "4", "--tr", "4", "-q", "-o"])
            .arg(&out)
            .assert()
            .success();
    }
    let png = dir.path().join("m.png");
    let constant = constant_model(dir.path(), 1);
    for (model, expected) in [
        (&huge, "beyond the ±1e9 a model may hold"),
        (&tiny, "below what the GPU's 32-bit floats"),
        (&constant, "the surface is degenerate"),
    ] {
        ntori()
            .arg("render")
            .arg(model)
            .args(["--size", "64x48", "--tessellation", "4", "-q", "-o"])
            .arg(&png)
            .assert()
            .code(1)
            .stderr(predicate::str::contains(expected));
        assert!(!png.exists());
    }
}

#[test]
fn messages_are_plain_and_said_once() {
    let dir = tempfile::tempdir().unwrap();
    // -1 is refused as a genus, not with u32's range.
    ntori()
        .args(["info", "--genus", "-1"])
        .assert()
        .code(2)
        .stderr(predicate::str::contains(
            "a genus is 0 or more (0 to 64), got -1",
        ))
        .stderr(predicate::str::contains("4294967295").not());
    // An absurd smoothness is an argument error, not "the edit's constraints could not be solved".
    ntori()
        .args(["new", "-g", "1", "--smoothness", "1e308", "-q", "-o"])
        .arg(dir.path().join("m.json"))
        .assert()
        .code(2)
        .stderr(predicate::str::contains(
            "the smoothness weight must lie in (0, 1e6]",
        ));
    // A model whose count is wrong: the cause (from the embedding crate) appears once.
    let mut model = crate::common::small_model(1).to_model();
    model.control_points.pop();
    let path = dir.path().join("short.json");
    std::fs::write(&path, serde_json::to_string(&model).unwrap()).unwrap();
    let out = ntori()
        .arg("export")
        .arg(&path)
        .arg("-o")
        .arg(dir.path().join("m.obj"))
        .assert()
        .code(1)
        .get_output()
        .stderr
        .clone();
    let text = String::from_utf8(out).unwrap();
    assert_eq!(
        text.matches("control points, its settings need").count(),
        1,
        "{text}"
    );
    // Log lines to a pipe carry no colour codes.
    let out = ntori()
        .args([
            "-v",
            "tessellate",
            "-g",
            "2",
            "--te",
            "1",
            "--tr",
            "1",
            "--svg",
        ])
        .arg(dir.path().join("t.svg"))
        .assert()
        .success()
        .get_output()
        .stderr
        .clone();
    let text = String::from_utf8(out).unwrap();
    assert!(text.contains("wrote the drawing"), "{text}");
    assert!(!text.contains('\u{1b}'), "escape codes in {text:?}");
}

#[test]
fn render_without_a_runtime_directory_prints_nothing_when_quiet() {
    let dir = tempfile::tempdir().unwrap();
    let model = scaled_model(dir.path(), "m.json", 1.0, None);
    ntori()
        .env_remove("XDG_RUNTIME_DIR")
        .env_remove("WAYLAND_DISPLAY")
        .arg("render")
        .arg(&model)
        .args(["--size", "64x48", "--tessellation", "4", "-q", "-o"])
        .arg(dir.path().join("m.png"))
        .assert()
        .success()
        .stdout("")
        .stderr("");
}

/// The fixtures `docs/bad-inputs.md` names (`$NAME`), made in `dir`.
fn bad_input_fixtures(dir: &Path) -> Vec<(String, std::path::PathBuf)> {
    let model = scaled_model(dir, "model.json", 1.0, None);
    let good: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&model).unwrap()).unwrap();
    let text = serde_json::to_string(&good).unwrap();
    let variant = |name: &str, contents: String| {
        let path = dir.join(name);
        std::fs::write(&path, contents).unwrap();
        path
    };
    let edit = |name: &str, f: &dyn Fn(&mut serde_json::Value)| {
        let mut v = good.clone();
        f(&mut v);
        variant(name, serde_json::to_string(&v).unwrap())
    };
    let fifo = dir.join("fifo");
    mkfifo(&fifo);
    let big = dir.join("big.json");
    std::fs::File::create(&big)
        .unwrap()
        .set_len(ntori::io::model_file::MAX_MODEL_BYTES + 1)
        .unwrap();
    let constant64 = constant_model(dir, 64);
    let constant = constant_model(dir, 1);
    let meshes = mesh_fixtures(dir);
    let mut fixtures: Vec<(String, std::path::PathBuf)> = vec![
        ("MODEL".into(), model),
        ("CONSTANT64".into(), constant64),
        ("CONSTANT".into(), constant),
        ("HUGE".into(), scaled_model(dir, "huge.json", 1e39, None)),
        (
            "ABSURD".into(),
            edit("absurd.json", &|v| {
                v["control_points"][17][1] = 1e300.into()
            }),
        ),
        ("TINY".into(), scaled_model(dir, "tiny.json", 1e-46, None)),
        (
            "NULL".into(),
            edit("null.json", &|v| {
                v["control_points"][17][1] = serde_json::Value::Null
            }),
        ),
        (
            "UNKNOWN".into(),
            edit("unknown.json", &|v| v["colour"] = "red".into()),
        ),
        (
            "DUPLICATE".into(),
            variant("duplicate.json", text.replacen("{\"", "{\"genus\":3,\"", 1)),
        ),
        (
            "VERSION0".into(),
            edit("version0.json", &|v| v["version"] = 0.into()),
        ),
        (
            "FUTURE".into(),
            edit("future.json", &|v| v["version"] = 99.into()),
        ),
        (
            "PIN_CHART".into(),
            edit("pin-chart.json", &|v| {
                v["version"] = 2.into();
                v["pins"] = serde_json::json!([{"chart": 0, "at": [0.0, 0.0]}, {"chart": 4000, "at": [0.0, 0.0]}]);
            }),
        ),
        (
            "PIN_OUTSIDE".into(),
            edit("pin-outside.json", &|v| {
                v["version"] = 2.into();
                v["pins"] = serde_json::json!([{"chart": 0, "at": [7.0, 0.0]}]);
            }),
        ),
        (
            "PIN_VERSION1".into(),
            edit("pin-version1.json", &|v| {
                v["pins"] = serde_json::json!([{"chart": 0, "at": [0.0, 0.0]}]);
            }),
        ),
        (
            "DISK_GRID_VERSION1".into(),
            edit("disk-grid-version1.json", &|v| {
                v["settings"]["disk_grid"] = 8.into();
            }),
        ),
        (
            "LONG_STRING".into(),
            edit("long.json", &|v| v["genus"] = "y".repeat(1_000_000).into()),
        ),
        (
            "SHORT".into(),
            edit("short.json", &|v| {
                v["control_points"].as_array_mut().unwrap().pop();
            }),
        ),
        (
            "TRUNCATED".into(),
            variant("truncated.json", text[..100].to_owned()),
        ),
        ("BIG".into(), big),
        ("FIFO".into(), fifo),
        ("OUT".into(), dir.join("out")),
        ("DIR".into(), dir.to_path_buf()),
    ];
    fixtures.extend(meshes);
    fixtures
}

// ------------------------------------------------------------------- meshes for `ntori fit`

/// A tetrahedron: its corners and its triangles (outward).
const TETRA_POINTS: [[f64; 3]; 4] = [
    [0.0, 0.0, 0.0],
    [1.0, 0.0, 0.0],
    [0.0, 1.0, 0.0],
    [0.0, 0.0, 1.0],
];
const TETRA: [[u32; 3]; 4] = [[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]];

/// A mesh as positions and triangles (vertex indices from 0).
type Mesh = (Vec<[f64; 3]>, Vec<[u32; 3]>);

/// OBJ text of a mesh, coordinates rounded to 4 decimals (so messages quote short numbers).
fn obj_text((positions, triangles): &Mesh) -> String {
    let mut text = String::new();
    for p in positions {
        let [x, y, z] = p.map(|c| (c * 1e4).round() / 1e4 + 0.0);
        text += &format!("v {x} {y} {z}\n");
    }
    for t in triangles {
        text += &format!("f {} {} {}\n", t[0] + 1, t[1] + 1, t[2] + 1);
    }
    text
}

/// A grid of n × m vertices over the square [0, 2π)², each quad cut in two; `vertex(i, j)` gives
/// the index of grid point (i, j) for i in 0..=n, j in 0..=m (so the caller says how the sides are
/// glued), `position(u, v)` the point.
fn glued_grid(
    n: u32,
    m: u32,
    vertex: impl Fn(u32, u32) -> u32,
    position: impl Fn(f64, f64) -> [f64; 3],
) -> Mesh {
    let tau = std::f64::consts::TAU;
    let positions = (0..n)
        .flat_map(|i| (0..m).map(move |j| (i, j)))
        .map(|(i, j)| {
            position(
                tau * f64::from(i) / f64::from(n),
                tau * f64::from(j) / f64::from(m),
            )
        })
        .collect();
    let mut triangles = Vec::new();
    for i in 0..n {
        for j in 0..m {
            let (a, b, c, d) = (
                vertex(i, j),
                vertex(i + 1, j),
                vertex(i + 1, j + 1),
                vertex(i, j + 1),
            );
            triangles.extend([[a, b, c], [a, c, d]]);
        }
    }
    (positions, triangles)
}

/// A torus of 8 × 6 vertices (96 triangles, radii 2 and 1): a valid genus-1 mesh.
fn torus() -> Mesh {
    let (n, m) = (8, 6);
    glued_grid(
        n,
        m,
        |i, j| (i % n) * m + j % m,
        |u, v| {
            let w = 2.0 + v.cos();
            [w * u.cos(), w * u.sin(), v.sin()]
        },
    )
}

/// A Klein bottle (the figure-8 immersion, 12 × 8 vertices): closed and manifold, but going once
/// round in u turns the tube over (v → −v), so its faces cannot agree on a side.
fn klein_bottle() -> Mesh {
    let (n, m) = (12, 8);
    let vertex = move |i: u32, j: u32| {
        if i == n {
            (m - j % m) % m
        } else {
            i * m + j % m
        }
    };
    glued_grid(n, m, vertex, |u, v| {
        let v = v + 0.3;
        let w = 3.0 + (u / 2.0).cos() * v.sin() - (u / 2.0).sin() * (2.0 * v).sin();
        [
            w * u.cos(),
            w * u.sin(),
            (u / 2.0).sin() * v.sin() + (u / 2.0).cos() * (2.0 * v).sin(),
        ]
    })
}

/// Binary STL of triangles given by their corners, after an 80-byte header that begins with
/// `header`.
fn binary_stl(header: &[u8], triangles: &[[[f32; 3]; 3]]) -> Vec<u8> {
    let mut bytes = header.to_vec();
    bytes.resize(80, 0);
    bytes.extend((triangles.len() as u32).to_le_bytes());
    for t in triangles {
        bytes.extend([0u8; 12]);
        for c in t.iter().flatten() {
            bytes.extend(c.to_le_bytes());
        }
        bytes.extend([0u8; 2]);
    }
    bytes
}

/// The mesh files docs/bad-inputs.md's section on `ntori fit` names (`$MESH_…`), made in `dir`.
fn mesh_fixtures(dir: &Path) -> Vec<(String, std::path::PathBuf)> {
    let file = |name: &str, contents: &[u8]| {
        let path = dir.join(name);
        std::fs::write(&path, contents).unwrap();
        path
    };
    let tetra: Mesh = (TETRA_POINTS.to_vec(), TETRA.to_vec());
    let (torus_points, torus_triangles) = torus();
    // Two tetrahedra sharing the edge from vertex 0 to vertex 1 (four faces on it).
    let fin: Mesh = (
        [&TETRA_POINTS[..], &[[0.0, -1.0, 0.0], [0.0, 0.0, -1.0]]].concat(),
        [&TETRA[..], &[[0, 1, 4], [0, 5, 1], [1, 5, 4], [0, 4, 5]]].concat(),
    );
    // Two square pyramids (closed), their tips at vertex 0.
    let cones: Mesh = (
        vec![
            [0.0, 0.0, 0.0],
            [-1.0, -1.0, 1.0],
            [1.0, -1.0, 1.0],
            [1.0, 1.0, 1.0],
            [-1.0, 1.0, 1.0],
            [-1.0, -1.0, -1.0],
            [1.0, -1.0, -1.0],
            [1.0, 1.0, -1.0],
            [-1.0, 1.0, -1.0],
        ],
        vec![
            [0, 2, 1],
            [0, 3, 2],
            [0, 4, 3],
            [0, 1, 4],
            [1, 2, 3],
            [1, 3, 4],
            [0, 5, 6],
            [0, 6, 7],
            [0, 7, 8],
            [0, 8, 5],
            [5, 7, 6],
            [5, 8, 7],
        ],
    );
    // The torus less two triangles far apart: two holes.
    let mut open = torus();
    open.1.remove(40);
    open.1.remove(0);
    // The torus and, apart from it, a tetrahedron.
    let two: Mesh = (
        [
            &torus_points[..],
            &TETRA_POINTS.map(|p| [p[0] + 9.0, p[1], p[2]])[..],
        ]
        .concat(),
        [
            &torus_triangles[..],
            &TETRA.map(|t| t.map(|v| v + torus_points.len() as u32))[..],
        ]
        .concat(),
    );
    // The torus with one more triangle, whose vertex repeats.
    let mut sliver = torus();
    sliver.1.push([0, 0, 1]);
    // A tetrahedron whose corners lie on a line: every triangle has zero area.
    let flat: Mesh = (
        (0..4).map(|k| [f64::from(k), 0.0, 0.0]).collect(),
        TETRA.to_vec(),
    );
    let tetra_corners: Vec<[[f32; 3]; 3]> = tetra
        .1
        .iter()
        .map(|t| t.map(|v| tetra.0[v as usize].map(|c| c as f32)))
        .collect();
    let mut infinite = tetra_corners.clone();
    infinite[1][1][1] = f32::INFINITY;
    let stl = binary_stl(b"binary", &tetra_corners);
    let solid_stl = binary_stl(b"solid exported by a tool", &tetra_corners);
    let three = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
    let mesh_dir = dir.join("dir.obj");
    std::fs::create_dir(&mesh_dir).unwrap();
    let big = dir.join("big.stl");
    std::fs::File::create(&big)
        .unwrap()
        .set_len(ntori::io::import::MAX_MESH_BYTES + 1)
        .unwrap();
    let mut glb = b"glTF".to_vec();
    for word in [2u32, 4000, 20, 0x4E4F_534A] {
        glb.extend(word.to_le_bytes());
    }
    glb.extend(b"{\"asset\":{\"version\"");
    let mut no_magic = glb.clone();
    no_magic[3] = b'X';
    [
        ("TORUS", file("torus.obj", obj_text(&torus()).as_bytes())),
        ("DIR", mesh_dir),
        ("BIG", big),
        ("EMPTY", file("empty.stl", b"")),
        ("UNKNOWN", file("torus.3ds", obj_text(&torus()).as_bytes())),
        (
            "NUMBER",
            file("number.obj", b"v 0 0 0\nv 1,5 0 0\nv 0 1 0\nf 1 2 3\n"),
        ),
        (
            "INDEX",
            file("index.obj", format!("{three}f 1 2 9\n").as_bytes()),
        ),
        (
            "TWO_CORNERS",
            file("two-corners.obj", format!("{three}f 1 2\n").as_bytes()),
        ),
        (
            "NAN",
            file("nan.obj", b"v 0 0 0\nv 1 nan 0\nv 0 1 0\nf 1 2 3\n"),
        ),
        ("INFINITE", file("infinite.stl", &binary_stl(b"binary", &infinite))),
        ("STL_CUT", file("cut.stl", &stl[..stl.len() - 30])),
        (
            "STL_SOLID_CUT",
            file("solid-cut.stl", &solid_stl[..solid_stl.len() - 30]),
        ),
        (
            "STL_TEXT",
            file(
                "text.stl",
                b"solid x\n facet normal 0 0 1\n  outer loop\n   vertex 0 0 0\n   vertex 1 0 0\n   vertex 0 1 0\n  endloop\n endfacet\n hello world\nendsolid x\n",
            ),
        ),
        (
            "PLY_HEADER",
            file(
                "header.ply",
                b"ply\nformat ascii 1.0\nelement vertex 3\nproperty flaot x\nproperty float y\nproperty float z\nend_header\n0 0 0\n1 0 0\n0 1 0\n",
            ),
        ),
        ("GLB_MAGIC", file("magic.glb", &no_magic)),
        ("GLB_CUT", file("cut.glb", &glb)),
        ("OPEN", file("open.obj", obj_text(&open).as_bytes())),
        ("FIN", file("fin.obj", obj_text(&fin).as_bytes())),
        ("CONES", file("cones.obj", obj_text(&cones).as_bytes())),
        ("KLEIN", file("klein.obj", obj_text(&klein_bottle()).as_bytes())),
        ("TWO", file("two.obj", obj_text(&two).as_bytes())),
        ("SLIVER", file("sliver.obj", obj_text(&sliver).as_bytes())),
        ("FLAT", file("flat.obj", obj_text(&flat).as_bytes())),
        (
            "CAGE_TURNED",
            file(
                "cage-turned.obj",
                b"v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n\
                  f 1 2 3 4\nf 5 6 7 8\nf 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\n",
            ),
        ),
    ]
    .into_iter()
    .map(|(name, path)| (format!("MESH_{name}"), path))
    .collect()
}

/// One row of a table in docs/bad-inputs.md: the command's words, the exit status, the message.
struct Row {
    line: usize,
    command: String,
    exit: i32,
    message: String,
}

fn bad_input_rows() -> Vec<Row> {
    let doc =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/bad-inputs.md"))
            .unwrap();
    let mut rows = Vec::new();
    for (k, line) in doc.lines().enumerate() {
        let cells: Vec<&str> = line.split(" | ").map(str::trim).collect();
        let [_, command, exit, message] = cells[..] else {
            continue;
        };
        let Some(command) = command.strip_prefix('`').and_then(|c| c.strip_suffix('`')) else {
            continue;
        };
        rows.push(Row {
            line: k + 1,
            command: command.to_owned(),
            exit: exit
                .parse()
                .unwrap_or_else(|_| panic!("line {}: exit {exit:?}", k + 1)),
            message: message
                .trim_end_matches(" |")
                .trim_end_matches('|')
                .trim()
                .to_owned(),
        });
    }
    rows
}

#[test]
fn bad_inputs_table_holds() {
    let dir = tempfile::tempdir().unwrap();
    let fixtures = bad_input_fixtures(dir.path());
    let model = dir.path().join("model.json");
    let model_bytes = std::fs::read(&model).unwrap();
    let rows = bad_input_rows();
    assert!(rows.len() >= 71, "the table has {} rows", rows.len());
    // Where one fixture's name begins another's ($CONSTANT, $CONSTANT64), the longer comes first,
    // since the first that matches is used.
    for (i, (a, _)) in fixtures.iter().enumerate() {
        for (b, _) in &fixtures[i + 1..] {
            assert!(!b.starts_with(a.as_str()), "${b} must come before ${a}");
        }
    }
    for row in rows {
        let args: Vec<String> = row
            .command
            .split_whitespace()
            .map(|word| {
                let mut word = word.to_owned();
                for (name, path) in &fixtures {
                    let token = format!("${name}");
                    if word.starts_with(&token) {
                        word = word.replacen(&token, &path.display().to_string(), 1);
                        break;
                    }
                }
                word
            })
            .collect();
        let out = ntori()
            .args(&args)
            .timeout(std::time::Duration::from_secs(300))
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(
            out.status.code(),
            Some(row.exit),
            "docs/bad-inputs.md line {}: `{}`: {stderr}",
            row.line,
            row.command
        );
        assert!(
            stderr.contains(&row.message),
            "docs/bad-inputs.md line {}: `{}`: expected {:?} in {stderr}",
            row.line,
            row.command,
            row.message
        );
        assert!(!stderr.contains("panicked"), "{stderr}");
    }
    // Nothing was written where a row refused, nor replaced.
    for out in ["out.obj", "out.png", "out.json"] {
        assert!(!dir.path().join(out).exists(), "{out} was written");
    }
    assert!(is_fifo(&dir.path().join("fifo")));
    assert_eq!(std::fs::read(&model).unwrap(), model_bytes);
}

/// A refused `ntori fit` leaves an existing output byte for byte as it was (even with --force) and
/// makes no file where there was none: not the output, and no temporary file beside it.
#[test]
fn a_failing_fit_leaves_its_output_alone() {
    let dir = tempfile::tempdir().unwrap();
    let meshes = mesh_fixtures(dir.path());
    let mesh = |name: &str| {
        &meshes
            .iter()
            .find(|(n, _)| n == &format!("MESH_{name}"))
            .unwrap()
            .1
    };
    let out = tempfile::tempdir().unwrap();
    let existing = out.path().join("existing.json");
    // Not JSON, not text: any rewrite would show.
    let before: Vec<u8> = (0..=255u8).rev().chain(*b"mine").collect();
    std::fs::write(&existing, &before).unwrap();
    let absent = out.path().join("absent.json");
    let listing = || {
        let mut names: Vec<_> = std::fs::read_dir(out.path())
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        names.sort();
        names
    };
    let names = listing();
    for (name, message) in [
        ("OPEN", "the mesh is not closed: it has 2 holes"),
        ("KLEIN", "the mesh is not orientable"),
        ("CONES", "non-manifold vertex"),
        ("TWO", "pass --largest"),
        ("NAN", "not a finite number"),
        ("STL_CUT", "binary STL of 4 triangles"),
        ("EMPTY", "the file is empty"),
    ] {
        for (output, force) in [(&existing, true), (&absent, false), (&absent, true)] {
            let mut command = ntori();
            command
                .arg("fit")
                .arg(mesh(name))
                .arg("-q")
                .arg("-o")
                .arg(output);
            if force {
                command.arg("--force");
            }
            command
                .timeout(std::time::Duration::from_secs(120))
                .assert()
                .code(1)
                .stderr(predicate::str::contains(message))
                .stderr(predicate::str::contains("panicked").not());
            assert_eq!(std::fs::read(&existing).unwrap(), before, "{name}");
            assert!(!absent.exists(), "{name}: {} written", absent.display());
            assert_eq!(listing(), names, "{name}: files appeared");
        }
        // Without --force an existing output is refused before the mesh is read.
        ntori()
            .arg("fit")
            .arg(mesh(name))
            .args(["-q", "-o"])
            .arg(&existing)
            .assert()
            .code(1)
            .stderr(predicate::str::contains("it exists; pass --force"));
        assert_eq!(std::fs::read(&existing).unwrap(), before, "{name}");
    }
    // Nor is the input touched when the output names it.
    let torus = mesh("TORUS");
    let input = std::fs::read(torus).unwrap();
    ntori()
        .arg("fit")
        .arg(torus)
        .args(["-q", "--force", "-o"])
        .arg(torus)
        .assert()
        .code(1)
        .stderr(predicate::str::contains("it is the input"));
    assert_eq!(std::fs::read(torus).unwrap(), input);
}

/// Without a display the editor says so plainly, exit status 1, rather than winit's error naming
/// its own source file.
#[test]
fn the_editor_without_a_display_says_what_it_needs() {
    ntori()
        .arg("edit")
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .env_remove("WAYLAND_SOCKET")
        .timeout(std::time::Duration::from_secs(60))
        .assert()
        .code(1)
        .stderr(predicate::str::contains("the editor needs a display"))
        .stderr(predicate::str::contains("winit").not());
}
