//! Smooth conductor: Mitsuba's `conductor` plugin (`src/bsdfs/conductor.cpp`).
//!
//! ```xml
//! <bsdf type="conductor">
//!     <string name="material" value="Au"/>   <!-- or eta/k; default "none": F = 1 -->
//!     <rgb name="specular_reflectance" value="1"/>
//! </bsdf>
//! ```
//! A perfect mirror weighted by the exact conductor Fresnel reflectance of the complex IOR
//! η + ik. One-sided: nothing from below the surface. A single delta lobe: `sample` returns
//! pdf 1 and the weight F(cos θi)·specular_reflectance; `eval` and `pdf` are 0.

use crate::fresnel::{fresnel_conductor, reflect};
use crate::{BsdfSample, LobeFlags, ShadingPoint, Texture};
use glam::{Vec2, Vec3};
use radia_math::Spectrum;

#[derive(Clone, Debug)]
pub struct Conductor {
    /// Real part of the relative IOR (per channel).
    pub eta: Spectrum,
    /// Imaginary part (absorption coefficient).
    pub k: Spectrum,
    pub specular_reflectance: Texture,
}

impl Conductor {
    pub fn new(eta: Spectrum, k: Spectrum, specular_reflectance: impl Into<Texture>) -> Self {
        Self {
            eta,
            k,
            specular_reflectance: specular_reflectance.into(),
        }
    }

    /// Mitsuba's `material="none"`: eta 0, k 1, a perfect mirror with F = 1.
    pub fn perfect_mirror() -> Self {
        Self::new(Spectrum::ZERO, Spectrum::ONE, Spectrum::ONE)
    }

    pub fn flags(&self) -> LobeFlags {
        LobeFlags::DELTA_REFLECTION
    }

    #[inline]
    pub fn eval(&self, _sp: &ShadingPoint, _wi: Vec3, _wo: Vec3) -> Spectrum {
        Spectrum::ZERO
    }

    #[inline]
    pub fn pdf(&self, _sp: &ShadingPoint, _wi: Vec3, _wo: Vec3) -> f32 {
        0.0
    }

    #[inline]
    pub fn sample(&self, sp: &ShadingPoint, wi: Vec3, _u1: f32, _u2: Vec2) -> Option<BsdfSample> {
        if !(wi.z > 0.0) {
            return None;
        }
        let f = fresnel_conductor(wi.z, self.eta, self.k);
        Some(BsdfSample {
            wo: reflect(wi),
            weight: self.specular_reflectance.eval(sp) * f,
            pdf: 1.0,
            eta: 1.0,
            lobe: LobeFlags::DELTA_REFLECTION,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::ior::lookup_conductor;
    use crate::testing::*;
    use crate::Bsdf;

    fn gold() -> Conductor {
        let p = lookup_conductor("Au").unwrap();
        Conductor::new(p.eta.into(), p.k.into(), Spectrum::ONE)
    }

    /// Delta lobe: the sample is the mirror direction with the Fresnel weight, analytically.
    #[test]
    fn mirror_with_fresnel_weight() {
        let b = Bsdf::Conductor(gold());
        for wi in incident_directions(false) {
            let s = b.sample(&SP, wi, 0.3, Vec2::new(0.1, 0.9)).unwrap();
            assert!((s.wo - Vec3::new(-wi.x, -wi.y, wi.z)).length() < 1e-7);
            let p = lookup_conductor("Au").unwrap();
            assert_eq!(s.weight, fresnel_conductor(wi.z, p.eta.into(), p.k.into()));
            assert_eq!(
                (s.pdf, s.eta, s.lobe),
                (1.0, 1.0, LobeFlags::DELTA_REFLECTION)
            );
            assert!(s.weight.max_element() <= 1.0);
            check_consistency("conductor", &b, wi, 100, 0.0);
        }
        // Gold reflects red more than blue at normal incidence.
        let s = b.sample(&SP, Vec3::Z, 0.0, Vec2::ZERO).unwrap();
        assert!(s.weight.x > 0.9 && s.weight.z < 0.5, "{}", s.weight);
        // material="none" with a tint: exactly the tint.
        let m = Bsdf::Conductor(Conductor::new(
            Spectrum::ZERO,
            Spectrum::ONE,
            Spectrum::new(0.2, 0.5, 1.0),
        ));
        let s = m.sample(&SP, dir(0.01, 0.0), 0.0, Vec2::ZERO).unwrap();
        assert!(
            (s.weight - Spectrum::new(0.2, 0.5, 1.0))
                .abs()
                .max_element()
                < 1e-6
        );
    }

    #[test]
    fn one_sided_and_zero_eval() {
        let b = Bsdf::Conductor(gold());
        assert!(b
            .sample(&SP, dir(-0.5, 0.0), 0.5, Vec2::splat(0.5))
            .is_none());
        assert!(b
            .sample(&SP, dir(0.0, 0.0), 0.5, Vec2::splat(0.5))
            .is_none());
        assert_eq!(
            b.eval(&SP, dir(0.5, 0.0), dir(0.5, 3.14159)),
            Spectrum::ZERO
        );
        assert_eq!(b.pdf(&SP, dir(0.5, 0.0), dir(0.5, 3.14159)), 0.0);
    }
}
