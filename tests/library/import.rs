//! Mesh import (issue 14): every format read back from the project's own exporters and from small
//! inline files, one test per error class with the message a user sees, and mutated files that
//! never make a reader or the validation panic.

use std::io::Cursor;

use embedding::Point3;
use ntori::io::export::{self, Encoding, ExportOptions, Format, SurfaceMesh, UvLayout};
use ntori::io::import::{
    ImportError, ImportedMesh, MeshFormat, ValidMesh, read_mesh, read_mesh_bytes, triangulate,
    validate,
};

use crate::common::small_model;

// ------------------------------------------------------------------------------------- helpers

/// The exporters' mesh of the small model of `genus`, coarse.
fn surface(genus: u32, uv: UvLayout) -> SurfaceMesh {
    export::surface_mesh(small_model(genus), (3, 3), uv).unwrap()
}

fn exported(mesh: &SurfaceMesh, format: Format, encoding: Encoding) -> Vec<u8> {
    let options = ExportOptions {
        encoding: if matches!(format, Format::Ply | Format::Stl) {
            encoding
        } else {
            Encoding::default()
        },
        ..ExportOptions::default()
    };
    let mut out = Cursor::new(Vec::new());
    export::write_to(mesh, format, &options, &mut out).unwrap();
    out.into_inner()
}

/// The positions a `format` file holds of `mesh` (turned to its up axis, scaled, rounded to f32).
fn stored_positions(mesh: &SurfaceMesh, format: Format) -> Vec<Point3> {
    let options = ExportOptions::default();
    let placed = mesh.placed(options.up_for(format), options.factor_for(format));
    placed
        .positions
        .iter()
        .map(|p| p.map(|x| f64::from(x as f32)))
        .collect()
}

/// Positions as f32 (text files write f32 values' shortest decimals), sorted.
fn sorted(points: &[Point3]) -> Vec<[f32; 3]> {
    let mut v: Vec<[f32; 3]> = points
        .iter()
        .map(|p| [p.x as f32, p.y as f32, p.z as f32])
        .collect();
    v.sort_by(|a, b| a.partial_cmp(b).unwrap());
    v
}

fn message(result: Result<ValidMesh, ImportError>) -> String {
    let err = result.expect_err("an error");
    eprintln!("{err}");
    err.to_string()
}

fn read_error(bytes: &[u8], format: MeshFormat) -> String {
    let err = read_mesh_bytes(bytes, format).expect_err("an error");
    eprintln!("{err}");
    err.to_string()
}

fn imported(positions: &[[f64; 3]], triangles: &[[u32; 3]]) -> ImportedMesh {
    ImportedMesh {
        positions: positions.iter().map(|&p| Point3::from(p)).collect(),
        triangles: triangles.to_vec(),
        ..ImportedMesh::default()
    }
}

const TETRA_POINTS: [[f64; 3]; 4] = [
    [0.0, 0.0, 0.0],
    [1.0, 0.0, 0.0],
    [0.0, 1.0, 0.0],
    [0.0, 0.0, 1.0],
];
/// Outward (counter-clockwise seen from outside).
const TETRA: [[u32; 3]; 4] = [[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]];

fn tetra() -> ImportedMesh {
    imported(&TETRA_POINTS, &TETRA)
}

/// `mesh` and a copy of it moved by `dx` along x, in one mesh.
fn twice(mesh: &ImportedMesh, dx: f64) -> ImportedMesh {
    let n = mesh.positions.len() as u32;
    let mut out = mesh.clone();
    out.positions.extend(
        mesh.positions
            .iter()
            .map(|p| p + embedding::Vector3::new(dx, 0.0, 0.0)),
    );
    out.triangles
        .extend(mesh.triangles.iter().map(|t| t.map(|v| v + n)));
    out
}

/// A closed surface of genus `holes`: a square slab with `holes` square holes through it (top,
/// bottom, outer walls and a wall around each hole), counter-clockwise seen from outside.
fn slab(holes: usize) -> ImportedMesh {
    let columns = (holes as f64).sqrt().ceil().max(1.0) as usize;
    let rows = holes.div_ceil(columns).max(1);
    let (w, h) = (2 * columns + 1, 2 * rows + 1);
    let hole = |i: usize, j: usize| i % 2 == 1 && j % 2 == 1 && (j / 2) * columns + i / 2 < holes;
    let id =
        |i: usize, j: usize, top: bool| -> u32 { (((j * (w + 1)) + i) * 2 + top as usize) as u32 };
    let mut positions = Vec::new();
    for j in 0..=h {
        for i in 0..=w {
            for z in [0.0, 1.0] {
                positions.push([i as f64, j as f64, z]);
            }
        }
    }
    let mut triangles = Vec::new();
    let mut quad = |q: [u32; 4]| {
        triangles.push([q[0], q[1], q[2]]);
        triangles.push([q[0], q[2], q[3]]);
    };
    let solid = |i: isize, j: isize| {
        i >= 0 && j >= 0 && (i as usize) < w && (j as usize) < h && !hole(i as usize, j as usize)
    };
    for j in 0..h {
        for i in 0..w {
            if !solid(i as isize, j as isize) {
                continue;
            }
            let (a, b, c, d) = ((i, j), (i + 1, j), (i + 1, j + 1), (i, j + 1));
            quad([
                id(a.0, a.1, true),
                id(b.0, b.1, true),
                id(c.0, c.1, true),
                id(d.0, d.1, true),
            ]);
            quad([
                id(a.0, a.1, false),
                id(d.0, d.1, false),
                id(c.0, c.1, false),
                id(b.0, b.1, false),
            ]);
            // Walls where the neighbour is not solid: the square's side, run counter-clockwise
            // around the square, faces out of it.
            let (si, sj) = (i as isize, j as isize);
            for (neighbour, (p, q)) in [
                ((si, sj - 1), (a, b)),
                ((si + 1, sj), (b, c)),
                ((si, sj + 1), (c, d)),
                ((si - 1, sj), (d, a)),
            ] {
                if !solid(neighbour.0, neighbour.1) {
                    quad([
                        id(p.0, p.1, false),
                        id(q.0, q.1, false),
                        id(q.0, q.1, true),
                        id(p.0, p.1, true),
                    ]);
                }
            }
        }
    }
    imported(&positions, &triangles)
}

// ------------------------------------------------------------------------------------ reading

#[test]
fn every_format_reads_back_the_exporters_meshes() {
    for genus in 0..=2 {
        let mesh = surface(genus, UvLayout::Chart);
        for (format, encoding, ours) in [
            (Format::Obj, Encoding::Ascii, MeshFormat::Obj),
            (Format::Ply, Encoding::Binary, MeshFormat::Ply),
            (Format::Ply, Encoding::Ascii, MeshFormat::Ply),
            (Format::Off, Encoding::Ascii, MeshFormat::Off),
            (Format::Stl, Encoding::Binary, MeshFormat::Stl),
            (Format::Stl, Encoding::Ascii, MeshFormat::Stl),
            (Format::Glb, Encoding::Binary, MeshFormat::Glb),
        ] {
            let what = format!("{format:?} {encoding:?} genus {genus}");
            let bytes = exported(&mesh, format, encoding);
            let read = read_mesh_bytes(&bytes, ours).unwrap_or_else(|e| panic!("{what}: {e}"));
            assert_eq!(read.triangles.len(), mesh.triangles.len(), "{what}");
            if format == Format::Stl {
                // Every corner apart in the file, merged back to the surface's vertices.
                assert_eq!(
                    read.merged_vertices,
                    3 * mesh.triangles.len() - mesh.positions.len(),
                    "{what}"
                );
            }
            let expected = stored_positions(&mesh, format);
            assert!(
                sorted(&read.positions) == sorted(&expected),
                "{what}: positions differ"
            );
            let valid = validate(read, false).unwrap_or_else(|e| panic!("{what}: {e}"));
            assert_eq!(valid.genus, genus, "{what}");
            assert!(!valid.flipped, "{what}: the exports are outward");
            assert_eq!(valid.reoriented_triangles, 0, "{what}");
            assert_eq!(valid.positions.len(), mesh.positions.len(), "{what}");
        }
    }
}

/// Our OBJ reader and tobj agree on the exporters' files (tobj reads f32).
#[test]
fn obj_agrees_with_tobj() {
    let mesh = surface(2, UvLayout::Chart);
    let bytes = exported(&mesh, Format::Obj, Encoding::Ascii);
    let ours = read_mesh_bytes(&bytes, MeshFormat::Obj).unwrap();
    let options = tobj::LoadOptions {
        single_index: false,
        triangulate: false,
        ..Default::default()
    };
    let (models, _) =
        tobj::load_obj_buf(&mut Cursor::new(&bytes), &options, |_| unreachable!()).unwrap();
    let m = &models[0].mesh;
    // tobj numbers vertices in the order the faces first use them: compare corner by corner.
    let theirs = |v: u32| {
        let k = 3 * v as usize;
        [m.positions[k], m.positions[k + 1], m.positions[k + 2]]
    };
    let corners: Vec<[f32; 3]> = m.indices.iter().map(|&v| theirs(v)).collect();
    let ours_corners: Vec<[f32; 3]> = ours
        .triangles
        .iter()
        .flatten()
        .map(|&v| ours.positions[v as usize].coords.map(|x| x as f32).into())
        .collect();
    assert!(ours_corners == corners, "the corners differ");
}

/// glTF with the atlas layout splits vertices at chart seams; merged, the mesh is closed again.
#[test]
fn glb_split_at_seams_merges_back_into_a_closed_mesh() {
    for genus in [1, 2] {
        let mesh = surface(genus, UvLayout::Atlas);
        let bytes = exported(&mesh, Format::Glb, Encoding::Binary);
        let read = read_mesh_bytes(&bytes, MeshFormat::Glb).unwrap();
        assert!(read.merged_vertices > 0, "the atlas splits at seams");
        let valid = validate(read, false).unwrap();
        assert_eq!(valid.genus, genus);
    }
}

#[test]
fn binary_stl_of_a_closed_mesh_merges_back_closed() {
    let mut bytes = vec![b' '; 80];
    bytes.extend_from_slice(&(TETRA.len() as u32).to_le_bytes());
    for t in TETRA {
        bytes.extend_from_slice(&[0u8; 12]);
        for v in t {
            for x in TETRA_POINTS[v as usize] {
                bytes.extend_from_slice(&(x as f32).to_le_bytes());
            }
        }
        bytes.extend_from_slice(&[0, 0]);
    }
    let read = read_mesh_bytes(&bytes, MeshFormat::Stl).unwrap();
    assert_eq!((read.positions.len(), read.merged_vertices), (4, 8));
    let valid = validate(read, false).unwrap();
    assert_eq!((valid.genus, valid.triangles.len()), (0, 4));
}

const CUBE_POINTS: &str = "0 0 0\n1 0 0\n1 1 0\n0 1 0\n0 0 1\n1 0 1\n1 1 1\n0 1 1\n";
/// The cube's faces, counter-clockwise seen from outside, from 0.
const CUBE_QUADS: [[u32; 4]; 6] = [
    [0, 3, 2, 1],
    [4, 5, 6, 7],
    [0, 1, 5, 4],
    [1, 2, 6, 5],
    [2, 3, 7, 6],
    [3, 0, 4, 7],
];

#[test]
fn a_cube_of_six_quads_triangulates_to_twelve_triangles() {
    let mut obj = String::from("# a cube\no cube\n");
    for line in CUBE_POINTS.lines() {
        obj += &format!("v {line}\n");
    }
    for q in CUBE_QUADS {
        let [a, b, c, d] = q.map(|v| v + 1);
        obj += &format!("f {a}/1/1 {b}//2 {c} {d}/4\n");
    }
    let mut off = format!("OFF\n# a cube\n8 6 12\n{CUBE_POINTS}");
    for [a, b, c, d] in CUBE_QUADS {
        off += &format!("4 {a} {b} {c} {d} 255 0 0\n");
    }
    for (bytes, format) in [(obj, MeshFormat::Obj), (off, MeshFormat::Off)] {
        let read = read_mesh_bytes(bytes.as_bytes(), format).unwrap();
        assert_eq!((read.triangles.len(), read.triangulated_polygons), (12, 6));
        let valid = validate(read, false).unwrap();
        assert_eq!((valid.genus, valid.triangles.len()), (0, 12));
        assert!(!valid.flipped);
    }
}

#[test]
fn off_headers_and_obj_negative_indices() {
    for header in ["COFF\n", "NOFF\n", "STCNOFF\n", ""] {
        let text = format!(
            "{header}4 4 6\n0 0 0 1\n1 0 0 1\n0 1 0 1\n0 0 1 1\n3 0 2 1\n3 0 1 3\n3 1 2 3\n3 0 3 2\n"
        );
        let read = read_mesh_bytes(text.as_bytes(), MeshFormat::Off).unwrap();
        assert_eq!(validate(read, false).unwrap().genus, 0, "{header:?}");
    }
    let obj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf -4 -2 -3\nf -4 -3 -1\nf 2 3 \\\n 4\nf 1 4 3\n";
    let read = read_mesh_bytes(obj.as_bytes(), MeshFormat::Obj).unwrap();
    assert_eq!(read.triangles, TETRA);
}

/// A non-convex polygon (an L) is cut into triangles inside it, all turning its way.
#[test]
fn non_convex_polygons_are_ear_clipped() {
    let l = [
        [0.0, 0.0, 0.0],
        [2.0, 0.0, 0.0],
        [2.0, 1.0, 0.0],
        [1.0, 1.0, 0.0],
        [1.0, 2.0, 0.0],
        [0.0, 2.0, 0.0],
    ];
    // Tilted out of every axis plane.
    let positions: Vec<Point3> = l
        .iter()
        .map(|&[x, y, _]| Point3::new(x + 0.3 * y, y, 0.5 * x - 0.2 * y))
        .collect();
    let polygon = [0u32, 1, 2, 3, 4, 5];
    let triangles = triangulate(&positions, &polygon);
    assert_eq!(triangles.len(), 4);
    let flat = |v: u32| [l[v as usize][0], l[v as usize][1]];
    let mut area = 0.0;
    for t in &triangles {
        let [a, b, c] = t.map(flat);
        let doubled = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
        assert!(doubled > 0.0, "{t:?} turns the wrong way or is empty");
        area += doubled / 2.0;
    }
    assert!(
        (area - 3.0).abs() < 1e-12,
        "the L's area is 3, the triangles cover {area}"
    );
}

#[test]
fn gltf_node_transforms_are_applied() {
    // A tetrahedron in a .gltf whose buffer is a data: URI, instanced twice: once moved, once
    // mirrored (the winding is reversed with it).
    let mut data = Vec::new();
    for p in TETRA_POINTS {
        for x in p {
            data.extend_from_slice(&(x as f32).to_le_bytes());
        }
    }
    for t in TETRA {
        for v in t {
            data.extend_from_slice(&(v as u16).to_le_bytes());
        }
    }
    let b64 = base64(&data);
    let json = format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0,1]}}],
        "nodes":[{{"mesh":0,"translation":[5,0,0]}},{{"children":[2],"scale":[-1,1,1]}},{{"mesh":0}}],
        "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}},"indices":1}}]}}],
        "accessors":[{{"bufferView":0,"componentType":5126,"count":4,"type":"VEC3"}},
                     {{"bufferView":1,"componentType":5123,"count":12,"type":"SCALAR"}}],
        "bufferViews":[{{"buffer":0,"byteLength":48}},{{"buffer":0,"byteOffset":48,"byteLength":24}}],
        "buffers":[{{"byteLength":{},"uri":"data:application/octet-stream;base64,{b64}"}}]}}"#,
        data.len()
    );
    let read = read_mesh_bytes(json.as_bytes(), MeshFormat::Glb).unwrap();
    assert_eq!((read.positions.len(), read.triangles.len()), (8, 8));
    assert!(read.positions.contains(&Point3::new(5.0, 0.0, 0.0)));
    assert!(read.positions.contains(&Point3::new(-1.0, 0.0, 0.0)));
    let valid = validate(read.clone(), true).unwrap();
    assert_eq!(valid.dropped_components, 1);
    // Both copies stay outward: nothing to reorient in either.
    assert_eq!((valid.reoriented_triangles, valid.flipped), (0, false));
}

fn base64(data: &[u8]) -> String {
    const A: &[u8] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::new();
    for chunk in data.chunks(3) {
        let b = [
            chunk[0],
            *chunk.get(1).unwrap_or(&0),
            *chunk.get(2).unwrap_or(&0),
        ];
        let n = (u32::from(b[0]) << 16) | (u32::from(b[1]) << 8) | u32::from(b[2]);
        for k in 0..=chunk.len() {
            out.push(A[(n >> (18 - 6 * k) & 63) as usize] as char);
        }
        for _ in chunk.len()..3 {
            out.push('=');
        }
    }
    out
}

// -------------------------------------------------------------------------------------- genus

#[test]
fn genus_of_a_tetrahedron_a_torus_and_a_genus_two_slab() {
    assert_eq!(validate(tetra(), false).unwrap().genus, 0);
    assert_eq!(validate(slab(0), false).unwrap().genus, 0);
    for g in [1, 2, 5] {
        let valid = validate(slab(g), false).unwrap();
        assert_eq!(valid.genus, g as u32);
        assert!(!valid.flipped && valid.reoriented_triangles == 0);
    }
}

#[test]
fn inside_out_and_inconsistent_meshes_are_oriented_outward() {
    let mut inside_out = slab(2);
    for t in &mut inside_out.triangles {
        t.swap(1, 2);
    }
    let valid = validate(inside_out, false).unwrap();
    assert!(valid.flipped);
    assert_eq!(valid.triangles, slab(2).triangles);
    let mut one_wrong = tetra();
    one_wrong.triangles[2].swap(0, 1);
    let valid = validate(one_wrong, false).unwrap();
    assert_eq!((valid.reoriented_triangles, valid.flipped), (1, false));
    // The same triangles, each perhaps starting at another corner.
    let canonical = |t: &[u32; 3]| {
        let k = (0..3).min_by_key(|&k| t[k]).unwrap();
        [t[k], t[(k + 1) % 3], t[(k + 2) % 3]]
    };
    let got: Vec<_> = valid.triangles.iter().map(canonical).collect();
    let want: Vec<_> = TETRA.iter().map(canonical).collect();
    assert_eq!(got, want);
}

// ---------------------------------------------------------------------- errors, one per class

#[test]
fn reading_errors_say_what_and_where() {
    let dir = tempfile::tempdir().unwrap();
    let unknown = dir.path().join("mesh.xyz");
    std::fs::write(&unknown, "").unwrap();
    let text = read_mesh(&unknown).unwrap_err().to_string();
    eprintln!("{text}");
    assert!(
        text.contains(
            "unknown mesh format `.xyz`; ntori reads .obj, .ply, .off, .stl, .glb and .gltf"
        ),
        "{text}"
    );
    let text = read_mesh(&dir.path().join("none.OBJ"))
        .unwrap_err()
        .to_string();
    eprintln!("{text}");
    assert!(text.contains("none.OBJ: no such file"), "{text}");
    // What the path is comes before its extension.
    let text = read_mesh(dir.path()).unwrap_err().to_string();
    assert!(
        text.contains("it is a directory, not a regular file"),
        "{text}"
    );
    let bare = dir.path().join("mesh");
    std::fs::write(&bare, "v 0 0 0\n").unwrap();
    let text = read_mesh(&bare).unwrap_err().to_string();
    assert!(text.contains("no extension"), "{text}");
    // An empty file is called empty, whatever its format.
    for format in [
        MeshFormat::Obj,
        MeshFormat::Ply,
        MeshFormat::Stl,
        MeshFormat::Glb,
    ] {
        assert_eq!(read_error(b"", format), "the file is empty (0 bytes)");
    }
    // A binary STL cut short is not taken for text because its header begins with `solid`.
    let mut solid = b"solid made by a tool".to_vec();
    solid.resize(90, 0);
    solid[80] = 2;
    assert_eq!(
        read_error(&solid, MeshFormat::Stl),
        "not a valid STL file (byte 80): binary STL of 2 triangles has 184 bytes, but the file has 90"
    );
    // ply-rs-bw's several-line errors become one line, with the line number as the location.
    let ply = b"ply\nformat ascii 1.0\nelement vertex 3\nproperty flaot x\nend_header\n";
    assert_eq!(
        read_error(ply, MeshFormat::Ply),
        "not a valid PLY file (line 4): couldn't parse line: `property flaot x`"
    );
    // A GLB whose magic is wrong is not parsed as JSON.
    assert_eq!(
        read_error(b"glTX\x02\0\0\0", MeshFormat::Glb),
        "not a valid glTF file (byte 0): it begins with `glTX`, but binary glTF (GLB) begins with `glTF` and glTF JSON with `{`"
    );
    // A format error names the file once.
    let bad = dir.path().join("bad.off");
    std::fs::write(&bad, "OFF\n3 1 0\n0 0 0\n1 0 x\n").unwrap();
    let text = read_mesh(&bad).unwrap_err().to_string();
    eprintln!("{text}");
    assert_eq!(text.matches("bad.off").count(), 1, "{text}");
    assert!(
        text.ends_with("not a valid OFF file (line 4): `x` is not a number"),
        "{text}"
    );

    let text = read_error(b"v 0 0 0\nv 1 0\n", MeshFormat::Obj);
    assert_eq!(
        text,
        "not a valid OBJ file (line 2): a vertex needs three coordinates, found 2"
    );
    let text = read_error(
        b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 9\n",
        MeshFormat::Obj,
    );
    assert_eq!(
        text,
        "face 1 (line 5) refers to vertex 9, but there are only 3 vertices"
    );
    let text = read_error(
        b"OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n",
        MeshFormat::Off,
    );
    assert_eq!(
        text,
        "face 0 (line 6) refers to vertex 3, but there are only 3 vertices"
    );
    let ply = b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 7\n";
    let text = read_error(ply, MeshFormat::Ply);
    assert_eq!(
        text,
        "face 0 refers to vertex 7, but there are only 3 vertices"
    );
    let text = read_error(b"v 0 0 0\nv 1 nan 0\nv 0 1 0\nf 1 2 3\n", MeshFormat::Obj);
    assert_eq!(
        text,
        "vertex 1 (line 2) has a coordinate that is not a finite number: 1, NaN, 0"
    );
    let text = read_error(b"# nothing\nv 0 0 0\n", MeshFormat::Obj);
    assert_eq!(text, "the OBJ file holds no faces");
    let text = read_error(b"solid x\nendsolid x\n", MeshFormat::Stl);
    assert_eq!(text, "the STL file holds no vertices");
    let text = read_error(b"solid x\n facet normal 0 0 1\n  outer loop\n   vertex 0 0 0\n   vertex 1 0 0\n  endloop\n endfacet\nendsolid\n", MeshFormat::Stl);
    assert_eq!(
        text,
        "not a valid STL file (line 7): a facet needs three vertices, found 2"
    );
    let mut short = [0u8; 90];
    short[80] = 2;
    let text = read_error(&short, MeshFormat::Stl);
    assert_eq!(
        text,
        "not a valid STL file (byte 80): binary STL of 2 triangles has 184 bytes, but the file has 90"
    );
    let text = read_error(
        b"{\"asset\": {\"version\": \"2.0\"},\n \"meshes\": [}",
        MeshFormat::Glb,
    );
    // The place once, not again at the end of serde_json's message.
    assert_eq!(
        text,
        "not a valid glTF file (line 2, column 13): expected value"
    );
    let text = read_error(b"4OFF\n", MeshFormat::Off);
    assert_eq!(
        text,
        "OFF: `4OFF` (only three-dimensional OFF is read) is not supported (line 1)"
    );
}

#[test]
fn several_components_are_refused_or_the_largest_kept() {
    let mesh = twice(&slab(1), 20.0);
    let mut three = mesh.clone();
    let n = three.positions.len() as u32;
    three.positions.extend(
        TETRA_POINTS
            .iter()
            .map(|&p| Point3::from(p) + embedding::Vector3::new(0.0, 0.0, -9.0)),
    );
    three
        .triangles
        .extend(TETRA.iter().map(|t| t.map(|v| v + n)));
    let text = message(validate(three.clone(), false));
    assert_eq!(
        text,
        "the mesh has 3 separate components (of 64, 64 and 4 triangles); pass --largest to fit the largest"
    );
    let valid = validate(three, true).unwrap();
    assert_eq!(
        (
            valid.dropped_components,
            valid.dropped_triangles,
            valid.genus
        ),
        (2, 68, 1)
    );
    assert_eq!(valid.triangles.len(), 64);
    // Every vertex used, indices compact.
    assert_eq!(valid.positions.len(), slab(1).positions.len());
    assert_eq!(
        valid.removed_vertices,
        mesh.positions.len() + 4 - valid.positions.len()
    );
}

#[test]
fn degenerate_triangles_are_located() {
    // A repeated vertex.
    let mut mesh = tetra();
    mesh.triangles.push([0, 3, 3]);
    let text = message(validate(mesh, false));
    assert_eq!(
        text,
        "the mesh has 1 degenerate triangle (zero area or a repeated vertex); the first is triangle 4, vertices 0 at (0, 0, 0), 3 at (0, 0, 1), 3 at (0, 0, 1)"
    );
    // Zero area: vertex 3 on the edge from 0 to 1.
    let mut flat = tetra();
    flat.positions[3] = Point3::new(0.5, 0.0, 0.0);
    let text = message(validate(flat, false));
    assert_eq!(
        text,
        "the mesh has 1 degenerate triangle (zero area or a repeated vertex); the first is triangle 1, vertices 0 at (0, 0, 0), 1 at (1, 0, 0), 3 at (0.5, 0, 0)"
    );
    // Every triangle: said so, not as one more count.
    let mut point = tetra();
    point.positions.fill(Point3::new(1.0, 2.0, 3.0));
    let text = message(validate(point, false));
    assert!(
        text.starts_with("all 4 triangles of the mesh are degenerate (zero area or a repeated vertex), so it has no surface to fit; the first is triangle 0"),
        "{text}"
    );
    let text = message(validate(imported(&TETRA_POINTS[..3], &[[0, 1, 1]]), false));
    assert!(
        text.starts_with("the mesh's one triangle is degenerate (zero area or a repeated vertex), so it has no surface to fit"),
        "{text}"
    );
}

#[test]
fn non_manifold_edges_are_located() {
    // Two tetrahedra sharing the edge from 0 to 1.
    let mut mesh = tetra();
    mesh.positions
        .extend([Point3::new(0.0, -1.0, 0.0), Point3::new(0.0, 0.0, -1.0)]);
    mesh.triangles
        .extend([[0, 1, 4], [0, 5, 1], [1, 5, 4], [0, 4, 5]]);
    let text = message(validate(mesh, false));
    assert_eq!(
        text,
        "the mesh has 1 non-manifold edge (more than two faces on one edge); the first joins vertex 0 at (0, 0, 0) and vertex 1 at (1, 0, 0) and has 4 faces"
    );
}

#[test]
fn non_manifold_vertices_are_located() {
    // Two tetrahedra touching at vertex 0.
    let mut mesh = tetra();
    mesh.positions.extend([
        Point3::new(-1.0, 0.0, 0.0),
        Point3::new(0.0, -1.0, 0.0),
        Point3::new(0.0, 0.0, -1.0),
    ]);
    mesh.triangles.extend(
        TETRA
            .iter()
            .map(|t| t.map(|v| if v == 0 { 0 } else { v + 3 })),
    );
    let text = message(validate(mesh, false));
    assert_eq!(
        text,
        "the mesh has 1 non-manifold vertex (its faces meet there but do not form one fan, like two cones touching at their tips); the first is vertex 0 at (0, 0, 0)"
    );
}

#[test]
fn holes_are_located() {
    let mut mesh = slab(1);
    mesh.triangles.drain(0..2);
    let text = message(validate(mesh.clone(), false));
    assert_eq!(
        text,
        "the mesh is not closed: it has 1 hole (boundary loop); the first runs through vertex 3 at (1, 0, 1) and has 4 edges"
    );
    // Every hole is located, up to four of them.
    let last = mesh.triangles.len() - 2;
    mesh.triangles.drain(last..);
    let text = message(validate(mesh, false));
    assert!(
        text.starts_with("the mesh is not closed: it has 2 holes (boundary loops); the first runs through vertex 3 at (1, 0, 1) and has 4 edges; the other runs through vertex "),
        "{text}"
    );
}

#[test]
fn non_orientable_meshes_are_located() {
    // The six-vertex projective plane: closed, every edge on two faces, no orientation.
    let positions = [
        [1.0, 0.1, 0.2],
        [-0.3, 1.0, 0.1],
        [-0.8, -0.6, 0.3],
        [0.2, -0.4, 1.0],
        [0.1, 0.3, -1.0],
        [0.6, 0.7, 0.5],
    ];
    let triangles = [
        [0, 1, 2],
        [0, 2, 3],
        [0, 3, 4],
        [0, 4, 5],
        [0, 5, 1],
        [1, 2, 4],
        [2, 3, 5],
        [3, 4, 1],
        [4, 5, 2],
        [5, 1, 3],
    ];
    let text = message(validate(imported(&positions, &triangles), false));
    assert!(text.starts_with("the mesh is not orientable (like a Möbius strip or a Klein bottle): its faces cannot agree on a side at the edge from vertex "), "{text}");
    assert!(
        text.contains(" at (") && text.contains(") to vertex "),
        "{text}"
    );
}

#[test]
fn genus_beyond_64_is_refused() {
    let text = message(validate(slab(65), false));
    assert_eq!(text, "the mesh has genus 65; ntori fits genus 0 to 64");
}

// ---------------------------------------------------------------------------------- fuzzing

/// Small valid files of every format, the seeds of the fuzzing.
fn seeds() -> Vec<(Vec<u8>, MeshFormat)> {
    let mesh = surface(1, UvLayout::Chart);
    let mut seeds: Vec<(Vec<u8>, MeshFormat)> = [
        (Format::Obj, Encoding::Ascii, MeshFormat::Obj),
        (Format::Ply, Encoding::Binary, MeshFormat::Ply),
        (Format::Ply, Encoding::Ascii, MeshFormat::Ply),
        (Format::Off, Encoding::Ascii, MeshFormat::Off),
        (Format::Stl, Encoding::Binary, MeshFormat::Stl),
        (Format::Stl, Encoding::Ascii, MeshFormat::Stl),
        (Format::Glb, Encoding::Binary, MeshFormat::Glb),
    ]
    .into_iter()
    .map(|(f, e, ours)| (exported(&mesh, f, e), ours))
    .collect();
    let mut off = format!("OFF\n8 6 12\n{CUBE_POINTS}");
    for [a, b, c, d] in CUBE_QUADS {
        off += &format!("4 {a} {b} {c} {d}\n");
    }
    seeds.push((off.into_bytes(), MeshFormat::Off));
    seeds.push((
        b"v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 2 3 4\nf 1 4 3\n".to_vec(),
        MeshFormat::Obj,
    ));
    seeds
}

#[derive(Clone, Debug)]
enum Mutation {
    FlipBit(proptest::sample::Index, u8),
    SetByte(proptest::sample::Index, u8),
    Insert(proptest::sample::Index, Vec<u8>),
    Delete(proptest::sample::Index, usize),
    Truncate(proptest::sample::Index),
    /// A span copied elsewhere.
    Splice(proptest::sample::Index, usize, proptest::sample::Index),
    /// A 4-byte little-endian word set to an interesting value (counts, offsets, indices).
    Word(proptest::sample::Index, u32),
}

fn mutation() -> impl proptest::strategy::Strategy<Value = Mutation> {
    use proptest::prelude::*;
    let interesting = prop_oneof![
        Just(0u32),
        Just(1),
        Just(3),
        Just(u32::MAX),
        Just(0x7fff_ffff),
        Just(0x7fc0_0000), // NaN as f32
        Just(0x7f80_0000), // inf
        any::<u32>()
    ];
    prop_oneof![
        (any::<proptest::sample::Index>(), 0u8..8).prop_map(|(i, b)| Mutation::FlipBit(i, b)),
        (any::<proptest::sample::Index>(), any::<u8>()).prop_map(|(i, b)| Mutation::SetByte(i, b)),
        (
            any::<proptest::sample::Index>(),
            proptest::collection::vec(
                prop_oneof![
                    Just(b'\n'),
                    Just(b' '),
                    Just(b'-'),
                    Just(b'/'),
                    Just(b'9'),
                    Just(b'#'),
                    Just(b'\\'),
                    any::<u8>()
                ],
                1..8
            )
        )
            .prop_map(|(i, b)| Mutation::Insert(i, b)),
        (any::<proptest::sample::Index>(), 1usize..64).prop_map(|(i, n)| Mutation::Delete(i, n)),
        any::<proptest::sample::Index>().prop_map(Mutation::Truncate),
        (
            any::<proptest::sample::Index>(),
            1usize..200,
            any::<proptest::sample::Index>()
        )
            .prop_map(|(f, n, t)| Mutation::Splice(f, n, t)),
        (any::<proptest::sample::Index>(), interesting).prop_map(|(i, w)| Mutation::Word(i, w)),
    ]
}

fn apply(bytes: &mut Vec<u8>, m: &Mutation) {
    if bytes.is_empty() {
        return;
    }
    let len = bytes.len();
    match m {
        Mutation::FlipBit(i, b) => bytes[i.index(len)] ^= 1 << b,
        Mutation::SetByte(i, b) => bytes[i.index(len)] = *b,
        Mutation::Insert(i, b) => {
            let at = i.index(len + 1);
            bytes.splice(at..at, b.iter().copied());
        }
        Mutation::Delete(i, n) => {
            let at = i.index(len);
            bytes.drain(at..(at + n).min(len));
        }
        Mutation::Truncate(i) => bytes.truncate(i.index(len)),
        Mutation::Splice(f, n, t) => {
            let from = f.index(len);
            let span: Vec<u8> = bytes[from..(from + n).min(len)].to_vec();
            let to = t.index(len + 1);
            bytes.splice(to..to, span);
        }
        Mutation::Word(i, w) => {
            if len >= 4 {
                let at = i.index(len - 3);
                bytes[at..at + 4].copy_from_slice(&w.to_le_bytes());
            }
        }
    }
}

/// Mutated mesh files (1 to 4 edits of a seed of any format) never make a reader or the validation
/// panic, and every refusal is one short message. NTORI_FUZZ_CASES sets the number of cases
/// (default 3000).
#[test]
fn fuzz_mesh_readers() {
    use proptest::strategy::Strategy as _;
    let cases: u32 = std::env::var("NTORI_FUZZ_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(3_000);
    let seeds = seeds();
    for (bytes, format) in &seeds {
        let read = read_mesh_bytes(bytes, *format).expect("a seed reads");
        validate(read, false).expect("a seed is valid");
    }
    let strategy = (
        proptest::sample::select((0..seeds.len()).collect::<Vec<_>>()),
        proptest::collection::vec(mutation(), 1..5),
    );
    let mut runner = proptest::test_runner::TestRunner::new(proptest::test_runner::Config {
        cases,
        failure_persistence: None,
        ..Default::default()
    });
    let outcomes = std::cell::RefCell::new(std::collections::BTreeMap::<String, u64>::new());
    let result = runner.run(&strategy.boxed(), |(seed, mutations)| {
        let (mut bytes, format) = seeds[seed].clone();
        for m in &mutations {
            apply(&mut bytes, m);
        }
        let outcome = std::panic::catch_unwind(|| {
            read_mesh_bytes(&bytes, format).and_then(|mesh| validate(mesh, true))
        })
        .map_err(|_| {
            proptest::test_runner::TestCaseError::fail(format!(
                "{format:?} panicked on {:?}",
                String::from_utf8_lossy(&bytes)
            ))
        })?;
        let key = match &outcome {
            Ok(_) => "accepted".to_owned(),
            Err(e) => {
                let text = e.to_string();
                proptest::prop_assert!(text.len() <= 1_000, "a long message: {}", text);
                proptest::prop_assert!(
                    !text.contains('\n'),
                    "a message of several lines: {}",
                    text
                );
                format!("{e:?}")
                    .split([' ', '(', '{'])
                    .next()
                    .unwrap()
                    .to_owned()
            }
        };
        *outcomes.borrow_mut().entry(key).or_default() += 1;
        Ok(())
    });
    eprintln!("fuzz_mesh_readers: outcomes {:?}", outcomes.into_inner());
    result.unwrap();
}

#[test]
fn the_dialog_extension_list_is_what_the_readers_take() {
    for extension in MeshFormat::EXTENSION_LIST {
        assert!(
            MeshFormat::from_extension(extension).is_some(),
            "{extension}"
        );
        assert!(
            MeshFormat::EXTENSIONS.contains(&format!(".{extension}")),
            "{extension}"
        );
    }
    assert_eq!(
        MeshFormat::EXTENSIONS.matches('.').count(),
        MeshFormat::EXTENSION_LIST.len()
    );
}

/// A mesh exported in any format and read back is placed where the model had it: the file's up
/// axis turned back to +z and its unit back to model units (centimetres), as `ntori fit` and the
/// editor's import place it. Every format, at several scales and units. Reading every format as +z
/// up and unscaled (the old import) fails it for all but PLY and OFF at 1 cm.
#[test]
fn an_exported_mesh_is_placed_back_where_the_model_had_it() {
    use export::{Units, Up};
    use ntori::io::import::Placement;
    let mesh = surface(2, UvLayout::Chart);
    for format in Format::ALL {
        for (scale, units) in [(1.0, Units::Cm), (2.5, Units::Mm), (0.1, Units::In)] {
            let options = ExportOptions {
                scale,
                units,
                ..ExportOptions::default()
            };
            let placed = mesh.placed(options.up_for(format), options.factor_for(format));
            let path = std::path::PathBuf::from(format!("part.{}", format.extension()));
            // Read with the same --units (which OBJ, PLY and OFF need: their numbers carry no
            // unit), the model comes back at its physical size in centimetres: as it was at a
            // scale of 1 cm, `scale` × `units` larger otherwise.
            let placement = Placement::for_file(&path, None, units);
            let mut back = placed.positions.clone();
            placement.place_points(&mut back);
            for (p, back) in mesh.positions.iter().zip(&back) {
                let (back, want) = (
                    back.coords,
                    p.coords * scale * units.metres() / Units::Cm.metres(),
                );
                assert!(
                    (back - want).norm() <= 1e-9 * want.norm().max(1.0),
                    "{format:?} {scale} {units:?}: {p:?} came back as {back:?}, want {want:?}"
                );
            }
            let up = Placement::for_file(&path, Some(Up::Z), units).up;
            assert_eq!(up, Up::Z, "--up overrides {format:?}'s axis");
        }
    }
}
