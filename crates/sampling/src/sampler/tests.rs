//! Properties every sampler must have (values in [0, 1), purity, uniform marginals) and the
//! stratification each one promises.

use super::*;

fn keys() -> [PixelKey; 3] {
    [
        PixelKey::new(0, UVec2::new(0, 0)),
        PixelKey::new(0, UVec2::new(17, 3)),
        PixelKey::new(12345, UVec2::new(17, 3)),
    ]
}

/// Values in [0, 1), a function of (key, index, dim) only, and uniform marginals: the mean
/// over many pixels of every dimension of a fixed sample index is 1/2 and the fraction
/// below 1/4 is 1/4 (within 6 standard errors).
fn check_common(s: &dyn Sampler) {
    let n = s.sample_count();
    let k = keys()[1];
    for dim in [0u32, 1, 2, 5, 8, 33] {
        for i in 0..n.min(64) {
            let a = s.get_1d(k, i, dim);
            assert!((0.0..1.0).contains(&a), "1d value {a} out of range");
            assert_eq!(a.to_bits(), s.get_1d(k, i, dim).to_bits(), "not pure");
            let b = s.get_2d(k, i, dim);
            assert!((0.0..1.0).contains(&b.x) && (0.0..1.0).contains(&b.y));
        }
    }
    let pixels = 20_000u32;
    for dim in [0u32, 3, 4, 6, 13] {
        for index in [0u32, n / 2, n - 1] {
            let (mut sum, mut below) = (0.0f64, 0u32);
            for p in 0..pixels {
                let key = PixelKey::new(7, UVec2::new(p % 200, p / 200));
                let v = s.get_1d(key, index, dim) as f64;
                sum += v;
                below += (v < 0.25) as u32;
            }
            let mean = sum / pixels as f64;
            let se = (1.0 / 12.0 / pixels as f64).sqrt();
            assert!(
                (mean - 0.5).abs() < 6.0 * se,
                "dim {dim} index {index}: mean {mean}"
            );
            let frac = below as f64 / pixels as f64;
            let se = (0.25 * 0.75 / pixels as f64).sqrt();
            assert!(
                (frac - 0.25).abs() < 6.0 * se,
                "dim {dim}: P(<1/4) = {frac}"
            );
        }
    }
}

/// Each of the `n` 1D values of dimension `dim` of a pixel falls in its own stratum of width 1/n.
fn check_1d_strata(s: &dyn Sampler, key: PixelKey, dim: u32) {
    let n = s.sample_count();
    let mut seen = vec![false; n as usize];
    for i in 0..n {
        let c = (s.get_1d(key, i, dim) * n as f32) as usize;
        assert!(!seen[c], "dim {dim}: two samples in 1D stratum {c} of {n}");
        seen[c] = true;
    }
}

/// The `n` = 2^m 2D points at `dim` form a (0, m, 2)-net: every elementary interval of area
/// 1/n (2^a × 2^(m−a) cells) holds exactly one point.
fn check_net(s: &dyn Sampler, key: PixelKey, dim: u32) {
    let n = s.sample_count();
    assert!(n.is_power_of_two());
    let m = n.trailing_zeros();
    for a in 0..=m {
        let (cx, cy) = (1u32 << a, 1u32 << (m - a));
        let mut seen = vec![false; n as usize];
        for i in 0..n {
            let p = s.get_2d(key, i, dim);
            let c = (p.y * cy as f32) as u32 * cx + (p.x * cx as f32) as u32;
            assert!(
                !seen[c as usize],
                "dim {dim}: {cx}x{cy} cell {c} holds two points"
            );
            seen[c as usize] = true;
        }
    }
}

#[test]
fn independent_is_uniform_and_pure() {
    let s = IndependentSampler::new(64);
    check_common(&s);
    // Distinct pixels, seeds, indices and dimensions give distinct values.
    let [a, b, c] = keys();
    assert_ne!(s.get_1d(a, 0, 0), s.get_1d(b, 0, 0));
    assert_ne!(s.get_1d(b, 0, 0), s.get_1d(c, 0, 0));
    assert_ne!(s.get_1d(b, 0, 0), s.get_1d(b, 1, 0));
    assert_ne!(s.get_1d(b, 0, 0), s.get_1d(b, 0, 1));
}

#[test]
fn sobol_is_uniform_and_stratified() {
    for n in [16u32, 64, 256] {
        let s = SobolSampler::new(n);
        check_common(&s);
        for key in keys() {
            for dim in [0u32, 1, 2, 3, 4, 6, 7, 12, 40] {
                check_1d_strata(&s, key, dim);
            }
            // The first two values of every block: (0, m, 2)-nets.
            for dim in [0u32, 4, 8, 36] {
                check_net(&s, key, dim);
            }
        }
    }
}

#[test]
fn sobol_runs_past_the_sequence_length() {
    // Indices past 2^16 continue with other scrambles: values stay valid and differ.
    let s = SobolSampler::new(1 << 17);
    let k = keys()[0];
    assert_ne!(s.get_1d(k, 5, 0), s.get_1d(k, 5 + (1 << 16), 0));
    assert!((0.0..1.0).contains(&s.get_1d(k, (1 << 17) - 1, 9)));
}

#[test]
fn sample_count_rounding_as_mitsuba() {
    use SamplerKind::*;
    let cases: [(SamplerKind, [(u32, u32); 5]); 5] = [
        (
            Independent,
            [(1, 1), (5, 5), (16, 16), (17, 17), (100, 100)],
        ),
        (
            Stratified { jitter: true },
            [(1, 1), (5, 9), (16, 16), (17, 25), (100, 100)],
        ),
        (
            Multijitter { jitter: true },
            [(1, 1), (5, 6), (16, 16), (17, 20), (100, 100)],
        ),
        (
            Orthogonal {
                jitter: true,
                strength: 2,
            },
            [(1, 4), (5, 9), (16, 25), (26, 49), (100, 121)],
        ),
        (
            LowDiscrepancy,
            [(1, 4), (5, 16), (16, 16), (17, 64), (100, 256)],
        ),
    ];
    for (kind, pairs) in cases {
        for (spp, want) in pairs {
            assert_eq!(
                kind.round_sample_count(spp),
                want,
                "{} at {spp}",
                kind.name()
            );
        }
    }
    for name in SamplerKind::NAMES {
        assert_eq!(SamplerKind::from_name(name).unwrap().name(), name);
    }
}
