//! Statistical tests of light sampling, through the same calls the integrator makes
//! (`Scene::sample_emitter_direction`, `Scene::pdf_emitter_direction`):
//!
//! * chi-square tests of the directions sampled towards every kind of light that has a
//!   density (triangles, rectangles, meshes, spheres, disks, environments) against that
//!   density, from near, far and grazing points, the selection among light primitives
//!   included;
//! * the envmap's sampling on a generated map with a sharp bright spot, zoomed on the spot;
//! * the light selection (uniform, power, BVH): probabilities that sum to one and match the
//!   frequencies of the choices; delta lights' values against closed forms.
//!
//! The density of a direction is found as the integrator finds it: trace a ray from the
//! reference point, ask the light it meets.

use crate::description::*;
use crate::emitter::Emitter;
use crate::lights::{LightContext, LightSamplerKind};
use crate::shape::{MAX_SPHERICAL_SAMPLE_AREA, MIN_SPHERICAL_SAMPLE_AREA};
use crate::spherical::triangle_solid_angle;
use crate::Scene;
use glam::{Affine3A, Vec2, Vec3};
use radia_bsdf::{Bsdf, Diffuse};
use radia_math::{Frame, Ray, PI};
use radia_sampling::chi2::{
    chi2_test, chi2_test_2d, chi2_test_discrete, sidak_alpha, Chi2Config, Chi2Config2d,
    DEFAULT_ALPHA,
};
use radia_sampling::warp;

/// Chi-square tests in this file that are expected to pass (Šidák: the file falsely fails
/// with probability 1%).
const CHI2_TESTS: usize = 41;

fn alpha() -> f64 {
    sidak_alpha(DEFAULT_ALPHA, CHI2_TESTS)
}

// ---------------------------------------------------------------------------------------
// Scenes

fn emitting(geometry: Geometry, radiance: Vec3) -> ShapeDesc {
    ShapeDesc {
        geometry,
        bsdf: Bsdf::Diffuse(Diffuse::new(Vec3::ZERO)),
        emission: Some(radiance.into()),
        origin: "test".into(),
    }
}

fn scene(shapes: Vec<ShapeDesc>, emitters: Vec<EmitterDesc>, kind: LightSamplerKind) -> Scene {
    let mut s = Scene::build(SceneDescription {
        integrator: IntegratorDesc::default(),
        camera: CameraDesc {
            to_world: Affine3A::IDENTITY,
            fov_x_degrees: 45.0,
            near_clip: 0.01,
            far_clip: 1e4,
            principal_point_offset: glam::Vec2::ZERO,
        },
        film: FilmDesc::default(),
        sampler: SamplerDesc::default(),
        shapes,
        shape_groups: Vec::new(),
        world_origin: glam::DVec3::ZERO,
        emitters,
        sampling_weights: Default::default(),
    });
    s.set_light_sampler(kind);
    s
}

fn mesh(positions: Vec<Vec3>, indices: Vec<[u32; 3]>) -> Geometry {
    Geometry::Mesh(Mesh {
        positions,
        normals: None,
        uvs: None,
        tangents: None,
        indices,
        flip_normals: false,
    })
}

/// One triangle in the plane z = 0, facing +z.
fn triangle() -> Geometry {
    mesh(
        vec![
            Vec3::new(-0.5, -0.4, 0.0),
            Vec3::new(0.7, -0.2, 0.0),
            Vec3::new(0.1, 0.6, 0.0),
        ],
        vec![[0, 1, 2]],
    )
}

/// Mitsuba's rectangle [−1, 1]² × {0} scaled by `s`, facing +z (two triangles).
fn rectangle(s: f32) -> Geometry {
    mesh(
        vec![
            Vec3::new(-s, -s, 0.0),
            Vec3::new(s, -s, 0.0),
            Vec3::new(s, s, 0.0),
            Vec3::new(-s, s, 0.0),
        ],
        vec![[0, 1, 2], [2, 3, 0]],
    )
}

/// An axis-aligned box of half-size `h` around `c`, normals outwards (12 triangles).
fn cube(c: Vec3, h: Vec3) -> Geometry {
    let p: Vec<Vec3> = (0..8)
        .map(|i| {
            c + h * Vec3::new(
                if i & 1 != 0 { 1.0 } else { -1.0 },
                if i & 2 != 0 { 1.0 } else { -1.0 },
                if i & 4 != 0 { 1.0 } else { -1.0 },
            )
        })
        .collect();
    // Faces as quads (counter-clockwise seen from outside).
    let quads = [
        [0, 2, 3, 1], // −z
        [4, 5, 7, 6], // +z
        [0, 1, 5, 4], // −y
        [2, 6, 7, 3], // +y
        [0, 4, 6, 2], // −x
        [1, 3, 7, 5], // +x
    ];
    let mut idx = Vec::new();
    for q in quads {
        idx.push([q[0], q[1], q[2]]);
        idx.push([q[2], q[3], q[0]]);
    }
    mesh(p, idx)
}

fn disk(center: Vec3, radius: f32, normal: Vec3) -> Geometry {
    let f = Frame::from_normal(normal.normalize());
    Geometry::Disk {
        to_world: Affine3A::from_cols(
            (f.s * radius).into(),
            (f.t * radius).into(),
            f.n.into(),
            center.into(),
        ),
        flip_normals: false,
    }
}

fn sphere(center: Vec3, radius: f32, flip_normals: bool) -> Geometry {
    Geometry::sphere(center, radius, flip_normals)
}

// ---------------------------------------------------------------------------------------
// The chi-square test of light sampling from one point

/// Density of the direction `d` from `ctx` as the integrator computes it for a ray that
/// BSDF sampling sent that way.
fn pdf_towards(scene: &Scene, ctx: &LightContext, d: Vec3) -> f32 {
    match scene.intersect(&Ray::new(ctx.p, d, f32::INFINITY)) {
        Some(si) => match scene.surface_emitter(&si) {
            Some((e, _)) => scene.pdf_emitter_direction(ctx, e, Some(&si), d),
            None => 0.0,
        },
        None => scene
            .environment
            .map_or(0.0, |e| scene.pdf_emitter_direction(ctx, e, None, d)),
    }
}

/// Chi-square test of next-event estimation's directions from (p, n), on a grid zoomed on
/// the cone around `target` of half-angle `half_angle` (π: the whole sphere). A sample whose
/// light is hidden behind another counts as failed: the density of its direction is the
/// visible light's.
fn check_from(scene: &Scene, p: Vec3, n: Vec3, target: Vec3, half_angle: f32, what: &str) {
    let ctx = LightContext { p, n };
    let frame = Frame::from_normal((target - p).normalize());
    let cos_min = if half_angle >= PI {
        -1.0
    } else {
        (half_angle as f64).cos().max(-1.0)
    };
    let cfg = Chi2Config {
        cos_theta_min: cos_min,
        alpha: alpha(),
        ..Default::default()
    };
    let r = chi2_test(
        &cfg,
        |u, u1| {
            let es = scene.sample_emitter_direction(&ctx, u1, u)?;
            // Hidden if something is hit clearly before the sampled point. A ray grazing the
            // edge of the sampled triangle may miss it by round-off, and near a sphere's
            // silhouette the two roots are ill-conditioned: neither is an occluder.
            let visible = scene
                .intersect(&Ray::new(p, es.d, f32::INFINITY))
                .is_none_or(|si| si.t >= es.dist * (1.0 - 1e-2));
            visible.then(|| frame.to_local(es.d))
        },
        |d| pdf_towards(scene, &ctx, frame.to_world(d)) as f64,
    );
    assert!(r.passed, "{what}: from {p}: {}", r.report);
    assert!(
        r.integral_of_pdf <= 1.0 + 2e-3,
        "{what}: from {p}: the density integrates to {}",
        r.integral_of_pdf
    );
}

/// The half-angle of the cone around the centre of a sphere (c, r) seen from `p`, widened by
/// a half so that the grid's border cells see nothing, or π from inside.
fn cone_around(p: Vec3, c: Vec3, r: f32) -> f32 {
    let d = (c - p).length();
    if d <= r * 1.01 {
        PI
    } else {
        ((r / d).asin() * 1.5).min(PI)
    }
}

// ---------------------------------------------------------------------------------------
// Area lights

/// Chi-square test of next-event estimation on a mesh light, in the domain of its
/// triangles rather than of directions: triangle k is mapped onto [k, k + 1] × [0, 1] by the
/// inverse of the uniform triangle warp (whose Jacobian is the triangle's area), so the
/// density of a point there is pdf_ω · cos θ_light / d² · area. A polygon's support then
/// fills the grid's cells instead of clipping their corners, where the quadrature of the
/// density cannot see it.
fn check_mesh_from(scene: &Scene, tris: &[[Vec3; 3]], p: Vec3, n: Vec3, what: &str) {
    let ctx = LightContext { p, n };
    let k = tris.len();
    let cfg = Chi2Config2d {
        x_res: (30 * k).max(51),
        y_res: 30,
        alpha: alpha(),
        ..Chi2Config2d::new(Vec2::ZERO, Vec2::new(k as f32, 1.0))
    };
    let normal = |v: &[Vec3; 3]| (v[1] - v[0]).cross(v[2] - v[0]);
    let r = chi2_test_2d(
        &cfg,
        |u, u1| {
            let es = scene.sample_emitter_direction(&ctx, u1, u)?;
            // The triangle the point lies on: in its plane and inside it.
            let (t, b) = tris
                .iter()
                .enumerate()
                .map(|(t, v)| {
                    let nv = normal(v);
                    let area2 = nv.length_squared();
                    let b1 = (es.p - v[0]).cross(v[2] - v[0]).dot(nv) / area2;
                    let b2 = (v[1] - v[0]).cross(es.p - v[0]).dot(nv) / area2;
                    let off_plane = (es.p - v[0]).dot(nv).abs() / area2.sqrt();
                    let outside = (-b1).max(-b2).max(b1 + b2 - 1.0).max(0.0);
                    (off_plane + outside, t, Vec2::new(b1, b2))
                })
                .min_by(|a, b| a.0.total_cmp(&b.0))
                .map(|(_, t, b)| (t, b))?;
            let q = warp::uniform_triangle_to_square(b.clamp(Vec2::ZERO, Vec2::ONE));
            Some(Vec2::new(t as f32 + q.x.min(0.999_999), q.y))
        },
        |x| {
            let t = (x.x as usize).min(k - 1);
            let v = &tris[t];
            let b = warp::square_to_uniform_triangle(Vec2::new(x.x - t as f32, x.y));
            let q = v[0] * (1.0 - b.x - b.y) + v[1] * b.x + v[2] * b.y;
            let delta = q - p;
            let dist2 = delta.length_squared();
            let d = delta / dist2.sqrt();
            let nv = normal(v);
            let cos = nv.normalize().dot(d).abs();
            let area = 0.5 * nv.length();
            // Only a first hit on this very triangle counts: a point hidden behind the mesh's
            // front faces, or on the edge of a back face, is never reached by sampling it.
            let pdf = match scene.intersect(&Ray::new(p, d, f32::INFINITY)) {
                Some(si) if si.face == t as u32 && si.t >= dist2.sqrt() * (1.0 - 1e-3) => {
                    let (e, _) = scene.surface_emitter(&si).unwrap();
                    scene.pdf_emitter_direction(&ctx, e, Some(&si), d)
                }
                _ => 0.0,
            };
            (pdf * cos / dist2 * area) as f64
        },
    );
    assert!(r.passed, "{what}: from {p}: {}", r.report);
}

/// The triangles of a mesh geometry.
fn triangles(g: &Geometry) -> Vec<[Vec3; 3]> {
    match g {
        Geometry::Mesh(m) => m
            .indices
            .iter()
            .map(|idx| idx.map(|i| m.positions[i as usize]))
            .collect(),
        _ => unreachable!(),
    }
}

#[test]
fn chi2_triangle_near_far_grazing() {
    let s = scene(
        vec![emitting(triangle(), Vec3::ONE)],
        vec![],
        LightSamplerKind::Bvh,
    );
    let tris = triangles(&triangle());
    let near = Vec3::new(0.3, -0.1, 0.4);
    let far = Vec3::new(-20.0, 30.0, 60.0);
    let grazing = Vec3::new(1.5, 0.4, 0.02);
    // Near samples the spherical triangle (1.6 sr); far and grazing, where it subtends
    // less than `MIN_SPHERICAL_SAMPLE_AREA`, by area.
    let omega = |p: Vec3| triangle_solid_angle(&tris[0], p);
    assert!(omega(near) >= MIN_SPHERICAL_SAMPLE_AREA);
    assert!(omega(far) < MIN_SPHERICAL_SAMPLE_AREA);
    assert!(omega(grazing) < MIN_SPHERICAL_SAMPLE_AREA);
    for (p, n) in [(near, -Vec3::Z), (far, Vec3::ZERO), (grazing, Vec3::X)] {
        check_mesh_from(&s, &tris, p, n, "triangle");
    }
}

/// The spherical-triangle sampler where single precision is tested hardest: a sliver (a
/// corner angle of about a degree) seen from just above its middle and from near its narrow
/// end, and a large triangle seen from so close that it fills most of the hemisphere
/// (4.3 and 5.9 sr, below pbrt-v4's 6.22 sr limit). Every point is one the renderer samples
/// by solid angle. (In single precision, as pbrt-v4 writes it, the sliver seen from near its
/// narrow end fails: there cos b′ is within 10⁻⁷ of 1, √(1 − cos² b′) keeps few digits, and
/// the barycentrics near the edge are off by 10⁻⁴, a tenth of their size.)
#[test]
fn chi2_spherical_triangles_thin_and_wide() {
    let cases = [
        (
            [(-2.0, 0.0), (2.0, 0.0), (0.0, 0.05)],
            [Vec3::new(0.0, 0.02, 0.03), Vec3::new(1.5, 0.01, 0.02)],
        ),
        (
            [(-10.0, -10.0), (10.0, -10.0), (0.0, 10.0)],
            [Vec3::new(0.0, -2.0, 0.5), Vec3::new(3.0, -9.0, 1.0)],
        ),
    ];
    for (corners, points) in cases {
        let g = mesh(
            corners.map(|(x, y)| Vec3::new(x, y, 0.0)).to_vec(),
            vec![[0, 1, 2]],
        );
        let tris = triangles(&g);
        let s = scene(vec![emitting(g, Vec3::ONE)], vec![], LightSamplerKind::Bvh);
        for p in points {
            let omega = triangle_solid_angle(&tris[0], p);
            assert!(
                (MIN_SPHERICAL_SAMPLE_AREA..=MAX_SPHERICAL_SAMPLE_AREA).contains(&omega),
                "{omega} sr from {p}"
            );
            check_mesh_from(&s, &tris, p, Vec3::ZERO, "spherical triangle");
        }
    }
}

#[test]
fn chi2_rectangle_uniform_power_bvh() {
    let points = [
        (Vec3::new(0.2, 0.1, 0.3), -Vec3::Z),
        (
            Vec3::new(-3.0, 2.0, 1.5),
            Vec3::new(1.0, 0.0, 1.0).normalize(),
        ),
        (Vec3::new(0.0, -2.0, 0.01), Vec3::Y),
    ];
    let tris = triangles(&rectangle(0.5));
    for kind in [
        LightSamplerKind::Uniform,
        LightSamplerKind::Power,
        LightSamplerKind::Bvh,
    ] {
        let s = scene(
            vec![emitting(rectangle(0.5), Vec3::new(4.0, 3.0, 2.0))],
            vec![],
            kind,
        );
        for (p, n) in points {
            check_mesh_from(&s, &tris, p, n, "rectangle");
        }
    }
}

#[test]
fn chi2_sphere_near_far_grazing_inside() {
    let c = Vec3::new(0.0, 1.0, 0.0);
    let s = scene(
        vec![emitting(sphere(c, 0.5, false), Vec3::ONE)],
        vec![],
        LightSamplerKind::Bvh,
    );
    for p in [
        Vec3::new(0.3, 0.0, 0.4),
        Vec3::new(60.0, -50.0, 40.0),
        // Just above the surface: the cone is nearly a hemisphere.
        c + Vec3::new(0.0, 0.0, 0.5003),
    ] {
        check_from(&s, p, Vec3::ZERO, c, cone_around(p, c, 0.5), "sphere");
    }
    // Inside a sphere that emits inwards: area sampling.
    let s = scene(
        vec![emitting(sphere(c, 0.5, true), Vec3::ONE)],
        vec![],
        LightSamplerKind::Bvh,
    );
    check_from(
        &s,
        c + Vec3::new(0.1, 0.2, -0.15),
        Vec3::Y,
        c,
        PI,
        "sphere inside",
    );
}

#[test]
fn chi2_tiny_distant_sphere() {
    // sin² θmax = 2.5·10⁻⁷: 1 − cos θmax needs the cancellation-free form.
    let c = Vec3::new(100.0, 0.0, 0.0);
    let s = scene(
        vec![emitting(sphere(c, 0.05, false), Vec3::ONE)],
        vec![],
        LightSamplerKind::Bvh,
    );
    check_from(
        &s,
        Vec3::ZERO,
        Vec3::X,
        c,
        cone_around(Vec3::ZERO, c, 0.05),
        "tiny sphere",
    );
}

#[test]
fn chi2_disk_near_far_grazing() {
    let c = Vec3::new(0.0, 0.0, 1.0);
    let n = Vec3::new(0.2, -0.3, -1.0).normalize();
    let s = scene(
        vec![emitting(disk(c, 0.4, n), Vec3::ONE)],
        vec![],
        LightSamplerKind::Bvh,
    );
    let f = Frame::from_normal(n);
    for p in [
        c + n * 0.3 + f.s * 0.1,
        c + n * 40.0 + f.t * 7.0,
        c + n * 0.06 + f.s * 1.0,
    ] {
        check_from(&s, p, -n, c, cone_around(p, c, 0.4), "disk");
    }
}

#[test]
fn chi2_cube_mesh_light_by_bvh_and_uniform() {
    // Twelve triangles, half of them facing away from any outside point.
    let c = Vec3::new(0.0, 0.5, 0.0);
    let h = Vec3::new(0.3, 0.2, 0.4);
    let tris = triangles(&cube(c, h));
    for kind in [LightSamplerKind::Bvh, LightSamplerKind::Uniform] {
        let s = scene(vec![emitting(cube(c, h), Vec3::ONE)], vec![], kind);
        for (p, n) in [
            (Vec3::new(0.5, -0.2, 0.6), Vec3::Y),
            (Vec3::new(-4.0, 3.0, 1.0), Vec3::ZERO),
        ] {
            check_mesh_from(&s, &tris, p, n, "cube");
        }
    }
}

#[test]
fn chi2_many_lights_mixed_by_bvh() {
    // Small spheres, triangles and disks around the point, plus a constant environment:
    // the selection probabilities enter the density of every direction.
    let mut shapes = Vec::new();
    for i in 0..6 {
        let a = i as f32 * 1.1;
        let c = Vec3::new(a.cos() * 1.5, 0.5 + 0.3 * i as f32, a.sin() * 1.5);
        shapes.push(emitting(
            sphere(c, 0.1 + 0.05 * i as f32, false),
            Vec3::splat(1.0 + i as f32),
        ));
        shapes.push(emitting(
            disk(c * 1.3 + Vec3::Y, 0.2, -c),
            Vec3::new(2.0, 1.0, 0.5),
        ));
    }
    shapes.push(emitting(rectangle(0.3), Vec3::splat(3.0)));
    let s = scene(
        shapes,
        vec![EmitterDesc::Constant {
            radiance: Vec3::splat(0.2),
        }],
        LightSamplerKind::Bvh,
    );
    check_from(
        &s,
        Vec3::new(0.1, 1.0, 0.2),
        Vec3::ZERO,
        Vec3::Y,
        PI,
        "mixed",
    );
}

// ---------------------------------------------------------------------------------------
// Environments

#[test]
fn chi2_constant_environment() {
    // (Mitsuba's uniform choice: radia's own leave a constant environment to BSDF sampling.)
    let s = scene(
        vec![],
        vec![EmitterDesc::Constant {
            radiance: Vec3::splat(2.0),
        }],
        LightSamplerKind::Uniform,
    );
    check_from(&s, Vec3::ZERO, Vec3::Z, Vec3::Z, PI, "constant");
}

/// A W × H map: a smooth sky, darker below the horizon, with a sun of a few texels `sun`
/// times brighter centred on texel (si, sj).
fn sky_image(w: u32, h: u32, si: u32, sj: u32, sun: f32) -> RgbImage {
    let mut pixels = Vec::new();
    for j in 0..h {
        for i in 0..w {
            let v = j as f32 / (h - 1) as f32;
            let base = if v < 0.5 { 0.6 + 0.4 * v } else { 0.1 };
            let mut c =
                Vec3::new(base * 0.8, base * 0.9, base) * (1.0 + 0.2 * (i as f32 * 0.7).sin());
            let (di, dj) = (i as i32 - si as i32, j as i32 - sj as i32);
            if di.abs() <= 1 && dj.abs() <= 1 {
                c += Vec3::new(1.0, 0.9, 0.7) * sun * if di == 0 && dj == 0 { 1.0 } else { 0.3 };
            }
            pixels.push(c);
        }
    }
    RgbImage {
        width: w,
        height: h,
        pixels,
    }
}

/// Mitsuba's direction of (u, v) in the envmap's frame (envmap.cpp's `uv_to_direction`).
fn uv_to_direction(u: f32, v: f32) -> Vec3 {
    let (st, ct) = (v * PI).sin_cos();
    let (sp, cp) = (u * 2.0 * PI).sin_cos();
    Vec3::new(sp * st, ct, -cp * st)
}

fn envmap_scene(image: RgbImage, to_world: Affine3A) -> Scene {
    scene(
        vec![],
        vec![EmitterDesc::Envmap {
            image,
            scale: 1.0,
            to_world,
            mis_compensation: false,
        }],
        LightSamplerKind::Bvh,
    )
}

#[test]
fn chi2_envmap_with_a_sun() {
    let (w, h) = (48, 25);
    let (si, sj) = (31, 7);
    let to_world = Affine3A::from_rotation_y(0.7) * Affine3A::from_rotation_x(-0.4);
    let s = envmap_scene(sky_image(w, h, si, sj, 5000.0), to_world);
    let sun = to_world.transform_vector3(uv_to_direction(
        (si as f32 + 0.5) / w as f32,
        sj as f32 / (h - 1) as f32,
    ));
    // The whole sphere, then a cap of 0.3 rad around the sun (the sun's texels span about
    // 2 × 0.13 rad in each direction).
    check_from(&s, Vec3::ZERO, Vec3::ZERO, Vec3::Y, PI, "envmap");
    check_from(&s, Vec3::ZERO, Vec3::ZERO, sun, 0.3, "envmap sun");
    // Most samples go to the sun.
    let ctx = LightContext {
        p: Vec3::ZERO,
        n: Vec3::ZERO,
    };
    let mut towards_sun = 0;
    for k in 0..1000 {
        let u = Vec2::new(
            (k as f32 + 0.5) / 1000.0,
            ((k * 7919) % 1000) as f32 / 1000.0,
        );
        let es = s.sample_emitter_direction(&ctx, 0.5, u).unwrap();
        if es.d.dot(sun) > 0.3f32.cos() {
            towards_sun += 1;
        }
    }
    assert!(
        towards_sun > 800,
        "{towards_sun} of 1000 samples near the sun"
    );
}

/// A tall thin map with bright poles and the sun on the seam (column 0).
fn poles_image() -> RgbImage {
    let (w, h) = (8, 33);
    let mut img = sky_image(w, h, 0, 16, 300.0);
    for i in 0..w as usize {
        img.pixels[i] = Vec3::splat(50.0);
        img.pixels[(h as usize - 1) * w as usize + i] = Vec3::splat(20.0);
    }
    img
}

fn poles_envmap(mis_compensation: bool) -> Emitter {
    Emitter::from_desc(&EmitterDesc::Envmap {
        image: poles_image(),
        scale: 2.0,
        to_world: Affine3A::IDENTITY,
        mis_compensation,
    })
}

#[test]
fn chi2_envmap_poles_and_seam() {
    // The rows at the poles and the periodic wrap are sampled right.
    let s = scene(
        vec![],
        vec![EmitterDesc::Envmap {
            image: poles_image(),
            scale: 2.0,
            to_world: Affine3A::IDENTITY,
            mis_compensation: false,
        }],
        LightSamplerKind::Bvh,
    );
    // A grid whose pole is not the map's, so no row of grid cells straddles a
    // discontinuity of the density all the way round.
    check_from(
        &s,
        Vec3::ZERO,
        Vec3::ZERO,
        Vec3::new(1.0, 0.3, 0.5),
        PI,
        "envmap poles",
    );
}

/// A 24 × 12 map of a dim sky with one texel 10⁵ times brighter at (7, 4), a black block
/// around (16..20, 6..10) and, inside it, at (18, 8), a texel with a positive red and a
/// negative green component whose luminance is negative. The height is even: a row of cells
/// straddles the horizon.
fn bright_texel_image() -> (RgbImage, (u32, u32)) {
    let (w, h) = (24u32, 12u32);
    let mut pixels = vec![Vec3::new(0.15, 0.2, 0.3); (w * h) as usize];
    pixels[(4 * w + 7) as usize] = Vec3::splat(2e4);
    for j in 6..=10 {
        for i in 16..=20 {
            pixels[(j * w + i) as usize] = Vec3::ZERO;
        }
    }
    pixels[(8 * w + 18) as usize] = Vec3::new(1.0, -0.5, 0.0);
    (
        RgbImage {
            width: w,
            height: h,
            pixels,
        },
        (7, 4),
    )
}

#[test]
fn chi2_envmap_one_bright_texel() {
    let (img, (si, sj)) = bright_texel_image();
    let (w, h) = (img.width, img.height);
    let to_world = Affine3A::from_rotation_z(0.4);
    let s = envmap_scene(img, to_world);
    let texel = to_world.transform_vector3(uv_to_direction(
        (si as f32 + 0.5) / w as f32,
        sj as f32 / (h - 1) as f32,
    ));
    check_from(
        &s,
        Vec3::ZERO,
        Vec3::ZERO,
        Vec3::Y,
        PI,
        "envmap bright texel",
    );
    // The four cells around the texel span ±0.26 rad in each direction.
    check_from(
        &s,
        Vec3::ZERO,
        Vec3::ZERO,
        texel,
        0.35,
        "envmap bright texel, zoomed",
    );
}

#[test]
fn envmap_density_is_positive_where_radiance_is() {
    let (img, _) = bright_texel_image();
    let e = Emitter::from_desc(&EmitterDesc::Envmap {
        image: img,
        scale: 1.0,
        to_world: Affine3A::IDENTITY,
        mis_compensation: false,
    });
    let (n_u, n_v) = (480, 240);
    let (mut black, mut lit) = (0, 0);
    for a in 0..n_u {
        for b in 0..n_v {
            let d = uv_to_direction(
                (a as f32 + 0.37) / n_u as f32,
                (b as f32 + 0.61) / n_v as f32,
            );
            let l = e.eval_environment(d);
            let pdf = e.pdf_direction(&[], Vec3::ZERO, None, d);
            assert!(pdf.is_finite() && pdf >= 0.0);
            if l.max_element() > 0.0 {
                lit += 1;
                assert!(pdf > 0.0, "radiance {l} but density 0 at {d}");
            } else {
                black += 1;
                assert_eq!(pdf, 0.0, "black at {d} but density {pdf}");
            }
        }
    }
    // Both kinds were probed (the black block, the negative-luminance texel's cells).
    assert!(black > 100 && lit > 100, "{black} black, {lit} lit");
    // The texel of negative luminance is sampled: the density at it is not zero.
    let d = uv_to_direction(18.5 / 24.0, 8.0 / 11.0);
    assert!(e.pdf_direction(&[], Vec3::ZERO, None, d) > 0.0);
}

/// ∫ pdf dω by the midpoint rule on an n × n grid in (cos θ, φ).
fn integral_of_pdf(e: &Emitter, n: usize) -> f64 {
    let mut sum = 0.0f64;
    for a in 0..n {
        let z = 1.0 - 2.0 * (a as f64 + 0.5) / n as f64;
        let r = (1.0 - z * z).sqrt();
        for b in 0..n {
            let phi = std::f64::consts::TAU * (b as f64 + 0.5) / n as f64;
            let d = Vec3::new((r * phi.cos()) as f32, (r * phi.sin()) as f32, z as f32);
            sum += e.pdf_direction(&[], Vec3::ZERO, None, d) as f64;
        }
    }
    sum * 4.0 * std::f64::consts::PI / (n * n) as f64
}

#[test]
fn envmap_mis_compensation_is_consistent() {
    // Mitsuba's MIS compensation gives the cells darker than average no samples: their
    // density drops to zero, a discontinuity the chi-square quadrature cannot follow, so
    // here the density is checked directly against the samples and for normalization.
    let (plain, compensated) = (poles_envmap(false), poles_envmap(true));
    for e in [&plain, &compensated] {
        let integral = integral_of_pdf(e, 1000);
        assert!((integral - 1.0).abs() < 1e-3, "∫ pdf = {integral}");
        let mut worst = 0.0f32;
        for k in 0..100_000u32 {
            let u = Vec2::new(
                ((k as u64 * 2654435761) % 1_000_003) as f32 / 1_000_003.0,
                (k as f32 + 0.5) / 1e5,
            );
            let es = e.sample_direction(&[], Vec3::ZERO, 0, u).unwrap();
            assert!(es.pdf > 0.0);
            let pdf = e.pdf_direction(&[], Vec3::ZERO, None, es.d);
            // The sampler returns its density at the point it drew; pdf_direction finds
            // that point again from the direction, up to the direction's round-off.
            worst = worst.max((pdf - es.pdf).abs() / es.pdf);
            // Equal up to the round-off of the direction (steep near the sun's texels).
            let l = e.eval_environment(es.d);
            let tolerance = 1e-3 * (es.radiance.max_element() + 1.0);
            assert!(
                (es.radiance - l).abs().max_element() < tolerance,
                "{} vs {l}",
                es.radiance
            );
        }
        // Measured: 6.8e-5 on the plain map, 1.04e-4 on the compensated one, whose weights
        // drop to zero within a cell, at directions one ulp-scale step from a row border.
        // A wrong factor or a wrong cell would be off by far more than 1e-3.
        assert!(
            worst < 1e-3,
            "a sample's pdf differs from pdf_direction by {worst} (relative)"
        );
        eprintln!("largest relative difference of a sample's pdf from pdf_direction: {worst}");
    }
    // Below-average directions are never sampled once compensated (the horizon band is dark).
    let dark = Vec3::new(1.0, -0.6, 0.3).normalize();
    assert!(plain.pdf_direction(&[], Vec3::ZERO, None, dark) > 0.0);
    assert_eq!(compensated.pdf_direction(&[], Vec3::ZERO, None, dark), 0.0);
}

#[test]
fn envmap_mapping_is_mitsubas() {
    // Texel centres: column i at u = (i + ½)/W, row j at v = j/(H − 1).
    let (w, h) = (6u32, 5u32);
    let img = RgbImage {
        width: w,
        height: h,
        pixels: (0..w * h).map(|k| Vec3::new(k as f32, 1.0, 0.0)).collect(),
    };
    let to_world = Affine3A::from_rotation_z(0.3);
    let e = Emitter::from_desc(&EmitterDesc::Envmap {
        image: img,
        scale: 3.0,
        to_world,
        mis_compensation: false,
    });
    for j in 1..h - 1 {
        for i in 0..w {
            let d = uv_to_direction((i as f32 + 0.5) / w as f32, j as f32 / (h - 1) as f32);
            let l = e.eval_environment(to_world.transform_vector3(d));
            let expect = 3.0 * (j * w + i) as f32;
            assert!(
                (l.x - expect).abs() < 2e-3 * expect.max(1.0),
                "texel ({i}, {j}): {l}"
            );
            assert!((l.y - 3.0).abs() < 1e-4);
        }
    }
    // Half-way between columns 5 and 0 (the seam, u = 0): their mean.
    let d = uv_to_direction(0.0, 2.0 / 4.0);
    let l = e.eval_environment(to_world.transform_vector3(d));
    assert!((l.x - 3.0 * (12.0 + 17.0) / 2.0).abs() < 1e-2, "{l}");
    // The local +y axis is the first row; −z is u = 0.
    let zenith = e.eval_environment(to_world.transform_vector3(Vec3::Y));
    assert!(zenith.x < 3.0 * 6.0, "{zenith}");
}

// ---------------------------------------------------------------------------------------
// Light selection

/// 192 light primitives of every kind with a position, scattered, plus lights at infinity.
fn many_lights(kind: LightSamplerKind, with_infinite: bool) -> Scene {
    let mut shapes = Vec::new();
    let mut emitters = Vec::new();
    let mut seed = 12345u32;
    let mut rnd = || {
        seed = seed.wrapping_mul(1664525).wrapping_add(1013904223);
        (seed >> 8) as f32 / (1u32 << 24) as f32
    };
    for i in 0..60 {
        let c = Vec3::new(rnd() * 8.0 - 4.0, rnd() * 3.0, rnd() * 8.0 - 4.0);
        let l = Vec3::new(rnd(), rnd(), rnd()) * (0.1 + 10.0 * rnd());
        match i % 5 {
            0 => shapes.push(emitting(sphere(c, 0.05 + 0.2 * rnd(), false), l)),
            1 => {
                let n = Vec3::new(rnd() - 0.5, rnd() - 0.5, rnd() - 0.5);
                shapes.push(emitting(disk(c, 0.1 + 0.2 * rnd(), n), l));
            }
            2 => shapes.push(emitting(
                cube(c, Vec3::new(0.1, 0.2, 0.15) * (0.5 + rnd())),
                l,
            )),
            3 => emitters.push(EmitterDesc::Point {
                position: c,
                intensity: l,
            }),
            _ => emitters.push(EmitterDesc::Spot {
                to_world: crate::look_at(c, c + Vec3::new(rnd() - 0.5, -1.0, rnd() - 0.5), Vec3::Z)
                    .unwrap(),
                intensity: l,
                cutoff_angle: 20.0 + 40.0 * rnd(),
                beam_width: 15.0,
                falloff_exponent: None,
            }),
        }
    }
    if with_infinite {
        emitters.push(EmitterDesc::Directional {
            direction: Vec3::new(0.3, -1.0, 0.2),
            irradiance: Vec3::splat(2.0),
        });
        emitters.push(EmitterDesc::Directional {
            direction: Vec3::new(-0.5, -1.0, 0.1),
            irradiance: Vec3::splat(0.7),
        });
        // Last: chosen by the uniform strategy only (`a_constant_environment_is_left_to_bsdf_sampling`).
        emitters.push(EmitterDesc::Constant {
            radiance: Vec3::splat(0.3),
        });
    }
    scene(shapes, emitters, kind)
}

fn contexts() -> Vec<LightContext> {
    vec![
        LightContext {
            p: Vec3::new(0.1, 0.0, 0.2),
            n: Vec3::Y,
        },
        LightContext {
            p: Vec3::new(-3.5, 1.2, 3.0),
            n: Vec3::new(1.0, 0.5, -1.0).normalize(),
        },
        LightContext {
            p: Vec3::new(20.0, 5.0, -7.0),
            n: Vec3::ZERO,
        },
        // In the middle of the lights, facing down.
        LightContext {
            p: Vec3::new(0.0, 1.5, 0.0),
            n: -Vec3::Y,
        },
    ]
}

#[test]
fn bvh_selection_sums_to_one_and_matches_its_sampling() {
    for with_infinite in [false, true] {
        let s = many_lights(LightSamplerKind::Bvh, with_infinite);
        let lights = &s.lights;
        assert!(lights.len() > 180);
        for ctx in contexts() {
            let pmf: Vec<f64> = (0..lights.len())
                .map(|i| lights.pmf(&ctx, i) as f64)
                .collect();
            let sum: f64 = pmf.iter().sum();
            assert!((sum - 1.0).abs() < 1e-4, "at {}: Σ pmf = {sum}", ctx.p);
            // The probability sampling reports is the one pmf() recomputes.
            for k in 0..2000 {
                let u = (k as f32 + 0.5) / 2000.0;
                let (i, p) = lights.sample(&ctx, u).expect("a light");
                assert!(
                    (p as f64 - pmf[i]).abs() <= 1e-5 * pmf[i],
                    "light {i}: sampled with {p}, pmf {}",
                    pmf[i]
                );
            }
            let r = chi2_test_discrete(
                lights.len(),
                1_000_000,
                7,
                alpha(),
                |u, _| lights.sample(&ctx, u).map(|(i, _)| i),
                |i| pmf[i],
            );
            assert!(r.passed, "at {}: {}", ctx.p, r.report);
        }
    }
}

#[test]
fn bvh_selection_follows_distance_and_orientation() {
    // Two equal lights: the near one is chosen more often, and a light facing away from the
    // point is never chosen.
    let shapes = vec![
        emitting(disk(Vec3::new(0.0, 1.0, 0.0), 0.1, -Vec3::Y), Vec3::ONE),
        emitting(disk(Vec3::new(3.0, 1.0, 0.0), 0.1, -Vec3::Y), Vec3::ONE),
        emitting(disk(Vec3::new(-1.0, 1.0, 0.0), 0.1, Vec3::Y), Vec3::ONE),
    ];
    let s = scene(shapes, vec![], LightSamplerKind::Bvh);
    let ctx = LightContext {
        p: Vec3::ZERO,
        n: Vec3::Y,
    };
    let (near, far, away) = (
        s.lights.pmf(&ctx, 0),
        s.lights.pmf(&ctx, 1),
        s.lights.pmf(&ctx, 2),
    );
    assert!(near > 5.0 * far, "near {near}, far {far}");
    assert_eq!(away, 0.0);
    assert!((near + far - 1.0).abs() < 1e-6);
}

#[test]
fn uniform_and_power_tables() {
    for kind in [LightSamplerKind::Uniform, LightSamplerKind::Power] {
        let s = many_lights(kind, true);
        let ctx = contexts()[0];
        let n = s.lights.len();
        let pmf: Vec<f64> = (0..n).map(|i| s.lights.pmf(&ctx, i) as f64).collect();
        assert!((pmf.iter().sum::<f64>() - 1.0).abs() < 1e-4);
        let r = chi2_test_discrete(
            n,
            1_000_000,
            8,
            alpha(),
            |u, _| s.lights.sample(&ctx, u).map(|(i, _)| i),
            |i| pmf[i],
        );
        assert!(r.passed, "{kind}: {}", r.report);
    }
    // Uniform is Mitsuba's: each emitter 1/n, a mesh's triangles by area.
    let s = scene(
        vec![
            emitting(rectangle(1.0), Vec3::ONE),
            emitting(sphere(Vec3::Y, 0.1, false), Vec3::splat(100.0)),
        ],
        vec![],
        LightSamplerKind::Uniform,
    );
    let ctx = contexts()[0];
    assert_eq!(s.lights.len(), 3);
    for i in 0..2 {
        assert!((s.lights.pmf(&ctx, i) - 0.25).abs() < 1e-6);
    }
    assert!((s.lights.pmf(&ctx, 2) - 0.5).abs() < 1e-6);
}

#[test]
fn one_light_needs_no_selection() {
    let s = scene(
        vec![emitting(sphere(Vec3::Y, 0.5, false), Vec3::ONE)],
        vec![],
        LightSamplerKind::Bvh,
    );
    let ctx = contexts()[0];
    assert_eq!(s.lights.sample(&ctx, 0.7), Some((0, 1.0)));
    let s = scene(vec![], vec![], LightSamplerKind::Bvh);
    assert!(s.lights.is_empty());
}

fn point_light(position: Vec3) -> EmitterDesc {
    EmitterDesc::Point {
        position,
        intensity: Vec3::ONE,
    }
}

#[test]
fn few_delta_lights_are_split_under_radia_strategies() {
    // An area light with a point, a spot and a directional light: radia's strategies sample
    // the three delta lights at every vertex (density 1 each) and choose among the rest;
    // Mitsuba's uniform choice takes each emitter as one of four.
    let delta = vec![
        point_light(Vec3::new(1.0, 2.0, 0.0)),
        EmitterDesc::Spot {
            to_world: crate::look_at(Vec3::new(0.0, 3.0, 0.0), Vec3::ZERO, Vec3::Z).unwrap(),
            intensity: Vec3::splat(8.0),
            cutoff_angle: 30.0,
            beam_width: 20.0,
            falloff_exponent: None,
        },
        EmitterDesc::Directional {
            direction: Vec3::new(0.0, -1.0, 0.5),
            irradiance: Vec3::splat(2.0),
        },
    ];
    let shapes = vec![emitting(
        sphere(Vec3::new(-1.0, 1.0, 0.0), 0.3, false),
        Vec3::ONE,
    )];
    let ctx = LightContext {
        p: Vec3::new(0.2, 0.0, 0.1),
        n: Vec3::Y,
    };
    for kind in [LightSamplerKind::Bvh, LightSamplerKind::Power] {
        let s = scene(shapes.clone(), delta.clone(), kind);
        let split = s.lights.split().to_vec();
        let deltas: Vec<u32> = (0..s.emitters.len() as u32)
            .filter(|&e| s.emitters[e as usize].is_delta())
            .collect();
        assert_eq!((split.len(), &split), (3, &deltas), "{kind}");
        for (i, &e) in split.iter().enumerate() {
            // The emitter's own sample, at density 1.
            let want = s.emitters[e as usize].sample_direction(&s.shapes, ctx.p, 0, Vec2::ZERO);
            let got = s.sample_split_light(i, ctx.p);
            assert_eq!(
                got.map(|g| (g.d, g.radiance, g.pdf)),
                want.map(|w| (w.d, w.radiance, 1.0))
            );
            assert!(got.is_some(), "{kind}: light {e} lights the point");
            assert_eq!(s.lights.pmf(&ctx, s.lights.prim_index(e, 0)), 0.0, "{kind}");
        }
        // The area light is the one left to choose.
        assert!(s.lights.chooses() && !s.lights.is_empty());
        for k in 0..100 {
            let (i, pmf) = s.lights.sample(&ctx, (k as f32 + 0.5) / 100.0).unwrap();
            assert!(
                !s.emitters[s.lights.prim(i).emitter as usize].is_delta(),
                "{kind}"
            );
            assert_eq!(pmf, 1.0, "{kind}");
        }
        // Delta lights alone: nothing to choose, but something to sample.
        let alone = scene(vec![], delta.clone(), kind);
        assert_eq!(alone.lights.split().len(), 3);
        assert!(!alone.lights.chooses() && !alone.lights.is_empty());
    }
    let s = scene(shapes.clone(), delta.clone(), LightSamplerKind::Uniform);
    assert!(s.lights.split().is_empty());
    for e in 0..4 {
        assert_eq!(s.lights.pmf(&ctx, s.lights.prim_index(e, 0)), 0.25);
    }
    // More delta lights than `SPLIT_DELTA_LIGHTS_MAX`: chosen among, as before.
    let many: Vec<EmitterDesc> = (0..=crate::lights::SPLIT_DELTA_LIGHTS_MAX)
        .map(|i| point_light(Vec3::new(i as f32, 2.0, 0.0)))
        .collect();
    let s = scene(vec![], many, LightSamplerKind::Bvh);
    assert!(s.lights.split().is_empty() && s.lights.chooses());
    // A delta light of sampling weight 0 is never sampled (as Mitsuba never chooses it).
    let mut s = scene(
        vec![],
        vec![point_light(Vec3::Y), point_light(Vec3::X)],
        LightSamplerKind::Bvh,
    );
    s.sampling_weights = vec![0.0, 1.0];
    s.set_light_sampler(LightSamplerKind::Bvh);
    assert_eq!(s.lights.split(), &[1]);
    assert!(!s.lights.chooses());
}

#[test]
fn a_lone_emitting_mesh_is_chosen_from_by_the_tree_and_a_rectangle_by_area() {
    // A cube seen from below its −y face: with the default sampler the tree never picks the
    // +y face, turned right away (its bounds are conservative: the side faces, seen at a
    // grazing angle, keep a little), and the −y face gets most of it.
    let ctx = LightContext {
        p: Vec3::new(0.0, -3.0, 0.0),
        n: Vec3::Y,
    };
    let s = scene(
        vec![emitting(cube(Vec3::ZERO, Vec3::splat(0.5)), Vec3::ONE)],
        vec![],
        LightSamplerKind::Bvh,
    );
    let pmf: Vec<f32> = (0..12).map(|i| s.lights.pmf(&ctx, i)).collect();
    // Quads −z, +z, −y, +y, −x, +x in order, two triangles each.
    assert_eq!((pmf[6], pmf[7]), (0.0, 0.0), "{pmf:?}");
    assert!(pmf[4] + pmf[5] > 0.7, "{pmf:?}");
    assert!((pmf.iter().sum::<f32>() - 1.0).abs() < 1e-5, "{pmf:?}");
    // Asked for, Mitsuba's choice: by area.
    let s = scene(
        vec![emitting(cube(Vec3::ZERO, Vec3::splat(0.5)), Vec3::ONE)],
        vec![],
        LightSamplerKind::Uniform,
    );
    for i in 0..12 {
        assert!((s.lights.pmf(&ctx, i) - 1.0 / 12.0).abs() < 1e-6);
    }
    // A lone rectangle: by area whatever the sampler, from anywhere.
    let s = scene(
        vec![emitting(rectangle(1.0), Vec3::ONE)],
        vec![],
        LightSamplerKind::Bvh,
    );
    let near = LightContext {
        p: Vec3::new(0.9, 0.9, 0.1),
        n: -Vec3::Z,
    };
    for i in 0..2 {
        assert_eq!(s.lights.pmf(&near, i), 0.5);
    }
}

// ---------------------------------------------------------------------------------------
// Smooth mesh lights: Mitsuba's convention

/// Mesh `g` moved by `offset`, with `flip_normals` set to `flip`.
fn moved(g: Geometry, offset: Vec3, flip: bool) -> Geometry {
    let Geometry::Mesh(mut m) = g else {
        unreachable!()
    };
    for p in &mut m.positions {
        *p += offset;
    }
    m.flip_normals = flip;
    Geometry::Mesh(m)
}

/// A low cap of three triangles around the z axis, apex up, with vertex normals of a sphere
/// (bent outwards from each facet's own normal), glowing with radiance 1.
fn smooth_cap() -> Geometry {
    let apex = Vec3::new(0.0, 0.0, 0.3);
    let base: Vec<Vec3> = (0..3)
        .map(|k| {
            let a = k as f32 * 2.0 * PI / 3.0;
            Vec3::new(a.cos(), a.sin(), 0.0)
        })
        .collect();
    let mut positions = vec![apex];
    positions.extend(&base);
    let mut normals = vec![Vec3::Z];
    normals.extend(
        base.iter()
            .map(|b| (*b + Vec3::new(0.0, 0.0, 0.5)).normalize()),
    );
    Geometry::Mesh(Mesh {
        positions,
        normals: Some(normals),
        uvs: None,
        tangents: None,
        indices: vec![[0, 1, 2], [0, 2, 3], [0, 3, 1]],
        flip_normals: false,
    })
}

/// What Mitsuba's next-event estimate of a mesh light of radiance 1 converges to from `p`
/// (`src/render/shape.cpp`, `src/emitters/area.cpp`): ∫ |d·n_s| / r² dA over the points whose
/// interpolated vertex normal n_s faces `p` (or, with `smooth` false, the facet's normal: the
/// solid angle the mesh's front faces subtend), by the midpoint rule.
fn cap_integral(g: &Geometry, p: Vec3, smooth: bool) -> f64 {
    let Geometry::Mesh(m) = g else { unreachable!() };
    let n = 600;
    let mut sum = 0.0f64;
    for idx in &m.indices {
        let v = idx.map(|i| m.positions[i as usize]);
        let vn = idx.map(|i| m.normals.as_ref().unwrap()[i as usize]);
        let ng = (v[1] - v[0]).cross(v[2] - v[0]);
        let area = 0.5 * ng.length() as f64;
        let mut acc = 0.0f64;
        for i in 0..n {
            for j in 0..n {
                let u = Vec2::new((i as f32 + 0.5) / n as f32, (j as f32 + 0.5) / n as f32);
                let b = warp::square_to_uniform_triangle(u);
                let y = v[0] * (1.0 - b.x - b.y) + v[1] * b.x + v[2] * b.y;
                let ns = if smooth {
                    (vn[0] * (1.0 - b.x - b.y) + vn[1] * b.x + vn[2] * b.y).normalize()
                } else {
                    ng.normalize()
                };
                let delta = y - p;
                let cos = -ns.dot(delta.normalize());
                if cos > 0.0 {
                    acc += (cos / delta.length_squared()) as f64;
                }
            }
        }
        sum += acc * area / (n * n) as f64;
    }
    sum
}

#[test]
fn a_smooth_mesh_light_glows_about_its_vertex_normals_as_in_mitsuba() {
    let cap = smooth_cap();
    let s = scene(
        vec![emitting(cap.clone(), Vec3::ONE)],
        vec![],
        LightSamplerKind::Bvh,
    );
    let tris = triangles(&cap);
    let mut rng = rand_pcg::Pcg32::new(7, 11);
    use rand::Rng;
    // Above (the triangles by solid angle), far above (by area); below the base plane
    // beside the cap, where every facet is seen from behind but the normals near a base
    // edge face the point (near and far); and far away level with the base, where one facet
    // faces the point and the vertex normals of another bend towards it, which the light
    // tree's bounds of the facet alone would give no importance (its cones must hold the
    // vertex normals).
    for p in [
        Vec3::new(0.3, 0.2, 1.5),
        Vec3::new(60.0, 30.0, 90.0),
        Vec3::new(2.0, 0.0, -1.0),
        Vec3::new(10.0, 17.32, -15.0),
        Vec3::new(12.5, 21.65, -1.0),
    ] {
        let ctx = LightContext { p, n: Vec3::ZERO };
        let (mut sum, mut sum2, n) = (0.0f64, 0.0f64, 400_000);
        let mut checked = 0;
        for _ in 0..n {
            let u = Vec2::new(rng.random(), rng.random());
            let Some(es) = s.sample_emitter_direction(&ctx, rng.random(), u) else {
                continue;
            };
            let x = (es.radiance.x / es.pdf) as f64;
            sum += x;
            sum2 += x * x;
            // The density BSDF sampling's MIS asks for at that point is the same one (away
            // from grazing the shading normal, where its cosine has few significant bits).
            if checked < 2000 {
                if let Some(si) = s.intersect(&Ray::new(p, es.d, f32::INFINITY)) {
                    // Inside the face hit, clear of its edges: the face that was sampled.
                    let v = tris[si.face as usize];
                    let nv = (v[1] - v[0]).cross(v[2] - v[0]);
                    let b1 = (si.p - v[0]).cross(v[2] - v[0]).dot(nv) / nv.length_squared();
                    let b2 = (v[1] - v[0]).cross(si.p - v[0]).dot(nv) / nv.length_squared();
                    let inside = b1.min(b2).min(1.0 - b1 - b2) > 1e-3;
                    if inside
                        && (si.p - es.p).length() < 1e-4 * es.dist
                        && si.frame.n.dot(es.d) < -0.05
                    {
                        let (e, _) = s.surface_emitter(&si).unwrap();
                        let pdf = s.pdf_emitter_direction(&ctx, e, Some(&si), es.d);
                        assert!(
                            (pdf / es.pdf - 1.0).abs() < 2e-3,
                            "from {p}: sampled with pdf {}, asked {pdf}",
                            es.pdf
                        );
                        checked += 1;
                    }
                }
            }
        }
        assert!(checked > 100, "from {p}: {checked} samples checked");
        let mean = sum / n as f64;
        let err = ((sum2 / n as f64 - mean * mean) / n as f64).sqrt();
        let (smooth, flat) = (cap_integral(&cap, p, true), cap_integral(&cap, p, false));
        eprintln!("from {p}: {mean:.6e} ± {err:.1e}, Mitsuba's {smooth:.6e}, facets' {flat:.6e}");
        assert!(
            (mean - smooth).abs() < 4.0 * err + 1e-4 * smooth,
            "from {p}: next-event estimation gives {mean} ± {err}, Mitsuba's integral {smooth}"
        );
        // The two differ by far more than the test's resolution, so it can fail.
        assert!(
            (smooth - flat).abs() > 20.0 * err,
            "{smooth} against {flat}"
        );
    }
}

// ---------------------------------------------------------------------------------------
// Delta lights: values against closed forms

#[test]
fn point_spot_directional_values() {
    // Through Mitsuba's choice, which samples a lone delta light as the chosen one (radia's
    // strategies sample it as a split light, the same sample at density 1:
    // `few_delta_lights_are_split_under_radia_strategies`).
    let ctx = LightContext {
        p: Vec3::new(0.0, 0.0, 0.0),
        n: Vec3::Y,
    };
    let s = scene(
        vec![],
        vec![EmitterDesc::Point {
            position: Vec3::new(0.0, 2.0, 0.0),
            intensity: Vec3::new(4.0, 8.0, 12.0),
        }],
        LightSamplerKind::Uniform,
    );
    let es = s
        .sample_emitter_direction(&ctx, 0.3, Vec2::splat(0.5))
        .unwrap();
    assert!(es.is_delta && es.pdf == 1.0 && (es.dist - 2.0).abs() < 1e-6);
    assert!((es.d - Vec3::Y).length() < 1e-6);
    assert!((es.radiance - Vec3::new(1.0, 2.0, 3.0)).length() < 1e-6);

    // Spot at (0, 2, 0) looking down, cutoff 30°, beam 20°: the receiver at horizontal
    // offset x sees it at angle atan(x / 2).
    let spot = |beam: f32, exponent: Option<f32>| {
        scene(
            vec![],
            vec![EmitterDesc::Spot {
                to_world: crate::look_at(Vec3::new(0.0, 2.0, 0.0), Vec3::ZERO, Vec3::Z).unwrap(),
                intensity: Vec3::splat(8.0),
                cutoff_angle: 30.0,
                beam_width: beam,
                falloff_exponent: exponent,
            }],
            LightSamplerKind::Uniform,
        )
    };
    let at_angle = |s: &Scene, deg: f32| {
        let x = 2.0 * deg.to_radians().tan();
        let ctx = LightContext {
            p: Vec3::new(x, 0.0, 0.0),
            n: Vec3::Y,
        };
        s.sample_emitter_direction(&ctx, 0.5, Vec2::ZERO)
            .map_or(0.0, |es| es.radiance.x * es.dist * es.dist / 8.0)
    };
    let s = spot(20.0, None);
    for (deg, expect) in [
        (0.0, 1.0),
        (19.0, 1.0),
        (25.0, 0.5),
        (27.5, 0.25),
        (31.0, 0.0),
    ] {
        let f = at_angle(&s, deg);
        assert!(
            (f - expect).abs() < 2e-3,
            "spot falloff at {deg}°: {f}, expected {expect}"
        );
    }
    // radia's cos^e extension.
    let s = spot(20.0, Some(8.0));
    for deg in [0.0f32, 10.0, 25.0] {
        let f = at_angle(&s, deg);
        let expect = deg.to_radians().cos().powf(8.0);
        assert!((f - expect).abs() < 1e-3, "cos^8 at {deg}°: {f}");
    }
    assert_eq!(at_angle(&s, 31.0), 0.0);

    let s = scene(
        vec![],
        vec![EmitterDesc::Directional {
            direction: Vec3::new(0.0, -2.0, 0.0),
            irradiance: Vec3::splat(3.0),
        }],
        LightSamplerKind::Uniform,
    );
    let es = s.sample_emitter_direction(&ctx, 0.5, Vec2::ZERO).unwrap();
    assert!(es.is_delta && es.dist.is_infinite());
    assert!((es.d - Vec3::Y).length() < 1e-6 && es.radiance == Vec3::splat(3.0));
}

/// `many_lights` with pseudo-random `sampling_weight`s in {0, 0.25 … 4}, one of 7 emitters
/// at 0 (never chosen by next-event estimation).
fn weighted_lights(kind: LightSamplerKind) -> Scene {
    let mut s = many_lights(kind, true);
    s.sampling_weights = (0..s.emitters.len())
        .map(|e| {
            if e % 7 == 3 {
                0.0
            } else {
                0.25 * (1 + (e * 5) % 16) as f32
            }
        })
        .collect();
    s.set_light_sampler(kind);
    s
}

#[test]
fn sampling_weights_keep_the_pmf_consistent_with_sampling() {
    for kind in [
        LightSamplerKind::Uniform,
        LightSamplerKind::Power,
        LightSamplerKind::Bvh,
    ] {
        let s = weighted_lights(kind);
        let lights = &s.lights;
        for ctx in contexts() {
            let pmf: Vec<f64> = (0..lights.len())
                .map(|i| lights.pmf(&ctx, i) as f64)
                .collect();
            let sum: f64 = pmf.iter().sum();
            assert!(
                (sum - 1.0).abs() < 1e-4,
                "{kind} at {}: Σ pmf = {sum}",
                ctx.p
            );
            for i in 0..lights.len() {
                if s.sampling_weights[lights.prim(i).emitter as usize] == 0.0 {
                    assert_eq!(pmf[i], 0.0, "{kind}: a weight-0 light is chosen");
                }
            }
            for k in 0..2000 {
                let u = (k as f32 + 0.5) / 2000.0;
                let (i, p) = lights.sample(&ctx, u).expect("a light");
                assert!(
                    (p as f64 - pmf[i]).abs() <= 1e-5 * pmf[i],
                    "{kind}: light {i}: sampled with {p}, pmf {}",
                    pmf[i]
                );
            }
            let r = chi2_test_discrete(
                lights.len(),
                1_000_000,
                9,
                alpha(),
                |u, _| lights.sample(&ctx, u).map(|(i, _)| i),
                |i| pmf[i],
            );
            assert!(r.passed, "{kind} at {}: {}", ctx.p, r.report);
        }
    }
}

#[test]
fn sampling_weights_mean_what_mitsuba_means() {
    let ctx = contexts()[0];
    let per_emitter = |s: &Scene| {
        let mut p = vec![0.0f64; s.emitters.len()];
        for i in 0..s.lights.len() {
            p[s.lights.prim(i).emitter as usize] += s.lights.pmf(&ctx, i) as f64;
        }
        p
    };
    // Uniform is Mitsuba's scene.cpp exactly: emitter e with probability w_e / Σw.
    let s = weighted_lights(LightSamplerKind::Uniform);
    let total: f64 = s.sampling_weights.iter().map(|&w| w as f64).sum();
    for (e, p) in per_emitter(&s).iter().enumerate() {
        let expected = s.sampling_weights[e] as f64 / total;
        assert!(
            (p - expected).abs() < 1e-5,
            "emitter {e}: {p} vs {expected}"
        );
    }
    // Power and BVH: a weight multiplies the emitter's odds against every other emitter.
    for kind in [LightSamplerKind::Power, LightSamplerKind::Bvh] {
        let plain = per_emitter(&many_lights(kind, true));
        let weighted = per_emitter(&weighted_lights(kind));
        let w = weighted_lights(kind).sampling_weights;
        // Power: any two emitters (0 and 1 are a sphere and a disk). BVH: the two directional
        // lights at infinity (the tree's inner nodes merge bounds, so between two bounded
        // lights a weight is not an exact factor on the odds, only on the light's own
        // importance). The last emitter, a constant environment, is never chosen by these.
        let n = w.len();
        let pairs: &[(usize, usize)] = if kind == LightSamplerKind::Power {
            &[(0, 1), (0, 2), (n - 3, n - 2), (1, n - 2)]
        } else {
            &[(n - 3, n - 2)]
        };
        for &(a, b) in pairs {
            assert!(
                plain[a] > 0.0 && plain[b] > 0.0,
                "{kind}: {a}, {b} never chosen"
            );
            let odds = (weighted[a] / weighted[b]) / (plain[a] / plain[b]);
            let expected = (w[a] / w[b]) as f64;
            let tol = 1e-4;
            assert!(
                (odds / expected - 1.0).abs() < tol,
                "{kind}: emitters {a}, {b}: odds ×{odds}, weights ×{expected}"
            );
        }
    }
}

#[test]
fn a_constant_environment_is_left_to_bsdf_sampling() {
    // Among other lights: radia's strategies never choose it and give it density 0 (so BSDF
    // samples that escape take it at full weight), and their choices still sum to one;
    // Mitsuba's uniform choice takes it as one emitter of N.
    for kind in [
        LightSamplerKind::Uniform,
        LightSamplerKind::Power,
        LightSamplerKind::Bvh,
    ] {
        let s = many_lights(kind, true);
        let env = s.emitters.len() - 1;
        assert!(matches!(s.emitters[env], Emitter::Constant(_)));
        let env_prim = s.lights.prim_index(env as u32, 0);
        for ctx in contexts() {
            let total: f64 = (0..s.lights.len())
                .map(|i| s.lights.pmf(&ctx, i) as f64)
                .sum();
            assert!((total - 1.0).abs() < 1e-4, "{kind}: pmfs sum to {total}");
            let pmf = s.lights.pmf(&ctx, env_prim);
            if kind == LightSamplerKind::Uniform {
                let expected = 1.0 / s.emitters.len() as f32;
                assert!((pmf - expected).abs() < 1e-6, "{kind}: {pmf} vs {expected}");
            } else {
                assert_eq!(pmf, 0.0, "{kind}");
                assert_eq!(s.environment_pmf(env as u32), 0.0, "{kind}");
                for k in 0..1000 {
                    let u = (k as f32 + 0.5) / 1000.0;
                    let chosen = s.lights.sample(&ctx, u).map(|(i, _)| i);
                    assert_ne!(chosen, Some(env_prim), "{kind}: chosen with u = {u}");
                }
            }
        }
    }
    // Alone, it leaves radia's strategies nothing to sample; the uniform one samples it.
    let alone = |kind| {
        scene(
            vec![],
            vec![EmitterDesc::Constant {
                radiance: Vec3::splat(2.0),
            }],
            kind,
        )
    };
    let ctx = contexts()[0];
    for kind in [LightSamplerKind::Power, LightSamplerKind::Bvh] {
        assert!(alone(kind)
            .sample_emitter_direction(&ctx, 0.5, Vec2::splat(0.5))
            .is_none());
    }
    let s = alone(LightSamplerKind::Uniform);
    assert!(s
        .sample_emitter_direction(&ctx, 0.5, Vec2::splat(0.5))
        .is_some());
}

#[test]
fn sampling_weight_multiplies_a_bvh_leafs_odds() {
    // Two lights: the tree's root has the two leaves as children, so the weight is an exact
    // factor on the odds of one against the other.
    let shapes = || {
        vec![
            emitting(disk(Vec3::new(0.0, 1.0, 0.0), 0.1, -Vec3::Y), Vec3::ONE),
            emitting(disk(Vec3::new(3.0, 1.0, 0.0), 0.1, -Vec3::Y), Vec3::ONE),
        ]
    };
    let ctx = LightContext {
        p: Vec3::ZERO,
        n: Vec3::Y,
    };
    let plain = scene(shapes(), vec![], LightSamplerKind::Bvh);
    let mut weighted = scene(shapes(), vec![], LightSamplerKind::Bvh);
    weighted.sampling_weights = vec![1.0, 3.0];
    weighted.set_light_sampler(LightSamplerKind::Bvh);
    let odds = |s: &Scene| s.lights.pmf(&ctx, 1) / s.lights.pmf(&ctx, 0);
    let ratio = odds(&weighted) / odds(&plain);
    assert!((ratio - 3.0).abs() < 1e-4, "odds ×{ratio}");
}

// ---------------------------------------------------------------------------------------
// Light samples in lanes

/// `Scene::sample_emitter_directions` (sixteen queries at once, triangles sampled in lanes)
/// gives, bit for bit, what `sample_emitter_direction` gives each query: from points near a
/// light triangle, flat or smooth (solid-angle sampling in f64 lanes), far from it (area
/// sampling in lanes), behind it (no sample), from outside spheres (cone sampling in lanes)
/// and inside them (the scalar code), among lights of other kinds (disk: the scalar code;
/// a constant environment or an environment map: in lanes; point, spot and directional
/// lights: in lanes, a spot's falloff lane by lane), and with lanes left out of the batch.
#[test]
fn light_samples_in_lanes_are_the_scalar_ones_bit_for_bit() {
    use crate::lights::LIGHT_LANES;
    use crate::EmitterSample;
    use radia_math::lanes::{f32x16, Vec3s};
    use radia_math::real::Vector2;
    use rand::Rng;
    let mut rng = rand_pcg::Pcg32::new(3, 5);
    let shapes = vec![
        emitting(rectangle(0.5), Vec3::splat(4.0)),
        emitting(cube(Vec3::new(2.0, 1.0, 0.5), Vec3::splat(0.2)), Vec3::ONE),
        emitting(
            sphere(Vec3::new(-2.0, 0.0, 1.0), 0.3, false),
            Vec3::splat(2.0),
        ),
        emitting(
            disk(Vec3::new(0.0, 2.0, 1.0), 0.4, -Vec3::Y),
            Vec3::splat(3.0),
        ),
        // Meshes with vertex normals (the emitted normal interpolated), one flipped.
        emitting(
            moved(smooth_cap(), Vec3::new(1.0, -2.0, 0.5), false),
            Vec3::splat(1.5),
        ),
        emitting(
            moved(smooth_cap(), Vec3::new(-1.5, -1.0, -0.5), true),
            Vec3::splat(2.5),
        ),
    ];
    let constant = EmitterDesc::Constant {
        radiance: Vec3::splat(0.1),
    };
    let map = EmitterDesc::Envmap {
        image: poles_image(),
        scale: 0.5,
        to_world: Affine3A::from_rotation_x(0.4),
        mis_compensation: false,
    };
    let bits = |es: &Option<EmitterSample>| {
        es.map(|e| {
            let v = |v: Vec3| v.to_array().map(f32::to_bits);
            (
                v(e.d),
                e.dist.to_bits(),
                v(e.p),
                v(e.n),
                v(e.p_error),
                e.pdf.to_bits(),
                v(e.radiance),
                e.is_delta,
            )
        })
    };
    // Delta lights (in lanes): a point light at the origin (from which some queries start:
    // no sample there), spot lights of each profile aimed at the origin, a directional light.
    let spot_at = |from: Vec3| crate::look_at(from, Vec3::ZERO, Vec3::Z).unwrap();
    let deltas = vec![
        EmitterDesc::Point {
            position: Vec3::ZERO,
            intensity: Vec3::new(1.0, 2.0, 3.0),
        },
        EmitterDesc::Spot {
            to_world: spot_at(Vec3::new(0.0, 3.0, 0.5)),
            intensity: Vec3::splat(5.0),
            cutoff_angle: 40.0,
            beam_width: 20.0,
            falloff_exponent: None,
        },
        EmitterDesc::Spot {
            to_world: spot_at(Vec3::new(1.0, -2.0, 0.0)),
            intensity: Vec3::splat(7.0),
            cutoff_angle: 60.0,
            beam_width: 0.0,
            falloff_exponent: Some(3.0),
        },
        EmitterDesc::SmoothSpot {
            to_world: spot_at(Vec3::new(-2.0, 0.5, 1.0)),
            intensity: Vec3::splat(3.0),
            inner_cone_angle: 15.0,
            outer_cone_angle: 45.0,
        },
        EmitterDesc::Directional {
            direction: Vec3::new(0.3, -1.0, 0.2),
            irradiance: Vec3::splat(2.0),
        },
    ];
    let (mut in_lanes, mut delta, mut total) = (0, 0, 0);
    for kind in [LightSamplerKind::Bvh, LightSamplerKind::Uniform] {
        for env in [
            vec![],
            vec![constant.clone()],
            vec![map.clone()],
            deltas.clone(),
        ] {
            let s = scene(shapes.clone(), env, kind);
            for _ in 0..400 {
                let ctx: [LightContext; LIGHT_LANES] = std::array::from_fn(|_| {
                    if rng.random_range(0..16) == 0 {
                        return LightContext {
                            p: Vec3::ZERO,
                            n: Vec3::Y,
                        };
                    }
                    // Distances from 10⁻³ to 10² of the rectangle, on both sides.
                    let r = 10f32.powf(rng.random_range(-3.0..2.0));
                    let d = warp::square_to_uniform_sphere(Vec2::new(rng.random(), rng.random()));
                    LightContext {
                        p: d * r,
                        n: warp::square_to_uniform_sphere(Vec2::new(rng.random(), rng.random())),
                    }
                });
                let u_sel: [f32; LIGHT_LANES] = std::array::from_fn(|_| rng.random());
                let u: [Vec2; LIGHT_LANES] =
                    std::array::from_fn(|_| Vec2::new(rng.random(), rng.random()));
                let active: u32 = rng.random::<u32>() & 0xffff;
                let stale = Some(EmitterSample {
                    d: Vec3::X,
                    dist: 7.0,
                    p: Vec3::ONE,
                    n: Vec3::Y,
                    p_error: Vec3::ZERO,
                    pdf: 3.0,
                    radiance: Vec3::ONE,
                    is_delta: true,
                });
                let mut out = crate::EmitterSampleLanes::new();
                for k in 0..LIGHT_LANES {
                    out.set(k, stale.as_ref());
                }
                let p = Vec3s::from_fn(|k| ctx[k].p);
                let n = Vec3s::from_fn(|k| ctx[k].n);
                let u_lanes = Vector2::from_fn(|k| u[k]);
                s.sample_emitter_directions(active, p, n, f32x16::new(u_sel), u_lanes, &mut out);
                for k in 0..LIGHT_LANES {
                    let want = if active & (1 << k) != 0 {
                        total += 1;
                        s.sample_emitter_direction(&ctx[k], u_sel[k], u[k])
                    } else {
                        stale
                    };
                    assert_eq!(
                        bits(&out.get(k)),
                        bits(&want),
                        "lane {k} from {:?}",
                        ctx[k].p
                    );
                    in_lanes += usize::from(want.is_some() && !want.unwrap().is_delta);
                    delta += usize::from(want.is_some_and(|e| e.is_delta));
                }
            }
        }
    }
    // The batch must have met both strategies and failures (checked loosely: it is the
    // bit-for-bit equality above that is the test).
    assert!(
        in_lanes > total / 4,
        "{in_lanes} samples of {total} queries"
    );
    assert!(
        delta > total / 40,
        "{delta} delta samples of {total} queries"
    );
}

#[test]
fn bvh_choices_in_lanes_are_the_scalar_ones_bit_for_bit() {
    use crate::lights::LIGHT_LANES;
    use radia_math::lanes::{f32x16, Vec3s};
    use rand::Rng;
    let mut rng = rand_pcg::Pcg32::new(7, 11);
    // A root of a few children (weighed child by child over the lanes), with and without
    // lights at infinity, and the 60-light tree of several levels.
    let few = |with_infinite: bool| {
        let mut shapes = vec![
            emitting(
                sphere(Vec3::new(-2.0, 0.5, 1.0), 0.3, false),
                Vec3::splat(2.0),
            ),
            emitting(
                sphere(Vec3::new(1.0, 2.0, -1.0), 0.1, false),
                Vec3::splat(9.0),
            ),
            emitting(
                disk(Vec3::new(0.0, 2.0, 1.0), 0.4, -Vec3::Y),
                Vec3::splat(3.0),
            ),
            emitting(
                disk(Vec3::new(3.0, 0.0, 0.0), 0.2, Vec3::X),
                Vec3::splat(5.0),
            ),
        ];
        shapes.push(emitting(rectangle(0.5), Vec3::splat(4.0)));
        let env = if with_infinite {
            vec![EmitterDesc::Constant {
                radiance: Vec3::splat(0.2),
            }]
        } else {
            vec![]
        };
        scene(shapes, env, LightSamplerKind::Bvh)
    };
    let scenes = [
        few(false),
        few(true),
        many_lights(LightSamplerKind::Bvh, false),
        many_lights(LightSamplerKind::Bvh, true),
    ];
    let mut chosen = 0;
    for s in &scenes {
        for round in 0..600 {
            let ctx: [LightContext; LIGHT_LANES] = std::array::from_fn(|k| {
                let r = 10f32.powf(rng.random_range(-3.0..2.0));
                let d = warp::square_to_uniform_sphere(Vec2::new(rng.random(), rng.random()));
                let n = warp::square_to_uniform_sphere(Vec2::new(rng.random(), rng.random()));
                LightContext {
                    p: Vec3::new(0.0, 1.0, 0.0) + d * r,
                    // Some points without a normal (the receiver's cosine left out).
                    n: if k % 5 == 0 { Vec3::ZERO } else { n },
                }
            });
            // Values at the ends of [0, 1) as well.
            let u: [f32; LIGHT_LANES] = std::array::from_fn(|k| match (round + k) % 7 {
                0 => 0.0,
                1 => 1.0 - f32::EPSILON / 2.0,
                _ => rng.random(),
            });
            // All lanes (the root weighed over the lanes), or a random set.
            let active = if round % 2 == 0 {
                0xffff
            } else {
                rng.random::<u32>() & 0xffff
            };
            let stale = Some((usize::MAX, -1.0f32));
            let mut out = [stale; LIGHT_LANES];
            let p = Vec3s::from_fn(|k| ctx[k].p);
            let n = Vec3s::from_fn(|k| ctx[k].n);
            s.lights
                .sample_lanes(active, p, n, f32x16::new(u), &mut out);
            for k in 0..LIGHT_LANES {
                let want = if active & (1 << k) != 0 {
                    s.lights.sample(&ctx[k], u[k])
                } else {
                    stale
                };
                let bits = |c: Option<(usize, f32)>| c.map(|(i, pmf)| (i, pmf.to_bits()));
                assert_eq!(bits(out[k]), bits(want), "lane {k} at {:?}", ctx[k]);
                chosen += usize::from(want.is_some() && active & (1 << k) != 0);
            }
        }
    }
    assert!(chosen > 4 * 600 * 10, "{chosen} lights chosen");
}
