// Re-embedding: the tensor stencil's rows (embedding::TensorStencil) applied to the control points,
// one invocation per row, the same sums as the CPU kernel: for each block (a chart whose blend counts
// at the row's point), Σ_j β N_j(v) Σ_i N_i(u) c_ij over a (order × order) block of the chart's grid.
// Positions come out relative to the control points' centre, as the control points go in.

struct Params {
    rows: u32,
    order: u32,
    // Control points per side of a chart's grid: the stride between a block's lines.
    grid: u32,
    // u32 words per block: its first control point, then 2 · order factors as f32 bits.
    stride: u32,
}

@group(0) @binding(0) var<uniform> params: Params;
@group(0) @binding(1) var<storage, read> row_starts: array<u32>;
@group(0) @binding(2) var<storage, read> blocks: array<u32>;
@group(0) @binding(3) var<storage, read> control: array<vec4<f32>>;
@group(0) @binding(4) var<storage, read_write> positions: array<vec4<f32>>;

const GROUP: u32 = 64u;

@compute @workgroup_size(64)
fn reembed(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    // Rows beyond 65535 groups go on in the second dimension.
    let r = id.x + id.y * groups.x * GROUP;
    if (r >= params.rows) {
        return;
    }
    let o = params.order;
    var acc = vec4<f32>(0.0);
    for (var k = row_starts[r]; k < row_starts[r + 1u]; k++) {
        let b = k * params.stride;
        let first = blocks[b];
        for (var j = 0u; j < o; j++) {
            let line = first + j * params.grid;
            var s = vec4<f32>(0.0);
            for (var i = 0u; i < o; i++) {
                s += bitcast<f32>(blocks[b + 1u + i]) * control[line + i];
            }
            acc += bitcast<f32>(blocks[b + 1u + o + j]) * s;
        }
    }
    positions[r] = acc;
}
