//! The test harness every model's tests share, in the spirit of Mitsuba's
//! `src/bsdfs/tests/` (with `chi2.py`) and pbrt-v4's `bsdfs_test.cpp`:
//!
//! * [`chi2_bsdf`]: a chi-square goodness-of-fit test of `sample` against `pdf` over the
//!   sphere of `wo` (the harness of `radia_sampling::chi2`: pdf integrated per cell, small
//!   cells pooled), optionally zoomed onto a lobe;
//! * [`check_consistency`]: the pdf returned by `sample` equals `pdf`, the weight equals
//!   eval/pdf, every value finite;
//! * [`check_reciprocity`]: f(wi, wo) = f(wo, wi);
//! * [`albedo_sampled`] and [`albedo_uniform`]: directional albedo by the model's own
//!   sampling and, independently of it, by uniform sampling of the sphere;
//! * [`check_finite`]: no NaN or infinity from any entry point.
//!
//! Every chi-square test of the crate uses [`suite_alpha`]: 1% Šidák-corrected for
//! [`CHI2_SUITE_SIZE`] tests, so that the whole suite falsely fails with probability ≤ 1%.
//! The tests are deterministic (fixed seeds): a pass is reproducible.

use crate::{Bsdf, LobeFlags, ShadingPoint};
use glam::{Vec2, Vec3};
use radia_math::{Frame, Spectrum};
use radia_sampling::chi2::{self, chi2_test, Chi2Config, Chi2Result};
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg32;

/// An upper bound on the number of chi-square tests in this crate's suite (about 505 at
/// the time of writing: rough dielectric 160, principled 57, principledthin 56, microfacet
/// normals, rough conductor and Cook–Torrance 48 each, plastics 28, Phong models 32, blend
/// 17, two-sided 8, Lambert 4).
pub const CHI2_SUITE_SIZE: usize = 600;

/// Per-test significance level: 0.01 for the whole suite (Šidák).
pub fn suite_alpha() -> f64 {
    chi2::sidak_alpha(chi2::DEFAULT_ALPHA, CHI2_SUITE_SIZE)
}

pub const SP: ShadingPoint = ShadingPoint::at_uv(Vec2::ZERO);

/// The unit direction with cosine `cos_theta` to +z and azimuth `phi`.
pub fn dir(cos_theta: f32, phi: f32) -> Vec3 {
    let s = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
    Vec3::new(s * phi.cos(), s * phi.sin(), cos_theta)
}

/// `v` rotated by `phi` about +z.
pub fn rotate_z(v: Vec3, phi: f32) -> Vec3 {
    let (s, c) = phi.sin_cos();
    Vec3::new(c * v.x - s * v.y, s * v.x + c * v.y, v.z)
}

/// Midpoint quadrature of `f` over the sphere on an `n_theta` × `n_phi` grid in (θ, φ).
pub fn integrate_sphere(f: impl Fn(Vec3) -> f64, n_theta: usize, n_phi: usize) -> f64 {
    let dt = std::f64::consts::PI / n_theta as f64;
    let dp = std::f64::consts::TAU / n_phi as f64;
    let mut sum = 0.0;
    for i in 0..n_theta {
        let t = (i as f64 + 0.5) * dt;
        let (st, ct) = t.sin_cos();
        let mut row = 0.0;
        for j in 0..n_phi {
            let p = (j as f64 + 0.5) * dp;
            let d = Vec3::new((st * p.cos()) as f32, (st * p.sin()) as f32, ct as f32);
            row += f(d);
        }
        sum += row * st;
    }
    sum * dt * dp
}

/// Calls `f(u2, u1)` with `n` uniform sample values from a seeded PCG32 stream.
pub fn for_each_sample(n: usize, seed: u64, mut f: impl FnMut(Vec2, f32)) {
    let mut rng = Pcg32::seed_from_u64(seed);
    for _ in 0..n {
        let u = Vec2::new(rng.random::<f32>(), rng.random::<f32>());
        f(u, rng.random::<f32>());
    }
}

/// Where a chi-square test looks: the whole sphere, or a cap around a lobe's centre.
#[derive(Clone, Copy, Debug)]
pub struct Zoom {
    /// Direction mapped to the pole of the histogram (None: +z).
    pub center: Option<Vec3>,
    /// The histogram covers cos θ ≥ this around the centre (−1: the whole sphere).
    pub cos_theta_min: f64,
}

impl Zoom {
    pub const SPHERE: Zoom = Zoom {
        center: None,
        cos_theta_min: -1.0,
    };
    /// A cap around a lobe centred on `center` (a mirror or refraction direction) reaching
    /// `angle` radians from it. The histogram's pole is where its thin wedge cells meet and
    /// the pdf integration is least accurate; for a lobe at the horizon, where the pdf jumps
    /// to zero, the cap's centre is tilted away from the horizon (|z| ≥ 0.15) and widened.
    pub fn lobe(center: Vec3, angle: f32) -> Zoom {
        let z = if center.z < 0.0 {
            center.z.min(-0.15)
        } else {
            center.z.max(0.15)
        };
        let c = Vec3::new(center.x, center.y, z).normalize();
        let angle = angle + c.dot(center).clamp(-1.0, 1.0).acos();
        if angle >= std::f32::consts::FRAC_PI_2 {
            // A broad lobe: its whole hemisphere.
            return Zoom::cap(Vec3::new(0.0, 0.0, z.signum()), std::f32::consts::FRAC_PI_2);
        }
        Zoom::cap(c, angle)
    }

    /// A cap of half-angle `angle` (radians) around `center`; the whole sphere when the
    /// angle reaches π.
    pub fn cap(center: Vec3, angle: f32) -> Zoom {
        if angle >= std::f32::consts::PI {
            return Zoom {
                center: Some(center),
                cos_theta_min: -1.0,
            };
        }
        Zoom {
            center: Some(center),
            cos_theta_min: (angle as f64).cos(),
        }
    }
}

/// Chi-square test of the smooth part of `b`'s sampling at `wi` against its pdf. Delta
/// samples count as lost: the pdf then integrates to 1 − P(delta), which the test checks.
///
/// A zoomed test (a cap smaller than the sphere) only looks at the side of the surface its
/// centre is on: samples on the other side count as lost and the pdf is zero there. The
/// rest of the sphere outside the cap is a single cell whose expected count is integrated
/// coarsely, which is accurate unless it holds a narrow lobe, as the other lobe of a smooth
/// rough dielectric: that lobe is then tested by its own zoomed test.
pub fn chi2_bsdf(b: &Bsdf, wi: Vec3, zoom: Zoom, sample_count: usize) -> Chi2Result {
    chi2_bsdf_res(b, wi, zoom, sample_count, (51, 100))
}

/// [`chi2_bsdf`] on a histogram of `res` = (rows in cos θ, columns in φ).
pub fn chi2_bsdf_res(
    b: &Bsdf,
    wi: Vec3,
    zoom: Zoom,
    sample_count: usize,
    res: (usize, usize),
) -> Chi2Result {
    let frame = zoom.center.map(Frame::from_normal);
    let side = match zoom.center {
        Some(c) if zoom.cos_theta_min > -1.0 => c.z.signum(),
        _ => 0.0,
    };
    let on_side = |wo: Vec3| side == 0.0 || wo.z * side > 0.0;
    let cfg = Chi2Config {
        sample_count,
        theta_res: res.0,
        phi_res: res.1,
        cos_theta_min: zoom.cos_theta_min,
        alpha: suite_alpha(),
        ..Default::default()
    };
    chi2_test(
        &cfg,
        |u, u1| {
            let s = b.sample(&SP, wi, u1, u)?;
            if s.lobe.is_delta() || !on_side(s.wo) {
                return None;
            }
            Some(frame.map_or(s.wo, |f| f.to_local(s.wo)))
        },
        |d| {
            let wo = frame.map_or(d, |f| f.to_world(d));
            if !on_side(wo) {
                return 0.0;
            }
            b.pdf(&SP, wi, wo) as f64
        },
    )
}

/// Runs [`chi2_bsdf`] and panics with the report (labelled `what`) on failure.
#[track_caller]
pub fn assert_chi2(what: &str, b: &Bsdf, wi: Vec3, zoom: Zoom, sample_count: usize) {
    let r = chi2_bsdf(b, wi, zoom, sample_count);
    assert!(r.passed, "{what}: wi {wi}, {zoom:?}\n{b:?}\n{}", r.report);
}

/// Runs many chi-square tests and reports every failure at the end (with the head of each
/// report), rather than stopping at the first.
pub struct Chi2Suite {
    failures: Vec<String>,
    count: usize,
    /// Histogram resolution (rows in cos θ, columns in φ).
    pub res: (usize, usize),
}

impl Default for Chi2Suite {
    fn default() -> Self {
        Self {
            failures: Vec::new(),
            count: 0,
            res: (51, 100),
        }
    }
}

impl Chi2Suite {
    pub fn check(&mut self, what: &str, b: &Bsdf, wi: Vec3, zoom: Zoom, sample_count: usize) {
        self.count += 1;
        let r = chi2_bsdf_res(b, wi, zoom, sample_count, self.res);
        // Next to nothing expected where the test looks (the transmission side under total
        // internal reflection, the reflection of an index-matched interface): too few cells
        // for a chi-square test; the count must still agree with the pdf's mass (Poisson,
        // 5 standard deviations).
        let n = sample_count as f64;
        let expected = r.integral_of_pdf * n;
        let tiny = expected < 50.0
            && (r.sampled_fraction * n - expected).abs() <= 5.0 * expected.sqrt() + 5.0;
        if !r.passed && !tiny {
            // RADIA_CHI2_VERBOSE=1 shows the whole report (residual maps, tables).
            let lines = if std::env::var_os("RADIA_CHI2_VERBOSE").is_some() {
                70
            } else {
                7
            };
            let head: Vec<&str> = r.report.lines().take(lines).collect();
            self.failures
                .push(format!("{what}: wi {wi}, {zoom:?}\n{}", head.join("\n")));
        }
    }

    #[track_caller]
    pub fn finish(self) {
        assert!(
            self.failures.is_empty(),
            "{} of {} chi-square tests failed:\n\n{}",
            self.failures.len(),
            self.count,
            self.failures.join("\n\n")
        );
    }
}

fn close(a: f32, b: f32, rel: f32, abs: f32) -> bool {
    (a - b).abs() <= rel * a.abs().max(b.abs()) + abs
}

fn finite_spectrum(s: Spectrum) -> bool {
    s.is_finite()
}

/// For `n` samples at `wi`: every returned value is finite and in range, the lobe is one of
/// the model's, the pdf returned by `sample` equals `pdf(wo)` and the weight equals
/// eval(wo)/pdf(wo), within the relative tolerance `rel` (f32 round-off: `pdf` and `eval`
/// recompute the half vector from the rounded `wo`); delta samples have eval = pdf = 0
/// unless the model has smooth lobes too. Ill-conditioned configurations (a Fresnel term at
/// its critical angle) may exceed `rel`: at most 0.2% of the samples, and none by more than
/// 10%. A systematic error shows in most samples. A model that does not sample a lobe
/// ([`Bsdf::samples_lobe`]) returns the same sample for u1 and 1 − u1.
#[track_caller]
pub fn check_consistency(what: &str, b: &Bsdf, wi: Vec3, n: usize, rel: f32) {
    let flags = b.flags();
    let mut outliers = 0usize;
    let mut checked = 0usize;
    for_each_sample(n, 0xc0ffee ^ n as u64, |u, u1| {
        let sampled = b.sample(&SP, wi, u1, u);
        if !b.samples_lobe() {
            let other = b.sample(&SP, wi, 1.0 - u1, u);
            assert_eq!(
                sampled.map(|s| (s.wo, s.weight, s.pdf, s.lobe)),
                other.map(|s| (s.wo, s.weight, s.pdf, s.lobe)),
                "{what}: samples_lobe() is false but u1 changes the sample (wi {wi}, u {u})"
            );
        }
        let Some(s) = sampled else {
            return;
        };
        let ctx = || format!("{what}: wi {wi}, u ({u}, {u1}), sample {s:?}");
        assert!(
            s.wo.is_finite() && (s.wo.length() - 1.0).abs() < 1e-3,
            "{}",
            ctx()
        );
        assert!(
            finite_spectrum(s.weight) && s.weight.min_element() >= 0.0,
            "{}",
            ctx()
        );
        assert!(s.pdf.is_finite() && s.pdf > 0.0, "{}", ctx());
        assert!(s.eta.is_finite() && s.eta > 0.0, "{}", ctx());
        assert!(
            flags.contains(s.lobe) && s.lobe != LobeFlags::NONE,
            "{}",
            ctx()
        );
        let refracted = s.wo.z * wi.z < 0.0;
        assert_eq!(
            s.lobe.intersects(LobeFlags::TRANSMISSION),
            refracted,
            "{}",
            ctx()
        );
        if s.lobe.is_delta() {
            if !flags.has_smooth() {
                assert_eq!(b.eval(&SP, wi, s.wo), Spectrum::ZERO, "{}", ctx());
                assert_eq!(b.pdf(&SP, wi, s.wo), 0.0, "{}", ctx());
            }
            return;
        }
        let pdf = b.pdf(&SP, wi, s.wo);
        let f = b.eval(&SP, wi, s.wo);
        // eval_pdf (which some models compute in one pass) is eval and pdf bit for bit, at
        // the sampled direction and at its mirror image through the surface.
        for wo in [s.wo, Vec3::new(s.wo.x, s.wo.y, -s.wo.z)] {
            let (fe, pe) = b.eval_pdf(&SP, wi, wo);
            let (fs, ps) = (b.eval(&SP, wi, wo), b.pdf(&SP, wi, wo));
            assert!(
                fe.to_array().map(f32::to_bits) == fs.to_array().map(f32::to_bits)
                    && pe.to_bits() == ps.to_bits(),
                "{}: eval_pdf at {wo} gives ({fe}, {pe}), eval and pdf ({fs}, {ps})",
                ctx()
            );
        }
        let w = f / pdf;
        let scale = w.max_element().max(s.weight.max_element());
        let agree = |rel: f32| {
            close(s.pdf, pdf, rel, 0.0)
                && (0..3).all(|c| close(s.weight[c], w[c], rel, 1e-6 * scale + 1e-7))
        };
        checked += 1;
        if !agree(rel) {
            assert!(agree(0.1), "{}: pdf() {pdf}, eval/pdf {w}", ctx());
            outliers += 1;
        }
    });
    assert!(
        outliers * 500 <= checked,
        "{what}: wi {wi}: {outliers} of {checked} samples disagree with pdf()/eval() by more than {rel}"
    );
}

/// f(wi, wo)/|cos θo| = f(wo, wi)/|cos θi| for `n` pairs of directions in the upper
/// hemisphere (cos θ ≥ 0.02): half drawn uniformly, half by sampling the model from wi (so
/// that narrow lobes are exercised too). With `lower`, wo is mirrored below the surface.
#[track_caller]
pub fn check_reciprocity(what: &str, b: &Bsdf, n: usize, lower: bool) {
    let mut rng = Pcg32::seed_from_u64(17);
    let mut checked = 0;
    for i in 0..n {
        let wi = dir(rng.random_range(0.02..1.0), rng.random_range(0.0..6.283));
        let mut wo = dir(rng.random_range(0.02..1.0), rng.random_range(0.0..6.283));
        if i % 2 == 1 {
            let u = Vec2::new(rng.random(), rng.random());
            match b.sample(&SP, wi, rng.random(), u) {
                Some(s) if !s.lobe.is_delta() && s.wo.z.abs() >= 0.02 => wo = s.wo,
                _ => continue,
            }
        }
        wo.z = if lower { -wo.z.abs() } else { wo.z.abs() };
        let a = b.eval(&SP, wi, wo) / wo.z.abs();
        let c = b.eval(&SP, wo, wi) / wi.z.abs();
        for k in 0..3 {
            assert!(
                close(a[k], c[k], 2e-3, 1e-6),
                "{what}: f(wi, wo) {a} != f(wo, wi) {c} for wi {wi}, wo {wo}"
            );
        }
        checked += (a != Spectrum::ZERO) as usize;
    }
    assert!(checked > n / 10, "{what}: only {checked} nonzero pairs");
}

/// Directional "energy" albedo by the model's sampling: the mean of weight·η² over `n`
/// samples (η² undoes the radiance scaling of refraction, so this is the fraction of energy
/// scattered, ≤ 1), with its standard error, per channel.
pub fn albedo_sampled(b: &Bsdf, wi: Vec3, n: usize) -> (Spectrum, Spectrum) {
    let mut sum = glam::DVec3::ZERO;
    let mut sum2 = glam::DVec3::ZERO;
    for_each_sample(n, 0xa1bed0 ^ n as u64, |u, u1| {
        if let Some(s) = b.sample(&SP, wi, u1, u) {
            let w = (s.weight * (s.eta * s.eta)).as_dvec3();
            sum += w;
            sum2 += w * w;
        }
    });
    let mean = sum / n as f64;
    let var = (sum2 / n as f64 - mean * mean).max(glam::DVec3::ZERO);
    (mean.as_vec3(), (var / n as f64).map(f64::sqrt).as_vec3())
}

/// Directional albedo ∫ eval dω of the smooth lobes by uniform sampling of the sphere:
/// independent of the model's sampling routine and pdf. With radiance scaling undone for
/// transmission when `eta_rel` (η of the side `wi` is on, relative) is given.
pub fn albedo_uniform(b: &Bsdf, wi: Vec3, n: usize) -> (Spectrum, Spectrum) {
    let mut sum = glam::DVec3::ZERO;
    let mut sum2 = glam::DVec3::ZERO;
    let inv_pdf = 4.0 * std::f64::consts::PI;
    for_each_sample(n, 0x5ca1ab1e ^ n as u64, |u, _| {
        let wo = radia_sampling::warp::square_to_uniform_sphere(u);
        let w = b.eval(&SP, wi, wo).as_dvec3() * inv_pdf;
        sum += w;
        sum2 += w * w;
    });
    let mean = sum / n as f64;
    let var = (sum2 / n as f64 - mean * mean).max(glam::DVec3::ZERO);
    (mean.as_vec3(), (var / n as f64).map(f64::sqrt).as_vec3())
}

/// Energy conservation: the sampled energy albedo is ≤ 1 up to 4 standard errors plus 10⁻³.
#[track_caller]
pub fn assert_albedo_at_most_one(what: &str, b: &Bsdf, wi: Vec3, n: usize) -> Spectrum {
    let (a, e) = albedo_sampled(b, wi, n);
    for c in 0..3 {
        assert!(
            a[c] <= 1.0 + 4.0 * e[c] + 1e-3,
            "{what}: albedo {a} ± {e} > 1 at wi {wi}"
        );
    }
    a
}

/// The smooth-lobe albedo by the model's sampling equals that by uniform sampling of
/// the sphere (within 4.5 combined standard errors + `abs`): sampling covers the whole
/// support of eval and weights are unbiased. Only for lobes broad enough for uniform
/// sampling to converge.
#[track_caller]
pub fn assert_albedo_unbiased(what: &str, b: &Bsdf, wi: Vec3, n: usize, abs: f32) {
    // Smooth part only: delta samples contribute nothing to the uniform estimate.
    let mut sum = glam::DVec3::ZERO;
    let mut sum2 = glam::DVec3::ZERO;
    for_each_sample(n, 0x0dd ^ n as u64, |u, u1| {
        if let Some(s) = b.sample(&SP, wi, u1, u) {
            if !s.lobe.is_delta() {
                let w = s.weight.as_dvec3();
                sum += w;
                sum2 += w * w;
            }
        }
    });
    let mean = sum / n as f64;
    let err = ((sum2 / n as f64 - mean * mean).max(glam::DVec3::ZERO) / n as f64).map(f64::sqrt);
    let (u, ue) = albedo_uniform(b, wi, n);
    for c in 0..3 {
        let tol = 4.5 * (err[c] * err[c] + (ue[c] as f64).powi(2)).sqrt() + abs as f64;
        assert!(
            (mean[c] - u[c] as f64).abs() <= tol,
            "{what}: sampled albedo {mean} ± {err} vs uniform {u} ± {ue} at wi {wi}"
        );
    }
}

/// No NaN or infinity: `eval`, `pdf` and `sample` at the given directions return finite
/// values (eval ≥ 0, pdf ≥ 0), and samples are finite unit vectors.
#[track_caller]
pub fn check_finite(what: &str, b: &Bsdf, wi: Vec3, wo: Vec3, u1: f32, u2: Vec2) {
    let f = b.eval(&SP, wi, wo);
    assert!(
        f.is_finite() && f.min_element() >= 0.0,
        "{what}: eval({wi}, {wo}) = {f}\n{b:?}"
    );
    let p = b.pdf(&SP, wi, wo);
    assert!(
        p.is_finite() && p >= 0.0,
        "{what}: pdf({wi}, {wo}) = {p}\n{b:?}"
    );
    if let Some(s) = b.sample(&SP, wi, u1, u2) {
        assert!(
            s.wo.is_finite()
                && (s.wo.length() - 1.0).abs() < 1e-3
                && s.weight.is_finite()
                && s.weight.min_element() >= 0.0
                && s.pdf.is_finite()
                && s.pdf > 0.0
                && s.eta.is_finite()
                && s.eta > 0.0,
            "{what}: sample({wi}, {u1}, {u2}) = {s:?}\n{b:?}"
        );
    }
}

/// Incident directions for the standard battery: normal, oblique and grazing (cos θ = 0.01),
/// at an azimuth that is not axis-aligned (anisotropic models), and from below the surface
/// when `both_sides`.
pub fn incident_directions(both_sides: bool) -> Vec<Vec3> {
    let mut v: Vec<Vec3> = [1.0f32, 0.7, 0.3, 0.01]
        .iter()
        .map(|&c| dir(c, 0.4))
        .collect();
    if both_sides {
        v.extend([-0.8f32, -0.2, -0.01].iter().map(|&c| dir(c, 2.1)));
    }
    v
}
