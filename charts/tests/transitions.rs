//! Transition functions: ψ_ii = id, ψ_ji ∘ ψ_ij = id and ψ_jk ∘ ψ_ij = ψ_ik, over 10^5 random chart
//! points for each genus, to 1e-12 in chart units; and point location finds every chart holding a
//! point (compared with an independent path through the model space and the tiling).

use std::sync::OnceLock;

use charts::check::{BOUNDARY_BAND, consistency_at};
use charts::{Atlas, ChartId, ChartPoint, Domain, Lft};
use num_complex::Complex64;
use proptest::prelude::*;

const TOL: f64 = 1e-12;
const CASES: u32 = 100_000;

fn atlas(genus: u32) -> &'static Atlas {
    static ATLASES: [OnceLock<Atlas>; 65] = [const { OnceLock::new() }; 65];
    ATLASES[genus as usize].get_or_init(|| Atlas::new(genus).expect("default atlas"))
}

use charts::check::chart_point_from_unit as chart_point;

fn check_point(genus: u32, p: ChartPoint) -> Result<(), TestCaseError> {
    let atlas = atlas(genus);
    let located = atlas
        .locate(p)
        .map_err(|e| TestCaseError::fail(e.to_string()))?;
    let reps = located.representations();
    prop_assert!(
        reps.windows(2).all(|w| w[0].chart < w[1].chart),
        "a chart appears twice: {reps:?}"
    );
    prop_assert_eq!(located.in_chart(p.chart), Some(p.coords));
    // Inverse and cocycle conditions, seen from every representation.
    let c = consistency_at(atlas, p);
    prop_assert!(
        c.missing == 0,
        "{} representations missing at {p:?}",
        c.missing
    );
    prop_assert!(
        c.inverse_error <= TOL,
        "inverse error {:e} at {p:?}",
        c.inverse_error
    );
    prop_assert!(
        c.cocycle_error <= TOL,
        "cocycle error {:e} at {p:?}",
        c.cocycle_error
    );
    // Completeness: the model-space path (reduce into the polygon, map through each chart's tiles)
    // finds the same charts, away from chart boundaries. That path works with disk points, which near
    // the unit circle carry ~1e-16/(1 − |z|) of error (1 − |z| reaches 1e-6 at genus 64), so it is
    // compared at that accuracy; the transitions themselves are held to 1e-12 above.
    let z = atlas
        .to_model(p)
        .map_err(|e| TestCaseError::fail(e.to_string()))?;
    let via_model = atlas.locate_model(z);
    let model_tol = 1e-8_f64.max(1e-12 / (1.0 - z.0.norm()).max(1e-300));
    let deep =
        |r: &&ChartPoint| atlas.charts()[r.chart.index()].domain().margin(r.coords) > model_tol;
    for r in reps.iter().filter(deep) {
        let w = via_model.in_chart(r.chart);
        prop_assert!(
            w.is_some_and(|w| (w - r.coords).norm() < model_tol),
            "model path disagrees in {} at {p:?}",
            r.chart
        );
    }
    for r in via_model.representations().iter().filter(deep) {
        prop_assert!(
            located.in_chart(r.chart).is_some(),
            "transitions missed {} at {p:?}",
            r.chart
        );
    }
    Ok(())
}

macro_rules! transition_properties {
    ($($name:ident: $genus:expr,)*) => {$(
        proptest! {
            #![proptest_config(ProptestConfig { cases: CASES, failure_persistence: None, ..ProptestConfig::default() })]
            #[test]
            fn $name(chart in 0usize..1000, u in 0.0f64..1.0, v in 0.0f64..1.0) {
                check_point($genus, chart_point(atlas($genus), chart, u, v))?;
            }
        }
    )*};
}

transition_properties! {
    genus_0: 0,
    genus_1: 1,
    genus_2: 2,
    genus_3: 3,
    genus_5: 5,
    genus_8: 8,
    genus_16: 16,
    genus_32: 32,
    genus_64: 64,
}

#[test]
fn self_transitions_are_exactly_the_identity() {
    for genus in [0, 1, 2, 3, 5, 8, 16, 32, 64] {
        let atlas = atlas(genus);
        for chart in atlas.charts() {
            let own = atlas.transitions(chart.id(), chart.id());
            assert_eq!(
                own.len(),
                1,
                "genus {genus}: {} overlaps itself",
                chart.kind().label()
            );
            assert_eq!(own[0].lft, Lft::IDENTITY);
        }
    }
}

#[test]
fn inverse_components_pair_up() {
    // Every component of U_ij has a component of U_ji whose transition is its inverse.
    for genus in [0, 1, 2, 3, 8, 32] {
        let atlas = atlas(genus);
        for a in atlas.charts() {
            for b in atlas.charts().iter().filter(|b| b.id() != a.id()) {
                let forth = atlas.transitions(a.id(), b.id());
                let back = atlas.transitions(b.id(), a.id());
                assert_eq!(forth.len(), back.len(), "genus {genus}");
                for t in forth {
                    let best = back
                        .iter()
                        .map(|s| s.lft.compose(&t.lft).distance(&Lft::IDENTITY))
                        .fold(f64::INFINITY, f64::min);
                    assert!(
                        best < TOL,
                        "genus {genus}: no inverse for a component of U_{}{}: {best:e}",
                        a.id().0,
                        b.id().0
                    );
                }
            }
        }
    }
}

#[test]
fn the_papers_overlap_structure_for_genus_two() {
    // Inside–edge: two components (left and right halves); vertex–inside: 4n; vertex–edge: two.
    let atlas = atlas(2);
    let (inside, vertex) = (ChartId(0), ChartId(1));
    for e in 2..6 {
        assert_eq!(atlas.transitions(inside, ChartId(e)).len(), 2);
        assert_eq!(atlas.transitions(vertex, ChartId(e)).len(), 2);
    }
    assert_eq!(atlas.transitions(vertex, inside).len(), 8);
    // Edge–edge overlaps have one to three components, each about a corner.
    for a in 2..6 {
        for b in (2..6).filter(|&b| b != a) {
            assert!(atlas.transitions(ChartId(a), ChartId(b)).len() <= 3);
        }
    }
}

#[test]
fn points_hugging_chart_boundaries_stay_consistent() {
    // Within 1e-13 of a chart's boundary a representation may be found from one side only; the
    // check skips representations inside the boundary band, and everything else must still agree.
    for genus in [0, 1, 2, 8, 64] {
        let atlas = atlas(genus);
        for chart in atlas.charts() {
            for k in 0..64 {
                let t = std::f64::consts::TAU * k as f64 / 64.0;
                let w = match chart.domain() {
                    Domain::Disk => Complex64::from_polar(0.5 - 1e-13, t),
                    Domain::Square => {
                        let d = Complex64::from_polar(1.0, t);
                        d * ((0.5 - 1e-13) / d.re.abs().max(d.im.abs()))
                    }
                };
                let p = ChartPoint::new(chart.id(), w);
                assert!(atlas.locate(p).is_ok());
                let c = consistency_at(atlas, p);
                assert!(c.worst() <= TOL, "genus {genus}, {p:?}: {c:?}");
            }
        }
    }
    const {
        assert!(
            BOUNDARY_BAND >= 1e3 * TOL,
            "the band must exceed the transition error by far"
        )
    };
}

#[test]
fn bad_points_are_errors_not_panics() {
    let atlas = atlas(2);
    let nan = ChartPoint::new(ChartId(0), Complex64::new(f64::NAN, 0.0));
    assert!(matches!(
        atlas.locate(nan),
        Err(charts::ChartsError::NotFinite { .. })
    ));
    let outside = ChartPoint::new(ChartId(2), Complex64::new(0.5, 0.0));
    assert!(matches!(
        atlas.locate(outside),
        Err(charts::ChartsError::OutsideChart { .. })
    ));
    let missing = ChartPoint::new(ChartId(99), Complex64::ZERO);
    assert!(matches!(
        atlas.locate(missing),
        Err(charts::ChartsError::NoSuchChart { .. })
    ));
    assert!(matches!(
        Atlas::new(65),
        Err(charts::ChartsError::UnsupportedGenus { .. })
    ));
}

#[test]
fn chart_scales_are_validated() {
    use charts::ChartScales;
    let bad = [
        (
            2,
            ChartScales::Polygon {
                inside: f64::NAN,
                edge: 0.9,
                vertex: 0.5,
            },
        ),
        (
            2,
            ChartScales::Polygon {
                inside: 0.5,
                edge: 2.0,
                vertex: 0.5,
            },
        ),
        (2, ChartScales::Sphere { cap: 2.0 }),
        (0, ChartScales::Sphere { cap: 0.9 }),
        (
            0,
            ChartScales::Polygon {
                inside: 0.5,
                edge: 0.9,
                vertex: 0.5,
            },
        ),
        // Too large a vertex disk meets its own copies about the other lifts of the vertex.
        (
            2,
            ChartScales::Polygon {
                inside: 0.5,
                edge: 0.9,
                vertex: 0.95,
            },
        ),
    ];
    for (genus, scales) in bad {
        assert!(
            matches!(
                Atlas::with_scales(genus, scales),
                Err(charts::ChartsError::InvalidScales(_))
            ),
            "{genus} {scales:?}"
        );
    }
}

/// Number of 8-connected pieces of the grid cells whose centres lie in the component.
fn pieces(atlas: &Atlas, t: &charts::Transition, m: usize) -> usize {
    let (from, to) = (
        atlas.charts()[t.from.index()].domain(),
        atlas.charts()[t.to.index()].domain(),
    );
    let at = |x: usize, y: usize| {
        Complex64::new(
            (x as f64 + 0.5) / m as f64 - 0.5,
            (y as f64 + 0.5) / m as f64 - 0.5,
        )
    };
    let mut inside: Vec<bool> = (0..m * m)
        .map(|k| {
            let w = at(k % m, k / m);
            from.contains(w) && to.contains(t.apply(w))
        })
        .collect();
    let mut count = 0;
    for start in 0..m * m {
        if !inside[start] {
            continue;
        }
        count += 1;
        let mut stack = vec![start];
        inside[start] = false;
        while let Some(k) = stack.pop() {
            let (x, y) = ((k % m) as isize, (k / m) as isize);
            for (dx, dy) in [
                (-1, -1),
                (-1, 0),
                (-1, 1),
                (0, -1),
                (0, 1),
                (1, -1),
                (1, 0),
                (1, 1),
            ] {
                let (nx, ny) = (x + dx, y + dy);
                if nx >= 0 && ny >= 0 && (nx as usize) < m && (ny as usize) < m {
                    let nk = ny as usize * m + nx as usize;
                    if inside[nk] {
                        inside[nk] = false;
                        stack.push(nk);
                    }
                }
            }
        }
    }
    count
}

#[test]
fn each_overlap_component_is_connected_and_non_empty() {
    for genus in [0, 1, 2, 3, 5] {
        let atlas = atlas(genus);
        for a in atlas.charts() {
            for b in atlas.charts().iter().filter(|b| b.id() != a.id()) {
                for t in atlas.transitions(a.id(), b.id()) {
                    let k = pieces(atlas, t, 400);
                    // A sliver thinner than the grid may show no cell; it must never show two pieces.
                    assert!(
                        k <= 1,
                        "genus {genus}: U_{}{} component splits into {k} pieces",
                        a.id().0,
                        b.id().0
                    );
                    if k == 0 {
                        assert!(
                            pieces(atlas, t, 2000) == 1,
                            "genus {genus}: empty or split component in U_{}{}",
                            a.id().0,
                            b.id().0
                        );
                    }
                }
            }
        }
    }
}
