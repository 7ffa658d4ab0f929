//! Wavefront OBJ, read by hand: `v x y z` (further numbers, a weight or a colour, ignored) and
//! `f` with corners `v`, `v/vt`, `v//vn` or `v/vt/vn`; indices count from 1, negative ones back
//! from the last vertex read so far. Lines ending in `\` continue on the next. Every other statement
//! (`vt`, `vn`, `o`, `g`, `s`, `usemtl`, `mtllib`, `l`, `p`, …) is ignored. Coordinates are read
//! as f64 (tobj reads f32 and says no line), and errors give the line.

use super::{ImportError, Location, MeshFormat, RawMesh, text_lines, text_vertex};

const FORMAT: MeshFormat = MeshFormat::Obj;

fn parse_error(line: usize, message: String) -> ImportError {
    ImportError::Parse {
        format: FORMAT,
        at: Location::Line(line),
        message,
    }
}

pub(crate) fn read(bytes: &[u8]) -> Result<RawMesh, ImportError> {
    let mut raw = RawMesh::default();
    // Faces as the file numbers them (resolved to 0-based where relative), with their lines: a face
    // may come before the vertices it names, so ranges are checked at the end.
    let mut face_lines: Vec<usize> = Vec::new();
    let mut written: Vec<i64> = Vec::new();
    let mut corners: Vec<u32> = Vec::new();
    let mut pending = String::new();
    let mut pending_line = 0;
    for (number, line) in text_lines(bytes) {
        if pending.is_empty() {
            pending_line = number;
        }
        if let Some(head) = line.strip_suffix('\\') {
            pending.push_str(head);
            pending.push(' ');
            continue;
        }
        pending.push_str(&line);
        let statement = std::mem::take(&mut pending);
        let number = pending_line;
        let content = statement.split('#').next().unwrap_or("");
        let mut tokens = content.split_whitespace();
        match tokens.next() {
            Some("v") => {
                let p = text_vertex(&mut tokens, FORMAT, number, "a vertex", raw.positions.len())?;
                if raw.positions.len() >= u32::MAX as usize {
                    return Err(parse_error(number, "too many vertices".into()));
                }
                raw.positions.push(p);
            }
            Some("f") | Some("fo") => {
                corners.clear();
                let start = written.len();
                for token in tokens {
                    let index = token.split('/').next().unwrap_or("");
                    let index: i64 = index.parse().map_err(|_| {
                        parse_error(number, format!("`{}` is not a vertex index", quote(token)))
                    })?;
                    let resolved = match index {
                        0 => {
                            return Err(parse_error(
                                number,
                                "vertex index 0 (OBJ counts from 1)".into(),
                            ));
                        }
                        i if i > 0 => i - 1,
                        i => raw.positions.len() as i64 + i,
                    };
                    written.push(index);
                    corners.push(u32::try_from(resolved).unwrap_or(u32::MAX));
                }
                if corners.len() < 3 {
                    return Err(parse_error(
                        number,
                        format!("a face needs three corners, found {}", corners.len()),
                    ));
                }
                // Negative indices reaching before the first vertex are out of range now.
                if let Some(k) = (0..corners.len())
                    .find(|&k| written[start + k] < 0 && corners[k] as usize >= raw.positions.len())
                {
                    return Err(ImportError::IndexOutOfRange {
                        face: face_lines.len(),
                        at: Location::Line(number),
                        index: written[start + k],
                        vertex_count: raw.positions.len(),
                    });
                }
                face_lines.push(number);
                raw.push_polygon(&corners)?;
            }
            _ => {}
        }
    }
    // Positive indices past the last vertex.
    let n = raw.positions.len();
    let mut start = 0;
    for (f, &s) in raw.sides.iter().enumerate() {
        let s = s as usize;
        if let Some(k) = (start..start + s).find(|&k| raw.corners[k] as usize >= n) {
            return Err(ImportError::IndexOutOfRange {
                face: f,
                at: Location::Line(face_lines[f]),
                index: written[k],
                vertex_count: n,
            });
        }
        start += s;
    }
    Ok(raw)
}

/// A token as a message quotes it: at most 40 characters.
pub(crate) fn quote(token: &str) -> String {
    match token.char_indices().nth(40) {
        Some((end, _)) => format!("{}…", &token[..end]),
        None => token.to_owned(),
    }
}
