//! Binary glTF 2.0.

use std::io::Write;

use super::options::FileInfo;
use super::texture;
use super::{ExportError, MeshSource, SurfaceMesh};

/// How the `_CHART` attribute stores chart ids: as u8 while every id fits (Blender's importer
/// keeps u8 and float scalar attributes and drops u16 ones), as f32 (exact for integers below
/// 2²⁴) past 255. ntori's atlases have 2n + 2 charts, at most 130 (genus 64), so u8 in practice.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ChartComponent {
    U8,
    F32,
}

/// The component type `_CHART` takes for `mesh`'s chart ids.
pub fn chart_component(mesh: &SurfaceMesh) -> ChartComponent {
    if mesh.charts.iter().all(|&c| c <= u32::from(u8::MAX)) {
        ChartComponent::U8
    } else {
        ChartComponent::F32
    }
}

/// The most bytes the checker texture's PNG can take (its raw pixels and chunk overhead: PNG's
/// deflate never grows data by more than a few bytes a block).
const MAX_TEXTURE_BYTES: u64 = 3 * (texture::SIDE as u64 + 1) * texture::SIDE as u64 + 4096;

/// `n` rounded up to a multiple of 4.
fn padded(n: u64) -> u64 {
    n.div_ceil(4) * 4
}

/// The GLB BIN chunk's length: positions, normals (12 bytes a vertex each), texture coordinates
/// (8), charts (a u8 or f32 in a 4-byte stride), indices (12 a triangle) and the texture's PNG
/// (padded to 4 bytes); all multiples of 4.
fn glb_bin_length(mesh: &SurfaceMesh, png: u64) -> u64 {
    let v = mesh.positions.len() as u64;
    let f = mesh.triangles.len() as u64;
    36 * v + 12 * f + padded(png)
}

pub(super) fn glb_size(mesh: &SurfaceMesh) -> Result<u64, ExportError> {
    let bin = glb_bin_length(mesh, MAX_TEXTURE_BYTES);
    // The JSON is a few kilobytes.
    let total = 12 + 8 + 8192 + 8 + bin;
    if total > u64::from(u32::MAX) {
        return Err(ExportError::GlbTooLarge(total));
    }
    Ok(total)
}

/// The glTF JSON document describing the BIN chunk [`write_glb`] writes.
fn gltf_document(mesh: &SurfaceMesh, info: &FileInfo, png: u64) -> gltf_json::Root {
    use gltf_json as json;
    use json::accessor::{ComponentType, GenericComponentType, Type};
    use json::validation::Checked::Valid;
    use json::validation::USize64;

    let v = mesh.positions.len() as u64;
    let bin = glb_bin_length(mesh, png);
    let chart_type = match chart_component(mesh) {
        ChartComponent::U8 => "u8",
        ChartComponent::F32 => "f32",
    };
    let (te, tr) = match mesh.source {
        MeshSource::Tessellation { te, tr } => (Some(te), Some(tr)),
        _ => (None, None),
    };
    let mut root = json::Root {
        asset: json::Asset {
            generator: Some(format!("ntori {}", env!("CARGO_PKG_VERSION"))),
            extras: json::extras::RawValue::from_string(
                serde_json::json!({
                    "ntori": {
                        "genus": mesh.genus,
                        "te": te,
                        "tr": tr,
                        "frame": info.frame(),
                        "TEXCOORD_0": format!("{}, v flipped (glTF's convention)", mesh.describe_uvs()),
                        "_CHART": format!("the vertex's chart ({chart_type})"),
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
    let mut view = |root: &mut json::Root,
                    length: u64,
                    stride: Option<usize>,
                    target: Option<json::buffer::Target>| {
        let index = root.push(json::buffer::View {
            buffer,
            byte_length: USize64(length),
            byte_offset: Some(USize64(offset)),
            byte_stride: stride.map(json::buffer::Stride),
            name: None,
            target: target.map(Valid),
            extensions: None,
            extras: Default::default(),
        });
        offset += padded(length);
        index
    };
    let vertices = Some(json::buffer::Target::ArrayBuffer);
    let positions_view = view(&mut root, 12 * v, None, vertices);
    let normals_view = view(&mut root, 12 * v, None, vertices);
    let uvs_view = view(&mut root, 8 * v, None, vertices);
    let charts_view = view(&mut root, 4 * v, Some(4), vertices);
    let indices_view = view(
        &mut root,
        12 * mesh.triangles.len() as u64,
        None,
        Some(json::buffer::Target::ElementArrayBuffer),
    );
    let image_view = view(&mut root, png, None, None);

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
        "texture coordinates",
    );
    let charts = accessor(
        &mut root,
        charts_view,
        v,
        match chart_component(mesh) {
            ChartComponent::U8 => ComponentType::U8,
            ChartComponent::F32 => ComponentType::F32,
        },
        Type::Scalar,
        None,
        "charts",
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

    // A default PBR material whose base colour is the checker texture, read through TEXCOORD_0.
    let image = root.push(json::Image {
        buffer_view: Some(image_view),
        mime_type: Some(json::image::MimeType("image/png".into())),
        name: Some("checker".into()),
        uri: None,
        extensions: None,
        extras: Default::default(),
    });
    let sampler = root.push(json::texture::Sampler {
        mag_filter: Some(Valid(json::texture::MagFilter::Linear)),
        min_filter: Some(Valid(json::texture::MinFilter::LinearMipmapLinear)),
        wrap_s: Valid(json::texture::WrappingMode::ClampToEdge),
        wrap_t: Valid(json::texture::WrappingMode::ClampToEdge),
        ..Default::default()
    });
    let texture = root.push(json::Texture {
        name: Some("checker".into()),
        sampler: Some(sampler),
        source: image,
        extensions: None,
        extras: Default::default(),
    });
    let material = root.push(json::Material {
        name: Some("ntori checker".into()),
        pbr_metallic_roughness: json::material::PbrMetallicRoughness {
            base_color_texture: Some(json::texture::Info {
                index: texture,
                tex_coord: 0,
                extensions: None,
                extras: Default::default(),
            }),
            metallic_factor: json::material::StrengthFactor(0.0),
            roughness_factor: json::material::StrengthFactor(0.6),
            ..Default::default()
        },
        ..Default::default()
    });

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
        material: Some(material),
        mode: Valid(json::mesh::Mode::Triangles),
        targets: None,
        extensions: None,
        extras: Default::default(),
    };
    let gltf_mesh = root.push(json::Mesh {
        name: Some(info.name.clone()),
        primitives: vec![primitive],
        weights: None,
        extensions: None,
        extras: Default::default(),
    });
    let node = root.push(json::Node {
        mesh: Some(gltf_mesh),
        name: Some(info.name.clone()),
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

/// Binary glTF 2.0: one node and mesh named after the object, one triangle primitive with
/// `POSITION`, `NORMAL`, `TEXCOORD_0` (f32; v flipped as glTF's texture origin is the top left),
/// `_CHART` ([`chart_component`]) and u32 indices, and a default PBR material whose base colour is
/// a checker texture (an embedded PNG) read through `TEXCOORD_0`.
pub fn write_glb(mesh: &SurfaceMesh, info: &FileInfo, out: &mut dyn Write) -> std::io::Result<()> {
    let too_large = |_| std::io::Error::other("the mesh is too large for GLB (4 GiB)");
    let png = texture::checker_png()?;
    let mut json = serde_json::to_vec(&gltf_document(mesh, info, png.len() as u64))
        .map_err(std::io::Error::other)?;
    while json.len() % 4 != 0 {
        json.push(b' ');
    }
    let bin = glb_bin_length(mesh, png.len() as u64);
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
    // Every section but the image is a multiple of 4 bytes long; the image is padded with zeros.
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
    match chart_component(mesh) {
        ChartComponent::U8 => {
            for &c in &mesh.charts {
                out.write_all(&[c as u8, 0, 0, 0])?;
            }
        }
        ChartComponent::F32 => floats(out, mesh.charts.iter().map(|&c| c as f32))?,
    }
    for &i in mesh.triangles.iter().flatten() {
        out.write_all(&i.to_le_bytes())?;
    }
    out.write_all(&png)?;
    let padding = (padded(png.len() as u64) - png.len() as u64) as usize;
    out.write_all(&[0u8; 3][..padding])?;
    Ok(())
}
