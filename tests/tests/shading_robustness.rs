//! Shading at the edges of the parameter ranges never yields NaN or Inf: every material at
//! roughness 0 and 1 (and the 10⁻⁴ floor), IOR 1.0001 and 4, sampled and evaluated for
//! directions from normal incidence down to exactly grazing and just below the horizon; and
//! whole renders of such materials seen at grazing angles drop no sample.

use glam::{Vec2, Vec3};
use radia_bsdf::{Bsdf, ShadingPoint};
use radia_formats::load_mitsuba_xml_str;
use radia_render::{render, RenderOptions};
use radia_sampling::SamplerKind;
use radia_scene::Scene;
use std::path::Path;
use std::sync::atomic::AtomicBool;

fn scene_xml(bsdf: &str, camera_y: f32) -> String {
    format!(
        r#"<scene version="3.0.0">
    <sensor type="perspective">
        <transform name="to_world"><lookat origin="0, {camera_y}, -3" target="0, 0, 0" up="0, 1, 0"/></transform>
        <film type="hdrfilm"><integer name="width" value="24"/><integer name="height" value="24"/></film>
    </sensor>
    <emitter type="constant"/>
    <emitter type="point"><point name="position" x="0" y="1e-6" z="0.5"/><float name="intensity" value="1e6"/></emitter>
    <shape type="rectangle">
        <transform name="to_world"><scale value="20"/><rotate x="1" angle="-90"/></transform>
        {bsdf}
    </shape>
    <shape type="sphere"><float name="radius" value="0.5"/>{bsdf}</shape>
</scene>"#
    )
}

/// Every material radia reads, at the extremes of roughness and IOR.
fn materials() -> Vec<String> {
    let mut m = Vec::new();
    for ior in ["1.0001", "4"] {
        m.push(format!(
            r#"<bsdf type="dielectric"><float name="int_ior" value="{ior}"/></bsdf>"#
        ));
        m.push(format!(
            r#"<bsdf type="thindielectric"><float name="int_ior" value="{ior}"/></bsdf>"#
        ));
        m.push(format!(
            r#"<bsdf type="plastic"><float name="int_ior" value="{ior}"/></bsdf>"#
        ));
        for alpha in ["0", "0.0001", "1"] {
            for dist in ["beckmann", "ggx"] {
                let rough = format!(
                    r#"<string name="distribution" value="{dist}"/><float name="alpha" value="{alpha}"/><float name="int_ior" value="{ior}"/>"#
                );
                m.push(format!(r#"<bsdf type="roughdielectric">{rough}</bsdf>"#));
                m.push(format!(r#"<bsdf type="roughplastic">{rough}</bsdf>"#));
            }
        }
    }
    for alpha in ["0", "0.0001", "1"] {
        for dist in ["beckmann", "ggx"] {
            m.push(format!(
                r#"<bsdf type="roughconductor"><string name="distribution" value="{dist}"/><float name="alpha" value="{alpha}"/></bsdf>"#
            ));
        }
    }
    m.push(r#"<bsdf type="conductor"/>"#.into());
    m.push(r#"<bsdf type="diffuse"/>"#.into());
    m
}

fn load(xml: &str) -> Scene {
    let (desc, _) = load_mitsuba_xml_str(Path::new("shading.xml"), xml, &[])
        .unwrap_or_else(|e| panic!("{e}\n{xml}"));
    Scene::build(desc)
}

/// Directions from the normal down to exactly grazing, and just below (both sides).
fn directions() -> Vec<Vec3> {
    let mut d = Vec::new();
    for cos in [1.0f32, 0.5, 1e-2, 1e-4, 1e-7, 0.0, -1e-7, -1e-4, -0.5, -1.0] {
        let sin = (1.0 - cos * cos).max(0.0).sqrt();
        d.push(Vec3::new(sin, 0.0, cos));
        d.push(Vec3::new(sin * 0.6, sin * 0.8, cos).normalize());
    }
    d
}

/// The BSDF checks: eval, pdf and sampled weights finite for every pair of directions.
fn check_bsdf(xml: &str, bsdf: &Bsdf) {
    let sp = ShadingPoint::default();
    let dirs = directions();
    for &wi in &dirs {
        for &wo in &dirs {
            let (f, pdf) = bsdf.eval_pdf(&sp, wi, wo);
            assert!(
                f.is_finite() && pdf.is_finite(),
                "{xml}: eval({wi}, {wo}) = {f}, pdf {pdf}"
            );
        }
        for i in 0..64 {
            let u1 = (i as f32 + 0.5) / 64.0;
            let u2 = Vec2::new((i * 37 % 64) as f32 / 64.0, (i * 11 % 64) as f32 / 63.0);
            if let Some(s) = bsdf.sample(&sp, wi, u1, u2) {
                assert!(
                    s.weight.is_finite() && s.pdf.is_finite() && s.wo.is_finite(),
                    "{xml}: sample({wi}, {u1}, {u2}) = {s:?}"
                );
            }
        }
    }
}

/// One test, so that each material (rough plastic precomputes tables) is built once.
#[test]
fn extreme_materials_stay_finite_in_bsdf_queries_and_grazing_renders() {
    for xml in materials() {
        // The camera 1e-3 above a floor of the material, looking along it; a point light
        // 1e-6 above it.
        let scene = load(&scene_xml(&xml, 1e-3));
        check_bsdf(&xml, &scene.bsdfs[0]);
        let out = render(
            &scene,
            &RenderOptions {
                spp: 4,
                seed: 0,
                sampler: SamplerKind::Independent,
                adaptive: false,
            },
            &AtomicBool::new(false),
            &|_| {},
        );
        assert_eq!(out.stats.invalid_samples, 0, "{xml}: NaN/Inf samples");
        assert!(out.image.pixels.iter().all(|p| p.is_finite()), "{xml}");
    }
}
