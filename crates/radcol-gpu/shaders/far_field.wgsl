// Far-field assembly of the geometric collocation matrix (radcol-gpu).
//
// One invocation fills the f entries of one (matrix row i, element k) pair of a
// tile:
//
//   Gm[i, k*f + j] = sum_q G(P_i, Q_kq) * wj_kq * l_j(q)                    (eq. 19)
//   G(P, Q)        = max((Q-P).nP, 0) * max(-(Q-P).nQ, 0) / |Q-P|^4
//
// where q runs over the far rule the plan chose for the pair, wj = weight x
// Jacobian / pi, and l_j(q) comes from the rule's basis table. Pairs that are
// not far (culled, near, self) get zeros here; the host fills near and self
// pairs on the CPU and merges them.
//
// The host prepends one line, `alias scalar = f64;` or `alias scalar = f32;`,
// so both precisions share this source. The arithmetic is written in the CPU
// backend's order (radcol_core::assembly::plan::far_kernel_row and contract)
// so that f64 results agree to rounding. Only +, -, *, / and max are used: f64
// transcendental builtins are unreliable on Vulkan (wgpu issue 6087).
//
// Layouts are mirrored by #[repr(C)] structs in crates/radcol-gpu/src/layout.rs
// (checked against naga's layouter in that crate's tests).

// Where the tile sits in the matrix. 32 bytes.
struct Params {
    // First matrix row of the tile.
    row0: u32,
    // Rows in the tile (dispatch y).
    rows: u32,
    // Element of the tile's first row block: row0 / f.
    kp0: u32,
    // Nodes per element f_r (at most MAX_F); equal to the override F.
    f: u32,
    // First element of the column tile.
    k0: u32,
    // Elements in the column tile (dispatch x).
    nk: u32,
    // Point slots per element in `far_points` (all used rules, concatenated).
    stride: u32,
    // Scalars per tile row: nk * f.
    out_cols: u32,
}

// The far rule behind one class code. 16 bytes.
struct RuleInfo {
    // Offset of the rule's points within an element's record of `far_points`.
    offset: u32,
    // Points of the rule.
    nq: u32,
    // Offset of the rule's basis table (nq x f, row q contiguous) in `basis_t`.
    basis: u32,
    // 1 for a far rule, 0 for culled, near and self codes.
    far: u32,
}

// A point with its inner unit normal and weight. 64 bytes in f64, 32 in f32.
struct Point {
    p: vec3<scalar>,
    // weight x Jacobian / pi (0 for collocation points).
    wj: scalar,
    n: vec3<scalar>,
    pad: scalar,
}

const MAX_F: u32 = 28u;

// Nodes per element, fixed per pipeline (the host overrides it with f_r): a
// constant trip count lets compilers unroll the accumulator loops and keep
// `acc` in registers instead of indexable (local) memory.
override F: u32 = MAX_F;

@group(0) @binding(0) var<uniform> params: Params;
// Indexed by class code (0 culled, d + 1 far rule of degree d, 254 near, 255 self).
@group(0) @binding(1) var<storage, read> rules: array<RuleInfo, 256>;
@group(0) @binding(2) var<storage, read> basis_t: array<scalar>;
// All N collocation points, row i = kp * f + node.
@group(0) @binding(3) var<storage, read> colloc: array<Point>;
// Far rule points of the column tile, point-major: rule point q of the rule at
// `offset`, for element k0 + e, is far_points[(offset + q) * nk + e], so that
// neighbouring invocations read neighbouring records.
@group(0) @binding(4) var<storage, read> far_points: array<Point>;
// Class codes of the tile, (kp - kp0) * nk + e, four u8 per u32 (little end first).
@group(0) @binding(5) var<storage, read> classes: array<u32>;
// The tile, rows x out_cols, row-major.
@group(0) @binding(6) var<storage, read_write> tile: array<scalar>;

@compute @workgroup_size(64, 1, 1)
fn far_field(@builtin(global_invocation_id) gid: vec3<u32>) {
    let e = gid.x;
    let row = gid.y;
    if (e >= params.nk || row >= params.rows) {
        return;
    }
    let i = params.row0 + row;
    let ci = (i / F - params.kp0) * params.nk + e;
    let code = (classes[ci / 4u] >> ((ci % 4u) * 8u)) & 0xffu;
    let rule = rules[code];
    var acc: array<scalar, MAX_F>;
    if (rule.far != 0u) {
        let pp = colloc[i].p;
        let np = colloc[i].n;
        for (var q = 0u; q < rule.nq; q++) {
            let pt = far_points[(rule.offset + q) * params.nk + e];
            let dx = pt.p.x - pp.x;
            let dy = pt.p.y - pp.y;
            let dz = pt.p.z - pp.z;
            let a = max(dx * np.x + dy * np.y + dz * np.z, 0.0);
            let b = max(-(dx * pt.n.x + dy * pt.n.y + dz * pt.n.z), 0.0);
            let r2 = dx * dx + dy * dy + dz * dz;
            let g = a * b / (r2 * r2) * pt.wj;
            let bq = rule.basis + q * F;
            for (var j = 0u; j < F; j++) {
                acc[j] += g * basis_t[bq + j];
            }
        }
    }
    let out0 = row * params.out_cols + e * F;
    for (var j = 0u; j < F; j++) {
        tile[out0 + j] = acc[j];
    }
}
