// Escape-time iteration of z -> z^2 + c, one invocation per sample, in f32 or in
// double-float (whichever number prelude, num_f32.wgsl or num_df.wgsl, precedes this
// text), with the per-sample quantities of docs/design.md (N, NF, T, DEX/DEY) and the
// bitmap orbit trap. Written after GLSL versions of Inigo Quilez's "Bitmap Orbit Traps"
// and "Distance Rendering for Fractals", with their slips fixed: the Mandelbrot
// derivative adds 1 (not (1, 1)), the Julia derivative adds nothing, escape is |z| > R
// with the scene's R (not 2), and the distance is measured in pixels. The semantics
// follow src/field (scalar kernel):
//
// * Mandelbrot starts at z_1 = c, dz_1 = 1 (n = 1); Julia at z_0 = pixel, dz_0 = 1 (n = 0).
// * Each step first lets the trap see z_n (n >= 1), then tests |z_n|^2 > R^2 (escape with
//   N = n), then n >= max_iter (interior), then advances dz and z.
// * The derivative is carried in f32 and in units of the pixel spacing (dz_1 = spacing,
//   Mandelbrot adds spacing each step), so it cannot overflow at any depth the arithmetic
//   resolves, and the distance comes out in pixels directly.
// * Interior samples in the main cardioid and period-2 bulb stop at once when no trap
//   needs their orbit (as the CPU kernels do); there is no periodicity check.

@group(0) @binding(1) var<storage, read> trap_texels: array<vec4<f32>>;

const INTERIOR: u32 = 0xffffffffu;
const NO_PLANE: u32 = 0xffffffffu;
// Largest f32 below 1: NF and T are clamped into [0, 1).
const BELOW_ONE: f32 = 0.99999994;
const DISTANCE_CAP: f32 = 1e30;
const TAU: f32 = 6.2831855;

struct Escape {
    n: u32,
    z: vec2<f32>,
    // dz_n / spacing (d z_n / d pixel).
    dz: vec2<f32>,
    // First bitmap-trap colour whose alpha passed the threshold (zero: none).
    trap: vec4<f32>,
}

fn in_main_components(c: vec2<f32>) -> bool {
    let y2 = c.y * c.y;
    let xq = c.x - 0.25;
    let q = xq * xq + y2;
    if q * (q + xq) <= 0.25 * y2 {
        return true;
    }
    let xb = c.x + 1.0;
    return xb * xb + y2 <= 0.0625;
}

// Bilinear sample of the trap bitmap (linear premultiplied RGBA) at the orbit point z, as
// BitmapTrap::sample: rotate z - centre by -angle, scale to texture coordinates (v down),
// clamp to [0, 1], filter within the frame's columns only.
fn trap_sample(z: vec2<f32>) -> vec4<f32> {
    let d = z - vec2<f32>(P.trap_center_x, P.trap_center_y);
    let rx = P.trap_cos * d.x + P.trap_sin * d.y;
    let ry = -P.trap_sin * d.x + P.trap_cos * d.y;
    let u = clamp(0.5 + rx / P.trap_width, 0.0, 1.0);
    let v = clamp(0.5 - ry / P.trap_height, 0.0, 1.0);
    let cols = P.trap_columns;
    let rows = P.trap_texture_height;
    let fx = u * f32(cols) - 0.5;
    let fy = v * f32(rows) - 0.5;
    let x0 = floor(fx);
    let y0 = floor(fy);
    let tx = fx - x0;
    let ty = fy - y0;
    let last_x = f32(cols - 1u);
    let last_y = f32(rows - 1u);
    let xa = P.trap_first_column + u32(clamp(x0, 0.0, last_x));
    let xb = P.trap_first_column + u32(clamp(x0 + 1.0, 0.0, last_x));
    let ya = u32(clamp(y0, 0.0, last_y)) * P.trap_texture_width;
    let yb = u32(clamp(y0 + 1.0, 0.0, last_y)) * P.trap_texture_width;
    let p00 = trap_texels[ya + xa];
    let p10 = trap_texels[ya + xb];
    let p01 = trap_texels[yb + xa];
    let p11 = trap_texels[yb + xb];
    let top = p00 + (p10 - p00) * tx;
    let bottom = p01 + (p11 - p01) * tx;
    return top + (bottom - top) * ty;
}

fn no_escape() -> Escape {
    return Escape(INTERIOR, vec2<f32>(0.0), vec2<f32>(0.0), vec4<f32>(0.0));
}

// One orbit from the sample point p = (x_hi, x_lo, y_hi, y_lo), in the number type `Num` of
// the prelude the module was built with (num_f32.wgsl or num_df.wgsl). Only z and c are in
// `Num`: the escape test, the trap and the derivative read z's f32 value, which is all
// they need.
fn escape(p: vec4<f32>) -> Escape {
    var e = no_escape();
    let de = (P.flags & FLAG_DERIVATIVE) != 0u;
    let trap = (P.flags & FLAG_TRAP) != 0u;
    var zx = num_from_df(p.xy);
    var zy = num_from_df(p.zw);
    var cx = zx;
    var cy = zy;
    var n = 1u;
    var add = P.spacing_hi;
    if P.family == FAMILY_JULIA {
        cx = num_from_df(vec2<f32>(P.julia_x_hi, P.julia_x_lo));
        cy = num_from_df(vec2<f32>(P.julia_y_hi, P.julia_y_lo));
        n = 0u;
        add = 0.0;
    } else if !trap && in_main_components(vec2<f32>(p.x, p.z)) {
        return e;
    }
    var dz = vec2<f32>(P.spacing_hi, 0.0);
    var hit = false;
    loop {
        let z = vec2<f32>(num_f32(zx), num_f32(zy));
        if trap && !hit && n >= 1u {
            let s = trap_sample(z);
            if s.w > P.trap_threshold {
                e.trap = s;
                hit = true;
            }
        }
        if z.x * z.x + z.y * z.y > P.escape_r2 {
            e.n = n;
            e.z = z;
            e.dz = dz;
            return e;
        }
        if n >= P.max_iter {
            return e;
        }
        if de {
            dz = vec2<f32>(2.0 * (z.x * dz.x - z.y * dz.y) + add, 2.0 * (z.x * dz.y + z.y * dz.x));
        }
        let xy2 = num_twice_mul(zx, zy);
        zx = num_add(num_sub(num_sqr(zx), num_sqr(zy)), cx);
        zy = num_add(xy2, cy);
        n += 1u;
    }
    return e;
}

// |z| without overflow (z_n may reach R^2).
fn abs_c(z: vec2<f32>) -> f32 {
    let m = max(abs(z.x), abs(z.y));
    if m == 0.0 {
        return 0.0;
    }
    let r = min(abs(z.x), abs(z.y)) / m;
    return m * sqrt(1.0 + r * r);
}

// ln |z| for |z| > 0, without overflow.
fn ln_abs(z: vec2<f32>) -> f32 {
    let m = max(abs(z.x), abs(z.y));
    let r = min(abs(z.x), abs(z.y)) / m;
    return log(m) + 0.5 * log(1.0 + r * r);
}

// NF = 1 - log2(ln|z_n| / ln R), clamped to [0, 1).
fn smooth_fraction(z: vec2<f32>) -> f32 {
    return clamp(1.0 - log2(ln_abs(z) / P.ln_escape), 0.0, BELOW_ONE);
}

// T = arg(z_n) in turns, in [0, 1).
fn phase(z: vec2<f32>) -> f32 {
    var t = atan2(z.y, z.x) / TAU;
    if t < 0.0 {
        t += 1.0;
    }
    return clamp(t, 0.0, BELOW_ONE);
}

// The distance estimate |z| ln|z| / |dz| in pixels (dz is already per pixel), as the
// vector of that length along conj(dz / z); capped at DISTANCE_CAP, and (d, 0) when the
// direction is undefined, as quantities::distance_vector does.
fn distance_vector(z: vec2<f32>, dz: vec2<f32>) -> vec2<f32> {
    let az = abs_c(z);
    let adz = abs_c(dz);
    let num = az * ln_abs(z);
    if adz <= 0.0 || num >= DISTANCE_CAP * adz {
        return vec2<f32>(DISTANCE_CAP, 0.0);
    }
    let d = num / adz;
    let uz = z / az;
    let udz = dz / adz;
    let w = vec2<f32>(udz.x * uz.x + udz.y * uz.y, udz.x * uz.y - udz.y * uz.x);
    let lw = length(w);
    if lw > 0.0 {
        return w * (d / lw);
    }
    return vec2<f32>(d, 0.0);
}

@group(0) @binding(2) var<storage, read_write> planes_out: array<u32>;

// Writes sample k of the chunk into the planes the uniforms name (plane p of the chunk
// starts at p * count; N is plane 0).
fn store(k: u32, e: Escape) {
    let count = P.count;
    planes_out[k] = e.n;
    let escaped = e.n != INTERIOR;
    if P.plane_nf != NO_PLANE {
        var v = 0.0;
        if escaped {
            v = smooth_fraction(e.z);
        }
        planes_out[P.plane_nf * count + k] = bitcast<u32>(v);
    }
    if P.plane_t != NO_PLANE {
        var v = 0.0;
        if escaped {
            v = phase(e.z);
        }
        planes_out[P.plane_t * count + k] = bitcast<u32>(v);
    }
    if P.plane_de != NO_PLANE {
        var v = vec2<f32>(0.0);
        if escaped {
            v = distance_vector(e.z, e.dz);
        }
        planes_out[P.plane_de * count + k] = bitcast<u32>(v.x);
        planes_out[(P.plane_de + 1u) * count + k] = bitcast<u32>(v.y);
    }
    if P.plane_trap != NO_PLANE {
        for (var c = 0u; c < 4u; c += 1u) {
            planes_out[(P.plane_trap + c) * count + k] = bitcast<u32>(e.trap[c]);
        }
    }
}

// One invocation per sample of the chunk: rows row_offset .. row_offset + count / width.
// The dispatch may be two-dimensional when a chunk needs more than 65535 workgroups.
fn chunk_sample(id: vec3<u32>, groups: vec3<u32>) -> vec3<u32> {
    let k = id.x + id.y * groups.x * 64u;
    return vec3<u32>(k, k % P.width, P.row_offset + k / P.width);
}

@compute @workgroup_size(64)
fn escape_main(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    df_one = P.one;
    let s = chunk_sample(id, groups);
    if s.x >= P.count {
        return;
    }
    store(s.x, escape(sample_point(s.y, s.z)));
}
