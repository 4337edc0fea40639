//! The `npr` integrator: toon shading has exactly N bands on a sphere; silhouette lines
//! appear exactly where the neighbours' depths jump, and nowhere else.

mod common;

use common::{aov_plane, render_xml, sensor, write_scene};
use radia_formats::load_mitsuba_xml;
use std::collections::BTreeSet;

#[test]
fn toon_has_exactly_n_bands_on_a_sphere() {
    for levels in [2, 4, 7] {
        // Lit from the side, so the visible half runs from unlit to fully lit; one sample
        // per pixel, so every pixel holds one band's value.
        let xml = format!(
            r#"<scene version="3.0.0">
            <integrator type="aov"><string name="aovs" value="s:shape_index"/>
                <integrator type="npr"><integer name="levels" value="{levels}"/>
                    <float name="line_width" value="0"/></integrator></integrator>
            {}
            <shape type="sphere"><bsdf type="diffuse"><rgb name="reflectance" value="0.8"/></bsdf></shape>
            <emitter type="directional"><vector name="direction" value="-1, -0.3, 0.2"/></emitter>
            </scene>"#,
            sensor("0, 0, -4", "0, 0, 0", 35.0, 64, 64)
        );
        let out = render_xml(&format!("npr-toon{levels}"), &xml, 1, 3);
        let shape = aov_plane(&out, "s.I");
        let bands: BTreeSet<u32> = out
            .image
            .pixels
            .iter()
            .zip(shape)
            .filter(|(_, &s)| s == 1.0)
            .map(|(p, _)| p.x.to_bits())
            .collect();
        assert_eq!(bands.len(), levels as usize, "{levels} levels: {bands:?}");
    }
}

#[test]
fn silhouette_lines_exactly_where_the_depth_jumps() {
    // A near plane (z = 2) covering world x >= 0, i.e. the image's left half (image x runs
    // towards -x), its edge projecting exactly onto the boundary between columns 19 and 20,
    // in front of a far plane (z = 4). Both face the camera and are lit head-on, so the
    // fill is kd = 0.5 everywhere. With 1-pixel lines, a sample's horizontal neighbours
    // cross the edge exactly when it is in column 19 or 20.
    let plane = |sx: f32, tx: f32, z: f32| {
        format!(
            r#"<shape type="rectangle"><transform name="to_world"><rotate y="1" angle="180"/>
            <scale value="{sx}"/><translate x="{tx}" z="{z}"/></transform>
            <bsdf type="diffuse"><rgb name="reflectance" value="0.5"/></bsdf></shape>"#
        )
    };
    let xml = format!(
        r#"<scene version="3.0.0">
        <integrator type="npr"><integer name="levels" value="2"/><float name="line_width" value="1"/>
            <rgb name="line_color" value="1, 0, 0"/></integrator>
        {}
        {}
        {}
        <emitter type="directional"><vector name="direction" value="0, 0, 1"/></emitter>
        </scene>"#,
        sensor("0, 0, 0", "0, 0, 1", 60.0, 40, 30),
        plane(10.0, 10.0, 2.0),
        plane(50.0, 0.0, 4.0)
    );
    let out = render_xml("npr-silhouette", &xml, 4, 3);
    let line = radia_math::Spectrum::new(1.0, 0.0, 0.0);
    let fill = radia_math::Spectrum::splat(0.5);
    for y in 0..30 {
        for x in 0..40 {
            let p = out.image.get(x, y);
            let expected = if x == 19 || x == 20 { line } else { fill };
            assert_eq!(p, expected, "pixel ({x}, {y})");
        }
    }
}

/// The toon sphere of `toon_has_exactly_n_bands_on_a_sphere` with `fill` as the integrator's
/// toon parameters: (image, whether each pixel is on the sphere).
fn toon_sphere(name: &str, fill: &str) -> (Vec<radia_math::Spectrum>, Vec<bool>) {
    let xml = format!(
        r#"<scene version="3.0.0">
        <integrator type="aov"><string name="aovs" value="s:shape_index"/>
            <integrator type="npr">{fill}<float name="line_width" value="0"/></integrator></integrator>
        {}
        <shape type="sphere"><bsdf type="diffuse"><rgb name="reflectance" value="1"/></bsdf></shape>
        <emitter type="directional"><vector name="direction" value="-1, -0.3, 0.2"/></emitter>
        </scene>"#,
        sensor("0, 0, -4", "0, 0, 0", 35.0, 64, 64)
    );
    let out = render_xml(name, &xml, 1, 3);
    let on_sphere = aov_plane(&out, "s.I").iter().map(|&s| s == 1.0).collect();
    (out.image.pixels, on_sphere)
}

#[test]
fn toon_ramp_maps_each_band_to_exactly_its_colour() {
    use radia_math::Spectrum;
    let ramp = [
        Spectrum::new(0.05, 0.02, 0.2),
        Spectrum::new(0.7, 0.1, 0.1),
        Spectrum::new(0.2, 0.9, 0.3),
        Spectrum::new(1.0, 1.0, 0.6),
    ];
    // The same samples with plain levels and a white sphere show band k as k/3 exactly,
    // which tells each pixel's band.
    let (bands, on_sphere) =
        toon_sphere("npr-ramp-levels", r#"<integer name="levels" value="4"/>"#);
    let text = "0.05, 0.02, 0.2; 0.7 0.1 0.1; 0.2,0.9,0.3 ; 1, 1, 0.6";
    let (image, _) = toon_sphere(
        "npr-ramp",
        &format!(r#"<string name="ramp" value="{text}"/>"#),
    );
    let mut seen = [0usize; 4];
    for (i, (&b, &p)) in bands.iter().zip(&image).enumerate() {
        if !on_sphere[i] {
            continue;
        }
        let k = (b.x * 3.0).round() as usize;
        assert_eq!(
            b,
            Spectrum::splat(k as f32 / 3.0),
            "pixel {i} is not one band"
        );
        assert_eq!(p, ramp[k], "pixel {i} in band {k}");
        seen[k] += 1;
    }
    assert!(
        seen.iter().all(|&n| n > 0),
        "every band on the sphere: {seen:?}"
    );
    // A one-value colour is a grey.
    let (image, on_sphere) = toon_sphere(
        "npr-ramp-grey",
        r#"<string name="ramp" value="0.25; 0.5"/>"#,
    );
    let greys: BTreeSet<u32> = image
        .iter()
        .zip(&on_sphere)
        .filter(|(_, &on)| on)
        .map(|(p, _)| {
            assert!(p.x == p.y && p.y == p.z, "{p:?}");
            p.x.to_bits()
        })
        .collect();
    assert_eq!(greys, [0.25f32.to_bits(), 0.5f32.to_bits()].into());
}

#[test]
fn toon_ramp_errors_name_the_problem() {
    for (name, params, needle) in [
        (
            "ramp-text",
            r#"<string name="ramp" value="0.1; red"/>"#,
            "colour 2 (\"red\") is not numbers",
        ),
        (
            "ramp-two",
            r#"<string name="ramp" value="0.1, 0.2"/>"#,
            "one grey value or three",
        ),
        (
            "ramp-neg",
            r#"<string name="ramp" value="0.1; -1"/>"#,
            "non-negative",
        ),
        (
            "ramp-empty",
            r#"<string name="ramp" value="0.1;;0.3"/>"#,
            "colour 2",
        ),
        (
            "ramp-levels",
            r#"<integer name="levels" value="3"/><string name="ramp" value="0; 1"/>"#,
            "\"levels\" is 3 but the ramp has 2 colours",
        ),
        (
            "ramp-gooch",
            r#"<string name="style" value="gooch"/><string name="ramp" value="0; 1"/>"#,
            "\"ramp\"",
        ),
    ] {
        let xml = format!(
            r#"<scene version="3.0.0"><integrator type="npr">{params}</integrator>
            <shape type="sphere"/></scene>"#
        );
        let path = write_scene(&format!("npr-{name}"), &xml);
        let err = load_mitsuba_xml(&path, &[])
            .err()
            .unwrap_or_else(|| panic!("{name} loaded"));
        let text = err.to_string();
        assert!(text.contains(needle), "{name}: {text}");
        assert!(
            text.contains("scene.xml") && err.line.is_some(),
            "{name}: {text}"
        );
    }
}
