// The editor's vertex stage, appended to shaders/surface.wgsl (whose fragment stage it feeds): shared
// vertices pulled from storage buffers through the index buffer, so an edit rewrites each moved
// vertex once, while every triangle corner still gets its barycentric coordinate for the wireframe.

struct PulledVertex {
    px: f32, py: f32, pz: f32,
    nx: f32, ny: f32, nz: f32,
    // RGBA8, red in the low byte.
    colour: u32,
    flags: u32,
};

@group(1) @binding(0) var<storage, read> pulled_vertices: array<PulledVertex>;
@group(1) @binding(1) var<storage, read> pulled_indices: array<u32>;

@vertex
fn vs_pulled(@builtin(vertex_index) k: u32) -> VertexOut {
    let v = pulled_vertices[pulled_indices[k]];
    let position = vec3<f32>(v.px, v.py, v.pz);
    var out: VertexOut;
    out.clip = frame.view_proj * vec4<f32>(position, 1.0);
    out.world = position;
    out.normal = vec3<f32>(v.nx, v.ny, v.nz);
    out.colour = unpack4x8unorm(v.colour).rgb;
    let corner = k % 3u;
    out.bary = vec3<f32>(f32(corner == 0u), f32(corner == 1u), f32(corner == 2u));
    return out;
}
