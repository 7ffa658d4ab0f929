//! Evening a triangle mesh out along its own surface: the vertices slide over the mesh's triangles
//! towards their neighbours' centroid, so long thin triangles become rounder while the surface (the
//! piecewise-linear one the triangles make) stays where it is and the connectivity is unchanged.
//!
//! Why: a map built from a mesh's own angles (mean value weights) follows the mesh's triangles. On a
//! mesh with a directional bias (marching cubes or tetrahedra, a scanner's grid, CAD tessellations
//! with needles) that map is not smooth where the bias turns, and a spline fitted through the
//! vertices at those parameters wrinkles. Evened vertices sample the same surface without the bias.
//!
//! Only the vertices near long thin triangles move: those with a triangle of an angle under
//! [`THIN_ANGLE_DEGREES`] in their fan, and their neighbours (so the region relaxes as a whole). A
//! mesh without such triangles is left as it is.
//!
//! Every vertex keeps a host triangle of the original mesh; a move is projected onto the nearest
//! point of the triangles round the host (the host's corners' fans), so a vertex never jumps to
//! another sheet of a thin part. Vertices on sharp features (an edge whose normals turn more than
//! [`SHARP_DIHEDRAL_DEGREES`]) stay put, so creases and corners keep their samples. A move that
//! would turn a triangle over (its normal against the original's) is taken back.

use crate::spatial::{barycentric, closest_point_on_triangle};

type Point = [f64; 3];

/// Edges whose two triangles' normals differ by more than this many degrees are features: their
/// vertices are not moved.
pub const SHARP_DIHEDRAL_DEGREES: f64 = 40.0;

/// Triangles with an angle under this many degrees are thin: the vertices round them are evened.
pub const THIN_ANGLE_DEGREES: f64 = 20.0;

/// What [`even_out`] did.
#[derive(Clone, Debug, PartialEq)]
pub struct Evened {
    /// The new positions, one per vertex, each on a triangle of the original mesh.
    pub positions: Vec<[f64; 3]>,
    /// Each new position's triangle of the original mesh, and its barycentric coordinates there
    /// (with respect to the triangle's corners in order): what the original mesh's attributes,
    /// such as its vertex normals, are interpolated with.
    pub hosts: Vec<(u32, [f64; 3])>,
    /// Vertices that were free to move (near thin triangles, off sharp features).
    pub free: usize,
    /// Vertices near thin triangles held in place on sharp features.
    pub pinned: usize,
    /// The largest distance a vertex moved.
    pub largest_move: f64,
}

/// Evens `positions` (a closed or open triangle mesh `triangles`) out over `rounds` rounds: each
/// round moves every free vertex halfway to its neighbours' centroid and back onto the mesh.
pub fn even_out(positions: &[[f64; 3]], triangles: &[[u32; 3]], rounds: usize) -> Evened {
    let n = positions.len();
    let fans = Fans::new(n, triangles);
    let normals: Vec<Point> = triangles
        .iter()
        .map(|t| unit_normal(t.map(|v| positions[v as usize])))
        .collect();
    let sharp = sharp_vertices(n, triangles, &normals);
    let neighbours = neighbours(n, triangles);
    let near_thin = near_thin_triangles(positions, triangles, &neighbours);
    let free: Vec<bool> = (0..n).map(|v| near_thin[v] && !sharp[v]).collect();
    let mut host: Vec<u32> = (0..n)
        .map(|v| fans.of(v).first().copied().unwrap_or(0))
        .collect();
    let mut current = positions.to_vec();
    let mut candidates = Vec::new();
    for _ in 0..rounds {
        let previous = current.clone();
        let previous_host = host.clone();
        for v in 0..n {
            let ring = &neighbours[v];
            if !free[v] || ring.is_empty() || fans.of(v).is_empty() {
                continue;
            }
            let centroid = scale(
                &ring
                    .iter()
                    .fold([0.0; 3], |s, &u| add(&s, &previous[u as usize])),
                1.0 / ring.len() as f64,
            );
            let target = scale(&add(&previous[v], &centroid), 0.5);
            let (t, p) = project(
                &target,
                host[v],
                triangles,
                positions,
                &fans,
                &mut candidates,
            );
            host[v] = t;
            current[v] = p;
        }
        undo_turned(
            &mut current,
            &mut host,
            &previous,
            &previous_host,
            triangles,
            &normals,
        );
    }
    let largest_move = current
        .iter()
        .zip(positions)
        .map(|(a, b)| norm(&sub(a, b)))
        .fold(0.0, f64::max);
    let hosts = host
        .iter()
        .zip(&current)
        .map(|(&t, p)| {
            (
                t,
                barycentric(*p, triangles[t as usize].map(|v| positions[v as usize])),
            )
        })
        .collect();
    Evened {
        positions: current,
        hosts,
        free: free.iter().filter(|&&f| f).count(),
        pinned: (0..n).filter(|&v| near_thin[v] && sharp[v]).count(),
        largest_move,
    }
}

/// Triangles round each vertex (compressed rows).
struct Fans {
    offsets: Vec<usize>,
    triangles: Vec<u32>,
}

impl Fans {
    fn new(n: usize, triangles: &[[u32; 3]]) -> Fans {
        let mut offsets = vec![0usize; n + 1];
        for t in triangles {
            for &v in t {
                offsets[v as usize + 1] += 1;
            }
        }
        for i in 0..n {
            offsets[i + 1] += offsets[i];
        }
        let mut fill = offsets.clone();
        let mut list = vec![0u32; offsets[n]];
        for (i, t) in triangles.iter().enumerate() {
            for &v in t {
                list[fill[v as usize]] = i as u32;
                fill[v as usize] += 1;
            }
        }
        Fans {
            offsets,
            triangles: list,
        }
    }

    fn of(&self, v: usize) -> &[u32] {
        &self.triangles[self.offsets[v]..self.offsets[v + 1]]
    }
}

/// The nearest point to `p` on the triangles of the host's corners' fans, and its triangle.
fn project(
    p: &Point,
    host: u32,
    triangles: &[[u32; 3]],
    positions: &[[f64; 3]],
    fans: &Fans,
    candidates: &mut Vec<u32>,
) -> (u32, Point) {
    candidates.clear();
    for &corner in &triangles[host as usize] {
        candidates.extend_from_slice(fans.of(corner as usize));
    }
    let mut best = (
        host,
        positions[triangles[host as usize][0] as usize],
        f64::INFINITY,
    );
    for &t in candidates.iter() {
        let q = closest_point_on_triangle(*p, triangles[t as usize].map(|v| positions[v as usize]));
        let d = norm2(&sub(p, &q));
        if d < best.2 {
            best = (t, q, d);
        }
    }
    (best.0, best.1)
}

/// Vertices on an edge whose triangles' normals turn more than [`SHARP_DIHEDRAL_DEGREES`].
fn sharp_vertices(n: usize, triangles: &[[u32; 3]], normals: &[Point]) -> Vec<bool> {
    let mut pinned = vec![false; n];
    for (a, b) in sharp_edges_with(triangles, normals) {
        pinned[a as usize] = true;
        pinned[b as usize] = true;
    }
    pinned
}

/// A mesh's sharp edges: those across which its triangles' normals turn more than
/// [`SHARP_DIHEDRAL_DEGREES`] (a crease or a corner's edge, which a smooth surface rounds), each
/// as its two vertices, the smaller first, in the order the triangles first reach them. Edges
/// of a triangle without area (no normal) count as sharp.
pub fn sharp_edges(positions: &[Point], triangles: &[[u32; 3]]) -> Vec<(u32, u32)> {
    let normals: Vec<Point> = triangles
        .iter()
        .map(|t| unit_normal(t.map(|v| positions[v as usize])))
        .collect();
    sharp_edges_with(triangles, &normals)
}

/// [`sharp_edges`] given the triangles' unit normals.
fn sharp_edges_with(triangles: &[[u32; 3]], normals: &[Point]) -> Vec<(u32, u32)> {
    let cos_sharp = SHARP_DIHEDRAL_DEGREES.to_radians().cos();
    let mut edges: std::collections::HashMap<(u32, u32), usize> =
        std::collections::HashMap::with_capacity(triangles.len() * 3 / 2);
    let mut sharp = Vec::new();
    for (i, t) in triangles.iter().enumerate() {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            let key = (a.min(b), a.max(b));
            if let Some(j) = edges.insert(key, i)
                && dot(&normals[i], &normals[j]) < cos_sharp
            {
                sharp.push(key);
            }
        }
    }
    sharp
}

/// Vertices of a triangle with an angle under [`THIN_ANGLE_DEGREES`], and their neighbours.
fn near_thin_triangles(
    positions: &[Point],
    triangles: &[[u32; 3]],
    neighbours: &[Vec<u32>],
) -> Vec<bool> {
    let cos_thin = THIN_ANGLE_DEGREES.to_radians().cos();
    let mut thin = vec![false; positions.len()];
    for t in triangles {
        let p = t.map(|v| positions[v as usize]);
        let is_thin = (0..3).any(|k| {
            let (a, b) = (sub(&p[(k + 1) % 3], &p[k]), sub(&p[(k + 2) % 3], &p[k]));
            let (la, lb) = (norm(&a), norm(&b));
            la == 0.0 || lb == 0.0 || dot(&a, &b) > cos_thin * la * lb
        });
        if is_thin {
            for &v in t {
                thin[v as usize] = true;
            }
        }
    }
    (0..positions.len())
        .map(|v| thin[v] || neighbours[v].iter().any(|&u| thin[u as usize]))
        .collect()
}

/// Each vertex's neighbours (once each).
fn neighbours(n: usize, triangles: &[[u32; 3]]) -> Vec<Vec<u32>> {
    let mut lists = vec![Vec::new(); n];
    for t in triangles {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            lists[a as usize].push(b);
            lists[b as usize].push(a);
        }
    }
    for list in &mut lists {
        list.sort_unstable();
        list.dedup();
    }
    lists
}

/// Puts back, vertex by vertex, the moves that turned a triangle against its original normal (or
/// flattened it to nothing), until none is turned.
fn undo_turned(
    current: &mut [Point],
    host: &mut [u32],
    previous: &[Point],
    previous_host: &[u32],
    triangles: &[[u32; 3]],
    normals: &[Point],
) {
    loop {
        let mut undone = false;
        for (t, normal) in triangles.iter().zip(normals) {
            let corners = t.map(|v| current[v as usize]);
            let turned = dot(&cross_of(corners), normal) <= 0.0;
            if !turned {
                continue;
            }
            for &v in t {
                let v = v as usize;
                if current[v] != previous[v] {
                    current[v] = previous[v];
                    host[v] = previous_host[v];
                    undone = true;
                }
            }
        }
        if !undone {
            return;
        }
    }
}

fn cross_of([a, b, c]: [Point; 3]) -> Point {
    cross(&sub(&b, &a), &sub(&c, &a))
}

fn unit_normal(corners: [Point; 3]) -> Point {
    let c = cross_of(corners);
    let l = norm(&c);
    if l > 0.0 { scale(&c, 1.0 / l) } else { c }
}

fn add(a: &Point, b: &Point) -> Point {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

fn sub(a: &Point, b: &Point) -> Point {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn scale(a: &Point, s: f64) -> Point {
    [a[0] * s, a[1] * s, a[2] * s]
}

fn dot(a: &Point, b: &Point) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn cross(a: &Point, b: &Point) -> Point {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn norm2(a: &Point) -> f64 {
    dot(a, a)
}

fn norm(a: &Point) -> f64 {
    norm2(a).sqrt()
}
