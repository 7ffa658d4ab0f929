//! Issue 15's quality tessellation over the example models: triangle count and time against the
//! t_e = t_r = 32 tessellation, triangle angles, the largest bend between neighbours, triangles
//! facing away from the surface, and the chordal error.
//! `cargo run --release -p embedding --example quality_report [GENERA…]`; `NTORI_ROUNDS=R` sets
//! the rounds, `NTORI_TOLERANCE=T` the tolerance, `NTORI_WHERE=1` lists the triangles that miss
//! the targets, `NTORI_QUADS=1` reports the all-quad tessellation instead (its corner angles).
use std::time::Instant;

use embedding::remesh::{QualitySettings, quad_mesh, quality_mesh};
use embedding::{Model, Point3, Stencil, Surface};

fn asset(genus: u32) -> Option<Surface> {
    let path = format!(
        "{}/../assets/models/genus-{genus}.json",
        env!("CARGO_MANIFEST_DIR")
    );
    let text = std::fs::read_to_string(path).ok()?;
    let model: Model = serde_json::from_str(&text).expect("a model");
    Some(Surface::from_model(&model).expect("a surface"))
}

fn main() {
    let genera: Vec<u32> = std::env::args()
        .skip(1)
        .map(|a| a.parse().expect("a genus"))
        .collect();
    let genera = if genera.is_empty() {
        (0..=10).collect()
    } else {
        genera
    };
    let mut settings = QualitySettings::default();
    if let Ok(r) = std::env::var("NTORI_ROUNDS") {
        settings.rounds = r.parse().expect("NTORI_ROUNDS: a number of rounds");
    }
    if let Ok(t) = std::env::var("NTORI_TOLERANCE") {
        settings.tolerance = t
            .parse()
            .expect("NTORI_TOLERANCE: a fraction of the diagonal");
    }
    println!(
        "genus  triangles  time(s)  t32-triangles  t32-time(s)  angles(°)      ≥20°(%)  ≥150°  bend(°)  away  chordal/diag"
    );
    for genus in genera {
        let Some(s) = asset(genus) else { continue };
        let start = Instant::now();
        let quads = std::env::var("NTORI_QUADS").is_ok();
        let q = if quads {
            quad_mesh(&s, &settings).expect("a quad mesh")
        } else {
            quality_mesh(&s, &settings).expect("a quality mesh")
        };
        let seconds = start.elapsed().as_secs_f64();
        if std::env::var("NTORI_WHERE").is_ok() {
            report_bad(&s, &q);
        }
        let start = Instant::now();
        let tess = s.atlas().tessellate(32, 32).expect("a tessellation");
        let stencil = Stencil::build(&s.layout(), &tess.vertices);
        let mut positions = vec![Point3::origin(); stencil.rows()];
        stencil.positions(s.control_points(), &mut positions);
        let t32 = start.elapsed().as_secs_f64();
        let pos: Vec<[f64; 3]> = q.positions.iter().map(|p| [p.x, p.y, p.z]).collect();
        let topology =
            mesh::HalfEdgeMesh::from_polygons(pos.len(), q.triangles.iter().map(|t| &t[..]))
                .expect("a mesh")
                .topology();
        assert!(
            topology.closed && topology.manifold && topology.orientable,
            "genus {genus}"
        );
        assert_eq!(
            topology.euler_characteristic,
            2 - 2 * genus as i64,
            "genus {genus}"
        );
        if quads {
            report_quads(genus, seconds, &q);
        }
        let shape = mesh::mesh_shape(&pos, &q.triangles).expect("a mesh");
        let fidelity = q.fidelity(&s);
        let (worst, away) = (fidelity.chordal_error, fidelity.facing_away);
        println!(
            "{genus:5}  {:9}  {seconds:7.2}  {:13}  {t32:11.2}  {:5.1}–{:5.1}  {:7.2}  {:5}  {:7.1}  {away:4}  {worst:.2e}",
            q.triangles.len(),
            tess.triangles.len(),
            shape.smallest_angle,
            shape.largest_angle,
            100.0 * shape.well_shaped(),
            shape.above_150,
            shape.largest_bend,
        );
    }
}

/// Prints the edges bending more than 20° (with |κ| and length over the diagonal) and the
/// triangles with an angle ≥ 150° (chart, largest |κ| at their corners, longest edge over the
/// diagonal). `NTORI_WHERE=1`.
pub fn report_bad(s: &Surface, q: &embedding::remesh::QualityMesh) {
    let diagonal = embedding::fit::diagonal(&q.positions);
    // Directed edge → its triangle, to find each edge's other side.
    let owner: std::collections::HashMap<(u32, u32), usize> = q
        .triangles
        .iter()
        .enumerate()
        .flat_map(|(t, tri)| (0..3).map(move |k| ((tri[k], tri[(k + 1) % 3]), t)))
        .collect();
    for (t, tri) in q.triangles.iter().enumerate() {
        let p = tri.map(|i| q.positions[i as usize]);
        let angle = |a: Point3, b: Point3, c: Point3| (b - a).angle(&(c - a)).to_degrees();
        let big = angle(p[0], p[1], p[2])
            .max(angle(p[1], p[2], p[0]))
            .max(angle(p[2], p[0], p[1]));
        for k in 0..3 {
            let (a, b) = (tri[k], tri[(k + 1) % 3]);
            if let Some(&u) = owner.get(&(b, a)) {
                let other = &q.triangles[u];
                let n = |t: &[u32; 3]| {
                    let p = t.map(|i| q.positions[i as usize]);
                    (p[1] - p[0]).cross(&(p[2] - p[0])).normalize()
                };
                let bend = n(tri).angle(&n(other)).to_degrees();
                if bend > 20.0 && u > t {
                    let (k1, k2) = s.eval(q.vertices[a as usize]).principal_curvatures();
                    println!(
                        "  bend {bend:.1}° |κ| {:.1} edge {:.2e} at {:?}",
                        k1.abs().max(k2.abs()),
                        (q.positions[a as usize] - q.positions[b as usize]).norm() / diagonal,
                        q.positions[a as usize]
                    );
                }
            }
        }
        if big >= 150.0 {
            let kappa = tri
                .iter()
                .map(|&i| {
                    let (k1, k2) = s.eval(q.vertices[i as usize]).principal_curvatures();
                    k1.abs().max(k2.abs())
                })
                .fold(0.0, f64::max);
            let longest = (0..3)
                .map(|k| (p[k] - p[(k + 1) % 3]).norm())
                .fold(0.0, f64::max)
                / diagonal;
            println!(
                "  {big:.1}° chart {} |κ| {kappa:.1} longest {longest:.2e} at {:?}",
                q.triangle_charts[t].0, p[0]
            );
        }
    }
}

/// Quad count, corner angles (smallest, largest, share within 45°–135°) and the largest bend
/// between a quad's two halves.
fn report_quads(genus: u32, seconds: f64, q: &embedding::remesh::QualityMesh) {
    let faces = q.quad_faces();
    let (mut least, mut most, mut fine) = (f64::INFINITY, 0.0f64, 0usize);
    for f in &faces {
        let p = f.map(|i| q.positions[i as usize]);
        let angles: Vec<f64> = (0..4)
            .map(|k| {
                (p[(k + 3) % 4] - p[k])
                    .angle(&(p[(k + 1) % 4] - p[k]))
                    .to_degrees()
            })
            .collect();
        let (lo, hi) = angles
            .iter()
            .fold((f64::INFINITY, 0.0f64), |(l, h), &a| (l.min(a), h.max(a)));
        least = least.min(lo);
        most = most.max(hi);
        if lo >= 45.0 && hi <= 135.0 {
            fine += 1;
        }
    }
    println!(
        "genus {genus}: {} quads in {seconds:.2} s, corner angles {least:.1}°–{most:.1}°, {:.2}% within 45°–135°",
        faces.len(),
        100.0 * fine as f64 / faces.len() as f64
    );
}
