//! `mask` and `null` surfaces in the path tracer, against ground truth rather than against
//! Mitsuba 3.9.1 (whose shadow rays stop at every surface, so that a point light casts a
//! black shadow through a fully transparent one: see `crates/bsdf/src/mask.rs`):
//!
//! * a `null` rectangle between a point light and the scene, and between the camera and
//!   the scene, changes nothing;
//! * a checkerboard-opacity cut-out renders as its opaque squares modelled as geometry,
//!   under a point light (shadow rays through the holes) and an area light (MIS between
//!   light sampling through the holes and BSDF sampling through them);
//! * the classic integrator sees through a `null` surface too.

mod common;

use common::{render_xml, sensor};
use radia_math::Spectrum;
use radia_render::RenderOutput;

const W: u32 = 48;
const H: u32 = 36;

/// A diffuse floor and box under `lights`, with `extra` shapes, path traced to depth
/// `max_depth`.
fn scene(extra: &str, lights: &str, integrator: &str) -> String {
    format!(
        r#"<scene version="3.0.0">
    {integrator}
    {sensor}
    <shape type="rectangle">
        <transform name="to_world"><scale value="3"/><rotate x="1" angle="-90"/></transform>
        <bsdf type="diffuse"><rgb name="reflectance" value="0.6, 0.5, 0.4"/></bsdf></shape>
    <shape type="cube">
        <transform name="to_world"><scale value="0.3"/><translate x="0.6" y="0.3" z="0.4"/></transform>
        <bsdf type="diffuse"><rgb name="reflectance" value="0.3, 0.6, 0.8"/></bsdf></shape>
    {extra}
    {lights}
</scene>"#,
        sensor = sensor("0, 2.5, 4", "0, 0.3, 0", 45.0, W, H)
    )
}

const PATH: &str = r#"<integrator type="path"/>"#;
const POINT: &str = r#"<emitter type="point"><point name="position" value="-0.3, 2.5, -0.2"/>
    <rgb name="intensity" value="8"/></emitter>"#;
const AREA: &str = r#"<shape type="rectangle">
    <transform name="to_world"><scale value="0.4"/><rotate x="1" angle="90"/><translate x="-0.3" y="2.5" z="-0.2"/></transform>
    <emitter type="area"><rgb name="radiance" value="10"/></emitter></shape>"#;

/// A horizontal rectangle at height 1.2 (between the light and the floor) with `bsdf`;
/// the camera looks at part of the floor through it too.
fn plane(bsdf: &str) -> String {
    format!(
        r#"<shape type="rectangle">
        <transform name="to_world"><scale value="0.9"/><rotate x="1" angle="-90"/><translate y="1.2"/></transform>
        {bsdf}</shape>"#
    )
}

/// The largest relative difference of 6×6-pixel block means (channel sums; relative to at
/// least a fifth of the average block, so that noise in nearly black blocks does not
/// count as a difference) and the relative difference of the image means.
fn differences(a: &RenderOutput, b: &RenderOutput) -> (f64, f64) {
    let px = |img: &RenderOutput, x: u32, y: u32| {
        let p: Spectrum = img.image.pixels[(y * W + x) as usize];
        (p.x + p.y + p.z) as f64
    };
    let floor = 0.2 * 36.0 * 3.0 * a.image.mean().max(b.image.mean());
    let mut worst = 0.0f64;
    for by in 0..H / 6 {
        for bx in 0..W / 6 {
            let (mut sa, mut sb) = (0.0, 0.0);
            for y in by * 6..by * 6 + 6 {
                for x in bx * 6..bx * 6 + 6 {
                    sa += px(a, x, y);
                    sb += px(b, x, y);
                }
            }
            worst = worst.max((sa - sb).abs() / sa.max(sb).max(floor));
        }
    }
    let (ma, mb) = (a.image.mean(), b.image.mean());
    (worst, (ma - mb).abs() / ma.max(mb))
}

#[test]
fn a_null_surface_changes_nothing_for_point_and_area_lights() {
    for (name, lights, spp) in [("point", POINT, 256), ("area", AREA, 512)] {
        let truth = render_xml(
            &format!("null-truth-{name}"),
            &scene("", lights, PATH),
            spp,
            1,
        );
        let null = plane(r#"<bsdf type="null"/>"#);
        let with = render_xml(&format!("null-{name}"), &scene(&null, lights, PATH), spp, 2);
        assert!(with.image.pixels.iter().all(|p| p.is_finite()));
        let (block, mean) = differences(&truth, &with);
        println!("{name}: null plane vs none: worst block {block:.4}, mean {mean:.5}");
        assert!(
            block < 0.06 && mean < 0.01,
            "{name}: block {block}, mean {mean}"
        );
        // Mitsuba 3.9.1's shadow rays would stop at the plane; an opaque black plane shows
        // what that costs under a point light (everything under it in shadow).
        let black = plane(r#"<bsdf type="diffuse"><rgb name="reflectance" value="0"/></bsdf>"#);
        let blocked = render_xml(
            &format!("black-{name}"),
            &scene(&black, lights, PATH),
            16,
            3,
        );
        assert!(
            blocked.image.mean() < 0.8 * truth.image.mean(),
            "{name}: the plane does not shadow much: {} vs {}",
            blocked.image.mean(),
            truth.image.mean()
        );
    }
}

#[test]
fn a_checkerboard_cut_out_renders_as_its_opaque_squares_as_geometry() {
    let nested = r#"<bsdf type="twosided"><bsdf type="diffuse"><rgb name="reflectance" value="0.8, 0.3, 0.3"/></bsdf></bsdf>"#;
    // The checkerboard's scalar lookup (Mitsuba's `eval_1`, which swaps the colours of its
    // `eval`) gives color0 (opacity 1) where floor(2u) and floor(2v) have different
    // parities: the quadrants x < 0, y > 0 and x > 0, y < 0 of the rectangle.
    let masked = plane(&format!(
        r#"<bsdf type="mask"><texture type="checkerboard" name="opacity">
            <float name="color0" value="1"/><float name="color1" value="0"/></texture>{nested}</bsdf>"#
    ));
    let square = |x: f32, y: f32| {
        format!(
            r#"<shape type="rectangle">
        <transform name="to_world"><scale value="0.5"/><translate x="{x}" y="{y}"/>
            <scale value="0.9"/><rotate x="1" angle="-90"/><translate y="1.2"/></transform>
        {nested}</shape>"#
        )
    };
    let geometry = square(-0.5, 0.5) + &square(0.5, -0.5);
    for (name, lights, spp) in [("point", POINT, 256), ("area", AREA, 512)] {
        let truth = render_xml(
            &format!("squares-{name}"),
            &scene(&geometry, lights, PATH),
            spp,
            1,
        );
        let cut = render_xml(
            &format!("mask-{name}"),
            &scene(&masked, lights, PATH),
            spp,
            2,
        );
        assert!(cut.image.pixels.iter().all(|p| p.is_finite()));
        let (block, mean) = differences(&truth, &cut);
        println!("{name}: checkerboard mask vs squares: worst block {block:.4}, mean {mean:.5}");
        assert!(
            block < 0.06 && mean < 0.01,
            "{name}: block {block}, mean {mean}"
        );
    }
    // The comparison sees the other two squares cut out instead.
    let other = square(-0.5, -0.5) + &square(0.5, 0.5);
    let truth = render_xml("squares-other", &scene(&other, POINT, PATH), 64, 1);
    let cut = render_xml("mask-other", &scene(&masked, POINT, PATH), 64, 2);
    let (block, _) = differences(&truth, &cut);
    assert!(block > 0.2, "the other squares went unnoticed: {block}");
}

#[test]
fn null_crossings_count_as_bounces_as_in_mitsuba() {
    // With max_depth 2 (direct light only) a path through one null surface has no segment
    // left for the light behind it: in Mitsuba the BSDF-sampled crossing is a bounce, so
    // radia's shadow rays may not cross either, and the floor under the plane is dark. With
    // max_depth 3 a shadow ray from a floor point the camera sees directly crosses it.
    let null = plane(r#"<bsdf type="null"/>"#);
    let depth = |d: u32| {
        format!(r#"<integrator type="path"><integer name="max_depth" value="{d}"/></integrator>"#)
    };
    let open2 = render_xml("depth2-open", &scene("", POINT, &depth(2)), 16, 1);
    let null2 = render_xml("depth2-null", &scene(&null, POINT, &depth(2)), 16, 1);
    let null3 = render_xml("depth3-null", &scene(&null, POINT, &depth(3)), 16, 1);
    assert!(null2.image.mean() < 0.6 * open2.image.mean());
    assert!(null3.image.mean() > 1.3 * null2.image.mean());
}

#[test]
fn the_classic_integrator_sees_and_shadows_through_a_null_surface() {
    let classic =
        r#"<integrator type="classic"><string name="shading" value="phong"/></integrator>"#;
    let truth = render_xml("classic-open", &scene("", POINT, classic), 4, 1);
    let null = plane(r#"<bsdf type="null"/>"#);
    let with = render_xml("classic-null", &scene(&null, POINT, classic), 4, 1);
    let (block, mean) = differences(&truth, &with);
    assert!(block < 1e-3 && mean < 1e-4, "block {block}, mean {mean}");
}
