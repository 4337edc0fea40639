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
        let c = stratum(s.get_1d(key, i, dim), n);
        assert!(!seen[c], "dim {dim}: two samples in 1D stratum {c} of {n}");
        seen[c] = true;
    }
}

/// The stratum of width 1/n that holds `v`, in exact arithmetic (a 24-bit float times an
/// integer below 2²⁹ is exact in f64).
fn stratum(v: f32, n: u32) -> usize {
    (v as f64 * n as f64).floor() as usize
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

/// The `n` = 2^m points (value `a`, value `b`) of one pixel form a (t, m, 2)-net: every
/// elementary interval of area 2^(t − m) holds exactly 2^t points. (A (t', m, 2)-net with
/// t' < t is one for t too.)
fn check_pair_net(s: &dyn Sampler, key: PixelKey, a: u32, b: u32, t: u32) {
    let n = s.sample_count();
    assert!(n.is_power_of_two());
    let m = n.trailing_zeros();
    if t > m {
        return;
    }
    for k in 0..=m - t {
        let (cx, cy) = (1u32 << k, 1u32 << (m - t - k));
        let mut count = vec![0u32; (cx * cy) as usize];
        for i in 0..n {
            let (x, y) = (s.get_1d(key, i, a), s.get_1d(key, i, b));
            count[(stratum(y, cy) * cx as usize) + stratum(x, cx)] += 1;
        }
        assert!(
            count.iter().all(|&c| c == 1 << t),
            "dims ({a}, {b}) at {n} spp: not a (t = {t})-net in {cx}x{cy} cells"
        );
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
            // The first two dimensions: a (0, m, 2)-net.
            check_net(&s, key, 0);
            // Any pair of dimensions, within a block or across blocks (the film position and
            // a bounce's light sample, a light and a BSDF sample): a (t, m, 2)-net of small t,
            // as the Sobol points of all dimensions are one sequence. (t is a property of the
            // pair of Sobol dimensions, kept by Owen scrambling and by the index shuffle.)
            for (a, b) in [(4, 5), (8, 9), (0, 4), (4, 8), (5, 9), (0, 8), (6, 10)] {
                check_pair_net(&s, key, a, b, 3);
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

/// The `n` 2D points at `dim` take one cell each of the `rx` × `ry` grid.
fn check_grid(s: &dyn Sampler, key: PixelKey, dim: u32, rx: u32, ry: u32) {
    let n = s.sample_count();
    assert_eq!(rx * ry, n);
    let mut seen = vec![false; n as usize];
    for i in 0..n {
        let p = s.get_2d(key, i, dim);
        let c = stratum(p.y, ry) * rx as usize + stratum(p.x, rx);
        assert!(!seen[c], "dim {dim}: {rx}x{ry} cell {c} holds two points");
        seen[c] = true;
    }
}

/// Each coordinate of the `n` 2D points at `dim` takes one 1D stratum of width 1/n each.
fn check_2d_axis_strata(s: &dyn Sampler, key: PixelKey, dim: u32) {
    let n = s.sample_count();
    for axis in 0..2 {
        let mut seen = vec![false; n as usize];
        for i in 0..n {
            let c = stratum(s.get_2d(key, i, dim)[axis], n);
            assert!(!seen[c], "dim {dim} axis {axis}: stratum {c} of {n} twice");
            seen[c] = true;
        }
    }
}

/// The 1D values of dimensions `j` and `k` of each of samples `0..count`, as points, put
/// exactly `count / p²` points in each cell of the p × p grid.
fn check_pair_grid(s: &dyn Sampler, key: PixelKey, j: u32, k: u32, p: u32, count: u32) {
    let mut cells = vec![0u32; (p * p) as usize];
    for i in 0..count {
        let (a, b) = (s.get_1d(key, i, j), s.get_1d(key, i, k));
        cells[stratum(b, p) * p as usize + stratum(a, p)] += 1;
    }
    let want = count / (p * p);
    assert!(
        cells.iter().all(|&c| c == want),
        "dims ({j}, {k}): {p}x{p} cells hold {cells:?}, not {want} each"
    );
}

/// `v` lies at the centre of its stratum of width 1/n.
fn assert_centred(v: f32, n: u32, what: &str) {
    let f = (v as f64 * n as f64).fract();
    assert!(
        (f - 0.5).abs() < 1e-3,
        "{what}: {v} is not centred in 1/{n}"
    );
}

/// Over many pixels, the values of sample `index` at two different dimensions (and the two
/// coordinates of a 2D request) are uncorrelated (correlation within 6 standard errors):
/// distinct dimensions are independent, as an unbiased estimate of an integrand coupling
/// two dimensions needs.
fn check_decorrelated(s: &dyn Sampler) {
    let pixels = 20_000u32;
    let n = s.sample_count();
    let corr = |f: &dyn Fn(PixelKey) -> (f32, f32)| {
        let (mut sa, mut sb, mut saa, mut sbb, mut sab) = (0.0f64, 0.0, 0.0, 0.0, 0.0);
        for p in 0..pixels {
            let (a, b) = f(PixelKey::new(3, UVec2::new(p % 150, p / 150)));
            let (a, b) = (a as f64, b as f64);
            sa += a;
            sb += b;
            saa += a * a;
            sbb += b * b;
            sab += a * b;
        }
        let m = pixels as f64;
        let cov = sab / m - sa / m * (sb / m);
        cov / ((saa / m - (sa / m).powi(2)) * (sbb / m - (sb / m).powi(2))).sqrt()
    };
    let limit = 6.0 / (pixels as f64).sqrt();
    for index in [0, n - 1] {
        // Neighbours, and dimensions 4, 8, 24 and 64 apart (Mitsuba's `seed + dim`
        // permutation seeds correlated those).
        for (d1, d2) in [
            (0u32, 1u32),
            (1, 2),
            (6, 7),
            (5, 13),
            (4, 12),
            (0, 4),
            (4, 20),
            (6, 30),
            (0, 64),
        ] {
            let r = corr(&|k| (s.get_1d(k, index, d1), s.get_1d(k, index, d2)));
            assert!(r.abs() < limit, "dims {d1}, {d2} at index {index}: r = {r}");
        }
        for dim in [0u32, 4, 6] {
            let r = corr(&|k| {
                let v = s.get_2d(k, index, dim);
                (v.x, v.y)
            });
            assert!(r.abs() < limit, "2d at {dim}, index {index}: r = {r}");
        }
    }
}

/// The 1D strata that samples `0..n` take at `dim`, in sample order.
fn strata_order(s: &dyn Sampler, key: PixelKey, dim: u32) -> Vec<usize> {
    let n = s.sample_count();
    (0..n).map(|i| stratum(s.get_1d(key, i, dim), n)).collect()
}

const DIMS_1D: [u32; 10] = [0, 1, 2, 3, 5, 6, 7, 12, 13, 40];
const DIMS_2D: [u32; 6] = [0, 2, 4, 6, 12, 36];

#[test]
fn stratified_is_uniform_and_stratified() {
    for (spp, n) in [
        (1u32, 1u32),
        (4, 4),
        (5, 9),
        (16, 16),
        (17, 25),
        (64, 64),
        (100, 100),
    ] {
        let s = StratifiedSampler::new(spp, true);
        assert_eq!(s.sample_count(), n, "stratified at {spp}");
        let r = floor_sqrt(n);
        check_common(&s);
        for key in keys() {
            for dim in DIMS_1D {
                check_1d_strata(&s, key, dim);
            }
            for dim in DIMS_2D {
                check_grid(&s, key, dim, r, r);
            }
        }
        if n >= 16 {
            // Distinct dimensions take their strata in different orders.
            let k = keys()[1];
            assert_ne!(strata_order(&s, k, 0), strata_order(&s, k, 1));
            assert_ne!(strata_order(&s, k, 4), strata_order(&s, k, 12));
        }
    }
    check_decorrelated(&StratifiedSampler::new(4, true));
    check_decorrelated(&StratifiedSampler::new(16, true));
}

#[test]
fn stratified_without_jitter_sits_at_stratum_centres() {
    for spp in [4u32, 9, 17] {
        let s = StratifiedSampler::new(spp, false);
        let (n, r) = (s.sample_count(), floor_sqrt(s.sample_count()));
        for key in keys() {
            for i in 0..n {
                for dim in [0u32, 3, 9] {
                    assert_centred(s.get_1d(key, i, dim), n, "stratified 1d");
                    let p = s.get_2d(key, i, dim);
                    assert_centred(p.x, r, "stratified 2d x");
                    assert_centred(p.y, r, "stratified 2d y");
                }
            }
            check_1d_strata(&s, key, 2);
            check_grid(&s, key, 4, r, r);
        }
    }
}

#[test]
fn multijitter_is_stratified_in_2d_and_both_projections() {
    for (spp, rx, ry) in [
        (1u32, 1u32, 1u32),
        (4, 2, 2),
        (5, 3, 2),
        (6, 3, 2),
        (16, 4, 4),
        (17, 5, 4),
        (30, 6, 5),
        (64, 8, 8),
        (100, 10, 10),
    ] {
        let s = MultijitterSampler::new(spp, true);
        assert_eq!(s.sample_count(), rx * ry, "multijitter at {spp}");
        assert_eq!(s.resolution(), (rx, ry));
        check_common(&s);
        for key in keys() {
            for dim in DIMS_1D {
                check_1d_strata(&s, key, dim);
            }
            for dim in DIMS_2D {
                check_grid(&s, key, dim, rx, ry);
                check_2d_axis_strata(&s, key, dim);
            }
        }
        if rx * ry >= 16 {
            let k = keys()[2];
            assert_ne!(strata_order(&s, k, 0), strata_order(&s, k, 1));
        }
    }
    check_decorrelated(&MultijitterSampler::new(4, true));
    check_decorrelated(&MultijitterSampler::new(20, true));
}

#[test]
fn multijitter_without_jitter_sits_at_substratum_centres() {
    for spp in [4u32, 6, 17] {
        let s = MultijitterSampler::new(spp, false);
        let (n, (rx, ry)) = (s.sample_count(), s.resolution());
        for key in keys() {
            for i in 0..n {
                for dim in [0u32, 3, 9] {
                    assert_centred(s.get_1d(key, i, dim), n, "multijitter 1d");
                    let p = s.get_2d(key, i, dim);
                    assert_centred(p.x, n, "multijitter 2d x");
                    assert_centred(p.y, n, "multijitter 2d y");
                }
            }
            check_grid(&s, key, 6, rx, ry);
            check_2d_axis_strata(&s, key, 6);
        }
    }
}

#[test]
fn orthogonal_every_pair_of_dimensions_is_an_orthogonal_array() {
    for (spp, p) in [
        (1u32, 2u32),
        (4, 2),
        (5, 3),
        (9, 3),
        (16, 5),
        (25, 5),
        (26, 7),
    ] {
        let s = OrthogonalSampler::new(spp, true, 2);
        let n = p * p;
        assert_eq!(s.sample_count(), n, "orthogonal at {spp}");
        assert_eq!(s.resolution(), p);
        check_common(&s);
        for key in keys() {
            // Every dimension, also past the p + 1 columns of the array, is stratified over
            // all n strata (multi-jitter flavour).
            for dim in (0..p + 5).chain(DIMS_1D) {
                check_1d_strata(&s, key, dim);
            }
            // Any two of the dimensions 0 ..= p of a sample: one point per p × p cell.
            for j in 0..=p {
                for k in 0..=p {
                    if j != k {
                        check_pair_grid(&s, key, j, k, p, n);
                    }
                }
            }
            // 2D requests are two consecutive dimensions.
            for dim in [0u32, 1, 4, 6, 13] {
                for i in 0..n {
                    let v = s.get_2d(key, i, dim);
                    assert_eq!(v.x.to_bits(), s.get_1d(key, i, dim).to_bits());
                    assert_eq!(v.y.to_bits(), s.get_1d(key, i, dim + 1).to_bits());
                }
            }
            for dim in 0..p {
                check_grid(&s, key, dim, p, p);
                check_2d_axis_strata(&s, key, dim);
            }
        }
    }
    check_decorrelated(&OrthogonalSampler::new(4, true, 2));
    check_decorrelated(&OrthogonalSampler::new(25, true, 2));
}

#[test]
fn orthogonal_without_jitter_sits_at_substratum_centres() {
    for spp in [4u32, 9, 49] {
        let s = OrthogonalSampler::new(spp, false, 2);
        let n = s.sample_count();
        for key in keys() {
            for i in 0..n {
                for dim in [0u32, 1, 2, 5, 11] {
                    assert_centred(s.get_1d(key, i, dim), n, "orthogonal");
                }
            }
            check_1d_strata(&s, key, 3);
            check_pair_grid(&s, key, 0, 2, s.resolution(), n);
        }
    }
}

#[test]
fn orthogonal_bush_has_strength_s_over_its_runs() {
    // p = 3, strength 3: 27 runs. Over all of them, any 3 of the dimensions 0 .. p hit each
    // cell of the 3 × 3 × 3 grid once and every dimension takes 27 strata.
    let s = OrthogonalSampler::new(9, true, 3);
    assert_eq!(s.sample_count(), 9);
    check_common(&s);
    let (p, runs) = (3u32, 27u32);
    for key in keys() {
        let mut cells = vec![0u32; runs as usize];
        for i in 0..runs {
            let c: Vec<usize> = (0..3).map(|j| stratum(s.get_1d(key, i, j), p)).collect();
            cells[c[0] + 3 * c[1] + 9 * c[2]] += 1;
        }
        assert!(cells.iter().all(|&c| c == 1), "cells {cells:?}");
        for j in 0..p {
            let mut seen = vec![false; runs as usize];
            for i in 0..runs {
                let c = stratum(s.get_1d(key, i, j), runs);
                assert!(!seen[c], "dim {j}: stratum {c} of {runs} twice");
                seen[c] = true;
            }
            for k in 0..p {
                if j != k {
                    check_pair_grid(&s, key, j, k, p, runs);
                }
            }
        }
    }
    // Strengths whose p^s overflows 32 bits are capped, and still give valid values.
    for (spp, strength) in [(4u32, 5u32), (121, 16)] {
        let s = OrthogonalSampler::new(spp, true, strength);
        let k = keys()[0];
        for i in 0..s.sample_count() {
            for dim in [0u32, 1, 7] {
                assert!((0.0..1.0).contains(&s.get_1d(k, i, dim)));
            }
        }
    }
}

#[test]
fn ldsampler_is_a_shuffled_scrambled_02_sequence() {
    for (spp, n) in [
        (1u32, 4u32),
        (4, 4),
        (5, 16),
        (16, 16),
        (17, 64),
        (100, 256),
    ] {
        let s = LowDiscrepancySampler::new(spp);
        assert_eq!(s.sample_count(), n, "ldsampler at {spp}");
        check_common(&s);
        for key in keys() {
            for dim in DIMS_1D {
                check_1d_strata(&s, key, dim);
            }
            for dim in DIMS_2D {
                check_net(&s, key, dim);
            }
        }
        if n >= 16 {
            // The sample order is shuffled per dimension.
            let k = keys()[1];
            assert_ne!(strata_order(&s, k, 0), strata_order(&s, k, 1));
            assert_ne!(strata_order(&s, k, 5), strata_order(&s, k, 13));
            let a: Vec<Vec2> = (0..n).map(|i| s.get_2d(k, i, 0)).collect();
            let b: Vec<Vec2> = (0..n).map(|i| s.get_2d(k, i, 4)).collect();
            assert_ne!(a, b);
        }
    }
    check_decorrelated(&LowDiscrepancySampler::new(4));
    check_decorrelated(&LowDiscrepancySampler::new(16));
}

fn every_kind() -> Vec<SamplerKind> {
    let mut kinds: Vec<SamplerKind> = SamplerKind::NAMES
        .iter()
        .map(|n| SamplerKind::from_name(n).unwrap())
        .collect();
    kinds.extend([
        SamplerKind::Stratified { jitter: false },
        SamplerKind::Multijitter { jitter: false },
        SamplerKind::Orthogonal {
            jitter: false,
            strength: 2,
        },
        SamplerKind::Orthogonal {
            jitter: true,
            strength: 3,
        },
    ]);
    kinds
}

#[test]
fn any_sampler_dispatches_to_each_kind() {
    for kind in every_kind() {
        for spp in [1u32, 5, 17, 64] {
            let any = AnySampler::new(kind, spp);
            assert_eq!(any.sample_count(), kind.round_sample_count(spp));
            let ok = matches!(
                (kind, &any),
                (SamplerKind::Independent, AnySampler::Independent(_))
                    | (SamplerKind::Stratified { .. }, AnySampler::Stratified(_))
                    | (SamplerKind::Multijitter { .. }, AnySampler::Multijitter(_))
                    | (SamplerKind::Orthogonal { .. }, AnySampler::Orthogonal(_))
                    | (SamplerKind::LowDiscrepancy, AnySampler::LowDiscrepancy(_))
                    | (SamplerKind::Sobol, AnySampler::Sobol(_))
            );
            assert!(ok, "{kind:?} built {any:?}");
            assert_eq!(
                crate::with_sampler!(&any, s => s.sample_count()),
                any.sample_count()
            );
        }
    }
}

/// A value depends on (key, index, dim) and the sampler's parameters only: not on the
/// order of the calls, on other calls in between, on the sampler instance, or on whether
/// it is asked directly or through a [`SampleStream`].
#[test]
fn values_depend_on_key_index_and_dim_only() {
    for kind in every_kind() {
        let a = AnySampler::new(kind, 16);
        let n = a.sample_count();
        let dims = 0..14u32;
        let mut table = Vec::new();
        crate::with_sampler!(&a, s => {
            for key in keys() {
                for i in 0..n {
                    for d in dims.clone() {
                        table.push((key, i, d, s.get_1d(key, i, d), s.get_2d(key, i, d)));
                    }
                }
            }
        });
        let b = AnySampler::new(kind, 16);
        crate::with_sampler!(&b, s => {
            let mut noise = 0.0f32;
            for (n_call, &(key, i, d, v1, v2)) in table.iter().rev().enumerate() {
                // Unrelated calls in between.
                noise += s.get_1d(keys()[n_call % 3], (n_call as u32 * 7) % n, d + 3);
                noise += s.get_2d(key, (i + 1) % n, d ^ 1).x;
                assert_eq!(s.get_2d(key, i, d), v2, "{kind:?} 2d ({key:?}, {i}, {d})");
                assert_eq!(s.get_1d(key, i, d).to_bits(), v1.to_bits(), "{kind:?} 1d");
            }
            assert!(noise.is_finite());
            // Through a stream: seek, then the walk 2d, 1d, 1d, 2d.
            for key in keys() {
                for i in 0..n {
                    let mut st = SampleStream::new(s, key, i);
                    st.seek(4);
                    assert_eq!(st.next_2d(), s.get_2d(key, i, 4));
                    assert_eq!(st.next_1d(), s.get_1d(key, i, 6));
                    assert_eq!(st.next_1d(), s.get_1d(key, i, 7));
                    assert_eq!(st.next_2d(), s.get_2d(key, i, 8));
                }
            }
        });
    }
}

#[test]
fn samples_past_the_sample_count_stay_valid() {
    // The renderer never asks for them, but other sets follow: valid values, not repeats.
    for kind in every_kind() {
        let any = AnySampler::new(kind, 9);
        let n = any.sample_count();
        let k = keys()[1];
        crate::with_sampler!(&any, s => {
            for i in [n, 2 * n + 1, 1000 * n] {
                let v = s.get_1d(k, i, 3);
                assert!((0.0..1.0).contains(&v));
                let w = s.get_2d(k, i, 4);
                assert!((0.0..1.0).contains(&w.x) && (0.0..1.0).contains(&w.y));
            }
            let first: Vec<u32> = (0..n).map(|i| s.get_1d(k, i, 5).to_bits()).collect();
            let second: Vec<u32> = (n..2 * n).map(|i| s.get_1d(k, i, 5).to_bits()).collect();
            assert_ne!(first, second, "{kind:?}");
        });
    }
}

/// `get_block_lanes` is `get_block` in every lane it is asked for, bit for bit, and leaves
/// the other lanes alone: random pixel keys, sample indices (below 2¹⁶, about the runs'
/// boundaries and anywhere), blocks (the whole first dimension group with its last blocks,
/// the first blocks past it, later groups) and lane subsets.
#[test]
fn sobol_block_lanes_are_get_block_in_each_lane() {
    use rand::{Rng, SeedableRng};
    let mut rng = rand_pcg::Pcg32::seed_from_u64(11);
    let s = SobolSampler::new(64);
    let sets = sobol_burley::NUM_DIMENSION_SETS_4D;
    let (mut simd, mut past) = (0u32, 0u32);
    for round in 0..20_000 {
        let keys: [PixelKey; LANES] = std::array::from_fn(|_| PixelKey(rng.random()));
        let indices: [u32; LANES] = std::array::from_fn(|_| match rng.random_range(0..4) {
            0 => rng.random_range(0..64),
            1 => rng.random_range(0..1 << 16),
            2 => (rng.random_range(1..64u32) << 16).wrapping_add(rng.random_range(0..4)) - 2,
            _ => rng.random(),
        });
        let blocks: [u32; LANES] = std::array::from_fn(|_| match rng.random_range(0..6) {
            0 => sets - 2,
            1 => sets - 1 + rng.random_range(0..3),
            2 => rng.random_range(sets..1 << 12),
            _ => rng.random_range(0..sets - 1),
        });
        let lanes = match round % 4 {
            0 => 0xffff,
            // Bits past the sixteenth mean nothing.
            1 => rng.random::<u32>(),
            _ => rng.random::<u32>() & rng.random::<u32>() & 0xffff,
        };
        let prepared = std::array::from_fn(|k| s.prepare(keys[k], indices[k]));
        let before: [[u32; LANES]; 8] = std::array::from_fn(|_| rng.random());
        let mut out = before.map(|row| row.map(f32::from_bits));
        assert!(s.get_block_lanes(lanes, &keys, &indices, &blocks, &prepared, &mut out));
        // Fewer rows asked for: the same first values, and nothing written past them.
        let rows = 1 + round % 7;
        let mut first = out.map(|row| row.map(|_| -1.0f32));
        assert!(s.get_block_lanes(
            lanes,
            &keys,
            &indices,
            &blocks,
            &prepared,
            &mut first[..rows]
        ));
        for (j, (row, full)) in first.iter().zip(&out).enumerate() {
            for k in 0..LANES {
                let want = if j < rows && lanes & (1 << k) != 0 {
                    full[k]
                } else {
                    -1.0
                };
                assert_eq!(row[k].to_bits(), want.to_bits(), "{rows} rows: [{j}][{k}]");
            }
        }
        for k in 0..LANES {
            let got: [u32; 8] = std::array::from_fn(|j| out[j][k].to_bits());
            if lanes & (1 << k) == 0 {
                assert_eq!(
                    got,
                    std::array::from_fn(|j| before[j][k]),
                    "lane {k} changed"
                );
                continue;
            }
            let want = s
                .get_block(keys[k], indices[k], blocks[k], prepared[k])
                .unwrap()
                .map(f32::to_bits);
            assert_eq!(
                got, want,
                "lane {k}: key {:?}, index {}, block {}",
                keys[k], indices[k], blocks[k]
            );
            if blocks[k] + 1 < sets {
                simd += 1;
            } else {
                past += 1;
            }
        }
    }
    // Both branches well exercised.
    assert!(
        simd > 100_000 && past > 50_000,
        "{simd} lanes in the group, {past} past it"
    );
}

/// Samplers that make no blocks make no lanes of blocks either, and leave `out` alone.
#[test]
fn samplers_without_blocks_make_no_block_lanes() {
    for kind in every_kind() {
        let any = AnySampler::new(kind, 16);
        let key = keys()[1];
        let keys = [key; LANES];
        let indices: [u32; LANES] = std::array::from_fn(|k| k as u32);
        let blocks = [1; LANES];
        let mut out = [[0.25f32; LANES]; 8];
        let made = crate::with_sampler!(&any, s => {
            let prepared = std::array::from_fn(|k| s.prepare(key, indices[k]));
            let made = s.get_block_lanes(0xffff, &keys, &indices, &blocks, &prepared, &mut out);
            assert_eq!(made, s.get_block(key, 0, 1, prepared[0]).is_some(), "{kind:?}");
            made
        });
        assert_eq!(made, kind == SamplerKind::Sobol, "{kind:?}");
        if !made {
            assert_eq!(out, [[0.25f32; LANES]; 8], "{kind:?} wrote to out");
        }
    }
}
