// The minimal IFS density field, a shader idiom (the "kali" fold): iterate
// p -> |p| / (p . p) + offset and accumulate exp(-strength |mag - prev|^2.3) with weights
// exp(-i / decay); the density is max(0, 5 accum / total weight - 0.7). Here it is a 2D
// layer: the plane point (x, y) becomes p = (x scale, y scale, z), a slice of the 3D field.
//
// The slips of the GLSL idiom are fixed: p . p is bounded below (a zero point no longer divides by
// zero), and pow() only ever sees a positive argument (pow(0, y) and pow of huge values
// are undefined or infinite in WGSL, which implementations may assume never happen). Its
// random jitter of `strength` from iTime is the plain `strength` parameter. The same
// operations in the same order run on the CPU in ifs.rs.

const IFS_MIN_MAG: f32 = 1e-20;
const IFS_MIN_STEP: f32 = 1e-30;
const IFS_MAX_STEP: f32 = 1e4;

fn ifs_density(x: f32, y: f32) -> f32 {
    var p = vec3<f32>(x * P.ifs_scale, y * P.ifs_scale, P.ifs_z);
    let offset = vec3<f32>(P.ifs_offset_x, P.ifs_offset_y, P.ifs_offset_z);
    var accum = 0.0;
    var prev = 0.0;
    var total = 0.0;
    for (var i = 0u; i < P.ifs_iterations; i += 1u) {
        let mag = p.x * p.x + p.y * p.y + p.z * p.z;
        p = abs(p) / max(mag, IFS_MIN_MAG) + offset;
        let w = exp(-f32(i) / P.ifs_decay);
        let step = clamp(abs(mag - prev), IFS_MIN_STEP, IFS_MAX_STEP);
        accum += w * exp(-P.ifs_strength * pow(step, 2.3));
        total += w;
        prev = mag;
    }
    if total <= 0.0 {
        return 0.0;
    }
    return max(0.0, 5.0 * accum / total - 0.7);
}

@group(0) @binding(2) var<storage, read_write> density_out: array<f32>;

@compute @workgroup_size(64)
fn ifs_main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    df_one = P.one;
    let k = id.x + id.y * groups.x * 64u;
    if k >= P.count {
        return;
    }
    let p = sample_point(k % P.width, P.row_offset + k / P.width);
    density_out[k] = ifs_density(p.x, p.z);
}
