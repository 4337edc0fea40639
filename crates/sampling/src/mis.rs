//! Multiple importance sampling weights (Veach 1997, ch. 9).

use radia_math::real::Real;

/// Power heuristic with β = 2 for one sample from each strategy: the weight of the strategy
/// whose pdf is `pdf_a`. Mitsuba's `mis_weight`; non-finite results become 0 (path.cpp does
/// the same with `dr::select(dr::isfinite(w), w, 0)`).
///
/// The pdfs are divided by the larger one before squaring: squares of solid-angle pdfs of
/// near-specular lobes or tiny lights overflow f32 (1e20² = ∞, giving ∞/∞ = NaN and thus a
/// weight of 0 for both strategies), and squares of tiny pdfs underflow to 0.
#[inline]
pub fn power_heuristic(pdf_a: f32, pdf_b: f32) -> f32 {
    power_heuristic_r(pdf_a, pdf_b)
}

/// [`power_heuristic`] over any [`Real`].
#[inline(always)]
pub fn power_heuristic_r<R: Real>(pdf_a: R, pdf_b: R) -> R {
    let m = pdf_a.max(pdf_b);
    let (a, b) = (pdf_a / m, pdf_b / m);
    let a2 = a * a;
    let w = a2 / (a2 + b * b);
    R::select(w.is_finite(), w, R::zero())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn weights_sum_to_one_and_stay_finite() {
        for (a, b) in [(1.0, 1.0), (0.3, 7.0), (1e-20, 1e-20), (1e30, 1.0)] {
            let s = power_heuristic(a, b) + power_heuristic(b, a);
            assert!((s - 1.0).abs() < 1e-5, "{a} {b} {s}");
        }
        assert_eq!(power_heuristic(0.0, 0.0), 0.0);
        assert_eq!(power_heuristic(f32::INFINITY, f32::INFINITY), 0.0);
        assert_eq!(power_heuristic(1.0, 0.0), 1.0);
        assert_eq!(power_heuristic(0.0, 1.0), 0.0);
        // Squares that would overflow or underflow f32.
        assert!((power_heuristic(3e20, 1e20) - 0.9).abs() < 1e-6);
        assert!((power_heuristic(1e-25, 3e-25) - 0.1).abs() < 1e-6);
        assert_eq!(power_heuristic(f32::NAN, 1.0), 0.0);
    }
}
