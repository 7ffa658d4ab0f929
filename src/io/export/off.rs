//! Object File Format.

use std::io::Write;

use super::SurfaceMesh;
use super::options::FileInfo;

/// Object File Format: positions and triangles (or quads); the name, the up axis and the unit in comments.
pub fn write_off(mesh: &SurfaceMesh, info: &FileInfo, out: &mut dyn Write) -> std::io::Result<()> {
    writeln!(out, "OFF")?;
    writeln!(out, "# {}", info.name)?;
    writeln!(out, "# {}", mesh.describe())?;
    writeln!(out, "# {}", info.frame())?;
    let quads = mesh.quad_faces();
    let faces = if mesh.quads {
        quads.len()
    } else {
        mesh.triangles.len()
    };
    writeln!(out, "{} {faces} 0", mesh.positions.len())?;
    for i in 0..mesh.positions.len() {
        let [x, y, z] = mesh.position_f32(i);
        writeln!(out, "{x} {y} {z}")?;
    }
    if mesh.quads {
        for [a, b, c, d] in quads {
            writeln!(out, "4 {a} {b} {c} {d}")?;
        }
    } else {
        for [a, b, c] in &mesh.triangles {
            writeln!(out, "3 {a} {b} {c}")?;
        }
    }
    Ok(())
}
