//! Closed all-quad cages for the side-by-side benches: the boundary of a slab of unit voxels,
//! 2n + 1 long and 3 wide, with a one-voxel hole through every other voxel of its middle row, so a
//! surface of genus n made only of quads (valence-3, -5 and -6 vertices where the slab turns).

use std::collections::HashMap;

/// A closed quad mesh: positions, and faces as four vertex indices counter-clockwise seen from
/// outside.
#[derive(Clone, Debug)]
pub struct QuadMesh {
    pub positions: Vec<[f32; 3]>,
    pub faces: Vec<[u32; 4]>,
}

impl QuadMesh {
    /// The slab of genus `genus` (see the module's comment).
    pub fn genus_cage(genus: u32) -> QuadMesh {
        let (len, wide) = (2 * genus as i32 + 1, 3);
        let solid = |x: i32, y: i32, z: i32| {
            (0..len).contains(&x) && (0..wide).contains(&y) && z == 0 && !(y == 1 && x % 2 == 1)
        };
        let mut mesh = QuadMesh {
            positions: Vec::new(),
            faces: Vec::new(),
        };
        let mut index: HashMap<[i32; 3], u32> = HashMap::new();
        for x in 0..len {
            for y in 0..wide {
                if !solid(x, y, 0) {
                    continue;
                }
                for axis in 0..3 {
                    for side in [0, 1] {
                        let mut next = [x, y, 0];
                        next[axis] += 2 * side - 1;
                        if !solid(next[0], next[1], next[2]) {
                            let face = voxel_face([x, y, 0], axis, side == 1)
                                .map(|p| mesh.vertex(&mut index, p));
                            mesh.faces.push(face);
                        }
                    }
                }
            }
        }
        mesh
    }

    fn vertex(&mut self, index: &mut HashMap<[i32; 3], u32>, p: [i32; 3]) -> u32 {
        *index.entry(p).or_insert_with(|| {
            self.positions.push(p.map(|c| c as f32));
            self.positions.len() as u32 - 1
        })
    }

    /// Edges (each shared by two faces of a closed mesh).
    pub fn edge_count(&self) -> usize {
        2 * self.faces.len()
    }

    /// Vertices after `level` steps of Catmull–Clark refinement: each step adds a vertex per edge
    /// and per face, and leaves 4 faces per face and 2 edges per edge plus 4 per face.
    pub fn refined_vertex_count(&self, level: u32) -> usize {
        let (mut v, mut e, mut f) = (self.positions.len(), self.edge_count(), self.faces.len());
        for _ in 0..level {
            (v, e, f) = (v + e + f, 2 * e + 4 * f, 4 * f);
        }
        v
    }

    /// `k × k` limit locations per face, at the centres of a k × k grid in (s, t), face by face.
    pub fn limit_locations(&self, k: u32) -> Vec<(u32, f32, f32)> {
        let at = |i: u32| (i as f32 + 0.5) / k as f32;
        (0..self.faces.len() as u32)
            .flat_map(|f| (0..k * k).map(move |i| (f, at(i % k), at(i / k))))
            .collect()
    }
}

/// The corners of a unit voxel's face across `axis` (at the high side if `high`), ordered
/// counter-clockwise seen from outside the voxel.
fn voxel_face(voxel: [i32; 3], axis: usize, high: bool) -> [[i32; 3]; 4] {
    let (b, c) = ((axis + 1) % 3, (axis + 2) % 3);
    let corner = |db: i32, dc: i32| {
        let mut p = voxel;
        p[axis] += i32::from(high);
        p[b] += db;
        p[c] += dc;
        p
    };
    // e_b × e_c = e_axis, so this order faces +axis; the low side is the same loop reversed.
    let ring = [corner(0, 0), corner(1, 0), corner(1, 1), corner(0, 1)];
    if high {
        ring
    } else {
        [ring[0], ring[3], ring[2], ring[1]]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::HashMap;

    /// χ = V − E + F = 2 − 2g, and every directed edge appears once (closed, oriented, manifold).
    #[test]
    fn cages_are_closed_oriented_surfaces_of_their_genus() {
        for genus in 0..=6u32 {
            let cage = QuadMesh::genus_cage(genus);
            let mut directed: HashMap<(u32, u32), usize> = HashMap::new();
            for f in &cage.faces {
                for k in 0..4 {
                    *directed.entry((f[k], f[(k + 1) % 4])).or_default() += 1;
                }
            }
            assert!(
                directed.values().all(|&n| n == 1),
                "genus {genus}: repeated edge"
            );
            assert!(
                directed
                    .keys()
                    .all(|&(a, b)| directed.contains_key(&(b, a))),
                "genus {genus}: an edge without its twin"
            );
            let (v, e, f) = (
                cage.positions.len() as i64,
                directed.len() as i64 / 2,
                cage.faces.len() as i64,
            );
            assert_eq!(e as usize, cage.edge_count());
            assert_eq!(v - e + f, 2 - 2 * i64::from(genus), "genus {genus}");
        }
    }
}
