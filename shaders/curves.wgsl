// Polylines on the surface, drawn on top as screen-space ribbons of constant pixel width: each
// segment is one instance, expanded to two triangles in clip space, pulled slightly towards the
// camera so the surface it lies on does not hide it. The uniforms (`frame`) are frame.wgsl's, put in
// front of this file.

struct SegmentIn {
    @location(0) a: vec3<f32>,
    @location(1) b: vec3<f32>,
    @location(2) colour: vec3<f32>,
};

struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) colour: vec3<f32>,
};

@vertex
fn vs_main(@builtin(vertex_index) corner: u32, s: SegmentIn) -> VertexOut {
    let ca = frame.view_proj * vec4<f32>(s.a, 1.0);
    let cb = frame.view_proj * vec4<f32>(s.b, 1.0);
    let half = 0.5 * frame.viewport.xy;
    let pa = ca.xy / ca.w * half;
    let pb = cb.xy / cb.w * half;
    var dir = pb - pa;
    if (length(dir) < 1e-6) {
        dir = vec2<f32>(1.0, 0.0);
    }
    let side = normalize(vec2<f32>(-dir.y, dir.x)) * (0.5 * frame.viewport.z);
    // Corners: 0, 1, 2 and 2, 1, 3 of the quad (a−, a+, b−, b+).
    var ends = array<u32, 6>(0u, 0u, 1u, 1u, 0u, 1u);
    var signs = array<f32, 6>(-1.0, 1.0, -1.0, -1.0, 1.0, 1.0);
    let at_b = ends[corner] == 1u;
    var c = ca;
    if (at_b) {
        c = cb;
    }
    let offset = side * signs[corner] / half * c.w;
    var out: VertexOut;
    out.clip = vec4<f32>(c.xy + offset, c.z - frame.viewport.w * c.w, c.w);
    out.colour = s.colour;
    return out;
}

@fragment
fn fs_main(in: VertexOut) -> @location(0) vec4<f32> {
    return vec4<f32>(in.colour, 1.0);
}
