// Re-embedding: the tensor stencil's rows (embedding::TensorStencil) applied to the control points,
// one invocation per row, the same sums as the CPU kernel: for each block (a chart whose blend counts
// at the row's point), Σ_j β N_j(v) Σ_i N_i(u) c_ij over a (order × order) block of the chart's grid.
// Positions come out relative to the control points' centre, as the control points go in.

struct Params {
    rows: u32,
    order: u32,
    // Control points per side of a square chart's grid: the stride between a block's lines.
    grid: u32,
    // u32 words per block: its first control point, then 2 · order factors as f32 bits.
    stride: u32,
    // The disk charts' grid, and how many control points they hold (they come first).
    disk_grid: u32,
    disk_controls: u32,
    pad0: u32,
    pad1: u32,
}

// The stride between the lines of a block whose first control point is `first`.
fn line_stride(first: u32) -> u32 {
    return select(params.grid, params.disk_grid, first < params.disk_controls);
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
            let line = first + j * line_stride(first);
            var s = vec4<f32>(0.0);
            for (var i = 0u; i < o; i++) {
                s += bitcast<f32>(blocks[b + 1u + i]) * control[line + i];
            }
            acc += bitcast<f32>(blocks[b + 1u + o + j]) * s;
        }
    }
    positions[r] = acc;
}

// With tangents (embedding::TensorStencil::build_with_tangents): a block's words go on with
// N_i'(u), β N_j'(v), then β_u/β, β_v/β, Re ψ', Im ψ'. Three vec4s per row come out: the position
// and the first derivatives S_u, S_v in the row's own chart (see the tensor stencil's comment).
@compute @workgroup_size(64)
fn reembed_with_tangents(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let r = id.x + id.y * groups.x * GROUP;
    if (r >= params.rows) {
        return;
    }
    let o = params.order;
    var p = vec4<f32>(0.0);
    var su = vec4<f32>(0.0);
    var sv = vec4<f32>(0.0);
    for (var k = row_starts[r]; k < row_starts[r + 1u]; k++) {
        let b = k * params.stride;
        let first = blocks[b];
        // Where the derivative factors start.
        let d = b + 1u + 2u * o;
        var a = vec4<f32>(0.0);
        var bu = vec4<f32>(0.0);
        var cv = vec4<f32>(0.0);
        for (var j = 0u; j < o; j++) {
            let line = first + j * line_stride(first);
            var s = vec4<f32>(0.0);
            var s1 = vec4<f32>(0.0);
            for (var i = 0u; i < o; i++) {
                let c = control[line + i];
                s += bitcast<f32>(blocks[b + 1u + i]) * c;
                s1 += bitcast<f32>(blocks[d + i]) * c;
            }
            let vj = bitcast<f32>(blocks[b + 1u + o + j]);
            a += vj * s;
            bu += vj * s1;
            cv += bitcast<f32>(blocks[d + o + j]) * s;
        }
        let gu = bitcast<f32>(blocks[d + 2u * o]);
        let gv = bitcast<f32>(blocks[d + 2u * o + 1u]);
        let re = bitcast<f32>(blocks[d + 2u * o + 2u]);
        let im = bitcast<f32>(blocks[d + 2u * o + 3u]);
        p += a;
        su += gu * a + re * bu + im * cv;
        sv += gv * a - im * bu + re * cv;
    }
    positions[3u * r] = p;
    positions[3u * r + 1u] = su;
    positions[3u * r + 2u] = sv;
}
