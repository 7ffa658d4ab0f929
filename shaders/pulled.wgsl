// The editor's vertex stage, appended to frame.wgsl and surface.wgsl (whose fragment stage it
// feeds): shared vertices pulled from storage buffers through the index buffer, so an edit rewrites
// each moved vertex once, while every triangle corner still gets its barycentric coordinate for the
// wireframe.

struct PulledVertex {
    px: f32, py: f32, pz: f32,
    nx: f32, ny: f32, nz: f32,
    // RGBA8, red in the low byte.
    colour: u32,
    flags: u32,
};

// A vertex that follows the drag in progress: position and tangents when the drag began, and the
// gains per axis that multiply the dragged point's displacement (see src/editor/drag.rs).
struct DragRow {
    bx: f32, by: f32, bz: f32,
    ux: f32, uy: f32, uz: f32,
    vx: f32, vy: f32, vz: f32,
    gx: f32, gy: f32, gz: f32,
    gux: f32, guy: f32, guz: f32,
    gvx: f32, gvy: f32, gvz: f32,
};

struct Drag {
    // xyz: the dragged point's displacement.
    delta: vec4<f32>,
};

@group(1) @binding(0) var<storage, read> pulled_vertices: array<PulledVertex>;
@group(1) @binding(1) var<storage, read> pulled_indices: array<u32>;
@group(1) @binding(2) var<storage, read> drag_rows: array<DragRow>;
@group(1) @binding(3) var<uniform> drag: Drag;

@vertex
fn vs_pulled(@builtin(vertex_index) k: u32) -> VertexOut {
    let v = pulled_vertices[pulled_indices[k]];
    var position = vec3<f32>(v.px, v.py, v.pz);
    var normal = vec3<f32>(v.nx, v.ny, v.nz);
    if (v.flags != 0u) {
        let r = drag_rows[v.flags - 1u];
        let d = drag.delta.xyz;
        position = vec3<f32>(r.bx, r.by, r.bz) + vec3<f32>(r.gx, r.gy, r.gz) * d;
        let su = vec3<f32>(r.ux, r.uy, r.uz) + vec3<f32>(r.gux, r.guy, r.guz) * d;
        let sv = vec3<f32>(r.vx, r.vy, r.vz) + vec3<f32>(r.gvx, r.gvy, r.gvz) * d;
        normal = normalize(cross(su, sv));
    }
    var out: VertexOut;
    out.clip = frame.view_proj * vec4<f32>(position, 1.0);
    out.world = position;
    out.normal = normal;
    out.colour = unpack4x8unorm(v.colour).rgb;
    let corner = k % 3u;
    out.bary = vec3<f32>(f32(corner == 0u), f32(corner == 1u), f32(corner == 2u));
    return out;
}
