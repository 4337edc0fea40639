//! Normal mapping: Mitsuba's `normalmap` adapter (`src/bsdfs/normalmap.cpp`, 3.9.1).
//!
//! ```xml
//! <bsdf type="normalmap">
//!     <texture name="normalmap" type="bitmap">
//!         <boolean name="raw" value="true"/>
//!         <string name="filename" value="normals.png"/>
//!     </texture>
//!     <bsdf type="roughplastic"/>
//! </bsdf>
//! ```
//! The texture's colour encodes the perturbed normal relative to the shading frame:
//! n = 2·rgb − 1, flipped to (−x, −y, z) when it faces away from `wi` (with
//! `flip_invalid_normals`), normalised; the perturbed frame's s is (1, 0, 0) made
//! orthogonal to n, t = n × s. The nested BSDF is evaluated in that frame (see
//! `perturbed.rs` for the side checks and the shadowing term).

use crate::nested::{Lanes, Nested, OnePath, Want};
use crate::perturbed::{self, frame_from, PerturbOptions, Perturbed};
use crate::{Bsdf, BsdfSample, BsdfSampleR, LobeFlags, ShadingPoint, ShadingPointR, Texture};
use glam::{Vec2, Vec3};
use radia_math::real::{Real, Vector2, Vector3};
use radia_math::{Frame, Spectrum};

#[derive(Clone, Debug)]
pub struct NormalMap {
    /// Normals encoded as colours (load it `raw`).
    pub normalmap: Texture,
    pub nested: Box<Bsdf>,
    pub options: PerturbOptions,
}

impl NormalMap {
    pub fn new(normalmap: Texture, nested: Bsdf, options: PerturbOptions) -> Self {
        Self {
            normalmap,
            nested: Box::new(nested),
            options,
        }
    }

    pub fn flags(&self) -> LobeFlags {
        self.nested.flags()
    }

    /// The perturbed frame relative to the shading frame (Mitsuba's `frame()`, first part).
    #[inline]
    pub(crate) fn frame(&self, sp: &ShadingPoint, wi: Vec3) -> Option<Frame> {
        self.frame_r::<f32>(&sp.into(), wi.into()).one_path()
    }

    /// [`NormalMap::frame`] over any [`Real`].
    #[inline(always)]
    fn frame_r<R: Real>(&self, sp: &ShadingPointR<R>, wi: Vector3<R>) -> Perturbed<R> {
        let n = self.normalmap.eval_r(sp) * R::splat(2.0) - Vector3::splat(Vec3::ONE);
        frame_from(self.options.flip(n, wi), Vector3::splat(Vec3::X))
    }

    #[inline]
    pub fn eval(&self, sp: &ShadingPoint, wi: Vec3, wo: Vec3) -> Spectrum {
        let n = OnePath::new(Want::Eval);
        self.eval_pdf_with(&n, &sp.into(), wi.into(), wo.into())
            .0
            .into()
    }

    #[inline]
    pub fn pdf(&self, sp: &ShadingPoint, wi: Vec3, wo: Vec3) -> f32 {
        let n = OnePath::new(Want::Pdf);
        self.eval_pdf_with(&n, &sp.into(), wi.into(), wo.into()).1
    }

    /// [`NormalMap::eval`] and [`NormalMap::pdf`] at once (the frame made once).
    #[inline]
    pub fn eval_pdf(&self, sp: &ShadingPoint, wi: Vec3, wo: Vec3) -> (Spectrum, f32) {
        let n = OnePath::new(Want::Both);
        let (f, pdf) = self.eval_pdf_with(&n, &sp.into(), wi.into(), wo.into());
        (f.into(), pdf)
    }

    #[inline]
    pub fn sample(&self, sp: &ShadingPoint, wi: Vec3, u1: f32, u2: Vec2) -> Option<BsdfSample> {
        let n = OnePath::new(Want::Both);
        let s = self.sample_with(&n, &sp.into(), wi.into(), u1, u2.into());
        s.one_path(n.lobe())
    }

    /// eval and pdf over any [`Real`], where the nested model has lane versions.
    #[inline(always)]
    pub fn eval_pdf_r<R: Real>(
        &self,
        sp: &ShadingPointR<R>,
        wi: Vector3<R>,
        wo: Vector3<R>,
    ) -> (Vector3<R>, R) {
        self.eval_pdf_with(&Lanes, sp, wi, wo)
    }

    /// sample over any [`Real`], where the nested model has lane versions.
    #[inline(always)]
    pub fn sample_r<R: Real>(
        &self,
        sp: &ShadingPointR<R>,
        wi: Vector3<R>,
        u1: R,
        u2: Vector2<R>,
    ) -> BsdfSampleR<R> {
        self.sample_with(&Lanes, sp, wi, u1, u2)
    }

    #[inline(always)]
    fn eval_pdf_with<R: Real, N: Nested<R>>(
        &self,
        n: &N,
        sp: &ShadingPointR<R>,
        wi: Vector3<R>,
        wo: Vector3<R>,
    ) -> (Vector3<R>, R) {
        let p = self.frame_r(sp, wi);
        perturbed::eval_pdf(n, &self.nested, &p, self.options, sp, wi, wo)
    }

    #[inline(always)]
    fn sample_with<R: Real, N: Nested<R>>(
        &self,
        n: &N,
        sp: &ShadingPointR<R>,
        wi: Vector3<R>,
        u1: R,
        u2: Vector2<R>,
    ) -> BsdfSampleR<R> {
        let p = self.frame_r(sp, wi);
        perturbed::sample(n, &self.nested, &p, self.options, sp, wi, u1, u2)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::microfacet::MicrofacetType;
    use crate::perturbed::shadow_terminator_1 as shadow_terminator;
    use crate::testing::*;
    use crate::MicrofacetDistribution;
    use crate::{Diffuse, RoughConductor};

    /// A normal map that tilts every normal by about 27° (constant colour).
    fn tilted(nested: Bsdf, options: PerturbOptions) -> Bsdf {
        let n = Vec3::new(0.3, -0.35, 0.9).normalize();
        Bsdf::NormalMap(NormalMap::new(
            Texture::Constant((n + Vec3::ONE) * 0.5),
            nested,
            options,
        ))
    }

    fn nested_models() -> Vec<(&'static str, Bsdf)> {
        let d = MicrofacetDistribution::new(MicrofacetType::Ggx, 0.3, 0.3, true);
        vec![
            ("diffuse", Bsdf::Diffuse(Diffuse::new(Spectrum::splat(0.8)))),
            (
                "roughconductor",
                Bsdf::RoughConductor(RoughConductor::new(
                    d,
                    Spectrum::ZERO,
                    Spectrum::ONE,
                    Spectrum::ONE,
                )),
            ),
        ]
    }

    /// Sampling matches eval/pdf in the perturbed frame, with and without the shadowing
    /// term and the flip, from directions on both sides of the tilted normal.
    #[test]
    fn chi2_and_consistency() {
        for (name, nested) in nested_models() {
            for options in [
                PerturbOptions::default(),
                PerturbOptions {
                    flip_invalid_normals: false,
                    use_shadowing_function: false,
                },
            ] {
                let b = tilted(nested.clone(), options);
                for wi in incident_directions(false) {
                    let what = format!("normalmap {name} {options:?}");
                    assert_chi2(&what, &b, wi, Zoom::SPHERE, 200_000);
                    check_consistency(&what, &b, wi, 10_000, 2e-3);
                    assert_albedo_unbiased(&what, &b, wi, 200_000, 0.0);
                }
            }
        }
    }

    /// No light leaks: wo below the surface gives nothing, even where the tilted normal
    /// would let the nested BSDF see it above its own horizon.
    #[test]
    fn no_leaks_below_the_surface() {
        let b = tilted(
            Bsdf::Diffuse(Diffuse::new(Spectrum::ONE)),
            PerturbOptions::default(),
        );
        let wi = dir(0.7, 0.4);
        for_each_sample(20_000, 7, |u, u1| {
            let wo = dir(-u.x, 6.28 * u.y);
            assert_eq!(b.eval(&SP, wi, wo), Spectrum::ZERO);
            assert_eq!(b.pdf(&SP, wi, wo), 0.0);
            if let Some(s) = b.sample(&SP, wi, u1, u) {
                assert!(s.wo.z > 0.0, "{s:?}");
            }
        });
    }

    /// A flat normal map ((0.5, 0.5, 1) = +z) is the nested BSDF itself, without the
    /// shadowing term (tan θ(n) = 0 makes it 1).
    #[test]
    fn flat_map_is_the_nested_bsdf() {
        let nested = Bsdf::Diffuse(Diffuse::new(Spectrum::splat(0.6)));
        let b = Bsdf::NormalMap(NormalMap::new(
            Texture::Constant(Spectrum::new(0.5, 0.5, 1.0)),
            nested.clone(),
            PerturbOptions::default(),
        ));
        for_each_sample(1000, 3, |u, u1| {
            let wi = dir(0.05 + 0.95 * u1, 1.0);
            let wo = dir(u.x, 6.28 * u.y);
            let (a, e) = (b.eval(&SP, wi, wo), nested.eval(&SP, wi, wo));
            assert!((a - e).abs().max_element() < 1e-6, "{a} vs {e}");
        });
        assert_eq!(shadow_terminator(Vec3::Z, dir(0.3, 0.0)), 1.0);
    }

    /// Mitsuba's flip: a perturbed normal facing away from wi becomes (−x, −y, z).
    #[test]
    fn invalid_normals_are_flipped() {
        let n = Vec3::new(0.8, 0.0, 0.6);
        let m = NormalMap::new(
            Texture::Constant((n + Vec3::ONE) * 0.5),
            Bsdf::Diffuse(Diffuse::new(Spectrum::ONE)),
            PerturbOptions::default(),
        );
        // wi grazing from −x: wi · n < 0.
        let wi = Vec3::new(-0.99, 0.0, 0.141).normalize();
        let f = m.frame(&SP, wi).unwrap();
        assert!(
            (f.n - Vec3::new(-0.8, 0.0, 0.6)).length() < 1e-5,
            "{:?}",
            f.n
        );
        let f = m.frame(&SP, dir(0.9, 0.0)).unwrap();
        assert!((f.n - n).length() < 1e-5);
    }
}
