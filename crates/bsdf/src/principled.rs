//! The Disney principled BSDF: Mitsuba 3.9.1's `principled` plugin
//! (`src/bsdfs/principled.cpp`, helpers in `principledhelpers.h`), what Mitsuba's Blender
//! add-on exports for Blender's Principled BSDF. This follows Mitsuba's code term by term.
//!
//! ```xml
//! <bsdf type="principled">
//!     <rgb name="base_color" value="0.8, 0.2, 0.1"/>  <!-- default 0.5 -->
//!     <float name="roughness" value="0.3"/>           <!-- default 0.5 -->
//!     <float name="metallic" value="0.0"/>            <!-- every weight: default 0 -->
//!     <float name="spec_trans" value="0.0"/>
//!     <float name="specular" value="0.5"/>            <!-- or eta (not both); η = 1.5 -->
//!     <float name="anisotropic" value="0.0"/>
//!     <float name="spec_tint" value="0.0"/>
//!     <float name="sheen" value="0.0"/> <float name="sheen_tint" value="0.0"/>
//!     <float name="clearcoat" value="0.0"/> <float name="clearcoat_gloss" value="0.0"/>
//!     <float name="flatness" value="0.0"/>
//! </bsdf>
//! ```
//!
//! With brdf = (1 − metallic)(1 − spec_trans) and bsdf = (1 − metallic) spec_trans, and h
//! the (generalized) half vector turned to the upper side, f·cos θo is the sum of
//!
//! * the main specular reflection F_p D G / (4 |cos θi|): GGX with α from roughness² and
//!   anisotropy, separable Smith G; F_p is [`principled_fresnel`]: from the front
//!   (1 − m)(1 − spec_tint) F_dielectric(wi·h) + m Schlick(base_color) + (1 − m) spec_tint
//!   Schlick(tint F0), from the back bsdf · F_dielectric;
//! * the specular transmission √base_color · bsdf · (roughdielectric's refraction term,
//!   radiance mode), from either side;
//! * the clearcoat 0.25 clearcoat · Schlick(0.04) · GTR1(h) · G_GGX(α 0.25) · |cos θo| (as
//!   Mitsuba writes it: without the 1/(4 cos θi cos θo) of Burley's specular form), front
//!   only;
//! * the diffuse brdf · base_color/π · (f_diff + f_retro) |cos θo| (lerped towards the fake
//!   subsurface term by `flatness`) and the sheen sheen (1 − m) Fd c_sheen |cos θo|, front
//!   only.
//!
//! Sampling picks the diffuse cosine lobe, the clearcoat (GTR1 normals), the specular
//! transmission or the specular reflection (both from one GGX visible normal) with Mitsuba's
//! probabilities: from the front proportional to brdf·diffuse_rate, 0.25·clearcoat·
//! clearcoat_rate, spec_rate·bsdf(1 − F) and spec_rate(1 − bsdf(1 − F)); from the back
//! (inside a transmissive object) 1 − F and F. The weight is eval/pdf of the whole mixture.
//!
//! Parameters Mitsuba reads but only to turn a lobe on (`get_flag`: present and not the
//! float 0) are `Option`s here: `None` is Mitsuba's `m_has_* = false`.
//!
//! Differences from Mitsuba 3.9.1, none visible in an image: from the back of a surface
//! without transmission (where eval is 0 and Mitsuba's `sample` returns nothing) `pdf` is 0
//! rather than Mitsuba's nonzero value, so that it is the density of `sample`. The sheen is
//! added wherever its own mask holds, as Mitsuba's JIT (`llvm`/`cuda`) variants do; the
//! scalar variants skip it when the diffuse lobe is off (spec_trans = 1, metallic < 1).
//!
//! Written once over [`Real`] (`eval_pdf_r`, `sample_r`) for one path or a packet's lanes:
//! the lobes are masks (a lane adds a lobe's term where its conditions hold; for one path
//! the `if` of the scalar code), the lobe u1 picks a select. The `has_*` flags are the
//! material's, tested once for all lanes.

use crate::fresnel::{fresnel_dielectric_r, reflect_about_r, refract_about_r};
use crate::microfacet::{MicrofacetDistributionR, MicrofacetType, Shadowing, MIN_ALPHA};
use crate::principled_helpers::{
    add_where, calc_dist_params, calc_schlick_1, clearcoat_g, mac_mic_compatible, mulsign, opt_1,
    principled_fresnel, schlick_weight, tint_color, Gtr1,
};
use crate::{BsdfSample, BsdfSampleR, LobeFlags, ShadingPoint, ShadingPointR, Texture};
use glam::{Vec2, Vec3};
use radia_math::real::{Mask, Real, Vector2, Vector3};
use radia_math::{luminance_r, Spectrum, INV_PI};
use radia_sampling::warp;

#[derive(Clone, Debug)]
pub struct Principled {
    pub base_color: Texture,
    pub roughness: Texture,
    /// `None`: the parameter is absent or the float 0 (Mitsuba's `m_has_*` false).
    pub anisotropic: Option<Texture>,
    pub metallic: Option<Texture>,
    pub spec_trans: Option<Texture>,
    pub spec_tint: Option<Texture>,
    pub sheen: Option<Texture>,
    pub sheen_tint: Option<Texture>,
    pub flatness: Option<Texture>,
    pub clearcoat: Option<Texture>,
    pub clearcoat_gloss: Texture,
    /// Relative IOR, interior over exterior (from `eta`, or from `specular`).
    pub eta: f32,
    /// `main_specular_sampling_rate`, `clearcoat_sampling_rate`,
    /// `diffuse_reflectance_sampling_rate` (default 1 each).
    pub spec_srate: f32,
    pub clearcoat_srate: f32,
    pub diff_refl_srate: f32,
}

/// How the IOR is given: Mitsuba's `eta`, or its `specular` (η = 2/(1 − √(0.08 s)) − 1).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum PrincipledIor {
    Eta(f32),
    Specular(f32),
}

/// Lobe selection probabilities (diffuse, clearcoat, transmission, reflection), normalized,
/// in the lanes of `ok` (where they do not sum to a positive finite number, no lobe).
struct LobeProbabilities<R: Real> {
    diffuse: R,
    clearcoat: R,
    spec_trans: R,
    spec_reflect: R,
    ok: R::Mask,
}

/// The lobe weights the sampling routine and the pdf need.
struct Weights<R> {
    metallic: R,
    anisotropic: R,
    roughness: R,
    clearcoat: R,
    brdf: R,
    bsdf: R,
}

/// What evaluating the model and its density at (wi, wo) share ([`Principled::pair`]), in
/// the lanes of `valid` (elsewhere both are zero: grazing wi, wo in the plane, no half
/// vector).
struct Pair<R: Real> {
    valid: R::Mask,
    w: Weights<R>,
    cos_i: R,
    cos_o: R,
    reflect: R::Mask,
    refract: R::Mask,
    front: R::Mask,
    /// η on the path's side: η from the front, 1/η from the back.
    eta_path: R,
    /// The half vector on the upper side.
    wh: Vector3<R>,
    dist: MicrofacetDistributionR<R>,
    dot_i: R,
    dot_o: R,
    /// The dielectric Fresnel reflectance at ωh.
    f: R,
}

/// A sample and the lobe it came from (the other lanes took a glossy reflection).
struct LobeSample<R: Real> {
    s: BsdfSampleR<R>,
    diffuse: R::Mask,
    transmission: R::Mask,
}

impl Principled {
    /// Mitsuba's defaults: base colour 0.5, roughness 0.5, specular 0.5 (η 1.5), every
    /// other weight absent, sampling rates 1.
    pub fn new(base_color: impl Into<Texture>) -> Self {
        Self {
            base_color: base_color.into(),
            roughness: 0.5.into(),
            anisotropic: None,
            metallic: None,
            spec_trans: None,
            spec_tint: None,
            sheen: None,
            sheen_tint: None,
            flatness: None,
            clearcoat: None,
            clearcoat_gloss: 0.0.into(),
            eta: 1.5,
            spec_srate: 1.0,
            clearcoat_srate: 1.0,
            diff_refl_srate: 1.0,
        }
    }

    /// Sets η as Mitsuba's constructor does: `eta` = 1 becomes 1.001 and `specular` = 0
    /// becomes 10⁻³ when the transmission lobe is on (an index-matched interface transmits
    /// nothing it could sample); call after setting `spec_trans`.
    pub fn with_ior(mut self, ior: PrincipledIor) -> Self {
        let st = self.spec_trans.is_some();
        self.eta = match ior {
            PrincipledIor::Eta(e) => {
                if st && e == 1.0 {
                    1.001
                } else {
                    e
                }
            }
            PrincipledIor::Specular(s) => {
                let s = if st && s == 0.0 { 1e-3 } else { s };
                2.0 / (1.0 - (0.08 * s).sqrt()) - 1.0
            }
        };
        self
    }

    pub fn flags(&self) -> LobeFlags {
        let f = LobeFlags::DIFFUSE_REFLECTION | LobeFlags::GLOSSY_REFLECTION;
        if self.spec_trans.is_some() {
            f | LobeFlags::GLOSSY_TRANSMISSION
        } else {
            f
        }
    }

    #[inline]
    pub fn eval(&self, sp: &ShadingPoint, wi: Vec3, wo: Vec3) -> Spectrum {
        self.eval_r(&sp.into(), wi.into(), wo.into()).into()
    }

    #[inline]
    pub fn pdf(&self, sp: &ShadingPoint, wi: Vec3, wo: Vec3) -> f32 {
        self.pdf_r(&sp.into(), wi.into(), wo.into())
    }

    /// [`Principled::eval`] and [`Principled::pdf`] at once: the weights' textures, the half
    /// vector, the Fresnel term and D(ωh) found once (next-event estimation asks for both at
    /// every vertex, where the two calls were a fifth of a render of
    /// `scenes/principled.xml`). The same values bit for bit.
    #[inline]
    pub fn eval_pdf(&self, sp: &ShadingPoint, wi: Vec3, wo: Vec3) -> (Spectrum, f32) {
        let (f, pdf) = self.eval_pdf_r(&sp.into(), wi.into(), wo.into());
        (f.into(), pdf)
    }

    #[inline]
    pub fn sample(&self, sp: &ShadingPoint, wi: Vec3, u1: f32, u2: Vec2) -> Option<BsdfSample> {
        let l = self.sample_lobe(&sp.into(), wi.into(), u1, u2.into());
        l.s.one_path(if l.diffuse {
            LobeFlags::DIFFUSE_REFLECTION
        } else if l.transmission {
            LobeFlags::GLOSSY_TRANSMISSION
        } else {
            LobeFlags::GLOSSY_REFLECTION
        })
    }

    /// eval over any [`Real`].
    #[inline(always)]
    pub fn eval_r<R: Real>(
        &self,
        sp: &ShadingPointR<R>,
        wi: Vector3<R>,
        wo: Vector3<R>,
    ) -> Vector3<R> {
        match self.pair(sp, wi, wo) {
            Some(q) => self.eval_pair(sp, wi, wo, &q, q.dist.eval(q.wh)),
            None => Vector3::zero(),
        }
    }

    /// pdf over any [`Real`].
    #[inline(always)]
    pub fn pdf_r<R: Real>(&self, sp: &ShadingPointR<R>, wi: Vector3<R>, wo: Vector3<R>) -> R {
        match self.pair(sp, wi, wo) {
            Some(q) => self.pdf_pair(sp, wi, wo, &q, q.dist.eval(q.wh)),
            None => R::zero(),
        }
    }

    /// eval and pdf over any [`Real`], sharing what they can.
    #[inline(always)]
    pub fn eval_pdf_r<R: Real>(
        &self,
        sp: &ShadingPointR<R>,
        wi: Vector3<R>,
        wo: Vector3<R>,
    ) -> (Vector3<R>, R) {
        let Some(q) = self.pair(sp, wi, wo) else {
            return (Vector3::zero(), R::zero());
        };
        let d = q.dist.eval(q.wh);
        (
            self.eval_pair(sp, wi, wo, &q, d),
            self.pdf_pair(sp, wi, wo, &q, d),
        )
    }

    /// sample over any [`Real`].
    #[inline(always)]
    pub fn sample_r<R: Real>(
        &self,
        sp: &ShadingPointR<R>,
        wi: Vector3<R>,
        u1: R,
        u2: Vector2<R>,
    ) -> BsdfSampleR<R> {
        self.sample_lobe(sp, wi, u1, u2).s
    }

    #[inline(always)]
    fn weights<R: Real>(&self, sp: &ShadingPointR<R>) -> Weights<R> {
        let one = R::one();
        let metallic = opt_1(&self.metallic, sp);
        let spec_trans = opt_1(&self.spec_trans, sp);
        Weights {
            metallic,
            anisotropic: opt_1(&self.anisotropic, sp),
            roughness: self.roughness.eval_1_r(sp),
            clearcoat: opt_1(&self.clearcoat, sp),
            brdf: (one - metallic) * (one - spec_trans),
            bsdf: (one - metallic) * spec_trans,
        }
    }

    /// The GGX distribution of the main specular lobes (α clamped as
    /// `MicrofacetDistribution::new` clamps it).
    #[inline(always)]
    fn distribution<R: Real>(&self, w: &Weights<R>) -> MicrofacetDistributionR<R> {
        let (ax, ay) = calc_dist_params(w.anisotropic, w.roughness, self.anisotropic.is_some());
        let min = R::splat(MIN_ALPHA);
        MicrofacetDistributionR {
            kind: MicrofacetType::Ggx,
            alpha_u: ax.max(min),
            alpha_v: ay.max(min),
            sample_visible: true,
        }
    }

    /// Mitsuba's lobe probabilities for a dielectric Fresnel `f` (at the sampled or the
    /// half-vector normal).
    #[inline(always)]
    fn probabilities<R: Real>(&self, w: &Weights<R>, front: R::Mask, f: R) -> LobeProbabilities<R> {
        let (zero, one, k) = (R::zero(), R::one(), R::splat);
        let has_st = self.spec_trans.is_some();
        let srate = k(self.spec_srate);
        // From the front.
        let sr = srate * (one - w.bsdf * (one - f));
        let st = if has_st {
            srate * w.bsdf * (one - f)
        } else {
            zero
        };
        let cc = if self.clearcoat.is_some() {
            k(0.25) * w.clearcoat * k(self.clearcoat_srate)
        } else {
            zero
        };
        let d = w.brdf * k(self.diff_refl_srate);
        // From the back.
        let (sr, st, cc, d) = (
            R::select(front, sr, f),
            R::select(front, st, if has_st { one - f } else { zero }),
            R::select(front, cc, zero),
            R::select(front, d, zero),
        );
        let total = sr + st + cc + d;
        let r = one / total;
        LobeProbabilities {
            diffuse: d * r,
            clearcoat: cc * r,
            spec_trans: st * r,
            spec_reflect: sr * r,
            ok: total.greater(zero) & total.is_finite(),
        }
    }

    /// The half vector of (wi, wo) on the upper side, as Mitsuba's eval and pdf make it:
    /// normalize(wi + wo) for reflection, normalize(wi + η_path wo) otherwise. For η near 1
    /// the refraction sum nearly cancels: each component is made by one fused multiply-add,
    /// rounded once from the exact sum (as accurate as the sum in f64 it replaces).
    #[inline(always)]
    fn half_vector<R: Real>(
        wi: Vector3<R>,
        wo: Vector3<R>,
        reflect: R::Mask,
        eta_path: R,
    ) -> Vector3<R> {
        let s = R::select(reflect, R::one(), eta_path);
        let h = Vector3::new(
            s.mul_add(wo.x, wi.x),
            s.mul_add(wo.y, wi.y),
            s.mul_add(wo.z, wi.z),
        )
        .normalize();
        mulsign(h, h.z)
    }

    /// What eval and pdf both find first for (wi, wo): the lobe weights, the half vector,
    /// the distribution and the Fresnel term there. `None` where no lane has them.
    #[inline(always)]
    fn pair<R: Real>(
        &self,
        sp: &ShadingPointR<R>,
        wi: Vector3<R>,
        wo: Vector3<R>,
    ) -> Option<Pair<R>> {
        let zero = R::zero();
        let cos_i = wi.z;
        let cos_o = wo.z;
        let reflect = (cos_i * cos_o).greater(zero);
        let refract = (cos_i * cos_o).less(zero);
        let valid = !cos_i.equals(zero) & (reflect | refract);
        if !valid.any() {
            return None;
        }
        let front = cos_i.greater(zero);
        let eta = R::splat(self.eta);
        let eta_path = R::select(front, eta, R::one() / eta);
        let wh = Self::half_vector(wi, wo, reflect, eta_path);
        let valid = valid & wh.is_finite();
        if !valid.any() {
            return None;
        }
        let w = self.weights(sp);
        let dist = self.distribution(&w);
        let (dot_i, dot_o) = (wi.dot(wh), wo.dot(wh));
        let f = fresnel_dielectric_r(dot_i, eta).f;
        Some(Pair {
            valid,
            w,
            cos_i,
            cos_o,
            reflect,
            refract,
            front,
            eta_path,
            wh,
            dist,
            dot_i,
            dot_o,
            f,
        })
    }

    /// eval given its [`Pair`] and D(ωh).
    #[inline(always)]
    fn eval_pair<R: Real>(
        &self,
        sp: &ShadingPointR<R>,
        wi: Vector3<R>,
        wo: Vector3<R>,
        q: &Pair<R>,
        d: R,
    ) -> Vector3<R> {
        let Pair {
            valid,
            ref w,
            cos_i,
            cos_o,
            reflect,
            refract,
            front,
            eta_path,
            wh,
            ref dist,
            dot_i,
            dot_o,
            f,
        } = *q;
        let (zero, one, k) = (R::zero(), R::one(), R::splat);
        let no = R::Mask::splat(false);
        let eta = k(self.eta);
        let metallic = w.metallic;
        let base_color = self.base_color.eval_r(sp);
        let inv_eta_path = one / eta_path;
        let refl_ok = reflect & mac_mic_compatible(wh, wi, wo, cos_i, true);
        let refr_ok = refract & mac_mic_compatible(wh, wi, wo, cos_i, false);

        let spec_reflect = refl_ok & f.greater(zero);
        let clearcoat = if self.clearcoat.is_some() {
            w.clearcoat.greater(zero) & refl_ok & front
        } else {
            no
        };
        let spec_trans = if self.spec_trans.is_some() {
            w.bsdf.greater(zero) & refr_ok & f.less(one)
        } else {
            no
        };
        let diffuse = w.brdf.greater(zero) & reflect & front;
        let sheen_w = opt_1(&self.sheen, sp);
        let sheen = if self.sheen.is_some() {
            sheen_w.greater(zero) & reflect & (one - metallic).greater(zero) & front
        } else {
            no
        };

        let mut value = Vector3::zero();
        if (spec_reflect | spec_trans).any() {
            let g = dist.g(wi, wo, wh, Shadowing::Separable);
            add_where!(spec_reflect, value, {
                let has_tint = self.spec_tint.is_some();
                let lum = if has_tint {
                    luminance_r(base_color)
                } else {
                    one
                };
                let spec_tint = opt_1(&self.spec_tint, sp);
                let fp = principled_fresnel(
                    f,
                    metallic,
                    spec_tint,
                    base_color,
                    lum,
                    dot_i,
                    front,
                    w.bsdf,
                    eta,
                    self.metallic.is_some(),
                    has_tint,
                );
                fp * (d * g / (k(4.0) * cos_i.abs()))
            });
            add_where!(spec_trans, value, {
                // Radiance mode: the 1/η² compression (Mitsuba's `scale`).
                let scale = inv_eta_path * inv_eta_path;
                let denom = dot_i + eta_path * dot_o;
                let t = (scale * (one - f) * d * g * eta_path * eta_path * dot_i * dot_o
                    / (cos_i * denom * denom))
                    .abs();
                let b = base_color;
                let root = Vector3::new(
                    b.x.max(zero).sqrt(),
                    b.y.max(zero).sqrt(),
                    b.z.max(zero).sqrt(),
                );
                root * (w.bsdf * t)
            });
        }
        add_where!(clearcoat, value, {
            let gloss = self.clearcoat_gloss.eval_1_r(sp);
            let fcc = calc_schlick_1(k(0.04), dot_i, eta);
            let dcc = Gtr1::clearcoat(gloss).eval(wh);
            let gcc = clearcoat_g(wi, wo, wh, 0.25);
            Vector3::splat_lanes(w.clearcoat * k(0.25) * fcc * dcc * gcc * cos_o.abs())
        });
        let cos_d = wh.dot(wo);
        add_where!(diffuse, value, {
            let half = k(0.5);
            let fo = schlick_weight(cos_o.abs());
            let fi = schlick_weight(cos_i.abs());
            let f_diff = (one - half * fi) * (one - half * fo);
            let rr = k(2.0) * w.roughness * cos_d * cos_d;
            let f_retro = rr * (fo + fi + fo * fi * (rr - one));
            let lobe = match &self.flatness {
                Some(t) => {
                    // Hanrahan–Krueger's flattened "fake subsurface".
                    let flatness = t.eval_1_r(sp);
                    let fss90 = rr / k(2.0);
                    let fss = (one + (fss90 - one) * fo) * (one + (fss90 - one) * fi);
                    let f_ss = k(1.25) * (fss * (one / (cos_o.abs() + cos_i.abs()) - half) + half);
                    let a = f_diff + f_retro;
                    a + (f_ss - a) * flatness
                }
                None => f_diff + f_retro,
            };
            base_color * (w.brdf * cos_o.abs() * k(INV_PI) * lobe)
        });
        add_where!(sheen, value, {
            let fd = schlick_weight(cos_d.abs());
            let white = Vector3::splat_lanes(one);
            let c_sheen = match &self.sheen_tint {
                Some(t) => {
                    let st = t.eval_1_r(sp);
                    let c_tint = tint_color(base_color, luminance_r(base_color));
                    white + (c_tint - white) * st
                }
                None => white,
            };
            c_sheen * (sheen_w * (one - metallic) * fd * cos_o.abs())
        });
        Vector3::select(valid & value.is_finite(), value, Vector3::zero())
    }

    /// pdf given its [`Pair`] and D(ωh).
    #[inline(always)]
    fn pdf_pair<R: Real>(
        &self,
        sp: &ShadingPointR<R>,
        wi: Vector3<R>,
        wo: Vector3<R>,
        q: &Pair<R>,
        d: R,
    ) -> R {
        let Pair {
            valid,
            ref w,
            cos_i,
            reflect,
            refract,
            front,
            eta_path,
            wh,
            ref dist,
            dot_i,
            dot_o,
            f,
            ..
        } = *q;
        let (zero, k) = (R::zero(), R::splat);
        let has_st = self.spec_trans.is_some();
        // What `sample` refuses (Mitsuba: `active &= front_side || bsdf > 0`).
        let sampled = if has_st {
            front | w.bsdf.greater(zero)
        } else {
            front
        };
        let p = self.probabilities(w, front, f);
        let dwh_dwo_reflect = (R::one() / (k(4.0) * dot_o)).abs();
        let dwh_dwo = if has_st {
            let denom = dot_i + eta_path * dot_o;
            let refract_form = (eta_path * eta_path * dot_o / (denom * denom)).abs();
            R::select(reflect, dwh_dwo_reflect, refract_form)
        } else {
            dwh_dwo_reflect
        };
        let refl_ok = reflect & mac_mic_compatible(wh, wi, wo, cos_i, true);
        let spec_reflect = refl_ok & p.spec_reflect.greater(zero);
        let spec_trans = if has_st {
            refract & p.spec_trans.greater(zero) & mac_mic_compatible(wh, wi, wo, cos_i, false)
        } else {
            R::Mask::splat(false)
        };
        let pdf_m = if (spec_reflect | spec_trans).any() {
            dist.pdf_given(d, mulsign(wi, cos_i), wh)
        } else {
            zero
        };
        let mut pdf = zero;
        add_where!(spec_reflect, pdf, { p.spec_reflect * pdf_m * dwh_dwo });
        add_where!(reflect, pdf, {
            p.diffuse * warp::cosine_hemisphere_pdf_r(wo)
        });
        add_where!(spec_trans, pdf, { p.spec_trans * pdf_m * dwh_dwo });
        if self.clearcoat.is_some() {
            add_where!(refl_ok & p.clearcoat.greater(zero), pdf, {
                let gloss = self.clearcoat_gloss.eval_1_r(sp);
                p.clearcoat * Gtr1::clearcoat(gloss).pdf(wh) * dwh_dwo
            });
        }
        R::select(valid & sampled & p.ok & pdf.is_finite(), pdf, zero)
    }

    /// sample over any [`Real`], with the lanes that chose the diffuse lobe and the
    /// transmission.
    #[inline(always)]
    fn sample_lobe<R: Real>(
        &self,
        sp: &ShadingPointR<R>,
        wi: Vector3<R>,
        u1: R,
        u2: Vector2<R>,
    ) -> LobeSample<R> {
        let (zero, one) = (R::zero(), R::one());
        let no = R::Mask::splat(false);
        let none = LobeSample {
            s: BsdfSampleR::none(),
            diffuse: no,
            transmission: no,
        };
        let has_st = self.spec_trans.is_some();
        let cos_i = wi.z;
        let mut valid = !cos_i.equals(zero) & wi.is_finite();
        if !valid.any() {
            return none;
        }
        let w = self.weights(sp);
        let front = cos_i.greater(zero);
        if has_st {
            valid &= front | w.bsdf.greater(zero);
        } else {
            valid &= front;
        }
        if !valid.any() {
            return none;
        }
        let dist = self.distribution(&w);
        let (m_spec, pdf_m) = dist.sample(mulsign(wi, cos_i), u2);
        valid &= pdf_m.greater(zero) & m_spec.is_finite();
        if !valid.any() {
            return none;
        }
        let fr = fresnel_dielectric_r(wi.dot(m_spec), R::splat(self.eta));
        let p = self.probabilities(&w, front, fr.f);
        valid &= p.ok;
        if !valid.any() {
            return none;
        }
        // The lobe, as Mitsuba orders them on u1: diffuse, clearcoat, transmission,
        // reflection.
        let is_diffuse = u1.less(p.diffuse);
        let c_clearcoat = p.diffuse + p.clearcoat;
        let is_clearcoat = !is_diffuse & u1.less(c_clearcoat);
        let is_trans = if has_st {
            !is_diffuse & !is_clearcoat & u1.less(c_clearcoat + p.spec_trans)
        } else {
            no
        };
        // Specular reflection, and where another lobe was chosen its direction instead.
        let mut wo = reflect_about_r(wi, m_spec);
        let mut ok = (cos_i * wo.z).greater(zero) & mac_mic_compatible(m_spec, wi, wo, cos_i, true);
        if is_trans.any() {
            let t = refract_about_r(wi, m_spec, fr.cos_theta_t, fr.eta_ti);
            let t_ok = (cos_i * t.z).less(zero) & mac_mic_compatible(m_spec, wi, t, cos_i, false);
            wo = Vector3::select(is_trans, t, wo);
            ok = (is_trans & t_ok) | (!is_trans & ok);
        }
        if is_clearcoat.any() {
            let gloss = self.clearcoat_gloss.eval_1_r(sp);
            let m = Gtr1::clearcoat(gloss).sample(u2);
            let c = reflect_about_r(wi, m);
            let c_ok = (cos_i * c.z).greater(zero) & mac_mic_compatible(m, wi, c, cos_i, true);
            wo = Vector3::select(is_clearcoat, c, wo);
            ok = (is_clearcoat & c_ok) | (!is_clearcoat & ok);
        }
        if is_diffuse.any() {
            let c = warp::square_to_cosine_hemisphere_r(u2);
            let c_ok = (cos_i * c.z).greater(zero);
            wo = Vector3::select(is_diffuse, c, wo);
            ok = (is_diffuse & c_ok) | (!is_diffuse & ok);
        }
        valid &= ok;
        if !valid.any() {
            return none;
        }
        let wo = wo.normalize();
        let (value, pdf) = self.eval_pdf_r(sp, wi, wo);
        valid &= pdf.greater(zero);
        let weight = value.div(pdf);
        LobeSample {
            s: BsdfSampleR {
                wo,
                weight,
                pdf,
                eta: R::select(is_trans, fr.eta_it, one),
                valid: valid & weight.is_finite(),
                delta: no,
                null: no,
            },
            diffuse: is_diffuse,
            transmission: is_trans,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fresnel::fresnel_dielectric;
    use crate::testing::*;
    use crate::Bsdf;

    /// A principled material with the given weights (each `Some` only when nonzero, as the
    /// loader does).
    #[derive(Clone, Copy, Default)]
    struct P {
        base: [f32; 3],
        roughness: f32,
        metallic: f32,
        spec_trans: f32,
        anisotropic: f32,
        spec_tint: f32,
        sheen: f32,
        sheen_tint: f32,
        flatness: f32,
        clearcoat: f32,
        clearcoat_gloss: f32,
        eta: Option<f32>,
    }

    fn some(x: f32) -> Option<Texture> {
        (x != 0.0).then(|| x.into())
    }

    impl P {
        fn build(&self) -> Principled {
            let mut m = Principled::new(Spectrum::from(self.base));
            m.roughness = self.roughness.into();
            m.metallic = some(self.metallic);
            m.spec_trans = some(self.spec_trans);
            m.anisotropic = some(self.anisotropic);
            m.spec_tint = some(self.spec_tint);
            m.sheen = some(self.sheen);
            m.sheen_tint = some(self.sheen_tint);
            m.flatness = some(self.flatness);
            m.clearcoat = some(self.clearcoat);
            m.clearcoat_gloss = self.clearcoat_gloss.into();
            m.with_ior(match self.eta {
                Some(e) => PrincipledIor::Eta(e),
                None => PrincipledIor::Specular(0.5),
            })
        }
        fn bsdf(&self) -> Bsdf {
            Bsdf::Principled(self.build())
        }
    }

    const BASE: P = P {
        base: [0.8, 0.5, 0.2],
        roughness: 0.5,
        metallic: 0.0,
        spec_trans: 0.0,
        anisotropic: 0.0,
        spec_tint: 0.0,
        sheen: 0.0,
        sheen_tint: 0.0,
        flatness: 0.0,
        clearcoat: 0.0,
        clearcoat_gloss: 0.0,
        eta: None,
    };

    /// The parameter corners every test runs over: (name, parameters).
    fn corners() -> Vec<(&'static str, P)> {
        vec![
            ("default dielectric", BASE),
            (
                "metal",
                P {
                    metallic: 1.0,
                    roughness: 0.4,
                    ..BASE
                },
            ),
            (
                "glass",
                P {
                    spec_trans: 1.0,
                    roughness: 0.4,
                    ..BASE
                },
            ),
            (
                "everything",
                P {
                    metallic: 0.3,
                    spec_trans: 0.5,
                    spec_tint: 0.5,
                    sheen: 1.0,
                    sheen_tint: 0.5,
                    flatness: 0.5,
                    clearcoat: 1.0,
                    clearcoat_gloss: 0.5,
                    ..BASE
                },
            ),
            (
                "anisotropic",
                P {
                    anisotropic: 0.8,
                    metallic: 0.5,
                    roughness: 0.6,
                    ..BASE
                },
            ),
            (
                "clearcoat gloss 1",
                P {
                    clearcoat: 1.0,
                    clearcoat_gloss: 1.0,
                    ..BASE
                },
            ),
            (
                "rough 1",
                P {
                    roughness: 1.0,
                    spec_trans: 0.3,
                    eta: Some(1.33),
                    ..BASE
                },
            ),
            (
                "smooth",
                P {
                    roughness: 0.05,
                    spec_trans: 0.5,
                    ..BASE
                },
            ),
            (
                "smooth metal",
                P {
                    roughness: 0.0,
                    metallic: 1.0,
                    ..BASE
                },
            ),
        ]
    }

    fn both_sides(p: &P) -> Vec<Vec3> {
        incident_directions(p.spec_trans > 0.0)
    }

    /// Chi-square of sampling against pdf at every corner and incident direction (both
    /// sides when there is transmission): the whole sphere for broad lobes, zoomed caps on
    /// the mirror and refraction directions for the smooth ones.
    #[test]
    fn principled_chi2() {
        let mut suite = Chi2Suite::default();
        suite.res = (31, 64);
        for (name, p) in corners() {
            let b = p.bsdf();
            for wi in both_sides(&p) {
                if p.roughness >= 0.3 {
                    suite.check(name, &b, wi, Zoom::SPHERE, 100_000);
                    continue;
                }
                let a = (p.roughness * p.roughness).max(0.001);
                suite.res = (51, 100);
                suite.check(
                    name,
                    &b,
                    wi,
                    Zoom::lobe(crate::fresnel::reflect(wi), (12.0 * a).max(0.05)),
                    100_000,
                );
                if p.spec_trans > 0.0 {
                    let eta = b_eta(&b);
                    let fr = fresnel_dielectric(wi.z, eta);
                    let zoom = if fr.f < 1.0 {
                        let t = crate::fresnel::refract(wi, fr.cos_theta_t, fr.eta_ti);
                        Zoom::lobe(t, (12.0 * a * (1.0 - fr.eta_ti).abs()).max(0.05))
                    } else {
                        Zoom::cap(
                            Vec3::new(0.0, 0.0, -wi.z.signum()),
                            std::f32::consts::FRAC_PI_2,
                        )
                    };
                    suite.check(name, &b, wi, zoom, 100_000);
                }
                // (No whole-sphere test here: its cells integrate a lobe this narrow too
                // coarsely. The diffuse and clearcoat lobes, the same code at every
                // roughness, are tested over the whole sphere at the broad corners.)
                suite.res = (31, 64);
            }
        }
        suite.finish();
    }

    fn b_eta(b: &Bsdf) -> f32 {
        match b {
            Bsdf::Principled(p) => p.eta,
            _ => unreachable!(),
        }
    }

    /// The sample's pdf is pdf(wo), its weight eval/pdf, every value finite.
    #[test]
    fn principled_consistency() {
        for (name, p) in corners() {
            let b = p.bsdf();
            for wi in incident_directions(true) {
                let rel = if p.roughness < 0.1 || wi.z.abs() < 0.05 {
                    3e-2
                } else {
                    2e-3
                };
                check_consistency(name, &b, wi, 10_000, rel);
            }
        }
    }

    /// Reflection from the front is reciprocal (every front lobe is symmetric in wi, wo,
    /// clearcoat included: Mitsuba's clearcoat value carries |cos θo| only, so f has no
    /// cosine); refraction obeys f(wo, wi) = η² f(wi, wo) (radiance mode), as roughdielectric.
    #[test]
    fn principled_reciprocity() {
        use rand::{Rng, SeedableRng};
        for (name, p) in corners() {
            if p.roughness < 0.1 {
                continue; // too narrow for pairs drawn at random
            }
            let b = p.bsdf();
            check_reciprocity(name, &b, 2000, false);
            if p.spec_trans == 0.0 {
                continue;
            }
            let eta = b_eta(&b);
            let mut nonzero = 0;
            let mut pairs = 0;
            let mut rng = rand_pcg::Pcg32::seed_from_u64(11);
            for _ in 0..8000 {
                let wi = dir(
                    rng.random_range(0.02..1.0),
                    rng.random_range(0.0..std::f32::consts::TAU),
                );
                let u = Vec2::new(rng.random(), rng.random());
                let Some(s) = b.sample(&SP, wi, rng.random(), u) else {
                    continue;
                };
                if s.lobe != LobeFlags::GLOSSY_TRANSMISSION || s.wo.z > -0.02 {
                    continue;
                }
                pairs += 1;
                let a = b.eval(&SP, wi, s.wo).max_element() / s.wo.z.abs();
                let c = b.eval(&SP, s.wo, wi).max_element() / wi.z.abs();
                assert!(
                    (c - eta * eta * a).abs() <= 2e-3 * c.abs().max(eta * eta * a) + 1e-6,
                    "{name}: f(wi, wo) {a}, f(wo, wi) {c}, η {eta}, wi {wi}, wo {}",
                    s.wo
                );
                nonzero += (a > 0.0) as usize;
            }
            assert!(
                nonzero > pairs / 2 && pairs > 500,
                "{name}: {nonzero} of {pairs}"
            );
        }
    }

    /// Sampled and uniform albedo agree (sampling covers eval's support, weights unbiased)
    /// at the broad corners.
    #[test]
    fn principled_albedo_unbiased() {
        for (name, p) in corners() {
            if p.roughness < 0.3 || p.clearcoat_gloss > 0.5 {
                continue;
            }
            let b = p.bsdf();
            for wi in both_sides(&p) {
                if wi.z.abs() < 0.05 {
                    continue;
                }
                assert_albedo_unbiased(name, &b, wi, 200_000, 1e-3);
            }
        }
    }

    /// Energy where Mitsuba's model conserves it: a metal (Schlick F ≤ 1 over a GGX lobe),
    /// a black dielectric (dielectric Fresnel only), a clear glass (F + (1 − F) = 1, from
    /// both sides), each for every roughness: albedo ≤ 1.
    #[test]
    fn principled_energy_conserving_corners() {
        for r in [0.0f32, 0.1, 0.5, 1.0] {
            let cases = [
                (
                    "metal",
                    P {
                        base: [1.0; 3],
                        metallic: 1.0,
                        roughness: r,
                        ..BASE
                    },
                ),
                (
                    "black dielectric",
                    P {
                        base: [0.0; 3],
                        roughness: r,
                        ..BASE
                    },
                ),
                (
                    "white glass",
                    P {
                        base: [1.0; 3],
                        spec_trans: 1.0,
                        roughness: r,
                        ..BASE
                    },
                ),
                (
                    "anisotropic metal",
                    P {
                        base: [1.0; 3],
                        metallic: 1.0,
                        anisotropic: 1.0,
                        roughness: r,
                        ..BASE
                    },
                ),
            ];
            for (name, p) in cases {
                let b = p.bsdf();
                for wi in both_sides(&p) {
                    assert_albedo_at_most_one(name, &b, wi, 20_000);
                }
            }
        }
        // Nearly smooth clear glass: R + T = 1.
        let b = P {
            base: [1.0; 3],
            spec_trans: 1.0,
            roughness: 0.05,
            ..BASE
        }
        .bsdf();
        let (a, _) = albedo_sampled(&b, dir(0.8, 0.3), 50_000);
        assert!(a.x > 0.99, "{a}");
    }

    /// Where Mitsuba's model itself creates energy, which radia reproduces: the diffuse lobe
    /// is not reduced by the specular reflection above it, and Burley's retro-reflection
    /// brightens rough surfaces, so a white rough dielectric reflects more than it receives
    /// (at grazing and at normal incidence); the clearcoat is added on top of everything,
    /// with no energy taken from the lobes below it.
    #[test]
    fn principled_energy_gain_where_mitsuba_gains() {
        let white = P {
            base: [1.0; 3],
            roughness: 1.0,
            ..BASE
        };
        let (a, e) = albedo_sampled(&white.bsdf(), dir(0.1, 0.3), 100_000);
        assert!(
            a.x > 1.0 + 5.0 * e.x,
            "white rough dielectric at grazing: {a} ± {e}"
        );
        // The clearcoat adds to the reflection of a white metal, whose Schlick F is already 1
        // at grazing angles (that sum stays below 1 here only because of masking).
        let metal = P {
            base: [1.0; 3],
            metallic: 1.0,
            roughness: 0.3,
            ..BASE
        };
        let coated = P {
            clearcoat: 1.0,
            ..metal
        };
        let (m, c) = (metal.bsdf(), coated.bsdf());
        let wi = dir(0.1, 0.3);
        let mut more = 0;
        for_each_sample(2000, 5, |u, _| {
            let wo = radia_sampling::warp::square_to_uniform_hemisphere(u);
            let (f0, f1) = (m.eval(&SP, wi, wo), c.eval(&SP, wi, wo));
            assert!(f1.x >= f0.x, "{wo}: {f0} {f1}");
            more += (f1.x > f0.x * (1.0 + 1e-4)) as usize;
        });
        assert!(more > 1000, "{more}");
        // At normal incidence too (1.052: diffuse ≈ 1 plus the specular 0.04 and more).
        let (a, e) = albedo_sampled(&white.bsdf(), Vec3::Z, 50_000);
        assert!(
            a.x > 1.0 + 5.0 * e.x,
            "white rough dielectric at normal incidence: {a} ± {e}"
        );
    }

    /// Below the surface, an opaque principled material neither reflects nor samples
    /// (Mitsuba: no diffuse, clearcoat or sheen from the back, and the specular reflection
    /// from the back is weighted by the transmission weight bsdf = 0).
    #[test]
    fn principled_back_side() {
        let b = BASE.bsdf();
        let wi = dir(-0.6, 1.0);
        for_each_sample(1000, 3, |u, u1| {
            assert!(b.sample(&SP, wi, u1, u).is_none());
            let wo = radia_sampling::warp::square_to_uniform_sphere(u);
            assert_eq!(b.eval(&SP, wi, wo), Spectrum::ZERO);
            assert_eq!(b.pdf(&SP, wi, wo), 0.0);
        });
        // With transmission, light inside reflects and refracts, untinted by metallic.
        let glass = P {
            spec_trans: 1.0,
            ..BASE
        }
        .bsdf();
        let (a, _) = albedo_sampled(&glass, wi, 20_000);
        assert!(a.max_element() > 0.5, "{a}");
    }

    /// eval and pdf against Mitsuba 3.9.1's own (`scalar_rgb`, `mi.load_dict` with the same
    /// parameters, `bsdf.eval`/`bsdf.pdf` at these directions), including refraction from
    /// both sides and reflection inside. One difference, by design (module docs): from the
    /// back of an opaque material ("aniso") Mitsuba's pdf is nonzero where its eval is 0
    /// and its sample returns nothing; radia's pdf is 0 there.
    #[test]
    #[allow(clippy::excessive_precision)] // Mitsuba's printed values, as printed
    fn principled_matches_mitsuba_values() {
        let everything = P {
            metallic: 0.3,
            spec_trans: 0.5,
            spec_tint: 0.5,
            sheen: 1.0,
            sheen_tint: 0.5,
            flatness: 0.5,
            clearcoat: 1.0,
            clearcoat_gloss: 0.5,
            ..BASE
        };
        let aniso = P {
            roughness: 0.6,
            metallic: 0.5,
            anisotropic: 0.8,
            spec_tint: 0.3,
            ..BASE
        }
        .build()
        .with_ior(PrincipledIor::Specular(0.7));
        let glass = P {
            roughness: 0.4,
            spec_trans: 1.0,
            eta: Some(1.33),
            ..BASE
        };
        #[allow(clippy::type_complexity)]
        let mitsuba: &[(&str, (f32, f32), (f32, f32), [f32; 3], f32)] = &[
            (
                "everything",
                (0.7, 0.4),
                (0.5, 2.0),
                [5.363502e-02, 3.389787e-02, 1.416071e-02],
                5.082572e-02,
            ),
            (
                "everything",
                (0.7, 0.4),
                (0.6, 3.4),
                [4.427016e-01, 2.976024e-01, 1.525032e-01],
                8.273803e-01,
            ),
            (
                "everything",
                (0.3, 1.0),
                (0.9, 4.0),
                [1.755732e-01, 1.140982e-01, 5.262329e-02],
                2.139795e-01,
            ),
            (
                "everything",
                (0.7, 0.4),
                (-0.6, 3.3),
                [2.381117e-02, 1.882438e-02, 1.190558e-02],
                3.844928e-02,
            ),
            (
                "everything",
                (-0.6, 1.0),
                (-0.5, 4.0),
                [4.630366e-01, 4.630366e-01, 4.630366e-01],
                1.382313e+00,
            ),
            (
                "everything",
                (-0.6, 1.0),
                (0.8, 4.2),
                [3.858334e-02, 3.050281e-02, 1.929167e-02],
                5.525505e-02,
            ),
            (
                "everything",
                (0.05, 0.0),
                (0.1, 3.0),
                [1.066730e-01, 8.953872e-02, 7.240442e-02],
                1.066073e-01,
            ),
            (
                "aniso",
                (0.7, 0.4),
                (0.5, 2.0),
                [6.641528e-02, 4.154791e-02, 1.668053e-02],
                5.654953e-02,
            ),
            (
                "aniso",
                (0.7, 0.4),
                (0.6, 3.4),
                [3.290110e-01, 2.118940e-01, 9.477688e-02],
                5.104908e-01,
            ),
            (
                "aniso",
                (0.3, 1.0),
                (0.9, 4.0),
                [1.484258e-01, 9.359379e-02, 3.876177e-02],
                1.470459e-01,
            ),
            (
                "aniso",
                (0.7, 0.4),
                (-0.6, 3.3),
                [0.000000e+00, 0.000000e+00, 0.000000e+00],
                0.000000e+00,
            ),
            (
                "aniso",
                (-0.6, 1.0),
                (-0.5, 4.0),
                [0.000000e+00, 0.000000e+00, 0.000000e+00],
                9.151433e-01,
            ),
            (
                "aniso",
                (-0.6, 1.0),
                (0.8, 4.2),
                [0.000000e+00, 0.000000e+00, 0.000000e+00],
                0.000000e+00,
            ),
            (
                "aniso",
                (0.05, 0.0),
                (0.1, 3.0),
                [7.468199e-03, 5.192730e-03, 2.917259e-03],
                1.688885e-02,
            ),
            (
                "glass",
                (0.7, 0.4),
                (0.5, 2.0),
                [2.824507e-04, 2.824507e-04, 2.824507e-04],
                2.877737e-04,
            ),
            (
                "glass",
                (0.7, 0.4),
                (0.6, 3.4),
                [6.955800e-02, 6.955800e-02, 6.955800e-02],
                7.034060e-02,
            ),
            (
                "glass",
                (0.3, 1.0),
                (0.9, 4.0),
                [6.119668e-03, 6.119668e-03, 6.119668e-03],
                6.128840e-03,
            ),
            (
                "glass",
                (0.7, 0.4),
                (-0.6, 3.3),
                [3.765229e-02, 2.976675e-02, 1.882615e-02],
                7.530239e-02,
            ),
            (
                "glass",
                (-0.6, 1.0),
                (-0.5, 4.0),
                [2.053526e+00, 2.053526e+00, 2.053526e+00],
                2.092224e+00,
            ),
            (
                "glass",
                (-0.6, 1.0),
                (0.8, 4.2),
                [0.000000e+00, 0.000000e+00, 0.000000e+00],
                0.000000e+00,
            ),
            (
                "glass",
                (0.05, 0.0),
                (0.1, 3.0),
                [2.953291e-02, 2.953291e-02, 2.953291e-02],
                4.252724e-02,
            ),
        ];
        for &(name, (ci, pi), (co, po), f, pdf) in mitsuba {
            let b = match name {
                "everything" => everything.bsdf(),
                "aniso" => Bsdf::Principled(aniso.clone()),
                _ => glass.bsdf(),
            };
            let (wi, wo) = (dir(ci, pi), dir(co, po));
            let v = b.eval(&SP, wi, wo);
            for c in 0..3 {
                assert!(
                    (v[c] - f[c]).abs() <= 2e-4 * f[c] + 1e-7,
                    "{name} wi {wi} wo {wo}: eval {v}, Mitsuba {f:?}"
                );
            }
            let p = b.pdf(&SP, wi, wo);
            let expected = if name == "aniso" && ci < 0.0 {
                0.0
            } else {
                pdf
            };
            assert!(
                (p - expected).abs() <= 2e-4 * expected + 1e-7,
                "{name} wi {wi} wo {wo}: pdf {p}, Mitsuba {pdf}"
            );
        }
    }

    /// Mitsuba's `specular` ↔ `eta` mapping and its adjustments for transmission.
    #[test]
    fn principled_ior() {
        let m = Principled::new(Spectrum::ONE).with_ior(PrincipledIor::Specular(0.5));
        assert!((m.eta - 1.5).abs() < 1e-6);
        let mut m = Principled::new(Spectrum::ONE);
        m.spec_trans = Some(1.0.into());
        assert_eq!(m.clone().with_ior(PrincipledIor::Eta(1.0)).eta, 1.001);
        let e = m.with_ior(PrincipledIor::Specular(0.0)).eta;
        assert!((e - (2.0 / (1.0 - 0.08f32.mul_add(1e-3, 0.0).sqrt()) - 1.0)).abs() < 1e-6);
        assert_eq!(
            Principled::new(Spectrum::ONE)
                .with_ior(PrincipledIor::Eta(1.0))
                .eta,
            1.0
        );
    }

    /// No NaN or infinity at extreme parameters and directions.
    #[test]
    fn principled_finite() {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_pcg::Pcg32::seed_from_u64(7);
        let pick = |rng: &mut rand_pcg::Pcg32| match rng.random_range(0..4) {
            0 => 0.0,
            1 => 1.0,
            _ => rng.random::<f32>(),
        };
        for _ in 0..300 {
            let p = P {
                base: [pick(&mut rng), pick(&mut rng), pick(&mut rng)],
                roughness: pick(&mut rng),
                metallic: pick(&mut rng),
                spec_trans: pick(&mut rng),
                anisotropic: pick(&mut rng),
                spec_tint: pick(&mut rng),
                sheen: pick(&mut rng),
                sheen_tint: pick(&mut rng),
                flatness: pick(&mut rng),
                clearcoat: pick(&mut rng),
                clearcoat_gloss: pick(&mut rng),
                eta: rng
                    .random::<bool>()
                    .then(|| 0.5 + 2.0 * rng.random::<f32>()),
            };
            let b = p.bsdf();
            for _ in 0..500 {
                let z = match rng.random_range(0..5) {
                    0 => 0.0,
                    1 => 1e-6 * rng.random::<f32>() - 0.5e-6,
                    2 => 1.0,
                    _ => rng.random_range(-1.0..1.0),
                };
                let wi = dir(z, rng.random::<f32>() * std::f32::consts::TAU);
                let wo = match rng.random_range(0..3) {
                    0 => Vec3::new(-wi.x, -wi.y, wi.z),
                    1 => -wi,
                    _ => dir(
                        rng.random_range(-1.0..1.0),
                        rng.random::<f32>() * std::f32::consts::TAU,
                    ),
                };
                let u = Vec2::new(rng.random(), rng.random());
                check_finite("principled", &b, wi, wo, rng.random(), u);
            }
        }
    }
}
