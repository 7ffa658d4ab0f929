//! Wavefront OBJ.

use std::io::Write;

use super::SurfaceMesh;
use super::options::FileInfo;

/// Wavefront OBJ: one object (`o` and its name), `v`, `vt`, `vn` per vertex (same index), faces
/// `f a/a/a b/b/b c/c/c` (or four corners, for quads). OBJ has no per-vertex attribute that could carry the chart id.
pub fn write_obj(mesh: &SurfaceMesh, info: &FileInfo, out: &mut dyn Write) -> std::io::Result<()> {
    writeln!(out, "# {}", mesh.describe())?;
    writeln!(out, "# {}", info.frame())?;
    writeln!(
        out,
        "# vt: {}; vn: the analytic unit normal, outward",
        mesh.describe_uvs()
    )?;
    writeln!(out, "o {}", info.name)?;
    for i in 0..mesh.positions.len() {
        let [x, y, z] = mesh.position_f32(i);
        writeln!(out, "v {x} {y} {z}")?;
    }
    for uv in &mesh.uvs {
        let [u, v] = uv.map(|x| x as f32);
        writeln!(out, "vt {u} {v}")?;
    }
    for i in 0..mesh.normals.len() {
        let [x, y, z] = mesh.normal_f32(i);
        writeln!(out, "vn {x} {y} {z}")?;
    }
    if mesh.quads {
        for q in mesh.quad_faces() {
            let [a, b, c, d] = q.map(|i| i + 1);
            writeln!(out, "f {a}/{a}/{a} {b}/{b}/{b} {c}/{c}/{c} {d}/{d}/{d}")?;
        }
        return Ok(());
    }
    for t in &mesh.triangles {
        let [a, b, c] = t.map(|i| i + 1);
        writeln!(out, "f {a}/{a}/{a} {b}/{b}/{b} {c}/{c}/{c}")?;
    }
    Ok(())
}
