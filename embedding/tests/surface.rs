//! The embedding: partition of unity, reproduction, convergence, derivatives, continuity across
//! chart boundaries, stencils.

use std::sync::OnceLock;

use charts::{Atlas, ChartId, ChartPoint};
use embedding::bspline::UniformBasis;
use embedding::{Layout, Model, Point3, SplineSettings, Stencil, StencilKernel, Vector3};
use nalgebra::{DMatrix, DVector};
use num_complex::Complex64;
use proptest::prelude::*;

fn atlas(genus: u32) -> &'static Atlas {
    static ATLASES: [OnceLock<Atlas>; 33] = [const { OnceLock::new() }; 33];
    ATLASES[genus as usize].get_or_init(|| Atlas::new(genus).unwrap())
}

use charts::check::chart_point_from_unit as chart_point;

/// Deterministic pseudo-random control points (each chart's patch differs, so blending matters).
fn noisy_controls(layout: &Layout, seed: u64) -> Vec<Point3> {
    let mut x = seed
        .wrapping_mul(6364136223846793005)
        .wrapping_add(1442695040888963407);
    let mut next = || {
        x = x
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (x >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    };
    (0..layout.control_count())
        .map(|_| Point3::new(next(), next(), next()))
        .collect()
}

/// How far one blend weight may differ when the point is read in another chart: that chart's
/// coordinates come through a transition whose rounding grows with the genus (the worst over
/// 3·10⁷ random points: 4.6e-15 at genus 2, 6.2e-14 at 8, 2.3e-13 at 16, 8.9e-13 at 32, about
/// g² · 1e-15), so 1e-12 up to genus 16 and g² · 4e-15 beyond (4.1e-12 at 32). A flat 1e-12
/// failed once in some hundreds of runs at genus 32.
fn blend_tolerance(genus: u32) -> f64 {
    (f64::from(genus * genus) * 4e-15).max(1e-12)
}

fn check_unity(genus: u32, p: ChartPoint) -> Result<(), TestCaseError> {
    let layout = Layout::new(atlas(genus), SplineSettings::default()).unwrap();
    let blends = layout.blends(p);
    let sum: f64 = blends.iter().map(|b| b.1).sum();
    prop_assert!((sum - 1.0).abs() <= 1e-12, "Σ b = {sum} at {p:?}");
    prop_assert!(blends.iter().all(|b| b.1 >= 0.0));
    // The same blends seen from every other chart holding the point (away from the boundary band).
    for rep in atlas(genus).locate_unchecked(p).representations() {
        let margin = atlas(genus).charts()[rep.chart.index()]
            .domain()
            .margin(rep.coords);
        if margin < 1e-9 {
            continue;
        }
        let again = layout.blends(*rep);
        for (a, b) in blends
            .iter()
            .filter(|b| b.1 > 1e-9)
            .zip(again.iter().filter(|b| b.1 > 1e-9))
        {
            prop_assert_eq!(a.0, b.0);
            prop_assert!(
                (a.1 - b.1).abs() <= blend_tolerance(genus),
                "blend of {} differs by {:e}",
                a.0,
                (a.1 - b.1).abs()
            );
        }
    }
    Ok(())
}

macro_rules! unity {
    ($($name:ident: $genus:expr,)*) => {$(
        proptest! {
            #![proptest_config(ProptestConfig { cases: 100_000, failure_persistence: None, ..ProptestConfig::default() })]
            #[test]
            fn $name(chart in 0usize..1000, u in 0.0f64..1.0, v in 0.0f64..1.0) {
                check_unity($genus, chart_point(atlas($genus), chart, u, v))?;
            }
        }
    )*};
}

unity! {
    partition_of_unity_genus_0: 0, partition_of_unity_genus_1: 1, partition_of_unity_genus_2: 2,
    partition_of_unity_genus_3: 3, partition_of_unity_genus_4: 4, partition_of_unity_genus_5: 5,
    partition_of_unity_genus_6: 6, partition_of_unity_genus_7: 7, partition_of_unity_genus_8: 8,
    partition_of_unity_genus_16: 16, partition_of_unity_genus_32: 32,
}

#[test]
fn constant_patches_give_a_point() {
    for genus in [0, 1, 2, 5] {
        let layout = Layout::new(atlas(genus), SplineSettings::default()).unwrap();
        let c = Point3::new(0.3, -1.2, 2.5);
        let control = Model::constant(&layout, c).points();
        for k in 0..2000 {
            let p = chart_point(
                atlas(genus),
                k,
                (k as f64 * 0.618).fract(),
                (k as f64 * 0.414).fract(),
            );
            let s = layout.eval(&control, p);
            assert!(
                (s.pos - c).norm() < 1e-12 && s.du.norm() < 1e-10 && s.duu.norm() < 1e-8,
                "genus {genus}"
            );
        }
    }
}

/// Least-squares coefficients of `f` sampled at `xs` in the 1D basis.
fn fit_1d(basis: &UniformBasis, xs: &[f64], f: impl Fn(f64) -> f64) -> DVector<f64> {
    let m = basis.count();
    let mut a = DMatrix::zeros(xs.len(), m);
    for (r, &x) in xs.iter().enumerate() {
        let (first, v) = basis.eval(x, 0);
        for j in 0..=basis.degree() {
            a[(r, first + j)] = v[0][j];
        }
    }
    let b = DVector::from_iterator(xs.len(), xs.iter().map(|&x| f(x)));
    a.svd(true, true).solve(&b, 1e-14).unwrap()
}

fn eval_1d(basis: &UniformBasis, coef: &DVector<f64>, x: f64) -> f64 {
    let (first, v) = basis.eval(x, 0);
    (0..=basis.degree())
        .map(|j| v[0][j] * coef[first + j])
        .sum()
}

#[test]
fn splines_reproduce_polynomials_up_to_their_degree() {
    for p in 1..=5 {
        let basis = UniformBasis::new(p, p + 5).unwrap();
        let xs: Vec<f64> = (0..200).map(|i| -0.5 + i as f64 / 199.0).collect();
        for k in 0..=p {
            let coef = fit_1d(&basis, &xs, |x| (x + 0.2).powi(k as i32));
            let err = (0..500)
                .map(|i| -0.5 + i as f64 / 499.0)
                .map(|x| (eval_1d(&basis, &coef, x) - (x + 0.2).powi(k as i32)).abs())
                .fold(0.0, f64::max);
            assert!(err < 1e-12, "degree {p} misses x^{k} by {err:e}");
        }
        // One degree more is not reproduced.
        let coef = fit_1d(&basis, &xs, |x| x.powi(p as i32 + 1));
        let err = (0..500)
            .map(|i| -0.5 + i as f64 / 499.0)
            .map(|x| (eval_1d(&basis, &coef, x) - x.powi(p as i32 + 1)).abs())
            .fold(0.0, f64::max);
        assert!(err > 1e-6, "degree {p} should not reproduce x^{}", p + 1);
    }
}

#[test]
fn fitting_converges_at_the_order_the_degree_predicts() {
    // A smooth target on a patch, fitted by tensor-product least squares on a grid of samples (which
    // separates into 1D fits); max error on a finer grid. Error ~ h^(p+1).
    let target = |x: f64, y: f64| (3.0 * x).sin() * (2.0 * y + 0.3).cos() + x * x * y;
    for p in [2usize, 3, 4] {
        let mut errors = Vec::new();
        for m in [8usize, 16, 32] {
            let basis = UniformBasis::new(p, m + p).unwrap();
            let xs: Vec<f64> = (0..4 * (m + p))
                .map(|i| -0.5 + (i as f64 + 0.5) / (4 * (m + p)) as f64)
                .collect();
            // Fit each row in x, then each column of coefficients in y.
            let rows: Vec<DVector<f64>> = xs
                .iter()
                .map(|&y| fit_1d(&basis, &xs, |x| target(x, y)))
                .collect();
            let n = basis.count();
            let coef: Vec<DVector<f64>> = (0..n)
                .map(|i| {
                    let col: Vec<f64> = rows.iter().map(|r| r[i]).collect();
                    fit_1d(&basis, &xs, |y| {
                        let k = xs.iter().position(|&v| v == y).unwrap();
                        col[k]
                    })
                })
                .collect();
            let err = (0..60)
                .flat_map(|a| {
                    (0..60).map(move |b| (-0.5 + a as f64 / 59.0, -0.5 + b as f64 / 59.0))
                })
                .map(|(x, y)| {
                    let vx: Vec<f64> = (0..n).map(|i| eval_1d(&basis, &coef[i], y)).collect();
                    let vx = DVector::from_vec(vx);
                    (eval_1d(&basis, &vx, x) - target(x, y)).abs()
                })
                .fold(0.0, f64::max);
            errors.push(err);
        }
        let orders: Vec<f64> = errors.windows(2).map(|e| (e[0] / e[1]).log2()).collect();
        println!(
            "degree {p}: errors {errors:?}, observed orders {orders:.2?} (predicted {})",
            p + 1
        );
        assert!(
            orders.iter().all(|&o| o > p as f64 + 0.5),
            "degree {p}: orders {orders:?}"
        );
    }
}

#[test]
fn analytic_derivatives_agree_with_finite_differences() {
    for genus in [0, 1, 2, 3] {
        let layout = Layout::new(atlas(genus), SplineSettings::default()).unwrap();
        let control = noisy_controls(&layout, 7 + u64::from(genus));
        for k in 0..300 {
            let p = chart_point(
                atlas(genus),
                k,
                0.05 + 0.9 * (k as f64 * 0.618).fract(),
                (k as f64 * 0.414).fract(),
            );
            let s = layout.eval(&control, p);
            let at = |dw: Complex64| layout.eval(&control, ChartPoint::new(p.chart, p.coords + dw));
            // Central differences of S: error O(h²) (S''' is bounded), so halving h quarters it. Of S_u
            // for the second derivatives: O(h²) away from knots, but S''' jumps across spline knot
            // lines (cubic patches are C²), and within h of one the error is O(h): halving h at
            // least halves it.
            let err = |h: f64| {
                let (u1, u0) = (at(Complex64::new(h, 0.0)), at(Complex64::new(-h, 0.0)));
                let (v1, v0) = (at(Complex64::new(0.0, h)), at(Complex64::new(0.0, -h)));
                let first = ((u1.pos - u0.pos) / (2.0 * h) - s.du)
                    .norm()
                    .max(((v1.pos - v0.pos) / (2.0 * h) - s.dv).norm());
                let second = ((u1.du - u0.du) / (2.0 * h) - s.duu)
                    .norm()
                    .max(((v1.du - v0.du) / (2.0 * h) - s.duv).norm())
                    .max(((v1.dv - v0.dv) / (2.0 * h) - s.dvv).norm());
                (first, second)
            };
            let ((f1, s1), (f2, s2)) = (err(2e-4), err(1e-4));
            let scale = 1.0 + s.duu.norm() + s.dvv.norm() + s.du.norm();
            assert!(
                f2 < 1e-5 * scale,
                "genus {genus}, {p:?}: first derivatives off by {f2:e}"
            );
            // Second derivatives: O(h)·(jump of S''') on a knot line, so only loosely bounded here.
            assert!(
                s2 < 1e-1 * scale,
                "genus {genus}, {p:?}: second derivatives off by {s2:e}"
            );
            assert!(
                f2 < 0.35 * f1 || f2 < 1e-9 * scale,
                "genus {genus}: S_u not second order ({f1:e} → {f2:e})"
            );
            assert!(
                s2 < 0.6 * s1 || s2 < 1e-7 * scale,
                "genus {genus}: S_uu not first order ({s1:e} → {s2:e})"
            );
        }
    }
}

/// max_n |D_j(t_{n+1}) − D_j(t_n)| / h for the j-th finite-difference derivative along a path.
fn variation(f: &impl Fn(f64) -> Point3, j: usize, t0: f64, t1: f64, h: f64) -> f64 {
    let f = |t: f64| f(t).coords;
    let d = |t: f64| match j {
        1 => (f(t + h) - f(t - h)) / (2.0 * h),
        2 => (f(t + h) - 2.0 * f(t) + f(t - h)) / (h * h),
        _ => {
            (f(t + 2.0 * h) - 2.0 * f(t + h) + 2.0 * f(t - h) - f(t - 2.0 * h)) / (2.0 * h * h * h)
        }
    };
    let n = ((t1 - t0) / h) as usize;
    let values: Vec<Vector3> = (0..=n).map(|i| d(t0 + i as f64 * h)).collect();
    values
        .windows(2)
        .map(|w| (w[1] - w[0]).norm())
        .fold(0.0, f64::max)
        / h
}

#[test]
fn the_surface_is_ck_across_every_kind_of_chart_boundary() {
    let genus = 2;
    let atlas = atlas(genus);
    // Paths in chart coordinates: across the polygon's edge (edge chart, a through 0); along an edge
    // past the corners' regions (other edge charts' and the vertex chart's blend supports); through the
    // vertex itself (the vertex chart's centre, where all 4n corners meet); out of the inside chart.
    let paths = [
        (
            ChartId(2),
            Complex64::new(-0.45, 0.05),
            Complex64::new(0.45, 0.05),
        ),
        (
            ChartId(2),
            Complex64::new(-0.1, -0.45),
            Complex64::new(-0.1, 0.45),
        ),
        (
            ChartId(1),
            Complex64::new(-0.4, -0.12),
            Complex64::new(0.4, 0.12),
        ),
        (
            ChartId(0),
            Complex64::new(0.05, 0.02),
            Complex64::new(0.45, 0.2),
        ),
    ];
    // Which chart boundaries the paths cross: record membership changes along each.
    let mut crossed = std::collections::BTreeSet::new();
    for &(chart, a, b) in &paths {
        let members = |t: f64| -> Vec<u32> {
            atlas
                .locate_unchecked(ChartPoint::new(chart, a + (b - a) * t))
                .representations()
                .iter()
                .map(|r| r.chart.0)
                .collect()
        };
        let mut prev = members(0.0);
        for i in 1..=2000 {
            let now = members(i as f64 / 2000.0);
            for c in prev
                .iter()
                .filter(|c| !now.contains(c))
                .chain(now.iter().filter(|c| !prev.contains(c)))
            {
                crossed.insert(
                    atlas.charts()[*c as usize]
                        .kind()
                        .label()
                        .split(' ')
                        .next()
                        .unwrap()
                        .to_string(),
                );
            }
            prev = now;
        }
    }
    assert!(
        crossed.contains("inside") && crossed.contains("vertex") && crossed.contains("edge"),
        "{crossed:?}"
    );
    let poly = atlas.polygon().unwrap();
    let leaves_polygon = |(chart, a, b): (ChartId, Complex64, Complex64)| {
        (0..=100).any(|i| {
            !poly.contains(
                atlas
                    .to_model(ChartPoint::new(chart, a + (b - a) * (i as f64 / 100.0)))
                    .unwrap()
                    .0,
                0.0,
            )
        })
    };
    assert!(
        leaves_polygon(paths[0]),
        "path 0 crosses the polygon's edge"
    );

    for (k, degree) in [(1usize, 3usize), (2, 3), (3, 4)] {
        let layout = Layout::new(
            atlas,
            SplineSettings {
                degree,
                continuity: k,
                grid: 8,
                // A finer grid in the disk charts: the surface is C^k wherever grids differ too.
                disk_grid: Some(13),
            },
        )
        .unwrap();
        let control = noisy_controls(&layout, 11);
        let mut jump_seen = false;
        for &(chart, a, b) in &paths {
            let f = |t: f64| {
                layout
                    .eval(&control, ChartPoint::new(chart, a + (b - a) * t))
                    .pos
            };
            let (t0, t1) = (0.01, 0.99);
            for j in 1..=k {
                let (r1, r2) = (
                    variation(&f, j, t0, t1, 2e-3),
                    variation(&f, j, t0, t1, 1e-3),
                );
                // Continuous: the variation per step scales with h, so r stays put; a jump doubles it.
                assert!(
                    r2 < 1.5 * r1,
                    "k = {k}: derivative {j} jumps on path {chart} ({r1:e} → {r2:e})"
                );
            }
            let (r1, r2) = (
                variation(&f, k + 1, t0, t1, 2e-3),
                variation(&f, k + 1, t0, t1, 1e-3),
            );
            jump_seen |= r2 > 1.7 * r1;
        }
        // The detector is not blind: with C^k blends, derivative k + 1 does jump somewhere.
        if k < 3 {
            assert!(
                jump_seen,
                "k = {k}: expected derivative {} to jump somewhere",
                k + 1
            );
        }
    }
}

#[test]
fn stencils_equal_direct_evaluation_and_update_in_part() {
    for genus in [0, 1, 2, 3] {
        let atlas = atlas(genus);
        let layout = Layout::new(atlas, SplineSettings::default()).unwrap();
        let mut control = noisy_controls(&layout, 3);
        let t = atlas.tessellate(4, 3).unwrap();
        let stencil = Stencil::build(&layout, &t.vertices);
        let mut pos = vec![Point3::origin(); t.vertices.len()];
        stencil.positions(&control, &mut pos);
        let (mut du, mut dv) = (
            vec![Vector3::zeros(); pos.len()],
            vec![Vector3::zeros(); pos.len()],
        );
        stencil.derivatives(&control, &mut du, &mut dv);
        for (i, &v) in t.vertices.iter().enumerate() {
            let s = layout.eval(&control, v);
            assert!((s.pos - pos[i]).norm() <= 1e-12, "genus {genus}");
            assert!((s.du - du[i]).norm() <= 1e-12 && (s.dv - dv[i]).norm() <= 1e-12);
        }
        // Move a few control points; the partial update equals a full re-evaluation.
        let index = stencil.column_index(layout.control_count());
        for (n, c) in [5usize, 77, layout.control_count() - 1]
            .into_iter()
            .enumerate()
        {
            let delta = Vector3::new(0.1, -0.2 * n as f64, 0.05);
            control[c] += delta;
            stencil.update(&index, c, delta, &mut pos);
        }
        let mut full = vec![Point3::origin(); t.vertices.len()];
        stencil.positions(&control, &mut full);
        let worst = pos
            .iter()
            .zip(&full)
            .map(|(a, b)| (a - b).norm())
            .fold(0.0, f64::max);
        assert!(
            worst <= 1e-12,
            "genus {genus}: partial update off by {worst:e}"
        );
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(32))]

    /// The stencil's first-order build gives every row the very control points of
    /// `Layout::weights` (the one routine direct evaluation uses) with their weights and first
    /// derivatives to rounding, for any genus, degree, grid and continuity; built on all cores it
    /// is the same stencil bit for bit.
    #[test]
    fn stencil_rows_are_the_layout_weights(
        genus in prop::sample::select(vec![0u32, 1, 2, 3, 5, 8, 16]),
        degree in 2usize..=5,
        grid in 8usize..=20,
        continuity in 1usize..=3,
        disk in prop::option::of(4usize..=28),
        units in prop::collection::vec((0usize..1000, 0.0f64..1.0, 0.0f64..1.0), 1..400),
    ) {
        let atlas = atlas(genus);
        let settings = SplineSettings { degree, grid, continuity, disk_grid: disk.map(|d| d.max(degree + 1)) };
        let layout = Layout::new(atlas, settings).unwrap();
        let mut points: Vec<ChartPoint> = units.iter().map(|&(a, b, c)| chart_point(atlas, a, b, c)).collect();
        // Chart boundaries, corners, the vertex chart's centre; and more rows than one task holds.
        let tessellation = atlas.tessellate(4, 3).unwrap().vertices;
        while points.len() <= 4096 {
            points.extend_from_slice(&tessellation);
        }
        let stencil = Stencil::build(&layout, &points);
        prop_assert_eq!(stencil.rows(), points.len());
        let mut expected = Vec::new();
        for (r, &p) in points.iter().enumerate() {
            expected.clear();
            layout.weights(p, &mut expected);
            expected.sort_unstable_by_key(|w| w.control);
            let row: Vec<(u32, [f64; 3])> = stencil.row(r).collect();
            prop_assert_eq!(row.len(), expected.len(), "row {}", r);
            // A derivative's scale: the grid's spacing in the chart, through the transition.
            let scale = expected.iter().map(|w| w.jet.du.abs().max(w.jet.dv.abs())).fold(1.0, f64::max);
            for ((control, [val, du, dv]), w) in row.iter().zip(&expected) {
                prop_assert_eq!(*control, w.control);
                prop_assert!((val - w.jet.val).abs() <= 1e-14, "row {}: weight {} against {}", r, val, w.jet.val);
                prop_assert!((du - w.jet.du).abs() <= 1e-13 * scale, "row {}: du {} against {}", r, du, w.jet.du);
                prop_assert!((dv - w.jet.dv).abs() <= 1e-13 * scale, "row {}: dv {} against {}", r, dv, w.jet.dv);
            }
        }
        prop_assert_eq!(Stencil::build_parallel(&layout, &points), stencil);
    }

    /// `Layout::weight_values` (the fit's data rows) gives `Layout::weights`' values bit for bit,
    /// control point by control point in the same order, and the same normalising sum.
    #[test]
    fn weight_values_are_the_weights_values_bit_for_bit(
        genus in prop::sample::select(vec![0u32, 1, 2, 3, 5, 8, 16]),
        degree in 1usize..=5,
        grid in 8usize..=48,
        continuity in 1usize..=4,
        disk in prop::option::of(4usize..=28),
        units in prop::collection::vec((0usize..1000, 0.0f64..1.0, 0.0f64..1.0), 1..200),
    ) {
        let atlas = atlas(genus);
        let settings = SplineSettings { degree, grid, continuity, disk_grid: disk.map(|d| d.max(degree + 1)) };
        let layout = Layout::new(atlas, settings).unwrap();
        let mut points: Vec<ChartPoint> = units.iter().map(|&(a, b, c)| chart_point(atlas, a, b, c)).collect();
        points.extend_from_slice(&atlas.tessellate(2, 2).unwrap().vertices);
        let (mut jets, mut values) = (Vec::new(), Vec::new());
        for &p in &points {
            jets.clear();
            values.clear();
            let sum = layout.weights(p, &mut jets);
            let value_sum = layout.weight_values(p, &mut values);
            prop_assert_eq!(sum.val.to_bits(), value_sum.to_bits());
            let expected: Vec<(u32, u64)> = jets.iter().map(|w| (w.control, w.jet.val.to_bits())).collect();
            let got: Vec<(u32, u64)> = values.iter().map(|&(c, v)| (c, v.to_bits())).collect();
            prop_assert_eq!(got, expected, "at {:?}", p);
        }
    }
}

#[test]
fn models_round_trip_and_refuse_newer_versions() {
    let layout = Layout::new(atlas(2), SplineSettings::default()).unwrap();
    let mut model = Model::constant(&layout, Point3::new(1.0, 2.0, 3.0));
    model.control_points[3] = [0.1, f64::MIN_POSITIVE, -7.25];
    let json = serde_json::to_string(&model).unwrap();
    let back: Model = serde_json::from_str(&json).unwrap();
    assert_eq!(back, model);
    assert!(back.validate(&layout).is_ok());
    let header: embedding::ModelHeader =
        serde_json::from_str(&json.replace("\"version\":1", "\"version\":99")).unwrap();
    assert!(matches!(
        header.check(),
        Err(embedding::EmbeddingError::FutureVersion { version: 99, .. })
    ));
    let mut broken = model.clone();
    broken.control_points.pop();
    assert!(matches!(
        broken.validate(&layout),
        Err(embedding::EmbeddingError::ControlCount { .. })
    ));
    broken = model;
    broken.control_points[0][1] = f64::NAN;
    assert!(matches!(
        broken.validate(&layout),
        Err(embedding::EmbeddingError::NotFinite(0))
    ));
}

#[test]
fn curvature_and_normals_do_not_depend_on_the_chart() {
    // K and H are invariants of the surface: computed in any chart holding a point, they agree (the
    // transitions are orientation-preserving, so the normal and the sign of H agree too).
    for genus in [0, 1, 2, 3, 8] {
        let atlas = atlas(genus);
        let layout = Layout::new(atlas, SplineSettings::default()).unwrap();
        let control = noisy_controls(&layout, 5);
        let mut compared = 0;
        for k in 0..3000 {
            let p = chart_point(
                atlas,
                k,
                (k as f64 * 0.618).fract(),
                (k as f64 * 0.414).fract(),
            );
            let s = layout.eval(&control, p);
            for rep in atlas
                .locate_unchecked(p)
                .representations()
                .iter()
                .filter(|r| r.chart != p.chart)
            {
                if atlas.charts()[rep.chart.index()]
                    .domain()
                    .margin(rep.coords)
                    < 1e-6
                {
                    continue;
                }
                let t = layout.eval(&control, *rep);
                let tol = 1e-8 * (1.0 + s.gaussian_curvature().abs());
                assert!((s.pos - t.pos).norm() < 1e-12);
                assert!(
                    (s.normal() - t.normal()).norm() < 1e-9,
                    "genus {genus}: normals differ"
                );
                assert!(
                    (s.gaussian_curvature() - t.gaussian_curvature()).abs() < tol,
                    "genus {genus}: K differs"
                );
                assert!(
                    (s.mean_curvature() - t.mean_curvature()).abs()
                        < 1e-8 * (1.0 + s.mean_curvature().abs())
                );
                compared += 1;
            }
        }
        assert!(
            compared > 1000,
            "genus {genus}: only {compared} overlaps compared"
        );
    }
}

/// A surface of `genus` with pseudo-random control points.
fn noisy_surface(genus: u32, seed: u64) -> embedding::Surface {
    let atlas = std::sync::Arc::new(Atlas::new(genus).unwrap());
    let settings = SplineSettings {
        grid: 6,
        ..SplineSettings::default()
    };
    let control = noisy_controls(&Layout::new(&atlas, settings).unwrap(), seed);
    embedding::Surface::new(atlas, settings, control).unwrap()
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]

    /// The one evaluation path: `evaluate` (stencils per chunk) and `evaluate_rows` (a kept
    /// stencil) hand the sink the same samples, in index order, equal to direct evaluation.
    #[test]
    fn the_evaluation_path_agrees_with_direct_evaluation(
        genus in prop::sample::select(vec![0u32, 1, 2, 3, 5, 8]),
        seed in any::<u64>(),
        units in prop::collection::vec((0usize..1000, 0.0f64..1.0, 0.0f64..1.0), 1..300),
    ) {
        let surface = noisy_surface(genus, seed);
        let points: Vec<ChartPoint> = units
            .iter()
            .map(|&(a, b, c)| chart_point(surface.atlas(), a, b, c))
            .collect();
        let wants = embedding::Wants { curvature: true, blends: true };
        let mut all = Vec::new();
        embedding::evaluate(&surface, &points, wants, 0.0, &mut |s: &embedding::Sample| {
            all.push(s.clone())
        });
        prop_assert_eq!(all.len(), points.len());
        let layout = surface.layout();
        for (i, s) in all.iter().enumerate() {
            prop_assert_eq!(s.index, i);
            let direct = surface.eval(points[i]);
            prop_assert!((s.position - direct.pos).norm() <= 1e-12);
            // The position-only path (the remesher's chordal tests) is the same point.
            prop_assert!((surface.position(points[i]) - direct.pos).norm() <= 1e-12);
            prop_assert!((s.du - direct.du).norm() <= 1e-9 * (1.0 + direct.du.norm()));
            let cross = s.du.cross(&s.dv);
            prop_assert!((cross - direct.du.cross(&direct.dv)).norm() <= 1e-9 * (1.0 + cross.norm()));
            match s.normal {
                Some(m) => prop_assert!((m - cross / cross.norm()).norm() <= 1e-15),
                None => prop_assert!(cross.norm() == 0.0),
            }
            let k = s.curvature.unwrap();
            prop_assert_eq!(k.gaussian, direct.gaussian_curvature());
            prop_assert_eq!(&s.blends, &layout.blends(points[i]));
        }
        // Every other row through a kept stencil: the very same numbers.
        let stencil = Stencil::build(&layout, &points);
        let rows: Vec<u32> = (0..points.len() as u32).step_by(2).collect();
        let mut some = Vec::new();
        embedding::evaluate_rows(&surface, &stencil, &points, &rows, wants, 0.0, &mut |s: &embedding::Sample| {
            some.push(s.clone())
        });
        prop_assert_eq!(some.len(), rows.len());
        for (s, &r) in some.iter().zip(&rows) {
            prop_assert_eq!(s, &all[r as usize]);
        }
    }
}

/// The layout numbers control points chart by chart with the disk charts' grid for a prefix of
/// the atlas's charts: that prefix must be exactly its disk charts, at every genus.
#[test]
fn every_atlas_lists_its_disk_charts_first() {
    for genus in 0..=charts::MAX_GENUS {
        let atlas = Atlas::new(genus).unwrap();
        let kinds: Vec<charts::Domain> = atlas.charts().iter().map(|c| c.domain()).collect();
        let disks = kinds
            .iter()
            .take_while(|&&d| d == charts::Domain::Disk)
            .count();
        assert!(
            kinds[disks..].iter().all(|&d| d == charts::Domain::Square),
            "genus {genus}: {kinds:?}"
        );
        assert_eq!(
            disks, 2,
            "genus {genus}: the caps, or the inside and vertex charts"
        );
    }
}

/// A model whose disk charts have their own grid is written as version 3 and read back equal; one
/// without is still version 1 (what every build reads); a disk grid in an older version is
/// refused rather than read with the wrong control point layout.
#[test]
fn a_disk_grid_round_trips_as_version_3_and_only_there() {
    for genus in [0, 1, 2, 5] {
        let atlas = std::sync::Arc::new(Atlas::new(genus).unwrap());
        let settings = SplineSettings {
            grid: 6,
            disk_grid: Some(9),
            ..SplineSettings::default()
        };
        let layout = Layout::new(&atlas, settings).unwrap();
        let disks = atlas
            .charts()
            .iter()
            .filter(|c| c.domain() == charts::Domain::Disk)
            .count();
        assert_eq!(
            layout.control_count(),
            disks * 81 + (atlas.charts().len() - disks) * 36
        );
        let surface =
            embedding::Surface::new(atlas.clone(), settings, noisy_controls(&layout, 3)).unwrap();
        let model = surface.to_model();
        assert_eq!(model.version, embedding::DISK_GRID_VERSION);
        assert_eq!(embedding::Surface::from_model(&model).unwrap(), surface);
        let mut old = model.clone();
        old.version = 2;
        assert_eq!(
            embedding::Surface::from_model(&old),
            Err(embedding::EmbeddingError::DiskGridVersion {
                grid: 9,
                version: 2
            })
        );
    }
    assert_eq!(noisy_surface(2, 7).to_model().version, 1);
}

#[test]
fn surfaces_are_validated_once_when_built() {
    let surface = noisy_surface(2, 7);
    // Round trip through the document.
    let model = surface.to_model();
    assert_eq!(embedding::Surface::from_model(&model).unwrap(), surface);
    // Wrong counts and non-finite points are refused, and leave the surface as it was.
    let mut short = surface.control_points().to_vec();
    short.pop();
    assert!(matches!(
        surface.with_control_points(short),
        Err(embedding::EmbeddingError::ControlCount { .. })
    ));
    let mut edited = surface.clone();
    let bad = [
        (embedding::ControlId(3), Point3::new(1.0, 2.0, 3.0)),
        (embedding::ControlId(5), Point3::new(f64::NAN, 0.0, 0.0)),
    ];
    assert_eq!(
        edited.set_control_points_at(bad),
        Err(embedding::EmbeddingError::NotFinite(5))
    );
    assert_eq!(edited, surface);
    let good = [(embedding::ControlId(3), Point3::new(1.0, 2.0, 3.0))];
    edited.set_control_points_at(good).unwrap();
    assert_eq!(edited.control_points()[3], Point3::new(1.0, 2.0, 3.0));
    assert_ne!(edited, surface);
    // A model of another genus than its control points fits is refused.
    let mut other = model.clone();
    other.genus = 3;
    assert!(embedding::Surface::from_model(&other).is_err());
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(32))]

    /// The tensor stencil (f32 factors, sums about the centre, negligible blends left out) gives the
    /// f64 stencil's positions to 1e-6 of the bounding-box diagonal, for any genus, degree, grid and
    /// blend continuity, and wherever the model sits; all cores give the very same numbers.
    #[test]
    fn tensor_stencil_positions_match_the_f64_stencil(
        genus in prop::sample::select(vec![0u32, 1, 2, 3, 5, 8, 16]),
        degree in 2usize..=5,
        grid in 8usize..=20,
        continuity in 1usize..=3,
        disk in prop::option::of(4usize..=28),
        seed in any::<u64>(),
        offset in prop::array::uniform3(-1e4f64..1e4),
        units in prop::collection::vec((0usize..1000, 0.0f64..1.0, 0.0f64..1.0), 1..400),
    ) {
        let atlas = atlas(genus);
        let settings = SplineSettings { degree, grid, continuity, disk_grid: disk.map(|d| d.max(degree + 1)) };
        let layout = Layout::new(atlas, settings).unwrap();
        let shift = Vector3::from(offset);
        let control: Vec<Point3> = noisy_controls(&layout, seed).into_iter().map(|c| c + shift).collect();
        let mut points: Vec<ChartPoint> = units.iter().map(|&(a, b, c)| chart_point(atlas, a, b, c)).collect();
        // And a whole coarse tessellation: chart boundaries, corners, the vertex chart's centre.
        points.extend(atlas.tessellate(3, 2).unwrap().vertices);
        let exact_stencil = Stencil::build(&layout, &points);
        let tensor = embedding::TensorStencil::build(&layout, &points);
        prop_assert_eq!(tensor.rows(), points.len());
        let mut exact = vec![Point3::origin(); points.len()];
        exact_stencil.positions(&control, &mut exact);
        let mut fast = vec![Point3::origin(); points.len()];
        tensor.positions(&control, &mut fast);
        let (lo, hi) = embedding::bounding_box(&exact);
        let diagonal = (hi - lo).norm();
        let worst = fast.iter().zip(&exact).map(|(a, b)| (a - b).norm()).fold(0.0, f64::max);
        prop_assert!(worst <= 1e-6 * diagonal, "off by {:e} of the diagonal", worst / diagonal);
        let mut parallel = vec![Point3::origin(); points.len()];
        tensor.positions_parallel(&control, &mut parallel);
        prop_assert_eq!(parallel, fast);
        // Far fewer bytes than the full stencil's (p+1)² weights per chart.
        let full_bytes = 12.0 * exact_stencil.nonzeros() as f64 / points.len() as f64 + 8.0 + 24.0;
        prop_assert!(tensor.bytes_per_row() < 0.6 * full_bytes);
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]

    /// Built with tangents, the tensor stencil gives the f64 stencil's first derivatives S_u, S_v
    /// (in each row's own chart: blend gradients and transitions' chain rule included) to 1e-5 of
    /// the largest tangent, and its positions to 1e-6 of the diagonal, for any genus, degree, grid,
    /// continuity and offset; all cores, and any subset of rows, give the very same numbers.
    #[test]
    fn tensor_stencil_tangents_match_the_f64_stencil(
        genus in prop::sample::select(vec![0u32, 1, 2, 3, 5, 8, 16]),
        degree in 2usize..=5,
        grid in 8usize..=20,
        continuity in 1usize..=3,
        disk in prop::option::of(4usize..=28),
        seed in any::<u64>(),
        offset in prop::array::uniform3(-1e4f64..1e4),
        units in prop::collection::vec((0usize..1000, 0.0f64..1.0, 0.0f64..1.0), 1..300),
    ) {
        let atlas = atlas(genus);
        let settings = SplineSettings { degree, grid, continuity, disk_grid: disk.map(|d| d.max(degree + 1)) };
        let layout = Layout::new(atlas, settings).unwrap();
        let shift = Vector3::from(offset);
        let control: Vec<Point3> = noisy_controls(&layout, seed).into_iter().map(|c| c + shift).collect();
        let mut points: Vec<ChartPoint> = units.iter().map(|&(a, b, c)| chart_point(atlas, a, b, c)).collect();
        points.extend(atlas.tessellate(3, 2).unwrap().vertices);
        let exact_stencil = Stencil::build(&layout, &points);
        let tensor = embedding::TensorStencil::build_with_tangents(&layout, &points);
        prop_assert!(tensor.has_tangents());
        let n = points.len();
        let mut positions = vec![Point3::origin(); n];
        let mut tangents = vec![[Vector3::zeros(); 2]; n];
        tensor.positions_and_tangents(&control, &mut positions, &mut tangents);
        let exact: Vec<(Point3, [Vector3; 2])> =
            (0..n).map(|r| exact_stencil.position_and_tangents(&control, r)).collect();
        let exact_positions: Vec<Point3> = exact.iter().map(|e| e.0).collect();
        let (lo, hi) = embedding::bounding_box(&exact_positions);
        let diagonal = (hi - lo).norm();
        let scale = exact.iter().flat_map(|e| e.1).map(|t| t.norm()).fold(0.0, f64::max);
        for (r, (e, (p, t))) in exact.iter().zip(positions.iter().zip(&tangents)).enumerate() {
            prop_assert!((p - e.0).norm() <= 1e-6 * diagonal, "row {}: position", r);
            for (k, (a, b)) in t.iter().zip(&e.1).enumerate() {
                let off = (a - b).norm();
                prop_assert!(off <= 1e-5 * scale, "row {}: tangent {} off by {:e} of the largest", r, k, off / scale);
            }
        }
        let mut all = (vec![Point3::origin(); n], vec![[Vector3::zeros(); 2]; n]);
        tensor.positions_and_tangents_parallel(&control, &mut all.0, &mut all.1);
        prop_assert_eq!(&all.0, &positions);
        prop_assert_eq!(&all.1, &tangents);
        // Some rows alone, in any order, give those rows' very numbers.
        let some: Vec<u32> = (0..n as u32).rev().step_by(3).collect();
        let mut jets = vec![(Point3::origin(), [Vector3::zeros(); 2]); some.len()];
        tensor.rows_positions_and_tangents(&control, &some, &mut jets);
        for (&r, jet) in some.iter().zip(&jets) {
            prop_assert_eq!(jet.0, positions[r as usize]);
            prop_assert_eq!(jet.1, tangents[r as usize]);
        }
        // After some control points move, with no lag allowed the rows that use them are updated
        // (to a fresh evaluation's very numbers), and every other row stays, where the f64
        // stencil says it moves by no more than the tensor stencil's own error.
        let moved: Vec<u32> = (0..layout.control_count() as u32)
            .filter(|c| (c ^ seed as u32).is_multiple_of(7))
            .collect();
        let step = Vector3::new(1.0, -2.0, 0.5) * (1e-2 * diagonal);
        let mut after = control.clone();
        for &c in &moved {
            after[c as usize] += step;
        }
        let displaced: Vec<(u32, Vector3)> = moved.iter().map(|&c| (c, step)).collect();
        let (mut updated, mut updated_tangents) = (positions.clone(), tangents.clone());
        let mut lag = vec![0f32; n];
        let followed = tensor.follow_controls(
            &after,
            &displaced,
            0.0,
            &mut lag,
            &mut updated,
            &mut updated_tangents,
            |p, t, position, tangents| (*p, *t) = (position, tangents),
        );
        let rows = followed.rows;
        prop_assert!(rows.windows(2).all(|w| w[0] < w[1]));
        // Every moved point moved the same way, so the bound is the motion itself: the largest
        // lag reported is how far the row that moved most went.
        let farthest = rows
            .iter()
            .map(|&r| (updated[r as usize] - positions[r as usize]).norm())
            .fold(0.0, f64::max);
        prop_assert!(
            (followed.largest_lag - farthest).abs() <= 1e-5 * farthest + 1e-6 * diagonal,
            "largest lag {:e}, farthest {:e}", followed.largest_lag, farthest
        );
        prop_assert!(lag.iter().all(|&l| l == 0.0));
        let mut fresh = (vec![Point3::origin(); n], vec![[Vector3::zeros(); 2]; n]);
        tensor.positions_and_tangents(&after, &mut fresh.0, &mut fresh.1);
        for r in 0..n {
            if rows.binary_search(&(r as u32)).is_ok() {
                prop_assert_eq!(updated[r], fresh.0[r]);
                prop_assert_eq!(updated_tangents[r], fresh.1[r]);
            } else {
                prop_assert_eq!(updated[r], positions[r]);
                let truth = exact_stencil.position(&after, r);
                prop_assert!((truth - updated[r]).norm() <= 1e-6 * diagonal, "row {} left behind", r);
            }
        }
        // With a lag allowed, over rounds of small motions of varying size and direction every
        // row stays within its lag of the surface, and its lag within the threshold; the rows
        // evaluated are exact.
        let threshold = 1e-3 * diagonal;
        let mut now = after;
        for round in 0..6u32 {
            let displaced: Vec<(u32, Vector3)> = moved
                .iter()
                .enumerate()
                .map(|(k, &c)| {
                    let phase = f64::from(round) + k as f64 * 0.7;
                    let d = Vector3::new(phase.sin(), phase.cos(), (2.0 * phase).sin());
                    (c, d * (threshold * (0.05 + 0.3 * ((k % 5) as f64 / 4.0))))
                })
                .collect();
            for &(c, d) in &displaced {
                now[c as usize] += d;
            }
            let written = updated.clone();
            let followed = tensor.follow_controls(
                &now,
                &displaced,
                threshold,
                &mut lag,
                &mut updated,
                &mut updated_tangents,
                |p, t, position, tangents| (*p, *t) = (position, tangents),
            );
            let rows = followed.rows;
            // An evaluated row moved by no more than the largest lag reported.
            for &r in &rows {
                let moved = (updated[r as usize] - written[r as usize]).norm();
                prop_assert!(moved <= followed.largest_lag * (1.0 + 1e-5) + 1e-6 * diagonal, "row {}: moved {:e}, largest lag {:e}", r, moved, followed.largest_lag);
            }
            tensor.positions_and_tangents(&now, &mut fresh.0, &mut fresh.1);
            for r in 0..n {
                prop_assert!(f64::from(lag[r]) < threshold, "row {}: lag {} at or over the threshold", r, lag[r]);
                let off = (updated[r] - fresh.0[r]).norm();
                prop_assert!(
                    off <= f64::from(lag[r]) * (1.0 + 1e-5) + 1e-6 * diagonal,
                    "round {}, row {}: {:e} off, lag {:e}", round, r, off, lag[r]
                );
            }
            for &r in &rows {
                prop_assert_eq!(updated[r as usize], fresh.0[r as usize]);
            }
        }
    }
}

/// Over many parallel tasks, all cores give the one-thread numbers: every stencil and every way
/// of applying one. 6·10⁴ rows are past each size from which the work is split over the cores
/// (small jobs run on the calling thread: the pool's round trip would cost more; the fastest
/// kernel's positions, 5 ns a row, split from 5·10⁴).
#[test]
fn stencils_give_the_same_numbers_on_all_cores() {
    let atlas = atlas(2);
    let layout = Layout::new(atlas, SplineSettings::default()).unwrap();
    let control = noisy_controls(&layout, 11);
    let points = atlas.tessellate(56, 56).unwrap().vertices;
    assert!(points.len() > 60_000);
    let n = points.len();
    let one_thread = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let all_cores = rayon::ThreadPoolBuilder::new()
        .num_threads(3)
        .build()
        .unwrap();
    let both = |f: &(dyn Fn() -> Vec<Point3> + Sync)| (one_thread.install(f), all_cores.install(f));

    // The column index: the same on all cores, and for each control point exactly the rows that
    // use it, in order.
    let stencil = Stencil::build(&layout, &points);
    let count = layout.control_count();
    let index = one_thread.install(|| stencil.column_index(count));
    assert_eq!(index, all_cores.install(|| stencil.column_index(count)));
    let mut users = vec![Vec::new(); count];
    for r in 0..stencil.rows() {
        for (c, w) in stencil.row(r) {
            users[c as usize].push((r as u32, w));
        }
    }
    for (c, column) in users.iter().enumerate() {
        assert!(
            stencil.column(&index, c).eq(column.iter().copied()),
            "control point {c}"
        );
    }

    let (one, all) = both(&|| {
        let stencil = Stencil::build_parallel(&layout, &points);
        assert_eq!(stencil, Stencil::build(&layout, &points));
        let mut out = vec![Point3::origin(); n];
        stencil.positions(&control, &mut out);
        out
    });
    assert_eq!(one, all, "the f64 stencil");

    let tensor = embedding::TensorStencil::build(&layout, &points);
    let (one, all) = both(&|| {
        let mut out = vec![Point3::origin(); n];
        tensor.positions_parallel(&control, &mut out);
        out
    });
    assert_eq!(one, all, "tensor positions");
    let (one_built, all_built) = both(&|| {
        let mut out = vec![Point3::origin(); n];
        embedding::TensorStencil::build(&layout, &points).positions(&control, &mut out);
        out
    });
    assert_eq!(one_built, all_built, "the tensor stencil built");
    assert_eq!(one, one_built);

    let framed = embedding::TensorStencil::build_with_tangents(&layout, &points);
    let frames = |out: &mut Vec<Point3>, jets: &[(Point3, [Vector3; 2])]| {
        out.extend(
            jets.iter()
                .flat_map(|(p, [u, v])| [*p, Point3::from(*u), Point3::from(*v)]),
        );
    };
    let (one, all) = both(&|| {
        let (mut p, mut t) = (vec![Point3::origin(); n], vec![[Vector3::zeros(); 2]; n]);
        framed.positions_and_tangents_parallel(&control, &mut p, &mut t);
        let jets: Vec<_> = p.into_iter().zip(t).collect();
        let mut out = Vec::new();
        frames(&mut out, &jets);
        // Every other row alone, backwards.
        let some: Vec<u32> = (0..n as u32).rev().step_by(2).collect();
        let mut picked = vec![(Point3::origin(), [Vector3::zeros(); 2]); some.len()];
        framed.rows_positions_and_tangents(&control, &some, &mut picked);
        for (&r, jet) in some.iter().zip(&picked) {
            assert_eq!(*jet, jets[r as usize], "row {r} alone");
        }
        // A third of the control points moved: every row that uses one, followed with no lag.
        let moved: Vec<(u32, Vector3)> = (0..control.len() as u32)
            .filter(|c| c % 3 == 0)
            .map(|c| (c, Vector3::new(0.01, -0.02, 0.03)))
            .collect();
        let mut after = control.clone();
        for &(c, d) in &moved {
            after[c as usize] += d;
        }
        let (mut lag, mut p, mut t) = (vec![0f32; n], jets.clone(), vec![(); n]);
        let followed = framed.follow_controls(
            &after,
            &moved,
            0.0,
            &mut lag,
            &mut p,
            &mut t,
            |a, _, p, t| *a = (p, t),
        );
        assert!(
            followed.rows.len() > n / 2,
            "{} rows followed",
            followed.rows.len()
        );
        assert!(followed.rows.windows(2).all(|w| w[0] < w[1]));
        out.extend(
            followed
                .rows
                .iter()
                .map(|&r| Point3::new(r as f64, 0.0, 0.0)),
        );
        frames(&mut out, &p);
        out
    });
    assert_eq!(one, all, "tangents, rows alone, rows followed");
}

/// The grids the kernel tests run on: the default (every chart's grid the same size, the
/// AVX-512 kernels' one line stride) and disk charts' grids larger than the squares', by an odd
/// number of points (their other path, a stride per block).
fn kernel_grids() -> [SplineSettings; 2] {
    [
        SplineSettings::default(),
        SplineSettings {
            grid: 14,
            disk_grid: Some(23),
            ..SplineSettings::default()
        },
    ]
}

/// Every kernel this CPU runs (the portable one, AVX with FMA, AVX-512) gives the f64 stencil's
/// positions to 1e-6 of the diagonal, and the same as the portable kernel to rounding, with equal
/// and with unequal grids. A kernel the CPU lacks is not run (this machine and CI's, Zen 5, run
/// all three).
#[test]
fn every_kernel_gives_the_f64_stencil_s_positions() {
    let kernels: Vec<StencilKernel> = StencilKernel::ALL
        .into_iter()
        .filter(|k| k.available())
        .collect();
    assert_eq!(kernels.last(), Some(&StencilKernel::fastest()));
    for (genus, settings) in [0, 2, 5]
        .into_iter()
        .flat_map(|g| kernel_grids().map(|s| (g, s)))
    {
        let atlas = atlas(genus);
        let layout = Layout::new(atlas, settings).unwrap();
        let control = noisy_controls(&layout, 5);
        let points = atlas.tessellate(12, 9).unwrap().vertices;
        let tensor = embedding::TensorStencil::build(&layout, &points);
        let mut exact = vec![Point3::origin(); points.len()];
        Stencil::build(&layout, &points).positions(&control, &mut exact);
        let (lo, hi) = embedding::bounding_box(&exact);
        let diagonal = (hi - lo).norm();
        let by = |kernel| {
            let mut out = vec![Point3::origin(); points.len()];
            tensor.positions_by(kernel, &control, &mut out);
            out
        };
        let portable = by(StencilKernel::Portable);
        for &kernel in &kernels {
            let out = by(kernel);
            for ((a, b), c) in out.iter().zip(&portable).zip(&exact) {
                assert!(
                    (a - b).norm() <= 1e-6 * diagonal,
                    "genus {genus}, {settings:?}, {kernel:?}"
                );
                assert!(
                    (a - c).norm() <= 1e-6 * diagonal,
                    "genus {genus}, {settings:?}, {kernel:?}"
                );
            }
        }
        let mut fastest = vec![Point3::origin(); points.len()];
        tensor.positions(&control, &mut fastest);
        assert_eq!(
            fastest,
            by(StencilKernel::fastest()),
            "positions runs the fastest"
        );
    }
}

/// Every kernel this CPU runs gives the portable kernel's positions and tangents to rounding (1e-6
/// of the diagonal, 1e-6 of the largest tangent), with equal and with unequal grids, and
/// `positions_and_tangents` runs the fastest.
#[test]
fn every_tangent_kernel_agrees_with_the_portable_one() {
    for (genus, settings) in [0, 2, 5]
        .into_iter()
        .flat_map(|g| kernel_grids().map(|s| (g, s)))
    {
        let atlas = atlas(genus);
        let layout = Layout::new(atlas, settings).unwrap();
        let control = noisy_controls(&layout, 9);
        let points = atlas.tessellate(12, 9).unwrap().vertices;
        let tensor = embedding::TensorStencil::build_with_tangents(&layout, &points);
        let n = points.len();
        let by = |kernel| {
            let mut out = (vec![Point3::origin(); n], vec![[Vector3::zeros(); 2]; n]);
            tensor.positions_and_tangents_by(kernel, &control, &mut out.0, &mut out.1);
            out
        };
        let portable = by(StencilKernel::Portable);
        let (lo, hi) = embedding::bounding_box(&portable.0);
        let diagonal = (hi - lo).norm();
        let largest = portable
            .1
            .iter()
            .flatten()
            .map(|t| t.norm())
            .fold(0.0, f64::max);
        for kernel in StencilKernel::ALL.into_iter().filter(|k| k.available()) {
            let fast = by(kernel);
            for r in 0..n {
                assert!(
                    (fast.0[r] - portable.0[r]).norm() <= 1e-6 * diagonal,
                    "genus {genus}, {settings:?}, {kernel:?}"
                );
                for k in 0..2 {
                    let off = (fast.1[r][k] - portable.1[r][k]).norm();
                    assert!(
                        off <= 1e-6 * largest,
                        "genus {genus}, {settings:?}, {kernel:?}, row {r}: {off:e}"
                    );
                }
            }
        }
        let mut fastest = (vec![Point3::origin(); n], vec![[Vector3::zeros(); 2]; n]);
        tensor.positions_and_tangents(&control, &mut fastest.0, &mut fastest.1);
        assert_eq!(fastest, by(StencilKernel::fastest()), "the fastest runs");
    }
}
