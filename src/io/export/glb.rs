//! Binary glTF 2.0.

use std::io::Write;

use super::{ExportError, SurfaceMesh};

/// The GLB BIN chunk's length: positions, normals (12 bytes a vertex each), texture coordinates
/// (8), charts (a u16 in a 4-byte stride) and indices (12 a triangle); all multiples of 4.
fn glb_bin_length(mesh: &SurfaceMesh) -> u64 {
    let v = mesh.positions.len() as u64;
    let f = mesh.triangles.len() as u64;
    36 * v + 12 * f
}

pub(super) fn glb_size(mesh: &SurfaceMesh) -> Result<u64, ExportError> {
    let bin = glb_bin_length(mesh);
    // The JSON is a few kilobytes.
    let total = 12 + 8 + 8192 + 8 + bin;
    if total > u64::from(u32::MAX) {
        return Err(ExportError::GlbTooLarge(total));
    }
    Ok(total)
}

/// The glTF JSON document describing the BIN chunk [`write_glb`] writes.
fn gltf_document(mesh: &SurfaceMesh) -> gltf_json::Root {
    use gltf_json as json;
    use json::accessor::{ComponentType, GenericComponentType, Type};
    use json::validation::Checked::Valid;
    use json::validation::USize64;

    let v = mesh.positions.len() as u64;
    let bin = glb_bin_length(mesh);
    let mut root = json::Root {
        asset: json::Asset {
            generator: Some(format!("ntori {}", env!("CARGO_PKG_VERSION"))),
            extras: json::extras::RawValue::from_string(
                serde_json::json!({
                    "ntori": {
                        "genus": mesh.genus,
                        "te": mesh.te,
                        "tr": mesh.tr,
                        "TEXCOORD_0": "home chart coordinates + 0.5, v flipped (glTF's convention)",
                        "_CHART": "home chart id",
                    }
                })
                .to_string(),
            )
            .ok(),
            ..Default::default()
        },
        ..Default::default()
    };
    let buffer = root.push(json::Buffer {
        byte_length: USize64(bin),
        name: None,
        uri: None,
        extensions: None,
        extras: Default::default(),
    });
    let mut offset = 0u64;
    let mut view = |root: &mut json::Root, length: u64, stride: Option<usize>, indices: bool| {
        let target = if indices {
            json::buffer::Target::ElementArrayBuffer
        } else {
            json::buffer::Target::ArrayBuffer
        };
        let index = root.push(json::buffer::View {
            buffer,
            byte_length: USize64(length),
            byte_offset: Some(USize64(offset)),
            byte_stride: stride.map(json::buffer::Stride),
            name: None,
            target: Some(Valid(target)),
            extensions: None,
            extras: Default::default(),
        });
        offset += length;
        index
    };
    let positions_view = view(&mut root, 12 * v, None, false);
    let normals_view = view(&mut root, 12 * v, None, false);
    let uvs_view = view(&mut root, 8 * v, None, false);
    let charts_view = view(&mut root, 4 * v, Some(4), false);
    let indices_view = view(&mut root, 12 * mesh.triangles.len() as u64, None, true);

    let accessor = |root: &mut json::Root,
                    view,
                    count: u64,
                    component: ComponentType,
                    type_: Type,
                    bounds: Option<([f32; 3], [f32; 3])>,
                    name: &str| {
        root.push(json::Accessor {
            buffer_view: Some(view),
            byte_offset: Some(USize64(0)),
            count: USize64(count),
            component_type: Valid(GenericComponentType(component)),
            type_: Valid(type_),
            min: bounds.map(|b| json::Value::from(b.0.to_vec())),
            max: bounds.map(|b| json::Value::from(b.1.to_vec())),
            name: Some(name.into()),
            normalized: false,
            sparse: None,
            extensions: None,
            extras: Default::default(),
        })
    };
    let mut min = [f32::INFINITY; 3];
    let mut max = [f32::NEG_INFINITY; 3];
    for i in 0..mesh.positions.len() {
        let p = mesh.position_f32(i);
        for k in 0..3 {
            min[k] = min[k].min(p[k]);
            max[k] = max[k].max(p[k]);
        }
    }
    let bounds = (!mesh.positions.is_empty()).then_some((min, max));
    let positions = accessor(
        &mut root,
        positions_view,
        v,
        ComponentType::F32,
        Type::Vec3,
        bounds,
        "positions",
    );
    let normals = accessor(
        &mut root,
        normals_view,
        v,
        ComponentType::F32,
        Type::Vec3,
        None,
        "normals",
    );
    let uvs = accessor(
        &mut root,
        uvs_view,
        v,
        ComponentType::F32,
        Type::Vec2,
        None,
        "home chart coordinates",
    );
    let charts = accessor(
        &mut root,
        charts_view,
        v,
        ComponentType::U16,
        Type::Scalar,
        None,
        "home charts",
    );
    let indices = accessor(
        &mut root,
        indices_view,
        3 * mesh.triangles.len() as u64,
        ComponentType::U32,
        Type::Scalar,
        None,
        "triangles",
    );
    let primitive = json::mesh::Primitive {
        attributes: [
            (json::mesh::Semantic::Positions, positions),
            (json::mesh::Semantic::Normals, normals),
            (json::mesh::Semantic::TexCoords(0), uvs),
            (json::mesh::Semantic::Extras("CHART".into()), charts),
        ]
        .into_iter()
        .map(|(s, a)| (Valid(s), a))
        .collect(),
        indices: Some(indices),
        material: None,
        mode: Valid(json::mesh::Mode::Triangles),
        targets: None,
        extensions: None,
        extras: Default::default(),
    };
    let name = format!("ntori genus {}", mesh.genus);
    let gltf_mesh = root.push(json::Mesh {
        name: Some(name.clone()),
        primitives: vec![primitive],
        weights: None,
        extensions: None,
        extras: Default::default(),
    });
    let node = root.push(json::Node {
        mesh: Some(gltf_mesh),
        name: Some(name),
        ..Default::default()
    });
    let scene = root.push(json::Scene {
        nodes: vec![node],
        name: None,
        extensions: None,
        extras: Default::default(),
    });
    root.scene = Some(scene);
    root
}

/// Binary glTF 2.0: one mesh, one triangle primitive with `POSITION`, `NORMAL`, `TEXCOORD_0`
/// (f32; v flipped as glTF's texture origin is the top left), `_CHART` (u16) and u32 indices.
pub fn write_glb(mesh: &SurfaceMesh, out: &mut dyn Write) -> std::io::Result<()> {
    let too_large = |_| std::io::Error::other("the mesh is too large for GLB (4 GiB)");
    let mut json = serde_json::to_vec(&gltf_document(mesh)).map_err(std::io::Error::other)?;
    while json.len() % 4 != 0 {
        json.push(b' ');
    }
    let bin = glb_bin_length(mesh);
    let total = 12 + 8 + json.len() as u64 + 8 + bin;
    let total = u32::try_from(total).map_err(too_large)?;
    let json_len = u32::try_from(json.len()).map_err(too_large)?;
    let bin_len = u32::try_from(bin).map_err(too_large)?;
    out.write_all(b"glTF")?;
    out.write_all(&2u32.to_le_bytes())?;
    out.write_all(&total.to_le_bytes())?;
    out.write_all(&json_len.to_le_bytes())?;
    out.write_all(b"JSON")?;
    out.write_all(&json)?;
    out.write_all(&bin_len.to_le_bytes())?;
    out.write_all(b"BIN\0")?;
    // Every section is a multiple of 4 bytes long, so the chunk needs no padding.
    fn floats(out: &mut dyn Write, values: impl Iterator<Item = f32>) -> std::io::Result<()> {
        for x in values {
            out.write_all(&x.to_le_bytes())?;
        }
        Ok(())
    }
    floats(
        out,
        (0..mesh.positions.len()).flat_map(|i| mesh.position_f32(i)),
    )?;
    floats(
        out,
        (0..mesh.normals.len()).flat_map(|i| mesh.normal_f32(i)),
    )?;
    floats(
        out,
        mesh.uvs
            .iter()
            .flat_map(|[u, v]| [*u as f32, (1.0 - v) as f32]),
    )?;
    for &c in &mesh.charts {
        let c = u16::try_from(c).map_err(|_| std::io::Error::other("chart id over 65535"))?;
        out.write_all(&c.to_le_bytes())?;
        out.write_all(&[0, 0])?;
    }
    for &i in mesh.triangles.iter().flatten() {
        out.write_all(&i.to_le_bytes())?;
    }
    Ok(())
}
