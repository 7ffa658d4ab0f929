// The surface: per-vertex colour (flat, chart blend or curvature), analytic normals, two-sided
// Blinn–Phong lighting from a key light fixed relative to the camera, and an optional wireframe
// drawn from barycentric coordinates (constant width in pixels, antialiased by fwidth). The uniforms
// (`frame`) are frame.wgsl's, put in front of this file.

struct VertexIn {
    @location(0) position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) colour: vec3<f32>,
    @location(3) bary: vec3<f32>,
};

struct VertexOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) colour: vec3<f32>,
    @location(3) bary: vec3<f32>,
};

@vertex
fn vs_main(v: VertexIn) -> VertexOut {
    var out: VertexOut;
    out.clip = frame.view_proj * vec4<f32>(v.position, 1.0);
    out.world = v.position;
    out.normal = v.normal;
    out.colour = v.colour;
    out.bary = v.bary;
    return out;
}

@fragment
fn fs_main(in: VertexOut, @builtin(front_facing) front: bool) -> @location(0) vec4<f32> {
    var n = normalize(in.normal);
    let to_eye = normalize(frame.eye.xyz - in.world);
    // Two-sided: light whichever side faces the camera.
    if (dot(n, to_eye) < 0.0) {
        n = -n;
    }
    let l = normalize(frame.light.xyz);
    let h = normalize(l + to_eye);
    let diffuse = max(dot(n, l), 0.0);
    // A weak fill light from the opposite side keeps shadowed parts readable.
    let fill = 0.25 * max(dot(n, -l), 0.0);
    let specular = frame.params.w * pow(max(dot(n, h), 0.0), 40.0);
    var c = in.colour * (frame.params.z + (1.0 - frame.params.z) * diffuse + fill) + vec3<f32>(specular);
    if (frame.params.x > 0.5) {
        let width = fwidth(in.bary) * frame.params.y;
        let edge = smoothstep(vec3<f32>(0.0), width, in.bary);
        let on_edge = 1.0 - min(min(edge.x, edge.y), edge.z);
        c = mix(c, vec3<f32>(0.08, 0.1, 0.14), on_edge);
    }
    return vec4<f32>(min(c, vec3<f32>(1.0)), 1.0);
}
