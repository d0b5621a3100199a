//! The M'4 interpolation/remeshing kernel (paper eq. 30).
//!
//! M'4(x) = 1 - 5x²/2 + 3|x|³/2 for |x| ≤ 1, (2 - |x|)²(1 - |x|)/2 for 1 ≤ |x| ≤ 2, 0 beyond.
//! (The paper's text prints `(1 + |x|)` in the outer branch; that is not continuous at |x| = 1
//! and is not Monaghan's M'4, whose outer factor is `(1 - |x|)`.) It is separable, interpolates (M'4(0) = 1,
//! M'4(±1) = M'4(±2) = 0), and reproduces polynomials up to degree two, so remeshing with it
//! conserves the zeroth, first and second moments of the particle distribution exactly.

/// M'4 kernel value at distance `x` (in grid units), eq. (30).
#[inline(always)]
pub fn m4prime(x: f64) -> f64 {
    let a = x.abs();
    if a > 2.0 {
        0.0
    } else if a >= 1.0 {
        0.5 * (2.0 - a) * (2.0 - a) * (1.0 - a)
    } else {
        1.0 - 2.5 * a * a + 1.5 * a * a * a
    }
}

/// The four M'4 weights of a particle at fractional offset `f ∈ [0, 1)` from node `i0`,
/// for nodes `i0 - 1, i0, i0 + 1, i0 + 2` (distances `1 + f, f, 1 - f, 2 - f`).
#[inline(always)]
pub fn m4prime_weights(f: f64) -> [f64; 4] {
    let g = 1.0 - f;
    [
        0.5 * g * g * (-f),
        1.0 - 2.5 * f * f + 1.5 * f * f * f,
        1.0 - 2.5 * g * g + 1.5 * g * g * g,
        0.5 * f * f * (-g),
    ]
}

/// The six Λ4,2 weights (Cottet, Etancelin, Perignon & Picard, ESAIM: M2AN 48 (2014)) of a
/// particle at fractional offset `f ∈ [0, 1)` from node `i0`, for nodes `i0 - 2 ..= i0 + 3`.
/// Λ4,2 is C², fourth order (it reproduces cubics, so remeshing conserves the moments up to
/// the third), with support [-3, 3].
#[inline(always)]
pub fn lambda42_weights(f: f64) -> [f64; 6] {
    [
        lambda42(2.0 + f),
        lambda42(1.0 + f),
        lambda42(f),
        lambda42(1.0 - f),
        lambda42(2.0 - f),
        lambda42(3.0 - f),
    ]
}

/// Λ4,2 kernel value at distance `x` (grid units).
#[inline(always)]
pub fn lambda42(x: f64) -> f64 {
    let a = x.abs();
    let a2 = a * a;
    let a3 = a2 * a;
    let a4 = a2 * a2;
    let a5 = a4 * a;
    if a <= 1.0 {
        1.0 - 1.25 * a2 - 35.0 / 12.0 * a3 + 5.25 * a4 - 25.0 / 12.0 * a5
    } else if a < 2.0 {
        -4.0 + 18.75 * a - 245.0 / 8.0 * a2 + 545.0 / 24.0 * a3 - 63.0 / 8.0 * a4 + 25.0 / 24.0 * a5
    } else if a < 3.0 {
        18.0 - 38.25 * a + 255.0 / 8.0 * a2 - 313.0 / 24.0 * a3 + 21.0 / 8.0 * a4 - 5.0 / 24.0 * a5
    } else {
        0.0
    }
}

/// Split a position in grid units into the base node `floor(x)` and the fraction in `[0, 1)`.
#[inline(always)]
pub fn split(x: f64) -> (i64, f64) {
    // `f64::floor` is a libm call without SSE4.1; truncation plus a correction is not.
    let t = x as i64;
    let b = if (t as f64) > x { t - 1 } else { t };
    (b, x - b as f64)
}

/// The smoothed Heaviside function of half-width `eps`: 0 below -eps, 1 above eps.
#[inline]
pub fn heaviside(phi: f64, eps: f64) -> f64 {
    if phi <= -eps {
        0.0
    } else if phi >= eps {
        1.0
    } else {
        0.5 * (1.0 + phi / eps + (std::f64::consts::PI * phi / eps).sin() / std::f64::consts::PI)
    }
}
