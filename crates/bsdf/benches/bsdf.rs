//! BSDF throughput, scalar: `sample`, `eval` and `eval_pdf` of several models through the
//! `Bsdf` enum (the dispatch the integrator pays), over fixed seeded inputs.
//!
//! Each model gets N = 4096 inputs (wi, u1, u2, wo), built once from a fixed seed: wi and
//! wo cosine-distributed about +z (for the dielectrics, the two-sided model, the transmissive
//! principled models and null, half of each below the surface, so both sides and both lobes
//! are exercised). `wo` is independent of `wi`, as for a light sample in next-event
//! estimation. Every iteration makes N calls; divan's
//! item counter reads as calls per second (Mitem/s = M calls/s).
//!
//! `eval_pdf_lanes` and `sample_lanes` make the same N calls sixteen lanes at a time through
//! the models written over `Real` (`Bsdf::eval_pdf_r`, `Bsdf::sample_r` over `f32x16`), as
//! the packet loop does; models without lane versions are skipped there.
//!
//! Run: `cargo bench -p radia-bsdf --bench bsdf` (quick: append `-- --sample-count 5`;
//! one model: `-- roughplastic`).

use divan::counter::ItemsCount;
use divan::{black_box, Bencher};
use glam::{Vec2, Vec3};
use radia_bsdf::ior::lookup_conductor;
use radia_bsdf::microfacet::Shadowing;
use radia_bsdf::ShadingPointR;
use radia_bsdf::{
    Bitmap, Blend, BlinnPhong, Bsdf, BumpMap, Conductor, CookTorrance, CookTorranceFresnel,
    Dielectric, Diffuse, FilterType, Mask, MicrofacetDistribution, MicrofacetType, NormalMap, Null,
    PerturbOptions, Phong, Plastic, Principled, PrincipledIor, PrincipledThin, RoughConductor,
    RoughDielectric, RoughPlastic, ShadingPoint, Texture, ThinDielectric, TwoSided, UvTransform,
    WrapMode,
};
use radia_math::real::{f32x16, Real, Vector2, Vector3};
use radia_sampling::warp::square_to_cosine_hemisphere;
use rand::{Rng, SeedableRng};
use rand_pcg::Pcg64;
use std::sync::LazyLock;

fn main() {
    divan::main();
}

const N: usize = 4096;

const MODELS: &[&str] = &[
    "diffuse",
    "conductor",
    "roughconductor_ggx",
    "roughconductor_beckmann",
    "roughconductor_beckmann_aniso_all",
    "dielectric",
    "thindielectric",
    "roughdielectric_ggx",
    "roughdielectric_beckmann",
    "plastic",
    "roughplastic_ggx",
    "twosided_roughconductor",
    "phong",
    "blinnphong",
    "cooktorrance_gltf",
    "principled",
    "principled_dielectric",
    "principledthin",
    "blend_diffuse_roughconductor",
    "normalmap_roughconductor",
    "bumpmap_diffuse",
    "mask_diffuse",
    "null",
];

struct Input {
    wi: Vec3,
    u1: f32,
    u2: Vec2,
    wo: Vec3,
}

struct Case {
    bsdf: Bsdf,
    inputs: Vec<Input>,
    /// The inputs by sixteen, in lanes.
    lanes: Vec<LaneInput>,
    /// Where the model is queried: uv 0 with the shading frame's tangents and normal (what
    /// a bump map reads).
    sp: ShadingPoint,
}

struct LaneInput {
    wi: Vector3<f32x16>,
    u1: f32x16,
    u2: Vector2<f32x16>,
    wo: Vector3<f32x16>,
}

fn model(name: &str) -> (Bsdf, bool) {
    let gold = lookup_conductor("Au").expect("Au preset");
    let (eta, k) = (Vec3::from(gold.eta), Vec3::from(gold.k));
    let ggx = |alpha| MicrofacetDistribution::new(MicrofacetType::Ggx, alpha, alpha, true);
    match name {
        "diffuse" => (Bsdf::Diffuse(Diffuse::new(Vec3::splat(0.5))), false),
        "roughconductor_ggx" => (
            Bsdf::RoughConductor(RoughConductor::new(ggx(0.2), eta, k, Vec3::ONE)),
            false,
        ),
        "roughconductor_beckmann" => (
            Bsdf::RoughConductor(RoughConductor::new(
                MicrofacetDistribution::new(MicrofacetType::Beckmann, 0.2, 0.2, true),
                eta,
                k,
                Vec3::ONE,
            )),
            false,
        ),
        "roughconductor_beckmann_aniso_all" => (
            Bsdf::RoughConductor(RoughConductor::new(
                MicrofacetDistribution::new(MicrofacetType::Beckmann, 0.1, 0.3, false),
                eta,
                k,
                Vec3::ONE,
            )),
            false,
        ),
        "conductor" => (Bsdf::Conductor(Conductor::new(eta, k, Vec3::ONE)), false),
        "dielectric" => (Bsdf::Dielectric(Dielectric::new(1.5, 1.0)), true),
        "thindielectric" => (Bsdf::ThinDielectric(ThinDielectric::new(1.5, 1.0)), true),
        "roughdielectric_ggx" => (
            Bsdf::RoughDielectric(RoughDielectric::new(ggx(0.2), 1.5, 1.0)),
            true,
        ),
        "roughdielectric_beckmann" => (
            Bsdf::RoughDielectric(RoughDielectric::new(
                MicrofacetDistribution::new(MicrofacetType::Beckmann, 0.2, 0.2, true),
                1.5,
                1.0,
            )),
            true,
        ),
        "twosided_roughconductor" => (
            Bsdf::TwoSided(TwoSided::new(
                Bsdf::RoughConductor(RoughConductor::new(ggx(0.2), eta, k, Vec3::ONE)),
                Bsdf::Diffuse(Diffuse::new(Vec3::splat(0.5))),
            )),
            true,
        ),
        "phong" => (
            Bsdf::Phong(Phong::new(Vec3::splat(0.3), Vec3::splat(0.5), 40.0)),
            false,
        ),
        "blinnphong" => (
            Bsdf::BlinnPhong(BlinnPhong::new(Vec3::splat(0.3), Vec3::splat(0.5), 40.0)),
            false,
        ),
        "cooktorrance_gltf" => (
            Bsdf::CookTorrance(CookTorrance::new(
                ggx(0.2),
                Shadowing::Separable,
                CookTorranceFresnel::MetallicRoughness {
                    base_color: Vec3::new(0.8, 0.5, 0.2).into(),
                    metallic: 0.5.into(),
                },
            )),
            false,
        ),
        "plastic" => (
            Bsdf::Plastic(Plastic::new(
                1.49,
                1.0,
                Vec3::new(0.5, 0.3, 0.2),
                Vec3::ONE,
                false,
            )),
            false,
        ),
        "roughplastic_ggx" => (
            Bsdf::RoughPlastic(RoughPlastic::new(
                MicrofacetType::Ggx,
                0.2,
                true,
                1.49,
                1.0,
                Vec3::new(0.5, 0.3, 0.2),
                Vec3::ONE,
                false,
            )),
            false,
        ),
        "principled" => {
            // Every lobe on (the "everything" corner of the principled tests).
            let mut m = Principled::new(Vec3::new(0.8, 0.5, 0.2));
            m.metallic = Some(0.3.into());
            m.spec_trans = Some(0.5.into());
            m.spec_tint = Some(0.5.into());
            m.sheen = Some(1.0.into());
            m.sheen_tint = Some(0.5.into());
            m.flatness = Some(0.5.into());
            m.clearcoat = Some(1.0.into());
            m.clearcoat_gloss = 0.5.into();
            (
                Bsdf::Principled(m.with_ior(PrincipledIor::Specular(0.5))),
                true,
            )
        }
        // Blender's default Principled BSDF: the diffuse and specular lobes only.
        "principled_dielectric" => (
            Bsdf::Principled(Principled::new(Vec3::new(0.8, 0.5, 0.2))),
            false,
        ),
        "principledthin" => {
            // The "leaf" corner of the principledthin tests.
            let mut m = PrincipledThin::new(Vec3::new(0.3, 0.6, 0.2));
            m.roughness = 0.4.into();
            m.spec_trans = Some(0.4.into());
            m.diff_trans = Some(0.8.into());
            m.eta = 1.4.into();
            m.spec_tint = Some(0.3.into());
            m.sheen = Some(0.5.into());
            m.sheen_tint = Some(0.5.into());
            m.flatness = Some(0.3.into());
            (Bsdf::PrincipledThin(m), true)
        }
        "blend_diffuse_roughconductor" => (
            Bsdf::Blend(Blend::new(
                0.3,
                Bsdf::Diffuse(Diffuse::new(Vec3::splat(0.5))),
                Bsdf::RoughConductor(RoughConductor::new(ggx(0.2), eta, k, Vec3::ONE)),
            )),
            false,
        ),
        "normalmap_roughconductor" => {
            let n = Vec3::new(0.3, -0.35, 0.9).normalize();
            (
                Bsdf::NormalMap(NormalMap::new(
                    Texture::Constant((n + Vec3::ONE) * 0.5),
                    Bsdf::RoughConductor(RoughConductor::new(ggx(0.2), eta, k, Vec3::ONE)),
                    PerturbOptions::default(),
                )),
                false,
            )
        }
        "bumpmap_diffuse" => {
            let height = Bitmap::new(
                2,
                2,
                1,
                vec![0.0, 0.4, 0.2, 1.0],
                FilterType::Bilinear,
                WrapMode::Repeat,
                UvTransform::IDENTITY,
            )
            .expect("valid bitmap");
            (
                Bsdf::BumpMap(BumpMap::new(
                    height.into(),
                    0.5,
                    Bsdf::Diffuse(Diffuse::new(Vec3::splat(0.5))),
                    PerturbOptions::default(),
                )),
                false,
            )
        }
        "mask_diffuse" => (
            Bsdf::Mask(Mask::new(
                0.7.into(),
                Bsdf::Diffuse(Diffuse::new(Vec3::splat(0.5))),
            )),
            false,
        ),
        "null" => (Bsdf::Null(Null), true),
        _ => unreachable!("unknown model {name}"),
    }
}

static CASES: LazyLock<Vec<(&'static str, Case)>> = LazyLock::new(|| {
    MODELS
        .iter()
        .enumerate()
        .map(|(i, &name)| {
            let (bsdf, two_sided) = model(name);
            let mut rng = Pcg64::seed_from_u64(1000 + i as u64);
            let dir = |rng: &mut Pcg64| {
                let d = square_to_cosine_hemisphere(Vec2::new(rng.random(), rng.random()));
                if two_sided && rng.random::<bool>() {
                    -d
                } else {
                    d
                }
            };
            let inputs: Vec<Input> = (0..N)
                .map(|_| Input {
                    wi: dir(&mut rng),
                    u1: rng.random(),
                    u2: Vec2::new(rng.random(), rng.random()),
                    wo: dir(&mut rng),
                })
                .collect();
            let lanes = inputs
                .chunks(16)
                .map(|c| LaneInput {
                    wi: Vector3::from_fn(|k| c[k].wi),
                    u1: f32x16::from_fn(|k| c[k].u1),
                    u2: Vector2::from_fn(|k| c[k].u2),
                    wo: Vector3::from_fn(|k| c[k].wo),
                })
                .collect();
            let sp = ShadingPoint::at_uv(Vec2::ZERO);
            (
                name,
                Case {
                    bsdf,
                    inputs,
                    lanes,
                    sp,
                },
            )
        })
        .collect()
});

fn case(name: &str) -> &'static Case {
    &CASES.iter().find(|(n, _)| *n == name).unwrap().1
}

fn run<O>(bencher: Bencher, name: &str, f: impl Fn(&Bsdf, &ShadingPoint, &Input) -> O + Sync) {
    let c = case(name);
    bencher.counter(ItemsCount::new(N)).bench(|| {
        let bsdf = black_box(&c.bsdf);
        for input in black_box(&c.inputs[..]) {
            black_box(f(bsdf, &c.sp, input));
        }
    });
}

/// `Bsdf::sample(wi, u1, u2)`: a direction, its weight and pdf.
#[divan::bench(args = MODELS)]
fn sample(bencher: Bencher, name: &str) {
    run(bencher, name, |b, sp, x| b.sample(sp, x.wi, x.u1, x.u2));
}

/// `Bsdf::eval(wi, wo)`.
#[divan::bench(args = MODELS)]
fn eval(bencher: Bencher, name: &str) {
    run(bencher, name, |b, sp, x| b.eval(sp, x.wi, x.wo));
}

/// `Bsdf::eval_pdf(wi, wo)`: the next-event-estimation call.
#[divan::bench(args = MODELS)]
fn eval_pdf(bencher: Bencher, name: &str) {
    run(bencher, name, |b, sp, x| b.eval_pdf(sp, x.wi, x.wo));
}

fn run_lanes<O>(
    bencher: Bencher,
    name: &str,
    f: impl Fn(&Bsdf, &ShadingPointR<f32x16>, &LaneInput) -> O + Sync,
) {
    let c = case(name);
    if !c.bsdf.has_r() {
        return;
    }
    let sp = ShadingPointR::<f32x16> {
        uv: Vector2::new(f32x16::ZERO, f32x16::ZERO),
        dp_du: Vector3::splat(Vec3::X),
        dp_dv: Vector3::splat(Vec3::Y),
        n: Vector3::splat(Vec3::Z),
    };
    bencher.counter(ItemsCount::new(N)).bench(|| {
        let bsdf = black_box(&c.bsdf);
        for input in black_box(&c.lanes[..]) {
            black_box(f(bsdf, &sp, input));
        }
    });
}

/// `Bsdf::eval_pdf_r` over sixteen lanes (items count single calls).
#[divan::bench(args = MODELS)]
fn eval_pdf_lanes(bencher: Bencher, name: &str) {
    run_lanes(bencher, name, |b, sp, x| b.eval_pdf_r(sp, x.wi, x.wo));
}

/// `Bsdf::sample_r` over sixteen lanes (items count single calls).
#[divan::bench(args = MODELS)]
fn sample_lanes(bencher: Bencher, name: &str) {
    run_lanes(bencher, name, |b, sp, x| b.sample_r(sp, x.wi, x.u1, x.u2));
}
