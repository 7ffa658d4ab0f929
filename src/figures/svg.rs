//! A small SVG writer for the figures: a white page whose `viewBox` is its size in pixels, so a
//! `font-size` is the size the text is drawn at; panels map model or chart coordinates to pixels.
//! Numbers are written with fixed precision, so the same figure always gives the same bytes.

use std::fmt::Write as _;

use num_complex::Complex64;

/// The smallest font size any figure uses, in pixels at the drawn size.
pub const MIN_FONT: f64 = 13.0;
/// Labels of points and lengths.
pub const LABEL_FONT: f64 = 20.0;
/// Panel headings.
pub const HEADING_FONT: f64 = 17.0;

const SANS: &str = "DejaVu Sans, Helvetica, Arial, sans-serif";
const SERIF: &str = "DejaVu Serif, Times New Roman, serif";

/// A document being written.
pub struct Doc {
    width: u32,
    height: u32,
    body: String,
    defs: String,
}

/// Where a text's anchor point lies on it.
#[derive(Clone, Copy, Debug)]
pub enum Anchor {
    Start,
    Middle,
}

impl Anchor {
    fn name(self) -> &'static str {
        match self {
            Anchor::Start => "start",
            Anchor::Middle => "middle",
        }
    }
}

/// Maps the plane onto pixels: 0 goes to `origin`, `scale` pixels per unit, y up.
#[derive(Clone, Copy, Debug)]
pub struct Frame {
    pub origin: Complex64,
    pub scale: f64,
}

impl Frame {
    pub fn new(origin: (f64, f64), scale: f64) -> Frame {
        Frame {
            origin: Complex64::new(origin.0, origin.1),
            scale,
        }
    }
    /// The pixel position of z (as a complex number x + iy, y pointing down).
    pub fn px(&self, z: Complex64) -> Complex64 {
        let d = z * self.scale;
        Complex64::new(self.origin.re + d.re, self.origin.im - d.im)
    }
}

/// Text content: plain characters and subscripts (kept as separate runs, so that the text of the
/// element reads e.g. "a1⁻¹" while the 1 is drawn lowered and smaller).
#[derive(Clone, Debug, Default)]
pub struct Label {
    runs: Vec<(String, bool)>,
}

impl Label {
    pub fn plain(s: &str) -> Label {
        Label {
            runs: vec![(s.to_owned(), false)],
        }
    }
    pub fn then(mut self, s: &str) -> Label {
        self.runs.push((s.to_owned(), false));
        self
    }
    pub fn sub(mut self, s: &str) -> Label {
        self.runs.push((s.to_owned(), true));
        self
    }
    /// This label followed by another.
    pub fn append(mut self, other: &Label) -> Label {
        self.runs.extend(other.runs.iter().cloned());
        self
    }
    /// The label as the text an SVG reader sees.
    pub fn text(&self) -> String {
        self.runs.iter().map(|(s, _)| s.as_str()).collect()
    }
    fn markup(&self, size: f64) -> String {
        let mut out = String::new();
        let mut lowered = false;
        let shift = 0.28 * size;
        for (s, sub) in &self.runs {
            let dy = match (lowered, *sub) {
                (false, true) => format!(" dy=\"{shift:.1}\""),
                (true, false) => format!(" dy=\"{:.1}\"", -shift),
                _ => String::new(),
            };
            if *sub {
                let small = (0.72 * size).max(MIN_FONT);
                let _ = write!(
                    out,
                    "<tspan{dy} font-size=\"{small:.0}\">{}</tspan>",
                    escape(s)
                );
            } else if dy.is_empty() {
                out.push_str(&escape(s));
            } else {
                let _ = write!(out, "<tspan{dy}>{}</tspan>", escape(s));
            }
            lowered = *sub;
        }
        out
    }
}

/// The label of polygon edge e = 4k + t: a_k, b_k, a_k⁻¹, b_k⁻¹ (handles counted from 1).
pub fn edge_label(e: usize) -> Label {
    let (k, t) = (e / 4, e % 4);
    let letter = if t % 2 == 0 { "a" } else { "b" };
    let label = Label::plain(letter).sub(&(k + 1).to_string());
    if t >= 2 { label.then("⁻¹") } else { label }
}

/// Text style: sans-serif upright, or serif italic for mathematical symbols.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Font {
    Sans,
    SansBold,
    Math,
}

pub fn escape(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// A pixel coordinate pair, fixed precision.
pub fn xy(p: Complex64) -> String {
    format!("{:.2} {:.2}", p.re, p.im)
}

impl Doc {
    /// A `width` × `height` pixel page with a white background (the title comes with [`Doc::finish`]).
    pub fn new(width: u32, height: u32) -> Doc {
        Doc {
            width,
            height,
            body: String::new(),
            defs: String::new(),
        }
    }

    /// A clip path with this id, from SVG path data in pixels.
    pub fn clip(&mut self, id: &str, path: &str) {
        let _ = writeln!(
            self.defs,
            "<clipPath id=\"{id}\"><path d=\"{path}\"/></clipPath>"
        );
    }

    /// Opens a group (`attrs` as written, e.g. `clip-path="url(#x)"`); close it with [`Doc::end`].
    pub fn group(&mut self, attrs: &str) {
        let _ = writeln!(self.body, "<g {attrs}>");
    }
    pub fn end(&mut self) {
        self.body.push_str("</g>\n");
    }

    pub fn path(&mut self, d: &str, attrs: &str) {
        let _ = writeln!(self.body, "<path d=\"{d}\" {attrs}/>");
    }

    /// An open polyline through pixel points.
    pub fn polyline(&mut self, pts: &[Complex64], attrs: &str) {
        if pts.len() < 2 {
            return;
        }
        self.path(&polyline_data(pts, false), attrs);
    }

    pub fn line(&mut self, a: Complex64, b: Complex64, attrs: &str) {
        let _ = writeln!(
            self.body,
            "<line x1=\"{:.2}\" y1=\"{:.2}\" x2=\"{:.2}\" y2=\"{:.2}\" {attrs}/>",
            a.re, a.im, b.re, b.im
        );
    }

    pub fn circle(&mut self, c: Complex64, r: f64, attrs: &str) {
        let _ = writeln!(
            self.body,
            "<circle cx=\"{:.2}\" cy=\"{:.2}\" r=\"{r:.2}\" {attrs}/>",
            c.re, c.im
        );
    }

    pub fn rect(&mut self, x: f64, y: f64, w: f64, h: f64, attrs: &str) {
        let _ = writeln!(
            self.body,
            "<rect x=\"{x:.2}\" y=\"{y:.2}\" width=\"{w:.2}\" height=\"{h:.2}\" {attrs}/>"
        );
    }

    /// A filled arrowhead at `tip` pointing along `dir` (pixel direction), `size` pixels long.
    pub fn arrowhead(&mut self, tip: Complex64, dir: Complex64, size: f64, colour: &str) {
        let u = dir / dir.norm();
        let n = Complex64::new(-u.im, u.re);
        let back = tip - u * size;
        let (l, r) = (back + n * (0.45 * size), back - n * (0.45 * size));
        let _ = writeln!(
            self.body,
            "<path d=\"M{} L{} L{} Z\" fill=\"{colour}\"/>",
            xy(tip),
            xy(l),
            xy(r)
        );
    }

    /// Text at pixel position `at` (the baseline's anchor point), at least [`MIN_FONT`] in size.
    /// A white halo keeps it readable over lines.
    pub fn text(
        &mut self,
        at: Complex64,
        size: f64,
        anchor: Anchor,
        font: Font,
        colour: &str,
        label: &Label,
    ) {
        let size = size.max(MIN_FONT);
        let (family, extra) = match font {
            Font::Sans => (SANS, ""),
            Font::SansBold => (SANS, " font-weight=\"bold\""),
            Font::Math => (SERIF, " font-style=\"italic\""),
        };
        let _ = writeln!(
            self.body,
            "<text x=\"{:.2}\" y=\"{:.2}\" font-family=\"{family}\" font-size=\"{size:.0}\"{extra} \
             text-anchor=\"{}\" fill=\"{colour}\" stroke=\"#ffffff\" stroke-width=\"3\" \
             stroke-linejoin=\"round\" paint-order=\"stroke\">{}</text>",
            at.re,
            at.im,
            anchor.name(),
            label.markup(size)
        );
    }

    /// Text centred on `at` (vertically too, roughly: the baseline sits 0.35 em below).
    pub fn text_centred(
        &mut self,
        at: Complex64,
        size: f64,
        font: Font,
        colour: &str,
        label: &Label,
    ) {
        let size = size.max(MIN_FONT);
        self.text(
            at + Complex64::new(0.0, 0.35 * size),
            size,
            Anchor::Middle,
            font,
            colour,
            label,
        );
    }

    /// The finished document.
    pub fn finish(self, title: &str) -> String {
        let mut s = String::new();
        let _ = writeln!(
            s,
            "<svg xmlns=\"http://www.w3.org/2000/svg\" version=\"1.1\" width=\"{w}\" height=\"{h}\" \
             viewBox=\"0 0 {w} {h}\">",
            w = self.width,
            h = self.height
        );
        let _ = writeln!(s, "<title>{}</title>", escape(title));
        if !self.defs.is_empty() {
            let _ = write!(s, "<defs>\n{}</defs>\n", self.defs);
        }
        let _ = writeln!(
            s,
            "<rect x=\"0\" y=\"0\" width=\"{}\" height=\"{}\" fill=\"#ffffff\"/>",
            self.width, self.height
        );
        s.push_str(&self.body);
        s.push_str("</svg>\n");
        s
    }
}

/// Path data through pixel points, closed or open.
pub fn polyline_data(pts: &[Complex64], closed: bool) -> String {
    let mut d = String::with_capacity(pts.len() * 16);
    for (i, p) in pts.iter().enumerate() {
        let _ = write!(d, "{}{}", if i == 0 { "M" } else { " L" }, xy(*p));
    }
    if closed {
        d.push_str(" Z");
    }
    d
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn labels_read_as_plain_text() {
        assert_eq!(edge_label(0).text(), "a1");
        assert_eq!(edge_label(7).text(), "b2⁻¹");
        assert_eq!(edge_label(10).text(), "a3⁻¹");
        let m = edge_label(2).markup(20.0);
        assert!(m.starts_with('a') && m.contains("font-size=\"14\"") && m.ends_with("⁻¹</tspan>"));
    }
}
