//! Stanford PLY (ASCII, binary little or big endian) through ply-rs-bw's parser: the `vertex`
//! element's `x y z` (any numeric type) and the `face` element's `vertex_indices` (or
//! `vertex_index`) lists; everything else is ignored. Elements are read into a small record, not
//! ply-rs-bw's hash maps, so a large file takes little more memory than its numbers.

use embedding::Point3;
use ply_rs_bw::ply::{Property, PropertyAccess, PropertyAccessResult};

use super::{ImportError, Location, MeshFormat, RawMesh};

const FORMAT: MeshFormat = MeshFormat::Ply;

/// One element of any kind: a vertex's coordinates (and which were set), a face's corners.
#[derive(Clone, Debug, Default)]
struct Record {
    xyz: [f64; 3],
    set: [bool; 3],
    corners: Vec<i64>,
    has_corners: bool,
}

fn scalar(p: &Property) -> Option<f64> {
    Some(match *p {
        Property::Char(x) => f64::from(x),
        Property::UChar(x) => f64::from(x),
        Property::Short(x) => f64::from(x),
        Property::UShort(x) => f64::from(x),
        Property::Int(x) => f64::from(x),
        Property::UInt(x) => f64::from(x),
        Property::Float(x) => f64::from(x),
        Property::Double(x) => x,
        _ => return None,
    })
}

fn list(p: Property) -> Option<Vec<i64>> {
    Some(match p {
        Property::ListChar(v) => v.into_iter().map(i64::from).collect(),
        Property::ListUChar(v) => v.into_iter().map(i64::from).collect(),
        Property::ListShort(v) => v.into_iter().map(i64::from).collect(),
        Property::ListUShort(v) => v.into_iter().map(i64::from).collect(),
        Property::ListInt(v) => v.into_iter().map(i64::from).collect(),
        Property::ListUInt(v) => v.into_iter().map(i64::from).collect(),
        _ => return None,
    })
}

impl PropertyAccess for Record {
    fn new() -> Self {
        Record::default()
    }
    fn set_property(&mut self, name: &str, property: Property) -> PropertyAccessResult {
        let axis = match name {
            "x" => Some(0),
            "y" => Some(1),
            "z" => Some(2),
            _ => None,
        };
        if let Some(k) = axis {
            return match scalar(&property) {
                Some(x) => {
                    self.xyz[k] = x;
                    self.set[k] = true;
                    PropertyAccessResult::Set
                }
                None => PropertyAccessResult::UnsupportedType,
            };
        }
        if name == "vertex_indices" || name == "vertex_index" {
            return match list(property) {
                Some(v) => {
                    self.corners = v;
                    self.has_corners = true;
                    PropertyAccessResult::Set
                }
                None => PropertyAccessResult::UnsupportedType,
            };
        }
        PropertyAccessResult::Ignored
    }
}

fn parse_error(message: String) -> ImportError {
    ImportError::Parse {
        format: FORMAT,
        at: Location::Unknown,
        message,
    }
}

/// ply-rs-bw's error as one line: its messages run over several (`Line 4: Couldn't parse line.`,
/// then a tab-indented `String: '…'` with the line read and an `Error: …` with the grammar's
/// debug output); this keeps the line number as the location, the first sentence, and the text
/// that was read (quoted short), and drops the rest.
fn library_error(e: &ply_rs_bw::parser::ParseError) -> ImportError {
    let text = e.to_string();
    let (line, rest) = match e.line() {
        Some(n) => (
            Location::Line(n),
            text.strip_prefix(&format!("Line {n}: ")).unwrap_or(&text),
        ),
        None => (Location::Unknown, text.as_str()),
    };
    let first = rest
        .lines()
        .next()
        .unwrap_or("")
        .trim()
        .trim_end_matches('.');
    let mut message: String = first.chars().take(1).flat_map(char::to_lowercase).collect();
    message.extend(first.chars().skip(1));
    let read = rest
        .split_once("\tString: ")
        .map(|(_, r)| r.split("\n\tError").next().unwrap_or(""))
        .map(|r| r.trim().trim_matches('\'').trim())
        .filter(|r| !r.is_empty());
    if let Some(read) = read {
        message.push_str(&format!(": `{}`", super::obj::quote(read)));
    }
    // Whatever else the library says (kinds of error not seen yet) stays on one line.
    let message = message.replace(|c: char| c.is_control(), " ");
    ImportError::Parse {
        format: FORMAT,
        at: line,
        message: if message.is_empty() {
            "unreadable".into()
        } else {
            message
        },
    }
}

pub(crate) fn read(bytes: &[u8]) -> Result<RawMesh, ImportError> {
    use ply_rs_bw::parser::Parser;
    let parser = Parser::<Record>::new();
    // The header first: counts no file could hold are refused before anything is read for them.
    let header = parser
        .read_ply_header(&mut std::io::Cursor::new(bytes))
        .map_err(|e| library_error(&e))?;
    let end = find(bytes, b"end_header").map_or(bytes.len(), |at| at + 10);
    let body = bytes.len() - end;
    let mut total = 0usize;
    for element in header.elements.values() {
        if element.count > 0 && element.properties.is_empty() {
            return Err(parse_error(format!(
                "the element `{}` has no properties",
                super::obj::quote(&element.name)
            )));
        }
        total = total.saturating_add(element.count);
    }
    // Every element with a property takes at least one byte (binary) or two (text).
    if total > body {
        return Err(ImportError::Parse {
            format: FORMAT,
            at: Location::Byte(end),
            message: format!(
                "the header declares {total} elements, but only {body} bytes follow it"
            ),
        });
    }
    let ply = parser
        .read_ply(&mut std::io::Cursor::new(bytes))
        .map_err(|e| library_error(&e))?;
    let mut raw = RawMesh::default();
    let vertices = ply.payload.get("vertex").map_or(&[][..], |v| &v[..]);
    if vertices.len() >= u32::MAX as usize {
        return Err(parse_error(format!(
            "{} vertices is too many",
            vertices.len()
        )));
    }
    for (v, r) in vertices.iter().enumerate() {
        if let Some(k) = (0..3).find(|&k| !r.set[k]) {
            return Err(parse_error(format!(
                "vertex {v} has no {} coordinate",
                ["x", "y", "z"][k]
            )));
        }
        let [x, y, z] = r.xyz;
        if !r.xyz.iter().all(|c| c.is_finite()) {
            return Err(ImportError::NonFinite {
                vertex: v,
                at: Location::Unknown,
                x,
                y,
                z,
            });
        }
        raw.positions.push(Point3::new(x, y, z));
    }
    let n = raw.positions.len();
    let faces = ply.payload.get("face").map_or(&[][..], |f| &f[..]);
    let mut corners = Vec::new();
    for (f, r) in faces.iter().enumerate() {
        if !r.has_corners {
            return Err(parse_error(format!(
                "face {f} has no vertex_indices (or vertex_index) list"
            )));
        }
        if r.corners.len() < 3 {
            return Err(parse_error(format!(
                "face {f} has {} corners",
                r.corners.len()
            )));
        }
        corners.clear();
        for &i in &r.corners {
            if i < 0 || i as usize >= n {
                return Err(ImportError::IndexOutOfRange {
                    face: f,
                    at: Location::Unknown,
                    index: i,
                    vertex_count: n,
                });
            }
            corners.push(i as u32);
        }
        raw.push_polygon(&corners)?;
    }
    Ok(raw)
}

fn find(haystack: &[u8], needle: &[u8]) -> Option<usize> {
    haystack.windows(needle.len()).position(|w| w == needle)
}
