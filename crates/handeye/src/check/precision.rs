//! The data's numerical precision: the floor under every noise scale a check divides by.
//!
//! A check that holds a pose out for being k times the typical residual means nothing when the
//! typical residual is rounding: on exact data every residual is rounding, and any of them may be
//! "8.7 times the typical". The floor is what f64 arithmetic can resolve in quantities of the
//! data's size, derived, not chosen:
//!
//! - a scatter computed from running sums (the mean of squares minus the square of the mean, as
//!   [`crate::solve::accumulate::PoseAccumulator::residual_scatter`] does in O(1)) is a difference
//!   of two numbers of size `magnitude²`, each rounded to ε of it per step: the variance resolves
//!   no finer than (steps)·ε·magnitude², the scatter no finer than √(steps·ε)·magnitude;
//! - an angle or screw pitch read from a rotation matrix near the identity (a cosine of
//!   1 − θ²/2, rounded to ε) resolves no finer than √ε either.
//!
//! Each rounded step adds its ε, and the closed form chains [`ROUNDED_STEPS`] of them per entry:
//! so the floor is √(64 ε) (about 1.2e-7) times the magnitude of what the scale is computed from:
//! 1 for rotations in radians (rotation matrices have entries of size 1), the size of the
//! translations for lengths. Real noise is orders above it (0.01° is 1.7e-4 rad, 0.1 mm of a 1 m
//! scene is 1e-4 of it), so it changes nothing there.

/// The rounded steps the closed-form scatter chains per entry, each adding ε to the variance's
/// error relative to magnitude²: a 9-term product of the 9×9 sums with vec(R_X), a 3×3 trace of
/// R_Yᵀ times it (9 products, 9 sums), the translation's four cross terms, and the sums over the
/// poses (whose rounding grows like √n: 16 up to 256 poses in a block of the sums). 9 + 18 + 4·4
/// + 16 + a few, rounded up to a power of two: 64.
pub const ROUNDED_STEPS: f64 = 64.0;

/// The finest scale resolved in quantities of size `magnitude` (module documentation):
/// √([`ROUNDED_STEPS`] ε) × `magnitude`.
pub fn resolution(magnitude: f64) -> f64 {
    magnitude.abs() * (ROUNDED_STEPS * f64::EPSILON).sqrt()
}

/// The finest rotation resolved, radians: [`resolution`] of rotation matrices' entries (size 1).
pub fn rotation_resolution() -> f64 {
    resolution(1.0)
}
