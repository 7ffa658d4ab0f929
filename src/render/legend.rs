//! The curvature style's legend, drawn into the finished image on the CPU: a colour bar at the
//! right edge with its end values and zero, and the quantity's name. Text comes from egui's own
//! default font (Ubuntu Light), so pictures look the same on every machine.

use ab_glyph::{Font, FontRef, PxScale, ScaleFont};

use super::scene::diverging;
use super::{CurvatureKind, Image};

/// Draws the legend for values in [−range, range].
pub fn draw(image: &mut Image, kind: CurvatureKind, range: f64) {
    let (w, h) = (image.width as i64, image.height as i64);
    let bar_h = (h * 6 / 10).max(20);
    let bar_w = (w / 40).clamp(8, 28);
    let x0 = w - bar_w - (w / 8).clamp(40, 140);
    let y0 = (h - bar_h) / 2;
    for y in 0..bar_h {
        let t = 1.0 - 2.0 * y as f64 / (bar_h - 1).max(1) as f64;
        let c = diverging(t).map(|v| (v * 255.0).round() as u8);
        for x in 0..bar_w {
            put(image, x0 + x, y0 + y, [c[0], c[1], c[2]], 1.0);
        }
    }
    // A thin frame around the bar.
    for x in -1..=bar_w {
        put(image, x0 + x, y0 - 1, [40, 40, 40], 1.0);
        put(image, x0 + x, y0 + bar_h, [40, 40, 40], 1.0);
    }
    for y in -1..=bar_h {
        put(image, x0 - 1, y0 + y, [40, 40, 40], 1.0);
        put(image, x0 + bar_w, y0 + y, [40, 40, 40], 1.0);
    }
    let size = (h as f32 / 30.0).clamp(11.0, 28.0);
    let label_x = x0 + bar_w + 6;
    text(image, &format!("{range:+.3}"), label_x, y0, size);
    text(image, "0", label_x, y0 + bar_h / 2, size);
    text(image, &format!("{:+.3}", -range), label_x, y0 + bar_h, size);
    let title = match kind {
        CurvatureKind::Gaussian => "Gaussian curvature K",
        CurvatureKind::Mean => "mean curvature H",
    };
    let title_w = text_width(title, size);
    let tx = (x0 + bar_w / 2 - title_w / 2).min(w - title_w - 4).max(0);
    text(image, title, tx, y0 - (size as i64) - 4, size);
}

fn font() -> FontRef<'static> {
    FontRef::try_from_slice(epaint_default_fonts::UBUNTU_LIGHT).expect("egui's bundled font parses")
}

fn text_width(s: &str, size: f32) -> i64 {
    let font = font();
    let scaled = font.as_scaled(PxScale::from(size));
    s.chars()
        .map(|c| scaled.h_advance(font.glyph_id(c)))
        .sum::<f32>()
        .ceil() as i64
}

/// Dark text with its vertical centre at `y`.
fn text(image: &mut Image, s: &str, x: i64, y: i64, size: f32) {
    let font = font();
    let scale = PxScale::from(size);
    let scaled = font.as_scaled(scale);
    let baseline = y as f32 + (scaled.ascent() + scaled.descent()) / 2.0;
    let mut pen = x as f32;
    for c in s.chars() {
        let id = font.glyph_id(c);
        let glyph = id.with_scale_and_position(scale, ab_glyph::point(pen, baseline));
        pen += scaled.h_advance(id);
        if let Some(outline) = font.outline_glyph(glyph) {
            let bounds = outline.px_bounds();
            outline.draw(|gx, gy, coverage| {
                put(
                    image,
                    bounds.min.x as i64 + i64::from(gx),
                    bounds.min.y as i64 + i64::from(gy),
                    [20, 20, 20],
                    coverage,
                );
            });
        }
    }
}

/// Blends a colour into one pixel (ignored outside the image).
fn put(image: &mut Image, x: i64, y: i64, rgb: [u8; 3], alpha: f32) {
    if x < 0 || y < 0 || x >= i64::from(image.width) || y >= i64::from(image.height) {
        return;
    }
    let i = 4 * (y as usize * image.width as usize + x as usize);
    let a = alpha.clamp(0.0, 1.0);
    for (k, &c) in rgb.iter().enumerate() {
        let old = f32::from(image.rgba[i + k]);
        image.rgba[i + k] = (old + (f32::from(c) - old) * a).round() as u8;
    }
    image.rgba[i + 3] = 255;
}
