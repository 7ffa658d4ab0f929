//! `ntori sculpt`: the editor's grab brush from the command line.

use charts::{ChartId, ChartPoint};
use embedding::{Point3, Stencil, Vector3};
use num_complex::Complex64;

use crate::common::{asset, ntori, ntori_json};

fn point_arg(p: Point3) -> String {
    format!("{},{},{}", p.x, p.y, p.z)
}

/// A stroke takes the grabbed point to --to exactly, keeps the surface beyond the brush where it
/// was, moves more than the paper's edit would, and writes a model that loads.
#[test]
fn a_stroke_moves_the_point_and_stays_inside_its_radius() {
    let input = asset("models/genus-2.json");
    let model = ntori::io::model_file::load(&input).unwrap();
    let layout = model.layout();
    let points = model.atlas().tessellate(16, 16).unwrap().vertices;
    let stencil = Stencil::build(&layout, &points);
    let mut before = vec![Point3::origin(); points.len()];
    stencil.positions(model.control_points(), &mut before);
    let size = embedding::fit::diagonal(&before);
    let at = layout
        .eval(
            model.control_points(),
            ChartPoint::new(ChartId(1), Complex64::new(0.1, -0.05)),
        )
        .pos;
    let to = at + Vector3::new(0.0, 0.0, 0.15 * size);
    let radius = 0.3 * size;
    let dir = tempfile::tempdir().unwrap();
    let run = |name: &str, extra: &[String]| {
        let output = dir.path().join(name);
        let mut args = vec![
            "sculpt".to_string(),
            input.display().to_string(),
            "-o".into(),
            output.display().to_string(),
            "--at".into(),
            point_arg(at),
            "--to".into(),
            point_arg(to),
            "--json".into(),
        ];
        args.extend_from_slice(extra);
        (ntori_json(&args), output)
    };
    let (report, output) = run("brush.json", &["--radius".into(), radius.to_string()]);
    let stroke = &report["strokes"][0];
    assert_eq!(stroke["brush"], "grab");
    assert!(stroke["reached_from_to"].as_f64().unwrap() <= 1e-6 * size);
    assert!(stroke["picked_from_at"].as_f64().unwrap() <= 0.02 * size);
    let sculpted = ntori::io::model_file::load(&output).unwrap();
    assert_eq!(sculpted.pins(), model.pins());
    let mut after = vec![Point3::origin(); points.len()];
    stencil.positions(sculpted.control_points(), &mut after);
    let lift = (to - at).norm();
    let far = before
        .iter()
        .zip(&after)
        .filter(|(b, _)| (*b - at).norm() > 1.2 * radius)
        .map(|(b, a)| (a - b).norm())
        .fold(0.0, f64::max);
    assert!(
        far <= 0.1 * lift,
        "beyond the brush the surface moved by {far}"
    );
    // A pin at the grabbed point itself: the compromise is written, and the exit status says so.
    let held = dir.path().join("held.json");
    ntori()
        .args(["sculpt", &input.display().to_string(), "-o"])
        .arg(&held)
        .args([
            "--at",
            &point_arg(at),
            "--to",
            &point_arg(to),
            "--pin",
            &point_arg(at),
        ])
        .assert()
        .code(3);
    assert!(ntori::io::model_file::load(&held).is_ok());
    // The paper's edit (no radius) moves fewer control points.
    let (paper, _) = run("paper.json", &[]);
    assert!(
        report["control_points_moved"].as_u64().unwrap()
            > 2 * paper["control_points_moved"].as_u64().unwrap()
    );
}

/// Bad arguments and outputs are refused, and nothing is written or replaced.
#[test]
fn sculpt_refuses_what_it_cannot_do() {
    let input = asset("models/genus-2.json");
    let dir = tempfile::tempdir().unwrap();
    let existing = dir.path().join("existing.json");
    std::fs::write(&existing, "keep me").unwrap();
    let args = |output: &std::path::Path, extra: &[&str]| {
        let mut a: Vec<String> = vec![
            "sculpt".into(),
            input.display().to_string(),
            "-o".into(),
            output.display().to_string(),
            "--at".into(),
            "1,0,0".into(),
            "--to".into(),
            "1,0,1".into(),
        ];
        a.extend(extra.iter().map(|s| s.to_string()));
        a
    };
    ntori()
        .args(args(&existing, &[]))
        .assert()
        .code(1)
        .stderr(predicates::str::contains("exists"));
    assert_eq!(std::fs::read_to_string(&existing).unwrap(), "keep me");
    ntori()
        .args(args(&input, &["--force"]))
        .assert()
        .code(1)
        .stderr(predicates::str::contains("input"));
    let fresh = dir.path().join("fresh.json");
    for bad in [
        &["--radius", "-1"][..],
        &["--radius", "nan"],
        &["--pin", "1,2"],
        &["--brush", "pinch"],
        &["--strength", "inf"],
        &["--symmetry", "w"],
        &["--script", "strokes.txt"],
    ] {
        ntori().args(args(&fresh, bad)).assert().code(2);
    }
    ntori()
        .args(["sculpt", &input.display().to_string(), "-o"])
        .arg(&fresh)
        .args(["--at", "1,x,0", "--to", "0,0,0"])
        .assert()
        .code(2)
        .stderr(predicates::str::contains("X,Y,Z"));
    // Stroke-level problems: exit 1, the stroke named, nothing written.
    let cases: [(&[&str], &str); 3] = [
        (&["--to", "1,0,1"], "needs --to"),
        (&["--brush", "inflate", "--pin", "1,0,0"], "no pins"),
        (&[], "--at"),
    ];
    for (extra, message) in cases {
        let mut a = vec![
            "sculpt".to_string(),
            input.display().to_string(),
            "-o".into(),
        ];
        a.push(fresh.display().to_string());
        if !extra.is_empty() {
            a.extend(["--at".to_string(), "1,0,0".to_string()]);
        }
        // (The first case leaves --to out of a grab.)
        let extra: Vec<&str> = if extra == ["--to", "1,0,1"] {
            vec![]
        } else {
            extra.to_vec()
        };
        a.extend(extra.iter().map(|s| s.to_string()));
        ntori()
            .args(&a)
            .assert()
            .code(1)
            .stderr(predicates::str::contains(message));
    }
    // A grab beyond ten times the model's size is refused before any work (its re-planning
    // steps grow with the reach: --to 1e9 had run for minutes).
    ntori()
        .args(["sculpt", &input.display().to_string(), "-o"])
        .arg(&fresh)
        .args(["--at", "1,0,0", "--to", "1,0,1e9"])
        .timeout(std::time::Duration::from_secs(60))
        .assert()
        .code(1)
        .stderr(predicates::str::contains(
            "more than 10 times the model's size",
        ));
    assert!(!fresh.exists());
    // A script's bad line is named by file and line.
    let script = dir.path().join("strokes.txt");
    for (text, message) in [
        (
            "# ok\n--brush inflate --at 1,0,0\n--brush inflat --at 1,0,0\n",
            "strokes.txt:3: invalid value 'inflat'",
        ),
        (
            "--brush smooth --radius 1\n",
            "strokes.txt:1: a stroke needs --at",
        ),
        ("# nothing\n\n", "no strokes"),
        (
            "--at 1,0,0 --output x.json\n",
            "strokes.txt:1: unexpected argument",
        ),
    ] {
        std::fs::write(&script, text).unwrap();
        ntori()
            .args(["sculpt", &input.display().to_string(), "-o"])
            .arg(&fresh)
            .arg("--script")
            .arg(&script)
            .assert()
            .code(1)
            .stderr(predicates::str::contains(message));
    }
    assert!(!fresh.exists());
}

/// The stroke brushes from the command line: inflate raises the enclosed volume and deflate
/// lowers it; with --symmetry x the mirror image moves alike; a script of strokes gives exactly
/// the model that the same strokes one command at a time give.
#[test]
fn stroke_brushes_symmetry_and_scripts() {
    let input = asset("models/genus-2.json");
    let model = ntori::io::model_file::load(&input).unwrap();
    let layout = model.layout();
    let mesh = model.atlas().tessellate(32, 32).unwrap();
    let stencil = Stencil::build(&layout, &mesh.vertices);
    let positions = |surface: &embedding::Surface| {
        let mut p = vec![Point3::origin(); mesh.vertices.len()];
        stencil.positions(surface.control_points(), &mut p);
        p
    };
    let volume = |p: &[Point3]| {
        mesh.triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|v| p[v as usize].coords);
                a.dot(&b.cross(&c)) / 6.0
            })
            .sum::<f64>()
            .abs()
    };
    let before = positions(&model);
    let v0 = volume(&before);
    let dir = tempfile::tempdir().unwrap();
    let sculpt = |from: &std::path::Path, name: &str, stroke: &str| {
        let output = dir.path().join(name);
        let mut args = vec![
            "sculpt".to_string(),
            from.display().to_string(),
            "-o".into(),
            output.display().to_string(),
            "--json".into(),
        ];
        args.extend(stroke.split_whitespace().map(str::to_string));
        let report = ntori_json(&args);
        (
            report,
            ntori::io::model_file::load(&output).unwrap(),
            output,
        )
    };
    let inflate = "--brush inflate --at 2.3,0,0.35 --radius 1 --strength 0.8";
    let (report, inflated, _) = sculpt(&input, "inflated.json", inflate);
    assert_eq!(report["strokes"][0]["dabs"], 1);
    let v1 = volume(&positions(&inflated));
    assert!(v1 > v0 * 1.002, "inflate: volume {v0} → {v1}");
    let deflate = "--brush inflate --at 2.3,0,0.35 --radius 1 --strength -0.8";
    let (_, deflated, _) = sculpt(&input, "deflated.json", deflate);
    let v2 = volume(&positions(&deflated));
    assert!(v2 < v0 * 0.998, "deflate: volume {v0} → {v2}");
    // Symmetry: the other side (x < 0) moves as much as the picked side.
    let (report, mirrored, _) = sculpt(&input, "mirrored.json", &format!("{inflate} --symmetry x"));
    assert_eq!(report["strokes"][0]["images"], 1);
    let after = positions(&mirrored);
    let most = |side: f64| {
        before
            .iter()
            .zip(&after)
            .filter(|(b, _)| b.x * side > 0.0)
            .map(|(b, a)| (a - b).norm())
            .fold(0.0, f64::max)
    };
    let (right, left) = (most(1.0), most(-1.0));
    // (The asset is a grid-16 fit, symmetric only to about 1e-3 of its size, and at grid 16 a radius
    // of 13% of the size is resolved a little differently in different charts: measured 0.0690
    // against 0.0657. Without symmetry the other side does not move at all; exact mirror symmetry
    // is tested on the sphere in `tests/editor.rs`.)
    assert!(
        right > 0.01 && (left / right - 1.0).abs() < 0.1,
        "moved {right} on the picked side, {left} on the other"
    );
    // A script against the same strokes one at a time.
    let strokes = [
        "--brush inflate --at 2.3,0,0.35 --radius 1 --symmetry x",
        "--brush smooth --at 2.3,-1,0.35 --to 2.3,1,0.35 --radius 1 --strength 1",
        "--brush flatten --at -2.3,0.5,0.35 --radius 0.8",
        "--at 2.3,0,0.4 --to 2.3,0,0.8 --radius 1.2 --falloff dome",
    ];
    let script = dir.path().join("strokes.txt");
    std::fs::write(
        &script,
        format!("# four strokes\n{}\n", strokes.join("\n\n")),
    )
    .unwrap();
    let (report, scripted, _) = sculpt(
        &input,
        "scripted.json",
        &format!("--script {}", script.display()),
    );
    assert_eq!(report["strokes"].as_array().unwrap().len(), 4);
    let mut from = input.clone();
    let mut one_by_one = model.clone();
    for (k, stroke) in strokes.iter().enumerate() {
        let (_, m, output) = sculpt(&from, &format!("step{k}.json"), stroke);
        one_by_one = m;
        from = output;
    }
    assert_eq!(scripted.control_points(), one_by_one.control_points());
}
