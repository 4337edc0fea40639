//! The second set of models written over [`Real`] (the principled models, the blend, the
//! normal and bump maps, mask and null) against their `f32` instantiation, as
//! `lanes_test.rs` does for the first: each lane of `f32x16` bit for bit, and the one-path
//! `eval`, `pdf`, `eval_pdf` and `sample` (lobe flags included) that instantiation.

use crate::lanes_test::{
    direction, random_alpha, random_eta, random_lane_bsdf, random_texture, same, same3,
};
use crate::tests::{log_uniform, random_u};
use crate::*;
use radia_math::real::{f32x16, Real, Vector2, Vector3};
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg32;

/// A weight in [0, 1], often at its ends, sometimes just outside.
fn random_weight(rng: &mut Pcg32) -> f32 {
    match rng.random_range(0..8) {
        0 => 0.0,
        1 => 1.0,
        2 => 1.0 - f32::EPSILON,
        3 => f32::EPSILON,
        4 => rng.random_range(-0.1..1.1),
        _ => rng.random(),
    }
}

/// An optional weight: absent (Mitsuba's `m_has_*` false), or a random texture of weights.
fn optional_weight(rng: &mut Pcg32) -> Option<Texture> {
    rng.random::<bool>()
        .then(|| random_texture(rng, random_weight))
}

/// A roughness from its extremes: 0, √10⁻⁴, 1, 1 − ε, anything between.
fn random_roughness(rng: &mut Pcg32) -> f32 {
    random_alpha(rng).sqrt()
}

/// A sampling rate: 1 (Mitsuba's default) mostly, sometimes 0 or anything up to 4.
fn random_rate(rng: &mut Pcg32) -> f32 {
    match rng.random_range(0..6) {
        0 => 0.0,
        1 => rng.random_range(0.0..4.0),
        _ => 1.0,
    }
}

/// An IOR: next to 1 (either side), 1 itself, or up to 4.
fn random_ior(rng: &mut Pcg32) -> f32 {
    let (i, e) = random_eta(rng);
    match rng.random_range(0..4) {
        0 => e / i,
        _ => i / e,
    }
}

pub(crate) fn random_principled(rng: &mut Pcg32) -> Bsdf {
    let colour = |rng: &mut Pcg32| random_texture(rng, random_weight);
    let mut m = Principled::new(colour(rng));
    m.roughness = random_texture(rng, random_roughness);
    m.anisotropic = optional_weight(rng);
    m.metallic = optional_weight(rng);
    m.spec_trans = optional_weight(rng);
    m.spec_tint = optional_weight(rng);
    m.sheen = optional_weight(rng);
    m.sheen_tint = optional_weight(rng);
    m.flatness = optional_weight(rng);
    m.clearcoat = optional_weight(rng);
    m.clearcoat_gloss = random_texture(rng, random_weight);
    if rng.random_range(0..4) == 0 {
        m.spec_srate = random_rate(rng);
        m.clearcoat_srate = random_rate(rng);
        m.diff_refl_srate = random_rate(rng);
    }
    let ior = if rng.random() {
        PrincipledIor::Eta(random_ior(rng))
    } else {
        PrincipledIor::Specular(random_weight(rng).max(0.0))
    };
    Bsdf::Principled(m.with_ior(ior))
}

pub(crate) fn random_principled_thin(rng: &mut Pcg32) -> Bsdf {
    let colour = |rng: &mut Pcg32| random_texture(rng, random_weight);
    let mut m = PrincipledThin::new(colour(rng));
    m.roughness = random_texture(rng, random_roughness);
    m.anisotropic = optional_weight(rng);
    m.spec_trans = optional_weight(rng);
    m.spec_tint = optional_weight(rng);
    m.sheen = optional_weight(rng);
    m.sheen_tint = optional_weight(rng);
    m.flatness = optional_weight(rng);
    m.diff_trans = rng
        .random::<bool>()
        .then(|| random_texture(rng, |r| 2.0 * random_weight(r)));
    m.eta = random_texture(rng, random_ior);
    if rng.random_range(0..4) == 0 {
        m.spec_refl_srate = random_rate(rng);
        m.spec_trans_srate = random_rate(rng);
        m.diff_refl_srate = random_rate(rng);
        m.diff_trans_srate = random_rate(rng);
    }
    Bsdf::PrincipledThin(m)
}

/// One of the models this file tests, with random parameters; those that nest others
/// (when `depth` > 0) nest any lane models.
fn random_model(rng: &mut Pcg32, depth: u32) -> Bsdf {
    let kinds = if depth > 0 { 7 } else { 3 };
    let options = |rng: &mut Pcg32| PerturbOptions {
        flip_invalid_normals: rng.random(),
        use_shadowing_function: rng.random(),
    };
    match rng.random_range(0..kinds) {
        0 => random_principled(rng),
        1 => random_principled_thin(rng),
        2 => Bsdf::Null(Null),
        3 => {
            let opacity = random_texture(rng, random_weight);
            let nested = random_nested(rng, depth - 1);
            Bsdf::Mask(match rng.random_range(0..3) {
                0 => Mask::with_cutoff(opacity, random_weight(rng), nested),
                _ => Mask::new(opacity, nested),
            })
        }
        4 => Bsdf::NormalMap(NormalMap::new(
            // Any colour: mid-grey (a zero normal), pure axes, tilts.
            random_texture(rng, |r| match r.random_range(0..4) {
                0 => 0.5,
                1 => 1.0,
                _ => r.random(),
            }),
            random_nested(rng, depth - 1),
            options(rng),
        )),
        5 => {
            // Heights as bitmaps (bilinear: a gradient; nearest: none), constants, and
            // checkerboards (no gradient at all: no frame).
            let height = random_texture(rng, |r| r.random_range(-1.0..1.0));
            let scale = match rng.random_range(0..4) {
                0 => 0.0,
                _ => log_uniform(rng, 1e-3, 1e3),
            };
            Bsdf::BumpMap(BumpMap::new(
                height,
                scale,
                random_nested(rng, depth - 1),
                options(rng),
            ))
        }
        _ => {
            let (first, second) = (random_nested(rng, depth - 1), random_nested(rng, depth - 1));
            Bsdf::Blend(if rng.random() {
                Blend::new(random_weight(rng), first, second)
            } else {
                Blend::textured(random_texture(rng, random_weight), first, second)
            })
        }
    }
}

/// Any model with lane versions: `lanes_test.rs`'s or this file's.
fn random_nested(rng: &mut Pcg32, depth: u32) -> Bsdf {
    loop {
        let b = if rng.random() {
            random_lane_bsdf(rng, 2)
        } else {
            random_model(rng, depth)
        };
        if b.has_r() {
            return b;
        }
    }
}

/// [`direction`]s, and rarely what a packet's idle lanes may hold: zero, NaN and infinite
/// vectors.
fn lane_direction(rng: &mut Pcg32) -> Vec3 {
    match rng.random_range(0..400) {
        0..4 => Vec3::ZERO,
        4 | 5 => Vec3::NAN,
        6 => Vec3::new(f32::INFINITY, 0.0, -f32::INFINITY),
        _ => direction(rng),
    }
}

/// A shading point at a random uv, with the parametrisation's tangents and the geometric
/// normal of a random (possibly skewed or degenerate) surface around the shading frame;
/// rarely an idle lane's NaN.
fn random_shading_point(rng: &mut Pcg32) -> ShadingPoint {
    if rng.random_range(0..200) == 0 {
        return ShadingPoint {
            uv: Vec2::NAN,
            dp_du: Vec3::NAN,
            dp_dv: Vec3::NAN,
            n: Vec3::NAN,
        };
    }
    let uv = match rng.random_range(0..100) {
        0 => Vec2::NAN,
        _ => Vec2::new(rng.random_range(-1.0..2.0), rng.random_range(-1.0..2.0)),
    };
    if rng.random_range(0..4) == 0 {
        return ShadingPoint::at_uv(uv);
    }
    let v = |rng: &mut Pcg32| {
        Vec3::new(
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
        ) * log_uniform(rng, 1e-3, 1e3)
    };
    let dp_du = match rng.random_range(0..6) {
        0 => Vec3::ZERO,
        1 => Vec3::Z,
        _ => v(rng),
    };
    let dp_dv = v(rng);
    let n = match rng.random_range(0..4) {
        0 => Vec3::Z,
        1 => -Vec3::Z,
        _ => direction(rng),
    };
    ShadingPoint {
        uv,
        dp_du,
        dp_dv,
        n,
    }
}

/// Counts of what the comparisons had to compare.
#[derive(Default, Debug)]
struct Counts {
    lanes: usize,
    sampled: usize,
    smooth: usize,
    nonzero: usize,
    dense: usize,
    null: usize,
}

/// Sixteen lanes of `b` at random points, directions and sample values against the `f32`
/// instantiation and the one-path functions.
fn compare(b: &Bsdf, rng: &mut Pcg32, counts: &mut Counts) {
    let mut sp = [ShadingPoint::default(); 16];
    let (mut wi, mut wo) = ([Vec3::ZERO; 16], [Vec3::ZERO; 16]);
    let (mut u1, mut u2) = ([0.0f32; 16], [Vec2::ZERO; 16]);
    for k in 0..16 {
        sp[k] = random_shading_point(rng);
        wi[k] = lane_direction(rng);
        wo[k] = match rng.random_range(0..5) {
            0 => -wi[k],
            1 => Vec3::new(-wi[k].x, -wi[k].y, wi[k].z),
            2 => wi[k],
            _ => lane_direction(rng),
        };
        u1[k] = random_u(rng);
        u2[k] = Vec2::new(random_u(rng), random_u(rng));
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
    let flags = b.flags();
    for k in 0..16 {
        let at = format!(
            "{b:?}\nsp {:?} wi {:?} wo {:?} u1 {:?} u2 {:?}",
            sp[k], wi[k], wo[k], u1[k], u2[k]
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
        let bit = |m: f32x16| m.bits() & (1 << k) != 0;
        let valid = bit(s.valid);
        counts.lanes += 1;
        counts.sampled += valid as usize;
        if flags.has_smooth() {
            counts.smooth += 1;
            counts.nonzero += (fk != Vector3::zero()) as usize;
            counts.dense += (pdfk > 0.0) as usize;
        }
        assert_eq!(valid, sk.valid, "sample validity\n{at}");
        if valid {
            let (delta, null) = (bit(s.delta), bit(s.null));
            counts.null += null as usize;
            assert!(
                same3(s.wo.lane(k), sk.wo.into())
                    && same3(s.weight.lane(k), sk.weight.into())
                    && same(s.pdf.lane(k), sk.pdf)
                    && same(s.eta.lane(k), sk.eta)
                    && delta == sk.delta
                    && null == sk.null,
                "sample: lanes ({}, {}, {}, {}, {delta}, {null}), f32 {sk:?}\n{at}",
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
                    && so.lobe.is_delta() == sk.delta
                    && so.lobe.is_null() == sk.null,
                "one-path sample {so:?}\n{at}"
            );
            // The lobe is one of the model's, on the side the direction went.
            assert!(
                flags.contains(so.lobe) && so.lobe != LobeFlags::NONE,
                "lobe {:?} of a model with {flags:?}\n{at}",
                so.lobe
            );
            // (Directions in the plane, as a refraction at grazing incidence, on neither; and
            // within round-off of it: a rough dielectric of IOR exactly 1 refracts
            // wi = (0.336, 0.942, 8e-6) to z = +9e-5, the cancellation in `refract_about`,
            // arithmetic the one-path model had before the lane port too. Under a normal or
            // bump map the side is the perturbed frame's.)
            let perturbed = b.reads_surface_frame();
            if !so.lobe.is_null() && !perturbed && wi[k].z.abs() > 1e-3 && so.wo.z.abs() > 1e-3 {
                let through = wi[k].z * so.wo.z < 0.0;
                assert_eq!(
                    so.lobe.intersects(LobeFlags::TRANSMISSION),
                    through,
                    "lobe {:?}, wo {}\n{at}",
                    so.lobe,
                    so.wo
                );
            }
        }
    }
}

#[test]
fn nested_and_principled_lanes_are_the_one_path_bit_for_bit() {
    let mut rng = Pcg32::seed_from_u64(0x9121_c1b1);
    let mut counts = Counts::default();
    for _ in 0..1500 {
        let b = random_model(&mut rng, 2);
        // The packet loop runs them all, null lobes (mask, null) included.
        assert!(b.has_r(), "{b:?}");
        for _ in 0..8 {
            compare(&b, &mut rng, &mut counts);
        }
    }
    let c = &counts;
    // Not a vacuous pass: many lanes sample and evaluate to something (directions below
    // one-sided models, masks of opacity 0, bump maps without a gradient give nothing).
    assert!(
        c.sampled * 3 > c.lanes
            && c.nonzero * 4 > c.smooth
            && c.dense * 4 > c.smooth
            && c.null * 20 > c.sampled,
        "{c:?}"
    );
}

/// The models of `lanes_test.rs` too, now that blends and adapters may nest them: each of
/// them through the same comparison, at shading points with tangents.
#[test]
fn first_lane_models_at_full_shading_points() {
    let mut rng = Pcg32::seed_from_u64(0x5eed_f00d);
    let mut counts = Counts::default();
    let mut models = 0;
    while models < 300 {
        let b = random_lane_bsdf(&mut rng, 2);
        if !b.has_r() {
            continue;
        }
        models += 1;
        for _ in 0..4 {
            compare(&b, &mut rng, &mut counts);
        }
    }
    assert!(counts.sampled * 4 > counts.lanes, "{counts:?}");
}
