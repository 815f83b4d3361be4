// The orbit's number type in plain f32: a coordinate is one f32. escape.wgsl's loop is
// written once against these functions; num_df.wgsl defines the same ones in double-float.

alias Num = f32;

// A coordinate from its double-float value (hi, lo): the high part.
fn num_from_df(v: vec2<f32>) -> Num {
    return v.x;
}

// The coordinate's nearest f32.
fn num_f32(a: Num) -> f32 {
    return a;
}

fn num_add(a: Num, b: Num) -> Num {
    return a + b;
}

fn num_sub(a: Num, b: Num) -> Num {
    return a - b;
}

// a^2.
fn num_sqr(a: Num) -> Num {
    return a * a;
}

// 2 a b.
fn num_twice_mul(a: Num, b: Num) -> Num {
    return 2.0 * a * b;
}
