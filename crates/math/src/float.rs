//! Floating-point error bounds, for ray origins that are provably on the right side of the
//! surface they leave (pbrt-v4's `src/pbrt/util/float.h` and `interaction.h`, after Higham's
//! bound on the relative error of n operations).

/// Half an ulp of 1 (pbrt-v4's `MachineEpsilon`): the relative rounding error of one `f32`
/// operation.
pub const MACHINE_EPSILON: f32 = f32::EPSILON * 0.5;

/// γₙ = n·ε / (1 − n·ε): a bound on the relative error accumulated by `n` operations.
#[inline]
pub const fn gamma(n: i32) -> f32 {
    (n as f32 * MACHINE_EPSILON) / (1.0 - n as f32 * MACHINE_EPSILON)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gamma_bounds_repeated_rounding() {
        // Summing 1 + 2⁻²⁴·k in f32 n times stays within γₙ of the exact sum.
        let mut acc = 0.0f32;
        let mut exact = 0.0f64;
        for i in 0..64 {
            let x = 1.0 + (i as f32) * 1.1e-7;
            acc += x;
            exact += x as f64;
        }
        assert!(((acc as f64 - exact) / exact).abs() <= gamma(64) as f64);
        assert!(gamma(1) > MACHINE_EPSILON && gamma(7) < 8.0 * MACHINE_EPSILON);
    }
}
