//! Stanford PLY, binary little endian or ASCII.

use std::io::Write;

use super::options::FileInfo;
use super::{Encoding, SurfaceMesh};

mod records {
    //! PLY records for ply-rs-bw's writer (its element type is a trait, so no hash maps).
    use ply_rs_bw::ply::PropertyAccess;

    #[derive(Clone, Copy, Debug, Default)]
    pub struct Vertex {
        pub position: [f32; 3],
        pub normal: [f32; 3],
        pub uv: [f32; 2],
        pub chart: u32,
    }

    impl PropertyAccess for Vertex {
        fn new() -> Self {
            Vertex::default()
        }
        fn get_float(&self, name: &str) -> Option<f32> {
            Some(match name {
                "x" => self.position[0],
                "y" => self.position[1],
                "z" => self.position[2],
                "nx" => self.normal[0],
                "ny" => self.normal[1],
                "nz" => self.normal[2],
                "s" => self.uv[0],
                "t" => self.uv[1],
                _ => return None,
            })
        }
        fn get_uint(&self, name: &str) -> Option<u32> {
            (name == "chart").then_some(self.chart)
        }
    }

    /// A triangle's or a quad's corners.
    #[derive(Clone, Debug, Default)]
    pub struct Face(pub Vec<i32>);

    impl PropertyAccess for Face {
        fn new() -> Self {
            Face::default()
        }
        fn get_list_int(&self, name: &str) -> Option<&[i32]> {
            (name == "vertex_indices").then_some(&self.0[..])
        }
    }
}

/// Stanford PLY, binary little endian or ASCII: vertex `x y z nx ny nz s t` (float; `s t` are the
/// texture coordinates, the names Blender and MeshLab read) and `chart` (uint); face
/// `vertex_indices` (list uchar int). The object's name, up axis and unit are comments.
pub fn write_ply(mesh: &SurfaceMesh, info: &FileInfo, out: &mut dyn Write) -> std::io::Result<()> {
    use ply_rs_bw::ply::{
        Addable, ElementDef, Encoding as PlyEncoding, Header, PropertyDef, PropertyType, ScalarType,
    };
    use ply_rs_bw::writer::Writer;

    let mut header = Header::new();
    header.encoding = match info.encoding {
        Encoding::Ascii => PlyEncoding::Ascii,
        Encoding::Binary => PlyEncoding::BinaryLittleEndian,
    };
    header.comments.push(format!("object: {}", info.name));
    header.comments.push(mesh.describe());
    header.comments.push(info.frame());
    header.comments.push(format!(
        "s t: {}; chart: the vertex's chart",
        mesh.describe_uvs()
    ));
    header
        .comments
        .push("nx ny nz: the analytic unit normal, outward".into());
    let mut vertex = ElementDef::new("vertex".into());
    vertex.count = mesh.positions.len();
    for name in ["x", "y", "z", "nx", "ny", "nz", "s", "t"] {
        vertex.properties.add(PropertyDef::new(
            name.into(),
            PropertyType::Scalar(ScalarType::Float),
        ));
    }
    vertex.properties.add(PropertyDef::new(
        "chart".into(),
        PropertyType::Scalar(ScalarType::UInt),
    ));
    let mut face = ElementDef::new("face".into());
    let corners = |f: &[u32]| records::Face(f.iter().map(|&i| i as i32).collect());
    let faces: Vec<records::Face> = if mesh.quads {
        mesh.quad_faces().iter().map(|q| corners(q)).collect()
    } else {
        mesh.triangles.iter().map(|t| corners(t)).collect()
    };
    face.count = faces.len();
    face.properties.add(PropertyDef::new(
        "vertex_indices".into(),
        PropertyType::List(ScalarType::UChar, ScalarType::Int),
    ));
    header.elements.add(vertex.clone());
    header.elements.add(face.clone());

    let mut out = out;
    let vertices: Vec<records::Vertex> = (0..mesh.positions.len())
        .map(|i| records::Vertex {
            position: mesh.position_f32(i),
            normal: mesh.normal_f32(i),
            uv: mesh.uvs[i].map(|x| x as f32),
            chart: mesh.charts[i],
        })
        .collect();
    let vertex_writer = Writer::<records::Vertex>::new();
    vertex_writer.write_header(&mut out, &header)?;
    vertex_writer.write_payload_of_element(&mut out, &vertices, &vertex, &header)?;
    drop(vertices);
    Writer::<records::Face>::new().write_payload_of_element(&mut out, &faces, &face, &header)?;
    Ok(())
}
