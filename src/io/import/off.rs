//! Object File Format, read by hand: an optional header (`OFF`, or with prefixes `ST`, `C`, `N`:
//! `COFF`, `NOFF`, `STCNOFF`…; the counts may follow on the same line), the counts `V F [E]`, V
//! vertex lines (the first three numbers; colours, normals and texture coordinates after them
//! ignored), F face lines `n i₁ … iₙ` (a colour after them ignored). `#` starts a comment; blank
//! lines are skipped. Four-dimensional (`4OFF`), `nOFF` and binary OFF are refused as unsupported.
//! Errors give the line.

use super::obj::quote;
use super::{ImportError, Location, MeshFormat, RawMesh, text_lines, text_vertex};

const FORMAT: MeshFormat = MeshFormat::Off;

fn parse_error(line: usize, message: String) -> ImportError {
    ImportError::Parse {
        format: FORMAT,
        at: Location::Line(line),
        message,
    }
}

pub(crate) fn read(bytes: &[u8]) -> Result<RawMesh, ImportError> {
    let mut lines = text_lines(bytes)
        .map(|(n, l)| {
            let content = l.split('#').next().unwrap_or("").trim().to_owned();
            (n, content)
        })
        .filter(|(_, l)| !l.is_empty());
    let Some((first_line, first)) = lines.next() else {
        return Err(ImportError::Empty {
            format: FORMAT,
            what: "vertices",
        });
    };
    let mut tokens: Vec<String> = first.split_whitespace().map(str::to_owned).collect();
    let mut counts_line = first_line;
    if let Some(keyword) = tokens.first().filter(|t| t.ends_with("OFF")) {
        let prefix = &keyword[..keyword.len() - 3];
        if prefix.contains('4') || prefix.contains('n') {
            return Err(ImportError::Unsupported {
                format: FORMAT,
                at: Location::Line(first_line),
                what: format!("`{}` (only three-dimensional OFF is read)", quote(keyword)),
            });
        }
        let known = ["ST", "C", "N"];
        let mut rest = prefix;
        for p in known {
            rest = rest.strip_prefix(p).unwrap_or(rest);
        }
        if !rest.is_empty() {
            return Err(parse_error(
                first_line,
                format!("unknown header `{}`", quote(keyword)),
            ));
        }
        if tokens
            .get(1)
            .is_some_and(|t| t.eq_ignore_ascii_case("BINARY"))
        {
            return Err(ImportError::Unsupported {
                format: FORMAT,
                at: Location::Line(first_line),
                what: "binary OFF".into(),
            });
        }
        tokens.remove(0);
        if tokens.is_empty() {
            let Some((n, l)) = lines.next() else {
                return Err(parse_error(first_line, "no counts after the header".into()));
            };
            counts_line = n;
            tokens = l.split_whitespace().map(str::to_owned).collect();
        }
    }
    let count = |k: usize, what: &str| -> Result<usize, ImportError> {
        let token = tokens.get(k).ok_or_else(|| {
            parse_error(
                counts_line,
                format!("expected the counts `V F E`, no {what} count"),
            )
        })?;
        token.parse::<usize>().map_err(|_| {
            parse_error(
                counts_line,
                format!("the {what} count `{}` is not a count", quote(token)),
            )
        })
    };
    let (vertices, faces) = (count(0, "vertex")?, count(1, "face")?);
    // Each vertex and face takes a line of at least two bytes: do not trust larger counts for memory.
    let cap = bytes.len() / 2;
    let mut raw = RawMesh {
        positions: Vec::with_capacity(vertices.min(cap)),
        ..RawMesh::default()
    };
    if vertices >= u32::MAX as usize {
        return Err(parse_error(
            counts_line,
            format!("{vertices} vertices is too many"),
        ));
    }
    let mut last_line = counts_line;
    for v in 0..vertices {
        let Some((n, l)) = lines.next() else {
            return Err(parse_error(
                last_line,
                format!("the file ends after {v} of its {vertices} vertices"),
            ));
        };
        last_line = n;
        let mut tokens = l.split_whitespace();
        let p = text_vertex(&mut tokens, FORMAT, n, &format!("vertex {v}"), v)?;
        raw.positions.push(p);
    }
    let mut corners = Vec::new();
    for f in 0..faces {
        let Some((n, l)) = lines.next() else {
            return Err(parse_error(
                last_line,
                format!("the file ends after {f} of its {faces} faces"),
            ));
        };
        last_line = n;
        let mut tokens = l.split_whitespace();
        let sides_token = tokens.next().unwrap_or("");
        let sides: usize = sides_token.parse().map_err(|_| {
            parse_error(
                n,
                format!(
                    "face {f}: `{}` is not a number of corners",
                    quote(sides_token)
                ),
            )
        })?;
        if sides < 3 {
            return Err(parse_error(n, format!("face {f} has {sides} corners")));
        }
        corners.clear();
        for k in 0..sides {
            let token = tokens.next().ok_or_else(|| {
                parse_error(n, format!("face {f} has {sides} corners but {k} indices"))
            })?;
            let index: i64 = token.parse().map_err(|_| {
                parse_error(
                    n,
                    format!("face {f}: `{}` is not a vertex index", quote(token)),
                )
            })?;
            if index < 0 || index as usize >= vertices {
                return Err(ImportError::IndexOutOfRange {
                    face: f,
                    at: Location::Line(n),
                    index,
                    vertex_count: vertices,
                });
            }
            corners.push(index as u32);
        }
        raw.push_polygon(&corners)?;
    }
    Ok(raw)
}
