//! Object File Format.

use std::io::Write;

use super::SurfaceMesh;
use super::options::FileInfo;

/// Object File Format: positions and triangles; the name, the up axis and the unit in comments.
pub fn write_off(mesh: &SurfaceMesh, info: &FileInfo, out: &mut dyn Write) -> std::io::Result<()> {
    writeln!(out, "OFF")?;
    writeln!(out, "# {}", info.name)?;
    writeln!(out, "# {}", mesh.describe())?;
    writeln!(out, "# {}", info.frame())?;
    writeln!(out, "{} {} 0", mesh.positions.len(), mesh.triangles.len())?;
    for i in 0..mesh.positions.len() {
        let [x, y, z] = mesh.position_f32(i);
        writeln!(out, "{x} {y} {z}")?;
    }
    for [a, b, c] in &mesh.triangles {
        writeln!(out, "3 {a} {b} {c}")?;
    }
    Ok(())
}
