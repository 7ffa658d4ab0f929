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
    assert!(report["reached_from_to"].as_f64().unwrap() <= 1e-6 * size);
    assert!(report["picked_from_at"].as_f64().unwrap() <= 0.02 * size);
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
        &["--falloff", "dome"],
        &["--pin", "1,2"],
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
    assert!(!fresh.exists());
}
