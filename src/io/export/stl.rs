//! STL, binary or ASCII.

use std::io::Write;

use super::options::FileInfo;
use super::{Encoding, SurfaceMesh};

/// STL: one facet per triangle with its (outward) face normal; no shared vertices, no attributes.
/// The object's name is the text variant's `solid` name and begins the binary variant's header.
pub fn write_stl(mesh: &SurfaceMesh, info: &FileInfo, out: &mut dyn Write) -> std::io::Result<()> {
    match info.encoding {
        Encoding::Ascii => {
            writeln!(out, "solid {}", info.name)?;
            for (k, t) in mesh.triangles.iter().enumerate() {
                let [nx, ny, nz]: [f32; 3] = mesh.face_normal(k).cast::<f32>().into();
                writeln!(out, "  facet normal {nx:e} {ny:e} {nz:e}")?;
                writeln!(out, "    outer loop")?;
                for &v in t {
                    let [x, y, z] = mesh.position_f32(v as usize);
                    writeln!(out, "      vertex {x:e} {y:e} {z:e}")?;
                }
                writeln!(out, "    endloop")?;
                writeln!(out, "  endfacet")?;
            }
            writeln!(out, "endsolid {}", info.name)
        }
        Encoding::Binary => {
            // An 80-byte header that must not begin with "solid" (readers would take it for text):
            // the name, then the description, cut at 80 bytes.
            let mut header = [b' '; 80];
            let name = if info.name.starts_with("solid") {
                format!("_{}", info.name)
            } else {
                info.name.clone()
            };
            let text = format!("{name}; {}", mesh.describe());
            let n = text.len().min(80);
            header[..n].copy_from_slice(&text.as_bytes()[..n]);
            out.write_all(&header)?;
            out.write_all(&(mesh.triangles.len() as u32).to_le_bytes())?;
            let mut record = [0u8; 50];
            for (k, t) in mesh.triangles.iter().enumerate() {
                let normal: [f32; 3] = mesh.face_normal(k).cast::<f32>().into();
                let corners = t.map(|v| mesh.position_f32(v as usize));
                let values = std::iter::once(normal).chain(corners).flatten();
                for (slot, x) in record.chunks_exact_mut(4).zip(values) {
                    slot.copy_from_slice(&x.to_le_bytes());
                }
                // Bytes 48..50: the attribute byte count, zero.
                out.write_all(&record)?;
            }
            Ok(())
        }
    }
}
