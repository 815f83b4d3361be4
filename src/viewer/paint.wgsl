// Draws the escape-time image straight into a render target (the egui frame): one
// fragment per physical pixel runs the same orbit code as the compute shader
// (escape.wgsl, after the number prelude of the chosen precision), colours it by smooth iteration through a palette table, optionally
// multiplies Inigo Quilez's soft distance shading over it, and encodes for the target.

@group(0) @binding(3) var<storage, read> palette: array<vec4<f32>>;

// One triangle that covers the whole viewport; the fragment position says which pixel.
@vertex
fn paint_vs(@builtin(vertex_index) v: u32) -> @builtin(position) vec4<f32> {
    let x = f32((v << 1u) & 2u) * 2.0 - 1.0;
    let y = f32(v & 2u) * 2.0 - 1.0;
    return vec4<f32>(x, y, 0.0, 1.0);
}

// The palette table (linear RGBA at positions k / len, k = 0 .. len - 1, periodic) at
// position `pos`, linearly interpolated; `pos` arrives as a double-float so that large
// iteration counts times the density keep their fraction.
fn palette_at(pos: vec2<f32>) -> vec4<f32> {
    let u = fract(fract(pos.x) + pos.y);
    let n = P.palette_len;
    let f = u * f32(n);
    let i0 = min(u32(f), n - 1u);
    let i1 = (i0 + 1u) % n;
    let w = f - f32(i0);
    return mix(palette[i0], palette[i1], w);
}

// sRGB transfer function (the exact piecewise curve).
fn srgb_from_linear(c: vec3<f32>) -> vec3<f32> {
    let lo = c * 12.92;
    let hi = 1.055 * pow(max(c, vec3<f32>(0.0031308)), vec3<f32>(1.0 / 2.4)) - 0.055;
    return select(hi, lo, c <= vec3<f32>(0.0031308));
}

fn linear_from_srgb(c: f32) -> f32 {
    if c <= 0.04045 {
        return c / 12.92;
    }
    return pow((c + 0.055) / 1.055, 2.4);
}

// Linear premultiplied colour of one orbit.
fn colour(e: Escape) -> vec4<f32> {
    if e.n == INTERIOR {
        let c = vec4<f32>(P.interior_r, P.interior_g, P.interior_b, P.interior_a);
        return vec4<f32>(c.rgb * c.a, c.a);
    }
    let nf = smooth_fraction(e.z);
    let pos = df_add(two_prod(f32(e.n), P.palette_density), vec2<f32>(nf * P.palette_density + P.palette_offset, 0.0));
    let c = palette_at(pos);
    var rgb = c.rgb * c.a;
    if (P.flags & FLAG_DISTANCE_SHADE) != 0u {
        // Inigo Quilez's soft distance colouring, clamp((k d)^0.2, 0, 1) with d in pixels, read
        // as an sRGB grey level (as the CPU's distance layer without a palette) and
        // multiplied over the palette colour in linear light.
        let d = length(distance_vector(e.z, e.dz));
        let g = clamp(pow(max(P.distance_k * d, 1e-30), 0.2), 0.0, 1.0);
        rgb *= linear_from_srgb(g);
    }
    return vec4<f32>(rgb, c.a);
}

// Pixel (i, j) of the image from the fragment position (pixel centres at +0.5) and the
// image's top-left corner in target pixels.
fn pixel(frag: vec4<f32>) -> vec2<u32> {
    let local = floor(frag.xy - vec2<f32>(P.origin_x, P.origin_y));
    let i = u32(clamp(local.x, 0.0, f32(P.width - 1u)));
    let j = u32(clamp(local.y, 0.0, f32(P.height - 1u)));
    return vec2<u32>(i, j);
}

// Opaque output: the premultiplied colour over black, sRGB-encoded unless the target
// format encodes by itself.
fn encode(c: vec4<f32>) -> vec4<f32> {
    let rgb = clamp(c.rgb, vec3<f32>(0.0), vec3<f32>(1.0));
    if P.encode_srgb != 0u {
        return vec4<f32>(srgb_from_linear(rgb), 1.0);
    }
    return vec4<f32>(rgb, 1.0);
}

@fragment
fn paint_fs(@builtin(position) frag: vec4<f32>) -> @location(0) vec4<f32> {
    df_one = P.one;
    let ij = pixel(frag);
    return encode(colour(escape(sample_point(ij.x, ij.y))));
}
