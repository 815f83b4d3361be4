// The orbit's number type in double-float (df.wgsl): a coordinate is vec2<f32>(hi, lo).
// escape.wgsl's loop is written once against these functions; num_f32.wgsl defines the
// same ones in plain f32.

alias Num = vec2<f32>;

// A coordinate from its double-float value (hi, lo): all of it.
fn num_from_df(v: vec2<f32>) -> Num {
    return v;
}

// The coordinate's nearest f32 (the high part).
fn num_f32(a: Num) -> f32 {
    return a.x;
}

fn num_add(a: Num, b: Num) -> Num {
    return df_add(a, b);
}

fn num_sub(a: Num, b: Num) -> Num {
    return df_sub(a, b);
}

// a^2.
fn num_sqr(a: Num) -> Num {
    return df_sqr(a);
}

// 2 a b (doubling is exact).
fn num_twice_mul(a: Num, b: Num) -> Num {
    return df_mul(a, b) * 2.0;
}
