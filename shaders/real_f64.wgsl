// The f64 precision (adapters with SHADER_F64; lavapipe has it): the scalar every kernel is
// written over, and the pieces whose f64 form differs from the f32 one (real_f32.wgsl): SPIR-V's
// sin, cos and log are f32 only, so f64 has its own. Assembled by src/gpu/shaders.rs in front
// of common.wgsl.

alias real = f64;

const PI: f64 = 3.141592653589793;

// Machine epsilon of real.
const EPSILON: real = 2.220446049250313e-16;
// 3-point Gauss-Legendre on [0, 1] for the drag along the lower rod.
const GAUSS_X: vec3<f64> = vec3<f64>(0.1127016653792583, 0.5, 0.8872983346207417);
const GAUSS_W: vec3<f64> = vec3<f64>(0.2777777777777778, 0.4444444444444444, 0.2777777777777778);

// Bisections that locate a crossing inside a step: 2^-53, f64's resolution of the fraction.
const BISECTIONS: i32 = 53;

// NaN fails every comparison, infinities fail this one.
fn is_finite4(v: vec4<f64>) -> bool {
    return all(abs(v) <= vec4<f64>(1.7976931348623157e308));
}

// (sin x, cos x) in f64: x = q pi/2 + r with pi/2 in three parts (Cody-Waite, fdlibm's
// constants), Taylor polynomials to r^17 and r^18 on |r| <= pi/4 (the next terms are below
// 1e-19), the quadrant q mod 4. tests/precision.rs measures it against Rust's sin and cos.
fn sincos(x: f64) -> vec2<f64> {
    let q = round(x * 0.6366197723675814);
    let r = fma(-q, 2.0222662487111665e-21, fma(-q, 6.077100506303966e-11, fma(-q, 1.5707963267341256, x)));
    let r2 = r * r;
    var s: f64 = 2.8114572543455206e-15;
    s = fma(s, r2, -7.647163731819816e-13);
    s = fma(s, r2, 1.6059043836821613e-10);
    s = fma(s, r2, -2.505210838544172e-8);
    s = fma(s, r2, 2.7557319223985893e-6);
    s = fma(s, r2, -1.984126984126984e-4);
    s = fma(s, r2, 8.333333333333333e-3);
    s = fma(s, r2, -1.6666666666666666e-1);
    s = fma(s * r2, r, r);
    var c: f64 = -1.5619206968586225e-16;
    c = fma(c, r2, 4.779477332387385e-14);
    c = fma(c, r2, -1.1470745597729725e-11);
    c = fma(c, r2, 2.08767569878681e-9);
    c = fma(c, r2, -2.755731922398589e-7);
    c = fma(c, r2, 2.48015873015873e-5);
    c = fma(c, r2, -1.388888888888889e-3);
    c = fma(c, r2, 4.1666666666666664e-2);
    c = fma(c * r2, r2, fma(-0.5, r2, 1.0));
    let quadrant = i32(q) & 3;
    let sc = select(vec2<f64>(s, c), vec2<f64>(c, -s), (quadrant & 1) != 0);
    return select(sc, -sc, (quadrant & 2) != 0);
}

// The energy from sincos (no f64 cos).
fn energy(c: Coeffs, y: vec4<f64>) -> f64 {
    let a = sincos(y.x);
    let b = sincos(y.z);
    let cd = a.y * b.y + a.x * b.x;
    let kinetic = 0.5 * c.a * y.y * y.y + 0.5 * c.b * y.w * y.w + c.c * y.y * y.w * cd;
    return kinetic - c.p * a.y - c.q * b.y;
}

// ln x in f64: x = m 2^e with m in [sqrt(1/2), sqrt(2)), ln m = 2 atanh(s) with
// s = (m - 1) / (m + 1), |s| <= 0.1716, by its series to s^23 (the next term is below
// 1e-21), plus e ln 2 in two parts (fdlibm's). tests/precision.rs measures it.
fn ln_real(x: f64) -> f64 {
    // x = m 2^e with m in [1, 2), by exact powers of two 2^512, 2^256, ... 2^1 (naga's f64
    // frexp returns an i64, which would need SHADER_INT64, and its bitcast of f64 to a pair
    // of u32 is not available). Positive, normal x.
    var m = x;
    var e: f64 = 0.0;
    var power: f64 = 1.3407807929942597e154;
    var k: f64 = 512.0;
    for (var i = 0; i < 10; i++) {
        if m >= power {
            m = m / power;
            e = e + k;
        }
        if m * power < 2.0 {
            m = m * power;
            e = e - k;
        }
        power = sqrt(power);
        k = 0.5 * k;
    }
    if m > 1.4142135623730951 {
        m = 0.5 * m;
        e = e + 1.0;
    }
    let s = (m - 1.0) / (m + 1.0);
    let s2 = s * s;
    var p: f64 = 0.043478260869565216;
    p = fma(p, s2, 0.047619047619047616);
    p = fma(p, s2, 0.05263157894736842);
    p = fma(p, s2, 0.058823529411764705);
    p = fma(p, s2, 0.06666666666666667);
    p = fma(p, s2, 0.07692307692307693);
    p = fma(p, s2, 0.09090909090909091);
    p = fma(p, s2, 0.1111111111111111);
    p = fma(p, s2, 0.14285714285714285);
    p = fma(p, s2, 0.2);
    p = fma(p, s2, 0.3333333333333333);
    let ln_m = 2.0 * s + 2.0 * s * s2 * p;
    return fma(e, 0.6931471803691238, fma(e, 1.9082149292705877e-10, ln_m));
}
