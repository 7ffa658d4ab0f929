//! How a fitted model rounds its input mesh's sharp edges: the largest |κ| at the t = 48
//! tessellation's vertices in bands of distance (0.25% of the diagonal each) from the sharp edges
//! (`quality::SharpEdges`), which `quality::CREASE_BAND` was chosen from.
//! `cargo run --release -p embedding --example crease_bands MODEL.json MESH.obj` (a triangle or
//! polygon OBJ; only its `v` and `f` lines are read).
use embedding::quality::{SharpEdges, sample_points};
use embedding::{Point3, Surface};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let model: embedding::model::Model =
        serde_json::from_str(&std::fs::read_to_string(&args[1]).expect("a readable model"))
            .expect("a model");
    let surface = Surface::from_model(&model).expect("a surface");
    let text = std::fs::read_to_string(&args[2]).expect("a readable OBJ");
    let mut positions = Vec::new();
    let mut triangles = Vec::new();
    for line in text.lines() {
        let mut w = line.split_whitespace();
        match w.next() {
            Some("v") => {
                let c: Vec<f64> = w
                    .take(3)
                    .map(|x| x.parse().expect("a coordinate"))
                    .collect();
                positions.push(Point3::new(c[0], c[1], c[2]));
            }
            Some("f") => {
                let v: Vec<u32> = w
                    .map(|x| {
                        x.split('/')
                            .next()
                            .unwrap_or(x)
                            .parse::<u32>()
                            .expect("a vertex index")
                            - 1
                    })
                    .collect();
                for k in 1..v.len() - 1 {
                    triangles.push([v[0], v[k], v[k + 1]]);
                }
            }
            _ => {}
        }
    }
    let sharp = SharpEdges::of(&positions, &triangles);
    let diag = embedding::fit::diagonal(&positions);
    println!("{} sharp edges, diagonal {diag:.3}", sharp.len());
    let points = sample_points(&surface, 48).expect("a tessellation");
    let mut bins = [0.0f64; 20];
    for p in &points {
        let jet = surface.eval(*p);
        let (k1, k2) = jet.principal_curvatures();
        let k = k1.abs().max(k2.abs());
        let d = sharp.distance(jet.pos) / diag;
        let bin = ((d / 0.0025) as usize).min(19);
        bins[bin] = bins[bin].max(k);
    }
    for (i, k) in bins.iter().enumerate() {
        println!("{:.2}%..: {k:.2}", i as f64 * 0.25);
    }
}
