// Color helpers shared by every shader. Mirrored in crates/render/src/cpu.rs.

// Rec. 709 / sRGB luminance of linear RGB.
fn luminance(c: vec3f) -> f32 {
    return dot(c, vec3f(0.2126, 0.7152, 0.0722));
}

// Linear -> sRGB transfer function, per channel, input clamped to [0, 1].
fn srgb_encode(linear: vec3f) -> vec3f {
    let c = clamp(linear, vec3f(0.0), vec3f(1.0));
    let lo = c * 12.92;
    let hi = 1.055 * pow(c, vec3f(1.0 / 2.4)) - 0.055;
    return select(hi, lo, c <= vec3f(0.0031308));
}

// sRGB -> linear transfer function, per channel.
fn srgb_decode(encoded: vec3f) -> vec3f {
    let c = clamp(encoded, vec3f(0.0), vec3f(1.0));
    let lo = c / 12.92;
    let hi = pow((c + 0.055) / 1.055, vec3f(2.4));
    return select(hi, lo, c <= vec3f(0.04045));
}
