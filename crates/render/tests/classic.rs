//! The `classic` integrator against what the textbook model must give: the path tracer's
//! direct illumination on a diffuse scene; Gouraud = Phong where lighting is constant;
//! flat shading constant per triangle.

mod common;

use common::{aov_plane, render_xml, sensor};
use radia_math::Spectrum;
use radia_render::RenderOutput;
use std::f64::consts::PI;

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
        1,
    );
    let classic = render_xml(
        "classic",
        &scene(
            r#"<integrator type="classic"><string name="shading" value="phong"/></integrator>"#,
            POINT,
        ),
        8,
        1,
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
        1,
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
            1,
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
            1,
        )
    };
    for (s, constant) in [("flat", true), ("gouraud", false)] {
        let out = with(s);
        let (shape, prim) = (aov_plane(&out, "s.I"), aov_plane(&out, "p.I"));
        let mut seen: std::collections::HashMap<u32, Vec<Spectrum>> = Default::default();
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

/// Every pixel of `out` equals `expected` to `rel` relative error (per channel).
fn assert_all_pixels(out: &RenderOutput, expected: [f64; 3], rel: f64, what: &str) {
    for (i, p) in out.image.pixels.iter().enumerate() {
        for (c, (&got, want)) in p.to_array().iter().zip(expected).enumerate() {
            let err = (got as f64 - want).abs() / want.abs().max(1e-12);
            assert!(
                err < rel,
                "{what}: pixel {i} channel {c} = {got}, expected {want} (rel. error {err:.2e})"
            );
        }
    }
}

/// A `w`×`h` rectangle (Mitsuba's: [−1, 1]² in z = 0, facing +z) with reflectance `rgb`,
/// turned by `yaw` degrees about y (its normal becomes (sin yaw, 0, cos yaw)) and moved to
/// `at`.
fn rectangle(bsdf: &str, sx: f32, sy: f32, yaw: f32, at: &str) -> String {
    format!(
        r#"<shape type="rectangle"><transform name="to_world"><scale x="{sx}" y="{sy}"/>
        <rotate y="1" angle="{yaw}"/><translate value="{at}"/></transform>{bsdf}</shape>"#
    )
}

fn diffuse(rgb: &str) -> String {
    format!(r#"<bsdf type="diffuse"><rgb name="reflectance" value="{rgb}"/></bsdf>"#)
}

#[test]
fn whitted_mirror_reflects_exactly_the_lit_surface_it_faces() {
    // The camera looks down +z (a 0.5° field: every ray within 0.25° of the axis) at a mirror
    // at z = 2 turned 45° (normal (−1, 0, −1)/√2), which folds the view to −x: onto a red
    // diffuse wall at x = −2 facing +x. Green stands where the unreflected ray would go,
    // blue where a reflection of the wrong handedness would. The mirror is `conductor`
    // material "none" (F = 1) tinted 0.5, so the pixel is 0.5 · ρ/π · E cos θ of the red wall,
    // lit by a directional light at 45° (its shadow rays pass above the mirror).
    let rho = [0.8, 0.2, 0.1];
    let xml = format!(
        r#"<scene version="3.0.0">
        <integrator type="classic"/>
        {}
        {}
        {}
        {}
        {}
        <emitter type="directional"><vector name="direction" value="-1, -1, 0"/>
            <rgb name="irradiance" value="2"/></emitter>
        </scene>"#,
        sensor("0, 0, 0", "0, 0, 1", 0.5, 3, 3),
        rectangle(
            r#"<bsdf type="conductor"><string name="material" value="none"/>
            <rgb name="specular_reflectance" value="0.5"/></bsdf>"#,
            0.5,
            0.5,
            -135.0,
            "0, 0, 2"
        ),
        rectangle(&diffuse("0.8, 0.2, 0.1"), 0.5, 0.5, 90.0, "-2, 0, 2"),
        rectangle(&diffuse("0.1, 0.8, 0.1"), 3.0, 3.0, 180.0, "0, 0, 5"),
        rectangle(&diffuse("0.1, 0.1, 0.8"), 0.5, 0.5, -90.0, "2, 0, 2"),
    );
    let out = render_xml("mirror", &xml, 4, 1);
    let e = 2.0 * (PI / 4.0).cos();
    assert_all_pixels(&out, rho.map(|r| 0.5 * r / PI * e), 1e-5, "mirror");
}

/// The Fresnel reflectance of unpolarised light from a medium of index 1 into one of index
/// `eta` at incidence cos θi, from the textbook formulas (Hecht, Optics, §4.6), in f64.
fn fresnel(cos_i: f64, eta: f64) -> f64 {
    let sin_t = (1.0 - cos_i * cos_i).sqrt() / eta;
    let cos_t = (1.0 - sin_t * sin_t).sqrt();
    let rs = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    let rp = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    0.5 * (rs * rs + rp * rp)
}

#[test]
fn whitted_refraction_bends_by_snell_and_weighs_by_fresnel() {
    // The camera looks at 40° to the normal of a glass interface z = 1 (`dielectric`,
    // η = 1.5; a 0.02° field). Snell's law bends the ray to θt = asin(sin 40° / 1.5) inside,
    // where it meets the plane z = 2 at x = tan 40° + tan θt: a red stripe 0.04 wide stands
    // there, in front of a green wall (what an unbent ray, x = 2 tan 40° = 1.68, or η = 1.33,
    // x = 1.39, would see). Only the ambient term lights the inside (shadow rays do not
    // cross glass), so the pixel is the transmitted lobe's probability and weight, as
    // radia's dielectric defines them (Mitsuba's): (1 − F(θi)) · 1/η² (radiance mode) times
    // ambient · ρ; the reflected ray escapes to black.
    let (theta, eta) = (40f64.to_radians(), 1.5f64);
    let theta_t = (theta.sin() / eta).asin();
    let x = theta.tan() + theta_t.tan();
    let target = format!("{}, 0, {}", theta.sin(), theta.cos());
    let xml = format!(
        r#"<scene version="3.0.0">
        <integrator type="classic"><rgb name="ambient" value="2"/></integrator>
        {}
        {}
        {}
        {}
        </scene>"#,
        sensor("0, 0, 0", &target, 0.02, 3, 3),
        rectangle(
            r#"<bsdf type="dielectric"><float name="int_ior" value="1.5"/>
            <float name="ext_ior" value="1"/></bsdf>"#,
            10.0,
            10.0,
            180.0,
            "0, 0, 1"
        ),
        rectangle(
            &diffuse("0.8, 0.2, 0.1"),
            0.02,
            1.0,
            180.0,
            &format!("{x}, 0, 2")
        ),
        rectangle(&diffuse("0.1, 0.8, 0.1"), 10.0, 10.0, 180.0, "0, 0, 2.05"),
    );
    let out = render_xml("refraction", &xml, 4, 1);
    let t = (1.0 - fresnel(theta.cos(), eta)) / (eta * eta);
    assert!(
        (0.9..0.99).contains(&(t * eta * eta)),
        "F(40°) = {}",
        1.0 - t * eta * eta
    );
    assert_all_pixels(
        &out,
        [0.8, 0.2, 0.1].map(|r| 2.0 * r * t),
        2e-5,
        "refraction",
    );
}

#[test]
fn distance_attenuation_is_one_over_a_plus_bd_plus_cd2() {
    // A point light at the pinhole, a diffuse wall facing it at distance d seen through a
    // 0.5° field (cos θ and the distance within 1e-5 of 1 and d): every pixel is
    // ρ/π · I / (a + b d + c d²), and I / d² without `attenuation`.
    let rho = [0.6, 0.4, 0.2];
    for (att, abc) in [
        (Some("0.5, 0.3, 0.2"), [0.5, 0.3, 0.2]),
        (Some("1, 0.5, 0"), [1.0, 0.5, 0.0]),
        (None, [0.0, 0.0, 1.0]),
    ] {
        for d in [0.5f64, 2.0, 5.0] {
            let integrator = match att {
                Some(a) => format!(
                    r#"<integrator type="classic"><string name="attenuation" value="{a}"/></integrator>"#
                ),
                None => r#"<integrator type="classic"/>"#.to_string(),
            };
            let xml = format!(
                r#"<scene version="3.0.0">
                {integrator}
                {}
                {}
                <emitter type="point"><point name="position" value="0, 0, 0"/>
                    <rgb name="intensity" value="3"/></emitter>
                </scene>"#,
                sensor("0, 0, 0", "0, 0, 1", 0.5, 3, 3),
                rectangle(
                    &diffuse("0.6, 0.4, 0.2"),
                    10.0,
                    10.0,
                    180.0,
                    &format!("0, 0, {d}")
                ),
            );
            let out = render_xml(&format!("attenuation-{d}-{}", att.is_some()), &xml, 4, 1);
            let [a, b, c] = abc;
            let e = 3.0 / (a + b * d + c * d * d);
            assert_all_pixels(
                &out,
                rho.map(|r| r / PI * e),
                1e-4,
                &format!("{att:?} at d = {d}"),
            );
        }
    }
}
