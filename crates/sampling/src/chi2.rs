//! Chi-square goodness-of-fit tests of sampling routines against their densities.
//!
//! The method is the one of Mitsuba 3's `chi2.py` and pbrt-v4's `bsdfs_test.cpp`: draw many
//! samples, histogram them over a grid in a 2D parameterization of the domain, integrate the
//! claimed density numerically over every cell of the same grid to get the expected counts,
//! pool cells whose expected count is too small for the chi-square approximation, and compute
//! Pearson's statistic and its p-value. A sampler whose samples really follow its pdf passes
//! with probability 1 − α; a mismatch (wrong pdf, wrong normalization, samples where the pdf
//! is zero, lost samples the pdf does not account for) is rejected once enough samples are
//! drawn.
//!
//! Three domains are provided:
//!
//! * [`chi2_test`]: directions on the unit sphere, binned over (cos θ, φ) around +z. The
//!   parameterization has a unit Jacobian (dω = d(cos θ) dφ), so the cells have equal solid
//!   angle. [`Chi2Config::cos_theta_min`] restricts the grid to a cap around +z (to resolve
//!   narrow lobes and small cones); what falls outside it is one extra cell.
//! * [`chi2_test_2d`]: points in a rectangle (planar warps: disks, triangle barycentrics).
//! * [`chi2_test_discrete`]: indices with a probability mass function.
//!
//! Samplers may fail (return `None`): the failed fraction must match the mass the density
//! misses, 1 − ∫pdf, and it enters the statistic as one more cell. [`Chi2Result`] returns both
//! the integral of the pdf and the fraction of successful samples so tests can also check that
//! a pdf integrates to one.
//!
//! The sample values handed to the sampler come from a PCG32 stream seeded by the
//! configuration, so every test is deterministic. Use [`sidak_alpha`] to keep the false
//! rejection probability of a whole suite of tests at the nominal level.
//!
//! ```
//! use radia_sampling::{chi2, warp};
//! let cfg = chi2::Chi2Config { sample_count: 200_000, ..Default::default() };
//! let r = chi2::chi2_test(
//!     &cfg,
//!     |u, _| Some(warp::square_to_cosine_hemisphere(u)),
//!     |d| warp::cosine_hemisphere_pdf(d) as f64,
//! );
//! assert!(r.passed, "{}", r.report);
//! assert!((r.integral_of_pdf - 1.0).abs() < 1e-3);
//! ```

use std::cell::Cell;
use std::f64::consts::TAU;
use std::fmt::Write;

use glam::{Vec2, Vec3};
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg32;

/// Significance level of a single test: 1% as in Mitsuba's and pbrt's test suites.
pub const DEFAULT_ALPHA: f64 = 0.01;

/// Cells (after pooling) must expect at least this many samples: below it the statistic no
/// longer follows the chi-square distribution.
pub const DEFAULT_MIN_EXPECTED: f64 = 5.0;

/// The Šidák-corrected significance level for each of `num_tests` independent tests such that
/// the probability that any of them falsely rejects is `alpha`: 1 − (1 − α)^(1/n).
pub fn sidak_alpha(alpha: f64, num_tests: usize) -> f64 {
    assert!(
        (0.0..=1.0).contains(&alpha),
        "significance level {alpha} outside [0, 1]"
    );
    let n = num_tests.max(1) as f64;
    // Written with ln_1p / exp_m1: for large n the naive form cancels catastrophically.
    -((-alpha).ln_1p() / n).exp_m1()
}

// ---------------------------------------------------------------------------------------------
// Configuration and result
// ---------------------------------------------------------------------------------------------

/// Parameters of a chi-square test of a direction sampler ([`chi2_test`]).
#[derive(Clone, Debug)]
pub struct Chi2Config {
    /// Rows of the histogram, uniform in cos θ over [`cos_theta_min`](Self::cos_theta_min), 1].
    /// Odd by default, as in Mitsuba, so that cos θ = 0 (where hemispherical samplers stop and
    /// rounding decides the side) falls inside a row rather than on the edge between two.
    pub theta_res: usize,
    /// Columns of the histogram, uniform in φ over [0, 2π).
    pub phi_res: usize,
    /// The grid covers the spherical cap cos θ ≥ `cos_theta_min` (−1: the whole sphere).
    /// Directions below it are counted in one extra cell whose expected count is the integral
    /// of the pdf over the rest of the sphere. Use it to resolve lobes and cones that would
    /// otherwise fall into a handful of cells; rotate directions in the closures to centre a
    /// lobe that is not around +z.
    pub cos_theta_min: f64,
    /// Number of samples drawn.
    pub sample_count: usize,
    /// Pooling threshold for expected cell counts.
    pub min_expected: f64,
    /// Significance level: the test fails when the p-value is below it. Apply
    /// [`sidak_alpha`] for suites of tests.
    pub alpha: f64,
    /// Seed of the PCG32 stream of sample values.
    pub seed: u64,
}

impl Default for Chi2Config {
    fn default() -> Self {
        Self {
            theta_res: 51,
            phi_res: 100,
            cos_theta_min: -1.0,
            sample_count: 1_000_000,
            min_expected: DEFAULT_MIN_EXPECTED,
            alpha: DEFAULT_ALPHA,
            seed: 0x5eed_c412,
        }
    }
}

/// Parameters of a chi-square test of a sampler of points in a rectangle ([`chi2_test_2d`]).
#[derive(Clone, Debug)]
pub struct Chi2Config2d {
    /// Lower corner of the rectangle; it must contain the support of the pdf.
    pub min: Vec2,
    /// Upper corner of the rectangle.
    pub max: Vec2,
    /// Columns of the histogram (along x).
    pub x_res: usize,
    /// Rows of the histogram (along y).
    pub y_res: usize,
    pub sample_count: usize,
    pub min_expected: f64,
    pub alpha: f64,
    pub seed: u64,
}

impl Chi2Config2d {
    /// A 51 × 51 grid over [min, max] with the default statistics parameters.
    pub fn new(min: Vec2, max: Vec2) -> Self {
        let d = Chi2Config::default();
        Self {
            min,
            max,
            x_res: 51,
            y_res: 51,
            sample_count: d.sample_count,
            min_expected: d.min_expected,
            alpha: d.alpha,
            seed: d.seed,
        }
    }
}

/// Outcome of a chi-square test.
#[derive(Clone, Debug)]
pub struct Chi2Result {
    /// Pearson's statistic Σ (observed − expected)² / expected over the pooled cells.
    pub statistic: f64,
    /// Degrees of freedom: number of pooled cells − 1.
    pub dof: usize,
    /// Probability of a statistic at least this large if the samples follow the pdf.
    pub p_value: f64,
    /// `p_value ≥ alpha` and none of the hard failures listed in the report happened (samples
    /// where the pdf is zero, invalid samples, negative or non-finite pdf values, too few cells).
    pub passed: bool,
    /// The numerical integral of the pdf over the whole domain.
    pub integral_of_pdf: f64,
    /// Fraction of the samples that succeeded (returned `Some` with a valid value).
    pub sampled_fraction: f64,
    /// Columns and rows of the histogram grid (φ × cos θ, x × y, or n × 1 for discrete tests).
    pub res: [usize; 2],
    /// Observed counts of the grid cells, row-major (`row * res[0] + column`); row 0 is
    /// cos θ = 1 for directions and the lowest y for rectangles.
    pub observed: Vec<f64>,
    /// Expected counts of the same cells.
    pub expected: Vec<f64>,
    /// Human-readable summary; when the test fails it also holds residual maps and the
    /// observed and expected tables.
    pub report: String,
}

impl Chi2Result {
    /// Panics with the report unless the test passed.
    #[track_caller]
    pub fn assert_passed(&self) {
        assert!(self.passed, "chi-square test failed:\n{}", self.report);
    }
}

// ---------------------------------------------------------------------------------------------
// Public test entry points
// ---------------------------------------------------------------------------------------------

/// Chi-square test of a direction sampler against its solid-angle density.
///
/// `sample(u, u1)` receives a 2D and a 1D sample value in [0, 1) and returns a unit direction,
/// or `None` when it fails. `pdf(d)` is the density per steradian of returning `d`; its mass
/// missing from 1 is the probability of failure.
pub fn chi2_test(
    cfg: &Chi2Config,
    mut sample: impl FnMut(Vec2, f32) -> Option<Vec3>,
    pdf: impl Fn(Vec3) -> f64,
) -> Chi2Result {
    assert!(cfg.theta_res > 0 && cfg.phi_res > 0 && cfg.sample_count > 0);
    assert!(
        (-1.0..1.0).contains(&cfg.cos_theta_min),
        "cos_theta_min {} outside [-1, 1)",
        cfg.cos_theta_min
    );
    let (cols, rows) = (cfg.phi_res, cfg.theta_res);
    let n = cfg.sample_count as f64;
    // Rows are uniform in 1 − cos θ, which directions near the pole keep precisely.
    let cap_width = 1.0 - cfg.cos_theta_min;
    let full_sphere = cfg.cos_theta_min <= -1.0;

    // Histogram.
    let mut rng = UniformStream::new(cfg.seed);
    let mut observed = vec![0.0; cols * rows];
    let (mut lost, mut outside, mut invalid) = (0usize, 0usize, 0usize);
    let mut first_invalid = None;
    for _ in 0..cfg.sample_count {
        let (u, u1) = rng.next_sample();
        let Some(d) = sample(u, u1) else {
            lost += 1;
            continue;
        };
        match bin_direction(d, cap_width, cols, rows) {
            DirBin::Cell(i) => observed[i] += 1.0,
            DirBin::Outside => outside += 1,
            DirBin::Invalid => {
                invalid += 1;
                first_invalid.get_or_insert(d);
            }
        }
    }

    // Expected counts.
    let bad_pdf = BadValues::default();
    let density = |phi: f64, omc: f64| bad_pdf.check(pdf(direction(omc, phi)));
    let expected_p = integrate_grid(
        &density,
        [cols, rows],
        [0.0, 0.0],
        [TAU, cap_width],
        &|whole| cell_tolerance(whole, n),
    );
    let outside_p = if full_sphere {
        0.0
    } else {
        // The rest of the sphere is one cell; its error budget is that of one cell.
        let lo = [0.0, cap_width];
        let hi = [TAU, 2.0];
        let coarse: f64 = integrate_grid(&density, [cols, rows], lo, hi, &|_| f64::INFINITY)
            .iter()
            .sum();
        let tol = cell_tolerance(coarse, n) / (cols * rows) as f64;
        integrate_grid(&density, [cols, rows], lo, hi, &|_| tol)
            .iter()
            .sum()
    };

    let mut t = Tally::new(
        Domain::Sphere {
            cos_theta_min: cfg.cos_theta_min,
        },
        [cols, rows],
        cfg.sample_count,
    );
    t.observed = observed;
    t.expected = expected_p.iter().map(|p| p * n).collect();
    t.integral = expected_p.iter().sum::<f64>() + outside_p;
    if !full_sphere {
        t.extra("below the cap", outside as f64, outside_p * n);
    }
    t.lost = lost;
    if invalid > 0 {
        t.fail(format!(
            "{invalid} sampled directions were not finite unit vectors (first: {:?})",
            first_invalid.unwrap()
        ));
    }
    bad_pdf.report(&mut t);
    t.finish(cfg.min_expected, cfg.alpha)
}

/// Chi-square test of a sampler of points in the rectangle `[cfg.min, cfg.max]` against its
/// density per unit area.
///
/// `sample(u, u1)` returns a point or `None` when it fails. The rectangle must contain the
/// support of `pdf`: samples outside it (beyond a 10⁻⁴ relative margin, which is clamped to
/// the border cells) fail the test.
pub fn chi2_test_2d(
    cfg: &Chi2Config2d,
    mut sample: impl FnMut(Vec2, f32) -> Option<Vec2>,
    pdf: impl Fn(Vec2) -> f64,
) -> Chi2Result {
    assert!(cfg.x_res > 0 && cfg.y_res > 0 && cfg.sample_count > 0);
    let lo = [cfg.min.x as f64, cfg.min.y as f64];
    let hi = [cfg.max.x as f64, cfg.max.y as f64];
    assert!(
        lo[0] < hi[0] && lo[1] < hi[1],
        "empty rectangle {:?} .. {:?}",
        cfg.min,
        cfg.max
    );
    let (cols, rows) = (cfg.x_res, cfg.y_res);
    let n = cfg.sample_count as f64;

    let mut rng = UniformStream::new(cfg.seed);
    let mut observed = vec![0.0; cols * rows];
    let (mut lost, mut outside) = (0usize, 0usize);
    let mut first_outside = None;
    for _ in 0..cfg.sample_count {
        let (u, u1) = rng.next_sample();
        let Some(p) = sample(u, u1) else {
            lost += 1;
            continue;
        };
        let cell = grid_index(p.x as f64, lo[0], hi[0], cols)
            .zip(grid_index(p.y as f64, lo[1], hi[1], rows));
        match cell {
            Some((c, r)) => observed[r * cols + c] += 1.0,
            None => {
                outside += 1;
                first_outside.get_or_insert(p);
            }
        }
    }

    let bad_pdf = BadValues::default();
    let density = |x: f64, y: f64| bad_pdf.check(pdf(Vec2::new(x as f32, y as f32)));
    let expected_p = integrate_grid(&density, [cols, rows], lo, hi, &|whole| {
        cell_tolerance(whole, n)
    });

    let mut t = Tally::new(
        Domain::Rect {
            min: cfg.min,
            max: cfg.max,
        },
        [cols, rows],
        cfg.sample_count,
    );
    t.observed = observed;
    t.expected = expected_p.iter().map(|p| p * n).collect();
    t.integral = expected_p.iter().sum();
    t.lost = lost;
    if outside > 0 {
        t.fail(format!(
            "{outside} samples fell outside the rectangle or were not finite (first: {:?})",
            first_outside.unwrap()
        ));
    }
    bad_pdf.report(&mut t);
    t.finish(cfg.min_expected, cfg.alpha)
}

/// Chi-square test of a sampler of indices in `0..n` against its probability mass function.
///
/// `sample(u, u2)` receives a 1D and a 2D sample value and returns an index or `None`; the
/// failure probability must be 1 − Σ pmf. Indices ≥ `n` fail the test.
pub fn chi2_test_discrete(
    n: usize,
    sample_count: usize,
    seed: u64,
    alpha: f64,
    mut sample: impl FnMut(f32, Vec2) -> Option<usize>,
    pmf: impl Fn(usize) -> f64,
) -> Chi2Result {
    assert!(n > 0 && sample_count > 0);
    let mut rng = UniformStream::new(seed);
    let mut observed = vec![0.0; n];
    let (mut lost, mut outside) = (0usize, 0usize);
    for _ in 0..sample_count {
        let (u2, u) = rng.next_sample();
        match sample(u, u2) {
            None => lost += 1,
            Some(i) if i < n => observed[i] += 1.0,
            Some(_) => outside += 1,
        }
    }
    let bad_pmf = BadValues::default();
    let pmf: Vec<f64> = (0..n).map(|i| bad_pmf.check(pmf(i))).collect();

    let mut t = Tally::new(Domain::Discrete, [n, 1], sample_count);
    t.observed = observed;
    t.expected = pmf.iter().map(|p| p * sample_count as f64).collect();
    t.integral = pmf.iter().sum();
    t.lost = lost;
    if outside > 0 {
        t.fail(format!("{outside} sampled indices were ≥ {n}"));
    }
    bad_pmf.report(&mut t);
    t.finish(DEFAULT_MIN_EXPECTED, alpha)
}

// ---------------------------------------------------------------------------------------------
// Statistics
// ---------------------------------------------------------------------------------------------

/// Pearson's chi-square statistic of observed against expected counts, pooling cells: cells
/// expecting fewer than `min_expected` samples are merged, smallest first, into groups that
/// reach it (a remainder that does not is merged into the smallest group). Cells with nothing
/// expected and nothing observed are ignored. Returns the statistic, the degrees of freedom
/// (groups − 1, as the total count is fixed), the number of cells pooled and the number of
/// groups they formed.
///
/// A cell that expects nothing but observed samples makes the statistic infinite.
pub fn pearson_chi2(
    observed: &[f64],
    expected: &[f64],
    min_expected: f64,
) -> (f64, usize, usize, usize) {
    assert_eq!(observed.len(), expected.len());
    let mut cells: Vec<(f64, f64)> = observed
        .iter()
        .zip(expected)
        .map(|(&o, &e)| (o, e))
        .filter(|&(o, e)| o != 0.0 || e != 0.0)
        .collect();
    if cells.iter().any(|&(o, e)| e <= 0.0 && o > 0.0) {
        return (f64::INFINITY, cells.len().saturating_sub(1), 0, 0);
    }
    cells.sort_by(|a, b| a.1.total_cmp(&b.1));

    let mut groups: Vec<(f64, f64)> = Vec::with_capacity(cells.len());
    let (mut pool, mut pooled_in, mut pooled_out) = ((0.0, 0.0), 0usize, 0usize);
    let mut pool_open = false;
    for (o, e) in cells {
        if e >= min_expected && !pool_open {
            groups.push((o, e));
            continue;
        }
        // Sorted: once a cell reaches the threshold, only a pool still being filled remains.
        pool.0 += o;
        pool.1 += e;
        pool_open = true;
        pooled_in += 1;
        if pool.1 >= min_expected {
            groups.push(pool);
            pooled_out += 1;
            pool = (0.0, 0.0);
            pool_open = false;
        }
    }
    if pool_open {
        // A remainder below the threshold joins the smallest group (the last pool, if any).
        match groups.iter_mut().min_by(|a, b| a.1.total_cmp(&b.1)) {
            Some(g) => {
                g.0 += pool.0;
                g.1 += pool.1;
            }
            None => {
                groups.push(pool);
                pooled_out += 1;
            }
        }
    }
    let statistic = groups.iter().map(|&(o, e)| (o - e) * (o - e) / e).sum();
    (
        statistic,
        groups.len().saturating_sub(1),
        pooled_in,
        pooled_out,
    )
}

/// Cumulative distribution function of the chi-square distribution with `dof` degrees of
/// freedom: P(dof/2, x/2).
pub fn chi2_cdf(x: f64, dof: f64) -> f64 {
    if x <= 0.0 {
        return 0.0;
    }
    regularized_gamma_p(0.5 * dof, 0.5 * x)
}

/// Survival function (upper tail, the p-value of a statistic `x`) of the chi-square
/// distribution with `dof` degrees of freedom: Q(dof/2, x/2).
pub fn chi2_sf(x: f64, dof: f64) -> f64 {
    if x <= 0.0 {
        return 1.0;
    }
    regularized_gamma_q(0.5 * dof, 0.5 * x)
}

/// ln Γ(x) for x > 0 (Lanczos approximation, g = 7, nine terms; relative error ~1e-15), and
/// for non-integer x < 0 through the reflection formula (ln |Γ|).
pub fn ln_gamma(x: f64) -> f64 {
    const G: f64 = 7.0;
    const C: [f64; 9] = [
        0.999_999_999_999_809_9,
        676.520_368_121_885_1,
        -1_259.139_216_722_402_8,
        771.323_428_777_653_1,
        -176.615_029_162_140_6,
        12.507_343_278_686_905,
        -0.138_571_095_265_720_12,
        9.984_369_578_019_572e-6,
        1.505_632_735_149_311_6e-7,
    ];
    if x < 0.5 {
        // Γ(x) Γ(1 − x) = π / sin(πx)
        let s = (std::f64::consts::PI * x).sin().abs();
        return (std::f64::consts::PI / s).ln() - ln_gamma(1.0 - x);
    }
    let x = x - 1.0;
    let mut a = C[0];
    for (i, &c) in C.iter().enumerate().skip(1) {
        a += c / (x + i as f64);
    }
    let t = x + G + 0.5;
    0.5 * TAU.ln() + (x + 0.5) * t.ln() - t + a.ln()
}

/// The regularized lower incomplete gamma function P(a, x) = γ(a, x) / Γ(a), a > 0, x ≥ 0.
pub fn regularized_gamma_p(a: f64, x: f64) -> f64 {
    // Also NaN for NaN arguments.
    if !(a > 0.0 && x >= 0.0) {
        return f64::NAN;
    }
    if x == 0.0 {
        0.0
    } else if x.is_infinite() {
        1.0
    } else if x < a + 1.0 {
        gamma_series(a, x)
    } else {
        1.0 - gamma_continued_fraction(a, x)
    }
}

/// The regularized upper incomplete gamma function Q(a, x) = 1 − P(a, x), computed directly
/// (without cancellation) in the tail.
pub fn regularized_gamma_q(a: f64, x: f64) -> f64 {
    // Also NaN for NaN arguments.
    if !(a > 0.0 && x >= 0.0) {
        return f64::NAN;
    }
    if x == 0.0 {
        1.0
    } else if x.is_infinite() {
        0.0
    } else if x < a + 1.0 {
        1.0 - gamma_series(a, x)
    } else {
        gamma_continued_fraction(a, x)
    }
}

/// ln(e^−x x^a / Γ(a)), the common prefactor of both expansions.
fn gamma_prefactor_ln(a: f64, x: f64) -> f64 {
    -x + a * x.ln() - ln_gamma(a)
}

/// P(a, x) by its power series, converging quickly for x < a + 1:
/// P(a, x) = e^−x x^a / Γ(a) · Σₙ xⁿ / (a (a+1) ⋯ (a+n)).
fn gamma_series(a: f64, x: f64) -> f64 {
    let mut term = 1.0 / a;
    let mut sum = term;
    let mut ap = a;
    // Terms shrink once a + n > x; for x ≈ a it takes O(√a) of them.
    let max_iter = 1000 + 20 * (a.sqrt() as usize);
    for _ in 0..max_iter {
        ap += 1.0;
        term *= x / ap;
        sum += term;
        if term.abs() < sum.abs() * 1e-16 {
            break;
        }
    }
    (sum.ln() + gamma_prefactor_ln(a, x)).exp().min(1.0)
}

/// Q(a, x) by its continued fraction, converging quickly for x > a + 1:
/// Q(a, x) = e^−x x^a / Γ(a) · 1/(x+1−a− 1·(1−a)/(x+3−a− 2·(2−a)/(x+5−a− ⋯))),
/// evaluated with the modified Lentz method.
fn gamma_continued_fraction(a: f64, x: f64) -> f64 {
    const TINY: f64 = 1e-300;
    let mut b = x + 1.0 - a;
    let mut c = 1.0 / TINY;
    let mut d = 1.0 / b;
    let mut h = d;
    let max_iter = 1000 + 20 * (a.sqrt() as usize);
    for i in 1..=max_iter {
        let an = -(i as f64) * (i as f64 - a);
        b += 2.0;
        d = an * d + b;
        if d.abs() < TINY {
            d = TINY;
        }
        c = b + an / c;
        if c.abs() < TINY {
            c = TINY;
        }
        d = 1.0 / d;
        let delta = d * c;
        h *= delta;
        if (delta - 1.0).abs() < 1e-16 {
            break;
        }
    }
    (h.ln() + gamma_prefactor_ln(a, x)).exp().min(1.0)
}

// ---------------------------------------------------------------------------------------------
// Sample values, binning, quadrature
// ---------------------------------------------------------------------------------------------

/// Uniform sample values in [0, 1) with 24 random bits, like [`crate::IndependentSampler`].
struct UniformStream(Pcg32);

impl UniformStream {
    fn new(seed: u64) -> Self {
        Self(Pcg32::seed_from_u64(seed))
    }

    fn next_1d(&mut self) -> f32 {
        (self.0.random::<u32>() >> 8) as f32 * (1.0 / (1u32 << 24) as f32)
    }

    /// A 2D value then a 1D value.
    fn next_sample(&mut self) -> (Vec2, f32) {
        let x = self.next_1d();
        let y = self.next_1d();
        let z = self.next_1d();
        (Vec2::new(x, y), z)
    }
}

/// Unit direction at 1 − cos θ = `omc` and azimuth `phi`.
fn direction(omc: f64, phi: f64) -> Vec3 {
    let sin_theta = (omc * (2.0 - omc)).max(0.0).sqrt();
    let (s, c) = phi.sin_cos();
    Vec3::new(
        (sin_theta * c) as f32,
        (sin_theta * s) as f32,
        (1.0 - omc) as f32,
    )
}

enum DirBin {
    Cell(usize),
    Outside,
    Invalid,
}

/// Tolerance on the length of sampled directions.
const UNIT_TOLERANCE: f64 = 1e-3;
/// Samples this far (relative to the extent) beyond the edge of a grid are clamped into it:
/// they come from round-off in samplers whose support ends exactly there.
const EDGE_MARGIN: f64 = 1e-4;

fn bin_direction(d: Vec3, cap_width: f64, cols: usize, rows: usize) -> DirBin {
    let (x, y, z) = (d.x as f64, d.y as f64, d.z as f64);
    let len2 = x * x + y * y + z * z;
    if !len2.is_finite() || (len2.sqrt() - 1.0).abs() > UNIT_TOLERANCE {
        return DirBin::Invalid;
    }
    let inv = 1.0 / len2.sqrt();
    let (x, y, z) = (x * inv, y * inv, z * inv);
    // 1 − cos θ, from sin² θ near the pole where z has lost the information.
    let omc = if z > 0.0 {
        (x * x + y * y) / (1.0 + z)
    } else {
        1.0 - z
    };
    if omc > cap_width * (1.0 + EDGE_MARGIN) {
        return DirBin::Outside;
    }
    let row = ((omc / cap_width * rows as f64) as usize).min(rows - 1);
    let mut phi = y.atan2(x);
    if phi < 0.0 {
        phi += TAU;
    }
    let col = ((phi / TAU * cols as f64) as usize).min(cols - 1);
    DirBin::Cell(row * cols + col)
}

/// Cell index of `v` along one axis of a grid of `n` cells over [lo, hi], clamping a small
/// margin; `None` outside.
fn grid_index(v: f64, lo: f64, hi: f64, n: usize) -> Option<usize> {
    let t = (v - lo) / (hi - lo);
    // NaN fails `contains`.
    if !(-EDGE_MARGIN..=1.0 + EDGE_MARGIN).contains(&t) {
        return None;
    }
    Some(((t * n as f64).max(0.0) as usize).min(n - 1))
}

/// Counts pdf values that are negative, NaN or infinite; they are replaced by 0.
#[derive(Default)]
struct BadValues {
    count: Cell<usize>,
    first: Cell<Option<f64>>,
}

impl BadValues {
    fn check(&self, v: f64) -> f64 {
        if v.is_finite() && v >= 0.0 {
            v
        } else {
            self.count.set(self.count.get() + 1);
            if self.first.get().is_none() {
                self.first.set(Some(v));
            }
            0.0
        }
    }

    fn report(&self, t: &mut Tally) {
        if self.count.get() > 0 {
            t.fail(format!(
                "the pdf returned {} negative or non-finite values (first: {})",
                self.count.get(),
                self.first.get().unwrap()
            ));
        }
    }
}

/// Acceptable quadrature error (in probability) of a cell whose integral is about `p`:
/// a small fraction of the standard deviation of its count, so that quadrature error adds a
/// negligible amount to the statistic.
fn cell_tolerance(p: f64, n: f64) -> f64 {
    0.02 * (p * n).max(1.0).sqrt() / n
}

/// Deepest subdivision of a cell by the adaptive quadrature (4^depth subcells at most).
const MAX_DEPTH: u32 = 9;

const GAUSS_X: [f64; 4] = [
    -0.861_136_311_594_052_6,
    -0.339_981_043_584_856_3,
    0.339_981_043_584_856_3,
    0.861_136_311_594_052_6,
];
const GAUSS_W: [f64; 4] = [
    0.347_854_845_137_453_9,
    0.652_145_154_862_546_1,
    0.652_145_154_862_546_1,
    0.347_854_845_137_453_9,
];

/// 4 × 4-point Gauss-Legendre quadrature over [x0, x1] × [y0, y1] (exact for polynomials of
/// degree 7 in each variable), with the largest and smallest values seen.
fn gauss_rect(f: &dyn Fn(f64, f64) -> f64, x0: f64, x1: f64, y0: f64, y1: f64) -> Quad {
    let (cx, hx) = (0.5 * (x0 + x1), 0.5 * (x1 - x0));
    let (cy, hy) = (0.5 * (y0 + y1), 0.5 * (y1 - y0));
    let mut q = Quad {
        integral: 0.0,
        min: f64::INFINITY,
        max: 0.0,
    };
    for (gy, wy) in GAUSS_X.iter().zip(GAUSS_W) {
        let y = cy + hy * gy;
        let mut row = 0.0;
        for (gx, wx) in GAUSS_X.iter().zip(GAUSS_W) {
            let v = f(cx + hx * gx, y);
            q.min = q.min.min(v);
            q.max = q.max.max(v);
            row += wx * v;
        }
        q.integral += wy * row;
    }
    q.integral *= hx * hy;
    q
}

#[derive(Clone, Copy)]
struct Quad {
    integral: f64,
    min: f64,
    max: f64,
}

/// Adaptive quadrature of `f` over the rectangle `r` = [x0, x1, y0, y1], given its Gauss
/// estimate `whole`. The estimate is compared with the sum over the four quadrants, which are
/// subdivided in turn while
/// * the two disagree by more than `tol` (halved at every level, so that the error along a
///   discontinuity, spread over twice as many subcells at each level, converges), or
/// * the rectangle straddles the edge of the support (zero and positive values among the
///   Gauss nodes and probes at its corners and edge midpoints) and could hide more than
///   `support_tol` there. Both estimates agree on zero when a thin sliver of support cuts a
///   corner between the nodes; the probes catch it, as a sample landing in a cell that
///   expects nothing fails the whole test.
fn adaptive_rect(
    f: &dyn Fn(f64, f64) -> f64,
    r: [f64; 4],
    whole: Quad,
    tol: f64,
    support_tol: f64,
    depth: u32,
) -> f64 {
    let [x0, x1, y0, y1] = r;
    let (xm, ym) = (0.5 * (x0 + x1), 0.5 * (y0 + y1));
    let quads = [
        [x0, xm, y0, ym],
        [xm, x1, y0, ym],
        [x0, xm, ym, y1],
        [xm, x1, ym, y1],
    ];
    let parts = quads.map(|q| gauss_rect(f, q[0], q[1], q[2], q[3]));
    let sum: f64 = parts.iter().map(|p| p.integral).sum();
    if depth == 0 {
        return sum;
    }
    let mut min = parts.iter().fold(whole.min, |m, p| m.min(p.min));
    let mut max = parts.iter().fold(whole.max, |m, p| m.max(p.max));
    // Probes just inside the corners, on the edge midpoints and at the centre.
    let (ex, ey) = (PROBE_INSET * (x1 - x0), PROBE_INSET * (y1 - y0));
    for y in [y0 + ey, ym, y1 - ey] {
        for x in [x0 + ex, xm, x1 - ex] {
            let v = f(x, y);
            min = min.min(v);
            max = max.max(v);
        }
    }
    let straddles_support = min <= 0.0 && max > 0.0;
    let area = (x1 - x0) * (y1 - y0);
    if (sum - whole.integral).abs() <= tol && !(straddles_support && area * max > support_tol) {
        return sum;
    }
    quads
        .iter()
        .zip(parts)
        .map(|(q, p)| adaptive_rect(f, *q, p, 0.5 * tol, support_tol, depth - 1))
        .sum()
}

/// Relative inset of the corner probes of [`adaptive_rect`], keeping them off the cell edges
/// where many supports end exactly.
const PROBE_INSET: f64 = 1e-6;

/// Integrals of `f` over the cells of a `res[0]` × `res[1]` grid over [lo, hi] (row-major,
/// x fastest), each to the tolerance `tol(rough estimate)`.
fn integrate_grid(
    f: &dyn Fn(f64, f64) -> f64,
    res: [usize; 2],
    lo: [f64; 2],
    hi: [f64; 2],
    tol: &dyn Fn(f64) -> f64,
) -> Vec<f64> {
    let [cols, rows] = res;
    let dx = (hi[0] - lo[0]) / cols as f64;
    let dy = (hi[1] - lo[1]) / rows as f64;
    let mut out = Vec::with_capacity(cols * rows);
    for r in 0..rows {
        let y0 = lo[1] + r as f64 * dy;
        let y1 = if r + 1 == rows { hi[1] } else { y0 + dy };
        for c in 0..cols {
            let x0 = lo[0] + c as f64 * dx;
            let x1 = if c + 1 == cols { hi[0] } else { x0 + dx };
            let whole = gauss_rect(f, x0, x1, y0, y1);
            let t = tol(whole.integral);
            out.push(if t.is_finite() {
                adaptive_rect(f, [x0, x1, y0, y1], whole, t, t, MAX_DEPTH)
            } else {
                whole.integral
            });
        }
    }
    out
}

// ---------------------------------------------------------------------------------------------
// Tally and report
// ---------------------------------------------------------------------------------------------

enum Domain {
    Sphere { cos_theta_min: f64 },
    Rect { min: Vec2, max: Vec2 },
    Discrete,
}

/// Everything gathered by a test, turned into a [`Chi2Result`] by [`Tally::finish`].
struct Tally {
    domain: Domain,
    res: [usize; 2],
    sample_count: usize,
    observed: Vec<f64>,
    expected: Vec<f64>,
    /// Cells outside the grid: (name, observed, expected).
    extras: Vec<(&'static str, f64, f64)>,
    lost: usize,
    integral: f64,
    failures: Vec<String>,
}

impl Tally {
    fn new(domain: Domain, res: [usize; 2], sample_count: usize) -> Self {
        Self {
            domain,
            res,
            sample_count,
            observed: Vec::new(),
            expected: Vec::new(),
            extras: Vec::new(),
            lost: 0,
            integral: 0.0,
            failures: Vec::new(),
        }
    }

    fn extra(&mut self, name: &'static str, observed: f64, expected: f64) {
        self.extras.push((name, observed, expected));
    }

    fn fail(&mut self, msg: String) {
        self.failures.push(msg);
    }

    fn finish(mut self, min_expected: f64, alpha: f64) -> Chi2Result {
        let n = self.sample_count as f64;
        // Failed samples are one more cell, expecting the mass the pdf is missing. A pdf that
        // integrates to slightly more than one (quadrature error) expects no failures.
        let lost_expected = (n * (1.0 - self.integral)).max(0.0);
        self.extra("failed samples", self.lost as f64, lost_expected);

        let mut obs = self.observed.clone();
        let mut exp = self.expected.clone();
        for &(_, o, e) in &self.extras {
            obs.push(o);
            exp.push(e);
        }
        let impossible: Vec<usize> = (0..obs.len())
            .filter(|&i| obs[i] > 0.0 && exp[i] <= 0.0)
            .collect();
        if !impossible.is_empty() {
            let grid = self.observed.len();
            let names: Vec<String> = impossible
                .iter()
                .take(8)
                .map(|&i| {
                    if i < grid {
                        format!(
                            "cell (col {}, row {}): {} samples",
                            i % self.res[0],
                            i / self.res[0],
                            obs[i]
                        )
                    } else {
                        format!("{}: {}", self.extras[i - grid].0, obs[i])
                    }
                })
                .collect();
            let mut msg = format!(
                "{} cells received samples where the pdf integrates to zero: {}",
                impossible.len(),
                names.join("; ")
            );
            if matches!(self.domain, Domain::Sphere { .. }) {
                msg.push_str(
                    " (a narrow lobe may fall between quadrature points: zoom with cos_theta_min)",
                );
            }
            self.fail(msg);
        }
        let (statistic, dof, pooled_in, pooled_out) = pearson_chi2(&obs, &exp, min_expected);
        if dof < 1 {
            self.fail(format!(
                "only {} cells after pooling: too few for a test",
                dof + 1
            ));
        }
        let p_value = if statistic.is_finite() {
            chi2_sf(statistic, dof as f64)
        } else {
            0.0
        };
        let passed = self.failures.is_empty() && p_value.is_finite() && p_value >= alpha;

        let mut report = String::new();
        let r = &mut report;
        let [cols, rows] = self.res;
        let _ = match self.domain {
            Domain::Sphere { cos_theta_min } => writeln!(
                r,
                "chi-square test of directions: {rows} rows uniform in cos θ from 1 (row 0) to {cos_theta_min} \
                 × {cols} columns in φ from 0 to 2π"
            ),
            Domain::Rect { min, max } => writeln!(
                r,
                "chi-square test of points in [{}, {}] × [{}, {}]: {cols} columns in x × {rows} rows in y (row 0 lowest)",
                min.x, max.x, min.y, max.y
            ),
            Domain::Discrete => writeln!(r, "chi-square test of indices 0..{cols}"),
        };
        let sampled = self.sample_count - self.lost;
        let _ = writeln!(
            r,
            "  {} samples, {} succeeded (fraction {:.6}); integral of the pdf {:.6}",
            self.sample_count,
            sampled,
            sampled as f64 / n,
            self.integral
        );
        for &(name, o, e) in &self.extras {
            let _ = writeln!(r, "  {name}: observed {o}, expected {e:.2}");
        }
        if pooled_in > 0 {
            let _ = writeln!(
                r,
                "  pooled {pooled_in} cells expecting < {min_expected} samples into {pooled_out} groups"
            );
        }
        let _ = writeln!(
            r,
            "  statistic {statistic:.2}, {dof} degrees of freedom, p-value {p_value:.4e}, significance level {alpha:.4e}: {}",
            if passed { "accepted" } else { "REJECTED" }
        );
        for f in &self.failures {
            let _ = writeln!(r, "  failure: {f}");
        }
        if !passed {
            self.write_tables(r);
        }

        Chi2Result {
            statistic,
            dof,
            p_value,
            passed,
            integral_of_pdf: self.integral,
            sampled_fraction: sampled as f64 / n,
            res: self.res,
            observed: self.observed,
            expected: self.expected,
            report,
        }
    }

    fn write_tables(&self, r: &mut String) {
        let [cols, rows] = self.res;
        let _ = writeln!(
            r,
            "residual map, (observed − expected) / √expected per cell, one line per row:\n  \
             '.' |z| < 3, '+' / '-' 3 ≤ |z| < 6, '#' / '=' |z| ≥ 6 (more / fewer samples than expected), \
             '!' samples where nothing is expected, ' ' nothing expected or observed"
        );
        for row in 0..rows {
            let line: String = (0..cols)
                .map(|c| {
                    let i = row * cols + c;
                    residual_char(self.observed[i], self.expected[i])
                })
                .collect();
            let _ = writeln!(r, "  {row:4} |{line}|");
        }
        let _ = writeln!(r, "observed counts:");
        for row in 0..rows {
            let line: Vec<String> = (0..cols)
                .map(|c| format!("{}", self.observed[row * cols + c]))
                .collect();
            let _ = writeln!(r, "  {row:4}: {}", line.join(" "));
        }
        let _ = writeln!(r, "expected counts:");
        for row in 0..rows {
            let line: Vec<String> = (0..cols)
                .map(|c| format!("{:.1}", self.expected[row * cols + c]))
                .collect();
            let _ = writeln!(r, "  {row:4}: {}", line.join(" "));
        }
    }
}

fn residual_char(o: f64, e: f64) -> char {
    if e <= 0.0 {
        return if o > 0.0 { '!' } else { ' ' };
    }
    let z = (o - e) / e.sqrt();
    match z {
        z if z >= 6.0 => '#',
        z if z >= 3.0 => '+',
        z if z <= -6.0 => '=',
        z if z <= -3.0 => '-',
        _ => '.',
    }
}

// ---------------------------------------------------------------------------------------------
// Tests of the harness itself (the warps are tested in `warp.rs`).
// ---------------------------------------------------------------------------------------------

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: f64, b: f64, tol: f64) -> bool {
        (a - b).abs() <= tol * b.abs().max(1e-300)
    }

    #[test]
    fn ln_gamma_known_values() {
        let sqrt_pi_ln = 0.5 * std::f64::consts::PI.ln();
        let cases = [
            (1.0, 0.0),
            (2.0, 0.0),
            (0.5, sqrt_pi_ln),
            (1.5, sqrt_pi_ln - std::f64::consts::LN_2),
            (10.0, 362_880.0f64.ln()),
            (0.1, 9.513_507_698_668_732_f64.ln()),
            (171.0, 706.573_062_245_787_4), // ln(170!)
        ];
        for (x, want) in cases {
            let got = ln_gamma(x);
            assert!(
                (got - want).abs() < 1e-12 * want.abs().max(1.0),
                "lnΓ({x}) = {got}, want {want}"
            );
        }
        // Γ(n + 1) = n Γ(n) across the whole range used by the p-values.
        for i in 1..2000 {
            let x = i as f64 * 0.37;
            let lhs = ln_gamma(x + 1.0);
            let rhs = ln_gamma(x) + x.ln();
            assert!(
                (lhs - rhs).abs() < 1e-11 * lhs.abs().max(1.0),
                "recurrence at {x}"
            );
        }
    }

    #[test]
    fn incomplete_gamma_closed_forms() {
        // P(1, x) = 1 − e^−x and P(1/2, x) = erf(√x).
        for x in [1e-3, 0.1, 0.5, 1.0, 2.0, 5.0, 20.0] {
            assert!(
                close(regularized_gamma_q(1.0, x), (-x).exp(), 1e-13),
                "Q(1, {x})"
            );
            assert!(
                close(regularized_gamma_p(1.0, x), -(-x).exp_m1(), 1e-13),
                "P(1, {x})"
            );
        }
        assert!(close(
            regularized_gamma_p(0.5, 1.0),
            0.842_700_792_949_714_9,
            1e-13
        ));
        assert!(close(
            regularized_gamma_p(0.5, 4.0),
            0.995_322_265_018_952_7,
            1e-13
        ));
        assert!(close(
            regularized_gamma_q(0.5, 9.0),
            2.209_049_699_858_544e-5,
            1e-10
        )); // erfc(3)
            // Integer a: Q(n, x) = e^−x Σ_{k<n} x^k / k!, on both sides of the switch at x = a + 1
            // and for large a, where the series and continued fraction need many terms.
        for (a, x) in [
            (3, 0.5),
            (3, 3.9),
            (3, 4.1),
            (3, 30.0),
            (50, 40.0),
            (50, 51.0),
            (50, 60.0),
            (400, 380.0),
            (400, 430.0),
        ] {
            // Terms in log space: e^−x alone underflows for large x.
            let mut ln_term: f64 = -x;
            let mut sum = 0.0;
            for k in 0..a {
                if k > 0 {
                    ln_term += (x / k as f64).ln();
                }
                sum += ln_term.exp();
            }
            let q = regularized_gamma_q(a as f64, x);
            let p = regularized_gamma_p(a as f64, x);
            assert!(close(q, sum, 1e-10), "Q({a}, {x}) = {q}, want {sum}");
            assert!((p + q - 1.0).abs() < 1e-14, "P + Q at ({a}, {x})");
        }
        assert_eq!(regularized_gamma_p(2.0, 0.0), 0.0);
        assert_eq!(regularized_gamma_q(2.0, 0.0), 1.0);
        assert!(regularized_gamma_p(-1.0, 1.0).is_nan());
    }

    #[test]
    fn chi2_table_values() {
        // Critical values from standard tables: (dof, x, cdf).
        let table = [
            (1.0, 3.841, 0.95),
            (1.0, 6.635, 0.99),
            (2.0, 9.210, 0.99),
            (5.0, 11.070, 0.95),
            (10.0, 23.209, 0.99),
            (10.0, 2.558, 0.01),
            (30.0, 50.892, 0.99),
            (100.0, 135.807, 0.99),
            (100.0, 70.065, 0.01),
            (1000.0, 1106.969, 0.99),
        ];
        for (dof, x, cdf) in table {
            let got = chi2_cdf(x, dof);
            assert!(
                (got - cdf).abs() < 2e-4,
                "chi2 cdf(dof {dof}, {x}) = {got}, want {cdf}"
            );
            assert!((chi2_sf(x, dof) + got - 1.0).abs() < 1e-14);
        }
        // dof 2 is exponential: cdf = 1 − e^(−x/2).
        for x in [0.1, 1.0, 7.0, 40.0] {
            assert!(close(chi2_sf(x, 2.0), (-0.5 * x).exp(), 1e-13));
        }
        // Large dof: the median is ≈ k (1 − 2/(9k))³.
        let k: f64 = 8000.0;
        let median = k * (1.0 - 2.0 / (9.0 * k)).powi(3);
        assert!((chi2_cdf(median, k) - 0.5).abs() < 1e-3);
        assert_eq!(chi2_sf(0.0, 3.0), 1.0);
    }

    #[test]
    fn sidak() {
        assert!(close(sidak_alpha(0.01, 1), 0.01, 1e-14));
        let a = sidak_alpha(0.01, 10);
        assert!(close(1.0 - (1.0 - a).powi(10), 0.01, 1e-12));
        assert!(a < 0.01 / 10.0 * 1.01 && a > 0.01 / 10.0);
        assert!(close(sidak_alpha(0.05, 1_000_000), 5.129_329_307e-8, 1e-8));
        assert_eq!(sidak_alpha(0.01, 0), 0.01);
    }

    #[test]
    fn pooling() {
        // Large cells stay alone; small ones are merged until they expect 5.
        let obs = [100.0, 2.0, 1.0, 0.0, 3.0, 0.0];
        let exp = [98.0, 1.5, 1.5, 1.5, 1.5, 0.0];
        let (stat, dof, pooled_in, pooled_out) = pearson_chi2(&obs, &exp, 5.0);
        // Pool of four small cells: 6 observed vs 6 expected, plus 100 vs 98.
        assert_eq!((dof, pooled_in, pooled_out), (1, 4, 1));
        assert!(close(stat, 4.0 / 98.0, 1e-12));
        // A remainder that never reaches the threshold joins the smallest group.
        let (stat, dof, ..) = pearson_chi2(&[10.0, 1.0], &[10.0, 2.0], 5.0);
        assert_eq!(dof, 0);
        assert!(close(stat, 1.0 / 12.0, 1e-12));
        // Samples where nothing is expected.
        assert_eq!(pearson_chi2(&[1.0, 5.0], &[0.0, 6.0], 5.0).0, f64::INFINITY);
    }

    #[test]
    fn quadrature_handles_discontinuities() {
        // Indicator of the unit disk over [-1, 1]²: area π, discontinuous along a circle.
        let f = |x: f64, y: f64| if x * x + y * y <= 1.0 { 1.0 } else { 0.0 };
        let cells = integrate_grid(&f, [7, 7], [-1.0, -1.0], [1.0, 1.0], &|_| 1e-7);
        let total: f64 = cells.iter().sum();
        assert!((total - std::f64::consts::PI).abs() < 1e-4, "{total}");
        // Smooth: ∫∫ x² y³ over [0, 1] × [0, 2] = 1/3 · 4 exactly.
        let g = |x: f64, y: f64| x * x * y * y * y;
        let cells = integrate_grid(&g, [3, 2], [0.0, 0.0], [1.0, 2.0], &|_| 1e-12);
        assert!((cells.iter().sum::<f64>() - 4.0 / 3.0).abs() < 1e-13);
    }

    #[test]
    fn binning_of_directions() {
        let (cols, rows) = (8, 4);
        // Near the pole z rounds to 1 but x, y keep the angle.
        let d = Vec3::new(1e-4, 0.0, 1.0);
        // 1 − cos θ = sin² θ / (1 + cos θ) ≈ 5e-9.
        assert!(matches!(
            bin_direction(d, 4e-9, cols, rows),
            DirBin::Outside
        ));
        assert!(matches!(bin_direction(d, 9e-9, cols, rows), DirBin::Cell(c) if c / cols == 2));
        assert!(
            matches!(bin_direction(Vec3::new(0.0, -1.0, 0.0), 2.0, cols, rows), DirBin::Cell(c) if c == 2 * cols + 6)
        );
        assert!(
            matches!(bin_direction(Vec3::new(0.0, 0.0, -1.0), 2.0, cols, rows), DirBin::Cell(c) if c / cols == 3)
        );
        assert!(matches!(
            bin_direction(Vec3::new(0.0, 0.0, 2.0), 2.0, cols, rows),
            DirBin::Invalid
        ));
        assert!(matches!(
            bin_direction(Vec3::NAN, 2.0, cols, rows),
            DirBin::Invalid
        ));
    }
}
