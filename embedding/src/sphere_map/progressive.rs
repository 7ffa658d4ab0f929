//! A genus-0 mesh put on the sphere coarse to fine: a bijective map that never passes through the
//! conformal map's squeeze of long limbs (after Shapiro and Tal, "Polyhedron realization for shape
//! transformation", 1998, for the hierarchy, and Praun and Hoppe, "Spherical parametrization and
//! remeshing", 2003, for the stretch each insertion is smoothed by).
//!
//! 1. The mesh is simplified one vertex at a time down to a tetrahedron. Each step takes out a
//!    vertex of degree at most 5 and fills its hole with a fan. A hole of at most five sides is
//!    star-shaped wherever the coarser map draws it without overlap (one guard sees any simple
//!    polygon of five sides or fewer), so the vertex has room to come back inside it (up to
//!    rounding: where none is found, no map is made). The vertex
//!    whose star has least area goes first: the coarse meshes keep their vertices spread evenly
//!    over the surface, and a long limb keeps vertices in proportion to its area.
//! 2. The tetrahedron goes onto the sphere as the regular one.
//! 3. The vertices come back in reverse order. Each is put where its star's triangles are furthest
//!    from turning over (the centre of its hole's kernel), then it and its ring are moved down the
//!    map's symmetric Dirichlet energy over their triangles ([`Energy`]), and every so often the
//!    whole mesh is. The energy grows without bound as a triangle's image shrinks to nothing, so
//!    it charges a squeezed triangle most, and the limbs keep room on the sphere as they come back.
//!
//! The conformal map squeezes a limb exponentially in its length over its girth (CGAL's dino ×10²⁰
//! at its tail); built this way, the same mesh's map squeezes no triangle by more than ×87, and
//! [`super::equalize_areas`] can even out from there.

use std::cmp::Reverse;
use std::collections::{BinaryHeap, HashMap};

use nalgebra::{Vector2, Vector3};

use super::{folded_triangles, from_frame, orientation, orientation_of, tangent_frame, to_frame};
use crate::surface::Point3;

/// The largest hole a removed vertex leaves: five sides, the most that are always star-shaped.
const MAX_HOLE: usize = 5;

/// Descent steps each vertex takes when it or a neighbour comes back.
const LOCAL_STEPS: usize = 2;

/// [`GROWTH_PASSES`] whole-mesh passes of descent are run each time the number of vertices back
/// on the sphere grows by this factor, so the early, coarse layout keeps adapting as the mesh
/// fills in.
const PASS_GROWTH: f64 = 1.5;

/// Passes run at each growth by [`PASS_GROWTH`]. One vertex's descent moves the map only locally,
/// so a squeeze that spans a limb takes many passes to undo on the whole mesh, and few on a
/// coarse one, where they cost little (over all growths, about 30 vertex moves per vertex of the
/// mesh). CGAL's dino (3 916 vertices): with 1 pass a growth its worst triangle stays ×2·10⁴ after
/// the final passes (its fit 5.9% of the diagonal from its mesh both ways); with 10, ×87 (2.4%);
/// with 30, ×46 (1.9%). 30 is not the rule: it took u.off from 1.4% to 1.2% but the cow from 1.2%
/// to 1.4% and the cactus from 1.3% to 2.0% (the airplane 0.27% either way).
const GROWTH_PASSES: usize = 10;

/// Most whole-mesh passes once every vertex is back. On pymeshlab's cow (3 043 vertices with its
/// long edges split; measured with one pass a growth and the earlier energy) the worst triangle after 10, 50, 200, 500
/// and 1 000 final passes was ×313, ×51, ×46, ×46 and ×46, and the fit through the map came no
/// closer to the mesh after 200 (4.9%, 3.4%, 2.1%, 2.3% and 2.3% of the diagonal).
const FINAL_PASSES: usize = 300;

/// Most vertex moves of the final passes together, so a large mesh takes fewer of them: 300
/// passes up to 6 666 vertices, 71 for the bunny's 28 088 (whose coarse-to-fine map took 10 s
/// with 300).
const FINAL_MOVES: usize = 2_000_000;

/// A pass in which no vertex moves further than this (on the unit sphere) ends the passes.
const SETTLED: f64 = 1e-6;

/// Halvings of a descent step before the vertex is left where it is.
const LINE_HALVINGS: usize = 10;

/// A vertex is moved only while every ring point lies this far round from it (the cosine of the
/// angle): its frame, the stereographic projection from its antipode, sends the antipode to
/// infinity.
const MIN_RING_COSINE: f64 = -0.9;

/// The map of the mesh onto the unit sphere, built coarse to fine, or None where the mesh cannot
/// be simplified to a tetrahedron (its triangles do not make a closed, consistently oriented
/// genus-0 surface) or a vertex finds no room in its hole. No triangle of the map turns over.
pub(super) fn progressive_map(
    positions: &[Point3],
    triangles: &[[u32; 3]],
) -> Option<Vec<Vector3<f64>>> {
    let mut mesh = Connectivity::new(positions.len(), triangles)?;
    let removed = simplify(&mut mesh, positions)?;
    let mut points = vec![Vector3::zeros(); positions.len()];
    place_tetrahedron(&mesh, &mut points)?;
    let energy = Energy::new(positions, triangles);
    let mut back = positions.len() - removed.len();
    let mut next_pass = back as f64 * PASS_GROWTH;
    for removal in removed.iter().rev() {
        reinsert(&mut mesh, removal);
        points[removal.vertex as usize] = kernel_centre(&points, &removal.ring)?;
        let v = removal.vertex;
        energy.descend(&mesh, &mut points, v, LOCAL_STEPS);
        for &r in &removal.ring {
            energy.descend(&mesh, &mut points, r, 1);
        }
        energy.descend(&mesh, &mut points, v, LOCAL_STEPS);
        back += 1;
        if back as f64 >= next_pass {
            next_pass = back as f64 * PASS_GROWTH;
            for _ in 0..GROWTH_PASSES {
                energy.whole_pass(&mesh, &mut points);
            }
        }
    }
    let passes = FINAL_PASSES.min(FINAL_MOVES / positions.len().max(1));
    for _ in 0..passes {
        if energy.whole_pass(&mesh, &mut points) < SETTLED {
            break;
        }
    }
    (folded_triangles(&points, triangles) == 0).then_some(points)
}

/// One step of the simplification: `vertex` was taken out of the hole bounded by `ring`
/// (counter-clockwise seen from outside), which was filled by a fan from `ring[apex]`.
#[derive(Clone, Debug)]
struct Removal {
    vertex: u32,
    ring: Vec<u32>,
    apex: usize,
}

impl Removal {
    /// The fan's triangles, counter-clockwise like the ring.
    fn fan(&self) -> impl Iterator<Item = [u32; 3]> + '_ {
        let d = self.ring.len();
        let at = move |k: usize| self.ring[(self.apex + k) % d];
        (1..d - 1).map(move |j| [at(0), at(j), at(j + 1)])
    }

    /// The vertex's own triangles, as they were before it was taken out.
    fn star(&self) -> impl Iterator<Item = [u32; 3]> + '_ {
        let d = self.ring.len();
        (0..d).map(move |i| [self.vertex, self.ring[i], self.ring[(i + 1) % d]])
    }

    /// The fan's diagonals: the edges it adds inside the hole.
    fn diagonals(&self) -> impl Iterator<Item = (u32, u32)> + '_ {
        let d = self.ring.len();
        let at = move |k: usize| self.ring[(self.apex + k) % d];
        (2..d - 1).map(move |j| (at(0), at(j)))
    }
}

/// The mesh's triangles as they change during simplification and insertion.
struct Connectivity {
    /// For every directed edge (a, b) of a triangle (a, b, c), its third corner c.
    apex: HashMap<u64, u32>,
    /// Each vertex's neighbours, in no order (empty once it is taken out).
    adjacent: Vec<Vec<u32>>,
}

/// A directed edge as one key.
fn key(a: u32, b: u32) -> u64 {
    (u64::from(a) << 32) | u64::from(b)
}

impl Connectivity {
    /// None where a directed edge belongs to two triangles (the mesh is not manifold or not
    /// consistently oriented) or an edge has one triangle only (it is not closed).
    fn new(vertices: usize, triangles: &[[u32; 3]]) -> Option<Self> {
        let mut mesh = Connectivity {
            apex: HashMap::with_capacity(3 * triangles.len()),
            adjacent: vec![Vec::new(); vertices],
        };
        for &t in triangles {
            if !mesh.add(t) {
                return None;
            }
        }
        let closed = mesh.apex.keys().all(|&k| {
            let (a, b) = ((k >> 32) as u32, k as u32);
            mesh.apex.contains_key(&key(b, a))
        });
        closed.then_some(mesh)
    }

    /// Adds a triangle's directed edges and any of its edges not yet known; false where a directed
    /// edge is taken already.
    fn add(&mut self, [a, b, c]: [u32; 3]) -> bool {
        for (x, y, z) in [(a, b, c), (b, c, a), (c, a, b)] {
            if self.apex.insert(key(x, y), z).is_some() {
                return false;
            }
            if !self.adjacent[x as usize].contains(&y) {
                self.adjacent[x as usize].push(y);
                self.adjacent[y as usize].push(x);
            }
        }
        true
    }

    /// Takes a triangle's directed edges out (its edges stay: see [`Connectivity::cut`]).
    fn remove(&mut self, [a, b, c]: [u32; 3]) {
        for (x, y) in [(a, b), (b, c), (c, a)] {
            self.apex.remove(&key(x, y));
        }
    }

    /// Takes edge ab out.
    fn cut(&mut self, a: u32, b: u32) {
        self.adjacent[a as usize].retain(|&u| u != b);
        self.adjacent[b as usize].retain(|&u| u != a);
    }

    fn degree(&self, v: u32) -> usize {
        self.adjacent[v as usize].len()
    }

    /// v's neighbours counter-clockwise seen from outside, or None if its triangles do not close
    /// round it.
    fn ring(&self, v: u32) -> Option<Vec<u32>> {
        let first = *self.adjacent[v as usize].first()?;
        let mut ring = vec![first];
        let mut u = *self.apex.get(&key(v, first))?;
        while u != first {
            if ring.len() >= self.degree(v) {
                return None;
            }
            ring.push(u);
            u = *self.apex.get(&key(v, u))?;
        }
        (ring.len() == self.degree(v)).then_some(ring)
    }
}

/// The area of v's star in space.
fn star_area(positions: &[Point3], v: u32, ring: &[u32]) -> f64 {
    let x = positions[v as usize];
    (0..ring.len())
        .map(|i| {
            let a = positions[ring[i] as usize] - x;
            let b = positions[ring[(i + 1) % ring.len()] as usize] - x;
            a.cross(&b).norm() / 2.0
        })
        .sum()
}

/// Takes vertices out of `mesh` (least star area first, degree at most [`MAX_HOLE`]) until four
/// are left, in the order taken; None if it stalls before.
fn simplify(mesh: &mut Connectivity, positions: &[Point3]) -> Option<Vec<Removal>> {
    let n = positions.len();
    // Entries carry the vertex's version when pushed; one whose star has changed since is stale.
    let mut version = vec![0u32; n];
    let mut queue = BinaryHeap::new();
    let push = |queue: &mut BinaryHeap<_>, mesh: &Connectivity, v: u32, version: u32| {
        if mesh.degree(v) <= MAX_HOLE
            && let Some(ring) = mesh.ring(v)
        {
            let area = star_area(positions, v, &ring);
            // Areas are not negative, so their bits order as they do.
            queue.push(Reverse((area.to_bits(), v, version)));
        }
    };
    for v in 0..n as u32 {
        push(&mut queue, mesh, v, 0);
    }
    let mut removed = Vec::with_capacity(n.saturating_sub(4));
    let mut left = n;
    while left > 4 {
        let Reverse((_, v, stamp)) = queue.pop()?;
        if stamp != version[v as usize] || mesh.degree(v) == 0 || mesh.degree(v) > MAX_HOLE {
            continue;
        }
        let Some(removal) = best_fan(mesh, positions, v) else {
            // Every fan would double an edge: wait until v's star changes.
            continue;
        };
        take_out(mesh, &removal);
        for &r in &removal.ring {
            version[r as usize] += 1;
            push(&mut queue, mesh, r, version[r as usize]);
        }
        removed.push(removal);
        left -= 1;
    }
    Some(removed)
}

/// Of the fans that can fill v's hole without doubling an edge, the one whose worst triangle is
/// best shaped in space (and faces the way v's star faced).
fn best_fan(mesh: &Connectivity, positions: &[Point3], v: u32) -> Option<Removal> {
    let ring = mesh.ring(v)?;
    let d = ring.len();
    let facing: Vector3<f64> = (0..d)
        .map(|i| {
            let x = positions[v as usize];
            (positions[ring[i] as usize] - x).cross(&(positions[ring[(i + 1) % d] as usize] - x))
        })
        .sum();
    let quality = |t: [u32; 3]| {
        let [a, b, c] = t.map(|k| positions[k as usize]);
        let normal = (b - a).cross(&(c - a));
        let edges = (b - a).norm_squared() + (c - b).norm_squared() + (a - c).norm_squared();
        let shape = 2.0 * 3f64.sqrt() * normal.norm() / edges.max(f64::MIN_POSITIVE);
        if normal.dot(&facing) > 0.0 {
            shape
        } else {
            shape - 1.0
        }
    };
    let apexes = if d == 3 { 1 } else { d };
    (0..apexes)
        .map(|apex| Removal {
            vertex: v,
            ring: ring.clone(),
            apex,
        })
        .filter(|r| {
            r.diagonals()
                .all(|(a, b)| !mesh.adjacent[a as usize].contains(&b))
        })
        .map(|r| {
            let worst = r.fan().map(quality).fold(f64::INFINITY, f64::min);
            (worst, r)
        })
        .max_by(|a, b| a.0.total_cmp(&b.0))
        .map(|(_, r)| r)
}

fn take_out(mesh: &mut Connectivity, removal: &Removal) {
    removal.star().for_each(|t| mesh.remove(t));
    for &r in &removal.ring {
        mesh.cut(removal.vertex, r);
    }
    for t in removal.fan() {
        mesh.add(t);
    }
}

fn reinsert(mesh: &mut Connectivity, removal: &Removal) {
    removal.fan().for_each(|t| mesh.remove(t));
    for (a, b) in removal.diagonals() {
        mesh.cut(a, b);
    }
    for t in removal.star() {
        mesh.add(t);
    }
}

/// The last four vertices at the corners of a regular tetrahedron, its triangles counter-clockwise
/// seen from outside.
fn place_tetrahedron(mesh: &Connectivity, points: &mut [Vector3<f64>]) -> Option<()> {
    // The lowest directed edge left, so the same mesh always gets the same map.
    let (&k, &c) = mesh.apex.iter().min_by_key(|(k, _)| **k)?;
    let (a, b) = ((k >> 32) as u32, k as u32);
    let d = *mesh.apex.get(&key(b, a))?;
    // Triangle abc faces away from d: with d at the north pole, a, b, c run clockwise seen from
    // above, counter-clockwise seen from below.
    let r = (8.0f64 / 9.0).sqrt();
    let corner = |k: f64| {
        let angle = -k * std::f64::consts::TAU / 3.0;
        Vector3::new(r * angle.cos(), r * angle.sin(), -1.0 / 3.0)
    };
    points[d as usize] = Vector3::z();
    points[a as usize] = corner(0.0);
    points[b as usize] = corner(1.0);
    points[c as usize] = corner(2.0);
    let faces: Vec<[u32; 3]> = mesh
        .apex
        .iter()
        .map(|(&k, &z)| [(k >> 32) as u32, k as u32, z])
        .collect();
    faces
        .iter()
        .all(|t| orientation(points, t) > 0.0)
        .then_some(())
}

/// The point of the sphere inside every great circle through consecutive ring points (the
/// positive side of each), as far from the nearest as can be: the centre of the hole's kernel.
/// None if the kernel is empty.
fn kernel_centre(points: &[Vector3<f64>], ring: &[u32]) -> Option<Vector3<f64>> {
    let d = ring.len();
    let normals: Vec<Vector3<f64>> = (0..d)
        .filter_map(|i| {
            let (a, b) = (points[ring[i] as usize], points[ring[(i + 1) % d] as usize]);
            a.cross(&b).try_normalize(0.0)
        })
        .collect();
    if normals.len() < d {
        return None;
    }
    let margin = |p: &Vector3<f64>| {
        normals
            .iter()
            .map(|n| n.dot(p))
            .fold(f64::INFINITY, f64::min)
    };
    // The best point has one, two or three sides at the same, least distance: try every such set.
    let mut candidates: Vec<Vector3<f64>> = normals.clone();
    for i in 0..d {
        for j in i + 1..d {
            candidates.extend((normals[i] + normals[j]).try_normalize(0.0));
            for k in j + 1..d {
                let p = (normals[i] - normals[j]).cross(&(normals[j] - normals[k]));
                if let Some(p) = p.try_normalize(0.0) {
                    candidates.extend([p, -p]);
                }
            }
        }
    }
    candidates
        .into_iter()
        .map(|p| (margin(&p), p))
        .max_by(|a, b| a.0.total_cmp(&b.0))
        .filter(|(m, _)| *m > 0.0)
        .map(|(_, p)| p)
}

/// The symmetric Dirichlet energy of the map from the sphere to the surface (Schreiner, Asirvatham,
/// Praun and Hoppe 2004; Smith and Schaefer 2015): over each triangle, its area in space times
/// |J|² + |J⁻¹|², J the map's derivative, with the surface scaled to the sphere's area. It is
/// least where the map is an isometry, and it grows without bound both where a triangle's image
/// shrinks to nothing (so none turns over) and where it is sheared: L² stretch alone (the first
/// term) left the cow's map sheared σ₁/σ₂ 190 at worst after 200 passes, against 59 with both.
struct Energy<'a> {
    positions: &'a [Point3],
    /// The sphere's area over the surface's.
    scale: f64,
    /// The least scaled area a triangle of the mesh counts with: 10⁻¹² of the mean.
    least_area: f64,
}

impl<'a> Energy<'a> {
    fn new(positions: &'a [Point3], triangles: &[[u32; 3]]) -> Self {
        let area: f64 = triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|v| positions[v as usize]);
                (b - a).cross(&(c - a)).norm() / 2.0
            })
            .sum();
        let sphere = 4.0 * std::f64::consts::PI;
        Energy {
            positions,
            scale: sphere / area.max(f64::MIN_POSITIVE),
            least_area: 1e-12 * sphere / triangles.len().max(1) as f64,
        }
    }

    /// One descent step for every vertex back on the sphere; returns the furthest any moved.
    fn whole_pass(&self, mesh: &Connectivity, points: &mut [Vector3<f64>]) -> f64 {
        let mut furthest = 0.0f64;
        for v in 0..points.len() as u32 {
            if mesh.degree(v) > 0 {
                let before = points[v as usize];
                self.descend(mesh, points, v, 1);
                furthest = furthest.max((points[v as usize] - before).norm());
            }
        }
        furthest
    }

    /// Moves v on the sphere to lower the energy of its triangles, `steps` steps of gradient
    /// descent in its own frame (the stereographic projection from its antipode, scaled to keep
    /// lengths at v), each step halved until the energy falls and no triangle of v's turns over
    /// on the sphere. The energy, measured in the frame, grows without bound as a triangle's
    /// image there shrinks, so the steps stop short of that.
    fn descend(&self, mesh: &Connectivity, points: &mut [Vector3<f64>], v: u32, steps: usize) {
        let Some(ring) = mesh.ring(v) else {
            return;
        };
        let c = points[v as usize];
        if ring
            .iter()
            .any(|&r| points[r as usize].dot(&c) < MIN_RING_COSINE)
        {
            return;
        }
        let (e1, e2) = tangent_frame(c);
        let plane = |q: Vector3<f64>| {
            let d = to_frame(c, q) * 2.0;
            Vector2::new(d.dot(&e1), d.dot(&e2))
        };
        let sphere = |p: Vector2<f64>| from_frame(c, (e1 * p.x + e2 * p.y) / 2.0);
        let flat: Vec<Vector2<f64>> = ring.iter().map(|&r| plane(points[r as usize])).collect();
        let around: Vec<Point3> = ring.iter().map(|&r| self.positions[r as usize]).collect();
        let x = self.positions[v as usize];
        let energy = |p: Vector2<f64>| self.star(p, &flat, x, &around);
        // The fold test the finished map is checked by, which keeps its sign on triangles
        // squeezed to 1e-8 and less, where q·(a × b) is lost to rounding.
        let unfolded = |q: Vector3<f64>| {
            let d = ring.len();
            (0..d).all(|i| {
                let (a, b) = (points[ring[i] as usize], points[ring[(i + 1) % d] as usize]);
                orientation_of(q, a, b) > 0.0
            })
        };
        let size = flat.iter().map(|w| w.norm()).sum::<f64>() / flat.len() as f64;
        let mut p = Vector2::zeros();
        let mut now = energy(p);
        if !now.is_finite() {
            return;
        }
        let h = 1e-6 * size;
        for _ in 0..steps {
            let gradient = Vector2::new(
                energy(p + Vector2::new(h, 0.0)) - energy(p - Vector2::new(h, 0.0)),
                energy(p + Vector2::new(0.0, h)) - energy(p - Vector2::new(0.0, h)),
            ) / (2.0 * h);
            let Some(direction) = (-gradient).try_normalize(0.0) else {
                break;
            };
            let mut step = 0.5 * size;
            let mut moved = false;
            for _ in 0..LINE_HALVINGS {
                let trial = p + direction * step;
                let e = energy(trial);
                if e < now && unfolded(sphere(trial)) {
                    (p, now, moved) = (trial, e, true);
                    break;
                }
                step /= 2.0;
            }
            if !moved {
                break;
            }
        }
        if p != Vector2::zeros() {
            points[v as usize] = sphere(p);
        }
    }

    /// The energy of v's triangles with v at p in its frame and its ring at `flat` (v at `x` in
    /// space, its ring at `around`); infinite if a triangle is not counter-clockwise in the frame.
    fn star(&self, p: Vector2<f64>, flat: &[Vector2<f64>], x: Point3, around: &[Point3]) -> f64 {
        let d = flat.len();
        let mut sum = 0.0;
        for i in 0..d {
            let j = (i + 1) % d;
            let s = [p, flat[i], flat[j]];
            let q = [x, around[i], around[j]];
            let doubled = (s[1] - s[0]).perp(&(s[2] - s[0]));
            if doubled <= 0.0 {
                return f64::INFINITY;
            }
            // The affine map from the plane's triangle to the surface's: its derivatives along the
            // plane's two axes (Sander et al.'s S_s and S_t).
            let along_s = (q[0].coords * (s[1].y - s[2].y)
                + q[1].coords * (s[2].y - s[0].y)
                + q[2].coords * (s[0].y - s[1].y))
                / doubled;
            let along_t = (q[0].coords * (s[2].x - s[1].x)
                + q[1].coords * (s[0].x - s[2].x)
                + q[2].coords * (s[1].x - s[0].x))
                / doubled;
            let area = (q[1] - q[0]).cross(&(q[2] - q[0])).norm() / 2.0;
            // With the surface scaled by the sphere's area over its own (k): area·(|J|² + |J⁻¹|²)
            // = k·area·k|J|² + |J|²·image²/area, k times this sum; |J⁻¹|² = |J|² / det J², det J
            // the ratio of the areas. The scaled area is floored, so a degenerate triangle of the
            // mesh neither divides by zero nor freezes its corners.
            let squared = along_s.norm_squared() + along_t.norm_squared();
            let image = doubled / 2.0;
            let scaled = (self.scale * area).max(self.least_area);
            sum += squared * (scaled + image * image / scaled);
        }
        sum
    }
}
