//! glTF 2.0: binary (GLB: the container read by hand) or JSON (`.gltf` whose buffers are `data:`
//! URIs), the JSON through gltf-json. Every triangle primitive (`TRIANGLES`, `TRIANGLE_STRIP`,
//! `TRIANGLE_FAN`; points and lines are skipped) of every mesh instance in the default scene (the
//! first scene, or every root node, or every mesh when there are no nodes), with its node's
//! transform applied; a transform that mirrors reverses its triangles. `POSITION` must be f32
//! VEC3, indices u8, u16 or u32 scalars; sparse accessors, compressed or quantised meshes
//! (`extensionsRequired`) and external buffers are refused as unsupported. Every offset, stride and
//! count is checked against the buffer before a byte is read. glTF splits vertices at UV and normal
//! seams, so exactly coincident vertices are merged.

use std::collections::BTreeMap;

use embedding::Point3;
use gltf_json::Root;
use gltf_json::accessor::{ComponentType, Type};
use gltf_json::mesh::{Mode, Semantic};
use gltf_json::validation::Checked;

use super::obj::quote;
use super::{ImportError, Location, MAX_TRIANGLES, MeshFormat, RawMesh};

const FORMAT: MeshFormat = MeshFormat::Glb;
/// The deepest node hierarchy followed (deeper is taken for a cycle).
const MAX_DEPTH: usize = 64;

fn parse_error(at: Location, message: String) -> ImportError {
    ImportError::Parse {
        format: FORMAT,
        at,
        message,
    }
}

fn unsupported(at: Location, what: String) -> ImportError {
    ImportError::Unsupported {
        format: FORMAT,
        at,
        what,
    }
}

/// The JSON chunk and the binary chunk (if any) of a GLB container.
fn container(bytes: &[u8]) -> Result<(&[u8], Option<&[u8]>), ImportError> {
    let word = |at: usize| {
        bytes
            .get(at..at + 4)
            .map(|w| u32::from_le_bytes([w[0], w[1], w[2], w[3]]) as usize)
    };
    let version = word(4).unwrap_or(0);
    if version != 2 {
        return Err(unsupported(
            Location::Byte(4),
            format!("GLB version {version} (ntori reads glTF 2)"),
        ));
    }
    let length = word(8).unwrap_or(0);
    if length > bytes.len() || length < 12 {
        return Err(parse_error(
            Location::Byte(8),
            format!(
                "the header gives a length of {length} bytes, but the file has {}",
                bytes.len()
            ),
        ));
    }
    let (mut at, mut json, mut bin) = (12usize, None, None);
    while at + 8 <= length {
        let (size, kind) = (word(at).unwrap_or(0), word(at + 4).unwrap_or(0));
        let data = at
            .checked_add(8)
            .and_then(|start| Some(start..start.checked_add(size)?))
            .filter(|r| r.end <= length)
            .and_then(|r| bytes.get(r))
            .ok_or_else(|| {
                parse_error(
                    Location::Byte(at),
                    format!("a chunk of {size} bytes runs past the end of the file"),
                )
            })?;
        match kind {
            0x4E4F_534A if json.is_none() => json = Some(data),
            0x004E_4942 if bin.is_none() => bin = Some(data),
            _ => {}
        }
        at += 8 + size;
        at = at.next_multiple_of(4);
    }
    let json = json.ok_or_else(|| parse_error(Location::Byte(12), "no JSON chunk".into()))?;
    Ok((json, bin))
}

pub(crate) fn read(bytes: &[u8]) -> Result<RawMesh, ImportError> {
    let binary = bytes.starts_with(b"glTF");
    let text = bytes
        .strip_prefix(b"\xEF\xBB\xBF")
        .unwrap_or(bytes)
        .trim_ascii_start();
    if !binary && !text.starts_with(b"{") {
        let start = &bytes[..bytes.len().min(4)];
        return Err(parse_error(
            Location::Byte(0),
            format!(
                "it begins with `{}`, but binary glTF (GLB) begins with `glTF` and glTF JSON with `{{`",
                quote(&start.escape_ascii().to_string())
            ),
        ));
    }
    let (json, bin) = if binary {
        container(bytes)?
    } else {
        (bytes, None)
    };
    let root = Root::from_slice(json).map_err(|e| {
        // serde_json ends its message with the place; the location says it once.
        let message = e.to_string();
        let place = format!(" at line {} column {}", e.line(), e.column());
        if binary {
            parse_error(
                Location::Unknown,
                format!(
                    "the JSON chunk: {}",
                    message.replace(
                        &place,
                        &format!(" (line {}, column {})", e.line(), e.column())
                    )
                ),
            )
        } else {
            let message = message.strip_suffix(&place).unwrap_or(&message);
            parse_error(
                Location::LineColumn(e.line(), e.column()),
                message.to_owned(),
            )
        }
    })?;
    if let Some(ext) = root.extensions_required.first() {
        return Err(unsupported(
            Location::Unknown,
            format!("the required extension {}", quote(ext)),
        ));
    }
    let buffers = root
        .buffers
        .iter()
        .enumerate()
        .map(|(i, b)| buffer_data(i, b.uri.as_deref(), bin))
        .collect::<Result<Vec<_>, _>>()?;
    let mut raw = RawMesh {
        merge: true,
        ..RawMesh::default()
    };
    let mut reader = Reader {
        root: &root,
        buffers: &buffers,
        cache: BTreeMap::new(),
    };
    // Instances: (mesh, transform), in scene order.
    let mut instances: Vec<(usize, Affine)> = Vec::new();
    let roots: Vec<usize> = if let Some(scene) = root
        .scene
        .map(|s| s.value())
        .or((!root.scenes.is_empty()).then_some(0))
    {
        let scene = root
            .scenes
            .get(scene)
            .ok_or_else(|| parse_error(Location::Unknown, format!("no scene {scene}")))?;
        scene.nodes.iter().map(|n| n.value()).collect()
    } else {
        let mut child = vec![false; root.nodes.len()];
        for node in &root.nodes {
            for c in node.children.iter().flatten() {
                if let Some(slot) = child.get_mut(c.value()) {
                    *slot = true;
                }
            }
        }
        (0..root.nodes.len()).filter(|&n| !child[n]).collect()
    };
    if root.nodes.is_empty() {
        instances.extend((0..root.meshes.len()).map(|m| (m, IDENTITY)));
    }
    let mut stack: Vec<(usize, Affine, usize)> =
        roots.iter().rev().map(|&n| (n, IDENTITY, 0)).collect();
    while let Some((n, parent, depth)) = stack.pop() {
        let node = root
            .nodes
            .get(n)
            .ok_or_else(|| parse_error(Location::Unknown, format!("no node {n}")))?;
        if depth > MAX_DEPTH {
            return Err(parse_error(
                Location::Unknown,
                format!("the node hierarchy is deeper than {MAX_DEPTH} (a cycle?) at node {n}"),
            ));
        }
        let world = compose(&parent, &local(node));
        if let Some(m) = node.mesh {
            instances.push((m.value(), world));
            if instances.len() > MAX_TRIANGLES {
                return Err(ImportError::TooManyTriangles {
                    at: Location::Unknown,
                    max: MAX_TRIANGLES,
                });
            }
        }
        for c in node.children.iter().flatten().rev() {
            stack.push((c.value(), world, depth + 1));
        }
    }
    for (m, transform) in instances {
        let mesh = root
            .meshes
            .get(m)
            .ok_or_else(|| parse_error(Location::Unknown, format!("no mesh {m}")))?;
        let mirror = determinant(&transform) < 0.0;
        for (p, primitive) in mesh.primitives.iter().enumerate() {
            let at = Location::Primitive {
                mesh: m,
                primitive: p,
            };
            let mode = match primitive.mode {
                Checked::Valid(mode) => mode,
                Checked::Invalid => return Err(parse_error(at, "an invalid mode".into())),
            };
            if !matches!(
                mode,
                Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan
            ) {
                continue;
            }
            let position = primitive
                .attributes
                .get(&Checked::Valid(Semantic::Positions))
                .ok_or_else(|| parse_error(at, "no POSITION attribute".into()))?;
            let local_positions = reader.positions(position.value(), at)?;
            let count = local_positions.len();
            let indices: Vec<u32> = match primitive.indices {
                Some(a) => reader.indices(a.value(), at)?,
                None => (0..count as u32).collect(),
            };
            let base = raw.positions.len();
            if base + count >= u32::MAX as usize {
                return Err(ImportError::TooManyTriangles {
                    at,
                    max: MAX_TRIANGLES,
                });
            }
            for (v, q) in local_positions.iter().enumerate() {
                let p = apply(&transform, q);
                if !p.iter().all(|x| x.is_finite()) {
                    return Err(ImportError::NonFinite {
                        vertex: v,
                        at,
                        x: p.x,
                        y: p.y,
                        z: p.z,
                    });
                }
                raw.positions.push(p);
            }
            let triangles = corners_of(mode, &indices);
            for (t, mut corners) in triangles.enumerate() {
                if let Some(&bad) = corners.iter().find(|&&i| i as usize >= count) {
                    return Err(ImportError::IndexOutOfRange {
                        face: t,
                        at,
                        index: i64::from(bad),
                        vertex_count: count,
                    });
                }
                if mirror {
                    corners.swap(1, 2);
                }
                // Strips and fans repeat corners where they restart; those are not triangles.
                let repeats = corners[0] == corners[1]
                    || corners[1] == corners[2]
                    || corners[0] == corners[2];
                if repeats && mode != Mode::Triangles {
                    continue;
                }
                raw.push_polygon(&corners.map(|i| (base + i as usize) as u32))?;
            }
        }
    }
    Ok(raw)
}

/// A primitive's triangles (corner indices into its vertices), counter-clockwise as glTF defines.
fn corners_of(mode: Mode, indices: &[u32]) -> Box<dyn Iterator<Item = [u32; 3]> + '_> {
    match mode {
        Mode::TriangleStrip => Box::new((0..indices.len().saturating_sub(2)).map(move |k| {
            if k % 2 == 0 {
                [indices[k], indices[k + 1], indices[k + 2]]
            } else {
                [indices[k + 1], indices[k], indices[k + 2]]
            }
        })),
        Mode::TriangleFan => Box::new(
            (1..indices.len().saturating_sub(1))
                .map(move |k| [indices[0], indices[k], indices[k + 1]]),
        ),
        _ => Box::new(indices.chunks_exact(3).map(|c| [c[0], c[1], c[2]])),
    }
}

/// An affine map of R³: three rows of a 4×4 matrix whose last row is (0, 0, 0, 1).
type Affine = [[f64; 4]; 3];

const IDENTITY: Affine = [
    [1.0, 0.0, 0.0, 0.0],
    [0.0, 1.0, 0.0, 0.0],
    [0.0, 0.0, 1.0, 0.0],
];

fn compose(a: &Affine, b: &Affine) -> Affine {
    let mut m = [[0.0; 4]; 3];
    for (i, row) in m.iter_mut().enumerate() {
        for (j, entry) in row.iter_mut().enumerate() {
            *entry =
                (0..3).map(|k| a[i][k] * b[k][j]).sum::<f64>() + if j == 3 { a[i][3] } else { 0.0 };
        }
    }
    m
}

fn apply(m: &Affine, p: &Point3) -> Point3 {
    let r = |i: usize| m[i][0] * p.x + m[i][1] * p.y + m[i][2] * p.z + m[i][3];
    Point3::new(r(0), r(1), r(2))
}

fn determinant(m: &Affine) -> f64 {
    m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
        - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
        + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
}

/// A node's own transform: its matrix (column-major), or translation · rotation · scale.
fn local(node: &gltf_json::scene::Node) -> Affine {
    if let Some(m) = node.matrix {
        let m = m.map(f64::from);
        return [0, 1, 2].map(|i| [m[i], m[4 + i], m[8 + i], m[12 + i]]);
    }
    let t = node.translation.unwrap_or([0.0; 3]).map(f64::from);
    let [x, y, z, w] = node
        .rotation
        .map_or([0.0, 0.0, 0.0, 1.0], |r| r.0)
        .map(f64::from);
    let s = node.scale.unwrap_or([1.0; 3]).map(f64::from);
    let norm = (x * x + y * y + z * z + w * w).sqrt();
    let (x, y, z, w) = if norm > 0.0 && norm.is_finite() {
        (x / norm, y / norm, z / norm, w / norm)
    } else {
        (0.0, 0.0, 0.0, 1.0)
    };
    let r = [
        [
            1.0 - 2.0 * (y * y + z * z),
            2.0 * (x * y - z * w),
            2.0 * (x * z + y * w),
        ],
        [
            2.0 * (x * y + z * w),
            1.0 - 2.0 * (x * x + z * z),
            2.0 * (y * z - x * w),
        ],
        [
            2.0 * (x * z - y * w),
            2.0 * (y * z + x * w),
            1.0 - 2.0 * (x * x + y * y),
        ],
    ];
    [0, 1, 2].map(|i| [r[i][0] * s[0], r[i][1] * s[1], r[i][2] * s[2], t[i]])
}

/// A buffer's bytes: GLB's binary chunk, or a `data:` URI decoded.
fn buffer_data(i: usize, uri: Option<&str>, bin: Option<&[u8]>) -> Result<Vec<u8>, ImportError> {
    match uri {
        None => bin.map(<[u8]>::to_vec).ok_or_else(|| {
            parse_error(
                Location::Unknown,
                format!("buffer {i} has no URI, and there is no binary chunk"),
            )
        }),
        Some(uri) if uri.starts_with("data:") => {
            let (_, data) = uri.split_once(";base64,").ok_or_else(|| {
                unsupported(
                    Location::Unknown,
                    format!("buffer {i}'s data URI without base64"),
                )
            })?;
            base64(data).ok_or_else(|| {
                parse_error(
                    Location::Unknown,
                    format!("buffer {i}'s data URI is not base64"),
                )
            })
        }
        Some(uri) => Err(unsupported(
            Location::Unknown,
            format!(
                "buffer {i} in the external file `{}` (ntori reads .glb, or .gltf with its buffers inside)",
                quote(uri)
            ),
        )),
    }
}

fn base64(text: &str) -> Option<Vec<u8>> {
    let value = |c: u8| -> Option<u32> {
        Some(match c {
            b'A'..=b'Z' => c - b'A',
            b'a'..=b'z' => c - b'a' + 26,
            b'0'..=b'9' => c - b'0' + 52,
            b'+' | b'-' => 62,
            b'/' | b'_' => 63,
            _ => return None,
        } as u32)
    };
    let clean: Vec<u8> = text
        .bytes()
        .filter(|c| !c.is_ascii_whitespace() && *c != b'=')
        .collect();
    let mut out = Vec::with_capacity(clean.len() / 4 * 3 + 2);
    for chunk in clean.chunks(4) {
        let mut acc = 0u32;
        for &c in chunk {
            acc = acc << 6 | value(c)?;
        }
        match chunk.len() {
            4 => out.extend_from_slice(&[(acc >> 16) as u8, (acc >> 8) as u8, acc as u8]),
            3 => out.extend_from_slice(&[(acc >> 10) as u8, (acc >> 2) as u8]),
            2 => out.push((acc >> 4) as u8),
            _ => return None,
        }
    }
    Some(out)
}

struct Reader<'a> {
    root: &'a Root,
    buffers: &'a [Vec<u8>],
    /// Accessors already read (instances share them).
    cache: BTreeMap<usize, Vec<Point3>>,
}

impl Reader<'_> {
    /// An accessor's elements as byte slices of `size` bytes each, every bound checked.
    fn elements(&self, a: usize, size: usize, at: Location) -> Result<Vec<&[u8]>, ImportError> {
        let bad = |message: String| parse_error(at, format!("accessor {a}: {message}"));
        let accessor = self
            .root
            .accessors
            .get(a)
            .ok_or_else(|| bad("there is no such accessor".into()))?;
        if accessor.sparse.is_some() {
            return Err(unsupported(at, format!("accessor {a} is sparse, which")));
        }
        let view_index = accessor
            .buffer_view
            .ok_or_else(|| unsupported(at, format!("accessor {a} without a buffer view, which")))?
            .value();
        let view = self
            .root
            .buffer_views
            .get(view_index)
            .ok_or_else(|| bad(format!("there is no buffer view {view_index}")))?;
        let buffer = self
            .buffers
            .get(view.buffer.value())
            .ok_or_else(|| bad(format!("there is no buffer {}", view.buffer.value())))?;
        let view_start = view.byte_offset.map_or(0, |o| o.0) as usize;
        let view_bytes = view_start
            .checked_add(view.byte_length.0 as usize)
            .and_then(|end| buffer.get(view_start..end))
            .ok_or_else(|| bad(format!("buffer view {view_index} runs past its buffer")))?;
        let stride = view.byte_stride.map_or(size, |s| s.0);
        if stride < size {
            return Err(bad(format!(
                "a stride of {stride} bytes for elements of {size}"
            )));
        }
        let count = accessor.count.0 as usize;
        let offset = accessor.byte_offset.map_or(0, |o| o.0) as usize;
        if count == 0 {
            return Ok(Vec::new());
        }
        let end = (count - 1)
            .checked_mul(stride)
            .and_then(|b| b.checked_add(offset)?.checked_add(size));
        if end.is_none_or(|e| e > view_bytes.len()) {
            return Err(bad(format!(
                "{count} elements run past buffer view {view_index}"
            )));
        }
        Ok((0..count)
            .map(|k| &view_bytes[offset + k * stride..offset + k * stride + size])
            .collect())
    }

    fn positions(&mut self, a: usize, at: Location) -> Result<Vec<Point3>, ImportError> {
        if let Some(p) = self.cache.get(&a) {
            return Ok(p.clone());
        }
        let accessor = self.root.accessors.get(a);
        let ok = accessor.is_some_and(|acc| {
            acc.type_ == Checked::Valid(Type::Vec3)
                && matches!(acc.component_type, Checked::Valid(c) if c.0 == ComponentType::F32)
        });
        if !ok && accessor.is_some() {
            return Err(unsupported(
                at,
                format!("POSITION accessor {a} not of f32 VEC3, which"),
            ));
        }
        let f = |b: &[u8], k: usize| {
            f64::from(f32::from_le_bytes([
                b[4 * k],
                b[4 * k + 1],
                b[4 * k + 2],
                b[4 * k + 3],
            ]))
        };
        let points: Vec<Point3> = self
            .elements(a, 12, at)?
            .into_iter()
            .map(|b| Point3::new(f(b, 0), f(b, 1), f(b, 2)))
            .collect();
        self.cache.insert(a, points.clone());
        Ok(points)
    }

    fn indices(&self, a: usize, at: Location) -> Result<Vec<u32>, ImportError> {
        let accessor = self.root.accessors.get(a);
        let size = match accessor.map(|acc| (acc.type_, acc.component_type)) {
            Some((Checked::Valid(Type::Scalar), Checked::Valid(c))) => match c.0 {
                ComponentType::U8 => 1,
                ComponentType::U16 => 2,
                ComponentType::U32 => 4,
                _ => 0,
            },
            None => 4,
            _ => 0,
        };
        if size == 0 {
            return Err(unsupported(
                at,
                format!("index accessor {a} not of unsigned scalars, which"),
            ));
        }
        Ok(self
            .elements(a, size, at)?
            .into_iter()
            .map(|b| match size {
                1 => u32::from(b[0]),
                2 => u32::from(u16::from_le_bytes([b[0], b[1]])),
                _ => u32::from_le_bytes([b[0], b[1], b[2], b[3]]),
            })
            .collect())
    }
}
