//! The models written over [`Real`] give in every lane of `f32x16` bit for bit what their
//! `f32` instantiation gives for that lane's values, and the one-path `eval`, `pdf`,
//! `eval_pdf` and `sample` are that instantiation (the packet loop's images are the
//! one-path loop's only if both hold).

use crate::microfacet::{RoughnessTextures, Shadowing};
use crate::tests::{log_uniform, random_bsdf, random_direction, random_u};
use crate::*;
use radia_math::real::{f32x16, Real, Vector2, Vector3};
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg32;

/// A texture: a constant, a 2×2 bitmap (one or three channels) or a checkerboard, with
/// values from `value`.
pub(crate) fn random_texture(rng: &mut Pcg32, mut value: impl FnMut(&mut Pcg32) -> f32) -> Texture {
    match rng.random_range(0..4) {
        0 => Texture::from(value(rng)),
        1 => {
            let channels = if rng.random() { 1 } else { 3 };
            let data: Vec<f32> = (0..4 * channels).map(|_| value(rng)).collect();
            Bitmap::new(
                2,
                2,
                channels,
                data,
                if rng.random() {
                    FilterType::Bilinear
                } else {
                    FilterType::Nearest
                },
                WrapMode::Repeat,
                UvTransform::IDENTITY,
            )
            .expect("valid bitmap")
            .into()
        }
        2 => Checkerboard::new(value(rng), value(rng), UvTransform::IDENTITY).into(),
        _ => Texture::from(Spectrum::new(value(rng), value(rng), value(rng))),
    }
}

/// α from its extremes: the clamp 10⁻⁴, next to it, smooth, rough, 1 and a little below.
pub(crate) fn random_alpha(rng: &mut Pcg32) -> f32 {
    match rng.random_range(0..6) {
        0 => 0.0,
        1 => 1e-4,
        2 => 1.0,
        3 => 1.0 - f32::EPSILON,
        _ => log_uniform(rng, 1e-4, 1.0),
    }
}

/// A relative IOR, often next to 1 (where refraction half vectors cancel) or exactly 1.
pub(crate) fn random_eta(rng: &mut Pcg32) -> (f32, f32) {
    let eta = match rng.random_range(0..6) {
        0 => 1.0,
        1 => 1.0001,
        2 => 1.0 + f32::EPSILON,
        _ => 1.0001 + rng.random::<f32>() * 2.9999,
    };
    if rng.random() {
        (eta, 1.0)
    } else {
        (1.0, eta)
    }
}

/// [`random_bsdf`]'s models, and each lane model with parameters at their extremes:
/// textured and anisotropic roughness, IORs next to 1, textured reflectances.
pub(crate) fn random_lane_bsdf(rng: &mut Pcg32, depth: u32) -> Bsdf {
    if rng.random() {
        return random_bsdf(rng, depth);
    }
    if depth > 0 && rng.random_range(0..8) == 0 {
        // Two sides from this generator, reflective ones as the loader allows.
        let mut side = || loop {
            let b = random_lane_bsdf(rng, depth - 1);
            if b.has_r() && !b.flags().intersects(LobeFlags::TRANSMISSION) {
                return b;
            }
        };
        return Bsdf::TwoSided(TwoSided::new(side(), side()));
    }
    let kind = if rng.random() {
        MicrofacetType::Beckmann
    } else {
        MicrofacetType::Ggx
    };
    let (au, av) = (random_alpha(rng), random_alpha(rng));
    let av = if rng.random() { au } else { av };
    let dist = MicrofacetDistribution::new(kind, au, av, rng.random_range(0..4) != 0);
    let roughness = rng.random::<bool>().then(|| {
        let alpha = |rng: &mut Pcg32| random_alpha(rng);
        let u = random_texture(rng, alpha);
        let v = if rng.random() {
            u.clone()
        } else {
            random_texture(rng, alpha)
        };
        RoughnessTextures {
            alpha_u: u,
            alpha_v: v,
        }
    });
    let shadowing = if rng.random() {
        Shadowing::Separable
    } else {
        Shadowing::HeightCorrelated
    };
    let color = |rng: &mut Pcg32| random_texture(rng, |r| r.random());
    let presets = crate::ior::CONDUCTOR_PRESETS;
    let preset = presets[rng.random_range(0..presets.len())];
    let (int_ior, ext_ior) = random_eta(rng);
    let exponent = match rng.random_range(0..4) {
        0 => 0.0,
        1 => 1e5,
        _ => log_uniform(rng, 1e-3, 1e4),
    };
    match rng.random_range(0..10) {
        7 => Bsdf::Phong(Phong::new(color(rng), color(rng), exponent)),
        8 => Bsdf::BlinnPhong(BlinnPhong::new(color(rng), color(rng), exponent)),
        9 => {
            let fresnel = if rng.random() {
                CookTorranceFresnel::Schlick { f0: color(rng) }
            } else {
                CookTorranceFresnel::MetallicRoughness {
                    base_color: color(rng),
                    metallic: random_texture(rng, |r| r.random_range(-0.1..1.1)),
                }
            };
            let m = CookTorrance::new(dist, shadowing, fresnel);
            Bsdf::CookTorrance(if rng.random() {
                m.with_roughness_texture(random_texture(rng, |r| r.random_range(-0.1..1.1)))
            } else {
                m
            })
        }
        // Its tables take 10⁶ normals to build: rarer.
        6 if rng.random_range(0..3) == 0 => Bsdf::RoughPlastic(RoughPlastic::new(
            kind,
            au,
            rng.random(),
            int_ior,
            ext_ior,
            color(rng),
            color(rng),
            rng.random(),
        )),
        5 => Bsdf::Plastic(Plastic::new(
            int_ior,
            ext_ior,
            color(rng),
            color(rng),
            rng.random(),
        )),
        4 => {
            let mut m = RoughDielectric::new(dist, int_ior, ext_ior).with_roughness(roughness);
            m.specular_reflectance = color(rng);
            m.specular_transmittance = color(rng);
            Bsdf::RoughDielectric(m)
        }
        0 => Bsdf::RoughConductor(
            RoughConductor::new(dist, preset.eta.into(), preset.k.into(), color(rng))
                .with_roughness(roughness)
                .with_shadowing(shadowing),
        ),
        1 => Bsdf::Conductor(Conductor::new(
            preset.eta.into(),
            preset.k.into(),
            color(rng),
        )),
        2 => {
            let mut m = Dielectric::new(int_ior, ext_ior);
            m.specular_reflectance = color(rng);
            m.specular_transmittance = color(rng);
            Bsdf::Dielectric(m)
        }
        _ => {
            let mut m = ThinDielectric::new(int_ior, ext_ior);
            m.specular_reflectance = color(rng);
            m.specular_transmittance = color(rng);
            Bsdf::ThinDielectric(m)
        }
    }
}

/// Directions as [`random_direction`] makes them, and ones with exactly zero components.
pub(crate) fn direction(rng: &mut Pcg32) -> Vec3 {
    match rng.random_range(0..12) {
        0 => Vec3::new(0.0, 0.0, if rng.random() { 1.0 } else { -1.0 }),
        1 => Vec3::new(if rng.random() { 1.0 } else { -1.0 }, 0.0, 0.0),
        2 => {
            let z: f32 = rng.random_range(-1.0..1.0);
            Vec3::new(0.0, (1.0 - z * z).sqrt(), z)
        }
        _ => random_direction(rng),
    }
}

pub(crate) fn same(a: f32, b: f32) -> bool {
    a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan())
}

pub(crate) fn same3(a: Vec3, b: Vec3) -> bool {
    same(a.x, b.x) && same(a.y, b.y) && same(a.z, b.z)
}

#[test]
fn lanes_are_the_one_path_bit_for_bit() {
    let mut rng = Pcg32::seed_from_u64(0x1a9e5);
    let mut models = 0;
    let mut kinds = std::collections::BTreeMap::<String, usize>::new();
    // How often the comparisons had something to compare: lanes with a sample, with a
    // nonzero value, with a positive density.
    let (mut lanes, mut sampled) = (0usize, 0usize);
    let (mut smooth, mut nonzero, mut dense) = (0usize, 0usize, 0usize);
    while models < 600 {
        let b = random_lane_bsdf(&mut rng, 2);
        if !b.has_r() {
            continue;
        }
        models += 1;
        let kind = format!("{b:?}");
        *kinds
            .entry(kind[..kind.find('(').unwrap_or(kind.len())].to_string())
            .or_insert(0) += 1;
        for _ in 0..8 {
            let mut sp = [ShadingPoint::default(); 16];
            let (mut wi, mut wo) = ([Vec3::ZERO; 16], [Vec3::ZERO; 16]);
            let (mut u1, mut u2) = ([0.0f32; 16], [Vec2::ZERO; 16]);
            for k in 0..16 {
                let uv = Vec2::new(rng.random_range(-1.0..2.0), rng.random_range(-1.0..2.0));
                sp[k] = ShadingPoint::at_uv(uv);
                wi[k] = direction(&mut rng);
                wo[k] = match rng.random_range(0..5) {
                    0 => -wi[k],
                    1 => Vec3::new(-wi[k].x, -wi[k].y, wi[k].z),
                    2 => wi[k],
                    _ => direction(&mut rng),
                };
                u1[k] = random_u(&mut rng);
                u2[k] = Vec2::new(random_u(&mut rng), random_u(&mut rng));
            }
            let spr = ShadingPointR {
                uv: Vector2::from_fn(|k| sp[k].uv),
                dp_du: Vector3::from_fn(|k| sp[k].dp_du),
                dp_dv: Vector3::from_fn(|k| sp[k].dp_dv),
                n: Vector3::from_fn(|k| sp[k].n),
            };
            let (wi_r, wo_r) = (
                Vector3::<f32x16>::from_fn(|k| wi[k]),
                Vector3::<f32x16>::from_fn(|k| wo[k]),
            );
            let (u1_r, u2_r) = (f32x16::from_fn(|k| u1[k]), Vector2::from_fn(|k| u2[k]));
            let (f, pdf) = b.eval_pdf_r(&spr, wi_r, wo_r).expect("a lane model");
            let s = b.sample_r(&spr, wi_r, u1_r, u2_r).expect("a lane model");
            for k in 0..16 {
                let at = format!(
                    "{b:?}\nuv {} wi {:?} wo {:?} u1 {:?} u2 {:?}",
                    sp[k].uv, wi[k], wo[k], u1[k], u2[k]
                );
                let spk = ShadingPointR::<f32>::from(&sp[k]);
                let (fk, pdfk) = b
                    .eval_pdf_r::<f32>(&spk, wi[k].into(), wo[k].into())
                    .expect("a lane model");
                assert!(
                    same3(f.lane(k), fk.into()) && same(pdf.lane(k), pdfk),
                    "eval_pdf: lanes ({}, {}), f32 ({:?}, {pdfk})\n{at}",
                    f.lane(k),
                    pdf.lane(k),
                    fk
                );
                let sk = b
                    .sample_r::<f32>(&spk, wi[k].into(), u1[k], u2[k].into())
                    .expect("a lane model");
                let valid = s.valid.bits() & (1 << k) != 0;
                lanes += 1;
                sampled += valid as usize;
                if b.flags().has_smooth() {
                    smooth += 1;
                    nonzero += (fk != Vector3::zero()) as usize;
                    dense += (pdfk > 0.0) as usize;
                }
                assert_eq!(valid, sk.valid, "sample validity\n{at}");
                // Elsewhere the fields are meaningless (and a model may skip computing them
                // when no lane has a sample).
                if valid {
                    let delta = s.delta.bits() & (1 << k) != 0;
                    assert!(
                        same3(s.wo.lane(k), sk.wo.into())
                            && same3(s.weight.lane(k), sk.weight.into())
                            && same(s.pdf.lane(k), sk.pdf)
                            && same(s.eta.lane(k), sk.eta)
                            && delta == sk.delta,
                        "sample: lanes ({}, {}, {}, {}, {delta}), f32 {sk:?}\n{at}",
                        s.wo.lane(k),
                        s.weight.lane(k),
                        s.pdf.lane(k),
                        s.eta.lane(k),
                    );
                }

                // The one-path functions are the f32 instantiation.
                let (fo, pdfo) = b.eval_pdf(&sp[k], wi[k], wo[k]);
                assert!(
                    same3(fo, fk.into()) && same(pdfo, pdfk),
                    "one-path eval_pdf ({fo}, {pdfo})\n{at}"
                );
                assert!(
                    same3(b.eval(&sp[k], wi[k], wo[k]), fo),
                    "one-path eval\n{at}"
                );
                assert!(
                    same(b.pdf(&sp[k], wi[k], wo[k]), pdfo),
                    "one-path pdf\n{at}"
                );
                let so = b.sample(&sp[k], wi[k], u1[k], u2[k]);
                assert_eq!(so.is_some(), sk.valid, "one-path sample\n{at}");
                if let Some(so) = so {
                    assert!(
                        same3(so.wo, sk.wo.into())
                            && same3(so.weight, sk.weight.into())
                            && same(so.pdf, sk.pdf)
                            && same(so.eta, sk.eta)
                            && so.lobe.is_delta() == sk.delta,
                        "one-path sample {so:?}\n{at}"
                    );
                }
            }
        }
    }
    println!("{models} models: {kinds:?}; {lanes} lanes, {sampled} sampled");
    // Every lane model was drawn, many times.
    for kind in [
        "Diffuse",
        "Conductor",
        "RoughConductor",
        "Dielectric",
        "ThinDielectric",
        "RoughDielectric",
        "Plastic",
        "RoughPlastic",
        "TwoSided",
        "Phong",
        "BlinnPhong",
        "CookTorrance",
    ] {
        assert!(kinds.get(kind).copied().unwrap_or(0) >= 10, "{kinds:?}");
    }
    // Not a vacuous pass: many lanes sample and evaluate to something (directions below
    // one-sided models and mirror pairs give nothing).
    assert!(
        sampled * 4 > lanes && nonzero * 8 > smooth && dense * 8 > smooth,
        "{lanes} lanes: {sampled} sampled; of {smooth} with smooth lobes {nonzero} nonzero, \
         {dense} with a density"
    );
}
