//! Bump mapping: Mitsuba's `bumpmap` adapter (`src/bsdfs/bumpmap.cpp`, 3.9.1).
//!
//! ```xml
//! <bsdf type="bumpmap">
//!     <texture name="height" type="bitmap">     <!-- any name -->
//!         <boolean name="raw" value="true"/>
//!         <string name="filename" value="bumps.png"/>
//!     </texture>
//!     <float name="scale" value="0.5"/>          <!-- default 1 -->
//!     <bsdf type="roughplastic"/>
//! </bsdf>
//! ```
//! The height h(u, v) = scale · texture moves the surface along its shading normal n:
//! ∂p/∂u' = ∂p/∂u + n (∂h/∂u − n·∂p/∂u), likewise for v, and the bumped normal is
//! normalize(∂p/∂u' × ∂p/∂v'), turned to the side of the geometric normal, then flipped as
//! `normalmap` does when it faces away from `wi`. ∂h/∂u is the texture's `eval_1_grad`
//! (zero for nearest-neighbour lookups). The frame's s is ∂p/∂u made orthogonal to the new
//! normal.
//!
//! Everything here is in the local shading frame. Mitsuba 3.9.1 makes s from the
//! **world-space** ∂p/∂u against the local normal (a mixed-frame expression that only turns
//! the frame about its normal); radia uses the local ∂p/∂u, which matters only for
//! anisotropic nested models.

use crate::nested::{Lanes, Nested, OnePath, Want};
use crate::perturbed::{self, frame_from, PerturbOptions, Perturbed};
use crate::{Bsdf, BsdfSample, BsdfSampleR, LobeFlags, ShadingPoint, ShadingPointR, Texture};
use glam::{Vec2, Vec3};
use radia_math::real::{Real, Vector2, Vector3};
use radia_math::{Frame, Spectrum};

#[derive(Clone, Debug)]
pub struct BumpMap {
    /// The height field; its `eval_1_grad` must exist (a bitmap or a constant).
    pub height: Texture,
    pub scale: f32,
    pub nested: Box<Bsdf>,
    pub options: PerturbOptions,
}

impl BumpMap {
    pub fn new(height: Texture, scale: f32, nested: Bsdf, options: PerturbOptions) -> Self {
        Self {
            height,
            scale,
            nested: Box::new(nested),
            options,
        }
    }

    pub fn flags(&self) -> LobeFlags {
        self.nested.flags()
    }

    /// The bumped frame relative to the shading frame (Mitsuba's `frame()`).
    #[inline]
    pub(crate) fn frame(&self, sp: &ShadingPoint, wi: Vec3) -> Option<Frame> {
        self.frame_r::<f32>(&sp.into(), wi.into())?.one_path()
    }

    /// [`BumpMap::frame`] over any [`Real`]; None for a height without a gradient.
    #[inline(always)]
    fn frame_r<R: Real>(&self, sp: &ShadingPointR<R>, wi: Vector3<R>) -> Option<Perturbed<R>> {
        let grad = self.height.eval_1_grad_r(sp)?;
        let scale = R::splat(self.scale);
        let (gu, gv) = (grad.x * scale, grad.y * scale);
        let z = Vector3::splat(Vec3::Z);
        let dp_du = sp.dp_du + z * (gu - sp.dp_du.z);
        let dp_dv = sp.dp_dv + z * (gv - sp.dp_dv.z);
        let n = dp_du.cross(dp_dv).normalize();
        let back = sp.n.dot(n).less(R::zero());
        let n = Vector3::new(
            n.x.negate_where(back),
            n.y.negate_where(back),
            n.z.negate_where(back),
        );
        Some(frame_from(self.options.flip(n, wi), sp.dp_du))
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

    /// [`BumpMap::eval`] and [`BumpMap::pdf`] at once (the frame made once).
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
        match self.frame_r(sp, wi) {
            Some(p) => perturbed::eval_pdf(n, &self.nested, &p, self.options, sp, wi, wo),
            None => (Vector3::zero(), R::zero()),
        }
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
        match self.frame_r(sp, wi) {
            Some(p) => perturbed::sample(n, &self.nested, &p, self.options, sp, wi, u1, u2),
            None => BsdfSampleR::none(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::*;
    use crate::{Bitmap, Diffuse, FilterType, UvTransform, WrapMode};

    /// A 2×2 height field, bilinear: at uv (0, 0) (the SP of the test harness) its gradient
    /// is (−1.6, 0.8) per unit of uv.
    fn heights() -> Texture {
        Bitmap::new(
            2,
            2,
            1,
            vec![0.0, 0.4, 0.2, 1.0],
            FilterType::Bilinear,
            WrapMode::Repeat,
            UvTransform::IDENTITY,
        )
        .unwrap()
        .into()
    }

    #[test]
    fn bumped_normal_follows_the_gradient() {
        let h = heights();
        let g = h.eval_1_grad(&SP).unwrap();
        let b = BumpMap::new(
            h,
            0.5,
            Bsdf::Diffuse(Diffuse::new(Spectrum::ONE)),
            PerturbOptions::default(),
        );
        let f = b.frame(&SP, dir(0.9, 0.0)).unwrap();
        // dp/du' = (1, 0, gu), dp/dv' = (0, 1, gv): n ∝ (−gu, −gv, 1).
        let want = Vec3::new(-0.5 * g.x, -0.5 * g.y, 1.0).normalize();
        assert!((f.n - want).length() < 1e-5, "{:?} vs {want}", f.n);
        assert!(g.length() > 0.1);
        // Zero scale: the shading frame itself.
        let flat = BumpMap::new(
            heights(),
            0.0,
            Bsdf::Diffuse(Diffuse::new(Spectrum::ONE)),
            PerturbOptions::default(),
        );
        assert!((flat.frame(&SP, dir(0.9, 0.0)).unwrap().n - Vec3::Z).length() < 1e-6);
    }

    #[test]
    fn chi2_and_consistency() {
        let b = Bsdf::BumpMap(BumpMap::new(
            heights(),
            0.5,
            Bsdf::Diffuse(Diffuse::new(Spectrum::splat(0.8))),
            PerturbOptions::default(),
        ));
        for wi in incident_directions(false) {
            assert_chi2("bumpmap", &b, wi, Zoom::SPHERE, 200_000);
            check_consistency("bumpmap", &b, wi, 10_000, 2e-3);
            assert_albedo_unbiased("bumpmap", &b, wi, 200_000, 0.0);
        }
    }
}
