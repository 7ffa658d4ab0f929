//! Exports read by the tools people use: trimesh (OBJ, PLY, STL, GLB, OFF), lib3mf (3MF, the 3MF
//! Consortium's library, as slicers use it) and the Khronos glTF validator, each run as a separate
//! process on files written with every option (`tests/tools/`: `read_mesh.py`,
//! `validate-gltf.js`).
//!
//! A test whose tool is not installed prints "skipped" and passes, unless NTORI_REQUIRE_TOOLS is
//! set, as `.ci/run` sets it after installing them (`pip3 install -r tests/tools/requirements.txt`,
//! `npm ci` in `tests/tools`): there a missing tool fails the test.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::OnceLock;

use ntori::io::export::{
    self, ExportOptions, Format, SurfaceMesh, Units, Up, UvLayout, surface_mesh,
};
use serde_json::Value;

/// The directory of the tools and their scripts.
fn tools_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/tools")
}

/// Runs `program script files…` and parses its standard output as JSON; `None` (after saying so)
/// when the program or the tool it needs is missing, which fails instead under NTORI_REQUIRE_TOOLS.
fn run_tool(program: &str, script: &str, files: &[PathBuf]) -> Option<Value> {
    let required = std::env::var_os("NTORI_REQUIRE_TOOLS").is_some();
    let skip = |why: String| {
        assert!(!required, "NTORI_REQUIRE_TOOLS is set, but {why}");
        eprintln!("skipped: {why}");
        None
    };
    let out = match Command::new(program)
        .arg(tools_dir().join(script))
        .args(files)
        .output()
    {
        Ok(out) => out,
        Err(e) => return skip(format!("{program} cannot run ({e})")),
    };
    let stderr = String::from_utf8_lossy(&out.stderr);
    if out.status.code() == Some(3) {
        return skip(format!("{script}: {}", stderr.trim()));
    }
    // Exit status 1: a file could not be read; the report says which and why.
    assert!(
        matches!(out.status.code(), Some(0 | 1)),
        "{program} {script} failed ({}): {stderr}",
        out.status
    );
    Some(
        serde_json::from_slice(&out.stdout)
            .unwrap_or_else(|e| panic!("{program} {script} printed no JSON ({e}): {stderr}")),
    )
}

/// One export to read: the model's genus, the format, the options (named after the model file).
struct Case {
    genus: u32,
    format: Format,
    options: ExportOptions,
    path: PathBuf,
}

impl Case {
    fn what(&self) -> String {
        format!(
            "genus {} {} {:?} up {:?} ×{} {:?} uv {:?}",
            self.genus,
            self.format,
            self.options.encoding,
            self.options.up_for(self.format),
            self.options.scale,
            self.options.units,
            self.options.uv
        )
    }

    /// The surface mesh the file holds, placed as its options say.
    fn expected(&self) -> SurfaceMesh {
        mesh(self.genus, self.options.uv)
            .placed(
                self.options.up_for(self.format),
                self.options.factor_for(self.format),
            )
            .into_owned()
    }
}

/// The small models' meshes at t_e = t_r = 6, by genus and layout.
fn mesh(genus: u32, uv: UvLayout) -> &'static SurfaceMesh {
    static MESHES: OnceLock<Vec<SurfaceMesh>> = OnceLock::new();
    let meshes = MESHES.get_or_init(|| {
        (0..=3)
            .flat_map(|g| {
                [UvLayout::Chart, UvLayout::Atlas]
                    .map(|uv| surface_mesh(crate::common::small_model(g), (6, 6), uv).unwrap())
            })
            .collect()
    });
    &meshes[2 * genus as usize + usize::from(uv == UvLayout::Atlas)]
}

/// Every format with its default options, and the options that change what a reader sees:
/// encodings, up axes, scales and units, the atlas.
fn cases(dir: &Path) -> Vec<Case> {
    use export::Encoding::{Ascii, Binary};
    let o = |encoding, up, scale, units, uv| ExportOptions {
        encoding,
        up,
        scale,
        units,
        uv,
        name: Some("genus-n".into()),
    };
    let (c, a) = (UvLayout::Chart, UvLayout::Atlas);
    let list: Vec<(u32, Format, ExportOptions)> = vec![
        (
            2,
            Format::Obj,
            ExportOptions {
                name: Some("genus-n".into()),
                ..ExportOptions::default()
            },
        ),
        (2, Format::Obj, o(Binary, Some(Up::Z), 2.0, Units::Mm, a)),
        (2, Format::Ply, o(Binary, None, 1.0, Units::Cm, c)),
        (2, Format::Ply, o(Ascii, Some(Up::Y), 1.0, Units::M, a)),
        (0, Format::Ply, o(Binary, None, 1.0, Units::Cm, a)),
        (2, Format::Stl, o(Binary, None, 1.0, Units::Cm, c)),
        (2, Format::Stl, o(Ascii, Some(Up::Y), 0.5, Units::In, c)),
        (2, Format::Glb, o(Binary, None, 1.0, Units::Cm, c)),
        (2, Format::Glb, o(Binary, Some(Up::Z), 10.0, Units::Mm, a)),
        (1, Format::Glb, o(Binary, None, 1.0, Units::M, a)),
        (3, Format::Glb, o(Binary, None, 1.0, Units::Cm, c)),
        (2, Format::Off, o(Binary, None, 1.0, Units::Cm, c)),
        (2, Format::ThreeMf, o(Binary, None, 1.0, Units::Cm, c)),
        (
            2,
            Format::ThreeMf,
            o(Binary, Some(Up::Y), 3.0, Units::In, c),
        ),
        (0, Format::ThreeMf, o(Binary, None, 2.0, Units::M, c)),
        (1, Format::ThreeMf, o(Binary, None, 1.0, Units::Mm, c)),
    ];
    list.into_iter()
        .enumerate()
        .map(|(k, (genus, format, options))| {
            let path = dir.join(format!("case{k}.{}", format.extension()));
            export::write(mesh(genus, options.uv), &path, format, &options).unwrap();
            Case {
                genus,
                format,
                options,
                path,
            }
        })
        .collect()
}

fn numbers(v: &Value) -> Vec<f64> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect()
}

fn triples(v: &Value) -> Vec<[f64; 3]> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|p| numbers(p).try_into().unwrap())
        .collect()
}

/// Positions as read, in order, against the mesh's, to f32 precision of its extent.
fn assert_positions(read: &[[f64; 3]], mesh: &SurfaceMesh, what: &str) {
    assert_eq!(read.len(), mesh.positions.len(), "{what}");
    let scale = mesh
        .positions
        .iter()
        .flat_map(|p| p.iter())
        .fold(0.0f64, |m, x| m.max(x.abs()));
    for (i, (got, want)) in read.iter().zip(&mesh.positions).enumerate() {
        let d = (0..3).map(|k| (got[k] - want[k]).abs()).fold(0.0, f64::max);
        assert!(
            d <= 2.0 * f64::from(f32::EPSILON) * scale,
            "{what}: vertex {i}: {got:?} vs {want:?}"
        );
    }
}

/// The signed volume of a mesh of positions `p` and triangles `t`.
fn volume(p: &[[f64; 3]], t: &[[f64; 3]]) -> f64 {
    t.iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| p[i as usize]);
            a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
                + a[2] * (b[0] * c[1] - b[1] * c[0])
        })
        .sum::<f64>()
        / 6.0
}

#[test]
fn trimesh_and_lib3mf_read_every_format_and_option() {
    let dir = tempfile::tempdir().unwrap();
    let cases = cases(dir.path());
    let files: Vec<PathBuf> = cases.iter().map(|c| c.path.clone()).collect();
    let Some(reports) = run_tool("python3", "read_mesh.py", &files) else {
        return;
    };
    let reports = reports.as_array().unwrap();
    assert_eq!(reports.len(), cases.len());
    for (case, report) in cases.iter().zip(reports) {
        let what = case.what();
        assert!(report.get("error").is_none(), "{what}: {report}");
        let mesh = case.expected();
        let genus = i64::from(case.genus);
        let expected_volume = export::signed_volume(&mesh.positions, &mesh.triangles);
        if case.format == Format::ThreeMf {
            // lib3mf, in strict mode: no warnings, millimetres, one object, manifold and outward.
            assert!(report["reader"].as_str().unwrap().starts_with("lib3mf"));
            assert_eq!(report["unit"], "millimeter", "{what}");
            assert_eq!(report["warnings"].as_array().unwrap().len(), 0, "{what}");
            assert_eq!(report["build_items"], 1, "{what}");
            let objects = report["objects"].as_array().unwrap();
            assert_eq!(objects.len(), 1, "{what}");
            let object = &objects[0];
            assert_eq!(object["name"], "genus-n", "{what}");
            assert_eq!(object["manifold_and_oriented"], true, "{what}");
            assert_eq!(
                object["faces"].as_u64().unwrap() as usize,
                mesh.triangles.len()
            );
            let positions = triples(&object["positions"]);
            // The size in millimetres is the model's times --scale in --units.
            assert_positions(&positions, &mesh, &what);
            let v = volume(&positions, &triples(&object["triangles"]));
            assert!((v / expected_volume - 1.0).abs() < 1e-4, "{what}: {v}");
            continue;
        }
        assert!(report["reader"].as_str().unwrap().starts_with("trimesh"));
        assert_eq!(
            report["faces"].as_u64().unwrap() as usize,
            mesh.triangles.len()
        );
        let merged = &report["merged"];
        assert_eq!(merged["watertight"], true, "{what}: {merged}");
        assert_eq!(merged["winding_consistent"], true, "{what}");
        assert_eq!(merged["euler"].as_i64().unwrap(), 2 - 2 * genus, "{what}");
        // Outward: trimesh's volume is positive, and the surface's.
        let v = merged["volume"].as_f64().unwrap();
        assert!(
            (v / expected_volume - 1.0).abs() < 1e-4,
            "{what}: {v} vs {expected_volume}"
        );
        let positions = triples(&report["positions"]);
        if case.format == Format::Stl {
            // Three corners a triangle; merged, the surface's vertices (chart layout).
            assert_eq!(positions.len(), 3 * mesh.triangles.len());
            assert_eq!(
                merged["vertices"].as_u64().unwrap() as usize,
                mesh.positions.len(),
                "{what}"
            );
        } else {
            assert_positions(&positions, &mesh, &what);
        }
        // Texture coordinates arrive as trimesh's UVs (GLB's v flipped back by the reader).
        if case.format.has_uvs() {
            let uvs: Vec<Vec<f64>> = report["uvs"]
                .as_array()
                .unwrap_or_else(|| panic!("{what}: no UVs"))
                .iter()
                .map(numbers)
                .collect();
            assert_eq!(uvs.len(), mesh.uvs.len(), "{what}");
            for (got, want) in uvs.iter().zip(&mesh.uvs) {
                assert!(
                    (got[0] - want[0]).abs() < 1e-6 && (got[1] - want[1]).abs() < 1e-6,
                    "{what}: uv {got:?} vs {want:?}"
                );
            }
        } else {
            assert!(report["uvs"].is_null(), "{what}");
        }
        match case.format {
            Format::Ply => {
                let properties: Vec<&str> = report["ply_properties"]
                    .as_array()
                    .unwrap()
                    .iter()
                    .map(|p| p.as_str().unwrap())
                    .collect();
                assert_eq!(
                    properties,
                    ["x", "y", "z", "nx", "ny", "nz", "s", "t", "chart"]
                );
            }
            Format::Glb => {
                // The material trimesh needs to keep TEXCOORD_0, with the checker texture.
                assert_eq!(report["material"], "PBRMaterial", "{what}");
                let side = u64::from(export::texture::SIDE);
                assert_eq!(report["texture_size"], serde_json::json!([side, side]));
                assert_eq!(report["units"], "meters");
                assert_eq!(report["charts_dtype"], "uint8", "{what}");
            }
            _ => {}
        }
        if matches!(case.format, Format::Ply | Format::Glb) {
            let charts: Vec<u32> = numbers(&report["charts"])
                .into_iter()
                .map(|c| c as u32)
                .collect();
            assert_eq!(charts, mesh.charts, "{what}");
        }
        // The object's name, where trimesh reads one (for the others it names the geometry
        // after the file).
        let stl_text =
            case.format == Format::Stl && case.options.encoding == export::Encoding::Ascii;
        if matches!(case.format, Format::Obj | Format::Glb) || stl_text {
            assert_eq!(report["names"][0], "genus-n", "{what}");
        }
    }
}

#[test]
fn the_khronos_validator_finds_nothing_in_any_glb() {
    let dir = tempfile::tempdir().unwrap();
    let cases: Vec<Case> = cases(dir.path())
        .into_iter()
        .filter(|c| c.format == Format::Glb)
        .collect();
    let files: Vec<PathBuf> = cases.iter().map(|c| c.path.clone()).collect();
    let Some(reports) = run_tool("node", "validate-gltf.js", &files) else {
        return;
    };
    let reports = reports.as_array().unwrap();
    assert_eq!(reports.len(), cases.len());
    for (case, report) in cases.iter().zip(reports) {
        let what = case.what();
        let issues = &report["issues"];
        // No errors, warnings, infos (unused TEXCOORD_0 was one) or hints.
        for count in ["numErrors", "numWarnings", "numInfos", "numHints"] {
            assert_eq!(issues[count], 0, "{what}: {count}: {issues}");
        }
        let info = &report["info"];
        assert_eq!(info["materialCount"], 1, "{what}");
        assert_eq!(info["hasTextures"], true, "{what}");
        assert_eq!(info["maxUVs"], 1, "{what}");
        let mesh = case.expected();
        assert_eq!(
            info["totalVertexCount"].as_u64().unwrap() as usize,
            mesh.positions.len()
        );
        assert_eq!(
            info["totalTriangleCount"].as_u64().unwrap() as usize,
            mesh.triangles.len()
        );
    }
}
