//! The checks a mesh must pass before a fit, in the order the module `import` documents.

use embedding::{Point3, bounding_box};
use mesh::HalfEdgeMesh;

use super::error::MORE_HOLES_NAMED;
use super::{DEGENERATE_AREA, ImportError, ImportedMesh, Location, MAX_GENUS, Place, ValidMesh};

/// Checks an imported mesh for what a fit needs (see the module's documentation for the order of
/// the checks) and returns it oriented outward with every vertex used. With `keep_largest`, a mesh
/// of several components keeps its largest (by triangles; the first of equals) instead of failing.
pub fn validate(mesh: ImportedMesh, keep_largest: bool) -> Result<ValidMesh, ImportError> {
    let ImportedMesh {
        positions,
        triangles,
        ..
    } = mesh;
    let n = positions.len();
    let place = |v: u32| Place(positions[v as usize]);
    if let Some((f, t)) = triangles
        .iter()
        .enumerate()
        .find(|(_, t)| t.iter().any(|&v| v as usize >= n))
    {
        let bad = t.iter().find(|&&v| v as usize >= n).copied().unwrap_or(0);
        return Err(ImportError::IndexOutOfRange {
            face: f,
            at: Location::Unknown,
            index: i64::from(bad),
            vertex_count: n,
        });
    }
    if triangles.is_empty() {
        return Err(ImportError::NoTriangles);
    }
    // Components, by shared vertices.
    let (component, count) = mesh::validate::face_components(n, triangles.iter().map(|t| &t[..]));
    let mut sizes = vec![0usize; count];
    for &c in &component {
        sizes[c as usize] += 1;
    }
    let (mut kept, mut dropped_components, mut dropped_triangles) = (triangles, 0, 0);
    // Each kept triangle's index in the input, for messages.
    let mut original: Vec<usize> = (0..kept.len()).collect();
    if count > 1 {
        if !keep_largest {
            let mut sorted = sizes.clone();
            sorted.sort_unstable_by(|a, b| b.cmp(a));
            return Err(ImportError::Components { sizes: sorted });
        }
        let largest = (0..count)
            .max_by_key(|&c| (sizes[c], std::cmp::Reverse(c)))
            .unwrap_or(0) as u32;
        let keep: Vec<bool> = component.iter().map(|&c| c == largest).collect();
        original.retain(|&f| keep[f]);
        let mut k = 0;
        kept.retain(|_| {
            k += 1;
            keep[k - 1]
        });
        dropped_components = count - 1;
        dropped_triangles = keep.len() - kept.len();
    }
    // Degenerate triangles, relative to the kept part's size.
    let used: Vec<Point3> = kept
        .iter()
        .flatten()
        .map(|&v| positions[v as usize])
        .collect();
    let (lo, hi) = bounding_box(&used);
    let diagonal2 = (hi - lo).norm_squared();
    let degenerate = |t: &[u32; 3]| {
        let [a, b, c] = t.map(|v| positions[v as usize]);
        t[0] == t[1]
            || t[1] == t[2]
            || t[0] == t[2]
            || (b - a).cross(&(c - a)).norm() <= DEGENERATE_AREA * diagonal2
    };
    let bad: Vec<usize> = (0..kept.len()).filter(|&i| degenerate(&kept[i])).collect();
    if let Some(&first) = bad.first() {
        let t = kept[first];
        return Err(ImportError::Degenerate {
            count: bad.len(),
            total: kept.len(),
            triangle: original[first],
            vertices: t,
            positions: t.map(place),
        });
    }
    // Compact: only used vertices, in their original order.
    let mut new_index = vec![u32::MAX; n];
    for t in &kept {
        for &v in t {
            new_index[v as usize] = 0;
        }
    }
    let mut old_index = Vec::new();
    for (v, slot) in new_index.iter_mut().enumerate() {
        if *slot == 0 {
            *slot = old_index.len() as u32;
            old_index.push(v as u32);
        }
    }
    let removed_vertices = n - old_index.len();
    let mut tris: Vec<[u32; 3]> = kept
        .iter()
        .map(|t| t.map(|v| new_index[v as usize]))
        .collect();
    let compact: Vec<Point3> = old_index.iter().map(|&v| positions[v as usize]).collect();
    let old = |v: u32| old_index[v as usize];
    let he = HalfEdgeMesh::from_polygons(compact.len(), tris.iter().map(|t| &t[..]))?;
    let edges = mesh::validate::nonmanifold_edges(&he);
    if let Some(&(a, b, faces)) = edges.first() {
        let (a, b) = (old(a), old(b));
        return Err(ImportError::NonManifoldEdges {
            count: edges.len(),
            vertices: [a, b],
            positions: [place(a), place(b)],
            faces,
        });
    }
    let vertices = mesh::validate::nonmanifold_vertices(&he);
    if let Some(&v) = vertices.first() {
        let v = old(v);
        return Err(ImportError::NonManifoldVertices {
            count: vertices.len(),
            vertex: v,
            position: place(v),
        });
    }
    let loops = mesh::validate::boundary_loops(&he);
    if let Some(first) = loops.first() {
        let v = old(first.first().copied().unwrap_or(0));
        return Err(ImportError::NotClosed {
            loops: loops.len(),
            vertex: v,
            position: place(v),
            length: first.len(),
            others: loops[1..]
                .iter()
                .take(MORE_HOLES_NAMED)
                .map(|l| {
                    let v = old(l.first().copied().unwrap_or(0));
                    (v, place(v), l.len())
                })
                .collect(),
        });
    }
    let flips = mesh::validate::orient(&he).map_err(|(a, b)| {
        let (a, b) = (old(a), old(b));
        ImportError::NonOrientable {
            vertices: [a, b],
            positions: [place(a), place(b)],
        }
    })?;
    // Flip the minority, so a mesh mostly right keeps its own orientation before the volume test.
    let majority_flipped = flips.iter().filter(|&&f| f).count() * 2 > flips.len();
    let mut reoriented = 0;
    for (t, &f) in tris.iter_mut().zip(&flips) {
        if f != majority_flipped {
            t.swap(1, 2);
            reoriented += 1;
        }
    }
    // χ = V − E + F on a closed triangle mesh: E = 3F/2.
    let chi = compact.len() as i64 - (3 * tris.len() / 2) as i64 + tris.len() as i64;
    let genus = (2 - chi).max(0) as u64 / 2;
    if genus > u64::from(MAX_GENUS) {
        return Err(ImportError::Genus { genus });
    }
    let volume: f64 = tris
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|v| compact[v as usize].coords);
            a.dot(&b.cross(&c))
        })
        .sum();
    let flipped = volume < 0.0;
    if flipped {
        for t in &mut tris {
            t.swap(1, 2);
        }
    }
    Ok(ValidMesh {
        positions: compact,
        triangles: tris,
        genus: genus as u32,
        dropped_components,
        dropped_triangles,
        removed_vertices,
        reoriented_triangles: reoriented,
        flipped,
    })
}
