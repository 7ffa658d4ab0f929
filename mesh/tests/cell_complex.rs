//! The example complex of the "Discrete Manifolds" interface document, loaded from its tables as
//! printed: the validator must report every inconsistency in them, and the corrected complex must be a
//! sphere. The cell-complex view of tessellations must be consistent too.

use mesh::HalfEdgeMesh;
use mesh::cell_complex::{Cell, CellComplex, Inconsistency};

/// Reads `tests/fixtures/ibm-example-complex.txt` (format described in the file).
fn load_fixture() -> CellComplex {
    let text = include_str!("fixtures/ibm-example-complex.txt");
    let mut cx = CellComplex::default();
    let mut dim = 0;
    let list = |s: &str| -> Vec<u32> {
        let s = s.trim();
        if s == "-" {
            Vec::new()
        } else {
            s.split(',').map(|v| v.trim().parse().unwrap()).collect()
        }
    };
    for line in text
        .lines()
        .map(str::trim)
        .filter(|l| !l.is_empty() && !l.starts_with('#'))
    {
        if let Some(d) = line.strip_prefix("cells ") {
            dim = d.trim().parse().unwrap();
            continue;
        }
        let parts: Vec<&str> = line.split('|').collect();
        assert_eq!(parts.len(), 3, "bad fixture line {line}");
        let index: usize = parts[0].trim().parse().unwrap();
        assert_eq!(
            index,
            cx.cells[dim].len(),
            "fixture cells must be listed in order"
        );
        cx.cells[dim].push(Cell {
            cofaces: list(parts[1]),
            faces: list(parts[2]),
        });
    }
    cx
}

#[test]
fn the_printed_tables_are_read_as_printed() {
    let cx = load_fixture();
    assert_eq!((cx.count(0), cx.count(1), cx.count(2)), (8, 18, 11));
    // The document's own examples.
    assert_eq!(cx.cells[2][0].faces, [6, 16, 17]);
    assert_eq!(cx.cells[1][16].faces, [6, 7]);
    assert_eq!(cx.cells[1][8].cofaces, [6, 7]);
    assert_eq!(cx.cells[0][5].cofaces, [5, 6, 8, 10, 17]);
}

#[test]
fn every_inconsistency_in_the_printed_tables_is_reported() {
    let cx = load_fixture();
    let found = cx.validate();
    for f in &found {
        println!("{f}");
    }
    use Inconsistency::*;
    assert_eq!(
        found,
        [
            // 0-cell 7 claims 1-cell 14, whose ends are 0 and 8.
            CofaceNotReciprocated {
                dim: 0,
                cell: 7,
                coface: 14
            },
            // 1-cell 1 joins 0-cells 1 and 2 (2-cell 2 = {1, 2, 9} needs it), but 0-cell 1 omits it.
            FaceNotReciprocated {
                dim: 1,
                cell: 1,
                face: 1
            },
            // The 0-cell table stops at 7; 1-cells 5, 13, 14 and 15 end at a ninth vertex, 8.
            UnknownFace {
                dim: 1,
                cell: 5,
                face: 8
            },
            UnknownFace {
                dim: 1,
                cell: 13,
                face: 8
            },
            UnknownFace {
                dim: 1,
                cell: 14,
                face: 8
            },
            UnknownFace {
                dim: 1,
                cell: 15,
                face: 8
            },
        ]
    );
    // As printed (and as the text says: eight vertices), V − E + F = 1: not a sphere.
    assert_eq!(cx.euler_characteristic(), 1);
}

#[test]
fn the_corrected_complex_is_a_sphere() {
    let mut cx = load_fixture();
    cx.cells[0][1].cofaces = vec![0, 1, 2, 3];
    cx.cells[0][7].cofaces = vec![3, 4, 6, 15, 16];
    cx.cells[0].push(Cell {
        faces: vec![],
        cofaces: vec![5, 13, 14, 15],
    });
    assert_eq!(cx.validate(), []);
    assert_eq!(cx.euler_characteristic(), 2);
    let polygons = cx.polygons().expect("closed 2-cells");
    let mesh = HalfEdgeMesh::from_polygons(cx.count(0), polygons.iter().map(|p| &p[..])).unwrap();
    let t = mesh.topology();
    assert!(t.closed && t.manifold && t.orientable, "{t:?}");
    assert_eq!(
        (t.components, t.euler_characteristic, t.genus),
        (1, 2, Some(0))
    );
    // Oriented 1-cells: the mirror twin of k is k + 18, reversed, with its sides swapped.
    for k in 0..18u32 {
        let (a, b) = cx.oriented_edge(k);
        assert_eq!(cx.oriented_edge(k + 18), (b, a));
        let (l, r) = cx.oriented_sides(k);
        assert_eq!(cx.oriented_sides(k + 18), (r, l));
    }
    // Each 2-cell's oriented boundary chains head to tail.
    for f in 0..11 {
        let b = cx.oriented_boundary(f).unwrap();
        for (i, &k) in b.iter().enumerate() {
            assert_eq!(
                cx.oriented_edge(k).1,
                cx.oriented_edge(b[(i + 1) % b.len()]).0
            );
        }
    }
}

#[test]
fn broken_tables_are_reported_not_panicked_on() {
    let mut cx = load_fixture();
    cx.cells[1][3].faces = vec![1]; // an edge with one end
    cx.cells[1][4].cofaces.push(99); // a face that does not exist
    cx.cells[2][4].faces.push(4); // listed twice
    let found = cx.validate();
    assert!(found.contains(&Inconsistency::EdgeEnds { cell: 3, count: 1 }));
    assert!(found.contains(&Inconsistency::UnknownCoface {
        dim: 1,
        cell: 4,
        coface: 99
    }));
    assert!(found.contains(&Inconsistency::Repeated {
        dim: 2,
        cell: 4,
        entry: 4
    }));
    assert!(found.contains(&Inconsistency::OpenBoundary { cell: 1 }));
}

#[test]
fn tessellations_have_a_consistent_cell_complex_view() {
    for (genus, te, tr) in [(0, 3, 2), (1, 2, 2), (2, 4, 3), (5, 2, 1)] {
        let t = charts::Atlas::new(genus)
            .unwrap()
            .tessellate(te, tr)
            .unwrap();
        let mesh =
            HalfEdgeMesh::from_polygons(t.vertices.len(), t.triangles.iter().map(|f| &f[..]))
                .unwrap();
        let cx = CellComplex::from_mesh(&mesh);
        assert_eq!(cx.validate(), [], "genus {genus}");
        assert_eq!(cx.euler_characteristic(), 2 - 2 * i64::from(genus));
        assert_eq!(cx.count(2), t.triangles.len());
    }
}
