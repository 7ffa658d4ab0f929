//! The minimum-norm edit: a dragged point reaches its target, pinned points stay, the change is the
//! smallest one, and the redraw from the stencil matches a full re-evaluation.

use charts::{Atlas, ChartId, ChartPoint};
use embedding::edit::{Constraint, RefreshScratch, refresh, solve};
use embedding::{Layout, Point3, SplineSettings, Stencil, Vector3};
use nalgebra::DMatrix;
use num_complex::Complex64;

fn wavy(layout: &Layout) -> Vec<Point3> {
    (0..layout.control_count())
        .map(|i| {
            Point3::new(
                (i as f64 * 0.37).sin(),
                (i as f64 * 0.71).cos(),
                (i as f64 * 0.13).sin(),
            )
        })
        .collect()
}

fn p(chart: u32, re: f64, im: f64) -> ChartPoint {
    ChartPoint::new(ChartId(chart), Complex64::new(re, im))
}

#[test]
fn a_drag_reaches_its_target_and_pins_stay() {
    for genus in [0, 1, 2, 3] {
        let atlas = Atlas::new(genus).unwrap();
        let layout = Layout::new(&atlas, SplineSettings::default()).unwrap();
        let mut control = wavy(&layout);
        let size = control.iter().map(|c| c.coords.norm()).fold(0.0, f64::max);
        let dragged = p(1, 0.1, -0.05);
        let pins = [p(0, 0.2, 0.1), p(1, -0.2, 0.15), p(0, -0.1, -0.3)];
        let before: Vec<Point3> = pins.iter().map(|&q| layout.eval(&control, q).pos).collect();
        let target = layout.eval(&control, dragged).pos + Vector3::new(0.3, -0.2, 0.25);
        let mut constraints = vec![Constraint {
            point: dragged,
            target,
        }];
        constraints.extend(pins.iter().zip(&before).map(|(&q, &b)| Constraint {
            point: q,
            target: b,
        }));
        let edit = solve(&layout, &control, &constraints).unwrap();
        edit.apply(&mut control);
        assert!(
            (layout.eval(&control, dragged).pos - target).norm() < 1e-6 * size,
            "genus {genus}"
        );
        for (q, b) in pins.iter().zip(&before) {
            assert!(
                (layout.eval(&control, *q).pos - b).norm() < 1e-9,
                "genus {genus}: a pin moved"
            );
        }
        assert!(edit.residual < 1e-9);
    }
}

#[test]
fn the_change_is_the_least_norm_one() {
    let atlas = Atlas::new(2).unwrap();
    let layout = Layout::new(&atlas, SplineSettings::default()).unwrap();
    let control = wavy(&layout);
    let points = [p(2, 0.05, 0.1), p(0, 0.3, 0.0)];
    let constraints: Vec<Constraint> = points
        .iter()
        .enumerate()
        .map(|(i, &q)| Constraint {
            point: q,
            target: layout.eval(&control, q).pos + Vector3::new(0.1 * i as f64, 0.2, -0.1),
        })
        .collect();
    let edit = solve(&layout, &control, &constraints).unwrap();
    // Independently: the pseudo-inverse of the full constraint matrix over all control points.
    let n = layout.control_count();
    let mut r = DMatrix::<f64>::zeros(points.len(), n);
    let mut d = DMatrix::<f64>::zeros(points.len(), 3);
    for (i, c) in constraints.iter().enumerate() {
        let mut row = Vec::new();
        layout.weights(c.point, &mut row);
        for w in &row {
            r[(i, w.control as usize)] += w.jet.val;
        }
        let gap = c.target - layout.eval(&control, c.point).pos;
        for a in 0..3 {
            d[(i, a)] = gap[a];
        }
    }
    let best = r.clone().pseudo_inverse(1e-12).unwrap() * d;
    let mut ours = DMatrix::<f64>::zeros(n, 3);
    for (&c, delta) in edit.controls.iter().zip(&edit.deltas) {
        for a in 0..3 {
            ours[(c.index(), a)] = delta[a];
        }
    }
    assert!((ours - best).norm() < 1e-10);
}

#[test]
fn conflicting_constraints_compromise_instead_of_failing() {
    let atlas = Atlas::new(1).unwrap();
    let layout = Layout::new(&atlas, SplineSettings::default()).unwrap();
    let mut control = wavy(&layout);
    let q = p(0, 0.1, 0.1);
    let here = layout.eval(&control, q).pos;
    let (a, b) = (
        here + Vector3::new(1.0, 0.0, 0.0),
        here - Vector3::new(1.0, 0.0, 0.0),
    );
    let edit = solve(
        &layout,
        &control,
        &[
            Constraint {
                point: q,
                target: a,
            },
            Constraint {
                point: q,
                target: b,
            },
        ],
    )
    .unwrap();
    assert!(
        (edit.residual - 1.0).abs() < 1e-9,
        "residual {}",
        edit.residual
    );
    edit.apply(&mut control);
    assert!(
        (layout.eval(&control, q).pos - here).norm() < 1e-9,
        "the compromise is the midpoint"
    );
    // Bad input is an error, not a panic.
    let nan = Constraint {
        point: q,
        target: Point3::new(f64::NAN, 0.0, 0.0),
    };
    assert!(solve(&layout, &control, &[nan]).is_err());
    let outside = Constraint {
        point: p(0, 0.7, 0.0),
        target: here,
    };
    assert!(solve(&layout, &control, &[outside]).is_err());
}

#[test]
fn refreshing_after_an_edit_equals_full_re_evaluation() {
    // Grid 8: each control point reaches most of its chart, so the refresh streams all rows; grid 24:
    // it gathers just the rows the moved control points touch. Both must equal a full re-evaluation.
    let atlas = Atlas::new(2).unwrap();
    let t = atlas.tessellate(8, 6).unwrap();
    for grid in [8, 24] {
        let layout = Layout::new(
            &atlas,
            SplineSettings {
                grid,
                ..SplineSettings::default()
            },
        )
        .unwrap();
        let mut control = wavy(&layout);
        let stencil = Stencil::build(&layout, &t.vertices);
        let index = stencil.column_index(layout.control_count());
        let mut positions = vec![Point3::origin(); stencil.rows()];
        stencil.positions(&control, &mut positions);
        let mut scratch = RefreshScratch::default();
        for (step, k) in [123usize, 900, 555].into_iter().enumerate() {
            let q = t.vertices[k];
            let target = layout.eval(&control, q).pos + Vector3::new(0.0, 0.5, 0.1 * step as f64);
            let edit = solve(&layout, &control, &[Constraint { point: q, target }]).unwrap();
            edit.apply(&mut control);
            refresh(
                &stencil,
                &index,
                &edit,
                &control,
                &mut positions,
                &mut scratch,
            );
            let mut full = vec![Point3::origin(); stencil.rows()];
            stencil.positions(&control, &mut full);
            let worst = positions
                .iter()
                .zip(&full)
                .map(|(a, b)| (a - b).norm())
                .fold(0.0, f64::max);
            assert!(worst <= 1e-12, "grid {grid}: {worst:e}");
            assert!((positions[k] - target).norm() < 1e-9);
            if grid == 24 {
                assert!(
                    scratch.refreshed() < stencil.rows() / 2,
                    "grid 24 refreshes only touched rows"
                );
            }
        }
    }
}
