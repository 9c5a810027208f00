//! 3-vectors and row-major 3×3 matrices as fixed-size arrays, for the robot model's frames
//! and mass properties. Symmetric 3×3 matrices are written as six entries `[xx, yy, zz, xy,
//! xz, yz]`.

#[inline]
pub(crate) fn dot3(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

#[inline]
pub(crate) fn add3(a: &[f64; 3], b: &[f64; 3]) -> [f64; 3] {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

pub(crate) fn mul3(a: &[f64; 9], b: &[f64; 9]) -> [f64; 9] {
    let mut c = [0.0; 9];
    for i in 0..3 {
        for j in 0..3 {
            c[3 * i + j] = a[3 * i] * b[j] + a[3 * i + 1] * b[3 + j] + a[3 * i + 2] * b[6 + j];
        }
    }
    c
}

pub(crate) fn transpose3(a: &[f64; 9]) -> [f64; 9] {
    [a[0], a[3], a[6], a[1], a[4], a[7], a[2], a[5], a[8]]
}

/// `R E Rᵀ` of the symmetric `E = [xx, yy, zz, xy, xz, yz]`, in the same form.
#[inline]
pub(crate) fn rotate_sym_full(e: &[f64; 6], r: &[f64; 9]) -> [f64; 6] {
    let full = sym_from_six(e);
    let t = mul3(&mul3(r, &full), &transpose3(r));
    [t[0], t[4], t[8], t[1], t[2], t[5]]
}

#[inline]
pub(crate) fn sub3(a: &[f64; 3], b: &[f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

#[inline]
pub(crate) fn cross3(a: &[f64; 3], b: &[f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

#[inline]
pub(crate) fn apply3(a: &[f64; 9], v: &[f64; 3]) -> [f64; 3] {
    [
        a[0] * v[0] + a[1] * v[1] + a[2] * v[2],
        a[3] * v[0] + a[4] * v[1] + a[5] * v[2],
        a[6] * v[0] + a[7] * v[1] + a[8] * v[2],
    ]
}

/// Row-major symmetric 3×3 from `[xx, yy, zz, xy, xz, yz]`.
#[inline]
pub(crate) fn sym_from_six(s: &[f64; 6]) -> [f64; 9] {
    [s[0], s[3], s[4], s[3], s[1], s[5], s[4], s[5], s[2]]
}

/// `(u, v) ↦ (c u − s v, s u + c v)`: a vector's components in a plane turned by `(s, c)`.
#[inline]
pub(crate) fn rotate_pair(u: f64, v: f64, c: f64, s: f64) -> (f64, f64) {
    (c * u - s * v, s * u + c * v)
}
