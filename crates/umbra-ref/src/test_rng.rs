//! The unit tests' deterministic random numbers (xorshift64), so that a failure reproduces.

/// Uniform f32 in [0, 1) from `seed` (non-zero), one per call.
pub fn uniform(seed: u64) -> impl FnMut() -> f32 {
    let mut state = seed;
    move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f32 / (1u64 << 53) as f32
    }
}
