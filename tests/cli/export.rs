//! `ntori export`: every format through the binary; the up axis, scale, units and UV layout
//! reaching the file; errors that name the file, exit non-zero and leave nothing behind; help that
//! says what each format carries.

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
    // The object is named after the model file: "model".
    let cases: [(&str, &[&str], &[u8]); 10] = [
        ("obj", &[], b"# ntori"),
        ("ply", &[], b"ply\nformat binary_little_endian 1.0\n"),
        ("ply", &["--ascii"], b"ply\nformat ascii 1.0\n"),
        ("stl", &[], b"model; ntori"),
        ("stl", &["--ascii"], b"solid model\n"),
        ("glb", &[], b"glTF\x02\0\0\0"),
        ("3mf", &[], b"PK\x03\x04"),
        ("off", &[], b"OFF\n"),
        ("OBJ", &["--te", "4", "--tr", "8"], b"# ntori"),
        (
            "glb",
            &[
                "--uv", "atlas", "--up", "z", "--units", "mm", "--scale", "3",
            ],
            b"glTF",
        ),
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
        // The quality tessellation by default; --te/--tr choose t_e/t_r (4n·t_e² +
        // 8n·t_e·(2t_r − 1) triangles at genus n).
        if extra.is_empty() {
            assert!(
                stdout.contains("quality tessellation to 0.001 of the diagonal"),
                "{stdout}"
            );
        } else if extra[0] == "--te" {
            assert!(stdout.contains("t_e = 4, t_r = 8"), "{stdout}");
            assert!(stdout.contains(" 1088 triangles"), "{stdout}");
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
    // Resolutions out of range, and t_e = 1 at genus 2; scales that are no size; unknown axes and
    // units.
    for args in [
        ["--te", "0"],
        ["--tr", "0"],
        ["--te", "513"],
        ["--tr", "-1"],
        ["--te", "1"],
        ["--scale", "0"],
        ["--scale", "-2"],
        ["--scale", "nan"],
        ["--scale", "inf"],
        ["--scale", "big"],
        ["--up", "x"],
        ["--units", "km"],
        ["--uv", "box"],
    ] {
        let mut all = vec![os(&model), "-o".into(), os(&out)];
        all.extend(args.iter().map(Into::into));
        let refs: Vec<&std::ffi::OsStr> = all.iter().map(|s| s.as_os_str()).collect();
        fails(&refs, args[0], dir.path());
    }
    // --ascii where the format has no text variant, --uv atlas where it has no UVs.
    fails(
        &[&os(&model), "-o".as_ref(), &os(&out), "--ascii".as_ref()],
        "--ascii applies to PLY and STL",
        dir.path(),
    );
    for ext in ["stl", "3mf", "off"] {
        let out = dir.path().join(format!("out.{ext}"));
        fails(
            &[
                &os(&model),
                "-o".as_ref(),
                &os(&out),
                "--uv".as_ref(),
                "atlas".as_ref(),
            ],
            "stores no texture coordinates; --uv atlas applies to OBJ, PLY and GLB only",
            dir.path(),
        );
    }
    // A scale that takes the surface beyond what f32 holds.
    let stl = dir.path().join("out.stl");
    fails(
        &[
            &os(&model),
            "-o".as_ref(),
            &os(&stl),
            "--scale".as_ref(),
            "1e39".as_ref(),
        ],
        "beyond the 32-bit floats STL stores",
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
                .and(predicate::str::contains("--te"))
                .and(predicate::str::contains(".3mf"))
                .and(predicate::str::contains("texture coordinates `s t`"))
                .and(predicate::str::contains("_CHART (u8)"))
                .and(predicate::str::contains("checker texture"))
                .and(predicate::str::contains("one model unit becomes S U"))
                .and(predicate::str::contains("by default 1 cm"))
                .and(predicate::str::contains("GLB in metres"))
                .and(predicate::str::contains("3MF in millimetres"))
                .and(predicate::str::contains("STL in millimetres"))
                .and(predicate::str::contains("(x, y, z) → (x, z, −y)"))
                .and(predicate::str::contains("--up <AXIS>"))
                .and(predicate::str::contains("--scale <S>"))
                .and(predicate::str::contains("--units <U>"))
                .and(predicate::str::contains("--uv <LAYOUT>"))
                .and(predicate::str::contains("1 is refused at genus")),
        );
    ntori()
        .arg("--help")
        .assert()
        .success()
        .stdout(predicate::str::contains("export"));
}

/// The numbers of an OFF file: its positions.
fn off_positions(path: &Path) -> Vec<[f64; 3]> {
    let text = std::fs::read_to_string(path).unwrap();
    let mut lines = text.lines().filter(|l| !l.starts_with('#'));
    assert_eq!(lines.next(), Some("OFF"));
    let counts: Vec<usize> = lines
        .next()
        .unwrap()
        .split_whitespace()
        .map(|x| x.parse().unwrap())
        .collect();
    lines
        .take(counts[0])
        .map(|l| {
            let v: Vec<f64> = l.split_whitespace().map(|x| x.parse().unwrap()).collect();
            [v[0], v[1], v[2]]
        })
        .collect()
}

/// The bounding box's size along x, y, z.
fn extent(points: impl IntoIterator<Item = [f64; 3]>) -> [f64; 3] {
    let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
    for p in points {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    [0, 1, 2].map(|k| hi[k] - lo[k])
}

fn assert_close(got: [f64; 3], want: [f64; 3], what: &str) {
    for k in 0..3 {
        assert!(
            (got[k] - want[k]).abs() <= 1e-6 * want[k].abs().max(1e-30),
            "{what}: {got:?} vs {want:?}"
        );
    }
}

/// `ntori export MODEL -o OUT --force` at t_e = t_r = 6 with `extra` options (the tests export
/// to one path again and again); what it printed.
fn coarse_export(model: &Path, out: &Path, extra: &[&str]) -> String {
    let assert = ntori()
        .arg("export")
        .arg(model)
        .args(["--te", "6", "--tr", "6", "--force", "-o"])
        .arg(out)
        .args(extra)
        .assert()
        .success();
    String::from_utf8_lossy(&assert.get_output().stdout).into_owned()
}

#[test]
fn up_scale_and_units_reach_the_file() {
    let (dir, model) = workspace();
    let export = |name: &str, extra: &[&str]| -> (PathBuf, String) {
        let out = dir.path().join(name);
        let said = coarse_export(&model, &out, extra);
        (out, said)
    };
    // OFF: z up, no unit, so the model's own coordinates (a model unit is 1 cm by default).
    let (off, said) = export("model.off", &[]);
    let model_extent = extent(off_positions(&off));
    assert!(said.contains(" cm\n"), "{said}");
    let [x, y, z] = model_extent;
    // The plate's thin axis is z.
    assert!(z < x && z < y, "{model_extent:?}");

    // GLB: y up, metres; its POSITION bounds say so.
    let glb_extent = |path: &Path| {
        let gltf = gltf::Gltf::open(path).unwrap();
        let p = gltf.meshes().next().unwrap().primitives().next().unwrap();
        let b = p.bounding_box();
        [0, 1, 2].map(|k| f64::from(b.max[k]) - f64::from(b.min[k]))
    };
    let (glb, said) = export("default.glb", &[]);
    assert_close(
        glb_extent(&glb),
        [x * 0.01, z * 0.01, y * 0.01],
        "GLB default",
    );
    assert!(said.contains(" m\n"), "{said}");
    let (glb, _) = export("z.glb", &["--up", "z", "--units", "mm", "--scale", "2"]);
    assert_close(
        glb_extent(&glb),
        [x * 0.002, y * 0.002, z * 0.002],
        "GLB z up, 2 mm",
    );

    // STL: millimetres, z up by default, y up when asked.
    let stl_extent = |path: &Path| {
        let stl = stl_io::read_stl(&mut std::fs::File::open(path).unwrap()).unwrap();
        extent(stl.vertices.iter().map(|v| v.0.map(f64::from)))
    };
    let (stl, said) = export("default.stl", &[]);
    assert_close(
        stl_extent(&stl),
        [x * 10.0, y * 10.0, z * 10.0],
        "STL default",
    );
    assert!(said.contains(" mm\n"), "{said}");
    let (stl, _) = export("y.stl", &["--up", "y", "--units", "in"]);
    assert_close(
        stl_extent(&stl),
        [x * 25.4, z * 25.4, y * 25.4],
        "STL y up, inches",
    );

    // 3MF: declares millimetres; a model unit of 2 inches is 50.8 mm.
    let (threemf, said) = export("print.3mf", &["--scale", "2", "--units", "in"]);
    assert!(said.contains("3MF") && said.contains(" mm\n"), "{said}");
    let model_xml = {
        use std::io::Read as _;
        let mut zip = zip::ZipArchive::new(std::fs::File::open(&threemf).unwrap()).unwrap();
        let mut text = String::new();
        zip.by_name("3D/3dmodel.model")
            .unwrap()
            .read_to_string(&mut text)
            .unwrap();
        text
    };
    let doc = roxmltree::Document::parse(&model_xml).unwrap();
    assert_eq!(doc.root_element().attribute("unit"), Some("millimeter"));
    let number = |n: &roxmltree::Node, k: &str| -> f64 { n.attribute(k).unwrap().parse().unwrap() };
    let vertices = doc
        .descendants()
        .filter(|n| n.has_tag_name("vertex"))
        .map(|n| [number(&n, "x"), number(&n, "y"), number(&n, "z")]);
    assert_close(extent(vertices), [x * 50.8, y * 50.8, z * 50.8], "3MF 2 in");
    let object = doc
        .descendants()
        .find(|n| n.has_tag_name("object"))
        .unwrap();
    assert_eq!(object.attribute("name"), Some("model"));

    // OBJ: y up, no unit: the numbers are --scale times the model's, and a comment names the unit.
    let (obj, _) = export("m.obj", &["--scale", "3", "--units", "m"]);
    let text = std::fs::read_to_string(&obj).unwrap();
    assert!(text.contains("# +y up, units: m\n"), "{text:.300}");
    assert!(text.contains("\no model\n"));
    let positions = text.lines().filter_map(|l| l.strip_prefix("v ")).map(|l| {
        let v: Vec<f64> = l.split_whitespace().map(|x| x.parse().unwrap()).collect();
        [v[0], v[1], v[2]]
    });
    assert_close(extent(positions), [x * 3.0, z * 3.0, y * 3.0], "OBJ ×3");
}

#[test]
fn the_uv_atlas_splits_the_mesh_at_chart_seams() {
    let (dir, model) = workspace();
    let vertices = |extra: &[&str]| -> usize {
        let said = coarse_export(&model, &dir.path().join("m.ply"), extra);
        let words: Vec<&str> = said.split_whitespace().collect();
        let at = words.iter().position(|w| *w == "vertices,").unwrap();
        words[at - 1].parse().unwrap()
    };
    let (chart, atlas) = (vertices(&[]), vertices(&["--uv", "atlas"]));
    assert!(atlas > chart, "{atlas} vs {chart}");
    // The PLY says which layout its s t are.
    let text = std::fs::read(dir.path().join("m.ply")).unwrap();
    let header = String::from_utf8_lossy(&text[..1000]);
    assert!(header.contains("comment s t: a packed atlas"), "{header}");
    assert!(
        header.contains("property float s\nproperty float t\n"),
        "{header}"
    );
}

#[test]
fn t_e_1_is_fine_at_genus_0() {
    let dir = tempfile::tempdir().unwrap();
    let model = dir.path().join("sphere.json");
    std::fs::write(
        &model,
        serde_json::to_string(&crate::common::small_model(0).to_model()).unwrap(),
    )
    .unwrap();
    let out = dir.path().join("sphere.obj");
    ntori()
        .arg("export")
        .arg(&model)
        .args(["--te", "1", "--tr", "2", "-q", "-o"])
        .arg(&out)
        .assert()
        .success();
    let (obj, _) = tobj::load_obj(&out, &tobj::GPU_LOAD_OPTIONS).unwrap();
    let mesh = &obj[0].mesh;
    assert_eq!(obj[0].name, "sphere");
    let topology =
        mesh::HalfEdgeMesh::from_polygons(mesh.positions.len() / 3, mesh.indices.chunks(3))
            .unwrap()
            .topology();
    assert!(topology.closed && topology.manifold);
    assert_eq!(topology.euler_characteristic, 2);
}

/// `--tolerance` exports the quality tessellation: the summary says so, the file is a closed mesh
/// of well-shaped triangles; a tolerance out of range, or with --te, is refused before any work.
#[test]
fn tolerance_exports_the_quality_tessellation() {
    let (dir, model) = workspace();
    let out = dir.path().join("q.obj");
    let run = ntori()
        .arg("export")
        .arg(&model)
        .arg("-o")
        .arg(&out)
        .args(["--tolerance", "0.002"])
        .assert()
        .success()
        .stdout(predicate::str::contains(
            "quality tessellation to 0.002 of the diagonal",
        ))
        .stderr(predicate::str::is_empty());
    drop(run);
    let (models, _) = tobj::load_obj(&out, &tobj::GPU_LOAD_OPTIONS).unwrap();
    let m = &models[0].mesh;
    let positions: Vec<[f64; 3]> = m
        .positions
        .chunks(3)
        .map(|p| [p[0] as f64, p[1] as f64, p[2] as f64])
        .collect();
    let triangles: Vec<[u32; 3]> = m.indices.chunks(3).map(|t| [t[0], t[1], t[2]]).collect();
    let topology =
        mesh::HalfEdgeMesh::from_polygons(positions.len(), triangles.iter().map(|t| &t[..]))
            .unwrap()
            .topology();
    assert!(topology.closed && topology.manifold);
    assert_eq!(topology.euler_characteristic, -2);
    let shape = mesh::mesh_shape(&positions, &triangles).unwrap();
    assert!(shape.well_shaped() >= 0.99, "{shape:?}");
    assert!(shape.largest_bend <= 20.0, "{shape:?}");
    for (bad, says) in [
        (
            &["--tolerance", "0.5"][..],
            "the tolerance is a fraction of the diagonal",
        ),
        (
            &["--tolerance", "nan"][..],
            "the tolerance is a fraction of the diagonal",
        ),
        (
            &["--tolerance", "0.001", "--te", "8"][..],
            "cannot be used with",
        ),
    ] {
        ntori()
            .arg("export")
            .arg(&model)
            .arg("-o")
            .arg(dir.path().join("bad.obj"))
            .args(bad)
            .assert()
            .failure()
            .stderr(predicate::str::contains(says));
    }
    assert!(!dir.path().join("bad.obj").exists());
    // --quads: all quads, in the formats with polygons only.
    let quads = dir.path().join("q.off");
    ntori()
        .arg("export")
        .arg(&model)
        .arg("-o")
        .arg(&quads)
        .args(["--quads", "--tolerance", "0.002"])
        .assert()
        .success()
        .stdout(
            predicate::str::contains("quad tessellation to 0.002 of the diagonal")
                .and(predicate::str::contains(" quads, ")),
        );
    let text = std::fs::read_to_string(&quads).unwrap();
    let counts: Vec<usize> = text
        .lines()
        .find(|l| !l.starts_with('#') && !l.starts_with("OFF"))
        .unwrap()
        .split_whitespace()
        .map(|x| x.parse().unwrap())
        .collect();
    assert_eq!(
        text.lines().filter(|l| l.starts_with("4 ")).count(),
        counts[1]
    );
    for bad in [&["--quads", "--te", "8"][..], &["--quads"][..]] {
        let out = dir.path().join("bad.stl");
        ntori()
            .arg("export")
            .arg(&model)
            .arg("-o")
            .arg(&out)
            .args(bad)
            .assert()
            .failure()
            .stderr(predicate::str::contains(if bad.len() > 1 {
                "cannot be used with"
            } else {
                "STL stores triangles only; --quads applies to OBJ, PLY and OFF"
            }));
        assert!(!out.exists());
    }
    // --te alone picks t_e/t_r, with t_r at 16.
    ntori()
        .arg("export")
        .arg(&model)
        .arg("-o")
        .arg(dir.path().join("te.off"))
        .args(["--te", "4"])
        .assert()
        .success()
        .stdout(predicate::str::contains("t_e = 4, t_r = 16"));
}
