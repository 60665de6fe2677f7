// The f32 precision (the default: every GPU, fastest): the scalar every kernel is written
// over, and the pieces whose f32 form differs from the f64 one (real_f64.wgsl). Assembled by
// src/gpu/shaders.rs in front of common.wgsl.

alias real = f32;

// Machine epsilon of real.
const EPSILON: real = 1.1920929e-7;
// f32(pi) rounds up to 3.1415927, so |theta| > PI is the f32 form of |theta| > pi.
const PI: f32 = 3.14159265358979;

// 3-point Gauss-Legendre on [0, 1] for the drag along the lower rod.
const GAUSS_X: vec3<f32> = vec3<f32>(0.1127016654, 0.5, 0.8872983346);
const GAUSS_W: vec3<f32> = vec3<f32>(0.2777777778, 0.4444444444, 0.2777777778);

// Bisections that locate a crossing inside a step: 2^-24, f32's resolution of the fraction.
const BISECTIONS: i32 = 24;

// Whether no component is infinite or NaN (by the exponent bits: `x != x` may be folded).
fn is_finite4(v: vec4<f32>) -> bool {
    let exponent = bitcast<vec4<u32>>(v) & vec4<u32>(0x7f800000u);
    return all(exponent != vec4<u32>(0x7f800000u));
}

// (sin x, cos x) with one shared range reduction: x = q pi/2 + r by Cody-Waite with fma (two
// parts of pi/2), then Cephes' minimax polynomials on |r| <= pi/4, then the quadrant q mod 4.
// About 2 ulp for |x| < 1e4 rad. Twice as fast on lavapipe as the built-in sin and cos, which
// reduce their argument separately.
fn sincos(x: f32) -> vec2<f32> {
    let q = round(x * 0.63661975);
    let r = fma(q, 4.371139e-8, fma(-q, 1.5707964, x));
    let r2 = r * r;
    let s = fma(r * r2, fma(r2, fma(r2, -1.9515296e-4, 8.332161e-3), -1.6666655e-1), r);
    let c = fma(r2 * r2, fma(r2, fma(r2, 2.4433157e-5, -1.3887316e-3), 4.1666646e-2), fma(-0.5, r2, 1.0));
    let quadrant = i32(q) & 3;
    let sc = select(vec2<f32>(s, c), vec2<f32>(c, -s), (quadrant & 1) != 0);
    return select(sc, -sc, (quadrant & 2) != 0);
}

fn energy(c: Coeffs, y: vec4<f32>) -> f32 {
    let kinetic = 0.5 * c.a * y.y * y.y + 0.5 * c.b * y.w * y.w + c.c * y.y * y.w * cos(y.x - y.z);
    return kinetic - c.p * cos(y.x) - c.q * cos(y.z);
}

// ln x: the built-in log is f32.
fn ln_real(x: f32) -> f32 {
    return log(x);
}
