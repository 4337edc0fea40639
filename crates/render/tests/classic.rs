//! The `classic` integrator against what the textbook model must give: the path tracer's
//! direct illumination on a diffuse scene; Gouraud = Phong where lighting is constant;
//! flat shading constant per triangle.

use radia_render::{render, RenderOptions, RenderOutput};
use radia_sampling::SamplerKind;
use radia_scene::{load_mitsuba_xml, Scene};
use std::sync::atomic::AtomicBool;

fn render_xml(name: &str, xml: &str, spp: u32) -> RenderOutput {
    let dir = std::env::temp_dir().join(format!("radia-classic-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("scene.xml");
    std::fs::write(&path, xml).unwrap();
    let scene = Scene::build(load_mitsuba_xml(&path, &[]).unwrap_or_else(|e| panic!("{e}")));
    let options = RenderOptions {
        spp,
        seed: 1,
        sampler: SamplerKind::Independent,
    };
    render(&scene, &options, &AtomicBool::new(false), &|_| {})
}

/// A diffuse sphere on a diffuse floor (a 2-triangle rectangle), seen at 40x30 px.
fn scene(integrator: &str, lights: &str) -> String {
    format!(
        r#"<scene version="3.0.0">
    {integrator}
    <sensor type="perspective">
        <float name="fov" value="45"/>
        <transform name="to_world"><lookat origin="0, 2, -5" target="0, 0.5, 0" up="0, 1, 0"/></transform>
        <film type="hdrfilm"><integer name="width" value="40"/><integer name="height" value="30"/>
            <rfilter type="box"/></film>
    </sensor>
    <shape type="sphere"><point name="center" value="0, 1, 0"/>
        <bsdf type="diffuse"><rgb name="reflectance" value="0.7, 0.5, 0.3"/></bsdf></shape>
    <shape type="rectangle">
        <transform name="to_world"><scale value="3"/><rotate x="1" angle="-90"/></transform>
        <bsdf type="diffuse"><rgb name="reflectance" value="0.4, 0.6, 0.8"/></bsdf></shape>
    {lights}
</scene>"#
    )
}

const POINT: &str = r#"<emitter type="point"><point name="position" value="1.5, 3, -1"/>
    <rgb name="intensity" value="10"/></emitter>"#;

fn max_abs_diff(a: &RenderOutput, b: &RenderOutput) -> f32 {
    a.image
        .pixels
        .iter()
        .zip(&b.image.pixels)
        .map(|(x, y)| (*x - *y).abs().max_element())
        .fold(0.0, f32::max)
}

#[test]
fn classic_equals_the_path_tracers_direct_illumination_on_a_diffuse_scene() {
    let path = render_xml(
        "path",
        &scene(
            r#"<integrator type="path"><integer name="max_depth" value="2"/></integrator>"#,
            POINT,
        ),
        8,
    );
    let classic = render_xml(
        "classic",
        &scene(
            r#"<integrator type="classic"><string name="shading" value="phong"/></integrator>"#,
            POINT,
        ),
        8,
    );
    // Same sample positions, and both estimators are exact for a point light: equal up to
    // float rounding, pixel by pixel (not only in expectation).
    assert!(path.image.mean() > 0.01);
    let d = max_abs_diff(&path, &classic);
    assert!(d < 1e-5, "max |path − classic| = {d}");
    // Shadows matter: without them the floor under the sphere lights up.
    let unshadowed = render_xml(
        "classic-noshadow",
        &scene(
            r#"<integrator type="classic"><boolean name="shadows" value="false"/></integrator>"#,
            POINT,
        ),
        8,
    );
    assert!(unshadowed.image.mean() > classic.image.mean() * 1.01);
}

#[test]
fn gouraud_equals_phong_on_a_plane_under_a_directional_light() {
    let light = r#"<emitter type="directional"><vector name="direction" value="0.3, -1, 0.2"/>
        <rgb name="irradiance" value="2"/></emitter>"#;
    let shading = |s: &str| {
        render_xml(
            s,
            &scene(
                &format!(
                    r#"<integrator type="classic"><boolean name="shadows" value="false"/>
                    <string name="shading" value="{s}"/></integrator>"#
                ),
                light,
            ),
            4,
        )
    };
    let (gouraud, phong, flat) = (shading("gouraud"), shading("phong"), shading("flat"));
    // The sphere is analytic (shaded per hit in every mode); the floor is a mesh whose
    // lighting is the same everywhere, so interpolating it changes nothing.
    let d = max_abs_diff(&gouraud, &phong);
    assert!(d < 1e-5, "max |gouraud − phong| = {d}");
    assert!(max_abs_diff(&flat, &phong) < 1e-5);
}

#[test]
fn flat_shading_is_constant_per_triangle_and_gouraud_is_not() {
    // One spp and a box filter: every pixel is one sample, so its value is its triangle's
    // and the prim_index AOV says which triangle that is.
    let with = |s: &str| {
        render_xml(
            s,
            &scene(
                &format!(
                    r#"<integrator type="aov"><string name="aovs" value="s:shape_index,p:prim_index"/>
                    <integrator type="classic"><string name="shading" value="{s}"/></integrator></integrator>"#
                ),
                POINT,
            ),
            1,
        )
    };
    for (s, constant) in [("flat", true), ("gouraud", false)] {
        let out = with(s);
        let aovs = out.aovs.as_ref().unwrap();
        let plane = |n: &str| &aovs.planes[aovs.names.iter().position(|x| x == n).unwrap()];
        let (shape, prim) = (plane("s.I"), plane("p.I"));
        let mut seen: std::collections::HashMap<u32, Vec<radia_math::Spectrum>> =
            Default::default();
        for (i, px) in out.image.pixels.iter().enumerate() {
            if shape[i] == 2.0 {
                seen.entry(prim[i] as u32).or_default().push(*px);
            }
        }
        assert_eq!(
            seen.len(),
            2,
            "{s}: the floor's two triangles are visible: {:?}",
            seen.keys().collect::<Vec<_>>()
        );
        for (tri, values) in &seen {
            let spread = values
                .iter()
                .map(|v| (*v - values[0]).abs().max_element())
                .fold(0.0, f32::max);
            if constant {
                assert_eq!(spread, 0.0, "flat: triangle {tri} varies by {spread}");
            } else {
                assert!(spread > 1e-3, "gouraud: triangle {tri} is constant");
            }
        }
    }
}
