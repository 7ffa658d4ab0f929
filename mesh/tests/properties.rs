//! Property tests of the half-edge mesh: no input makes it panic, and topology does not depend on how
//! vertices are numbered or where each face's cycle starts.

use mesh::HalfEdgeMesh;
use proptest::prelude::*;

proptest! {
    #![proptest_config(ProptestConfig { cases: 2000, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    fn any_polygon_soup_is_reported_not_panicked_on(
        vertices in 1usize..24,
        faces in proptest::collection::vec(proptest::collection::vec(0u32..26, 1..6), 0..40),
    ) {
        match HalfEdgeMesh::from_polygons(vertices, faces.iter().map(|f| &f[..])) {
            Err(_) => {}
            Ok(mesh) => {
                let t = mesh.topology();
                prop_assert_eq!(t.euler_characteristic, t.vertices as i64 - t.edges as i64 + t.faces as i64);
                prop_assert!(t.boundary_edges <= t.edges);
                prop_assert!(t.isolated_vertices <= t.vertices);
                prop_assert!(!t.closed || t.boundary_loops == 0);
                if let Some(g) = t.genus {
                    prop_assert!(t.manifold && t.orientable && t.components == 1);
                    prop_assert_eq!(2 - 2 * i64::from(g) - t.boundary_loops as i64, t.euler_characteristic);
                }
            }
        }
    }

    #[test]
    fn renumbering_keeps_the_topology(genus in 0u32..4, te in 2u32..5, tr in 1u32..4, seed in any::<u64>(), shift in 0usize..3) {
        let t = charts::Atlas::new(genus).unwrap().tessellate(te, tr).unwrap();
        let n = t.vertices.len();
        // A pseudo-random permutation of the vertices, and every face's cycle rotated.
        let mut perm: Vec<u32> = (0..n as u32).collect();
        let mut x = seed | 1;
        for i in (1..n).rev() {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            perm.swap(i, (x % (i as u64 + 1)) as usize);
        }
        let faces: Vec<Vec<u32>> = t
            .triangles
            .iter()
            .map(|f| (0..3).map(|k| perm[f[(k + shift) % 3] as usize]).collect())
            .collect();
        let a = HalfEdgeMesh::from_polygons(n, t.triangles.iter().map(|f| &f[..])).unwrap().topology();
        let b = HalfEdgeMesh::from_polygons(n, faces.iter().map(|f| &f[..])).unwrap().topology();
        prop_assert_eq!(a.clone(), b);
        prop_assert_eq!(a.genus, Some(genus));
    }
}
