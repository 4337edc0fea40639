//! What the AOV integrator asks of a BSDF besides scattering: the diffuse reflectance that
//! denoisers take as "albedo" (Mitsuba's `BSDF::eval_diffuse_reflectance`) and the shading
//! frame after any perturbation (Mitsuba's `BSDF::sh_frame`). Neither is on the hot path.

use crate::{Bsdf, ShadingPoint};
use glam::Vec3;
use radia_math::{Frame, Spectrum, PI};

impl Bsdf {
    /// The albedo at `sp` seen from `wi` (local shading frame), as Mitsuba 3.9.1 defines it:
    ///
    /// * `diffuse`: its reflectance (`src/bsdfs/diffuse.cpp`); `plastic`, `roughplastic`:
    ///   their `diffuse_reflectance` (`plastic.cpp`, `roughplastic.cpp`). radia's own `phong`
    ///   and `blinnphong` follow plastic: their diffuse reflectance `kd`. `principled`,
    ///   `principledthin`: their `base_color` (`principled.cpp`, `principledthin.cpp`).
    /// * `blendbsdf`: (1 − w)·first + w·second; `twosided`: the side `wi` is on, queried from
    ///   the front (`twosided.cpp`); `normalmap`, `bumpmap`: the nested BSDF at the
    ///   unperturbed point (`normalmap.cpp`, `bumpmap.cpp`).
    /// * every other model: the base class's default (`src/render/bsdf.cpp`),
    ///   π · eval(wi, wo = n), which is 0 for the smooth conductor and dielectrics.
    pub fn diffuse_reflectance(&self, sp: &ShadingPoint, wi: Vec3) -> Spectrum {
        match self {
            Bsdf::Diffuse(m) => m.reflectance.eval(sp),
            Bsdf::Plastic(m) => m.diffuse_reflectance.eval(sp),
            Bsdf::RoughPlastic(m) => m.diffuse_reflectance.eval(sp),
            Bsdf::Phong(m) => m.diffuse_reflectance.eval(sp),
            Bsdf::BlinnPhong(m) => m.diffuse_reflectance.eval(sp),
            // `principled.cpp`: its base colour.
            Bsdf::Principled(m) => m.base_color.eval(sp),
            Bsdf::PrincipledThin(m) => m.base_color.eval(sp),
            Bsdf::Blend(m) => {
                let w = m.weight_at(sp);
                m.bsdfs[0].diffuse_reflectance(sp, wi) * (1.0 - w)
                    + m.bsdfs[1].diffuse_reflectance(sp, wi) * w
            }
            Bsdf::TwoSided(m) => {
                if wi.z >= 0.0 {
                    m.sides[0].diffuse_reflectance(sp, wi)
                } else {
                    m.sides[1].diffuse_reflectance(sp, Vec3::new(wi.x, wi.y, -wi.z))
                }
            }
            Bsdf::NormalMap(m) => m.nested.diffuse_reflectance(sp, wi),
            Bsdf::BumpMap(m) => m.nested.diffuse_reflectance(sp, wi),
            // `mask.cpp`: the nested model's, not scaled by the opacity.
            Bsdf::Mask(m) => m.nested.diffuse_reflectance(sp, wi),
            other => other.eval(sp, wi, Vec3::Z) * PI,
        }
    }

    /// The shading frame the BSDF shades in, relative to the surface's own (identity unless
    /// a `normalmap` or `bumpmap` is the outermost model; as Mitsuba, an adapter nested
    /// inside `twosided` or `blendbsdf` does not show). `None` where the perturbed frame is
    /// degenerate (the adapter then reflects nothing).
    pub fn perturbed_frame(&self, sp: &ShadingPoint, wi: Vec3) -> Option<Frame> {
        match self {
            Bsdf::NormalMap(m) => m.frame(sp, wi),
            Bsdf::BumpMap(m) => m.frame(sp, wi),
            _ => Some(Frame {
                s: Vec3::X,
                t: Vec3::Y,
                n: Vec3::Z,
            }),
        }
    }
}

#[cfg(test)]
mod tests {
    use crate::{
        Bsdf, Conductor, Diffuse, MicrofacetDistribution, MicrofacetType, Plastic, RoughConductor,
        ShadingPoint, TwoSided,
    };
    use glam::{Vec2, Vec3};
    use radia_math::{Spectrum, PI};

    #[test]
    fn albedo_follows_mitsuba() {
        let sp = ShadingPoint::at_uv(Vec2::splat(0.5));
        let wi = Vec3::new(0.3, 0.1, 0.9).normalize();
        let red = Spectrum::new(0.8, 0.2, 0.1);
        let d = Bsdf::Diffuse(Diffuse::new(red));
        assert_eq!(d.diffuse_reflectance(&sp, wi), red);
        // twosided: the back side seen from below.
        let ts = Bsdf::TwoSided(TwoSided::new(
            d.clone(),
            Bsdf::Diffuse(Diffuse::new(Spectrum::ONE)),
        ));
        assert_eq!(ts.diffuse_reflectance(&sp, wi), red);
        assert_eq!(ts.diffuse_reflectance(&sp, -wi), Spectrum::ONE);
        // The default: π·eval(wi, n), zero for a smooth conductor, f·π for a rough one.
        let c = Bsdf::Conductor(Conductor::new(Spectrum::ZERO, Spectrum::ONE, Spectrum::ONE));
        assert_eq!(c.diffuse_reflectance(&sp, wi), Spectrum::ZERO);
        let rc = Bsdf::RoughConductor(RoughConductor::new(
            MicrofacetDistribution::new(MicrofacetType::Beckmann, 0.3, 0.3, true),
            Spectrum::ZERO,
            Spectrum::ONE,
            Spectrum::ONE,
        ));
        let expect = rc.eval(&sp, wi, Vec3::Z) * PI;
        assert!(expect.max_element() > 0.0);
        assert_eq!(rc.diffuse_reflectance(&sp, wi), expect);
        let p = Bsdf::Plastic(Plastic::new(
            1.5,
            1.0,
            Spectrum::splat(0.5),
            Spectrum::ONE,
            false,
        ));
        assert_eq!(p.diffuse_reflectance(&sp, wi), Spectrum::splat(0.5));
    }
}
