//! STL, binary or ASCII, read by hand. A file is binary when its size is exactly 84 + 50 × the
//! triangle count in bytes 80..84 (some binary files begin with `solid` too); otherwise one that
//! begins with `solid` and has no NUL byte in its first 84 bytes is read as text, line by line
//! (`facet normal`, `outer loop`, three or more `vertex x y z`, `endloop`, `endfacet`; several
//! solids allowed; the normals are ignored). STL stores every triangle's corners apart, so exactly
//! coincident corners are merged into one vertex.

use embedding::Point3;

use super::obj::quote;
use super::{ImportError, Location, MeshFormat, RawMesh, text_lines, text_vertex};

const FORMAT: MeshFormat = MeshFormat::Stl;

pub(crate) fn read(bytes: &[u8]) -> Result<RawMesh, ImportError> {
    if bytes.len() >= 84 {
        let count = u32::from_le_bytes([bytes[80], bytes[81], bytes[82], bytes[83]]) as usize;
        if count.checked_mul(50).and_then(|b| b.checked_add(84)) == Some(bytes.len()) {
            return binary(bytes, count);
        }
    }
    // Many binary files begin with `solid` too; a NUL byte in the header or the count (which text
    // never has) tells them apart when the size does not, as in a binary file cut short.
    let text = bytes.trim_ascii_start();
    let binary_header = bytes.len() >= 84 && bytes[..84].contains(&0);
    if text.len() >= 5 && text[..5].eq_ignore_ascii_case(b"solid") && !binary_header {
        return ascii(bytes);
    }
    if bytes.len() >= 84 {
        let count = u32::from_le_bytes([bytes[80], bytes[81], bytes[82], bytes[83]]) as usize;
        // Binary with bytes after the triangles (some writers pad).
        if count
            .checked_mul(50)
            .and_then(|b| b.checked_add(84))
            .is_some_and(|b| b < bytes.len())
        {
            return binary(bytes, count);
        }
    }
    if bytes.len() < 84 {
        return Err(ImportError::Parse {
            format: FORMAT,
            at: Location::Unknown,
            message: format!(
                "{} bytes is too short for binary STL (84 bytes or more), and text STL begins with `solid`",
                bytes.len()
            ),
        });
    }
    let count = u32::from_le_bytes([bytes[80], bytes[81], bytes[82], bytes[83]]) as u64;
    Err(ImportError::Parse {
        format: FORMAT,
        at: Location::Byte(80),
        message: format!(
            "binary STL of {count} triangles has {} bytes, but the file has {}",
            84 + 50 * count,
            bytes.len()
        ),
    })
}

fn binary(bytes: &[u8], count: usize) -> Result<RawMesh, ImportError> {
    if count > super::MAX_TRIANGLES {
        return Err(ImportError::TooManyTriangles {
            at: Location::Byte(80),
            max: super::MAX_TRIANGLES,
        });
    }
    let mut raw = RawMesh {
        positions: Vec::with_capacity(3 * count),
        merge: true,
        ..RawMesh::default()
    };
    let float = |at: usize| {
        f64::from(f32::from_le_bytes([
            bytes[at],
            bytes[at + 1],
            bytes[at + 2],
            bytes[at + 3],
        ]))
    };
    for t in 0..count {
        let record = 84 + 50 * t;
        for k in 0..3 {
            let at = record + 12 + 12 * k;
            let [x, y, z] = [float(at), float(at + 4), float(at + 8)];
            if !(x.is_finite() && y.is_finite() && z.is_finite()) {
                return Err(ImportError::NonFinite {
                    vertex: raw.positions.len(),
                    at: Location::Byte(at),
                    x,
                    y,
                    z,
                });
            }
            raw.positions.push(Point3::new(x, y, z));
        }
        let v = (3 * t) as u32;
        raw.push_polygon(&[v, v + 1, v + 2])?;
    }
    Ok(raw)
}

fn ascii(bytes: &[u8]) -> Result<RawMesh, ImportError> {
    let error = |line: usize, message: String| ImportError::Parse {
        format: FORMAT,
        at: Location::Line(line),
        message,
    };
    let mut raw = RawMesh {
        merge: true,
        ..RawMesh::default()
    };
    let mut facet: Option<Vec<u32>> = None;
    let mut in_solid = false;
    for (number, line) in text_lines(bytes) {
        let mut tokens = line.split_whitespace();
        let Some(keyword) = tokens.next() else {
            continue;
        };
        match keyword.to_ascii_lowercase().as_str() {
            "solid" if !in_solid && facet.is_none() => in_solid = true,
            "endsolid" if in_solid && facet.is_none() => in_solid = false,
            "facet" if in_solid && facet.is_none() => facet = Some(Vec::with_capacity(3)),
            "outer" | "endloop" if facet.is_some() => {}
            "vertex" if facet.is_some() => {
                let p = text_vertex(&mut tokens, FORMAT, number, "a vertex", raw.positions.len())?;
                if raw.positions.len() >= u32::MAX as usize {
                    return Err(error(number, "too many vertices".into()));
                }
                if let Some(corners) = facet.as_mut() {
                    corners.push(raw.positions.len() as u32);
                }
                raw.positions.push(p);
            }
            "endfacet" if facet.is_some() => {
                let corners = facet.take().unwrap_or_default();
                if corners.len() < 3 {
                    return Err(error(
                        number,
                        format!("a facet needs three vertices, found {}", corners.len()),
                    ));
                }
                raw.push_polygon(&corners)?;
            }
            _ => {
                let expected = match (in_solid, facet.is_some()) {
                    (false, _) => "`solid`",
                    (true, false) => "`facet` or `endsolid`",
                    (true, true) => "`outer loop`, `vertex`, `endloop` or `endfacet`",
                };
                return Err(error(
                    number,
                    format!("expected {expected}, found `{}`", quote(keyword)),
                ));
            }
        }
    }
    if facet.is_some() {
        return Err(ImportError::Parse {
            format: FORMAT,
            at: Location::Unknown,
            message: "the file ends inside a facet".into(),
        });
    }
    Ok(raw)
}
