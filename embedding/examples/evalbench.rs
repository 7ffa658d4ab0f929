use embedding::{Model, Surface};
use std::time::Instant;
fn main() {
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../assets/models/genus-10.json"
    ))
    .unwrap();
    let model: Model = serde_json::from_str(&text).unwrap();
    let s = Surface::from_model(&model).unwrap();
    let t = s.atlas().tessellate(32, 32).unwrap();
    for _ in 0..3 {
        let start = Instant::now();
        let mut acc = 0.0;
        for &p in &t.vertices {
            acc += s.eval(p).du.x;
        }
        let e = start.elapsed().as_secs_f64() / t.vertices.len() as f64;
        let start = Instant::now();
        for &p in &t.vertices {
            acc += s.position(p).x;
        }
        let q = start.elapsed().as_secs_f64() / t.vertices.len() as f64;
        let start = Instant::now();
        let layout = s.layout();
        let mut w = Vec::new();
        for &p in &t.vertices {
            w.clear();
            layout.weights(p, &mut w);
            acc += w[0].jet.val;
        }
        let r = start.elapsed().as_secs_f64() / t.vertices.len() as f64;
        let start = Instant::now();
        for &p in &t.vertices {
            acc += s.atlas().locate(p).unwrap().representations().len() as f64;
        }
        let l = start.elapsed().as_secs_f64() / t.vertices.len() as f64;
        println!(
            "eval {:.2} µs  position {:.2} µs  weights {:.2} µs  locate {:.2} µs ({acc:.1})",
            e * 1e6,
            q * 1e6,
            r * 1e6,
            l * 1e6
        );
    }
}
