//! Issue 12's crease test: how the bend between neighbouring triangles of the t_e = t_r = T
//! tessellation goes as T doubles from 32 to 64 and 128. On a smooth surface the bend across an
//! edge is about the edge's length times the normal curvature, so it halves when T doubles; a
//! crease keeps it.
//!
//! Prints, per model file and T, each measure with its ratio to the previous T's: the largest
//! bend, its 99.9th percentile, the largest bend between triangles with no angle above 120°, the
//! largest turn of the surface's own normal along an edge (which sees the surface, not the
//! triangles' shape); the count of triangles with an angle of 170° or more; and where the largest
//! bend lies. `NTORI_WHERE=1` adds the two triangles that bend most, per region of the
//! tessellation (square, inside wheel, vertex wheel) the edge along which the normal turns most,
//! and where the triangles of 170° or more lie (region, and how far out in their chart).
//! `cargo run --release -p embedding --example crease_report MODEL.json…`
use charts::Tessellation;
use embedding::{Point3, Stencil, Surface, Vector3};

fn main() {
    let paths: Vec<String> = std::env::args().skip(1).collect();
    assert!(!paths.is_empty(), "give one or more model files");
    let details = std::env::var("NTORI_WHERE").is_ok();
    println!(
        "model  T  triangles  ≥170°  largest bend(°) ratio  p99.9 bend ratio  well-shaped triangles' bend ratio  surface normal turn ratio  at"
    );
    for path in &paths {
        let model: embedding::model::Model =
            serde_json::from_str(&std::fs::read_to_string(path).expect("readable"))
                .expect("a model");
        let surface = Surface::from_model(&model).expect("a surface");
        let mut previous: Option<Bends> = None;
        for t in [32u32, 64, 128] {
            let mesh = Placed::new(&surface, t);
            let b = mesh.bends(details);
            if details {
                mesh.print_flat_triangles();
            }
            let ratio = |measure: fn(&Bends) -> f64| {
                let value = measure(&b);
                match &previous {
                    Some(p) => format!("{value:8.3} {:5.2}", value / measure(p)),
                    None => format!("{value:8.3}      "),
                }
            };
            println!(
                "{path}  {t:3}  {:9}  {:5}  {}  {}  {}  {}  ({:.3}, {:.3}, {:.3})",
                mesh.tess.triangles.len(),
                mesh.largest_angles.iter().filter(|&&a| a >= 170.0).count(),
                ratio(|b| b.largest),
                ratio(|b| b.p999),
                ratio(|b| b.well_shaped),
                ratio(|b| b.normal_turn),
                b.at.x,
                b.at.y,
                b.at.z
            );
            previous = Some(b);
        }
    }
}

/// The t_e = t_r = T tessellation placed on the surface: positions, the surface's normals at the
/// vertices, and each triangle's normal and largest angle (degrees).
struct Placed {
    tess: Tessellation,
    positions: Vec<Point3>,
    surface_normals: Vec<Vector3>,
    normals: Vec<Vector3>,
    largest_angles: Vec<f64>,
}

/// One tessellation's bends, in degrees.
struct Bends {
    /// The largest angle between the normals of two triangles sharing an edge, and its 99.9th
    /// percentile.
    largest: f64,
    p999: f64,
    /// The largest over edges whose two triangles have no angle above 120°.
    well_shaped: f64,
    /// The largest angle between the surface's own normals at an edge's two ends.
    normal_turn: f64,
    /// The midpoint of the edge that bends most.
    at: Point3,
}

impl Placed {
    fn new(surface: &Surface, t: u32) -> Self {
        let tess = surface.atlas().tessellate(t, t).expect("a tessellation");
        let stencil = Stencil::build(&surface.layout(), &tess.vertices);
        let mut positions = vec![Point3::origin(); stencil.rows()];
        stencil.positions(surface.control_points(), &mut positions);
        let mut surface_normals = vec![Vector3::zeros(); stencil.rows()];
        stencil.normals(surface.control_points(), &mut surface_normals);
        let corners = |tri: &[u32; 3]| tri.map(|i| positions[i as usize]);
        let normals = tess
            .triangles
            .iter()
            .map(|tri| {
                let p = corners(tri);
                (p[1] - p[0]).cross(&(p[2] - p[0])).normalize()
            })
            .collect();
        let largest_angles = tess
            .triangles
            .iter()
            .map(|tri| angles(corners(tri)).into_iter().fold(0.0, f64::max))
            .collect();
        Placed {
            tess,
            positions,
            surface_normals,
            normals,
            largest_angles,
        }
    }

    /// Every interior edge once: its ends and its two triangles.
    fn edges(&self) -> Vec<(u32, u32, usize, usize)> {
        let mut owner = std::collections::HashMap::with_capacity(3 * self.tess.triangles.len());
        for (k, tri) in self.tess.triangles.iter().enumerate() {
            for e in 0..3 {
                owner.insert((tri[e], tri[(e + 1) % 3]), k);
            }
        }
        owner
            .iter()
            .filter(|((a, b), _)| a < b)
            .filter_map(|(&(a, b), &k)| Some((a, b, k, *owner.get(&(b, a))?)))
            .collect()
    }

    fn bends(&self, details: bool) -> Bends {
        let well_shaped = |k: usize| self.largest_angles[k] <= 120.0;
        let turn = |a: u32, b: u32| {
            let n = &self.surface_normals;
            n[a as usize].angle(&n[b as usize]).to_degrees()
        };
        let edges = self.edges();
        let mut all = Vec::with_capacity(edges.len());
        let (mut largest, mut worst) = (0.0f64, edges[0]);
        let (mut shapely, mut normal_turn) = (0.0f64, 0.0f64);
        let mut region_turn = [(0.0f64, edges[0]); 3];
        for &edge @ (a, b, k, other) in &edges {
            let bend = self.normals[k].angle(&self.normals[other]).to_degrees();
            all.push(bend);
            if well_shaped(k) && well_shaped(other) {
                shapely = shapely.max(bend);
            }
            let along = turn(a, b);
            normal_turn = normal_turn.max(along);
            let region = &mut region_turn[self.tess.triangle_regions[k] as usize];
            if along > region.0 {
                *region = (along, edge);
            }
            if bend > largest {
                (largest, worst) = (bend, edge);
            }
        }
        if details {
            self.print_triangle(worst.2);
            self.print_triangle(worst.3);
            for (turn, (a, b, k, _)) in region_turn {
                let (p, q) = (self.positions[a as usize], self.positions[b as usize]);
                println!(
                    "  {:?}: the normal turns {turn:.1}° along an edge of length {:.3} at ({:.2}, {:.2}, {:.2}), chart {:?}",
                    self.tess.triangle_regions[k],
                    (p - q).norm(),
                    p.x,
                    p.y,
                    p.z,
                    self.tess.triangle_charts[k],
                );
            }
        }
        all.sort_by(f64::total_cmp);
        let (a, b) = (
            self.positions[worst.0 as usize],
            self.positions[worst.1 as usize],
        );
        Bends {
            largest,
            p999: all[(all.len() as f64 * 0.999) as usize],
            well_shaped: shapely,
            normal_turn,
            at: Point3::from((a.coords + b.coords) / 2.0),
        }
    }

    /// Where the triangles with an angle of 170° or more lie: per region, how many at each
    /// twentieth of the way from the wheel's centre to its farthest corner (the rim's star points;
    /// squares by their own chart's farthest corner).
    fn print_flat_triangles(&self) {
        let mut reach = std::collections::HashMap::new();
        for (k, corners) in self.tess.triangle_coords.iter().enumerate() {
            let far = reach.entry(self.tess.triangle_charts[k]).or_insert(0.0f64);
            *far = corners.iter().map(|z| z.norm()).fold(*far, f64::max);
        }
        let mut counts = std::collections::BTreeMap::new();
        for (k, &angle) in self.largest_angles.iter().enumerate() {
            if angle >= 170.0 {
                let [a, b, c] = self.tess.triangle_coords[k];
                let out = ((a + b + c) / 3.0).norm() / reach[&self.tess.triangle_charts[k]];
                let key = (
                    format!("{:?}", self.tess.triangle_regions[k]),
                    (20.0 * out) as u32,
                );
                *counts.entry(key).or_insert(0usize) += 1;
            }
        }
        for ((region, twentieth), count) in counts {
            println!(
                "  {count} triangles of 170° or more in the {region} at {:.2}–{:.2} of the way out",
                f64::from(twentieth) / 20.0,
                f64::from(twentieth + 1) / 20.0
            );
        }
    }

    fn print_triangle(&self, k: usize) {
        let p = self.tess.triangles[k].map(|i| self.positions[i as usize]);
        println!(
            "  triangle {k}: chart {:?}, {:?}, angles {:.2?}°, corners in its chart {:.4?}, in space {:.4?}",
            self.tess.triangle_charts[k],
            self.tess.triangle_regions[k],
            angles(p),
            self.tess.triangle_coords[k],
            p.map(|q| [q.x, q.y, q.z])
        );
    }
}

/// A triangle's angles in degrees.
fn angles(p: [Point3; 3]) -> [f64; 3] {
    [0, 1, 2].map(|j| {
        (p[(j + 1) % 3] - p[j])
            .angle(&(p[(j + 2) % 3] - p[j]))
            .to_degrees()
    })
}
