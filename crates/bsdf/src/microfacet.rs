//! Beckmann and GGX (Trowbridge–Reitz) microfacet distributions with Smith masking and
//! visible-normal sampling, after Mitsuba 3's `include/mitsuba/render/microfacet.h`:
//!
//! * B. Walter, S. Marschner, H. Li, K. Torrance, "Microfacet Models for Refraction through
//!   Rough Surfaces", EGSR 2007 (D, the separable Smith G, the rational Beckmann G1);
//! * E. Heitz, E. d'Eon, "Importance Sampling Microfacet-Based BSDFs using the Distribution
//!   of Visible Normals", EGSR 2014;
//! * W. Jakob, "An Improved Visible Normal Sampling Routine for the Beckmann Distribution",
//!   2014 (the numerical inversion below);
//! * E. Heitz, "Sampling the GGX Distribution of Visible Normals", JCGT 2018.
//!
//! Roughness `alpha` is used as given (no remapping), clamped to ≥ 10⁻⁴ as Mitsuba does.
//! All vectors are in the local frame; `m` is a microfacet normal.
//!
//! Written once over [`Real`] ([`MicrofacetDistributionR`], whose α may differ lane by lane
//! where a texture gives it): [`MicrofacetDistribution`]'s methods are its `f32`
//! instantiation. Early returns are masks and selects, so every lane computes the whole
//! formula (a Beckmann G1 at a back-facing normal is computed, then replaced by 0), unless
//! no lane needs it: then the costly ones return early, a branch for one path as before.

use crate::ShadingPointR;
use glam::{Vec2, Vec3};
use radia_math::lanes::f32x16;
use radia_math::real::{select_lazy, select_or_branch, Mask, Real, Vector2, Vector3};
use radia_math::{trig, PI};
use radia_sampling::warp;

/// Which normal distribution.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MicrofacetType {
    /// Gaussian random surfaces; Mitsuba's default.
    Beckmann,
    /// Trowbridge–Reitz / GGX: longer tails.
    Ggx,
}

/// How the masking-shadowing of both directions combines.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Shadowing {
    /// G1(wi)·G1(wo), as Mitsuba's `MicrofacetDistribution::G`.
    #[default]
    Separable,
    /// 1/(1 + Λ(wi) + Λ(wo)) (Heitz 2014, "Understanding the Masking-Shadowing Function in
    /// Microfacet-Based BRDFs", eq. 99): accounts for the correlation of heights, slightly
    /// brighter at grazing angles. A radia extension.
    HeightCorrelated,
}

/// A microfacet normal distribution with its roughness and sampling strategy.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MicrofacetDistribution {
    pub kind: MicrofacetType,
    /// Roughness along the tangent s (local x).
    pub alpha_u: f32,
    /// Roughness along the bitangent t (local y).
    pub alpha_v: f32,
    /// Sample the distribution of normals visible from `wi` (Mitsuba's `sample_visible`,
    /// default true) rather than D(m) cos θ_m.
    pub sample_visible: bool,
}

/// [`MicrofacetDistribution`] over a [`Real`]: α per lane (a texture's lookups, or the same
/// constant in every lane); the kind and the sampling strategy are the material's.
#[derive(Clone, Copy, Debug)]
pub struct MicrofacetDistributionR<R> {
    pub kind: MicrofacetType,
    pub alpha_u: R,
    pub alpha_v: R,
    pub sample_visible: bool,
}

/// Roughness given as textures (Mitsuba's `alpha`, or `alpha_u` and `alpha_v`, bound to a
/// texture): the distribution at a shading point takes α_u and α_v from their `eval_1`,
/// as `roughconductor.cpp` and `roughdielectric.cpp` build one per lookup.
#[derive(Clone, Debug)]
pub struct RoughnessTextures {
    pub alpha_u: crate::Texture,
    pub alpha_v: crate::Texture,
}

/// Mitsuba clamps roughness to this (`MicrofacetDistribution::configure`).
pub const MIN_ALPHA: f32 = 1e-4;

impl MicrofacetDistribution {
    pub fn new(kind: MicrofacetType, alpha_u: f32, alpha_v: f32, sample_visible: bool) -> Self {
        Self {
            kind,
            alpha_u: alpha_u.max(MIN_ALPHA),
            alpha_v: alpha_v.max(MIN_ALPHA),
            sample_visible,
        }
    }

    /// This distribution in every lane of a [`Real`].
    #[inline(always)]
    pub fn splat<R: Real>(&self) -> MicrofacetDistributionR<R> {
        MicrofacetDistributionR {
            kind: self.kind,
            alpha_u: R::splat(self.alpha_u),
            alpha_v: R::splat(self.alpha_v),
            sample_visible: self.sample_visible,
        }
    }

    /// One path's distribution over `f32`, what the methods below call.
    #[inline(always)]
    fn r(&self) -> MicrofacetDistributionR<f32> {
        self.splat()
    }

    /// This distribution, or with α looked up in `textures` at `sp` (kind and sampling
    /// strategy kept, α clamped as [`MicrofacetDistribution::new`] does). Without textures
    /// it is a copy: the constant path costs one branch.
    #[inline]
    pub fn at(&self, textures: &Option<Box<RoughnessTextures>>, sp: &crate::ShadingPoint) -> Self {
        let d = self.at_r::<f32>(textures, &sp.into());
        Self {
            alpha_u: d.alpha_u,
            alpha_v: d.alpha_v,
            ..*self
        }
    }

    /// [`MicrofacetDistribution::at`] over any [`Real`]: textured α looked up lane by lane.
    #[inline(always)]
    pub fn at_r<R: Real>(
        &self,
        textures: &Option<Box<RoughnessTextures>>,
        sp: &ShadingPointR<R>,
    ) -> MicrofacetDistributionR<R> {
        match textures {
            None => self.splat(),
            Some(t) => MicrofacetDistributionR {
                alpha_u: t.alpha_u.eval_1_r(sp).max(R::splat(MIN_ALPHA)),
                alpha_v: t.alpha_v.eval_1_r(sp).max(R::splat(MIN_ALPHA)),
                ..self.splat()
            },
        }
    }

    pub fn is_isotropic(&self) -> bool {
        self.alpha_u == self.alpha_v
    }

    /// The same distribution with both roughnesses multiplied by `s` (Mitsuba's `scale_alpha`).
    pub fn scaled(&self, s: f32) -> Self {
        let d = self.r().scaled(s);
        Self {
            alpha_u: d.alpha_u,
            alpha_v: d.alpha_v,
            ..*self
        }
    }

    /// D(m): microfacet area per unit projected area and solid angle of normals.
    #[inline]
    pub fn eval(&self, m: Vec3) -> f32 {
        self.r().eval(m.into())
    }

    /// Density (per solid angle of `m`) with which [`Self::sample`] returns `m`.
    #[inline]
    pub fn pdf(&self, wi: Vec3, m: Vec3) -> f32 {
        self.r().pdf(wi.into(), m.into())
    }

    /// [`Self::pdf`] given D(m) = `d` (`self.eval(m)`), for callers that evaluated it already.
    #[inline]
    pub fn pdf_given(&self, d: f32, wi: Vec3, m: Vec3) -> f32 {
        self.r().pdf_given(d, wi.into(), m.into())
    }

    /// The G1 that normalizes the distribution of visible normals (see
    /// [`MicrofacetDistributionR::visible_g1`]).
    #[inline]
    pub fn visible_g1(&self, v: Vec3, m: Vec3) -> f32 {
        self.r().visible_g1(v.into(), m.into())
    }

    /// Samples a microfacet normal (for `wi` on the upper side); returns it with its density.
    /// The density is 0 (and the normal possibly not finite) when sampling failed.
    #[inline]
    pub fn sample(&self, wi: Vec3, u: Vec2) -> (Vec3, f32) {
        let (m, pdf) = self.r().sample(wi.into(), u.into());
        (m.into(), pdf)
    }

    /// Calls `f(i, j, m)` with the normal `m` that [`Self::sample`] gives for
    /// `(xs[i], ys[j])`, for every pair, row by row: the grid of a quadrature over visible
    /// normals. The same normals bit for bit, but Beckmann's visible slopes are separable
    /// (x from u.x by a Newton inversion, y Gaussian from u.y), so each is made once per
    /// coordinate instead of once per pair: the rough plastic's tables at load take 10⁶ such
    /// normals.
    pub fn visible_normals_grid(
        &self,
        wi: Vec3,
        xs: &[f32],
        ys: &[f32],
        mut f: impl FnMut(usize, usize, Vec3),
    ) {
        if !(self.sample_visible && self.kind == MicrofacetType::Beckmann) {
            // Sixteen normals of a row at once (each lane the scalar sample's bits), without
            // the densities that `sample` would make alongside: GGX's visible normals are
            // not separable.
            let d = self.splat::<f32x16>();
            let wi16 = Vector3::splat(wi);
            for (i, &x) in xs.iter().enumerate() {
                for (chunk, ys) in ys.chunks(16).enumerate() {
                    let y = f32x16::new(std::array::from_fn(|l| ys[l.min(ys.len() - 1)]));
                    let m = d.sample_normal(wi16, Vector2::new(f32x16::splat(x), y));
                    for l in 0..ys.len() {
                        f(
                            i,
                            16 * chunk + l,
                            Vec3::new(m.x.lane(l), m.y.lane(l), m.z.lane(l)),
                        );
                    }
                }
            }
            return;
        }
        let d = self.r();
        let wi_p = d.stretched(wi.into());
        let (sin_phi, cos_phi) = sincos_phi(wi_p);
        let slopes_y: Vec<f32> = ys.iter().map(|&y| beckmann_slope_y(y)).collect();
        for (i, &x) in xs.iter().enumerate() {
            let slope_x = beckmann_slope_x(wi_p.z, x);
            for (j, &slope_y) in slopes_y.iter().enumerate() {
                let (m, finite) = d.unstretch(sin_phi, cos_phi, Vector2::new(slope_x, slope_y));
                f(i, j, if finite { m.into() } else { Vec3::Z });
            }
        }
    }

    /// Smith's G1 (see [`MicrofacetDistributionR::smith_g1`]).
    #[inline]
    pub fn smith_g1(&self, v: Vec3, m: Vec3) -> f32 {
        self.r().smith_g1(v.into(), m.into())
    }

    /// Smith's Λ (see [`MicrofacetDistributionR::lambda`]).
    #[inline]
    pub fn lambda(&self, v: Vec3) -> f32 {
        self.r().lambda(v.into())
    }

    /// The masking-shadowing G(wi, wo, m) of the given form.
    #[inline]
    pub fn g(&self, wi: Vec3, wo: Vec3, m: Vec3, form: Shadowing) -> f32 {
        self.r().g(wi.into(), wo.into(), m.into(), form)
    }
}

impl<R: Real> MicrofacetDistributionR<R> {
    /// The same distribution with both roughnesses multiplied by `s` (Mitsuba's `scale_alpha`).
    #[inline(always)]
    pub fn scaled(&self, s: R) -> Self {
        Self {
            alpha_u: self.alpha_u * s,
            alpha_v: self.alpha_v * s,
            ..*self
        }
    }

    /// D(m): microfacet area per unit projected area and solid angle of normals.
    #[inline(always)]
    pub fn eval(&self, m: Vector3<R>) -> R {
        let (au, av) = (self.alpha_u, self.alpha_v);
        let cos2 = m.z * m.z;
        let x = m.x / au;
        let y = m.y / av;
        let pi = R::splat(PI);
        let d = match self.kind {
            MicrofacetType::Beckmann => {
                exp_neg(-(x * x + y * y) / cos2) / (pi * au * av * cos2 * cos2)
            }
            MicrofacetType::Ggx => {
                let t = x * x + y * y + cos2;
                R::one() / (pi * au * av * t * t)
            }
        };
        // As Mitsuba: drop tiny values and everything on the lower hemisphere (and NaN).
        R::select((d * m.z).greater(R::splat(1e-20)), d, R::zero())
    }

    /// Density (per solid angle of `m`) with which [`Self::sample`] returns `m`.
    #[inline(always)]
    pub fn pdf(&self, wi: Vector3<R>, m: Vector3<R>) -> R {
        self.pdf_given(self.eval(m), wi, m)
    }

    /// [`Self::pdf`] given D(m) = `d` (`self.eval(m)`), for callers that evaluated it already.
    #[inline(always)]
    pub fn pdf_given(&self, d: R, wi: Vector3<R>, m: Vector3<R>) -> R {
        if self.sample_visible {
            d * self.visible_g1(wi, m) * wi.dot(m).abs() / wi.z
        } else {
            d * m.z
        }
    }

    /// (α_u v.x)² + (α_v v.y)²: tan²θ of `v` times α² along its azimuth, times cos²θ.
    #[inline(always)]
    fn xy_alpha_2(&self, v: Vector3<R>) -> R {
        let (x, y) = (self.alpha_u * v.x, self.alpha_v * v.y);
        x * x + y * y
    }

    /// The G1 that normalizes the distribution of visible normals, D(m) G1(wi) (wi·m)/cos θi,
    /// which [`Self::sample`] draws exactly: the exact Smith G1. For GGX that is
    /// [`Self::smith_g1`]; for Beckmann it is 2/(1 + erf(a) + e^(−a²)/(a√π)), where Mitsuba
    /// uses the rational approximation (up to 0.35% off) in its pdf too, so that its pdf and
    /// its sampler disagree by as much. radia evaluates the BSDF with Mitsuba's G (the same
    /// values) but its pdf and sample weights with this one: sampling stays exact.
    #[inline(always)]
    pub fn visible_g1(&self, v: Vector3<R>, m: Vector3<R>) -> R {
        match self.kind {
            MicrofacetType::Ggx => self.smith_g1(v, m),
            MicrofacetType::Beckmann => {
                let back = back_facing(v, m);
                if back.all() {
                    return R::zero();
                }
                let xy_alpha_2 = self.xy_alpha_2(v);
                let a = v.z.abs() / xy_alpha_2.sqrt();
                const SQRT_PI: f32 = 1.772_453_9;
                let two = R::splat(2.0);
                let g1 = two / (R::one() + erf(a) + exp_neg(-a * a) / (a * R::splat(SQRT_PI)));
                let g1 = R::select(xy_alpha_2.equals(R::zero()), R::one(), g1);
                R::select(back, R::zero(), g1)
            }
        }
    }

    /// Samples a microfacet normal (for `wi` on the upper side); returns it with its density.
    /// The density is 0 (and the normal possibly not finite) when sampling failed.
    #[inline(always)]
    pub fn sample(&self, wi: Vector3<R>, u: Vector2<R>) -> (Vector3<R>, R) {
        if self.sample_visible {
            self.sample_visible_normal(wi, u)
        } else {
            self.sample_all_normals(u)
        }
    }

    /// The normal [`Self::sample`] draws, without its density.
    #[inline(always)]
    pub fn sample_normal(&self, wi: Vector3<R>, u: Vector2<R>) -> Vector3<R> {
        if self.sample_visible {
            let (m, finite) = self.visible_normal(wi, u);
            select_or_branch(finite, || m, || Vector3::splat(Vec3::Z))
        } else {
            self.sample_all_normals(u).0
        }
    }

    /// D(m) cos θ_m sampling (Walter et al. 2007), isotropic or anisotropic.
    #[inline(always)]
    fn sample_all_normals(&self, u: Vector2<R>) -> (Vector3<R>, R) {
        let (au, av) = (self.alpha_u, self.alpha_v);
        let (s, c) = trig::sin_cos_turns(u.y);
        let (sin_phi, cos_phi, alpha_2) = select_lazy(
            au.equals(av),
            || (s, c, au * au),
            || {
                // The azimuth of an elliptical distribution, tan φ' = (αv/αu) tan 2πu in the
                // quadrant of 2πu: the direction of (αu cos 2πu, αv sin 2πu). (Mitsuba takes
                // tan 2πu and restores the quadrant; this form has no pole at a quarter turn.)
                let (x, y) = (au * c, av * s);
                let inv = R::one() / (x * x + y * y).sqrt();
                let (cos_phi, sin_phi) = (x * inv, y * inv);
                let (cu, sv) = (cos_phi / au, sin_phi / av);
                (sin_phi, cos_phi, R::one() / (cu * cu + sv * sv))
            },
        );
        let one = R::one();
        let pi_au_av = R::splat(PI) * au * av;
        let (cos_theta, pdf) = match self.kind {
            MicrofacetType::Beckmann => {
                let cos_theta = one / (one - alpha_2 * (one - u.x).ln()).sqrt();
                let cos3 = (cos_theta * cos_theta * cos_theta).max(R::splat(1e-20));
                (cos_theta, (one - u.x) / (pi_au_av * cos3))
            }
            MicrofacetType::Ggx => {
                let tan2 = alpha_2 * u.x / (one - u.x);
                let cos_theta = one / (one + tan2).sqrt();
                let temp = one + tan2 / alpha_2;
                let cos3 = (cos_theta * cos_theta * cos_theta).max(R::splat(1e-20));
                (cos_theta, one / (pi_au_av * cos3 * temp * temp))
            }
        };
        let sin_theta = (one - cos_theta * cos_theta).safe_sqrt();
        (
            Vector3::new(cos_phi * sin_theta, sin_phi * sin_theta, cos_theta),
            pdf,
        )
    }

    /// `v` stretched to the α = 1 configuration: normalize(α_u x, α_v y, z).
    #[inline(always)]
    fn stretched(&self, v: Vector3<R>) -> Vector3<R> {
        Vector3::new(self.alpha_u * v.x, self.alpha_v * v.y, v.z).normalize()
    }

    /// Visible normals (Heitz and d'Eon 2014): stretch wi to the α = 1 configuration,
    /// sample slopes there, rotate and unstretch.
    #[inline(always)]
    fn sample_visible_normal(&self, wi: Vector3<R>, u: Vector2<R>) -> (Vector3<R>, R) {
        let (m, finite) = self.visible_normal(wi, u);
        // Almost always finite: for one path a branch, not a select on the chain to D(m).
        let m = select_or_branch(finite, || m, || Vector3::splat(Vec3::Z));
        let pdf = self.eval(m) * self.visible_g1(wi, m) * wi.dot(m).abs() / wi.z;
        (m, select_or_branch(finite, || pdf, R::zero))
    }

    /// The visible normal of [`Self::sample_visible_normal`], and where it is finite.
    #[inline(always)]
    fn visible_normal(&self, wi: Vector3<R>, u: Vector2<R>) -> (Vector3<R>, R::Mask) {
        let wi_p = self.stretched(wi);
        let (sin_phi, cos_phi) = sincos_phi(wi_p);
        let slope = self.sample_visible_11(wi_p.z, u);
        self.unstretch(sin_phi, cos_phi, slope)
    }

    /// The normal of the α = 1 slopes `slope`, rotated to wi's azimuth (φ given by its sine
    /// and cosine) and unstretched, and where it is finite.
    #[inline(always)]
    fn unstretch(&self, sin_phi: R, cos_phi: R, slope: Vector2<R>) -> (Vector3<R>, R::Mask) {
        let sx = (cos_phi * slope.x - sin_phi * slope.y) * self.alpha_u;
        let sy = (sin_phi * slope.x + cos_phi * slope.y) * self.alpha_v;
        let m = Vector3::new(-sx, -sy, R::one()).normalize();
        (m, m.is_finite())
    }

    /// Slopes of the visible normals of the α = 1 distribution seen under cos θ_i.
    #[inline(always)]
    fn sample_visible_11(&self, cos_theta_i: R, u: Vector2<R>) -> Vector2<R> {
        match self.kind {
            MicrofacetType::Beckmann => {
                Vector2::new(beckmann_slope_x(cos_theta_i, u.x), beckmann_slope_y(u.y))
            }
            MicrofacetType::Ggx => {
                // Heitz 2018: a disk sample projected onto the visible half of the
                // hemisphere as seen from wi, as Mitsuba's GGX branch.
                let one = R::one();
                let p = warp::square_to_uniform_disk_concentric_r(u);
                let s = R::splat(0.5) * (one + cos_theta_i);
                let (x, y) = (p.x, (one - s) * (one - p.x * p.x).safe_sqrt() + s * p.y);
                let z = (one - x * x - y * y).safe_sqrt();
                let sin_theta_i = (one - cos_theta_i * cos_theta_i).safe_sqrt();
                let norm = one / (sin_theta_i * y + cos_theta_i * z);
                Vector2::new((cos_theta_i * y - sin_theta_i * z) * norm, x * norm)
            }
        }
    }

    /// Smith's G1 for direction `v` and microfacet normal `m` (Mitsuba's `smith_g1`:
    /// the exact GGX form, Walter's rational approximation for Beckmann), 0 when `v` sees
    /// the back of the microfacet.
    #[inline(always)]
    pub fn smith_g1(&self, v: Vector3<R>, m: Vector3<R>) -> R {
        let back = back_facing(v, m);
        if back.all() {
            return R::zero();
        }
        let xy_alpha_2 = self.xy_alpha_2(v);
        let tan_theta_alpha_2 = xy_alpha_2 / (v.z * v.z);
        let one = R::one();
        let g1 = match self.kind {
            MicrofacetType::Beckmann => {
                let a = one / tan_theta_alpha_2.sqrt();
                let k = R::splat;
                let g1 =
                    (k(3.535) * a + k(2.181) * a * a) / (one + k(2.276) * a + k(2.577) * a * a);
                R::select(a.greater_eq(k(1.6)), one, g1)
            }
            MicrofacetType::Ggx => R::splat(2.0) / (one + (one + tan_theta_alpha_2).sqrt()),
        };
        let g1 = R::select(xy_alpha_2.equals(R::zero()), one, g1);
        R::select(back, R::zero(), g1)
    }

    /// Smith's Λ(v) with G1 = 1/(1 + Λ), for the height-correlated form. For Beckmann it is
    /// the Λ of the same rational approximation, (1 − 1.259a + 0.396a²)/(3.535a + 2.181a²)
    /// (Walter et al. 2007, eq. 27), so both forms agree for one direction.
    #[inline(always)]
    pub fn lambda(&self, v: Vector3<R>) -> R {
        let xy_alpha_2 = self.xy_alpha_2(v);
        let tan_theta_alpha_2 = xy_alpha_2 / (v.z * v.z);
        let (zero, one) = (R::zero(), R::one());
        let lambda = match self.kind {
            MicrofacetType::Beckmann => {
                let a = one / tan_theta_alpha_2.sqrt();
                let k = R::splat;
                let l = (one - k(1.259) * a + k(0.396) * a * a) / (k(3.535) * a + k(2.181) * a * a);
                R::select(a.greater_eq(k(1.6)), zero, l)
            }
            MicrofacetType::Ggx => R::splat(0.5) * ((one + tan_theta_alpha_2).sqrt() - one),
        };
        R::select(xy_alpha_2.equals(zero), zero, lambda)
    }

    /// The masking-shadowing G(wi, wo, m) of the given form.
    #[inline(always)]
    pub fn g(&self, wi: Vector3<R>, wo: Vector3<R>, m: Vector3<R>, form: Shadowing) -> R {
        match form {
            Shadowing::Separable => self.smith_g1(wi, m) * self.smith_g1(wo, m),
            Shadowing::HeightCorrelated => {
                let back = back_facing(wi, m) | back_facing(wo, m);
                if back.all() {
                    return R::zero();
                }
                let g = R::one() / (R::one() + self.lambda(wi) + self.lambda(wo));
                R::select(back, R::zero(), g)
            }
        }
    }
}

/// Whether `v` sees the back of the microfacet `m` (or is in the surface): (v·m) cos θ ≤ 0.
#[inline(always)]
fn back_facing<R: Real>(v: Vector3<R>, m: Vector3<R>) -> R::Mask {
    (v.dot(m) * v.z).less_eq(R::zero())
}

/// (sin φ, cos φ) of a direction, (0, 1) on the pole (Mitsuba's `Frame3f::sincos_phi`).
#[inline(always)]
fn sincos_phi<R: Real>(v: Vector3<R>) -> (R, R) {
    let sin2 = v.x * v.x + v.y * v.y;
    let inv = R::one() / sin2.sqrt();
    let (one, zero) = (R::one(), R::zero());
    select_or_branch(
        sin2.less_eq(R::splat(4.0 * f32::EPSILON)),
        || (zero, one),
        || ((v.y * inv).clamp(-one, one), (v.x * inv).clamp(-one, one)),
    )
}

/// The x slope of the visible normals of the α = 1 Beckmann distribution (Jakob 2014), as
/// Mitsuba's `sample_visible_11`: the visible-slope CDF inverted numerically in the erf
/// domain from an analytic initial guess with three Newton steps.
#[inline(always)]
fn beckmann_slope_x<R: Real>(cos_theta_i: R, u: R) -> R {
    const INV_SQRT_PI: f32 = 0.564_189_6;
    let (one, k) = (R::one(), R::splat);
    let tan_theta_i = (one - cos_theta_i * cos_theta_i).safe_sqrt() / cos_theta_i;
    let cot_theta_i = one / tan_theta_i;
    let tan_over_sqrt_pi = k(INV_SQRT_PI) * tan_theta_i;

    // Search interval: everything is parameterized in the erf() domain.
    let maxval = erf(cot_theta_i);
    let u = u.clamp(k(1e-6), k(1.0 - 1e-6));
    // Initial guess: the analytic solution for θ_i = π/2, the most nonlinear case.
    let mut x = maxval - (maxval + one) * erf((-u.ln()).sqrt());
    // Normalization of the CDF.
    let target = u * (one + maxval + tan_over_sqrt_pi * exp_neg(-cot_theta_i * cot_theta_i));
    for _ in 0..3 {
        let slope = erfinv(x);
        let value = one + x + tan_over_sqrt_pi * exp_neg(-slope * slope) - target;
        let derivative = one - slope * tan_theta_i;
        x -= value / derivative;
    }
    erfinv(x)
}

/// The y slope of the visible normals of the α = 1 Beckmann distribution: Gaussian.
#[inline(always)]
fn beckmann_slope_y<R: Real>(u: R) -> R {
    let k = R::splat;
    erfinv(k(2.0) * u.clamp(k(1e-6), k(1.0 - 1e-6)) - R::one())
}

/// e^x for the Gaussians' x ≤ 0: [`Real::exp`], which is `x.exp()` bit for bit (glibc's
/// algorithm without the call: libm's underflow path, setting `errno`, was 2% of
/// `scenes/veach-mis.xml`, where Beckmann sampling at near-normal incidence takes
/// e^(−cot²θ) with cot θ above 10).
#[inline(always)]
fn exp_neg<R: Real>(x: R) -> R {
    x.exp()
}

/// The error function: Abramowitz and Stegun's 7.1.26 (absolute error below 1.5·10⁻⁷).
#[inline(always)]
pub(crate) fn erf<R: Real>(x: R) -> R {
    let k = R::splat;
    let z = x.abs();
    let t = R::one() / (R::one() + k(0.327_591_1) * z);
    let poly = t
        * (k(0.254_829_6)
            + t * (k(-0.284_496_74)
                + t * (k(1.421_413_8) + t * (k(-1.453_152) + t * k(1.061_405_4)))));
    let y = R::one() - poly * exp_neg(-z * z);
    let y = R::select(x.less(R::zero()), -y, y);
    R::select(x.equals(x), y, x)
}

/// The inverse of the error function on (−1, 1): M. Giles' single-precision approximation
/// ("Approximating the erfinv function", GPU Computing Gems, 2011), relative error about
/// 3·10⁻⁷. Inputs are clamped into (−1, 1), so it saturates at about ±3.9 rather than
/// returning infinities; NaN gives 0.
#[inline(always)]
pub(crate) fn erfinv<R: Real>(y: R) -> R {
    let k = R::splat;
    let is_nan = !y.equals(y);
    let y = y.clamp(k(-1.0 + f32::EPSILON), k(1.0 - f32::EPSILON));
    let w = -((R::one() - y) * (R::one() + y)).ln();
    let horner = |w: R, c: &[f32]| c[1..].iter().fold(k(c[0]), |p, &c| k(c) + p * w);
    let p = select_lazy(
        w.less(k(5.0)),
        || {
            let c = [
                2.810_226_4e-08,
                3.432_739_4e-07,
                -3.523_387_7e-06,
                -4.391_506_5e-06,
                0.000_218_580_87,
                -0.001_253_725,
                -0.004_177_681_6,
                0.246_640_73,
                1.501_409_4,
            ];
            horner(w - k(2.5), &c)
        },
        || {
            let c = [
                -0.000_200_214_26,
                0.000_100_950_56,
                0.001_349_343_2,
                -0.003_673_428_4,
                0.005_739_507_7,
                -0.007_622_461,
                0.009_438_870_5,
                1.001_674_1,
                2.832_976_8,
            ];
            horner(w.sqrt() - k(3.0), &c)
        },
    );
    R::select(is_nan, R::zero(), p * y)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::*;
    use radia_sampling::chi2::{chi2_test, Chi2Config};

    #[test]
    fn exp_neg_is_exp_bit_for_bit() {
        // Every float from −120 to −80 (about 10⁶ of them), then a coarse sweep to 0.
        let mut x = -120.0f32;
        while x < -80.0 {
            assert_eq!(exp_neg(x).to_bits(), x.exp().to_bits(), "e^{x}");
            x = x.next_up();
        }
        for i in 0..=80_000 {
            let x = -(i as f32) * 1e-3;
            assert_eq!(exp_neg(x).to_bits(), x.exp().to_bits(), "e^{x}");
        }
        assert_eq!(exp_neg(f32::NEG_INFINITY), 0.0);
        assert!(exp_neg(f32::NAN).is_nan());
    }

    #[test]
    fn erf_and_erfinv() {
        // erf(0.5) = 0.5204998778, erf(1) = 0.8427007929, erf(2) = 0.9953222650.
        for (x, want) in [
            (0.5f32, 0.520_499_9f32),
            (1.0, 0.842_700_8),
            (2.0, 0.995_322_3),
        ] {
            assert!((erf(x) - want).abs() < 3e-7, "erf({x}) = {}", erf(x));
            assert!((erf(-x) + want).abs() < 3e-7);
        }
        assert_eq!(erf(f32::INFINITY), 1.0);
        assert_eq!(erf(f32::NEG_INFINITY), -1.0);
        // The pair agrees to the accuracy the sampler needs (it works in the erf domain).
        for i in -999..1000 {
            let y = i as f32 / 1000.0;
            let x = erfinv(y);
            assert!(
                (erf(x) - y).abs() < 1e-6,
                "erfinv({y}) = {x}: erf {}",
                erf(x)
            );
        }
        assert!(erfinv(1.0).is_finite() && erfinv(-1.0).is_finite());
    }

    fn dists() -> Vec<MicrofacetDistribution> {
        let mut v = Vec::new();
        for kind in [MicrofacetType::Beckmann, MicrofacetType::Ggx] {
            for (au, av) in [(0.1, 0.1), (0.5, 0.5), (1.0, 1.0), (0.15, 0.6)] {
                for vis in [true, false] {
                    v.push(MicrofacetDistribution::new(kind, au, av, vis));
                }
            }
        }
        v
    }

    /// ∫ D(m) cos θ_m dm = 1: the projected microfacet area is the macro-surface's.
    #[test]
    fn projected_area_is_one() {
        for d in dists() {
            if !d.sample_visible {
                continue;
            }
            let i = integrate_sphere(|m| (d.eval(m) * m.z.max(0.0)) as f64, 400, 800);
            assert!((i - 1.0).abs() < 2e-3, "{d:?}: {i}");
        }
    }

    /// The distribution of visible normals is normalized, for Beckmann only up to the
    /// accuracy of the rational G1 (0.35% per Mitsuba). This is the "weak white furnace"
    /// (Heitz 2014): ∫ D(h) G1(wi, h) / (4 cos θ_i) dωo = 1 over the whole sphere of wo.
    #[test]
    fn visible_normals_are_normalized() {
        for d in dists() {
            let tol = 3e-3;
            for cos_i in [1.0f32, 0.7, 0.2, 0.01] {
                let wi = Vec3::new((1.0 - cos_i * cos_i).sqrt(), 0.0, cos_i);
                let wi = rotate_z(wi, 0.7);
                let i = integrate_sphere(
                    |m| (d.eval(m) * d.visible_g1(wi, m) * wi.dot(m).max(0.0) / wi.z) as f64,
                    400,
                    800,
                );
                // With Mitsuba's rational G1 for Beckmann: within its 0.35%.
                let j = integrate_sphere(
                    |m| (d.eval(m) * d.smith_g1(wi, m) * wi.dot(m).max(0.0) / wi.z) as f64,
                    400,
                    800,
                );
                assert!((j - 1.0).abs() < 6e-3, "{d:?} cos_i {cos_i}: {j}");
                assert!((i - 1.0).abs() < tol, "{d:?} cos_i {cos_i}: {i}");
            }
        }
    }

    /// The weak white furnace as Heitz (2014, §4.2) states it, over outgoing directions:
    /// ∫ D(h) G1(wi, h) / (4 |cos θi|) dωo = 1 with h = normalize(wi + wo), wo over the
    /// whole sphere (the reflection model with F = 1 and G1 in place of G conserves energy
    /// exactly). Exact for GGX; for Beckmann within the 0.35% of Mitsuba's rational G1.
    #[test]
    fn weak_white_furnace() {
        for kind in [MicrofacetType::Ggx, MicrofacetType::Beckmann] {
            for a in [0.1f32, 0.5, 1.0] {
                let d = MicrofacetDistribution::new(kind, a, a, true);
                for cos_i in [1.0f32, 0.6, 0.2] {
                    let wi = Vec3::new((1.0 - cos_i * cos_i).sqrt(), 0.0, cos_i);
                    let i = integrate_sphere(
                        |wo| {
                            let h = (wi + wo).normalize();
                            (d.eval(h) * d.smith_g1(wi, h) / (4.0 * wi.z)) as f64
                        },
                        1000,
                        1000,
                    );
                    let tol = if kind == MicrofacetType::Ggx {
                        3e-3
                    } else {
                        6e-3
                    };
                    assert!((i - 1.0).abs() < tol, "{kind:?} α {a} cos θi {cos_i}: {i}");
                }
            }
        }
    }

    /// Chi-square test of the normal sampler against its pdf (both strategies, grazing
    /// incidence included).
    #[test]
    fn chi2_normal_sampling() {
        let cases: Vec<_> = dists()
            .into_iter()
            .flat_map(|d| [1.0f32, 0.5, 0.01].into_iter().map(move |c| (d, c)))
            .collect();
        let alpha = suite_alpha();
        for (d, cos_i) in cases {
            let wi = rotate_z(Vec3::new((1.0 - cos_i * cos_i).sqrt(), 0.0, cos_i), 0.3);
            let cfg = Chi2Config {
                sample_count: 150_000,
                alpha,
                theta_res: 51,
                phi_res: 100,
                cos_theta_min: 0.0,
                ..Default::default()
            };
            let r = chi2_test(
                &cfg,
                |u, _| {
                    let (m, pdf) = d.sample(wi, u);
                    (pdf > 0.0).then_some(m)
                },
                |m| d.pdf(wi, m) as f64,
            );
            assert!(r.passed, "{d:?} cos_i {cos_i}\n{}", r.report);
        }
    }

    #[test]
    fn sampled_pdf_matches_pdf() {
        for d in dists() {
            for cos_i in [1.0f32, 0.3, 0.01] {
                let wi = Vec3::new((1.0 - cos_i * cos_i).sqrt(), 0.0, cos_i);
                for_each_sample(20_000, 7, |u, _| {
                    let (m, pdf) = d.sample(wi, u);
                    if pdf > 0.0 {
                        let p = d.pdf(wi, m);
                        assert!((pdf - p).abs() <= 1e-3 * p + 1e-6, "{d:?}: {pdf} vs {p}");
                        assert!((m.length() - 1.0).abs() < 1e-4);
                    }
                });
            }
        }
    }

    #[test]
    fn height_correlated_is_between_separable_and_min() {
        let d = MicrofacetDistribution::new(MicrofacetType::Ggx, 0.5, 0.5, true);
        let wi = Vec3::new(0.8, 0.0, 0.6);
        let wo = Vec3::new(-0.6, 0.1, 0.7937254).normalize();
        let m = (wi + wo).normalize();
        let sep = d.g(wi, wo, m, Shadowing::Separable);
        let hc = d.g(wi, wo, m, Shadowing::HeightCorrelated);
        let g1 = d.smith_g1(wi, m).min(d.smith_g1(wo, m));
        assert!(sep < hc && hc <= g1, "{sep} {hc} {g1}");
        // With one direction at normal incidence both forms are G1 of the other.
        let hc = d.g(
            Vec3::Z,
            wo,
            (Vec3::Z + wo).normalize(),
            Shadowing::HeightCorrelated,
        );
        assert!((hc - d.smith_g1(wo, (Vec3::Z + wo).normalize())).abs() < 1e-6);
    }

    #[test]
    fn the_grid_of_visible_normals_is_the_samples_bit_for_bit() {
        // 37 columns: two chunks of sixteen lanes and a remainder; values at 0 and near 1.
        let xs: Vec<f32> = (0..13).map(|i| (i as f32 / 12.0).min(0.999_999)).collect();
        let ys: Vec<f32> = (0..37).map(|j| (j as f32 / 36.0).min(0.999_999)).collect();
        let mut checked = 0;
        for kind in [MicrofacetType::Beckmann, MicrofacetType::Ggx] {
            for visible in [true, false] {
                for (au, av) in [
                    (1e-4, 1e-4),
                    (0.05, 0.05),
                    (0.3, 0.3),
                    (1.0, 1.0),
                    (0.1, 0.6),
                ] {
                    let d = MicrofacetDistribution::new(kind, au, av, visible);
                    for wi in [
                        Vec3::Z,
                        Vec3::new(0.6, 0.0, 0.8),
                        Vec3::new(0.3, -0.5, 0.2).normalize(),
                        Vec3::new(1.0, 0.0, 1e-4).normalize(),
                    ] {
                        d.visible_normals_grid(wi, &xs, &ys, |i, j, m| {
                            let want = d.sample(wi, Vec2::new(xs[i], ys[j])).0;
                            assert_eq!(
                                m.to_array().map(f32::to_bits),
                                want.to_array().map(f32::to_bits),
                                "{kind:?} visible {visible} α ({au}, {av}) wi {wi} at ({i}, {j})"
                            );
                            checked += 1;
                        });
                    }
                }
            }
        }
        assert_eq!(checked, 2 * 2 * 5 * 4 * xs.len() * ys.len());
    }
}
