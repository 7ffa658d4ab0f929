// The per-frame uniforms (`FrameUniforms` in src/render/gpu.rs), written once per frame and read by
// every pipeline: the renderer puts this file in front of each shader that uses them.

struct Frame {
    view_proj: mat4x4<f32>,
    eye: vec4<f32>,
    // Key light direction (towards the light), world space.
    light: vec4<f32>,
    // x: wireframe on (1) or off (0); y: line width in pixels; z: ambient; w: specular strength.
    params: vec4<f32>,
    // x, y: viewport size in pixels; z: curve width in pixels; w: depth pull (clip-space w units).
    viewport: vec4<f32>,
};

@group(0) @binding(0) var<uniform> frame: Frame;
