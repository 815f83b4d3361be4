// Double-float ("df") arithmetic: a value is vec2<f32>(hi, lo) with value = hi + lo and
// |lo| <= ulp(hi) / 2, about 48 significant bits from two f32s.
//
// The building blocks are Knuth's two-sum and Dekker's two-product (with Veltkamp's
// splitting, since WGSL guarantees no fused multiply-add). Both rely on every f32 add and
// multiply being rounded exactly once, in the order written. Shader compilers may
// reassociate float arithmetic (WGSL and SPIR-V without NoContraction allow it), and
// algebraic rewrites such as `(a + b) - a -> b` or `t - (t - a) -> a` would silently turn
// the error terms into zero. So one operand of every such pattern is multiplied by
// `df_one`, a private copy of a uniform that is 1.0 at run time: the product is exact,
// and the compiler cannot see through it. Each entry point must set `df_one` first.
// Contraction into fma is harmless here: the products it could fuse are exact.
// `tests/integration/gpu.rs` checks the error terms on the device bit for bit against
// the same operations in f64.

var<private> df_one: f32 = 1.0;

// a + b = s + e exactly (Knuth).
fn two_sum(a: f32, b: f32) -> vec2<f32> {
    let s = a + b;
    let bb = s * df_one - a;
    let e = (a - (s - bb * df_one)) + (b - bb);
    return vec2<f32>(s, e);
}

// a + b = s + e exactly, given |a| >= |b| (or a == 0).
fn quick_two_sum(a: f32, b: f32) -> vec2<f32> {
    let s = a + b;
    let e = b - (s * df_one - a);
    return vec2<f32>(s, e);
}

// Veltkamp's split: a = hi + lo with hi and lo of at most 12 significant bits each.
fn df_split(a: f32) -> vec2<f32> {
    let t = 4097.0 * a;
    let hi = t * df_one - (t - a);
    return vec2<f32>(hi, a - hi * df_one);
}

// a * b = p + e exactly (Dekker).
fn two_prod(a: f32, b: f32) -> vec2<f32> {
    let p = a * b;
    let sa = df_split(a);
    let sb = df_split(b);
    let e = ((sa.x * sb.x - p * df_one) + sa.x * sb.y + sa.y * sb.x) + sa.y * sb.y;
    return vec2<f32>(p, e);
}

// a^2 = p + e exactly.
fn two_sqr(a: f32) -> vec2<f32> {
    let p = a * a;
    let s = df_split(a);
    let e = ((s.x * s.x - p * df_one) + 2.0 * s.x * s.y) + s.y * s.y;
    return vec2<f32>(p, e);
}

// a + b, both df. Error below about 2^-46 of max(|a|, |b|) ("sloppy" addition: exact
// enough for an orbit, whose rounding is relative to |z| anyway).
fn df_add(a: vec2<f32>, b: vec2<f32>) -> vec2<f32> {
    let s = two_sum(a.x, b.x);
    return quick_two_sum(s.x, s.y + (a.y + b.y));
}

fn df_sub(a: vec2<f32>, b: vec2<f32>) -> vec2<f32> {
    return df_add(a, -b);
}

// a * b, both df.
fn df_mul(a: vec2<f32>, b: vec2<f32>) -> vec2<f32> {
    let p = two_prod(a.x, b.x);
    return quick_two_sum(p.x, p.y + (a.x * b.y + a.y * b.x));
}

// a * b, a df and b an f32.
fn df_mul_f(a: vec2<f32>, b: f32) -> vec2<f32> {
    let p = two_prod(a.x, b);
    return quick_two_sum(p.x, p.y + a.y * b);
}

// a^2.
fn df_sqr(a: vec2<f32>) -> vec2<f32> {
    let p = two_sqr(a.x);
    return quick_two_sum(p.x, p.y + 2.0 * a.x * a.y);
}
