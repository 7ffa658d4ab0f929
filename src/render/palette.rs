//! One colour per chart kind and per edge pair, used by every figure, by `ntori tessellate --svg` and
//! by the renderer's charts style: a light tint to fill regions with, a dark shade of the same hue for
//! lines and labels, and a middle tone for lit 3D surfaces.
//!
//! Edge chart j = 2k + t (the pair a_k/a_k⁻¹ for t = 0, b_k/b_k⁻¹ for t = 1) gets the hue
//! 200° + 137.5°·j (the golden angle, so neighbouring pairs differ clearly); the inside chart is
//! orange and the vertex chart grey, neither of which the first four pairs come near.

use charts::ChartKind;

/// The fill tint of a chart kind.
pub fn fill(kind: ChartKind) -> String {
    match kind {
        ChartKind::Inside | ChartKind::Cap { north: true } => "#f6c28b".into(),
        ChartKind::Cap { north: false } => "#8fb8de".into(),
        ChartKind::Vertex => "#d2d2d2".into(),
        ChartKind::Edge { handle, side } => {
            format!("hsl({:.0},55%,72%)", edge_hue(2 * handle + side))
        }
    }
}

/// The dark shade of a chart kind, for lines, arrows and labels.
pub fn stroke(kind: ChartKind) -> String {
    match kind {
        ChartKind::Inside | ChartKind::Cap { north: true } => "#b8640f".into(),
        ChartKind::Cap { north: false } => "#2f6ea8".into(),
        ChartKind::Vertex => "#555555".into(),
        ChartKind::Edge { handle, side } => {
            format!("hsl({:.0},65%,36%)", edge_hue(2 * handle + side))
        }
    }
}

/// The kind of the edge chart that covers polygon edge e (edge 4k + t belongs to pair 2k + t mod 2).
pub fn edge_kind(e: usize) -> ChartKind {
    ChartKind::Edge {
        handle: (e / 4) as u32,
        side: (e % 2) as u32,
    }
}

/// The hue of edge chart j, in degrees.
fn edge_hue(j: u32) -> f64 {
    (f64::from(j) * 137.508 + 200.0) % 360.0
}

/// The same colour as an RGB triple in 0..=1 (for curves drawn by the renderer).
pub fn stroke_rgb(kind: ChartKind) -> [f32; 3] {
    match kind {
        ChartKind::Inside | ChartKind::Cap { north: true } => hex(0xb8640f),
        ChartKind::Cap { north: false } => hex(0x2f6ea8),
        ChartKind::Vertex => hex(0x555555),
        ChartKind::Edge { handle, side } => hsl(edge_hue(2 * handle + side), 0.65, 0.36),
    }
}

/// A middle tone of the same hue, for lit 3D surfaces (the tints wash out under lighting).
pub fn surface_rgb(kind: ChartKind) -> [f32; 3] {
    match kind {
        ChartKind::Inside | ChartKind::Cap { north: true } => hex(0xe8964a),
        ChartKind::Cap { north: false } => hex(0x5a8fc4),
        ChartKind::Vertex => hex(0x9a9a9a),
        ChartKind::Edge { handle, side } => hsl(edge_hue(2 * handle + side), 0.55, 0.55),
    }
}

/// The fill tint as an RGB triple in 0..=1 (for surfaces coloured by chart).
pub fn fill_rgb(kind: ChartKind) -> [f32; 3] {
    match kind {
        ChartKind::Inside | ChartKind::Cap { north: true } => hex(0xf6c28b),
        ChartKind::Cap { north: false } => hex(0x8fb8de),
        ChartKind::Vertex => hex(0xd2d2d2),
        ChartKind::Edge { handle, side } => hsl(edge_hue(2 * handle + side), 0.55, 0.72),
    }
}

fn hex(c: u32) -> [f32; 3] {
    [(c >> 16) & 255, (c >> 8) & 255, c & 255].map(|v| v as f32 / 255.0)
}

/// CSS's HSL to RGB.
fn hsl(h: f64, s: f64, l: f64) -> [f32; 3] {
    let a = s * l.min(1.0 - l);
    let f = |n: f64| {
        let k = (n + h / 30.0) % 12.0;
        (l - a * (k - 3.0).min(9.0 - k).clamp(-1.0, 1.0)) as f32
    };
    [f(0.0), f(8.0), f(4.0)]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hsl_matches_css() {
        // hsl(0, 100%, 50%) is red, hsl(120, 100%, 25%) is #008000.
        assert_eq!(hsl(0.0, 1.0, 0.5), [1.0, 0.0, 0.0]);
        let g = hsl(120.0, 1.0, 0.25);
        assert!(g[0].abs() < 1e-6 && (g[1] - 0.5).abs() < 1e-6 && g[2].abs() < 1e-6);
    }
}
