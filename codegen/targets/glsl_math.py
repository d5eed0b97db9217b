"""The scalar functions the GLSL kernels call, as GLSL source: ``<prefix>_lib_<name>``.

GLSL has no double overloads of exp, log, sin, cos, atan, acos, atanh, sinh, cosh and pow, and no cbrt
in any precision. Evaluating them in float (``double(sin(float(x)))``) would not only cap the double
kernels at ~1e-7: versor_exp's c = (θ − sin θ)/θ³ cancels, so a float sin gives ~1e-4 there. So the
double include carries its own double-precision implementations (a few ulp on the tested ranges):

exp     x = k ln2 + r (Cody–Waite ln2 in two parts, |r| <= ln2/2), Taylor degree 13, scaled by 2^k in two
        ldexp steps (GLSL's ldexp is undefined beyond 2^±1024); subnormal results (x < -708.4) flush to 0
log     (subnormal x scaled by 2^54 first, for frexp) x = m 2^e with m in [sqrt(1/2), sqrt(2)), log m = 2 atanh(s), s = (m-1)/(m+1), |s| <= 0.172, odd
        series to s^23
sin cos x = k π/2 + r with π/2 in three 33-bit parts (exact products for |k| < 2^20, i.e. |x| < 1.6e6;
        beyond that the reduction loses accuracy), Taylor to r^17 / r^18 on |r| <= π/4
atan2   ratio t in [0, 1]; t > tan(π/8): π/4 + atan((t-1)/(t+1)); Taylor to u^45 on |u| <= tan(π/8);
        octant, quadrant and the signed-zero cases as C's atan2
acos    |x| <= 1/2: π/2 - asin x; x > 1/2: 2 asin s, s = sqrt((1-x)/2) (1-x exact) with the rounding
        of s corrected (s = h + (z - h²)/(s + h), h its leading 21 bits); x < -1/2: π - 2 asin s, s =
        sqrt((1+x)/2); asin s = s + s z p(z), z = s² <= 1/4, Taylor to s^49: under 1 ulp (the float
        include's atan2(sqrt((1-x)(1+x)), x) reached 3 ulp in double, at x = 0.55: the roundings of the
        square root and of the ratio went through atan)
atanh   ±0.5 log1p(2|x|/(1-|x|)), log1p(u) = log(1+u) u/((1+u)-1)
sinh cosh  Taylor to x^21 for |x| < 1 (sinh), (e ± 1/e)/2 otherwise, e^(|x|/2)² /2 near overflow
cbrt    (both precisions) x = m 2^(3q+r): a float pow estimate of cbrt(m 2^r) in [0.79, 1.59], Newton steps
        (two in double, one in float), times 2^q: no overflow or underflow at any finite x

The reductions are declared ``precise`` so that the compiler neither fuses nor reassociates them.

The float include uses GLSL's own exp, sin, cos and cosh (measured on Mesa llvmpipe: 1.1e-7 relative
for sin/cos on [-10, 10], 1e-6 for exp/cosh) and the same algorithms as above, in float, for log,
atan2, atanh and sinh, and acos as atan2(sqrt((1-x)(1+x)), x) (within 4 float ulp), which GLSL does
not make accurate: llvmpipe's float atan is 2e-5 relative, acos 1.6e-4 absolute, log 1.6e-6 absolute
near 1 (unbounded relative), sinh and atanh lose relative accuracy near 0 (GLSL 4.60 section 8.1 gives
no precision for the trigonometric functions at all).
"""
from __future__ import annotations

import math
from fractions import Fraction

#: sympy function name -> GLSL helper name (without the prefix) in the double include
DOUBLE_FUNCTIONS = ("exp", "log", "sin", "cos", "atan2", "acos", "atanh", "sinh", "cosh")
#: ... and in the float include (the others are GLSL's float built-ins)
FLOAT_FUNCTIONS = ("log", "atan2", "acos", "atanh", "sinh")

_DOUBLE = """\
double P_lib_nan() { return packDouble2x32(uvec2(0u, 0x7ff80000u)); }
double P_lib_inf() { return packDouble2x32(uvec2(0u, 0x7ff00000u)); }
bool P_lib_signbit(double x) { return (unpackDouble2x32(x).y & 0x80000000u) != 0u; }

// 2^k for |k| up to ~2100 (two steps: GLSL's ldexp is undefined beyond 2^1024)
double P_lib_scale(double x, int k) {
    int h = k >> 1;
    return ldexp(ldexp(x, h), k - h);
}

double P_lib_exp(double x) {
    if (isnan(x)) return x;
    if (x > 709.782712893384lf) return P_lib_inf();
    if (x < -745.1332191019412lf) return 0.0lf;
    double k = floor(x * 1.4426950408889634lf + 0.5lf);
    precise double r = (x - k * 6.93147180369123816490e-01lf) - k * 1.90821492927058770002e-10lf;
    double p = 1.0lf / 6227020800.0lf;
    p = p * r + 1.0lf / 479001600.0lf;
    p = p * r + 1.0lf / 39916800.0lf;
    p = p * r + 1.0lf / 3628800.0lf;
    p = p * r + 1.0lf / 362880.0lf;
    p = p * r + 1.0lf / 40320.0lf;
    p = p * r + 1.0lf / 5040.0lf;
    p = p * r + 1.0lf / 720.0lf;
    p = p * r + 1.0lf / 120.0lf;
    p = p * r + 1.0lf / 24.0lf;
    p = p * r + 1.0lf / 6.0lf;
    p = p * r + 0.5lf;
    p = p * r + 1.0lf;
    p = p * r + 1.0lf;
    return P_lib_scale(p, int(k));
}

double P_lib_log(double x) {
    if (isnan(x) || x < 0.0lf) return P_lib_nan();
    if (x == 0.0lf) return -P_lib_inf();
    if (isinf(x)) return x;
    int e, sub = 0;
    if (x < 2.2250738585072014e-308lf) { x *= 18014398509481984.0lf; sub = 54; }    // frexp needs a normal x
    double m = frexp(x, e);
    e -= sub;
    if (m < 0.70710678118654752lf) { m = 2.0lf * m; e = e - 1; }
    precise double f = m - 1.0lf;
    double s = f / (2.0lf + f);
    double s2 = s * s;
    double p = LOG_SERIES;                               // sum of s2^n / (2n + 1), n <= 11
    double de = double(e);
    precise double lo = de * 1.90821492927058770002e-10lf + 2.0lf * s * p;
    return de * 6.93147180369123816490e-01lf + lo;
}

// log(1 + u), accurate for small u (the rounding of 1 + u is divided out)
double P_lib_log1p(double u) {
    precise double w = 1.0lf + u;
    if (w == 1.0lf) return u;
    precise double d = w - 1.0lf;
    return P_lib_log(w) * (u / d);
}

// x - k π/2, k = round(x 2/π); the quadrant k mod 4 in q
double P_lib_reduce(double x, out int q) {
    double k = floor(x * 0.63661977236758134lf + 0.5lf);
    q = int(mod(k, 4.0lf));
    precise double r = ((x - k * 1.57079632673412561417e+00lf) - k * 6.07710050630396597660e-11lf)
                       - k * 2.02226624871116645580e-21lf;
    return r;
}

double P_lib_sin_poly(double r) {
    double r2 = r * r;
    double p = -1.0lf / 355687428096000.0lf;
    p = p * r2 + 1.0lf / 1307674368000.0lf;
    p = p * r2 - 1.0lf / 6227020800.0lf;
    p = p * r2 + 1.0lf / 39916800.0lf;
    p = p * r2 - 1.0lf / 362880.0lf;
    p = p * r2 + 1.0lf / 5040.0lf;
    p = p * r2 - 1.0lf / 120.0lf;
    p = p * r2 + 1.0lf / 6.0lf;
    return r - r * r2 * p;
}

double P_lib_cos_poly(double r) {
    double r2 = r * r;
    double p = -1.0lf / 6402373705728000.0lf;
    p = p * r2 + 1.0lf / 20922789888000.0lf;
    p = p * r2 - 1.0lf / 87178291200.0lf;
    p = p * r2 + 1.0lf / 479001600.0lf;
    p = p * r2 - 1.0lf / 3628800.0lf;
    p = p * r2 + 1.0lf / 40320.0lf;
    p = p * r2 - 1.0lf / 720.0lf;
    p = p * r2 + 1.0lf / 24.0lf;
    return 1.0lf - r2 * (0.5lf - r2 * p);
}

double P_lib_sin(double x) {
    if (isnan(x) || isinf(x)) return P_lib_nan();
    if (x == 0.0lf) return x;                             // keeps the sign of zero
    int q;
    double r = P_lib_reduce(x, q);
    double v = (q == 0 || q == 2) ? P_lib_sin_poly(r) : P_lib_cos_poly(r);
    return (q >= 2) ? -v : v;
}

double P_lib_cos(double x) {
    if (isnan(x) || isinf(x)) return P_lib_nan();
    int q;
    double r = P_lib_reduce(x, q);
    double v = (q == 0 || q == 2) ? P_lib_cos_poly(r) : P_lib_sin_poly(r);
    return (q == 1 || q == 2) ? -v : v;
}

// atan(t) for t in [0, 1]
double P_lib_atan01(double t) {
    bool upper = t > 0.41421356237309505lf;
    double u = upper ? (t - 1.0lf) / (t + 1.0lf) : t;
    double u2 = u * u;
    double p = ATAN_SERIES;                              // atan u = u + u^3 p(u^2), to u^45
    double a = u + u * u2 * p;
    precise double shifted = 7.85398163397448278999e-01lf + (a + 3.06161699786838301793e-17lf);
    return upper ? shifted : a;
}

double P_lib_atan2(double y, double x) {
    if (isnan(x) || isnan(y)) return P_lib_nan();
    double ax = abs(x), ay = abs(y);
    double a;
    if (ax == ay) a = (ax == 0.0lf) ? 0.0lf : 7.85398163397448278999e-01lf;
    else if (ay < ax) a = P_lib_atan01(ay / ax);
    else { precise double c = 1.57079632679489655800e+00lf - (P_lib_atan01(ax / ay) - 6.12323399573676603587e-17lf); a = c; }
    if (P_lib_signbit(x)) { precise double c = 3.14159265358979311600e+00lf - (a - 1.22464679914735317720e-16lf); a = c; }
    return P_lib_signbit(y) ? -a : a;
}

// asin(s) - s for |s| <= 1/2, z = s^2: s z p(z), the Taylor series of asin to s^49
double P_lib_asin_tail(double s, double z) {
    double p = ASIN_SERIES;
    return s * (z * p);
}

double P_lib_acos(double x) {
    if (!(abs(x) <= 1.0lf)) return P_lib_nan();
    if (abs(x) <= 0.5lf) {                               // π/2 - asin x
        precise double v = 1.57079632679489655800e+00lf
                           - (x - (6.12323399573676603587e-17lf - P_lib_asin_tail(x, x * x)));
        return v;
    }
    if (x == 1.0lf) return 0.0lf;
    if (x > 0.0lf) {                                     // 2 asin s, s = sqrt((1 - x)/2): 1 - x is exact
        precise double z = (1.0lf - x) * 0.5lf;
        double s = sqrt(z);
        double h = packDouble2x32(uvec2(0u, unpackDouble2x32(s).y));      // s's leading 21 bits: h² is exact
        precise double v = 2.0lf * (h + (P_lib_asin_tail(s, z) + (z - h * h) / (s + h)));
        return v;
    }
    precise double z = (1.0lf + x) * 0.5lf;              // π - 2 asin s, s = sqrt((1 + x)/2)
    double s = sqrt(z);
    precise double v = 3.14159265358979311600e+00lf
                       - 2.0lf * (s + (P_lib_asin_tail(s, z) - 6.12323399573676603587e-17lf));
    return v;
}

double P_lib_atanh(double x) {
    double ax = abs(x);
    if (!(ax <= 1.0lf)) return P_lib_nan();
    if (ax == 1.0lf) return x * P_lib_inf();
    if (x == 0.0lf) return x;                             // keeps the sign of zero
    // on |x|: for x < 0 the 1 + u inside log1p would cancel
    double v = 0.5lf * P_lib_log1p(2.0lf * ax / (1.0lf - ax));
    return x < 0.0lf ? -v : v;
}

double P_lib_sinh(double x) {
    double ax = abs(x), v;
    if (ax < 1.0lf) {
        double x2 = x * x;
        double p = 1.0lf / 51090942171709440000.0lf;
        p = p * x2 + 1.0lf / 121645100408832000.0lf;
        p = p * x2 + 1.0lf / 355687428096000.0lf;
        p = p * x2 + 1.0lf / 1307674368000.0lf;
        p = p * x2 + 1.0lf / 6227020800.0lf;
        p = p * x2 + 1.0lf / 39916800.0lf;
        p = p * x2 + 1.0lf / 362880.0lf;
        p = p * x2 + 1.0lf / 5040.0lf;
        p = p * x2 + 1.0lf / 120.0lf;
        p = p * x2 + 1.0lf / 6.0lf;
        return x + x * x2 * p;
    }
    if (ax > 709.0lf) { double h = P_lib_exp(0.5lf * ax); v = (0.5lf * h) * h; }
    else { double e = P_lib_exp(ax); v = 0.5lf * (e - 1.0lf / e); }
    return x < 0.0lf ? -v : v;
}

double P_lib_cosh(double x) {
    double ax = abs(x);
    if (ax > 709.0lf) { double h = P_lib_exp(0.5lf * ax); return (0.5lf * h) * h; }
    double e = P_lib_exp(ax);
    return 0.5lf * (e + 1.0lf / e);
}

double P_lib_cbrt(double x) {
    if (x == 0.0lf || isnan(x) || isinf(x)) return x;
    int e, sub = 0;
    double ax = abs(x);
    if (ax < 2.2250738585072014e-308lf) { ax *= 18014398509481984.0lf; sub = 54; }  // frexp needs a normal x
    double m = frexp(ax, e);
    e -= sub;
    int q = (e + 3000) / 3 - 1000, r = e - 3 * q;       // floor division, r in [0, 3)
    double a = ldexp(m, r);                              // in [0.5, 4)
    double y = double(pow(float(a), 1.0 / 3.0));
    y = y - (y * y * y - a) / (3.0lf * y * y);
    y = y - (y * y * y - a) / (3.0lf * y * y);
    return sign(x) * P_lib_scale(y, q);
}
"""

_FLOAT = """\
float P_lib_nanf() { return uintBitsToFloat(0x7fc00000u); }
bool P_lib_signbit(float x) { return (floatBitsToUint(x) & 0x80000000u) != 0u; }

float P_lib_log(float x) {
    if (isnan(x) || x < 0.0) return P_lib_nanf();
    if (x == 0.0) return -uintBitsToFloat(0x7f800000u);
    if (isinf(x)) return x;
    int e, sub = 0;
    if (x < 1.17549435e-38) { x *= 16777216.0; sub = 24; }           // frexp needs a normal x
    float m = frexp(x, e);
    e -= sub;
    if (m < 0.70710678) { m = 2.0 * m; e = e - 1; }
    precise float f = m - 1.0;
    float s = f / (2.0 + f);
    float s2 = s * s;
    float p = LOG_SERIES_F;                              // sum of s2^n / (2n + 1), n <= 5
    float de = float(e);
    precise float lo = de * 9.05800061445916e-06 + 2.0 * s * p;
    return de * 0.6931381225585938 + lo;
}

float P_lib_log1p(float u) {
    precise float w = 1.0 + u;
    if (w == 1.0) return u;
    precise float d = w - 1.0;
    return P_lib_log(w) * (u / d);
}

float P_lib_atan01(float t) {
    bool upper = t > 0.41421356;
    float u = upper ? (t - 1.0) / (t + 1.0) : t;
    float u2 = u * u;
    float p = ATAN_SERIES_F;                             // atan u = u + u^3 p(u^2), to u^21
    float a = u + u * u2 * p;
    precise float shifted = 0.7853981852531433 + (a - 2.1855694143368964e-08);
    return upper ? shifted : a;
}

float P_lib_atan2(float y, float x) {
    if (isnan(x) || isnan(y)) return P_lib_nanf();
    float ax = abs(x), ay = abs(y);
    float a;
    if (ax == ay) a = (ax == 0.0) ? 0.0 : 0.7853981852531433;
    else if (ay < ax) a = P_lib_atan01(ay / ax);
    else { precise float c = 1.5707963705062866 - (P_lib_atan01(ax / ay) + 4.371138828673793e-08); a = c; }
    if (P_lib_signbit(x)) { precise float c = 3.1415927410125732 - (a + 8.742277657347586e-08); a = c; }
    return P_lib_signbit(y) ? -a : a;
}

float P_lib_acos(float x) {
    if (!(abs(x) <= 1.0)) return P_lib_nanf();
    return P_lib_atan2(sqrt((1.0 - x) * (1.0 + x)), x);
}

float P_lib_atanh(float x) {
    float ax = abs(x);
    if (!(ax <= 1.0)) return P_lib_nanf();
    if (ax == 1.0) return x * uintBitsToFloat(0x7f800000u);
    if (x == 0.0) return x;
    float v = 0.5 * P_lib_log1p(2.0 * ax / (1.0 - ax));
    return x < 0.0 ? -v : v;
}

float P_lib_sinh(float x) {
    float ax = abs(x);
    if (ax < 1.0) { float x2 = x * x; return x + x * x2 * SINH_SERIES_F; }
    float v;
    if (ax > 88.0) { float h = exp(0.5 * ax); v = (0.5 * h) * h; }
    else { float e = exp(ax); v = 0.5 * (e - 1.0 / e); }
    return x < 0.0 ? -v : v;
}

float P_lib_cbrt(float x) {
    if (x == 0.0 || isnan(x) || isinf(x)) return x;
    int e;
    float m = frexp(abs(x), e);
    int q = (e + 300) / 3 - 100, r = e - 3 * q;         // floor division, r in [0, 3)
    float a = ldexp(m, r);                               // in [0.5, 4)
    float y = pow(a, 1.0 / 3.0);
    y = y - (y * y * y - a) / (3.0 * y * y);
    int h = q >> 1;
    return sign(x) * ldexp(ldexp(y, h), q - h);
}
"""


def _horner(var: str, coefficients, suffix: str = "lf") -> str:
    """c0 + var (c1 + var (c2 + ...)) with literals (no division left to the shader)."""
    text = f"{coefficients[-1]!r}{suffix}"
    for c in reversed(coefficients[:-1]):
        text = f"({c!r}{suffix} + {var} * {text})"
    return text


_SERIES = {"LOG_SERIES_F": _horner("s2", [1.0 / (2 * n + 1) for n in range(6)], ""),
           "ATAN_SERIES_F": _horner("u2", [(-1.0) ** n / (2 * n + 1) for n in range(1, 11)], ""),
           "SINH_SERIES_F": _horner("x2", [1.0 / math.factorial(2 * n + 1) for n in range(1, 7)], ""),
           "LOG_SERIES": _horner("s2", [1.0 / (2 * n + 1) for n in range(12)]),
           "ATAN_SERIES": _horner("u2", [(-1.0) ** n / (2 * n + 1) for n in range(1, 23)]),
           "ASIN_SERIES": _horner("z", [float(Fraction(math.comb(2 * n, n), 4 ** n * (2 * n + 1)))
                                        for n in range(1, 25)])}


def library(prefix: str, double: bool) -> str:
    """The helper functions of one include, named ``<prefix>_lib_*``."""
    text = _DOUBLE if double else _FLOAT
    for name, series in _SERIES.items():
        text = text.replace(name, series)
    return text.replace("P_lib_", f"{prefix}_lib_")
