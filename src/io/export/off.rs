//! Object File Format.

use std::io::Write;

use super::SurfaceMesh;

/// Object File Format: positions and triangles.
pub fn write_off(mesh: &SurfaceMesh, out: &mut dyn Write) -> std::io::Result<()> {
    writeln!(out, "OFF")?;
    writeln!(out, "# {}", mesh.describe())?;
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
