"""Reads mesh files with independent readers and prints what they found, as JSON.

Usage: python3 read_mesh.py FILE...

OBJ, PLY, STL, GLB and OFF are read with trimesh, 3MF with lib3mf (the 3MF Consortium's library).
For each file, one JSON object: what the reader saw (counts, positions, texture coordinates, chart
ids, names, units) and, for trimesh, the mesh's topology once vertices at the same position are
merged (STL and the UV atlas split vertices). The tests in tests/library/export_tools.rs compare it
with what ntori wrote.

Exit status 0 when every file was read, 1 when a file could not be read (its error is in the
report), 3 when a reader is not installed (the message says which).
"""

import json
import sys

try:
    import numpy as np
    import trimesh
except ImportError as e:  # pragma: no cover - depends on the machine
    print(f"missing: {e.name} (pip3 install -r tests/tools/requirements.txt)", file=sys.stderr)
    sys.exit(3)


def floats(a):
    return np.asarray(a, dtype=np.float64).tolist()


def read_trimesh(path):
    scene = trimesh.load(path, force="scene", process=False)
    geometries = list(scene.geometry.items())
    if len(geometries) != 1:
        return {"error": f"{len(geometries)} geometries"}
    name, mesh = geometries[0]
    report = {
        "reader": f"trimesh {trimesh.__version__}",
        "names": [name] + list(scene.graph.nodes_geometry),
        "vertices": int(len(mesh.vertices)),
        "faces": int(len(mesh.faces)),
        "positions": floats(mesh.vertices),
        "triangles": np.asarray(mesh.faces).tolist(),
        "units": scene.units,
        "metadata_name": mesh.metadata.get("name"),
        "header": mesh.metadata.get("header"),
    }
    uv = getattr(mesh.visual, "uv", None)
    report["uvs"] = None if uv is None else floats(uv)
    material = getattr(mesh.visual, "material", None)
    report["material"] = type(material).__name__ if material is not None else None
    texture = getattr(material, "baseColorTexture", None)
    report["texture_size"] = list(texture.size) if texture is not None else None
    charts = mesh.vertex_attributes.get("_CHART")
    if charts is not None:
        report["charts"] = np.asarray(charts).reshape(-1).tolist()
        report["charts_dtype"] = str(np.asarray(charts).dtype)
    raw = mesh.metadata.get("_ply_raw")
    if raw is not None:
        # Binary PLY: a structured array; ASCII: a dict of arrays.
        data = raw["vertex"]["data"]
        names = list(data.keys()) if isinstance(data, dict) else list(data.dtype.names)
        report["ply_properties"] = names
        if "chart" in names:
            report["charts"] = np.asarray(data["chart"]).reshape(-1).tolist()
            report["charts_dtype"] = str(np.asarray(data["chart"]).dtype)
    # Topology with vertices at the same position merged (whatever their normals and UVs).
    merged = mesh.copy()
    merged.merge_vertices(merge_tex=True, merge_norm=True)
    report["merged"] = {
        "vertices": int(len(merged.vertices)),
        "watertight": bool(merged.is_watertight),
        "winding_consistent": bool(merged.is_winding_consistent),
        "euler": int(merged.euler_number),
        "volume": float(merged.volume),
    }
    return report


def read_3mf(path):
    try:
        import lib3mf
    except ImportError:  # pragma: no cover - depends on the machine
        print("missing: lib3mf (pip3 install -r tests/tools/requirements.txt)", file=sys.stderr)
        sys.exit(3)
    wrapper = lib3mf.get_wrapper()
    model = wrapper.CreateModel()
    reader = model.QueryReader("3mf")
    reader.SetStrictModeActive(True)
    reader.ReadFromFile(path)
    warnings = [reader.GetWarning(i)[1] for i in range(reader.GetWarningCount())]
    objects = []
    it = model.GetMeshObjects()
    while it.MoveNext():
        o = it.GetCurrentMeshObject()
        positions = [list(v.Coordinates) for v in o.GetVertices()]
        triangles = [list(t.Indices) for t in o.GetTriangleIndices()]
        objects.append(
            {
                "name": o.GetName(),
                "vertices": o.GetVertexCount(),
                "faces": o.GetTriangleCount(),
                "manifold_and_oriented": bool(o.IsManifoldAndOriented()),
                "positions": positions,
                "triangles": triangles,
            }
        )
    units = {
        lib3mf.ModelUnit.MicroMeter: "micron",
        lib3mf.ModelUnit.MilliMeter: "millimeter",
        lib3mf.ModelUnit.CentiMeter: "centimeter",
        lib3mf.ModelUnit.Inch: "inch",
        lib3mf.ModelUnit.Foot: "foot",
        lib3mf.ModelUnit.Meter: "meter",
    }
    return {
        "reader": "lib3mf {}.{}.{}".format(*wrapper.GetLibraryVersion()),
        "unit": units.get(model.GetUnit(), str(model.GetUnit())),
        "warnings": warnings,
        "build_items": model.GetBuildItems().Count(),
        "objects": objects,
    }


def main():
    reports = []
    failed = False
    for path in sys.argv[1:]:
        try:
            if path.lower().endswith(".3mf"):
                report = read_3mf(path)
            else:
                report = read_trimesh(path)
        except Exception as e:  # a reader's refusal is a finding, reported for the test
            report = {"error": f"{type(e).__name__}: {e}"}
            failed = True
        report["path"] = path
        reports.append(report)
    json.dump(reports, sys.stdout)
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main()
