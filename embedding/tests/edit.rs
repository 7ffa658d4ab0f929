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
    // And grid 12 with the disk charts at 20: the column index and the refresh follow each
    // chart's own numbering.
    let atlas = Atlas::new(2).unwrap();
    let t = atlas.tessellate(8, 6).unwrap();
    for (grid, disk_grid) in [(8, None), (24, None), (12, Some(20))] {
        let layout = Layout::new(
            &atlas,
            SplineSettings {
                grid,
                disk_grid,
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

/// A grab brush is defined on the surface: in an inside, a vertex and an edge chart of the fitted
/// genus-2 model, the spline it makes follows the smooth falloff of the model-space distance (the
/// half-height at 0.454 R within ±15%, at most 6% of Δ beyond 1.1 R, the full displacement at the
/// centre) at radii of 12%, 20% and 30% of the model's size (at grid 32; at grid 16 only from 20%
/// outside the edge charts); so it does where the disk charts have a finer grid (48) than the edge
/// charts. The footprint is measured on a tessellation other than the brush's samples.
#[test]
fn a_grab_brush_has_the_same_footprint_in_every_kind_of_chart() {
    for disk_grid in [None, Some(48)] {
        let settings = SplineSettings {
            disk_grid,
            ..SplineSettings::default()
        };
        grab_footprints(settings);
    }
}

fn grab_footprints(settings: SplineSettings) {
    use charts::ChartKind;
    use embedding::brush::{Falloff, grab_shares};
    let model =
        embedding::fit::initial_model(2, 32, settings, embedding::fit::FitSettings::default())
            .unwrap()
            .surface;
    let layout = model.layout();
    let atlas = model.atlas();
    let points = atlas.tessellate(32, 32).unwrap();
    let stencil = Stencil::build(&layout, &points.vertices);
    let mut positions = vec![Point3::origin(); stencil.rows()];
    stencil.positions(model.control_points(), &mut positions);
    // The brush samples the surface as the editor's brushes do: on a tessellation of its own.
    let brush_samples = embedding::brush::SurfaceSamples::new(&model).unwrap();
    let samples = brush_samples.view(&model);
    let size = embedding::fit::diagonal(&positions);
    let kinds = [
        ChartKind::Inside,
        ChartKind::Vertex,
        ChartKind::Edge { handle: 1, side: 0 },
    ];
    for kind in kinds {
        let chart = atlas
            .charts()
            .iter()
            .find(|c| c.kind() == kind)
            .unwrap()
            .id();
        for (radius, at) in [(0.12, (0.0, 0.0)), (0.2, (0.15, -0.1)), (0.3, (0.0, 0.1))] {
            let radius = radius * size;
            let centre = layout
                .eval(model.control_points(), p(chart.0, at.0, at.1))
                .pos;
            let shares = grab_shares(&samples, centre, radius, Falloff::Smooth).unwrap();
            let mut beta = vec![0.0; layout.control_count()];
            for (c, b) in shares {
                beta[c.index()] = b;
            }
            let moved: Vec<(f64, f64)> = (0..stencil.rows())
                .map(|r| {
                    let d: f64 = stencil.row(r).map(|(c, w)| w[0] * beta[c as usize]).sum();
                    ((positions[r] - centre).norm() / radius, d)
                })
                .collect();
            let outside = moved
                .iter()
                .filter(|m| m.0 > 1.1)
                .map(|m| m.1.abs())
                .fold(0.0, f64::max);
            let half = moved
                .iter()
                .filter(|m| m.1 >= 0.5)
                .map(|m| m.0)
                .fold(0.0, f64::max);
            let centre_gain = moved.iter().min_by(|a, b| a.0.total_cmp(&b.0)).unwrap().1;
            let rms = (moved
                .iter()
                .filter(|m| m.0 < 1.0)
                .map(|m| (m.1 - Falloff::Smooth.at(m.0)).powi(2))
                .sum::<f64>()
                / moved.iter().filter(|m| m.0 < 1.0).count() as f64)
                .sqrt();
            println!(
                "{kind:?} R {:.3}: half-height at {half:.3} R (0.454), centre {centre_gain:.3}, \
                 beyond 1.1 R {outside:.3}, rms {rms:.3}",
                radius / size
            );
            assert!(
                (half / 0.4542 - 1.0).abs() <= 0.15,
                "{kind:?}: half-height at {half} R"
            );
            assert!(
                (centre_gain - 1.0).abs() <= 0.1,
                "{kind:?}: centre {centre_gain}"
            );
            assert!(outside <= 0.06, "{kind:?}: {outside} beyond the radius");
            assert!(rms <= 0.05, "{kind:?}: rms {rms}");
        }
    }
}
