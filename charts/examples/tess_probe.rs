use charts::Atlas;
fn main() {
    let mut bad = vec![];
    for g in 0..=charts::MAX_GENUS {
        let atlas = Atlas::new(g).unwrap();
        for (te, tr) in [(1, 1), (4, 4), (16, 3)] {
            if let Err(e) = atlas.tessellate(te, tr) { bad.push((g, te, tr, e.to_string())); }
        }
    }
    println!("{} failures", bad.len());
    for b in bad { println!("{b:?}"); }
}
