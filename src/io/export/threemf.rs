//! 3MF (3D Manufacturing Format), for slicers: an OPC package (a ZIP) holding
//! `[Content_Types].xml`, `_rels/.rels` and the model part `3D/3dmodel.model` with one mesh
//! object, in millimetres, and one build item.

use std::io::{BufWriter, Write};

use super::options::FileInfo;
use super::{SurfaceMesh, WriteSeek};

/// The model part's path in the package.
pub const MODEL_PART: &str = "3D/3dmodel.model";

const CONTENT_TYPES: &str = r#"<?xml version="1.0" encoding="UTF-8"?>
<Types xmlns="http://schemas.openxmlformats.org/package/2006/content-types">
  <Default Extension="rels" ContentType="application/vnd.openxmlformats-package.relationships+xml"/>
  <Default Extension="model" ContentType="application/vnd.ms-package.3dmanufacturing-3dmodel+xml"/>
</Types>
"#;

const RELATIONSHIPS: &str = r#"<?xml version="1.0" encoding="UTF-8"?>
<Relationships xmlns="http://schemas.openxmlformats.org/package/2006/relationships">
  <Relationship Id="rel0" Target="/3D/3dmodel.model" Type="http://schemas.microsoft.com/3dmanufacturing/2013/01/3dmodel"/>
</Relationships>
"#;

/// `text` with XML's special characters escaped (for attribute values and element text).
fn escape(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for c in text.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            c => out.push(c),
        }
    }
    out
}

/// The model part: `<model unit="millimeter">` with one object (its name the mesh's), vertices
/// (f32, shortest decimals) and triangles (counter-clockwise seen from outside, as 3MF requires),
/// and a build item placing it.
pub fn write_model_xml(
    mesh: &SurfaceMesh,
    info: &FileInfo,
    out: &mut dyn Write,
) -> std::io::Result<()> {
    let name = escape(&info.name);
    writeln!(out, r#"<?xml version="1.0" encoding="UTF-8"?>"#)?;
    writeln!(
        out,
        r#"<model unit="millimeter" xml:lang="en-US" xmlns="http://schemas.microsoft.com/3dmanufacturing/core/2015/02">"#
    )?;
    writeln!(out, r#"  <metadata name="Title">{name}</metadata>"#)?;
    writeln!(
        out,
        r#"  <metadata name="Application">ntori {}</metadata>"#,
        env!("CARGO_PKG_VERSION")
    )?;
    writeln!(
        out,
        r#"  <metadata name="Description">{}</metadata>"#,
        escape(&mesh.describe())
    )?;
    writeln!(out, "  <resources>")?;
    writeln!(out, r#"    <object id="1" type="model" name="{name}">"#)?;
    writeln!(out, "      <mesh>")?;
    writeln!(out, "        <vertices>")?;
    for i in 0..mesh.positions.len() {
        let [x, y, z] = mesh.position_f32(i);
        writeln!(out, r#"          <vertex x="{x}" y="{y}" z="{z}"/>"#)?;
    }
    writeln!(out, "        </vertices>")?;
    writeln!(out, "        <triangles>")?;
    for [a, b, c] in &mesh.triangles {
        writeln!(out, r#"          <triangle v1="{a}" v2="{b}" v3="{c}"/>"#)?;
    }
    writeln!(out, "        </triangles>")?;
    writeln!(out, "      </mesh>")?;
    writeln!(out, "    </object>")?;
    writeln!(out, "  </resources>")?;
    writeln!(out, "  <build>")?;
    writeln!(out, r#"    <item objectid="1"/>"#)?;
    writeln!(out, "  </build>")?;
    writeln!(out, "</model>")
}

/// A 3MF package (see the module documentation), deflated, every entry dated 1980-01-01 so the
/// same mesh gives the same bytes.
pub fn write_3mf(
    mesh: &SurfaceMesh,
    info: &FileInfo,
    out: &mut dyn WriteSeek,
) -> std::io::Result<()> {
    use zip::write::SimpleFileOptions;
    let options = SimpleFileOptions::default()
        .compression_method(zip::CompressionMethod::Deflated)
        .last_modified_time(zip::DateTime::default());
    // An upper bound on the model part's length: past 4 GiB it needs ZIP64 records, which must be
    // asked for before the entry is written.
    let bound = 200 + 180 * mesh.positions.len() as u64 + 64 * mesh.triangles.len() as u64;
    let mut zip = zip::ZipWriter::new(out);
    zip.start_file("[Content_Types].xml", options)?;
    zip.write_all(CONTENT_TYPES.as_bytes())?;
    zip.start_file("_rels/.rels", options)?;
    zip.write_all(RELATIONSHIPS.as_bytes())?;
    zip.start_file(MODEL_PART, options.large_file(bound >= u64::from(u32::MAX)))?;
    {
        let mut part = BufWriter::with_capacity(1 << 16, &mut zip);
        write_model_xml(mesh, info, &mut part)?;
        part.flush()?;
    }
    zip.finish()?;
    Ok(())
}
