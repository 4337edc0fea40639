//! Mitsuba's `sphere` with a whole `to_world` (`src/shapes/sphere.cpp`): the surface is the
//! sphere of the transformed centre and radius, and the rotation (or mirror) orients its uv
//! parametrisation: a hit point is mapped back by `to_object`, so that a texture turns with
//! the sphere.

use glam::{DMat3, DMat4, DQuat, DVec3, Vec3};
use radia_formats::load_mitsuba_xml_with_warnings;
use radia_math::Ray;
use radia_scene::Scene;
use std::f64::consts::PI;

/// A scene with the camera at the origin (render space is the file's world space) and one
/// sphere with the `to_world` given as XML.
fn load(name: &str, to_world: &str) -> (Scene, Vec<String>) {
    let dir = std::env::temp_dir().join(format!("radia-sphere-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(format!("{name}.xml"));
    let xml = format!(
        r#"<scene version="3.0.0">
    <sensor type="perspective">
        <transform name="to_world"><lookat origin="0, 0, 0" target="0, 0, -1" up="0, 1, 0"/></transform>
        <film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/></film>
    </sensor>
    <emitter type="constant"/>
    <shape type="sphere">
        <transform name="to_world">{to_world}</transform>
    </shape>
</scene>
"#
    );
    std::fs::write(&path, xml).unwrap();
    let loaded = load_mitsuba_xml_with_warnings(&path, &[]);
    let _ = std::fs::remove_dir_all(&dir);
    let (desc, warnings) = loaded.unwrap_or_else(|e| panic!("{e}"));
    (Scene::build(desc), warnings)
}

/// The point of parameter (u, v) on the sphere that `m` maps the unit sphere onto: the
/// forward map whose inverse the renderer evaluates (Mitsuba's `eval_parameterization`:
/// φ = 2πu from +x towards +y, θ = πv from +z).
fn point_at(m: &DMat4, u: f64, v: f64) -> DVec3 {
    let (phi, theta) = (2.0 * PI * u, PI * v);
    m.transform_point3(DVec3::new(
        theta.sin() * phi.cos(),
        theta.sin() * phi.sin(),
        theta.cos(),
    ))
}

fn close(a: Vec3, b: DVec3, tol: f64) -> bool {
    (a.as_dvec3() - b).length() <= tol * b.length().max(1.0)
}

/// Rays from outside at points of known (u, v): the hit's uv is that (u, v), and ∂p/∂u,
/// ∂p/∂v are the forward map's derivatives by central differences; the shading frame's
/// tangent follows ∂p/∂u; a textured emitter's lookup (`uv_at`) finds the same uv.
fn check_parametrisation(name: &str, to_world_xml: &str, m: DMat4) {
    let (scene, warnings) = load(name, to_world_xml);
    assert!(warnings.is_empty(), "{name}: {warnings:?}");
    let center = m.transform_point3(DVec3::ZERO);
    let radius = m.transform_vector3(DVec3::X).length();
    let mut checked = 0;
    for i in 0..12 {
        for j in 1..8 {
            let (u, v) = ((i as f64 + 0.37) / 12.0, j as f64 / 8.0);
            let p = point_at(&m, u, v);
            let n = (p - center) / radius;
            let origin = p + n * (2.0 * radius);
            let ray = Ray::new(origin.as_vec3(), (-n).as_vec3(), f32::INFINITY);
            let si = scene
                .intersect(&ray)
                .unwrap_or_else(|| panic!("{name}: ray at ({u}, {v}) missed"));
            assert!(close(si.p, p, 1e-5), "{name} ({u}, {v}): p {} vs {p}", si.p);
            let du = (si.uv.x as f64 - u).rem_euclid(1.0);
            assert!(
                du.min(1.0 - du) < 1e-5 && (si.uv.y as f64 - v).abs() < 1e-5,
                "{name}: uv {} at ({u}, {v})",
                si.uv
            );
            let h = 1e-5;
            let dpdu = (point_at(&m, u + h, v) - point_at(&m, u - h, v)) / (2.0 * h);
            let dpdv = (point_at(&m, u, v + h) - point_at(&m, u, v - h)) / (2.0 * h);
            assert!(
                close(si.dp_du, dpdu, 1e-4),
                "{name} ({u}, {v}): dp/du {} vs {dpdu}",
                si.dp_du
            );
            assert!(
                close(si.dp_dv, dpdv, 1e-4),
                "{name} ({u}, {v}): dp/dv {} vs {dpdv}",
                si.dp_dv
            );
            let s = si.frame.s.as_dvec3();
            assert!(
                s.dot(dpdu.normalize()) > 0.9999,
                "{name} ({u}, {v}): shading tangent {s} vs dp/du {dpdu}"
            );
            let uv = scene.shapes[si.shape as usize].uv_at(si.face, si.p);
            assert!(
                (uv - si.uv).abs().max_element() < 1e-5,
                "{name}: uv_at {uv} vs hit {}",
                si.uv
            );
            checked += 1;
        }
    }
    assert_eq!(checked, 84);
}

#[test]
fn sphere_parametrisation_follows_the_whole_to_world() {
    let translate = DVec3::new(0.5, -1.0, -6.0);
    let axis = DVec3::new(1.0, 2.0, -0.5).normalize();
    let angle = 50f64;
    let m = DMat4::from_translation(translate)
        * DMat4::from_quat(DQuat::from_axis_angle(axis, angle.to_radians()))
        * DMat4::from_scale(DVec3::splat(1.5));
    let xml = format!(
        r#"<scale value="1.5"/><rotate x="{}" y="{}" z="{}" angle="{angle}"/><translate x="{}" y="{}" z="{}"/>"#,
        axis.x, axis.y, axis.z, translate.x, translate.y, translate.z
    );
    check_parametrisation("rotated", &xml, m);
    // The unrotated sphere: poles on z, u = 0 towards +x.
    check_parametrisation(
        "translated",
        r#"<scale value="0.7"/><translate z="-4"/>"#,
        DMat4::from_translation(DVec3::new(0.0, 0.0, -4.0)) * DMat4::from_scale(DVec3::splat(0.7)),
    );
}

#[test]
fn a_mirrored_sphere_turns_inside_out_and_its_parametrisation_mirrors() {
    let m = DMat4::from_translation(DVec3::new(0.0, 0.0, -5.0))
        * DMat4::from_mat3(DMat3::from_rotation_x(0.3))
        * DMat4::from_scale(DVec3::new(-1.0, 1.0, 1.0));
    check_parametrisation(
        "mirrored",
        r#"<scale x="-1"/><rotate x="1" angle="17.188733853924695"/><translate z="-5"/>"#,
        m,
    );
    // Mitsuba flips the normals of a mirrored sphere (a negative stretch in the polar
    // decomposition): the normal at a hit from outside points inwards.
    let (scene, _) = load("mirrored-normal", r#"<scale x="-1"/><translate z="-5"/>"#);
    let si = scene
        .intersect(&Ray::new(
            Vec3::ZERO,
            Vec3::new(0.0, 0.0, -1.0),
            f32::INFINITY,
        ))
        .expect("hit");
    assert!(si.n.z < -0.999, "normal {}", si.n);
}
