//! A closed box leaks no light (issue #11): lights inside a closed mesh leave its outside
//! exactly black, and an environment outside leaves its inside exactly black, at unit scale,
//! scaled by 10⁻⁴ and 10⁵ and moved 10⁵ from the origin. Any ray that slipped through an
//! edge, a vertex or a badly offset origin would carry light across and make a pixel non-zero.

use radia_formats::load_mitsuba_xml_str;
use radia_render::{render, RenderOptions};
use radia_sampling::SamplerKind;
use radia_scene::Scene;
use std::path::Path;
use std::sync::atomic::AtomicBool;

/// A rotated cube (its edges and vertices off every axis) of half-size `s` centred at `c`,
/// with `inside` in it and the camera at `eye`; `shape` "rectangle" instead of "cube" opens
/// it (the control: then light must get through).
fn scene(s: f32, c: [f32; 3], eye: [f32; 3], inside: &str, outside: &str, shape: &str) -> Scene {
    let [cx, cy, cz] = c;
    let [ex, ey, ez] = eye;
    let xml = format!(
        r#"<scene version="3.0.0">
    <integrator type="path"><integer name="max_depth" value="12"/></integrator>
    <sensor type="perspective">
        <float name="near_clip" value="{near}"/><float name="far_clip" value="{far}"/>
        <transform name="to_world"><lookat origin="{ex}, {ey}, {ez}" target="{cx}, {cy}, {cz}" up="0.2, 1, 0.1"/></transform>
        <film type="hdrfilm"><integer name="width" value="24"/><integer name="height" value="24"/></film>
    </sensor>
    {outside}
    <shape type="{shape}">
        <transform name="to_world">
            <scale value="{s}"/><rotate x="1" y="1" z="0.3" angle="37"/><translate x="{cx}" y="{cy}" z="{cz}"/>
        </transform>
        <bsdf type="diffuse"><rgb name="reflectance" value="0.9"/></bsdf>
    </shape>
    {inside}
</scene>"#,
        near = 1e-3 * s,
        far = 1e4 * s,
    );
    let (desc, _) = load_mitsuba_xml_str(Path::new("closed-box.xml"), &xml, &[]).unwrap();
    Scene::build(desc)
}

fn max_pixel(scene: &Scene) -> f32 {
    let out = render(
        scene,
        &RenderOptions {
            spp: 16,
            seed: 1,
            sampler: SamplerKind::Independent,
            adaptive: false,
        },
        &AtomicBool::new(false),
        &|_| {},
    );
    assert_eq!(out.stats.invalid_samples, 0);
    out.image
        .pixels
        .iter()
        .map(|p| p.max_element())
        .fold(0.0, f32::max)
}

const PLACES: [(f32, [f32; 3]); 4] = [
    (1.0, [0.0, 0.0, 0.0]),
    (1e-4, [0.0, 0.0, 0.0]),
    (1e5, [0.0, 0.0, 0.0]),
    (1.0, [1e5, 1e5, 1e5]),
];

#[test]
fn lights_inside_a_closed_box_leave_its_outside_black() {
    for (s, c) in PLACES {
        let at = |x: f32, y: f32, z: f32| [c[0] + x * s, c[1] + y * s, c[2] + z * s];
        let [lx, ly, lz] = at(0.1, -0.2, 0.3);
        let [px, py, pz] = at(-0.4, 0.5, 0.2);
        let inside = format!(
            r#"<shape type="sphere"><point name="center" x="{lx}" y="{ly}" z="{lz}"/><float name="radius" value="{r}"/>
                <emitter type="area"><rgb name="radiance" value="1000"/></emitter></shape>
            <emitter type="point"><point name="position" x="{px}" y="{py}" z="{pz}"/><rgb name="intensity" value="{i}"/></emitter>"#,
            r = 0.2 * s,
            i = 1000.0 * s * s,
        );
        // Outside: a white floor under the box that the light would reach through a leak.
        let [fx, fy, fz] = at(0.0, -3.0, 0.0);
        let outside = format!(
            r#"<shape type="rectangle"><transform name="to_world"><scale value="{w}"/><rotate x="1" angle="-90"/><translate x="{fx}" y="{fy}" z="{fz}"/></transform></shape>"#,
            w = 10.0 * s,
        );
        let eye = at(3.0, 2.0, 4.0);
        let closed = scene(s, c, eye, &inside, &outside, "cube");
        assert_eq!(
            max_pixel(&closed),
            0.0,
            "scale {s}, centre {c:?}: light leaked out"
        );
        assert!(max_pixel(&scene(s, c, eye, &inside, &outside, "rectangle")) > 0.0);
    }
}

#[test]
fn an_environment_outside_a_closed_box_leaves_its_inside_black() {
    for (s, c) in PLACES {
        let at = |x: f32, y: f32, z: f32| [c[0] + x * s, c[1] + y * s, c[2] + z * s];
        let outside = r#"<emitter type="constant"><rgb name="radiance" value="100"/></emitter>"#;
        let eye = at(0.2, 0.1, -0.3);
        let closed = scene(s, c, eye, "", outside, "cube");
        assert_eq!(
            max_pixel(&closed),
            0.0,
            "scale {s}, centre {c:?}: light leaked in"
        );
        assert!(max_pixel(&scene(s, c, eye, "", outside, "rectangle")) > 0.0);
    }
}
