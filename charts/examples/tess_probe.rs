use charts::Atlas;
use std::collections::HashMap;
fn main() {
    let atlas = Atlas::new(2).unwrap();
    let t = atlas.tessellate(1, 1).unwrap();
    let mut m: HashMap<(u32, u32), Vec<(usize, String)>> = HashMap::new();
    for (k, tri) in t.triangles.iter().enumerate() {
        for i in 0..3 {
            let (a, b) = (tri[i], tri[(i + 1) % 3]);
            m.entry((a.min(b), a.max(b))).or_default().push((
                k,
                format!("{:?}@{}", t.triangle_regions[k], t.triangle_charts[k].0),
            ));
        }
    }
    for (e, fs) in m.iter().filter(|(_, f)| f.len() > 2) {
        println!("{e:?}: {fs:?}");
    }
    for (i, v) in t.vertices.iter().enumerate() {
        println!("v{i}: {:?}", v);
    }
}
