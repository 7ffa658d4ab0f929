//! Export: every format written from fitted models of genus 0 to 3 and read back with an independent
//! reader (tobj, ply-rs-bw's parser, stl_io, gltf, a small OFF parser here), then checked: a closed,
//! manifold, orientable mesh of the right Euler characteristic, outward, with unit normals that
//! agree with the faces, at the positions the surface mesh has (to f32 precision).

use std::io::Cursor;
use std::sync::OnceLock;

use embedding::{Model, Surface};
use mesh::HalfEdgeMesh;
use ntori::io::export::{
    self, Encoding, ExportError, Format, MAX_RESOLUTION, SurfaceMesh, surface_mesh,
};
use ntori::io::model_file::{self, ModelFileError};

/// Small fitted models, genus 0 to 3.
fn models() -> Vec<&'static Surface> {
    (0..=3).map(crate::common::small_model).collect()
}

/// The surface meshes the format tests write, at the default t_e = t_r = 16. (Much coarser
/// tessellations of these coarse models fold: a few triangles face against the surface's normals.)
fn meshes() -> &'static [SurfaceMesh] {
    static MESHES: OnceLock<Vec<SurfaceMesh>> = OnceLock::new();
    MESHES.get_or_init(|| {
        models()
            .iter()
            .map(|m| surface_mesh(m, 16, 16).unwrap())
            .collect()
    })
}

fn write(mesh: &SurfaceMesh, format: Format, encoding: Encoding) -> Vec<u8> {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join(format!("surface.{}", format.extension()));
    export::write(mesh, &path, format, encoding).unwrap();
    std::fs::read(&path).unwrap()
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn widen(p: [f32; 3]) -> [f64; 3] {
    p.map(f64::from)
}

/// A mesh as read back from a file.
#[derive(Default)]
struct ReadBack {
    positions: Vec<[f64; 3]>,
    normals: Option<Vec<[f64; 3]>>,
    triangles: Vec<[u32; 3]>,
}

/// The checks every format must pass; returns, for each vertex read, the surface mesh's vertex it
/// is (matched corner by corner through the triangles, which every format keeps in order).
fn check(read: &ReadBack, reference: &SurfaceMesh, what: &str) -> Vec<usize> {
    let genus = reference.genus;
    let topology =
        HalfEdgeMesh::from_polygons(read.positions.len(), read.triangles.iter().map(|t| &t[..]))
            .unwrap_or_else(|e| panic!("{what}: {e}"))
            .topology();
    assert!(topology.closed, "{what}: not closed: {topology:?}");
    assert!(topology.manifold, "{what}: not manifold: {topology:?}");
    assert!(topology.orientable, "{what}: not orientable: {topology:?}");
    assert_eq!(topology.misoriented_edges, 0, "{what}");
    assert_eq!(topology.components, 1, "{what}");
    assert_eq!(
        topology.euler_characteristic,
        2 - 2 * i64::from(genus),
        "{what}: χ"
    );
    assert_eq!(read.triangles.len(), reference.triangles.len(), "{what}");
    assert_eq!(read.positions.len(), reference.positions.len(), "{what}");

    // The vertex correspondence: consistent and one to one.
    let mut map = vec![usize::MAX; read.positions.len()];
    for (t, r) in read.triangles.iter().zip(&reference.triangles) {
        for j in 0..3 {
            let slot = &mut map[t[j] as usize];
            assert!(
                *slot == usize::MAX || *slot == r[j] as usize,
                "{what}: vertex {} is both {} and {}",
                t[j],
                *slot,
                r[j]
            );
            *slot = r[j] as usize;
        }
    }
    let mut seen = vec![false; map.len()];
    for &m in &map {
        assert!(!std::mem::replace(&mut seen[m], true), "{what}: {m} twice");
    }

    // Outward: positive signed volume.
    let volume: f64 = read
        .triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| read.positions[i as usize]);
            dot(a, cross(b, c))
        })
        .sum::<f64>()
        / 6.0;
    assert!(volume > 0.0, "{what}: signed volume {volume}");

    // Positions as the surface mesh has them, to f32 precision.
    let scale = reference
        .positions
        .iter()
        .flatten()
        .fold(1.0f64, |m, x| m.max(x.abs()));
    let tolerance = 2.0 * f64::from(f32::EPSILON) * scale;
    for (i, &got) in read.positions.iter().enumerate() {
        let want = reference.positions[map[i]];
        let d = sub(got, want).iter().fold(0.0f64, |m, x| m.max(x.abs()));
        assert!(d <= tolerance, "{what}: vertex {i}: {got:?} vs {want:?}");
    }

    // Unit normals, the surface mesh's, agreeing in sign with the area-weighted face normals.
    if let Some(normals) = &read.normals {
        assert_eq!(normals.len(), read.positions.len(), "{what}");
        let mut faces = vec![[0.0; 3]; read.positions.len()];
        for t in &read.triangles {
            let [a, b, c] = t.map(|i| read.positions[i as usize]);
            let n = cross(sub(b, a), sub(c, a));
            for &v in t {
                let s = &mut faces[v as usize];
                *s = [s[0] + n[0], s[1] + n[1], s[2] + n[2]];
            }
        }
        for (i, (n, f)) in normals.iter().zip(&faces).enumerate() {
            let length = dot(*n, *n).sqrt();
            assert!((length - 1.0).abs() < 1e-6, "{what}: normal {i}: {length}");
            let d = sub(*n, reference.normals[map[i]]);
            assert!(dot(d, d).sqrt() < 1e-6, "{what}: normal {i}");
            let cosine = dot(*n, *f) / dot(*f, *f).sqrt();
            assert!(
                cosine > 0.5,
                "{what}: vertex {i}: normal {n:?} vs faces {f:?}"
            );
        }
    }
    map
}

fn assert_identity(map: &[usize], what: &str) {
    assert!(
        map.iter().enumerate().all(|(i, &m)| i == m),
        "{what}: the vertices are renumbered"
    );
}

fn check_uvs(uvs: &[[f64; 2]], map: &[usize], mesh: &SurfaceMesh, flipped: bool, what: &str) {
    assert_eq!(uvs.len(), mesh.uvs.len());
    for (i, got) in uvs.iter().enumerate() {
        let want = mesh.uvs[map[i]];
        let want = if flipped {
            [want[0], 1.0 - want[1]]
        } else {
            want
        };
        assert!(
            (got[0] - want[0]).abs() < 1e-6 && (got[1] - want[1]).abs() < 1e-6,
            "{what}: uv {got:?} vs {want:?}"
        );
        assert!(
            got.iter().all(|x| (0.0..=1.0).contains(x)),
            "{what}: {got:?}"
        );
    }
}

fn obj(bytes: &[u8]) -> (ReadBack, Vec<[f64; 2]>) {
    let options = tobj::LoadOptions {
        single_index: false,
        triangulate: false,
        ..Default::default()
    };
    let (models, _) =
        tobj::load_obj_buf(&mut Cursor::new(bytes), &options, |_| unreachable!()).unwrap();
    assert_eq!(models.len(), 1);
    let m = &models[0].mesh;
    assert!(m.face_arities.is_empty() || m.face_arities.iter().all(|&a| a == 3));
    // v/vt/vn share the index, so each vertex's texture coordinate and normal are its own.
    assert_eq!(m.indices, m.texcoord_indices);
    assert_eq!(m.indices, m.normal_indices);
    let triples = |v: &[f32]| -> Vec<[f64; 3]> {
        v.chunks_exact(3)
            .map(|c| widen([c[0], c[1], c[2]]))
            .collect()
    };
    let read = ReadBack {
        positions: triples(&m.positions),
        normals: Some(triples(&m.normals)),
        triangles: m
            .indices
            .chunks_exact(3)
            .map(|c| [c[0], c[1], c[2]])
            .collect(),
    };
    let uvs = m
        .texcoords
        .chunks_exact(2)
        .map(|c| [f64::from(c[0]), f64::from(c[1])])
        .collect();
    (read, uvs)
}

#[test]
fn obj_reads_back_with_tobj() {
    for mesh in meshes() {
        let bytes = write(mesh, Format::Obj, Encoding::Binary);
        let (read, uvs) = obj(&bytes);
        // tobj numbers vertices in the order the faces first use them.
        let map = check(&read, mesh, &format!("OBJ genus {}", mesh.genus));
        check_uvs(&uvs, &map, mesh, false, "OBJ");
    }
}

#[test]
fn ply_reads_back_with_the_ply_parser_in_both_encodings() {
    use ply_rs_bw::parser::Parser;
    use ply_rs_bw::ply::{DefaultElement, Encoding as PlyEncoding, Property};

    for mesh in meshes() {
        for (encoding, expected) in [
            (Encoding::Binary, PlyEncoding::BinaryLittleEndian),
            (Encoding::Ascii, PlyEncoding::Ascii),
        ] {
            let what = format!("PLY {encoding:?} genus {}", mesh.genus);
            let bytes = write(mesh, Format::Ply, encoding);
            let ply = Parser::<DefaultElement>::new()
                .read_ply(&mut Cursor::new(&bytes))
                .unwrap();
            assert_eq!(ply.header.encoding, expected, "{what}");
            let float = |e: &DefaultElement, k: &str| match e.get(k) {
                Some(Property::Float(x)) => f64::from(*x),
                other => panic!("{what}: property {k} is {other:?}"),
            };
            let vertices = &ply.payload["vertex"];
            let read = ReadBack {
                positions: vertices
                    .iter()
                    .map(|e| [float(e, "x"), float(e, "y"), float(e, "z")])
                    .collect(),
                normals: Some(
                    vertices
                        .iter()
                        .map(|e| [float(e, "nx"), float(e, "ny"), float(e, "nz")])
                        .collect(),
                ),
                triangles: ply.payload["face"]
                    .iter()
                    .map(|e| match e.get("vertex_indices") {
                        Some(Property::ListInt(l)) if l.len() == 3 => {
                            [l[0] as u32, l[1] as u32, l[2] as u32]
                        }
                        other => panic!("{what}: face is {other:?}"),
                    })
                    .collect(),
            };
            let map = check(&read, mesh, &what);
            assert_identity(&map, &what);
            let uvs: Vec<[f64; 2]> = vertices
                .iter()
                .map(|e| [float(e, "u"), float(e, "v")])
                .collect();
            check_uvs(&uvs, &map, mesh, false, &what);
            let charts: Vec<u32> = vertices
                .iter()
                .map(|e| match e.get("chart") {
                    Some(Property::UInt(c)) => *c,
                    other => panic!("{what}: chart is {other:?}"),
                })
                .collect();
            assert_eq!(charts, mesh.charts, "{what}");
        }
    }
}

#[test]
fn stl_reads_back_with_stl_io_in_both_encodings() {
    for mesh in meshes() {
        for encoding in [Encoding::Binary, Encoding::Ascii] {
            let what = format!("STL {encoding:?} genus {}", mesh.genus);
            let bytes = write(mesh, Format::Stl, encoding);
            assert_eq!(bytes.starts_with(b"solid"), encoding == Encoding::Ascii);
            if encoding == Encoding::Binary {
                assert_eq!(bytes.len(), 84 + 50 * mesh.triangles.len(), "{what}");
            }
            // stl_io merges corners at identical positions into vertices.
            let stl = stl_io::read_stl(&mut Cursor::new(&bytes)).unwrap();
            let read = ReadBack {
                positions: stl.vertices.iter().map(|v| widen(v.0)).collect(),
                normals: None,
                triangles: stl
                    .faces
                    .iter()
                    .map(|f| f.vertices.map(|i| i as u32))
                    .collect(),
            };
            check(&read, mesh, &what);
            // Face normals: unit, outward (as the winding), and on the side of the analytic normals.
            for (k, f) in stl.faces.iter().enumerate() {
                let n = widen(f.normal.0);
                assert!((dot(n, n).sqrt() - 1.0).abs() < 1e-5, "{what}: facet {k}");
                let [a, b, c] = read.triangles[k].map(|i| read.positions[i as usize]);
                assert!(
                    dot(n, cross(sub(b, a), sub(c, a))) > 0.0,
                    "{what}: facet {k}"
                );
                let analytic = mesh.triangles[k].iter().fold([0.0; 3], |s, &v| {
                    let m = mesh.normals[v as usize];
                    [s[0] + m[0], s[1] + m[1], s[2] + m[2]]
                });
                assert!(dot(n, analytic) > 0.0, "{what}: facet {k}");
            }
        }
    }
}

#[test]
fn glb_reads_back_with_gltf_and_is_well_formed() {
    use gltf::Semantic;

    for mesh in meshes() {
        let what = format!("GLB genus {}", mesh.genus);
        let bytes = write(mesh, Format::Glb, Encoding::Binary);
        // The container: header length, chunk lengths and 4-byte padding.
        let word = |at: usize| u32::from_le_bytes(bytes[at..at + 4].try_into().unwrap()) as usize;
        assert_eq!(&bytes[0..4], b"glTF");
        assert_eq!(word(4), 2);
        assert_eq!(word(8), bytes.len(), "{what}: header length");
        let json_len = word(12);
        assert_eq!(&bytes[16..20], b"JSON");
        assert_eq!(json_len % 4, 0);
        let bin_at = 20 + json_len;
        assert_eq!(&bytes[bin_at + 4..bin_at + 8], b"BIN\0");
        assert_eq!(word(bin_at) % 4, 0);
        assert_eq!(bin_at + 8 + word(bin_at), bytes.len());

        // from_slice validates the document (accessor bounds, POSITION's min and max, …).
        let gltf = gltf::Gltf::from_slice(&bytes).unwrap_or_else(|e| panic!("{what}: {e}"));
        let blob = gltf.blob.as_deref().unwrap();
        let meshes: Vec<_> = gltf.meshes().collect();
        assert_eq!(meshes.len(), 1);
        let primitives: Vec<_> = meshes[0].primitives().collect();
        assert_eq!(primitives.len(), 1);
        let p = &primitives[0];
        assert_eq!(p.mode(), gltf::mesh::Mode::Triangles);
        let reader = p.reader(|_| Some(blob));
        let positions: Vec<[f64; 3]> = reader.read_positions().unwrap().map(widen).collect();
        let read = ReadBack {
            normals: Some(reader.read_normals().unwrap().map(widen).collect()),
            triangles: reader
                .read_indices()
                .unwrap()
                .into_u32()
                .collect::<Vec<_>>()
                .chunks_exact(3)
                .map(|c| [c[0], c[1], c[2]])
                .collect(),
            positions,
        };
        let map = check(&read, mesh, &what);
        assert_identity(&map, &what);

        // POSITION's bounds are exactly the f32 positions' bounds (compared as f32: gltf's JSON
        // parser may round the decimal to a neighbouring f64).
        let accessor = p.get(&Semantic::Positions).unwrap();
        let bounds = |v: Option<gltf::json::Value>| -> Vec<f64> {
            v.unwrap()
                .as_array()
                .unwrap()
                .iter()
                .map(|x| x.as_f64().unwrap())
                .collect()
        };
        let (min, max) = (bounds(accessor.min()), bounds(accessor.max()));
        for k in 0..3 {
            let values = read.positions.iter().map(|p| p[k]);
            let low = values.clone().fold(f64::INFINITY, f64::min);
            let high = values.fold(f64::NEG_INFINITY, f64::max);
            assert_eq!((min[k] as f32, max[k] as f32), (low as f32, high as f32));
        }

        let uvs: Vec<[f64; 2]> = reader
            .read_tex_coords(0)
            .unwrap()
            .into_f32()
            .map(|[u, v]| [f64::from(u), f64::from(v)])
            .collect();
        check_uvs(&uvs, &map, mesh, true, &what);

        let chart = p.get(&Semantic::Extras("CHART".into())).unwrap();
        assert_eq!(chart.data_type(), gltf::accessor::DataType::U16);
        let charts: Vec<u32> = gltf::accessor::Iter::<u16>::new(chart, |_| Some(blob))
            .unwrap()
            .map(u32::from)
            .collect();
        assert_eq!(charts, mesh.charts, "{what}");
    }
}

/// The OFF reader a user would write: "OFF", counts, vertices, faces; `#` starts a comment.
fn parse_off(text: &str) -> ReadBack {
    let mut tokens = text
        .lines()
        .map(|l| l.split('#').next().unwrap())
        .flat_map(str::split_whitespace);
    assert_eq!(tokens.next(), Some("OFF"));
    let mut number = || tokens.next().unwrap().parse::<f64>().unwrap();
    let (v, f, _edges) = (number() as usize, number() as usize, number());
    let positions = (0..v).map(|_| [number(), number(), number()]).collect();
    let triangles = (0..f)
        .map(|_| {
            assert_eq!(number(), 3.0);
            [number() as u32, number() as u32, number() as u32]
        })
        .collect();
    ReadBack {
        positions,
        normals: None,
        triangles,
    }
}

#[test]
fn off_reads_back_with_a_plain_parser() {
    for mesh in meshes() {
        let bytes = write(mesh, Format::Off, Encoding::Binary);
        let read = parse_off(std::str::from_utf8(&bytes).unwrap());
        let what = format!("OFF genus {}", mesh.genus);
        assert_identity(&check(&read, mesh, &what), &what);
    }
}

#[test]
fn the_surface_mesh_has_the_tessellations_size_and_analytic_outward_normals() {
    for (model, mesh) in models().iter().zip(meshes()) {
        let genus = model.genus();
        let t = charts::Atlas::new(genus)
            .unwrap()
            .tessellate(16, 16)
            .unwrap();
        assert_eq!(mesh.positions.len(), t.vertices.len());
        assert_eq!(mesh.triangles.len(), t.triangles.len());
        assert_eq!(mesh.normals.len(), t.vertices.len());
        assert_eq!(mesh.uvs.len(), t.vertices.len());
        assert_eq!(mesh.charts.len(), t.vertices.len());
        assert!(export::signed_volume(&mesh.positions, &mesh.triangles) > 0.0);
        let read = ReadBack {
            positions: mesh.positions.clone(),
            normals: Some(mesh.normals.clone()),
            triangles: mesh.triangles.clone(),
        };
        check(&read, mesh, &format!("surface mesh genus {genus}"));
        assert_eq!(mesh.folded_triangles(), 0, "genus {genus}");
        // The chart ids are the tessellation's home charts, the UVs their coordinates + ½.
        for (i, p) in t.vertices.iter().enumerate() {
            assert_eq!(mesh.charts[i], p.chart.0);
            assert_eq!(mesh.uvs[i], [p.coords.re + 0.5, p.coords.im + 0.5]);
        }
    }
}

#[test]
fn a_mirrored_model_is_still_exported_outward() {
    let original = &models()[2];
    let mirrored = original
        .control_points()
        .iter()
        .map(|p| embedding::Point3::new(-p.x, p.y, p.z))
        .collect();
    let model = original.with_control_points(mirrored).unwrap();
    let mesh = surface_mesh(&model, 16, 16).unwrap();
    let read = ReadBack {
        positions: mesh.positions.clone(),
        normals: Some(mesh.normals.clone()),
        triangles: mesh.triangles.clone(),
    };
    check(&read, &mesh, "mirrored genus 2");
    // The mirror image of the original, wound the other way round.
    let original = &meshes()[2];
    for (p, q) in mesh.positions.iter().zip(&original.positions) {
        assert!((p[0] + q[0]).abs() < 1e-12 && p[1] == q[1] && p[2] == q[2]);
    }
    for (t, u) in mesh.triangles.iter().zip(&original.triangles) {
        assert_eq!(*t, [u[0], u[2], u[1]]);
    }
}

#[test]
fn bad_resolutions_and_degenerate_surfaces_are_refused() {
    let model = &models()[2];
    for (te, tr) in [(0, 4), (4, 0), (MAX_RESOLUTION + 1, 4)] {
        assert!(matches!(
            surface_mesh(model, te, tr),
            Err(ExportError::Resolution { .. })
        ));
    }
    // Within range but absurd: refused from the formula, before any work.
    let err = export::check_resolution(64, 512, 512).unwrap_err();
    assert!(matches!(err, ExportError::TooManyTriangles { .. }), "{err}");
    assert!(err.to_string().contains("triangles"));
    // A model whose control points do not match its settings never becomes a surface.
    let mut short = model.to_model();
    short.control_points.pop();
    assert!(matches!(
        Surface::from_model(&short),
        Err(embedding::EmbeddingError::ControlCount { .. })
    ));
    // Every control point in one place: no surface to export.
    let layout = model.layout();
    let point = Model::constant(&layout, embedding::Point3::new(1.0, 2.0, 3.0));
    let point = Surface::from_model(&point).unwrap();
    let err = surface_mesh(&point, 4, 4).unwrap_err();
    assert!(matches!(err, ExportError::Degenerate { .. }), "{err}");
}

#[test]
fn formats_come_from_extensions() {
    for format in Format::ALL {
        let name = format!("a/b.{}", format.extension().to_uppercase());
        assert_eq!(Format::from_path(name.as_ref()).unwrap(), format);
    }
    for name in ["a.json", "a", "a.obj.gz", ".obj"] {
        let err = Format::from_path(name.as_ref()).unwrap_err();
        assert!(err.to_string().contains(name), "{err}");
    }
}

#[test]
fn model_files_round_trip_and_report_what_is_wrong() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("m.json");
    model_file::save(&path, models()[1]).unwrap();
    assert_eq!(model_file::load(&path).unwrap(), *models()[1]);

    let text = std::fs::read_to_string(&path).unwrap();
    let cases: [(&str, String); 6] = [
        ("missing", String::new()),
        ("not json", "{ this is not json".into()),
        ("an array", "[1, 2, 3]".into()),
        (
            "other format",
            text.replace("ntori-model", "something-else"),
        ),
        ("future", text.replace("\"version\":1", "\"version\":99")),
        ("bad genus", text.replace("\"genus\":1", "\"genus\":2")),
    ];
    for (name, contents) in cases {
        let p = dir.path().join(format!("{name}.json"));
        if name != "missing" {
            std::fs::write(&p, contents).unwrap();
        }
        let err = model_file::load(&p).unwrap_err();
        assert!(
            err.to_string().contains(&p.display().to_string()),
            "{name}: {err}"
        );
        let expected = match name {
            "missing" => matches!(err, ModelFileError::Missing { .. }),
            "not json" => matches!(err, ModelFileError::NotJson { .. }),
            "an array" | "other format" => matches!(err, ModelFileError::NotAModel { .. }),
            "future" => matches!(err, ModelFileError::FutureVersion { version: 99, .. }),
            _ => matches!(err, ModelFileError::Inconsistent { .. }),
        };
        assert!(expected, "{name}: {err:?}");
    }

    // Saving into a directory that does not exist fails and leaves nothing behind.
    let nowhere = dir.path().join("no/such/dir/m.json");
    assert!(model_file::save(&nowhere, models()[1]).is_err());
    assert!(!nowhere.exists());
}

#[test]
fn a_failed_write_leaves_no_file() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("out.obj");
    let err = ntori::io::atomic::write_atomically_with(&path, |w| {
        w.write_all(b"partial")?;
        Err(std::io::Error::other("the disk is full"))
    })
    .unwrap_err();
    assert!(err.to_string().contains("out.obj"), "{err}");
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
    // And an existing file is kept as it was.
    std::fs::write(&path, b"before").unwrap();
    let _ = ntori::io::atomic::write_atomically_with(&path, |_| Err(std::io::Error::other("no")));
    assert_eq!(std::fs::read(&path).unwrap(), b"before");
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
}
