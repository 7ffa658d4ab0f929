//! Closed meshes that are not ntori's plates, for the fit of a user's mesh (issue 14's acceptance
//! set): a knotted tube, a pretzel and a cube with tunnels. The tube is a parametric quad grid; the
//! others are level sets of implicit functions, triangulated by marching tetrahedra, which leaves
//! irregular triangles, long thin ones among them, as scanned and voxel-made meshes have.
//!
//! Shared by `embedding/tests/mesh_fit.rs` and `embedding/examples/acceptance.rs`.
#![allow(dead_code)]

use std::collections::HashMap;

use embedding::{Point3, Vector3};

/// A triangle mesh, counter-clockwise seen from outside.
pub type Mesh = (Vec<Point3>, Vec<[u32; 3]>);

/// A tube of `radius` round the trefoil knot (sin t + 2 sin 2t, cos t − 2 cos 2t, −sin 3t), `along`
/// rings of `around` vertices: a knotted torus (genus 1) whose flat map is long and thin.
pub fn trefoil_tube(along: usize, around: usize, radius: f64) -> Mesh {
    let curve = |t: f64| {
        Vector3::new(
            t.sin() + 2.0 * (2.0 * t).sin(),
            t.cos() - 2.0 * (2.0 * t).cos(),
            -(3.0 * t).sin(),
        )
    };
    // The Frenet frame: this trefoil's curvature never vanishes, and the frame closes up.
    let frame = |t: f64| {
        let h = 1e-4;
        let (a, b, c) = (curve(t - h), curve(t), curve(t + h));
        let tangent = (c - a).normalize();
        let normal = (c - 2.0 * b + a).normalize();
        let normal = (normal - tangent * tangent.dot(&normal)).normalize();
        (b, normal, tangent.cross(&normal))
    };
    let mut positions = Vec::with_capacity(along * around);
    for i in 0..along {
        let t = std::f64::consts::TAU * i as f64 / along as f64;
        let (centre, n, b) = frame(t);
        for j in 0..around {
            let s = std::f64::consts::TAU * j as f64 / around as f64;
            positions.push(Point3::from(centre + (n * s.cos() + b * s.sin()) * radius));
        }
    }
    let at = |i: usize, j: usize| ((i % along) * around + j % around) as u32;
    let mut triangles = Vec::with_capacity(2 * along * around);
    for i in 0..along {
        for j in 0..around {
            let (a, b, c, d) = (at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
            triangles.push([a, b, c]);
            triangles.push([a, c, d]);
        }
    }
    orient_outward(&positions, &mut triangles);
    (positions, triangles)
}

/// Three tori of radii 1 and 0.35 in a row along x, 1.8 apart, smoothly joined: a pretzel (genus 3).
pub fn pretzel(cell: f64) -> Mesh {
    level_set(
        &pretzel_field,
        Point3::new(-3.5, -1.5, -0.6),
        Point3::new(3.5, 1.5, 0.6),
        cell,
    )
}

/// [`pretzel`] with its vertices evened out along the surface (`rounds` of [`even_out`]).
pub fn even_pretzel(cell: f64, rounds: usize) -> Mesh {
    let (mut positions, triangles) = pretzel(cell);
    even_out(&pretzel_field, &mut positions, &triangles, rounds);
    (positions, triangles)
}

/// [`cube_with_tunnels`] evened out.
pub fn even_cube_with_tunnels(cell: f64, rounds: usize) -> Mesh {
    let (mut positions, triangles) = cube_with_tunnels(cell);
    even_out(&cube_field, &mut positions, &triangles, rounds);
    (positions, triangles)
}

/// Moves each vertex halfway to its neighbours' centroid and back onto the surface f = 0 (Newton
/// steps along f's gradient), `rounds` times: the marching tetrahedra's thin triangles become
/// rounder while the surface stays the same.
pub fn even_out(
    f: &dyn Fn(Point3) -> f64,
    positions: &mut [Point3],
    triangles: &[[u32; 3]],
    rounds: usize,
) {
    let mut neighbours = vec![Vec::new(); positions.len()];
    for t in triangles {
        for k in 0..3 {
            neighbours[t[k] as usize].push(t[(k + 1) % 3]);
        }
    }
    let gradient = |p: Point3| {
        let h = 1e-6;
        Vector3::new(
            f(p + Vector3::x() * h) - f(p - Vector3::x() * h),
            f(p + Vector3::y() * h) - f(p - Vector3::y() * h),
            f(p + Vector3::z() * h) - f(p - Vector3::z() * h),
        ) / (2.0 * h)
    };
    for _ in 0..rounds {
        let before = positions.to_vec();
        for (v, around) in neighbours.iter().enumerate() {
            let centroid = around
                .iter()
                .fold(Vector3::zeros(), |s, &u| s + before[u as usize].coords)
                / around.len() as f64;
            let mut p = Point3::from((before[v].coords + centroid) / 2.0);
            for _ in 0..3 {
                let g = gradient(p);
                p -= g * (f(p) / g.norm_squared().max(1e-300));
            }
            positions[v] = p;
        }
    }
}

fn pretzel_field(p: Point3) -> f64 {
    {
        [-1.8, 0.0, 1.8]
            .into_iter()
            .map(|x0: f64| {
                let ring = (p.x - x0).hypot(p.y) - 1.0;
                ring.hypot(p.z) - 0.35
            })
            .reduce(|a, b| smooth_min(a, b, 0.2))
            .unwrap_or(f64::INFINITY)
    }
}

/// A cube of side 2 with rounded edges, bored through by three round tunnels of radius 0.45 along
/// the axes that meet in its centre (genus 5: six openings into one hollow).
pub fn cube_with_tunnels(cell: f64) -> Mesh {
    level_set(
        &cube_field,
        Point3::new(-1.2, -1.2, -1.2),
        Point3::new(1.2, 1.2, 1.2),
        cell,
    )
}

fn cube_field(p: Point3) -> f64 {
    {
        let q = p.coords.map(|c| (c.abs() - 0.7).max(0.0));
        let inner = (p.x.abs().max(p.y.abs()).max(p.z.abs()) - 0.7).min(0.0);
        let cube = q.norm() + inner - 0.3;
        let tunnel = |a: f64, b: f64| 0.45 - a.hypot(b);
        let tunnels = smooth_max(
            smooth_max(tunnel(p.y, p.z), tunnel(p.x, p.z), 0.1),
            tunnel(p.x, p.y),
            0.1,
        );
        smooth_max(cube, tunnels, 0.1)
    }
}

/// A smooth minimum of a and b (polynomial, blending over k): the union of two solids.
fn smooth_min(a: f64, b: f64, k: f64) -> f64 {
    let h = (0.5 + 0.5 * (b - a) / k).clamp(0.0, 1.0);
    b + (a - b) * h - k * h * (1.0 - h)
}

/// A smooth maximum: the intersection of two solids.
fn smooth_max(a: f64, b: f64, k: f64) -> f64 {
    -smooth_min(-a, -b, k)
}

/// The surface f = 0 (f < 0 inside) in the box from `lo` to `hi`, by marching tetrahedra on a grid
/// of `cell`-sized cubes, each split into six tetrahedra round its main diagonal (the same split in
/// every cube, so the faces match and the surface is closed and manifold). Values within a tenth of
/// a cell of 0 are moved to +cell/10, so no vertex of the surface sits on a grid point and no
/// triangle is degenerate; the surface moves by at most that.
pub fn level_set(f: &dyn Fn(Point3) -> f64, lo: Point3, hi: Point3, cell: f64) -> Mesh {
    let n = ((hi - lo) / cell).map(|c| c.ceil() as usize);
    let index = |i: usize, j: usize, k: usize| (k * (n.y + 1) + j) * (n.x + 1) + i;
    let point =
        |i: usize, j: usize, k: usize| lo + Vector3::new(i as f64, j as f64, k as f64) * cell;
    let mut values = vec![0.0; (n.x + 1) * (n.y + 1) * (n.z + 1)];
    for k in 0..=n.z {
        for j in 0..=n.y {
            for i in 0..=n.x {
                let v = f(point(i, j, k));
                values[index(i, j, k)] = if v.abs() < 0.1 * cell { 0.1 * cell } else { v };
            }
        }
    }
    let mut positions = Vec::new();
    let mut on_edge: HashMap<(usize, usize), u32> = HashMap::new();
    let mut triangles = Vec::new();
    // Corners of a cube by bits (x = 1, y = 2, z = 4); the six tetrahedra share the diagonal 0–7.
    const TETRAHEDRA: [[usize; 4]; 6] = [
        [0, 1, 3, 7],
        [0, 3, 2, 7],
        [0, 2, 6, 7],
        [0, 6, 4, 7],
        [0, 4, 5, 7],
        [0, 5, 1, 7],
    ];
    for k in 0..n.z {
        for j in 0..n.y {
            for i in 0..n.x {
                let corner = |c: usize| (i + (c & 1), j + ((c >> 1) & 1), k + ((c >> 2) & 1));
                for tet in TETRAHEDRA {
                    let ids = tet.map(|c| {
                        let (a, b, d) = corner(c);
                        (index(a, b, d), point(a, b, d))
                    });
                    let mut crossing = |a: usize, b: usize| -> u32 {
                        let ((ia, pa), (ib, pb)) = (ids[a], ids[b]);
                        let key = (ia.min(ib), ia.max(ib));
                        *on_edge.entry(key).or_insert_with(|| {
                            let (fa, fb) = (values[ia], values[ib]);
                            let t = fa / (fa - fb);
                            positions.push(pa + (pb - pa) * t);
                            (positions.len() - 1) as u32
                        })
                    };
                    let inside: Vec<usize> = (0..4).filter(|&c| values[ids[c].0] < 0.0).collect();
                    let outside: Vec<usize> = (0..4).filter(|&c| values[ids[c].0] >= 0.0).collect();
                    let faces: Vec<[u32; 3]> = match (inside.len(), outside.len()) {
                        (1, 3) | (3, 1) => {
                            let (lone, others) = if inside.len() == 1 {
                                (inside[0], outside.clone())
                            } else {
                                (outside[0], inside.clone())
                            };
                            vec![
                                others
                                    .iter()
                                    .map(|&o| crossing(lone, o))
                                    .collect::<Vec<_>>()
                                    .try_into()
                                    .expect("three crossings"),
                            ]
                        }
                        (2, 2) => {
                            let (a, b, c, d) = (inside[0], inside[1], outside[0], outside[1]);
                            let q = [
                                crossing(a, c),
                                crossing(a, d),
                                crossing(b, d),
                                crossing(b, c),
                            ];
                            vec![[q[0], q[1], q[2]], [q[0], q[2], q[3]]]
                        }
                        _ => Vec::new(),
                    };
                    // Each triangle faces from the tetrahedron's inside corners to its outside ones.
                    let towards_out = ids[outside.first().copied().unwrap_or(0)].1
                        - ids[inside.first().copied().unwrap_or(0)].1;
                    for mut t in faces {
                        let [a, b, c] = t.map(|v| positions[v as usize]);
                        if (b - a).cross(&(c - a)).dot(&towards_out) < 0.0 {
                            t.swap(1, 2);
                        }
                        triangles.push(t);
                    }
                }
            }
        }
    }
    (positions, triangles)
}

/// Turns every triangle over where the mesh encloses negative volume (a tube's rings wound the
/// wrong way round its frame).
fn orient_outward(positions: &[Point3], triangles: &mut [[u32; 3]]) {
    let volume: f64 = triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|v| positions[v as usize].coords);
            a.dot(&b.cross(&c))
        })
        .sum();
    if volume < 0.0 {
        for t in triangles {
            t.swap(1, 2);
        }
    }
}

/// An animal of capsules (genus 0): a body 3 long, four legs 1.2 long and 0.16 thick, a neck and a
/// head, smoothly joined. Its conformal map onto the sphere squeezes the legs' ends to specks, as a
/// scanned cow's or a dog's does.
pub fn animal(cell: f64) -> Mesh {
    level_set(
        &animal_field,
        Point3::new(-2.2, -1.0, -1.6),
        Point3::new(2.6, 1.0, 1.4),
        cell,
    )
}

fn animal_field(p: Point3) -> f64 {
    let capsule = |a: [f64; 3], b: [f64; 3], r: f64| {
        let (a, b) = (Vector3::from(a), Vector3::from(b));
        let t = ((p.coords - a).dot(&(b - a)) / (b - a).norm_squared()).clamp(0.0, 1.0);
        (p.coords - (a + (b - a) * t)).norm() - r
    };
    let body = capsule([-1.0, 0.0, 0.0], [1.0, 0.0, 0.0], 0.45);
    let legs = [(-0.9, -0.25), (-0.9, 0.25), (0.9, -0.25), (0.9, 0.25)]
        .iter()
        .map(|&(x, y)| capsule([x, y, -0.2], [x, y, -1.35], 0.16))
        .fold(f64::INFINITY, f64::min);
    let neck = capsule([1.1, 0.0, 0.1], [1.7, 0.0, 0.8], 0.2);
    let head = capsule([1.6, 0.0, 0.85], [2.15, 0.0, 0.75], 0.25);
    smooth_min(
        smooth_min(body, legs, 0.12),
        smooth_min(neck, head, 0.1),
        0.12,
    )
}

/// A gear as CAD programs tessellate one (genus 1): a prism of `height` over an annulus whose
/// outer rim is r(θ) = 1 + 0.12 cos(`teeth` θ) (rounded teeth) and inner rim 0.45, with vertices
/// only on the four rims, `segments` on each. The walls are single needle triangles from the top
/// rim to the bottom one (about `height` / (2π / `segments`) times longer than wide), and the rims
/// are sharp edges.
pub fn needle_gear(segments: usize, teeth: f64, height: f64) -> Mesh {
    let n = segments;
    let rim = |k: usize, outer: bool, z: f64| {
        let theta = std::f64::consts::TAU * (k % n) as f64 / n as f64;
        let r = if outer {
            1.0 + 0.12 * (teeth * theta).cos()
        } else {
            0.45
        };
        Point3::new(r * theta.cos(), r * theta.sin(), z)
    };
    let mut positions = Vec::with_capacity(4 * n);
    for (outer, z) in [(true, height), (false, height), (true, 0.0), (false, 0.0)] {
        positions.extend((0..n).map(|k| rim(k, outer, z)));
    }
    let index = |ring: usize, k: usize| (ring * n + k % n) as u32;
    let (top_out, top_in, bottom_out, bottom_in) = (0, 1, 2, 3);
    let mut triangles = Vec::with_capacity(8 * n);
    for k in 0..n {
        let quads = [
            // Top (+z), bottom (−z), outer wall (outwards), inner wall (towards the axis).
            [(top_out, k), (top_out, k + 1), (top_in, k + 1), (top_in, k)],
            [
                (bottom_out, k),
                (bottom_in, k),
                (bottom_in, k + 1),
                (bottom_out, k + 1),
            ],
            [
                (top_out, k),
                (bottom_out, k),
                (bottom_out, k + 1),
                (top_out, k + 1),
            ],
            [
                (top_in, k),
                (top_in, k + 1),
                (bottom_in, k + 1),
                (bottom_in, k),
            ],
        ];
        for q in quads {
            let [a, b, c, d] = q.map(|(ring, k)| index(ring, k));
            triangles.push([a, b, c]);
            triangles.push([a, c, d]);
        }
    }
    (positions, triangles)
}
