//! Export: every format written from fitted models of genus 0 to 3 and read back with an independent
//! reader (tobj, ply-rs-bw's parser, stl_io, gltf, zip + roxmltree for 3MF, a small OFF parser
//! here), then checked: a closed, manifold, orientable mesh of the right Euler characteristic,
//! outward, with unit normals that agree with the faces, at the positions the surface mesh has once
//! placed as the format's defaults say (to f32 precision). Also: the up axis, units and scale, the
//! UV atlas, the chart id's type, object names. (`export_tools.rs` reads the same files with
//! trimesh, lib3mf and the Khronos glTF validator.)

use std::io::Cursor;
use std::sync::OnceLock;

use embedding::{Model, Point3, Surface, Vector3};
use mesh::HalfEdgeMesh;
use ntori::io::export::{
    self, ChartComponent, ChartMesh, Encoding, ExportError, ExportOptions, Format, MAX_RESOLUTION,
    SurfaceMesh, Units, Up, UvAtlas, UvLayout, surface_mesh,
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
            .map(|m| surface_mesh(m, (16, 16), UvLayout::Chart).unwrap())
            .collect()
    })
}

/// The file `export::write` makes of `mesh` with the default options but `encoding`.
fn write(mesh: &SurfaceMesh, format: Format, encoding: Encoding) -> Vec<u8> {
    write_with(
        mesh,
        format,
        &ExportOptions {
            encoding,
            ..ExportOptions::default()
        },
    )
}

fn write_with(mesh: &SurfaceMesh, format: Format, options: &ExportOptions) -> Vec<u8> {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join(format!("surface.{}", format.extension()));
    export::write(mesh, &path, format, options).unwrap();
    std::fs::read(&path).unwrap()
}

/// `mesh` as a `format` file written with the default options holds it (turned to the format's up
/// axis, scaled to its unit).
fn placed(mesh: &SurfaceMesh, format: Format) -> SurfaceMesh {
    let options = ExportOptions::default();
    mesh.placed(options.up_for(format), options.factor_for(format))
        .into_owned()
}

/// A position or a direction as a file stores it (f32), widened.
fn point(p: [f32; 3]) -> Point3 {
    Point3::from(p.map(f64::from))
}
fn vector(v: [f32; 3]) -> Vector3 {
    Vector3::from(v.map(f64::from))
}

/// A mesh as read back from a file.
#[derive(Default)]
struct ReadBack {
    positions: Vec<Point3>,
    normals: Option<Vec<Vector3>>,
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
            let [a, b, c] = t.map(|i| read.positions[i as usize].coords);
            a.dot(&b.cross(&c))
        })
        .sum::<f64>()
        / 6.0;
    assert!(volume > 0.0, "{what}: signed volume {volume}");

    // Positions as the surface mesh has them, to f32 precision.
    let scale = reference
        .positions
        .iter()
        .flat_map(|p| p.iter())
        .fold(1.0f64, |m, x| m.max(x.abs()));
    let tolerance = 2.0 * f64::from(f32::EPSILON) * scale;
    for (i, &got) in read.positions.iter().enumerate() {
        let want = reference.positions[map[i]];
        let d = (got - want).amax();
        assert!(d <= tolerance, "{what}: vertex {i}: {got:?} vs {want:?}");
    }

    // Unit normals, the surface mesh's, agreeing in sign with the area-weighted face normals.
    if let Some(normals) = &read.normals {
        assert_eq!(normals.len(), read.positions.len(), "{what}");
        let mut faces = vec![Vector3::zeros(); read.positions.len()];
        for t in &read.triangles {
            let [a, b, c] = t.map(|i| read.positions[i as usize]);
            let n = (b - a).cross(&(c - a));
            for &v in t {
                faces[v as usize] += n;
            }
        }
        for (i, (n, f)) in normals.iter().zip(&faces).enumerate() {
            let length = n.norm();
            assert!((length - 1.0).abs() < 1e-6, "{what}: normal {i}: {length}");
            let d = n - reference.normals[map[i]];
            assert!(d.norm() < 1e-6, "{what}: normal {i}");
            let cosine = n.dot(f) / f.norm();
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
    let triples =
        |v: &[f32]| -> Vec<[f32; 3]> { v.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect() };
    let read = ReadBack {
        positions: triples(&m.positions).into_iter().map(point).collect(),
        normals: Some(triples(&m.normals).into_iter().map(vector).collect()),
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
        let map = check(
            &read,
            &placed(mesh, Format::Obj),
            &format!("OBJ genus {}", mesh.genus),
        );
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
                    .map(|e| Point3::new(float(e, "x"), float(e, "y"), float(e, "z")))
                    .collect(),
                normals: Some(
                    vertices
                        .iter()
                        .map(|e| Vector3::new(float(e, "nx"), float(e, "ny"), float(e, "nz")))
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
            let map = check(&read, &placed(mesh, Format::Ply), &what);
            assert_identity(&map, &what);
            // `s t`: the names Blender and MeshLab read as texture coordinates.
            let uvs: Vec<[f64; 2]> = vertices
                .iter()
                .map(|e| [float(e, "s"), float(e, "t")])
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
                positions: stl.vertices.iter().map(|v| point(v.0)).collect(),
                normals: None,
                triangles: stl
                    .faces
                    .iter()
                    .map(|f| f.vertices.map(|i| i as u32))
                    .collect(),
            };
            check(&read, &placed(mesh, Format::Stl), &what);
            // Face normals: unit, outward (as the winding), and on the side of the analytic normals.
            for (k, f) in stl.faces.iter().enumerate() {
                let n = vector(f.normal.0);
                assert!((n.norm() - 1.0).abs() < 1e-5, "{what}: facet {k}");
                let [a, b, c] = read.triangles[k].map(|i| read.positions[i as usize]);
                assert!(n.dot(&(b - a).cross(&(c - a))) > 0.0, "{what}: facet {k}");
                let analytic = mesh.triangles[k]
                    .iter()
                    .fold(Vector3::zeros(), |s, &v| s + mesh.normals[v as usize]);
                assert!(n.dot(&analytic) > 0.0, "{what}: facet {k}");
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
        let positions: Vec<Point3> = reader.read_positions().unwrap().map(point).collect();
        let read = ReadBack {
            normals: Some(reader.read_normals().unwrap().map(vector).collect()),
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
        let map = check(&read, &placed(mesh, Format::Glb), &what);
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

        // The chart id as u8 (Blender's importer drops u16 attributes).
        let chart = p.get(&Semantic::Extras("CHART".into())).unwrap();
        assert_eq!(chart.data_type(), gltf::accessor::DataType::U8);
        let charts: Vec<u32> = gltf::accessor::Iter::<u8>::new(chart, |_| Some(blob))
            .unwrap()
            .map(u32::from)
            .collect();
        assert_eq!(charts, mesh.charts, "{what}");

        // A PBR material whose base colour texture is read through TEXCOORD_0: an embedded PNG.
        let material = p.material();
        let pbr = material.pbr_metallic_roughness();
        let info = pbr.base_color_texture().expect("a base colour texture");
        assert_eq!(info.tex_coord(), 0);
        assert_eq!(pbr.metallic_factor(), 0.0);
        let gltf::image::Source::View { view, mime_type } = info.texture().source().source() else {
            panic!("{what}: the image is not in the buffer");
        };
        assert_eq!(mime_type, "image/png");
        let png = &blob[view.offset()..view.offset() + view.length()];
        assert_eq!(png, &export::texture::checker_png().unwrap()[..]);
        let decoder = png::Decoder::new(std::io::Cursor::new(png));
        let reader = decoder.read_info().unwrap();
        assert_eq!(
            (reader.info().width, reader.info().height),
            (export::texture::SIDE, export::texture::SIDE)
        );
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
    let positions = (0..v)
        .map(|_| Point3::new(number(), number(), number()))
        .collect();
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
        assert_identity(&check(&read, &placed(mesh, Format::Off), &what), &what);
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
    let mesh = surface_mesh(&model, (16, 16), UvLayout::Chart).unwrap();
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
            surface_mesh(model, (te, tr), UvLayout::Chart),
            Err(ExportError::Resolution { .. })
        ));
    }
    assert!(matches!(
        surface_mesh(model, (1, 4), UvLayout::Chart),
        Err(ExportError::SharedEdges { genus: 2 })
    ));
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
    let err = surface_mesh(&point, (4, 4), UvLayout::Chart).unwrap_err();
    assert!(matches!(err, ExportError::Degenerate { .. }), "{err}");
    // The quality tessellation refuses it too, counting the vertices it would start from.
    let err = export::quality_surface_mesh(&point, 1e-3, UvLayout::Chart).unwrap_err();
    let expected = embedding::remesh::start_vertex_count(point.atlas()).unwrap();
    assert!(
        matches!(err, ExportError::Degenerate { count, .. } if count == expected),
        "{err}"
    );
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

#[test]
fn export_surface_writes_what_surface_mesh_makes_and_says_so() {
    let dir = tempfile::tempdir().unwrap();
    for (genus, te, tr) in [(0, 16, 16), (2, 16, 16), (2, 2, 1), (3, 5, 7)] {
        let surface = crate::common::small_model(genus);
        let path = dir.path().join(format!("g{genus}-{te}-{tr}.off"));
        let options = ExportOptions::default();
        let exported =
            export::export_surface(surface, (te, tr).into(), &path, Format::Off, &options).unwrap();
        let mesh = surface_mesh(surface, (te, tr), UvLayout::Chart).unwrap();
        assert_eq!(exported.vertices, mesh.positions.len());
        assert_eq!(exported.triangles, mesh.triangles.len());
        assert_eq!(exported.folded, mesh.folded_triangles());
        assert_eq!(
            std::fs::read(&path).unwrap(),
            write(&mesh, Format::Off, Encoding::Binary)
        );
        // The size it reports is the written mesh's, in the file's unit (OFF: --units, cm).
        let (lo, hi) = embedding::bounding_box(&mesh.positions);
        assert_eq!(exported.unit, Units::Cm);
        for k in 0..3 {
            assert!((exported.size[k] - (hi[k] - lo[k])).abs() < 1e-12);
        }
    }
}

// ------------------------------------------------------------------ up axis, units, scale

#[test]
fn y_up_is_a_rotation_that_keeps_the_mesh_outward() {
    let mesh = &meshes()[2];
    let up = mesh.placed(Up::Y, 1.0).into_owned();
    // (x, y, z) → (x, z, −y), normals too.
    for (p, q) in up.positions.iter().zip(&mesh.positions) {
        assert_eq!([p.x, p.y, p.z], [q.x, q.z, -q.y]);
    }
    for (n, m) in up.normals.iter().zip(&mesh.normals) {
        assert_eq!([n.x, n.y, n.z], [m.x, m.z, -m.y]);
    }
    // The triangles are the same, and still face outward: a rotation keeps the signed volume.
    assert_eq!(up.triangles, mesh.triangles);
    let (before, after) = (
        export::signed_volume(&mesh.positions, &mesh.triangles),
        export::signed_volume(&up.positions, &up.triangles),
    );
    assert!(after > 0.0 && (after - before).abs() < 1e-12 * before);
    let read = ReadBack {
        positions: up.positions.clone(),
        normals: Some(up.normals.clone()),
        triangles: up.triangles.clone(),
    };
    check(&read, &up, "genus 2, y up");
    // The plate's thin axis, z in the model, is y in a Y-up file.
    let extent = |m: &SurfaceMesh| {
        let (lo, hi) = embedding::bounding_box(&m.positions);
        hi - lo
    };
    assert_eq!(extent(mesh).imin(), 2);
    assert_eq!(extent(&up).imin(), 1);
    // Scaling keeps the orientation too; nothing to do borrows.
    let big = mesh.placed(Up::Z, 2.5);
    let volume = export::signed_volume(&big.positions, &big.triangles);
    assert!((volume / before - 2.5f64.powi(3)).abs() < 1e-9);
    assert!(matches!(
        mesh.placed(Up::Z, 1.0),
        std::borrow::Cow::Borrowed(_)
    ));
}

#[test]
fn each_format_gets_its_up_axis_and_its_unit() {
    use Format::*;
    let default = ExportOptions::default();
    let expected_up = [
        (Obj, Up::Y),
        (Glb, Up::Y),
        (Ply, Up::Z),
        (Stl, Up::Z),
        (ThreeMf, Up::Z),
        (Off, Up::Z),
    ];
    for (format, up) in expected_up {
        assert_eq!(default.up_for(format), up, "{format}");
        let z = ExportOptions {
            up: Some(Up::Z),
            ..ExportOptions::default()
        };
        assert_eq!(z.up_for(format), Up::Z, "{format}");
    }
    // A model unit is 1 cm by default: 0.01 m in glTF, 10 mm in STL and 3MF, 1 (cm) elsewhere.
    let close = |a: f64, b: f64| (a - b).abs() <= 1e-12 * b;
    for (format, factor) in [
        (Glb, 0.01),
        (Stl, 10.0),
        (ThreeMf, 10.0),
        (Obj, 1.0),
        (Ply, 1.0),
        (Off, 1.0),
    ] {
        assert!(close(default.factor_for(format), factor), "{format}");
    }
    let inches = ExportOptions {
        scale: 2.0,
        units: Units::In,
        ..ExportOptions::default()
    };
    for (format, factor) in [(Glb, 0.0508), (Stl, 50.8), (ThreeMf, 50.8), (Obj, 2.0)] {
        assert!(close(inches.factor_for(format), factor), "{format}");
    }
    assert_eq!(inches.unit_for(Obj), Units::In);
    assert_eq!(inches.unit_for(Glb), Units::M);
    assert_eq!(inches.unit_for(ThreeMf), Units::Mm);
}

#[test]
fn options_that_do_not_apply_are_refused() {
    for format in Format::ALL {
        let atlas = ExportOptions {
            uv: UvLayout::Atlas,
            ..ExportOptions::default()
        };
        let ascii = ExportOptions {
            encoding: Encoding::Ascii,
            ..ExportOptions::default()
        };
        assert_eq!(atlas.check(format).is_ok(), format.has_uvs(), "{format}");
        assert_eq!(
            ascii.check(format).is_ok(),
            format.has_encodings(),
            "{format}"
        );
        if !format.has_uvs() {
            let err = atlas.check(format).unwrap_err();
            assert!(
                err.to_string()
                    .contains("--uv atlas applies to OBJ, PLY and GLB"),
                "{err}"
            );
        }
    }
    for scale in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        let options = ExportOptions {
            scale,
            ..ExportOptions::default()
        };
        let err = options.check(Format::Stl).unwrap_err();
        assert!(matches!(err, ExportError::Scale(_)), "{err}");
    }
    // A scale that takes the surface beyond f32 is refused when written, not written as inf.
    let options = ExportOptions {
        scale: 1e38,
        ..ExportOptions::default()
    };
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("m.stl");
    let err = export::write(&meshes()[1], &path, Format::Stl, &options).unwrap_err();
    assert!(matches!(err, ExportError::NotStorable { .. }), "{err}");
    assert!(!path.exists());
}

#[test]
fn t_e_1_is_refused_exactly_where_two_edges_would_join_the_same_vertices() {
    for genus in 0..=3 {
        let t = charts::Atlas::new(genus).unwrap().tessellate(1, 2).unwrap();
        // Edges known by their endpoints only, as mesh readers know them.
        let manifold =
            HalfEdgeMesh::from_polygons(t.vertices.len(), t.triangles.iter().map(|t| &t[..]))
                .unwrap()
                .topology()
                .manifold;
        let refused = export::check_resolution(genus, 1, 2).is_err();
        assert_eq!(manifold, genus == 0, "genus {genus}");
        assert_eq!(refused, !manifold, "genus {genus}");
        assert!(export::check_resolution(genus, 2, 1).is_ok());
    }
    let err = export::check_resolution(2, 1, 16).unwrap_err();
    assert!(err.to_string().contains("use --te 2 or more"), "{err}");
}

// ------------------------------------------------------------------------ chart ids, names

/// The GLB's `_CHART` accessor: its component type and values.
fn glb_charts(bytes: &[u8]) -> (gltf::accessor::DataType, Vec<f64>) {
    let gltf = gltf::Gltf::from_slice(bytes).unwrap();
    let blob = gltf.blob.as_deref().unwrap();
    let p = gltf.meshes().next().unwrap().primitives().next().unwrap();
    let chart = p.get(&gltf::Semantic::Extras("CHART".into())).unwrap();
    let values = match chart.data_type() {
        gltf::accessor::DataType::U8 => {
            gltf::accessor::Iter::<u8>::new(chart.clone(), |_| Some(blob))
                .unwrap()
                .map(f64::from)
                .collect()
        }
        gltf::accessor::DataType::F32 => {
            gltf::accessor::Iter::<f32>::new(chart.clone(), |_| Some(blob))
                .unwrap()
                .map(f64::from)
                .collect()
        }
        other => panic!("_CHART is {other:?}"),
    };
    (chart.data_type(), values)
}

#[test]
fn chart_ids_are_u8_while_they_fit_and_f32_beyond() {
    // ntori's atlases have 2n + 2 charts: 130 at genus 64, so u8 always fits.
    assert_eq!(charts::Atlas::new(64).unwrap().charts().len(), 130);
    let mesh = &meshes()[1];
    assert_eq!(export::chart_component(mesh), ChartComponent::U8);
    let (kind, values) = glb_charts(&write(mesh, Format::Glb, Encoding::Binary));
    assert_eq!(kind, gltf::accessor::DataType::U8);
    assert!(
        values
            .iter()
            .zip(&mesh.charts)
            .all(|(a, &b)| *a == f64::from(b))
    );
    // Ids past 255 (a mesh of more than 256 charts) are stored as f32, exactly.
    let mut many = mesh.clone();
    for (i, c) in many.charts.iter_mut().enumerate() {
        *c = (i % 300) as u32;
    }
    assert_eq!(export::chart_component(&many), ChartComponent::F32);
    let bytes = write(&many, Format::Glb, Encoding::Binary);
    let (kind, values) = glb_charts(&bytes);
    assert_eq!(kind, gltf::accessor::DataType::F32);
    assert!(
        values
            .iter()
            .zip(&many.charts)
            .all(|(a, &b)| *a == f64::from(b))
    );
    gltf::Gltf::from_slice(&bytes).unwrap();
}

#[test]
fn one_object_name_in_every_format_that_stores_one() {
    let mesh = &meshes()[2];
    let named = |encoding| ExportOptions {
        name: Some("torus\nof \"two\" <holes>".into()),
        encoding,
        ..ExportOptions::default()
    };
    // Control characters become spaces.
    let name = "torus of \"two\" <holes>";
    assert_eq!(named(Encoding::Binary).object_name(2), name);
    assert_eq!(
        ExportOptions::default().object_name(2),
        "ntori genus-2 surface"
    );
    let long = ExportOptions {
        name: Some("x".repeat(1000)),
        ..ExportOptions::default()
    };
    assert_eq!(long.object_name(2).len(), export::MAX_NAME_CHARS);
    let text = |format, encoding| {
        String::from_utf8_lossy(&write_with(mesh, format, &named(encoding))).into_owned()
    };
    assert!(text(Format::Obj, Encoding::Binary).contains(&format!("\no {name}\n")));
    assert!(text(Format::Ply, Encoding::Ascii).contains(&format!("\ncomment object: {name}\n")));
    assert!(text(Format::Off, Encoding::Binary).contains(&format!("\n# {name}\n")));
    let stl = text(Format::Stl, Encoding::Ascii);
    assert!(stl.starts_with(&format!("solid {name}\n")));
    assert!(stl.ends_with(&format!("endsolid {name}\n")));
    assert!(text(Format::Stl, Encoding::Binary).starts_with(name));
    let glb = write_with(mesh, Format::Glb, &named(Encoding::Binary));
    let gltf = gltf::Gltf::from_slice(&glb).unwrap();
    assert_eq!(gltf.nodes().next().unwrap().name(), Some(name));
    assert_eq!(gltf.meshes().next().unwrap().name(), Some(name));
    let package = read_3mf(&write_with(mesh, Format::ThreeMf, &named(Encoding::Binary)));
    let doc = roxmltree::Document::parse(&package.model).unwrap();
    let object = doc
        .descendants()
        .find(|n| n.has_tag_name("object"))
        .unwrap();
    assert_eq!(object.attribute("name"), Some(name));
    // A binary STL header never starts with "solid" (readers would take the file for text).
    let solid = ExportOptions {
        name: Some("solid torus".into()),
        ..ExportOptions::default()
    };
    assert!(write_with(mesh, Format::Stl, &solid).starts_with(b"_solid torus"));
}

// ----------------------------------------------------------------------------------- 3MF

/// A 3MF package's parts, as text.
struct Package {
    names: Vec<String>,
    content_types: String,
    relationships: String,
    model: String,
}

fn read_3mf(bytes: &[u8]) -> Package {
    use std::io::Read as _;
    let mut zip = zip::ZipArchive::new(Cursor::new(bytes)).unwrap();
    let names = zip.file_names().map(|n| n.unwrap().into_owned()).collect();
    let mut part = |name: &str| {
        let mut text = String::new();
        zip.by_name(name)
            .unwrap()
            .read_to_string(&mut text)
            .unwrap();
        text
    };
    Package {
        content_types: part("[Content_Types].xml"),
        relationships: part("_rels/.rels"),
        model: part(export::MODEL_PART),
        names,
    }
}

#[test]
fn threemf_is_a_package_of_one_object_in_millimetres() {
    const CORE: &str = "http://schemas.microsoft.com/3dmanufacturing/core/2015/02";
    for mesh in meshes() {
        let what = format!("3MF genus {}", mesh.genus);
        let options = ExportOptions {
            scale: 3.0,
            units: Units::In,
            ..ExportOptions::default()
        };
        let bytes = write_with(mesh, Format::ThreeMf, &options);
        // The same mesh gives the same bytes (no time stamps).
        assert_eq!(bytes, write_with(mesh, Format::ThreeMf, &options), "{what}");
        let package = read_3mf(&bytes);
        let mut names = package.names.clone();
        names.sort();
        assert_eq!(
            names,
            ["3D/3dmodel.model", "[Content_Types].xml", "_rels/.rels"],
            "{what}"
        );
        let types = roxmltree::Document::parse(&package.content_types).unwrap();
        let defaults: Vec<(&str, &str)> = types
            .descendants()
            .filter(|n| n.has_tag_name("Default"))
            .map(|n| {
                (
                    n.attribute("Extension").unwrap(),
                    n.attribute("ContentType").unwrap(),
                )
            })
            .collect();
        assert!(defaults.contains(&(
            "model",
            "application/vnd.ms-package.3dmanufacturing-3dmodel+xml"
        )));
        assert!(defaults.contains(&(
            "rels",
            "application/vnd.openxmlformats-package.relationships+xml"
        )));
        let rels = roxmltree::Document::parse(&package.relationships).unwrap();
        let rel = rels
            .descendants()
            .find(|n| n.has_tag_name("Relationship"))
            .unwrap();
        assert_eq!(rel.attribute("Target"), Some("/3D/3dmodel.model"));
        assert_eq!(
            rel.attribute("Type"),
            Some("http://schemas.microsoft.com/3dmanufacturing/2013/01/3dmodel")
        );

        let doc = roxmltree::Document::parse(&package.model).unwrap();
        let model = doc.root_element();
        assert_eq!(model.tag_name().namespace(), Some(CORE));
        assert_eq!(model.tag_name().name(), "model");
        assert_eq!(model.attribute("unit"), Some("millimeter"));
        let objects: Vec<_> = doc
            .descendants()
            .filter(|n| n.has_tag_name("object"))
            .collect();
        assert_eq!(objects.len(), 1, "{what}");
        assert_eq!(objects[0].attribute("type"), Some("model"));
        let id = objects[0].attribute("id").unwrap();
        let items: Vec<_> = doc
            .descendants()
            .filter(|n| n.has_tag_name("item"))
            .collect();
        assert_eq!(items.len(), 1);
        assert_eq!(items[0].attribute("objectid"), Some(id));
        let number =
            |n: &roxmltree::Node, k: &str| -> f64 { n.attribute(k).unwrap().parse().unwrap() };
        let read = ReadBack {
            positions: doc
                .descendants()
                .filter(|n| n.has_tag_name("vertex"))
                .map(|n| Point3::new(number(&n, "x"), number(&n, "y"), number(&n, "z")))
                .collect(),
            normals: None,
            triangles: doc
                .descendants()
                .filter(|n| n.has_tag_name("triangle"))
                .map(|n| ["v1", "v2", "v3"].map(|k| n.attribute(k).unwrap().parse().unwrap()))
                .collect(),
        };
        // In millimetres: a model unit is 3 inches, 76.2 mm; z up.
        let expected = mesh.placed(Up::Z, 76.2);
        assert_identity(&check(&read, &expected, &what), &what);
    }
}

// ------------------------------------------------------------------------------- UV atlas

#[test]
fn the_uv_atlas_gives_each_chart_its_own_tile_and_splits_the_seams() {
    let (te, tr) = (6, 5);
    for model in models() {
        let genus = model.genus();
        let what = format!("atlas genus {genus}");
        let chart_mode = surface_mesh(model, (te, tr), UvLayout::Chart).unwrap();
        let mesh = surface_mesh(model, (te, tr), UvLayout::Atlas).unwrap();
        assert_eq!(mesh.uv_layout, UvLayout::Atlas);
        let t = model.atlas().tessellate(te, tr).unwrap();
        let charts = model.atlas().charts().len();
        let layout = UvAtlas::new(&ChartMesh::from(&t), charts);

        // Tiles are disjoint squares inside [0, 1]².
        let tiles: Vec<_> = (0..charts as u32).map(|c| layout.tile(c)).collect();
        for (a, (lo, hi)) in tiles.iter().enumerate() {
            assert!(
                lo.iter().chain(hi).all(|x| (0.0..=1.0).contains(x)),
                "{what}"
            );
            assert!(((hi[0] - lo[0]) - (hi[1] - lo[1])).abs() < 1e-15);
            for (blo, bhi) in &tiles[a + 1..] {
                let apart = (0..2).any(|k| hi[k] <= blo[k] || bhi[k] <= lo[k]);
                assert!(apart, "{what}: tiles overlap");
            }
        }

        // The same surface: the same triangles at the same positions, the first vertices the
        // originals, the others copies of them.
        assert_eq!(mesh.triangles.len(), chart_mode.triangles.len());
        assert!(
            mesh.positions.len() > chart_mode.positions.len(),
            "{what}: no seam split"
        );
        assert_eq!(
            mesh.positions[..chart_mode.positions.len()],
            chart_mode.positions[..]
        );
        for (a, b) in mesh.triangles.iter().zip(&chart_mode.triangles) {
            for j in 0..3 {
                assert_eq!(
                    mesh.positions[a[j] as usize],
                    chart_mode.positions[b[j] as usize]
                );
                assert_eq!(
                    mesh.normals[a[j] as usize],
                    chart_mode.normals[b[j] as usize]
                );
            }
        }
        assert!(export::signed_volume(&mesh.positions, &mesh.triangles) > 0.0);

        // Every triangle lies in its home chart's tile, inside the gutter, at its corners' home
        // chart coordinates; its vertices carry that chart: no vertex is shared across a seam.
        let gutter = export::atlas::GUTTER / layout.columns as f64;
        let mut area_signs = [0usize; 2];
        for (k, tri) in mesh.triangles.iter().enumerate() {
            let chart = t.triangle_charts[k];
            let (lo, hi) = layout.tile(chart.0);
            for &v in tri {
                assert_eq!(
                    mesh.charts[v as usize], chart.0,
                    "{what}: a vertex spans a seam"
                );
                let uv = mesh.uvs[v as usize];
                for i in 0..2 {
                    assert!(
                        uv[i] >= lo[i] + gutter * 0.999 && uv[i] <= hi[i] - gutter * 0.999,
                        "{what}: {uv:?} outside its tile {lo:?}..{hi:?}"
                    );
                }
            }
            // The corners' coordinates in the triangle's chart, placed in its tile (the
            // tessellation's corner order; orientation may have swapped corners 1 and 2).
            let expected = t.triangle_coords[k].map(|w| layout.uv(chart.0, w));
            let got = tri.map(|v| mesh.uvs[v as usize]);
            let same = |order: [usize; 3]| {
                (0..3).all(|j| {
                    (got[j][0] - expected[order[j]][0]).abs() < 1e-12
                        && (got[j][1] - expected[order[j]][1]).abs() < 1e-12
                })
            };
            assert!(same([0, 1, 2]) || same([0, 2, 1]), "{what}: triangle {k}");
            let [a, b, c] = got;
            let area = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
            assert!(area != 0.0, "{what}: triangle {k} has no area in the atlas");
            area_signs[usize::from(area > 0.0)] += 1;
        }
        // No triangle is flipped in the atlas: all wind the same way there.
        assert!(area_signs.contains(&0), "{what}: {area_signs:?}");
    }
}

#[test]
fn the_atlas_reads_back_split_and_the_chart_mode_whole() {
    let model = crate::common::small_model(2);
    let mesh = surface_mesh(model, (4, 4), UvLayout::Atlas).unwrap();
    let options = ExportOptions {
        uv: UvLayout::Atlas,
        ..ExportOptions::default()
    };
    // OBJ through tobj: vertices and UVs as written; split at the seams, the mesh has boundaries
    // where the charts meet, and welding by position closes it.
    let (read, uvs) = obj(&write_with(&mesh, Format::Obj, &options));
    assert_eq!(read.positions.len(), mesh.positions.len());
    assert_eq!(uvs.len(), mesh.uvs.len());
    let topology =
        HalfEdgeMesh::from_polygons(read.positions.len(), read.triangles.iter().map(|t| &t[..]))
            .unwrap()
            .topology();
    assert!(!topology.closed);
    let chart_mode = surface_mesh(model, (4, 4), UvLayout::Chart).unwrap();
    // Each vertex replaced by the first at its position, then numbered densely.
    let mut number = std::collections::HashMap::new();
    let welded: Vec<[u32; 3]> = read
        .triangles
        .iter()
        .map(|t| {
            t.map(|v| {
                let p = read.positions[v as usize];
                let first = read.positions.iter().position(|q| *q == p).unwrap();
                let next = number.len() as u32;
                *number.entry(first).or_insert(next)
            })
        })
        .collect();
    assert_eq!(number.len(), chart_mode.positions.len());
    let topology = HalfEdgeMesh::from_polygons(number.len(), welded.iter().map(|t| &t[..]))
        .unwrap()
        .topology();
    assert!(topology.closed && topology.manifold);
    assert_eq!(topology.euler_characteristic, -2);
}

/// `Meshing::Quads` writes quads to OBJ, PLY and OFF, read back as quads by tobj (not
/// triangulating), ply-rs-bw's parser and the OFF parser here: a closed, manifold polygon mesh of
/// the right χ whose quads face outward; the formats without polygons refuse it.
#[test]
fn quads_read_back_as_quads_and_only_where_a_format_has_polygons() {
    use ply_rs_bw::parser::Parser;
    use ply_rs_bw::ply::{DefaultElement, Property};

    for genus in [0, 2, 3] {
        let surface = crate::common::small_model(genus);
        let mesh = export::quad_surface_mesh(surface, 0.002, UvLayout::Chart).unwrap();
        assert!(mesh.quads);
        let quads = mesh.quad_faces();
        assert_eq!(2 * quads.len(), mesh.triangles.len());
        assert_eq!(mesh.face_count(), format!("{} quads", quads.len()));
        let check_quads = |faces: &[Vec<u32>], positions: usize, what: &str| {
            assert_eq!(faces.len(), quads.len(), "{what}");
            assert!(faces.iter().all(|f| f.len() == 4), "{what}");
            let topology = HalfEdgeMesh::from_polygons(positions, faces.iter().map(|f| &f[..]))
                .unwrap()
                .topology();
            assert!(
                topology.closed && topology.manifold && topology.orientable,
                "{what}"
            );
            assert_eq!(
                topology.euler_characteristic,
                2 - 2 * genus as i64,
                "{what}"
            );
        };
        // Each quad faces the way its corners' normals do (its diagonals' cross product).
        for f in &quads {
            let p = f.map(|i| mesh.positions[i as usize]);
            let n = (p[2] - p[0]).cross(&(p[3] - p[1]));
            let m: Vector3 = f.iter().map(|&i| mesh.normals[i as usize]).sum();
            assert!(n.dot(&m) > 0.0, "genus {genus}: a quad faces inward");
        }
        // OBJ through tobj, faces kept as written.
        let bytes = write(&mesh, Format::Obj, Encoding::Binary);
        let options = tobj::LoadOptions {
            single_index: true,
            triangulate: false,
            ..Default::default()
        };
        let (models, _) =
            tobj::load_obj_buf(&mut Cursor::new(&bytes), &options, |_| unreachable!()).unwrap();
        let m = &models[0].mesh;
        assert!(m.face_arities.iter().all(|&a| a == 4), "OBJ genus {genus}");
        let faces: Vec<Vec<u32>> = m.indices.chunks(4).map(<[u32]>::to_vec).collect();
        check_quads(&faces, m.positions.len() / 3, &format!("OBJ genus {genus}"));
        // PLY through its parser.
        let bytes = write(&mesh, Format::Ply, Encoding::Binary);
        let ply = Parser::<DefaultElement>::new()
            .read_ply(&mut Cursor::new(&bytes))
            .unwrap();
        let faces: Vec<Vec<u32>> = ply.payload["face"]
            .iter()
            .map(|e| match e.get("vertex_indices") {
                Some(Property::ListInt(l)) => l.iter().map(|&i| i as u32).collect(),
                other => panic!("PLY genus {genus}: face is {other:?}"),
            })
            .collect();
        check_quads(
            &faces,
            ply.payload["vertex"].len(),
            &format!("PLY genus {genus}"),
        );
        assert_eq!(faces, quads.iter().map(|q| q.to_vec()).collect::<Vec<_>>());
        // OFF: "4 a b c d" lines.
        let bytes = write(&mesh, Format::Off, Encoding::Binary);
        let text = String::from_utf8(bytes).unwrap();
        let faces: Vec<Vec<u32>> = text
            .lines()
            .filter(|l| l.starts_with("4 "))
            .map(|l| {
                l.split_whitespace()
                    .skip(1)
                    .map(|x| x.parse().unwrap())
                    .collect()
            })
            .collect();
        check_quads(&faces, mesh.positions.len(), &format!("OFF genus {genus}"));
        for format in [Format::Stl, Format::Glb, Format::ThreeMf] {
            let err = export::write_to(
                &mesh,
                format,
                &ExportOptions::default(),
                &mut Cursor::new(Vec::new()),
            )
            .unwrap_err();
            assert!(
                matches!(err, ExportError::NoQuads(f) if f == format),
                "{err}"
            );
        }
    }
}
