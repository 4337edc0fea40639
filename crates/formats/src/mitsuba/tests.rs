//! Loader tests: every file is written to a fresh temporary directory.

use super::*;
use crate::{load_obj, load_ply, mesh, obj, ply};
use glam::{Affine3A, Mat4, Vec2, Vec3, Vec4};
use radia_bsdf::{Bsdf, Texture};
use radia_scene::{
    EmitterDesc, FilmDesc, FilterDesc, Geometry, IntegratorDesc, Mesh, SamplerDesc, ShapeDesc,
};
use std::f32::consts::{FRAC_PI_2, FRAC_PI_4};
use std::path::PathBuf;
use std::sync::atomic::{AtomicUsize, Ordering};

// ---------------------------------------------------------------------------------------
// Helpers

/// A fresh directory under the system temp dir, removed again when dropped.
struct TempDir(PathBuf);

impl std::ops::Deref for TempDir {
    type Target = std::path::Path;
    fn deref(&self) -> &std::path::Path {
        &self.0
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

fn temp_dir(name: &str) -> TempDir {
    static COUNTER: AtomicUsize = AtomicUsize::new(0);
    let n = COUNTER.fetch_add(1, Ordering::Relaxed);
    let dir = std::env::temp_dir().join(format!("radia-loader-{}-{name}-{n}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("create temp dir");
    TempDir(dir)
}

/// Writes `files` (name, contents) into a fresh directory; returns the directory.
fn write_files(name: &str, files: &[(&str, &[u8])]) -> TempDir {
    let dir = temp_dir(name);
    for (f, data) in files {
        let p = dir.join(f);
        if let Some(parent) = p.parent() {
            std::fs::create_dir_all(parent).expect("create dir");
        }
        std::fs::write(p, data).expect("write file");
    }
    dir
}

const SENSOR: &str = r#"<sensor type="perspective"><float name="fov" value="45"/>
    <film type="hdrfilm"><integer name="width" value="32"/><integer name="height" value="16"/></film></sensor>"#;

/// `body` inside `<scene>`, with a sensor unless the body has one.
fn scene_xml(body: &str) -> String {
    let sensor = if body.contains("<sensor") { "" } else { SENSOR };
    format!("<scene version=\"3.0.0\">\n{sensor}\n{body}\n</scene>\n")
}

fn load_in(
    dir: &std::path::Path,
    xml: &str,
    defines: &[(&str, &str)],
) -> Result<SceneDescription, LoadError> {
    let path = dir.join("scene.xml");
    std::fs::write(&path, xml).expect("write scene");
    let defines: Vec<(String, String)> = defines
        .iter()
        .map(|(a, b)| (a.to_string(), b.to_string()))
        .collect();
    load_mitsuba_xml_with_warnings(&path, &defines).map(|(s, _)| s)
}

fn load(name: &str, body: &str) -> Result<SceneDescription, LoadError> {
    load_in(&temp_dir(name), &scene_xml(body), &[])
}

fn load_ok(name: &str, body: &str) -> SceneDescription {
    match load(name, body) {
        Ok(s) => s,
        Err(e) => panic!("{name}: unexpected error: {e}"),
    }
}

/// Asserts an error whose message contains `needle` and which names `file` and a line.
fn expect_err(r: Result<SceneDescription, LoadError>, needle: &str) -> LoadError {
    match r {
        Ok(_) => panic!("expected an error containing {needle:?}"),
        Err(e) => {
            let shown = e.to_string();
            assert!(
                shown.contains(needle),
                "error {shown:?} does not contain {needle:?}"
            );
            assert!(e.line.is_some(), "error without a line: {shown}");
            let prefix = format!("{}:{}:", e.file.display(), e.line.unwrap_or(0));
            assert!(
                shown.starts_with(&prefix),
                "{shown:?} does not start with {prefix:?}"
            );
            e
        }
    }
}

fn assert_close(a: f32, b: f32, tol: f32, what: &str) {
    assert!((a - b).abs() <= tol, "{what}: {a} vs {b}");
}

fn assert_vec_close(a: Vec3, b: Vec3, tol: f32, what: &str) {
    assert!((a - b).abs().max_element() <= tol, "{what}: {a} vs {b}");
}

fn assert_mat_close(a: Mat4, b: Mat4, tol: f32, what: &str) {
    let (x, y) = (a.to_cols_array(), b.to_cols_array());
    for i in 0..16 {
        assert!(
            (x[i] - y[i]).abs() <= tol,
            "{what}: element {i}: {a} vs {b}"
        );
    }
}

fn mesh_of(s: &ShapeDesc) -> &Mesh {
    match &s.geometry {
        Geometry::Mesh(m) => m,
        g => panic!("expected a mesh, got {g:?}"),
    }
}

fn diffuse_color(b: &Bsdf) -> Vec3 {
    match b {
        Bsdf::Diffuse(d) => match &d.reflectance {
            Texture::Constant(c) => *c,
            #[allow(unreachable_patterns)]
            t => panic!("expected a constant reflectance, got {t:?}"),
        },
        other => panic!("expected diffuse, got {other:?}"),
    }
}

/// The to_world of a one-disk scene with the given transform children.
fn disk_transform(name: &str, ops: &str) -> Mat4 {
    let s = load_ok(
        name,
        &format!(r#"<shape type="disk"><transform name="to_world">{ops}</transform></shape>"#),
    );
    match &s.shapes[0].geometry {
        Geometry::Disk { to_world, .. } => Mat4::from(*to_world),
        g => panic!("expected a disk, got {g:?}"),
    }
}

fn camera_fov(name: &str, w: u32, h: u32, params: &str) -> f32 {
    let s = load_ok(
        name,
        &format!(
            r#"<sensor type="perspective">{params}<film type="hdrfilm">
            <integer name="width" value="{w}"/><integer name="height" value="{h}"/></film></sensor>"#
        ),
    );
    s.camera.fov_x_degrees
}

fn rows(r: [[f32; 4]; 4]) -> Mat4 {
    Mat4::from_cols_array_2d(&r).transpose()
}

// ---------------------------------------------------------------------------------------
// Values and transforms

#[test]
fn loader_transform_ops_compose_in_document_order() {
    // translate, then rotate 90° about z, then scale 2: M = S · R · T.
    let m = disk_transform(
        "compose",
        r#"<translate x="1" y="2" z="3"/><rotate z="1" angle="90"/><scale value="2"/>"#,
    );
    // T maps p to p + (1,2,3); R maps (x,y,z) to (−y,x,z); S doubles.
    let expected = rows([
        [0., -2., 0., -4.],
        [2., 0., 0., 2.],
        [0., 0., 2., 6.],
        [0., 0., 0., 1.],
    ]);
    assert_mat_close(m, expected, 1e-6, "S R T");
    // Same point check: (1, 0, 0) → T → (2, 2, 3) → R → (−2, 2, 3) → S → (−4, 4, 6).
    assert_vec_close(
        m.transform_point3(Vec3::X),
        Vec3::new(-4., 4., 6.),
        1e-6,
        "point",
    );

    // The reverse order gives a different matrix: T · R · S.
    let m2 = disk_transform(
        "compose-rev",
        r#"<scale value="2"/><rotate z="1" angle="90"/><translate value="1 2 3"/>"#,
    );
    let expected2 = rows([
        [0., -2., 0., 1.],
        [2., 0., 0., 2.],
        [0., 0., 2., 3.],
        [0., 0., 0., 1.],
    ]);
    assert_mat_close(m2, expected2, 1e-6, "T R S");
}

#[test]
fn loader_transform_variants() {
    let m = disk_transform("scale-xyz", r#"<scale x="2" z="3"/>"#);
    assert_mat_close(
        m,
        Mat4::from_scale(Vec3::new(2., 1., 3.)),
        0.0,
        "per-axis scale, y defaults to 1",
    );
    let m = disk_transform("scale-value3", r#"<scale value="2, 3, 4"/>"#);
    assert_mat_close(
        m,
        Mat4::from_scale(Vec3::new(2., 3., 4.)),
        0.0,
        "scale value=3 numbers",
    );
    let m = disk_transform("translate-xyz", r#"<translate y="5"/>"#);
    assert_mat_close(
        m,
        Mat4::from_translation(Vec3::new(0., 5., 0.)),
        0.0,
        "translate y only",
    );
    let m = disk_transform("rotate-value", r#"<rotate value="0, 1, 0" angle="90"/>"#);
    // About +y by 90°: x → −z, z → x.
    assert_vec_close(m.transform_vector3(Vec3::X), -Vec3::Z, 1e-6, "rotate y");
    assert_vec_close(m.transform_vector3(Vec3::Z), Vec3::X, 1e-6, "rotate y");
    let m = disk_transform("rotate-x", r#"<rotate x="1" angle="-90"/>"#);
    assert_vec_close(
        m.transform_vector3(Vec3::Z),
        Vec3::Y,
        1e-6,
        "rotate x -90 maps +z to +y",
    );
    // Mitsuba (Dr.Jit's rotate) does not normalize the axis: axis (2,0,0), 90° gives
    // diag(x²(1−c)+c, c, c) + ... = rows (4,0,0), (0,0,−2), (0,2,0).
    let m = disk_transform("rotate-unnormalized", r#"<rotate x="2" angle="90"/>"#);
    let expected = rows([
        [4., 0., 0., 0.],
        [0., 0., -2., 0.],
        [0., 2., 0., 0.],
        [0., 0., 0., 1.],
    ]);
    assert_mat_close(m, expected, 1e-6, "unnormalized axis");

    let m = disk_transform(
        "matrix16",
        r#"<matrix value="1 2 3 4  0 5 6 7  -1 0 8 9  0 0 0 1"/>"#,
    );
    let expected = rows([
        [1., 2., 3., 4.],
        [0., 5., 6., 7.],
        [-1., 0., 8., 9.],
        [0., 0., 0., 1.],
    ]);
    assert_mat_close(m, expected, 0.0, "matrix is row-major");
    let m = disk_transform("matrix9", r#"<matrix value="1,2,3,4,5,6,7,8,10"/>"#);
    let expected = rows([
        [1., 2., 3., 0.],
        [4., 5., 6., 0.],
        [7., 8., 10., 0.],
        [0., 0., 0., 1.],
    ]);
    assert_mat_close(m, expected, 0.0, "3x3 matrix");
}

#[test]
fn loader_lookat_matrix_columns() {
    let m = disk_transform(
        "lookat",
        r#"<lookat origin="1, 2, 3" target="1, 2, 13" up="0, 1, 0"/>"#,
    );
    // dir = +z; left = normalize(up × dir) = +x; up' = dir × left = +y.
    assert_vec_close(m.x_axis.truncate(), Vec3::X, 1e-6, "left");
    assert_vec_close(m.y_axis.truncate(), Vec3::Y, 1e-6, "up'");
    assert_vec_close(m.z_axis.truncate(), Vec3::Z, 1e-6, "dir");
    assert_eq!(m.w_axis, Vec4::new(1., 2., 3., 1.), "origin");

    // An oblique one, checked against the definition.
    let m = disk_transform(
        "lookat2",
        r#"<lookat origin="0 0 0" target="1 -1 -2" up="0 0 1"/>"#,
    );
    let dir = Vec3::new(1., -1., -2.).normalize();
    let left = Vec3::Z.cross(dir).normalize();
    let up = dir.cross(left);
    assert_vec_close(m.x_axis.truncate(), left, 1e-6, "left");
    assert_vec_close(m.y_axis.truncate(), up, 1e-6, "up'");
    assert_vec_close(m.z_axis.truncate(), dir, 1e-6, "dir");

    // Without up, some perpendicular up is chosen: still orthonormal with dir as column 2.
    let m = disk_transform("lookat-noup", r#"<lookat origin="0 0 0" target="0 0 -5"/>"#);
    assert_vec_close(m.z_axis.truncate(), -Vec3::Z, 1e-6, "dir");
    assert_close(
        m.x_axis.truncate().dot(m.z_axis.truncate()),
        0.0,
        1e-6,
        "left ⟂ dir",
    );
    assert_close(m.x_axis.truncate().length(), 1.0, 1e-6, "|left|");

    let e = expect_err(
        load(
            "lookat-bad",
            r#"<shape type="disk"><transform name="to_world"><lookat origin="0 0 0" target="0 5 0" up="0 1 0"/></transform></shape>"#,
        ),
        "invalid <lookat>",
    );
    assert_eq!(e.line, Some(4));
}

#[test]
fn loader_principal_point_offset_shifts_the_image_plane() {
    // Camera at the origin looking along +z with local +x = world +x (look_at: left = up ×
    // dir). fov_x 90° on a 200x100 film: tan_half_x = 1, tan_half_y = 0.5. Mitsuba's
    // perspective.cpp adds the offset to the film position before projecting, so film (u, v)
    // looks along ((1 − 2(u + 0.1))·1, (1 − 2(v − 0.05))·0.5, 1). The world point
    // (−0.3, 0.1, 1) solves that at u = 0.55, v = 0.45 by hand.
    let s = load_ok(
        "principal-point",
        r#"<sensor type="perspective"><float name="fov" value="90"/>
        <float name="principal_point_offset_x" value="0.1"/>
        <float name="principal_point_offset_y" value="-0.05"/>
        <transform name="to_world"><lookat origin="0, 0, 0" target="0, 0, 1" up="0, 1, 0"/></transform>
        <film type="hdrfilm"><integer name="width" value="200"/><integer name="height" value="100"/></film></sensor>"#,
    );
    assert_eq!(s.camera.principal_point_offset, Vec2::new(0.1, -0.05));
    let camera = radia_scene::Camera::new(&s.camera, 200, 100);
    let ray = camera.generate_ray(Vec2::new(0.55, 0.45));
    let expected = Vec3::new(-0.3, 0.1, 1.0).normalize();
    assert_vec_close(
        ray.d,
        expected,
        1e-6,
        "ray towards the hand-projected point",
    );
    // Without the offset the same film position looks elsewhere (the test can fail).
    let centred = radia_scene::Camera::new(
        &radia_scene::CameraDesc {
            principal_point_offset: Vec2::ZERO,
            ..s.camera.clone()
        },
        200,
        100,
    );
    assert!((centred.generate_ray(Vec2::new(0.55, 0.45)).d - expected).length() > 0.1);

    for (name, value) in [
        ("principal_point_offset_x", "nan"),
        ("principal_point_offset_y", "inf"),
    ] {
        let e = expect_err(
            load(
                "principal-point-bad",
                &format!(
                    r#"<sensor type="perspective">
                    <float name="{name}" value="{value}"/></sensor>"#
                ),
            ),
            "must be a finite number",
        );
        assert!(e.to_string().contains(name), "{e}");
    }
}

#[test]
fn loader_sampling_weights() {
    let s = load_ok(
        "sampling-weights",
        r#"<shape type="sphere"/>
        <shape type="sphere"><emitter type="area"><float name="sampling_weight" value="0.25"/></emitter></shape>
        <emitter type="point"><integer name="sampling_weight" value="3"/></emitter>
        <emitter type="constant"/>"#,
    );
    assert_eq!(s.sampling_weights.shape(1), 0.25);
    assert_eq!(s.sampling_weights.emitter(0), 3.0);
    assert_eq!(s.sampling_weights.emitter(1), 1.0, "the default is 1");
    // The scene gives them to the light selection by emitter: area lights first.
    let scene = radia_scene::Scene::build(s);
    assert_eq!(scene.sampling_weights, vec![0.25, 3.0, 1.0]);

    let plain = load_ok("sampling-weights-none", r#"<emitter type="point"/>"#);
    assert_eq!(
        plain.sampling_weights,
        radia_scene::SamplingWeights::default()
    );

    for (value, needle) in [
        (
            "-1",
            "\"sampling_weight\" must be a finite number >= 0, got -1",
        ),
        ("nan", "must be a finite number >= 0"),
    ] {
        expect_err(
            load(
                "sampling-weight-bad",
                &format!(
                    r#"<shape type="sphere"><emitter type="area">
                    <float name="sampling_weight" value="{value}"/></emitter></shape>"#
                ),
            ),
            needle,
        );
    }
    expect_err(
        load(
            "sampling-weight-all-zero",
            r#"<emitter type="point"><float name="sampling_weight" value="0"/></emitter>
            <shape type="sphere"><emitter type="area"><float name="sampling_weight" value="0"/></emitter></shape>"#,
        ),
        "every emitter has \"sampling_weight\" 0",
    );
}

#[test]
fn loader_camera_lookat_and_clips() {
    let s = load_ok(
        "camera",
        r#"<sensor type="perspective"><float name="fov" value="30"/><float name="near_clip" value="0.5"/>
        <integer name="far_clip" value="100"/>
        <transform name="to_world"><lookat origin="0, 1, 5" target="0, 1, 0" up="0, 1, 0"/></transform></sensor>"#,
    );
    let m = Mat4::from(s.camera.to_world);
    assert_vec_close(m.z_axis.truncate(), -Vec3::Z, 1e-6, "camera looks along −z");
    assert_vec_close(m.x_axis.truncate(), -Vec3::X, 1e-6, "left = up × dir = −x");
    // Render space is centred on the camera (`Builder::to_world`): the file's eye position
    // is the world origin, and the camera sits at render space's origin.
    assert_eq!(
        s.world_origin,
        glam::DVec3::new(0., 1., 5.),
        "world origin = eye"
    );
    assert_eq!(
        m.w_axis.truncate(),
        Vec3::ZERO,
        "the camera at render space's origin"
    );
    assert_eq!(s.camera.near_clip, 0.5);
    assert_eq!(
        s.camera.far_clip, 100.0,
        "an <integer> is accepted for a float"
    );
    assert_eq!(
        s.film,
        FilmDesc::default(),
        "film defaults: 768x576 gaussian 0.5"
    );
    assert_eq!(
        s.sampler,
        SamplerDesc::default(),
        "sampler defaults: 4 spp, seed 0"
    );
    assert_eq!(
        s.integrator,
        IntegratorDesc::default(),
        "missing integrator: defaults"
    );
}

#[test]
fn loader_fov_axis_conversions() {
    // Film 200x100: aspect 2.
    let a: f64 = 2.0;
    let t = |deg: f64| (deg.to_radians() * 0.5).tan();
    let deg = |tan_half: f64| (2.0 * tan_half.atan()).to_degrees() as f32;

    let x = camera_fov("fov-x", 200, 100, r#"<float name="fov" value="30"/>"#);
    assert_close(x, 30.0, 1e-5, "fov_axis x (default)");
    let y = camera_fov(
        "fov-y",
        200,
        100,
        r#"<float name="fov" value="30"/><string name="fov_axis" value="y"/>"#,
    );
    assert_close(y, deg(t(30.0) * a), 1e-4, "fov_axis y");
    let d = camera_fov(
        "fov-d",
        200,
        100,
        r#"<float name="fov" value="30"/><string name="fov_axis" value="diagonal"/>"#,
    );
    // Diagonal half-extent tan(15°); width : diagonal = 2 : sqrt(5).
    assert_close(
        d,
        deg(t(30.0) * 2.0 / 5f64.sqrt()),
        1e-4,
        "fov_axis diagonal",
    );
    let sm = camera_fov(
        "fov-s",
        200,
        100,
        r#"<float name="fov" value="30"/><string name="fov_axis" value="smaller"/>"#,
    );
    assert_close(sm, y, 1e-5, "smaller = y when wider than tall");
    let lg = camera_fov(
        "fov-l",
        200,
        100,
        r#"<float name="fov" value="30"/><string name="fov_axis" value="LARGER"/>"#,
    );
    assert_close(
        lg,
        30.0,
        1e-5,
        "larger = x when wider than tall (case-insensitive)",
    );
    // Portrait film: smaller is x, larger is y.
    let sm = camera_fov(
        "fov-s2",
        100,
        200,
        r#"<float name="fov" value="30"/><string name="fov_axis" value="smaller"/>"#,
    );
    assert_close(sm, 30.0, 1e-5, "smaller = x when taller than wide");
    let lg = camera_fov(
        "fov-l2",
        100,
        200,
        r#"<float name="fov" value="30"/><string name="fov_axis" value="larger"/>"#,
    );
    assert_close(
        lg,
        deg(t(30.0) * 0.5),
        1e-4,
        "larger = y when taller than wide",
    );

    // No fov: 50 mm on 36x24 film. With a 3:2 film the horizontal fov is 2·atan(18/50).
    let f = camera_fov("focal-default", 300, 200, "");
    assert_close(f, deg(18.0 / 50.0), 1e-4, "default focal length");
    let f = camera_fov(
        "focal-35",
        300,
        200,
        r#"<string name="focal_length" value="35mm"/>"#,
    );
    assert_close(f, deg(18.0 / 35.0), 1e-4, "35mm");

    expect_err(
        load(
            "fov-bad-axis",
            r#"<sensor type="perspective"><float name="fov" value="30"/><string name="fov_axis" value="z"/></sensor>"#,
        ),
        "fov_axis",
    );
    expect_err(
        load(
            "fov-both",
            r#"<sensor type="perspective"><float name="fov" value="30"/><string name="focal_length" value="20mm"/></sensor>"#,
        ),
        "either a focal length",
    );
    expect_err(
        load(
            "fov-axis-alone",
            r#"<sensor type="perspective"><string name="fov_axis" value="y"/></sensor>"#,
        ),
        "unexpected parameter \"fov_axis\"",
    );
}

#[test]
fn loader_camera_rejects_scale() {
    let e = expect_err(
        load(
            "camera-scale",
            r#"<sensor type="perspective">
<transform name="to_world"><scale value="2"/></transform></sensor>"#,
        ),
        "scale factors",
    );
    assert_eq!(e.line, Some(4), "at the transform: {e}");
}

#[test]
fn loader_film_sampler_integrator() {
    let s = load_ok(
        "film",
        r#"<integrator type="path"><integer name="max_depth" value="8"/><integer name="rr_depth" value="3"/>
             <boolean name="hide_emitters" value="TRUE"/></integrator>
           <sensor type="perspective"><float name="fov" value="40"/>
             <sampler type="independent"><integer name="sample_count" value="16"/><integer name="seed" value="7"/></sampler>
             <film type="hdrfilm"><integer name="width" value="64"/><integer name="height" value="48"/>
               <string name="pixel_format" value="RGBA"/><string name="component_format" value="float32"/>
               <string name="file_format" value="exr"/>
               <rfilter type="gaussian"><float name="stddev" value="0.25"/></rfilter></film></sensor>"#,
    );
    assert_eq!(
        s.integrator,
        IntegratorDesc {
            max_depth: 8,
            rr_depth: 3,
            hide_emitters: true,
            aov: None,
            classic: None,
            npr: None,
        }
    );
    assert_eq!(
        s.sampler,
        SamplerDesc {
            kind: radia_sampling::SamplerKind::Independent,
            sample_count: 16,
            seed: 7
        }
    );
    assert_eq!(
        s.film,
        FilmDesc {
            width: 64,
            height: 48,
            filter: FilterDesc::Gaussian { stddev: 0.25 }
        }
    );

    let s = load_ok(
        "box-filter",
        r#"<sensor type="perspective"><film type="hdrfilm"><rfilter type="box"/></film></sensor>"#,
    );
    assert_eq!(s.film.filter, FilterDesc::Box);

    expect_err(
        load(
            "bad-pixel-format",
            r#"<sensor type="perspective"><film type="hdrfilm"><string name="pixel_format" value="cmyk"/></film></sensor>"#,
        ),
        "pixel_format",
    );
    expect_err(
        load(
            "negative-width",
            r#"<sensor type="perspective"><film type="hdrfilm"><integer name="width" value="-4"/></film></sensor>"#,
        ),
        "out of bounds",
    );
    expect_err(
        load(
            "max-depth",
            r#"<integrator type="path"><integer name="max_depth" value="-2"/></integrator>"#,
        ),
        "max_depth",
    );
    expect_err(
        load(
            "float-depth",
            r#"<integrator type="path"><float name="max_depth" value="3"/></integrator>"#,
        ),
        "wrong type",
    );
    expect_err(
        load("volpath", r#"<integrator type="volpath"/>"#),
        "unsupported integrator plugin type \"volpath\"",
    );
    expect_err(
        load(
            "two-integrators",
            r#"<integrator type="path"/><integrator type="path"/>"#,
        ),
        "only one integrator",
    );
}

#[test]
fn loader_aov_integrator() {
    use radia_scene::{AovDesc, AovKind, AovOutput};
    let s = load_ok(
        "aov",
        r#"<integrator type="aov"><string name="aovs" value="dd.y:depth,nn:sh_normal"/>
             <integrator type="path" name="my_image"><integer name="max_depth" value="4"/></integrator>
           </integrator>"#,
    );
    assert_eq!(
        s.integrator.max_depth, 4,
        "the nested path integrator's parameters"
    );
    assert_eq!(
        s.integrator.aov,
        Some(AovDesc {
            outputs: vec![
                AovOutput {
                    name: "dd.y".into(),
                    kind: AovKind::Depth
                },
                AovOutput {
                    name: "nn".into(),
                    kind: AovKind::ShNormal
                },
            ],
            beauty_layer: Some("my_image".into()),
            has_beauty: true,
        })
    );
    // Unnamed nested objects are called _arg_N, as Mitsuba names them.
    let s = load_ok(
        "aov-unnamed",
        r#"<integrator type="aov"><string name="aovs" value="a:albedo"/><integrator type="path"/></integrator>"#,
    );
    assert_eq!(
        s.integrator.aov.unwrap().beauty_layer.as_deref(),
        Some("_arg_0")
    );
    let s = load_ok(
        "aov-alone",
        r#"<integrator type="aov"><string name="aovs" value="a:albedo"/></integrator>"#,
    );
    assert!(!s.integrator.aov.unwrap().has_beauty);
    for (name, body, needle) in [
        (
            "aov-missing",
            r#"<integrator type="aov"/>"#,
            "needs the string parameter \"aovs\"",
        ),
        (
            "aov-type",
            r#"<integrator type="aov"><string name="aovs" value="x:normals"/></integrator>"#,
            "invalid AOV type \"normals\"",
        ),
        (
            "aov-two",
            r#"<integrator type="aov"><string name="aovs" value="a:uv"/><integrator type="path"/><integrator type="path"/></integrator>"#,
            "one nested integrator",
        ),
        (
            "aov-nested-aov",
            r#"<integrator type="aov"><string name="aovs" value="a:uv"/><integrator type="aov"><string name="aovs" value="b:uv"/></integrator></integrator>"#,
            "cannot nest another",
        ),
        (
            "aov-unused",
            r#"<integrator type="aov"><string name="aovs" value="a:uv"/><integer name="max_depth" value="3"/></integrator>"#,
            "unexpected parameter \"max_depth\"",
        ),
    ] {
        expect_err(load(name, body), needle);
    }
}

#[test]
fn loader_classic_integrator() {
    use radia_scene::{ClassicDesc, ClassicShading};
    let s = load_ok(
        "classic",
        r#"<integrator type="classic"><rgb name="ambient" value="0.1"/><string name="attenuation" value="1, 0.5, 0"/>
             <string name="shading" value="gouraud"/><boolean name="shadows" value="false"/><integer name="max_depth" value="3"/></integrator>"#,
    );
    assert_eq!(s.integrator.max_depth, 3);
    assert_eq!(
        s.integrator.classic,
        Some(ClassicDesc {
            ambient: radia_math::Spectrum::splat(0.1),
            attenuation: [1.0, 0.5, 0.0],
            shading: ClassicShading::Gouraud,
            shadows: false,
        })
    );
    for (name, body, needle) in [
        (
            "classic-shading",
            r#"<integrator type="classic"><string name="shading" value="smooth"/></integrator>"#,
            "unknown shading \"smooth\"",
        ),
        (
            "classic-att",
            r#"<integrator type="classic"><string name="attenuation" value="1, 2"/></integrator>"#,
            "three non-negative numbers",
        ),
        (
            "classic-att0",
            r#"<integrator type="classic"><string name="attenuation" value="0, 0, 0"/></integrator>"#,
            "not all 0",
        ),
        (
            "classic-att-text",
            r#"<integrator type="classic"><string name="attenuation" value="a, b, c"/></integrator>"#,
            "must be three numbers",
        ),
        (
            "classic-depth",
            r#"<integrator type="classic"><integer name="max_depth" value="0"/></integrator>"#,
            "max_depth",
        ),
    ] {
        expect_err(load(name, body), needle);
    }
}

// ---------------------------------------------------------------------------------------
// $substitution, defaults, references

#[test]
fn loader_defaults_and_substitution() {
    let xml = r#"<scene version="3.0.0">
    <default name="spp" value="8"/>
    <default name="res" value="16"/>
    <default name="resx" value="$res"/>
    <sensor type="perspective">
        <sampler type="independent"><integer name="sample_count" value="$spp"/></sampler>
        <film type="hdrfilm"><integer name="width" value="$resx"/><integer name="height" value="$res"/></film>
    </sensor>
    <shape type="sphere"><float name="radius" value="$res.5"/></shape>
</scene>"#;
    let dir = temp_dir("subst");
    let s = load_in(&dir, xml, &[]).expect("defaults");
    assert_eq!(s.sampler.sample_count, 8);
    assert_eq!(
        (s.film.width, s.film.height),
        (16, 16),
        "$resx is not $res followed by x"
    );
    match s.shapes[0].geometry {
        Geometry::Sphere { radius, .. } => assert_eq!(radius, 16.5, "substitution is textual"),
        ref g => panic!("{g:?}"),
    }
    // Defines override defaults (also a default that refers to another parameter).
    let s = load_in(&dir, xml, &[("spp", "3"), ("res", "5")]).expect("defines");
    assert_eq!(s.sampler.sample_count, 3);
    assert_eq!((s.film.width, s.film.height), (5, 5));
    let s = load_in(&dir, xml, &[("resx", "7")]).expect("define of the longer name");
    assert_eq!((s.film.width, s.film.height), (7, 16));

    // A define that nothing uses is an error, as in Mitsuba 3.9.1.
    let e = load_in(&dir, xml, &[("sppp", "3")]).expect_err("unused define");
    assert!(e.to_string().contains("unused parameters: $sppp=3"), "{e}");
    assert!(
        e.to_string()
            .starts_with(&dir.join("scene.xml").display().to_string()),
        "{e}"
    );
}

#[test]
fn loader_unresolved_parameter() {
    let xml = scene_xml(
        r#"<shape type="sphere">
        <float name="radius" value="$radius"/></shape>"#,
    );
    let e = expect_err(
        load_in(&temp_dir("unresolved"), &xml, &[]),
        "undefined parameter \"$radius\"",
    );
    assert_eq!(e.line, Some(5));
    // A default must precede its use.
    let xml = scene_xml(
        r#"<shape type="sphere"><float name="radius" value="$r"/></shape><default name="r" value="1"/>"#,
    );
    expect_err(
        load_in(&temp_dir("late-default"), &xml, &[]),
        "undefined parameter \"$r\"",
    );
    // \$ escapes.
    let xml = scene_xml(
        r#"<default name="r" value="2"/><shape type="obj"><string name="filename" value="a\$r.obj"/></shape>"#,
    );
    let e = load_in(&temp_dir("escaped"), &xml, &[]).expect_err("the file a$r.obj does not exist");
    assert!(e.to_string().contains("a$r.obj"), "{e}");
}

#[test]
fn loader_references_and_ids() {
    let s = load_ok(
        "refs",
        r#"<bsdf type="diffuse" id="red"><rgb name="reflectance" value="0.8, 0.1, 0.1"/></bsdf>
        <shape type="sphere"><ref id="red"/></shape>
        <shape type="sphere"><ref name="bsdf" id="grey"/></shape>
        <shape type="sphere"><bsdf type="diffuse" id="grey"><float name="reflectance" value="0.25"/></bsdf></shape>"#,
    );
    assert_eq!(s.shapes.len(), 3);
    assert_vec_close(
        diffuse_color(&s.shapes[0].bsdf),
        Vec3::new(0.8, 0.1, 0.1),
        1e-6,
        "ref to top-level bsdf",
    );
    assert_vec_close(
        diffuse_color(&s.shapes[1].bsdf),
        Vec3::splat(0.25),
        1e-6,
        "named forward ref to a nested bsdf",
    );
    assert_vec_close(
        diffuse_color(&s.shapes[2].bsdf),
        Vec3::splat(0.25),
        1e-6,
        "nested bsdf",
    );

    let e = expect_err(
        load(
            "dup-id",
            r#"<bsdf type="diffuse" id="a"/>
<bsdf type="diffuse" id="a"/>"#,
        ),
        "duplicate id \"a\"",
    );
    assert_eq!(e.line, Some(5));
    let e = expect_err(
        load(
            "unresolved-ref",
            r#"<shape type="sphere">
   <ref id="nothing"/></shape>"#,
        ),
        "unresolved reference to \"nothing\"",
    );
    assert_eq!((e.line, e.col), (Some(5), Some(4)));
    expect_err(
        load(
            "cycle",
            r#"<bsdf type="twosided" id="loop"><bsdf type="twosided"><ref id="loop"/></bsdf></bsdf>"#,
        ),
        "circular reference",
    );
    // A reference of the wrong kind is an unexpected object.
    expect_err(
        load(
            "wrong-kind",
            r#"<sensor type="perspective" id="cam"/><shape type="sphere"><ref id="cam"/></shape>"#,
        ),
        "unexpected nested <sensor",
    );
}

// ---------------------------------------------------------------------------------------
// Materials and emitters

/// `<spectrum value="v"/>` as Mitsuba's RGB variants read it (`src/core/properties.cpp`,
/// `get_texture_impl`): grey v for a reflectance or an index, v · xyz_to_srgb(1, 1, 1) for
/// an emitter's radiance, intensity or irradiance; wavelength:value lists, files and
/// spectrum plugins are refused with the line.
#[test]
fn loader_uniform_spectra() {
    let s = load_ok(
        "uniform-spectrum",
        r#"<shape type="sphere"><bsdf type="diffuse"><spectrum name="reflectance" value="0.25"/></bsdf></shape>
        <shape type="sphere"><emitter type="area"><spectrum name="radiance" value="2"/></emitter></shape>
        <emitter type="constant"><spectrum name="radiance" value="0.5"/></emitter>"#,
    );
    assert_vec_close(
        diffuse_color(&s.shapes[0].bsdf),
        Vec3::splat(0.25),
        0.0,
        "a reflectance is the value itself",
    );
    // The rows of Mitsuba's XYZ-to-sRGB matrix summed: equal energy is purplish in sRGB.
    let white = Vec3::new(1.204794, 0.948291, 0.908916);
    match &s.shapes[1].emission {
        Some(radia_bsdf::Texture::Constant(c)) => {
            assert_vec_close(*c, 2.0 * white, 1e-6, "area radiance")
        }
        e => panic!("{e:?}"),
    }
    match &s.emitters[0] {
        EmitterDesc::Constant { radiance } => {
            assert_vec_close(*radiance, 0.5 * white, 1e-6, "constant radiance")
        }
        e => panic!("{e:?}"),
    }
    for (name, spectrum, needle) in [
        (
            "spectrum-pairs",
            r#"<spectrum name="radiance" value="400:0.1, 700:0.2"/>"#,
            "wavelength:value spectra are not supported",
        ),
        (
            "spectrum-file",
            r#"<spectrum name="radiance" filename="d65.spd"/>"#,
            "spectra from files are not supported",
        ),
        (
            "spectrum-both",
            r#"<spectrum name="radiance" value="1" filename="d65.spd"/>"#,
            "requires either",
        ),
        (
            "spectrum-plugin",
            r#"<spectrum type="blackbody" name="radiance"/>"#,
            "spectrum plugin type \"blackbody\"",
        ),
        (
            "spectrum-nan",
            r#"<spectrum name="radiance" value="bright"/>"#,
            "could not parse uniform spectrum value",
        ),
    ] {
        let body = format!(r#"<emitter type="constant">{spectrum}</emitter>"#);
        expect_err(load(name, &body), needle);
    }
}

#[test]
fn loader_twosided_and_default_bsdfs() {
    let s = load_ok(
        "twosided",
        r#"<shape type="sphere"><bsdf type="twosided"><bsdf type="diffuse"><rgb name="reflectance" value="0.2"/></bsdf></bsdf></shape>
        <shape type="sphere"><bsdf type="twosided">
            <bsdf type="diffuse"><rgb name="reflectance" value="0.1, 0.2, 0.3"/></bsdf>
            <bsdf type="diffuse"><float name="reflectance" value="0.9"/></bsdf></bsdf></shape>
        <shape type="sphere"/>
        <shape type="sphere"><emitter type="area"><rgb name="radiance" value="2, 3, 4"/></emitter></shape>
        <shape type="sphere"><emitter type="area"/></shape>
        <emitter type="constant"><float name="radiance" value="0.5"/></emitter>"#,
    );
    match &s.shapes[0].bsdf {
        Bsdf::TwoSided(t) => {
            assert_vec_close(diffuse_color(&t.sides[0]), Vec3::splat(0.2), 1e-6, "front");
            assert_vec_close(
                diffuse_color(&t.sides[1]),
                Vec3::splat(0.2),
                1e-6,
                "one nested BSDF on both sides",
            );
        }
        b => panic!("{b:?}"),
    }
    match &s.shapes[1].bsdf {
        Bsdf::TwoSided(t) => {
            assert_vec_close(
                diffuse_color(&t.sides[0]),
                Vec3::new(0.1, 0.2, 0.3),
                1e-6,
                "front",
            );
            assert_vec_close(diffuse_color(&t.sides[1]), Vec3::splat(0.9), 1e-6, "back");
        }
        b => panic!("{b:?}"),
    }
    assert_vec_close(
        diffuse_color(&s.shapes[2].bsdf),
        Vec3::splat(0.5),
        0.0,
        "default bsdf",
    );
    assert_eq!(s.shapes[2].emission, None);
    assert_vec_close(
        diffuse_color(&s.shapes[3].bsdf),
        Vec3::ZERO,
        0.0,
        "default bsdf of an emitter is black",
    );
    assert_eq!(s.shapes[3].emission, Some(Vec3::new(2., 3., 4.).into()));
    assert_eq!(
        s.shapes[4].emission,
        Some(Vec3::ONE.into()),
        "area radiance defaults to 1"
    );
    assert_eq!(
        s.emitters,
        vec![EmitterDesc::Constant {
            radiance: Vec3::splat(0.5)
        }]
    );
    assert!(
        s.shapes[0].origin.ends_with("scene.xml:4"),
        "{}",
        s.shapes[0].origin
    );

    expect_err(
        load("twosided-empty", r#"<bsdf type="twosided" id="t"/>"#),
        "nested one-sided BSDF is required",
    );
    expect_err(
        load(
            "twosided-3",
            r#"<bsdf type="twosided" id="t"><bsdf type="diffuse"/><bsdf type="diffuse"/><bsdf type="diffuse"/></bsdf>"#,
        ),
        "at most two",
    );
    expect_err(
        load("hair", r#"<bsdf type="hair" id="c"/>"#),
        "unsupported BSDF plugin type \"hair\"",
    );
    expect_err(
        load(
            "rgb-range",
            r#"<bsdf type="diffuse" id="d"><rgb name="reflectance" value="1.5, 0, 0"/></bsdf>"#,
        ),
        "range [0, 1]",
    );
    expect_err(
        load("projector-emitter", r#"<emitter type="projector"/>"#),
        "unsupported emitter plugin type \"projector\"",
    );
    expect_err(
        load(
            "two-bsdfs",
            r#"<shape type="sphere"><bsdf type="diffuse"/><bsdf type="diffuse"/></shape>"#,
        ),
        "only a single BSDF",
    );
    expect_err(
        load(
            "area-to-world",
            r#"<shape type="sphere"><emitter type="area"><transform name="to_world"/></emitter></shape>"#,
        ),
        "unexpected parameter \"to_world\"",
    );
}

// ---------------------------------------------------------------------------------------
// Built-in shapes

#[test]
fn loader_rectangle_cube_sphere_disk() {
    let s = load_ok(
        "shapes",
        r#"<shape type="rectangle"/>
        <shape type="rectangle"><boolean name="flip_normals" value="true"/>
            <transform name="to_world"><scale x="2" y="3"/><translate z="1"/></transform></shape>
        <shape type="cube"><transform name="to_world"><scale x="2"/></transform></shape>
        <shape type="sphere"><point name="center" x="1" y="2" z="3"/><float name="radius" value="0.5"/>
            <transform name="to_world"><scale value="2"/><translate x="10"/></transform></shape>
        <shape type="sphere"><boolean name="flip_normals" value="true"/></shape>
        <shape type="disk"><transform name="to_world"><translate y="1"/></transform>
            <boolean name="flip_normals" value="true"/></shape>"#,
    );
    // Rectangle: [-1,1]² at z = 0, normal +z, uv = ((x+1)/2, (y+1)/2), 2 triangles, no normals.
    let r = mesh_of(&s.shapes[0]);
    assert_eq!(r.positions.len(), 4);
    assert_eq!(r.indices.len(), 2);
    assert_eq!(r.normals, None);
    let uvs = r.uvs.as_ref().expect("rectangle uvs");
    for (p, uv) in r.positions.iter().zip(uvs) {
        assert_eq!(p.z, 0.0);
        assert!(p.x.abs() == 1.0 && p.y.abs() == 1.0);
        assert_eq!(*uv, Vec2::new((p.x + 1.0) / 2.0, (p.y + 1.0) / 2.0));
    }
    let mut area = 0.0;
    for t in &r.indices {
        let [a, b, c] = t.map(|i| r.positions[i as usize]);
        let n = (b - a).cross(c - a);
        assert!(
            n.z > 0.0 && n.x == 0.0 && n.y == 0.0,
            "counter-clockwise seen from +z"
        );
        area += n.length() / 2.0;
    }
    assert_eq!(area, 4.0);
    assert!(!r.flip_normals);
    let r2 = mesh_of(&s.shapes[1]);
    assert!(r2.flip_normals);
    assert!(
        r2.positions.contains(&Vec3::new(2., 3., 1.))
            && r2.positions.contains(&Vec3::new(-2., -3., 1.))
    );

    // Cube: 24 vertices, 12 triangles, per-face normals consistent with the winding.
    let c = mesh_of(&s.shapes[2]);
    assert_eq!((c.positions.len(), c.indices.len()), (24, 12));
    let normals = c.normals.as_ref().expect("cube normals");
    let uvs = c.uvs.as_ref().expect("cube uvs");
    for t in &c.indices {
        let [a, b, cc] = t.map(|i| c.positions[i as usize]);
        let g = (b - a).cross(cc - a).normalize();
        for &i in t {
            assert_vec_close(normals[i as usize], g, 1e-6, "cube normal = face normal");
            // Outward: the normal points away from the centre.
            assert!(normals[i as usize].dot(c.positions[i as usize]) > 0.0);
        }
    }
    assert!(c
        .positions
        .iter()
        .all(|p| p.x.abs() == 2.0 || p.y.abs() == 1.0 || p.z.abs() == 1.0));
    assert!(c
        .positions
        .iter()
        .all(|p| p.x.abs() <= 2.0 && p.y.abs() <= 1.0 && p.z.abs() <= 1.0));
    assert_eq!(uvs[0], Vec2::new(0., 1.));
    assert_eq!(uvs[2], Vec2::new(1., 0.));

    // Sphere: center = to_world(center), radius scaled.
    match s.shapes[3].geometry {
        Geometry::Sphere {
            center,
            radius,
            to_world,
            flip_normals,
        } => {
            assert_vec_close(center, Vec3::new(12., 4., 6.), 1e-6, "center");
            assert_close(radius, 1.0, 1e-6, "radius");
            assert_eq!(to_world, glam::Mat3A::IDENTITY, "scale 2 times radius 0.5");
            assert!(!flip_normals);
        }
        ref g => panic!("{g:?}"),
    }
    match s.shapes[4].geometry {
        Geometry::Sphere {
            center,
            radius,
            flip_normals,
            ..
        } => {
            assert_eq!((center, radius, flip_normals), (Vec3::ZERO, 1.0, true));
        }
        ref g => panic!("{g:?}"),
    }
    match &s.shapes[5].geometry {
        Geometry::Disk {
            to_world,
            flip_normals,
        } => {
            assert_eq!(*to_world, Affine3A::from_translation(Vec3::Y));
            assert!(*flip_normals);
        }
        g => panic!("{g:?}"),
    }

    expect_err(
        load(
            "sphere-facenormals",
            r#"<shape type="sphere"><boolean name="face_normals" value="true"/></shape>"#,
        ),
        "face_normals",
    );
    expect_err(
        load("cylinder", r#"<shape type="cylinder"/>"#),
        "unsupported shape plugin type \"cylinder\"",
    );
    // Instancing is supported (tests/instances.rs); an instance needs its group.
    expect_err(
        load("instance", r#"<shape type="instance"/>"#),
        "a reference to a shapegroup must be specified",
    );
    expect_err(
        load(
            "sphere-rgb-center",
            r#"<shape type="sphere"><rgb name="center" value="1"/></shape>"#,
        ),
        "wrong type",
    );
}

// ---------------------------------------------------------------------------------------
// Mesh files

const CUBE_CORNERS: [[f32; 3]; 4] = [[0., 0., 0.], [1., 0., 0.], [1., 1., 0.], [0., 1., 0.]];

fn ply_ascii_quad() -> String {
    let mut s = String::from(
        "ply\nformat ascii 1.0\ncomment a unit quad\nelement vertex 4\nproperty float x\nproperty float y\n\
         property float z\nproperty float u\nproperty float v\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n",
    );
    for (i, p) in CUBE_CORNERS.iter().enumerate() {
        s += &format!("{} {} {} {} {}\n", p[0], p[1], p[2], i as f32 * 0.25, 0.5);
    }
    s += "4 0 1 2 3\n";
    s
}

/// The same quad as binary PLY with normals (s, t texture names, vertex_index list, an
/// extra element to skip).
fn ply_binary_quad(big_endian: bool) -> Vec<u8> {
    let fmt = if big_endian {
        "binary_big_endian"
    } else {
        "binary_little_endian"
    };
    let mut out = format!(
        "ply\nformat {fmt} 1.0\nelement vertex 4\nproperty double x\nproperty float y\nproperty float z\n\
         property float nx\nproperty float ny\nproperty float nz\nproperty uchar red\nproperty float s\nproperty float t\n\
         element face 2\nproperty list uchar uint vertex_index\nelement material 1\nproperty list uchar float stuff\nend_header\n"
    )
    .into_bytes();
    let f32b = |x: f32| {
        if big_endian {
            x.to_be_bytes()
        } else {
            x.to_le_bytes()
        }
    };
    let u32b = |x: u32| {
        if big_endian {
            x.to_be_bytes()
        } else {
            x.to_le_bytes()
        }
    };
    for (i, p) in CUBE_CORNERS.iter().enumerate() {
        let x = p[0] as f64;
        out.extend(if big_endian {
            x.to_be_bytes()
        } else {
            x.to_le_bytes()
        });
        out.extend(f32b(p[1]));
        out.extend(f32b(p[2]));
        out.extend(f32b(0.0));
        out.extend(f32b(0.0));
        out.extend(f32b(2.0)); // not unit length: normalized by the loader
        out.push(200);
        out.extend(f32b(i as f32 * 0.25));
        out.extend(f32b(0.5));
    }
    for tri in [[0u32, 1, 2], [0, 2, 3]] {
        out.push(3);
        for i in tri {
            out.extend(u32b(i));
        }
    }
    out.push(2);
    out.extend(f32b(1.0));
    out.extend(f32b(2.0));
    out
}

fn check_quad(m: &Mesh, what: &str) {
    assert_eq!(m.positions.len(), 4, "{what}");
    for (p, q) in m.positions.iter().zip(CUBE_CORNERS) {
        assert_eq!(*p, Vec3::from_array(q), "{what}");
    }
    assert_eq!(
        m.indices,
        vec![[0, 1, 2], [0, 2, 3]],
        "{what}: quad split into two triangles"
    );
    let uvs = m.uvs.as_ref().expect("uvs");
    assert_eq!(
        uvs[1],
        Vec2::new(0.25, 0.5),
        "{what}: uv (PLY does not flip v by default)"
    );
    let n = m.normals.as_ref().expect("normals");
    for v in n {
        assert_vec_close(*v, Vec3::Z, 1e-6, what);
    }
}

#[test]
fn loader_ply_ascii_and_binary() {
    let dir = write_files(
        "ply",
        &[
            ("a.ply", ply_ascii_quad().as_bytes()),
            ("le.ply", &ply_binary_quad(false)),
            ("be.ply", &ply_binary_quad(true)),
        ],
    );
    check_quad(
        &load_ply(&dir.join("a.ply"), false).expect("ascii"),
        "ascii (normals recomputed)",
    );
    check_quad(
        &load_ply(&dir.join("le.ply"), false).expect("le"),
        "little endian",
    );
    check_quad(
        &load_ply(&dir.join("be.ply"), false).expect("be"),
        "big endian",
    );
    let flipped = load_ply(&dir.join("a.ply"), true).expect("flip");
    assert_eq!(
        flipped.uvs.as_ref().map(|u| u[1]),
        Some(Vec2::new(0.25, 0.5)),
        "1 - 0.5"
    );

    // Through the XML: transform, face_normals, flip_tex_coords.
    let s = load_in(
        &dir,
        &scene_xml(
            r#"<shape type="ply"><string name="filename" value="be.ply"/>
                <transform name="to_world"><scale z="-1"/><translate x="1"/></transform></shape>
            <shape type="ply"><string name="filename" value="a.ply"/><boolean name="face_normals" value="true"/></shape>"#,
        ),
        &[],
    )
    .expect("ply scene");
    let m = mesh_of(&s.shapes[0]);
    assert_eq!(m.positions[2], Vec3::new(2., 1., 0.));
    for n in m.normals.as_ref().expect("normals") {
        assert_vec_close(*n, -Vec3::Z, 1e-6, "normals by the inverse transpose");
    }
    assert_eq!(mesh_of(&s.shapes[1]).normals, None, "face_normals");

    // Errors name the mesh file.
    let bad_index = ply_ascii_quad().replace("4 0 1 2 3", "3 0 1 7");
    let full = ply_binary_quad(false);
    let truncated = &full[..full.len() - 10];
    let dir = write_files(
        "ply-bad",
        &[("idx.ply", bad_index.as_bytes()), ("short.ply", truncated)],
    );
    let e = load_ply(&dir.join("idx.ply"), false).expect_err("index out of range");
    assert!(
        e.to_string().contains("idx.ply") && e.to_string().contains("vertex 7"),
        "{e}"
    );
    let e = load_ply(&dir.join("short.ply"), false).expect_err("truncated");
    assert!(
        e.to_string().contains("short.ply") && e.to_string().contains("unexpected end"),
        "{e}"
    );
    let e = load_in(
        &dir,
        &scene_xml(r#"<shape type="ply"><string name="filename" value="idx.ply"/></shape>"#),
        &[],
    )
    .expect_err("through the scene");
    assert!(e.file.ends_with("idx.ply"), "{e}");
    assert!(
        e.message.contains("scene.xml:4:"),
        "the shape's position is mentioned: {e}"
    );
}

/// A binary PLY in the layout most exporters write (float x y z nx ny nz u v, then
/// `list uchar int vertex_indices`), the one the reader's fast paths are for: a small grid with
/// triangles and quads; `faces` replaces the face list when given.
fn ply_float_grid(big_endian: bool, faces: Option<&[Vec<i32>]>) -> Vec<u8> {
    let n = 5;
    let mut default_faces = Vec::new();
    for j in 0..n - 1 {
        for i in 0..n - 1 {
            let a = j * n + i;
            if (i + j) % 3 == 0 {
                default_faces.push(vec![a, a + 1, a + n + 1, a + n]);
            } else {
                default_faces.push(vec![a, a + n, a + 1]);
                default_faces.push(vec![a + 1, a + n, a + n + 1]);
            }
        }
    }
    let faces = faces.unwrap_or(&default_faces);
    let fmt = if big_endian {
        "binary_big_endian"
    } else {
        "binary_little_endian"
    };
    let mut out = format!(
        "ply\nformat {fmt} 1.0\nelement vertex {}\nproperty float x\nproperty float y\nproperty float z\n\
         property float nx\nproperty float ny\nproperty float nz\nproperty float u\nproperty float v\n\
         element face {}\nproperty list uchar int vertex_indices\nend_header\n",
        n * n,
        faces.len()
    )
    .into_bytes();
    let put = |out: &mut Vec<u8>, b: [u8; 4]| {
        out.extend(if big_endian {
            [b[3], b[2], b[1], b[0]]
        } else {
            b
        })
    };
    for j in 0..n {
        for i in 0..n {
            let (x, z) = (i as f32 / 3.0, j as f32 * 0.7);
            let y = (x * 2.0).sin() * 0.1;
            for v in [x, y, z, -0.2, 1.0, 0.1 * z, x * 0.3, 1.0 - z * 0.1] {
                put(&mut out, v.to_le_bytes());
            }
        }
    }
    for f in faces {
        out.push(f.len() as u8);
        for &i in f {
            put(&mut out, i.to_le_bytes());
        }
    }
    out
}

#[test]
fn loader_ply_fast_path_matches_general() {
    let files = [
        ("quad le", ply_binary_quad(false)),
        ("quad be", ply_binary_quad(true)),
        ("grid le", ply_float_grid(false, None)),
        ("grid be", ply_float_grid(true, None)),
        ("ascii", ply_ascii_quad().into_bytes()),
    ];
    for (what, data) in &files {
        for (flip, skip) in [(false, false), (true, false), (false, true)] {
            let fast = ply::parse_ply_with(data, flip, skip, true);
            let general = ply::parse_ply_with(data, flip, skip, false);
            assert!(fast.is_ok(), "{what}: {fast:?}");
            assert_eq!(fast, general, "{what}, flip {flip}, skip normals {skip}");
        }
    }
    let grid = ply::parse_ply(&files[2].1, false, false).expect("grid");
    assert_eq!(grid.positions.len(), 25);
    assert_eq!(grid.indices.len(), 32, "16 cells, two triangles each");
    assert!(grid.normals.is_some() && grid.uvs.is_some());

    // Invalid faces: the same error, found the same way, in both paths.
    for (what, faces) in [
        ("index out of range", vec![vec![0, 1, 2], vec![0, 25, 1]]),
        ("negative index", vec![vec![0, 1, 2, 3], vec![-1, 1, 2]]),
        (
            "two vertices",
            vec![vec![0, 1, 2], vec![0, 1], vec![0, 99, 1]],
        ),
    ] {
        let data = ply_float_grid(false, Some(&faces));
        let fast = ply::parse_ply_with(&data, false, false, true);
        assert!(fast.is_err(), "{what}");
        assert_eq!(
            fast,
            ply::parse_ply_with(&data, false, false, false),
            "{what}"
        );
    }
}

#[test]
fn loader_ply_truncated_binary_is_an_error() {
    // Every cut through the body, in both paths: an error, never a panic, and the same one.
    for data in [ply_float_grid(false, None), ply_binary_quad(true)] {
        let body = data
            .windows(11)
            .position(|w| w == b"end_header\n")
            .expect("header")
            + 11;
        for cut in body..data.len() {
            let fast = ply::parse_ply_with(&data[..cut], false, false, true);
            let e = fast.as_ref().expect_err("truncated");
            assert!(e.contains("unexpected end of data"), "cut at {cut}: {e}");
            assert_eq!(fast, ply::parse_ply_with(&data[..cut], false, false, false));
        }
    }
    // Named by the loader.
    let full = ply_float_grid(false, None);
    let dir = write_files("ply-cut", &[("cut.ply", &full[..full.len() - 7])]);
    let e = load_ply(&dir.join("cut.ply"), false).expect_err("truncated");
    assert!(
        e.to_string().contains("cut.ply") && e.to_string().contains("unexpected end"),
        "{e}"
    );
}

#[test]
fn loader_obj_variants() {
    let obj = "# comment\no thing\n\
        v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0.5 0.5 1\n\
        vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n\
        vn 0 0 1\nvn 0 0 -1\n\
        usemtl whatever\ns off\n\
        f 1/1/1 2/2/1 3/3/1 4/4/1\n\
        f 1//2 -2//-1 -3//-1\n\
        f -5/-4 -4/-3 5\n\
        f 1 2 5\n";
    let dir = write_files("obj", &[("m.obj", obj.as_bytes())]);
    let m = load_obj(&dir.join("m.obj"), true).expect("obj");
    // Distinct (v, vt, vn) triples in order of first use:
    // 1/1/1 2/2/1 3/3/1 4/4/1 | 1//2 4//2 3//2 | 1/1/0 2/2/0 5/0/0 | 1/0/0 2/0/0 (5/0/0 again)
    assert_eq!(m.positions.len(), 12);
    assert_eq!(
        m.indices.len(),
        2 + 1 + 1 + 1,
        "quad fan-triangulated + 3 triangles"
    );
    assert_eq!(m.indices[0], [0, 1, 2]);
    assert_eq!(m.indices[1], [0, 2, 3]);
    assert_eq!(m.indices[4], [10, 11, 9], "5/0/0 reused");
    assert_eq!(m.positions[5], Vec3::new(0., 1., 0.), "-2 is vertex 4");
    let uvs = m.uvs.as_ref().expect("uvs");
    assert_eq!(
        uvs[2],
        Vec2::new(1., 0.),
        "flip_tex_coords: (1, 1) -> (1, 0)"
    );
    assert_eq!(uvs[4], Vec2::ZERO, "missing vt");
    let n = m.normals.as_ref().expect("normals");
    assert_eq!(n[0], Vec3::Z);
    assert_eq!(n[4], -Vec3::Z);
    // 1/1 (no normal) gets a recomputed one from its faces: finite and unit.
    assert_close(n[7].length(), 1.0, 1e-5, "recomputed normal");
    let unflipped = load_obj(&dir.join("m.obj"), false).expect("obj");
    assert_eq!(
        unflipped.uvs.as_ref().map(|u| u[2]),
        Some(Vec2::new(1., 1.))
    );

    // Via XML, OBJ flips texture coordinates by default.
    let s = load_in(&dir, &scene_xml(r#"<shape type="obj"><string name="filename" value="m.obj"/></shape>
        <shape type="obj"><string name="filename" value="m.obj"/><boolean name="flip_tex_coords" value="false"/></shape>"#), &[])
        .expect("scene");
    assert_eq!(
        mesh_of(&s.shapes[0]).uvs.as_ref().map(|u| u[2]),
        Some(Vec2::new(1., 0.))
    );
    assert_eq!(
        mesh_of(&s.shapes[1]).uvs.as_ref().map(|u| u[2]),
        Some(Vec2::new(1., 1.))
    );

    // Errors carry the OBJ line.
    let dir = write_files(
        "obj-bad",
        &[
            ("range.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\n\nf 1 2 4\n"),
            ("syntax.obj", b"v 0 0\n"),
        ],
    );
    let e = load_obj(&dir.join("range.obj"), true).expect_err("out of range");
    assert_eq!(e.line, Some(5));
    assert!(
        e.to_string()
            .contains("range.obj:5: reference to invalid vertex 4"),
        "{e}"
    );
    let e = load_obj(&dir.join("syntax.obj"), true).expect_err("syntax");
    assert_eq!(e.line, Some(1));
    let e = load_in(
        &dir,
        &scene_xml(r#"<shape type="obj"><string name="filename" value="range.obj"/></shape>"#),
        &[],
    )
    .expect_err("through the scene");
    assert!(
        e.to_string()
            .starts_with(&format!("{}:5:", dir.join("range.obj").display())),
        "{e}"
    );
}

#[test]
fn loader_normals_recomputed_angle_weighted() {
    // A corner where three faces meet with different angles at vertex 0 (the origin): in the
    // xy-plane (normal +z) 90°, in the xz-plane (normal +y) 45°, in the yz-plane (+x) 90°.
    let obj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 0 1\nv 0 0 1\n\
               f 1 2 3\n\
               f 1 4 2\n\
               f 1 3 5\n";
    let dir = write_files("normals", &[("n.obj", obj.as_bytes())]);
    let m = load_obj(&dir.join("n.obj"), true).expect("obj");
    let n = m.normals.as_ref().expect("normals");
    // Definition: the sum of face normals weighted by the face's angle at the vertex.
    let p = &m.positions;
    let mut expected = Vec3::ZERO;
    for t in &m.indices {
        let [a, b, c] = t.map(|i| p[i as usize]);
        let fnorm = (b - a).cross(c - a).normalize();
        let angle = (b - a).normalize().dot((c - a).normalize()).acos();
        expected += fnorm * angle;
    }
    assert_vec_close(
        n[0],
        expected.normalize(),
        1e-5,
        "angle-weighted normal at the shared corner",
    );
    // The faces at vertex 0: +z with a 90° angle, +y with 45°, +x with 90°.
    let by_hand = Vec3::new(FRAC_PI_2, FRAC_PI_4, FRAC_PI_2).normalize();
    assert_vec_close(n[0], by_hand, 1e-5, "hand-computed");
    // Vertex (1, 0, 0) (output index 1): +z with 45°, +y with 90°.
    assert_eq!(p[1], Vec3::X);
    assert_vec_close(
        n[1],
        Vec3::new(0.0, FRAC_PI_2, FRAC_PI_4).normalize(),
        1e-5,
        "second vertex",
    );
    // A vertex of one face only gets that face's normal: (0, 0, 1) is only in the +x face.
    assert_eq!(p[4], Vec3::Z);
    assert_vec_close(n[4], Vec3::X, 1e-6, "single face");
}

#[test]
fn loader_degenerate_triangles_dropped() {
    let obj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 2 0 0\nf 1 2 3\nf 1 2 4\nf 1 1 3\n";
    let dir = write_files("degenerate", &[("d.obj", obj.as_bytes())]);
    let path = dir.join("scene.xml");
    std::fs::write(
        &path,
        scene_xml(r#"<shape type="obj"><string name="filename" value="d.obj"/></shape>"#),
    )
    .expect("write");
    let (s, warnings) = load_mitsuba_xml_with_warnings(&path, &[]).expect("load");
    assert_eq!(mesh_of(&s.shapes[0]).indices, vec![[0, 1, 2]]);
    assert!(
        warnings.iter().any(|w| w.contains("dropped 2 degenerate")),
        "{warnings:?}"
    );
}

// ---------------------------------------------------------------------------------------
// Errors

#[test]
fn loader_malformed_xml() {
    let dir = temp_dir("malformed");
    let e = load_in(
        &dir,
        "<scene version=\"3.0.0\">\n  <shape type=\"sphere\">\n</scene>\n",
        &[],
    )
    .expect_err("malformed");
    assert_eq!(e.line, Some(3));
    assert!(e.col.is_some());
    let shown = e.to_string();
    assert!(
        shown.starts_with(&format!("{}:3:", dir.join("scene.xml").display())),
        "{shown}"
    );
    assert!(shown.contains("malformed XML"), "{shown}");

    let e = load_in(&dir, "<scene>\n</scene>", &[]).expect_err("version");
    assert!(e.to_string().contains("version"), "{e}");
    let e = load_in(&dir, "<scene version=\"3.0\">\n</scene>", &[]).expect_err("version format");
    assert!(e.to_string().contains("invalid version"), "{e}");
    let e = load_in(&dir, "<bsdf version=\"3.0.0\" type=\"diffuse\"/>", &[]).expect_err("root");
    assert!(
        e.to_string().contains("root element must be <scene>"),
        "{e}"
    );
    let e = load_in(&dir, "<scene version=\"3.0.0\"/>", &[]).expect_err("no sensor");
    assert!(e.to_string().contains("no <sensor>"), "{e}");
}

#[test]
fn loader_missing_file_errors() {
    let missing = temp_dir("missing-scene").join("nope.xml");
    let e = load_mitsuba_xml(&missing, &[]).expect_err("missing scene");
    assert_eq!(e.line, None);
    assert!(
        e.to_string().starts_with(&missing.display().to_string()),
        "{e}"
    );

    let dir = temp_dir("missing-mesh");
    let e = expect_err(
        load_in(
            &dir,
            &scene_xml(
                r#"<shape type="obj">
    <string name="filename" value="meshes/none.obj"/></shape>"#,
            ),
            &[],
        ),
        "not found",
    );
    assert_eq!(e.file, dir.join("scene.xml"));
    assert_eq!(e.line, Some(4), "line of the <shape>");
    assert!(
        e.message
            .contains(&dir.join("meshes/none.obj").display().to_string()),
        "{e}"
    );
    expect_err(
        load("no-filename", r#"<shape type="ply"/>"#),
        "\"filename\" parameter is required",
    );
}

#[test]
fn loader_unsupported_and_unknown() {
    let e = expect_err(
        load(
            "unknown-element",
            "<shape type=\"sphere\">\n  <flaot name=\"radius\" value=\"1\"/></shape>",
        ),
        "unsupported XML element <flaot>",
    );
    assert_eq!((e.line, e.col), (Some(5), Some(3)));
    let e = expect_err(
        load(
            "unknown-param",
            "<shape type=\"sphere\">\n  <float name=\"radis\" value=\"1\"/></shape>",
        ),
        "unexpected parameter \"radis\"",
    );
    assert_eq!(e.line, Some(5));
    expect_err(
        load("texture", r#"<texture type="bitmap" id="t"/>"#),
        "bitmap: the \"filename\" parameter is required",
    );
    expect_err(
        load("medium", r#"<medium type="homogeneous" id="m"/>"#),
        "<medium> objects are not supported",
    );
    expect_err(
        load("path", r#"<path value="meshes"/>"#),
        "<path> is not supported",
    );
    expect_err(
        load(
            "unknown-attr",
            r#"<shape type="sphere"><float name="radius" value="1" unit="m"/></shape>"#,
        ),
        "unexpected attribute \"unit\"",
    );
    expect_err(
        load(
            "missing-attr",
            r#"<shape type="sphere"><float name="radius"/></shape>"#,
        ),
        "missing required attribute \"value\"",
    );
    expect_err(
        load(
            "bad-float",
            r#"<shape type="sphere"><float name="radius" value="1.0.0"/></shape>"#,
        ),
        "could not parse floating point value",
    );
    expect_err(
        load(
            "bad-int",
            r#"<sensor type="perspective"><sampler type="independent"><integer name="sample_count" value="4.5"/></sampler></sensor>"#,
        ),
        "could not parse integer",
    );
    expect_err(
        load(
            "bad-bool",
            r#"<shape type="sphere"><boolean name="flip_normals" value="yes"/></shape>"#,
        ),
        "could not parse boolean",
    );
    expect_err(
        load(
            "bad-rgb",
            r#"<bsdf type="diffuse" id="x"><rgb name="reflectance" value="0.1 0.2"/></bsdf>"#,
        ),
        "one or three values",
    );
    expect_err(
        load(
            "wrong-type",
            r#"<bsdf type="diffuse" id="x"><string name="reflectance" value="0.1"/></bsdf>"#,
        ),
        "wrong type",
    );
    expect_err(
        load(
            "duplicate-param",
            r#"<shape type="sphere"><float name="radius" value="1"/><float name="radius" value="2"/></shape>"#,
        ),
        "more than once",
    );
    expect_err(
        load(
            "nested-in-prop",
            r#"<shape type="sphere"><float name="radius" value="1"><float name="x" value="1"/></float></shape>"#,
        ),
        "cannot occur as a child",
    );
    expect_err(
        load(
            "op-outside",
            r#"<shape type="sphere"><translate x="1"/></shape>"#,
        ),
        "can only appear inside a <transform>",
    );
    expect_err(
        load(
            "zero-axis",
            r#"<shape type="disk"><transform name="to_world"><rotate angle="10"/></transform></shape>"#,
        ),
        "axis cannot be zero",
    );
    expect_err(
        load(
            "unknown-sampler",
            r#"<sensor type="perspective"><sampler type="halton"/></sensor>"#,
        ),
        "unsupported sampler plugin type",
    );
    expect_err(
        load(
            "nested-sampler-in-shape",
            r#"<shape type="sphere"><sampler type="independent"/></shape>"#,
        ),
        "unexpected nested <sampler",
    );
}

#[test]
fn loader_version_1_names_are_upgraded() {
    // Mitsuba upgrades camelCase names in files older than 2.0.0.
    let s = load_in(
        &temp_dir("v1"),
        r#"<scene version="0.6.0"><sensor type="perspective"><float name="fov" value="30"/><string name="fovAxis" value="y"/>
           <sampler type="independent"><integer name="sampleCount" value="9"/></sampler></sensor></scene>"#,
        &[],
    )
    .expect("v0.6 scene");
    assert_eq!(s.sampler.sample_count, 9);
    assert!(s.camera.fov_x_degrees > 30.0, "fov_axis y was read");
}

// ---------------------------------------------------------------------------------------
// The repository's scenes

fn repo_scene(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../scenes")
        .join(name)
}

#[test]
fn loader_repo_cornell_box() {
    let defines = vec![
        ("spp".to_string(), "16".to_string()),
        ("res".to_string(), "64".to_string()),
    ];
    let (s, warnings) = load_mitsuba_xml_with_warnings(&repo_scene("cornell-box.xml"), &defines)
        .expect("cornell box");
    assert!(warnings.is_empty(), "{warnings:?}");
    assert_eq!(
        (s.film.width, s.film.height, s.sampler.sample_count),
        (64, 64, 16)
    );
    assert_eq!(s.film.filter, FilterDesc::Box);
    assert_eq!(s.integrator.max_depth, -1);
    assert_eq!(s.shapes.len(), 6);
    let lights: Vec<&ShapeDesc> = s.shapes.iter().filter(|sh| sh.emission.is_some()).collect();
    assert_eq!(lights.len(), 1);
    let light = mesh_of(lights[0]);
    let mut area = 0.0;
    for t in &light.indices {
        let [a, b, c] = t.map(|i| light.positions[i as usize]);
        let n = (b - a).cross(c - a);
        assert!(n.y < 0.0, "the light faces down");
        area += n.length() / 2.0;
    }
    assert_close(area, 0.25, 1e-5, "light area");
    // Every wall and box is a mesh with normals; all vertices inside the box (in the file's
    // coordinates: render space is centred on the camera).
    let eps = 1e-5;
    for sh in &s.shapes {
        let m = mesh_of(sh);
        assert!(!m.indices.is_empty());
        assert!(m.positions.iter().all(|p| {
            let p = p.as_dvec3() + s.world_origin;
            p.x.abs() <= 1.0 + eps && p.y >= -eps && p.y <= 2.0 + eps && p.z.abs() <= 1.0 + eps
        }));
    }
    // Walls face into the box: the floor's normals point up.
    let floor = mesh_of(&s.shapes[0]);
    assert!(floor
        .normals
        .as_ref()
        .map_or(false, |n| n.iter().any(|v| *v == Vec3::Y)));
}

#[test]
fn loader_repo_furnace() {
    let s = load_mitsuba_xml(
        &repo_scene("furnace.xml"),
        &[("albedo".to_string(), "0.5".to_string())],
    )
    .expect("furnace");
    assert_eq!(
        s.emitters,
        vec![EmitterDesc::Constant {
            radiance: Vec3::ONE
        }]
    );
    assert_eq!(s.shapes.len(), 1);
    assert_vec_close(
        diffuse_color(&s.shapes[0].bsdf),
        Vec3::splat(0.5),
        0.0,
        "albedo define",
    );
    let s = load_mitsuba_xml(&repo_scene("furnace.xml"), &[]).expect("furnace");
    assert_vec_close(
        diffuse_color(&s.shapes[0].bsdf),
        Vec3::ONE,
        0.0,
        "default albedo 1",
    );
    assert_eq!(s.film.filter, FilterDesc::Box);
}

// ---------------------------------------------------------------------------------------
// Robustness: corrupted inputs give errors, never panics

/// A small deterministic generator (64-bit LCG).
struct Lcg(u64);

impl Lcg {
    fn next(&mut self) -> u64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        self.0 >> 33
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n.max(1) as u64) as usize
    }
}

/// `data` with a few random byte edits: replace, delete, duplicate a span, insert a
/// character that matters to the format.
fn mutate(rng: &mut Lcg, data: &[u8], specials: &[u8]) -> Vec<u8> {
    let mut d = data.to_vec();
    for _ in 0..1 + rng.below(4) {
        let at = rng.below(d.len());
        match rng.below(4) {
            0 if !d.is_empty() => d[at] = specials[rng.below(specials.len())],
            1 if !d.is_empty() => {
                let end = (at + 1 + rng.below(8)).min(d.len());
                d.drain(at..end);
            }
            2 => {
                let end = (at + 1 + rng.below(16)).min(d.len());
                let span = d[at..end].to_vec();
                d.splice(at..at, span);
            }
            _ => d.insert(at.min(d.len()), specials[rng.below(specials.len())]),
        }
    }
    d
}

#[test]
fn loader_corrupted_inputs_never_panic() {
    let xml = scene_xml(
        r#"<default name="r" value="0.5"/>
        <integrator type="path"><integer name="max_depth" value="4"/></integrator>
        <bsdf type="twosided" id="m"><bsdf type="diffuse"><rgb name="reflectance" value="0.2, 0.3, $r"/></bsdf></bsdf>
        <shape type="obj"><string name="filename" value="m.obj"/><ref id="m"/>
            <transform name="to_world"><rotate y="1" angle="30"/><scale value="2"/><lookat origin="0 0 1" target="0 0 0" up="0 1 0"/></transform></shape>
        <shape type="ply"><string name="filename" value="a.ply"/><emitter type="area"><rgb name="radiance" value="1 2 3"/></emitter></shape>
        <shape type="sphere"><point name="center" value="1 2 3"/><float name="radius" value="$r"/></shape>
        <shape type="cube"><transform name="to_world"><matrix value="1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1"/></transform></shape>
        <emitter type="constant"/>"#,
    );
    let obj = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 1\nvn 0 0 1\nf 1/1/1 2/2/1 3//1 4\nf -1 -2 -3\n";
    let dir = write_files(
        "fuzz",
        &[
            ("m.obj", obj.as_bytes()),
            ("a.ply", ply_ascii_quad().as_bytes()),
            ("b.ply", &ply_binary_quad(false)),
        ],
    );
    let scene_path = dir.join("scene.xml");
    // In memory (the mesh files stay intact; the readers get the corrupted bytes directly).
    let finalize = |raw: mesh::RawMesh| mesh::finalize(raw, &glam::DMat4::IDENTITY, false, false);
    let mut rng = Lcg(12345);
    let mut errors = 0;
    for i in 0..2000 {
        let bad = mutate(&mut rng, xml.as_bytes(), b"<>/\"=$ \n0-9.,x");
        let text = String::from_utf8_lossy(&bad);
        let r = xml::parse_str(&scene_path, &text, &[]).and_then(|doc| build::build_scene(&doc));
        errors += r.is_err() as usize;
        let bad = mutate(&mut rng, obj.as_bytes(), b"vf/ -0123456789\n.e");
        if let Ok(raw) = obj::parse_obj(&String::from_utf8_lossy(&bad), true, i % 3 == 0) {
            let _ = finalize(raw);
        }
        let bad = mutate(
            &mut rng,
            ply_ascii_quad().as_bytes(),
            b" \n-0123456789.eplyformatelementpropertylist",
        );
        if let Ok(raw) = ply::parse_ply(&bad, false, false) {
            let _ = finalize(raw);
        }
        let bad = mutate(
            &mut rng,
            &ply_binary_quad(i % 2 == 0),
            &[0, 1, 3, 4, 0x7f, 0x80, 0xff, b'\n'],
        );
        if let Ok(raw) = ply::parse_ply(&bad, i % 3 == 0, i % 5 == 0) {
            let _ = finalize(raw);
        }
    }
    assert!(errors > 100, "most corrupted scenes are errors ({errors})");

    // Deep nesting is an error, not a stack overflow.
    let deep = format!(
        "<scene version=\"3.0.0\">{}{}</scene>",
        "<bsdf type=\"twosided\">".repeat(5000),
        "</bsdf>".repeat(5000)
    );
    let e = load_in(&temp_dir("deep"), &deep, &[]).expect_err("deep nesting");
    assert!(e.to_string().contains("nested more than"), "{e}");
}

// ---------------------------------------------------------------------------------------------
// Textures
// ---------------------------------------------------------------------------------------------

/// An 8-bit PNG of `channels` (1 or 3) from raw bytes, row 0 at the top.
fn png(width: u32, height: u32, channels: u8, bytes: &[u8]) -> Vec<u8> {
    use ::image::ImageEncoder;
    let mut out = Vec::new();
    let color = if channels == 1 {
        ::image::ExtendedColorType::L8
    } else {
        ::image::ExtendedColorType::Rgb8
    };
    ::image::codecs::png::PngEncoder::new(&mut out)
        .write_image(bytes, width, height, color)
        .expect("encode png");
    out
}

fn first_bsdf(s: &SceneDescription, i: usize) -> &Bsdf {
    &s.shapes[i].bsdf
}

fn at(u: f32, v: f32) -> radia_bsdf::ShadingPoint {
    radia_bsdf::ShadingPoint::at_uv(Vec2::new(u, v))
}

/// A 2×2 sRGB PNG as a diffuse reflectance: texel centres give the decoded bytes, row 0
/// of the file is v = 0, `raw` gives byte/255, `nearest`, `mirror` and `to_uv` are read.
#[test]
fn bitmap_texture_parameters() {
    let img = png(2, 2, 3, &[255, 0, 0, 0, 255, 0, 0, 0, 255, 188, 188, 188]);
    let dir = write_files("bitmap", &[("t.png", &img)]);
    let xml = scene_xml(
        r#"<shape type="sphere"><bsdf type="diffuse"><texture type="bitmap" name="reflectance">
            <string name="filename" value="t.png"/></texture></bsdf></shape>
        <shape type="sphere"><bsdf type="diffuse"><texture type="bitmap" name="reflectance">
            <string name="filename" value="t.png"/><boolean name="raw" value="true"/>
            <string name="filter_type" value="nearest"/><string name="wrap_mode" value="mirror"/>
            <transform name="to_uv"><scale x="2" y="1"/><translate x="0.5"/></transform>
        </texture></bsdf></shape>"#,
    );
    let s = load_in(&dir, &xml, &[]).unwrap();
    let Bsdf::Diffuse(d) = first_bsdf(&s, 0) else {
        panic!()
    };
    assert!(matches!(d.reflectance, Texture::Bitmap(_)));
    let grey = radia_bsdf::srgb_to_linear(188.0 / 255.0);
    assert!(
        (d.reflectance.eval(&at(0.75, 0.75)) - Vec3::splat(grey))
            .abs()
            .max_element()
            < 1e-6
    );
    assert_eq!(d.reflectance.eval(&at(0.25, 0.25)), Vec3::X);
    assert_eq!(d.reflectance.eval(&at(0.75, 0.25)), Vec3::Y);
    let Bsdf::Diffuse(r) = first_bsdf(&s, 1) else {
        panic!()
    };
    // uv' = (2u + 0.5, v): u = 0.3 → 1.1, mirrored into texel 1 of row 1 (raw 188/255).
    assert!(
        (r.reflectance.eval(&at(0.3, 0.7)) - Vec3::splat(188.0 / 255.0))
            .abs()
            .max_element()
            < 1e-6
    );
    // u = 0.05 → 0.6, texel 1 of row 0: green.
    assert_eq!(r.reflectance.eval(&at(0.05, 0.2)), Vec3::Y);
}

/// A top-level texture referenced twice is decoded once and shared; a checkerboard may nest
/// a texture; alpha, blend weights and area radiance take textures.
#[test]
fn texture_refs_and_parameters() {
    let img = png(
        4,
        4,
        1,
        &[
            10, 50, 90, 130, 20, 60, 100, 140, 30, 70, 110, 150, 40, 80, 120, 160,
        ],
    );
    let dir = write_files("refs", &[("g.png", &img)]);
    let xml = scene_xml(
        r#"<texture type="bitmap" id="g"><string name="filename" value="g.png"/><boolean name="raw" value="true"/></texture>
        <shape type="sphere"><bsdf type="roughconductor"><ref name="alpha" id="g"/><ref name="specular_reflectance" id="g"/></bsdf></shape>
        <shape type="sphere"><bsdf type="blendbsdf">
            <texture type="checkerboard" name="weight"><ref name="color0" id="g"/><float name="color1" value="0.25"/></texture>
            <bsdf type="diffuse"/><bsdf type="roughdielectric"><ref name="alpha_u" id="g"/><float name="alpha_v" value="0.3"/></bsdf>
        </bsdf></shape>
        <shape type="sphere"><emitter type="area"><ref name="radiance" id="g"/></emitter></shape>"#,
    );
    let s = load_in(&dir, &xml, &[]).unwrap();
    let Bsdf::RoughConductor(c) = first_bsdf(&s, 0) else {
        panic!()
    };
    let rough = c.roughness.as_ref().expect("textured alpha");
    assert!(rough.alpha_u == rough.alpha_v && rough.alpha_u == c.specular_reflectance);
    let sp = at(0.375, 0.125); // texel (1, 0): 50/255
    assert!((rough.alpha_u.eval_1(&sp) - 50.0 / 255.0).abs() < 1e-6);
    assert!((c.distribution.at(&c.roughness, &sp).alpha_u - 50.0 / 255.0).abs() < 1e-6);
    let Bsdf::Blend(b) = first_bsdf(&s, 1) else {
        panic!()
    };
    let w = b.weight_texture.as_ref().expect("textured weight");
    let Texture::Checkerboard(cb) = w else {
        panic!()
    };
    assert!(cb.color0 == c.specular_reflectance);
    let Bsdf::RoughDielectric(rd) = &b.bsdfs[1] else {
        panic!()
    };
    let rt = rd.roughness.as_ref().unwrap();
    assert_eq!(rt.alpha_v.eval_1(&sp), 0.3);
    assert!(s.shapes[2].emission.as_ref().unwrap() == &c.specular_reflectance);
}

#[test]
fn texture_errors() {
    let img = png(2, 2, 1, &[0, 1, 2, 3]);
    let dir = write_files(
        "texerr",
        &[("g.png", &img), ("bad.png", b"\x89PNG garbage")],
    );
    let case = |body: &str, needle: &str| {
        expect_err(load_in(&dir, &scene_xml(body), &[]), needle);
    };
    let tex = |inner: &str| {
        format!(
            r#"<texture type="bitmap" name="reflectance"><string name="filename" value="g.png"/>{inner}</texture>"#
        )
    };
    case(
        &format!(
            r#"<shape type="sphere"><bsdf type="diffuse">{}</bsdf></shape>"#,
            tex(r#"<string name="filter_type" value="cubic"/>"#)
        ),
        "invalid filter type \"cubic\"",
    );
    case(
        &format!(
            r#"<shape type="sphere"><bsdf type="diffuse">{}</bsdf></shape>"#,
            tex(r#"<string name="wrap_mode" value="wrap"/>"#)
        ),
        "invalid wrap mode \"wrap\"",
    );
    case(
        r#"<shape type="sphere"><bsdf type="diffuse"><texture type="bitmap" name="reflectance"><string name="filename" value="nope.png"/></texture></bsdf></shape>"#,
        "nope.png",
    );
    case(
        r#"<shape type="sphere"><bsdf type="diffuse"><texture type="bitmap" name="reflectance"><string name="filename" value="bad.png"/></texture></bsdf></shape>"#,
        "cannot decode image",
    );
    case(
        r#"<shape type="sphere"><bsdf type="diffuse"><texture type="noise" name="reflectance"/></bsdf></shape>"#,
        "unsupported texture plugin type \"noise\"",
    );
    case(
        &format!(
            r#"<shape type="sphere"><bsdf type="dielectric">{}</bsdf></shape>"#,
            tex("").replace("reflectance", "int_ior")
        ),
        "unexpected nested <texture type=\"bitmap\">",
    );
    case(
        &format!(
            r#"<shape type="sphere"><bsdf type="roughplastic">{}</bsdf></shape>"#,
            tex("").replace("\"reflectance\"", "\"alpha\"")
        ),
        "the roughness must be a <float>",
    );
    case(
        r#"<shape type="sphere"><bsdf type="bumpmap"><texture type="checkerboard" name="h"/><bsdf type="diffuse"/></bsdf></shape>"#,
        "has no gradient",
    );
    case(
        r#"<shape type="sphere"><bsdf type="normalmap"><bsdf type="diffuse"/></bsdf></shape>"#,
        "\"normalmap\" (a texture) is required",
    );
    case(
        &format!(
            r#"<shape type="sphere"><bsdf type="normalmap">{}</bsdf></shape>"#,
            tex("").replace("\"reflectance\"", "\"normalmap\"")
        ),
        "exactly one BSDF child",
    );
    case(
        r#"<shape type="sphere"><bsdf type="diffuse"><bsdf type="diffuse" name="reflectance"/></bsdf></shape>"#,
        "expected <rgb>, <float> or <texture>",
    );
}

/// normalmap and bumpmap load with their nested model, options and texture.
#[test]
fn perturbing_adapters_load() {
    let img = png(
        2,
        2,
        3,
        &[128, 128, 255, 200, 128, 220, 128, 128, 255, 128, 60, 230],
    );
    let dir = write_files("perturb", &[("n.png", &img)]);
    let xml = scene_xml(
        r#"<shape type="sphere"><bsdf type="normalmap">
            <texture type="bitmap" name="normalmap"><string name="filename" value="n.png"/><boolean name="raw" value="true"/></texture>
            <boolean name="use_shadowing_function" value="false"/><bsdf type="diffuse"/></bsdf></shape>
        <shape type="sphere"><bsdf type="bumpmap">
            <texture type="bitmap" name="anything"><string name="filename" value="n.png"/><boolean name="raw" value="true"/></texture>
            <float name="scale" value="0.25"/><bsdf type="roughplastic"/></bsdf></shape>"#,
    );
    let s = load_in(&dir, &xml, &[]).unwrap();
    let Bsdf::NormalMap(n) = first_bsdf(&s, 0) else {
        panic!()
    };
    assert!(!n.options.use_shadowing_function && n.options.flip_invalid_normals);
    assert!(matches!(*n.nested, Bsdf::Diffuse(_)));
    let Bsdf::BumpMap(b) = first_bsdf(&s, 1) else {
        panic!()
    };
    assert_eq!(b.scale, 0.25);
    assert!(matches!(*b.nested, Bsdf::RoughPlastic(_)));
}

/// Issue #11: the whole scene translated far from the file's origin loads as the same render
/// space as the original, bit for bit (camera-relative coordinates, `Builder::to_world`):
/// only `world_origin` differs. Every coordinate below is a multiple of 2⁻⁷, so that the
/// translated file's values are exact in f64 and the two scenes are the same scene.
#[test]
fn translated_scene_loads_as_the_same_render_space() {
    let scene = |t: f64| {
        // Every x and z coordinate moves by t.
        let (x, z) = (|v: f64| v + t, |v: f64| v + t);
        let body = format!(
            r#"<sensor type="perspective"><transform name="to_world">
                <lookat origin="{}, 1.5, {}" target="{}, 0.25, {}" up="0, 1, 0"/></transform></sensor>
            <shape type="rectangle"><transform name="to_world"><scale x="0.75" y="1.25"/>
                <rotate x="1" angle="-37"/><translate x="{}" y="0.125" z="{}"/></transform>
                <emitter type="area"><rgb name="radiance" value="1"/></emitter></shape>
            <shape type="sphere"><point name="center" x="{}" y="0.5" z="{}"/><float name="radius" value="0.375"/></shape>
            <emitter type="point"><point name="position" x="{}" y="2" z="{}"/></emitter>
            <emitter type="spot"><transform name="to_world"><lookat origin="{}, 2, {}" target="{}, 0, {}"/></transform></emitter>"#,
            x(0.5),
            z(4.0),
            x(-0.25),
            z(0.0),
            x(-0.25),
            z(-0.5),
            x(0.5),
            z(-1.25),
            x(-0.25),
            z(0.5),
            x(0.5),
            z(1.0),
            x(-0.25),
            z(0.0),
        );
        load_ok("translated", &body)
    };
    let (a, b) = (scene(0.0), scene(1e5));
    assert_eq!(
        b.world_origin - a.world_origin,
        glam::DVec3::new(1e5, 0.0, 1e5)
    );
    assert_eq!(format!("{:?}", a.camera), format!("{:?}", b.camera));
    assert_eq!(format!("{:?}", a.emitters), format!("{:?}", b.emitters));
    assert_eq!(a.shapes.len(), b.shapes.len());
    for (sa, sb) in a.shapes.iter().zip(&b.shapes) {
        assert_eq!(format!("{:?}", sa.geometry), format!("{:?}", sb.geometry));
    }
    // The rendered bits (everything the fingerprint hashes but the origin) agree.
    let moved = SceneDescription {
        world_origin: a.world_origin,
        ..b.clone()
    };
    assert_eq!(a.fingerprint(), moved.fingerprint());
    assert_ne!(
        a.fingerprint(),
        b.fingerprint(),
        "the origin is part of the scene"
    );
}

// ---------------------------------------------------------------------------------------
// <include>

#[test]
fn loader_include_merges_scenes_and_objects() {
    // parts/shapes.xml: a <scene> root, its children join the including scene; it includes
    // red.xml from its own directory (parser.cpp resolves relative to the including file).
    let dir = write_files(
        "include",
        &[
            (
                "parts/shapes.xml",
                br#"<scene version="3.0.0">
    <bsdf type="diffuse" id="grey"><rgb name="reflectance" value="$grey"/></bsdf>
    <shape type="sphere"><float name="radius" value="2"/>
        <include filename="red.xml"/>
    </shape>
</scene>
"#,
            ),
            (
                "parts/red.xml",
                br#"<bsdf version="3.0.0" type="diffuse"><rgb name="reflectance" value="0.8, 0.1, 0.1"/></bsdf>
"#,
            ),
        ],
    );
    let s = load_in(
        &dir,
        &scene_xml(
            r#"<default name="grey" value="0.25"/>
            <include filename="parts/shapes.xml"/>
            <shape type="sphere"><ref id="grey"/></shape>"#,
        ),
        &[],
    )
    .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(s.shapes.len(), 2);
    assert_vec_close(
        diffuse_color(&s.shapes[0].bsdf),
        Vec3::new(0.8, 0.1, 0.1),
        1e-6,
        "included bsdf",
    );
    assert_vec_close(
        diffuse_color(&s.shapes[1].bsdf),
        Vec3::splat(0.25),
        1e-6,
        "id and $grey from the include",
    );
    assert!(
        s.shapes[0].origin.contains("shapes.xml:3"),
        "{}",
        s.shapes[0].origin
    );
}

#[test]
fn loader_include_errors_name_the_files() {
    // A missing file: the including file and line.
    let dir = temp_dir("include-missing");
    let e = expect_err(
        load_in(&dir, &scene_xml(r#"<include filename="nope.xml"/>"#), &[]),
        "included file \"nope.xml\" not found",
    );
    assert!(e.file.ends_with("scene.xml") && e.line == Some(4), "{e}");

    // A file that includes the file that includes it: the whole chain.
    let dir = write_files(
        "include-cycle",
        &[(
            "b.xml",
            br#"<scene version="3.0.0">
    <include filename="scene.xml"/>
</scene>
"#,
        )],
    );
    let e = expect_err(
        load_in(&dir, &scene_xml(r#"<include filename="b.xml"/>"#), &[]),
        "recursive <include>",
    );
    let shown = e.to_string();
    assert!(e.file.ends_with("b.xml") && e.line == Some(2), "{shown}");
    assert!(
        shown.contains("scene.xml:4 includes ") && shown.contains("b.xml:2 includes "),
        "{shown}"
    );

    // A mistake inside an included file: that file's line, and where it was included.
    let dir = write_files(
        "include-bad",
        &[(
            "bad.xml",
            br#"<scene version="3.0.0">
    <shape type="sphere"><float name="radius" value="one"/></shape>
</scene>
"#,
        )],
    );
    let e = expect_err(
        load_in(&dir, &scene_xml(r#"<include filename="bad.xml"/>"#), &[]),
        "could not parse floating point value",
    );
    assert!(e.file.ends_with("bad.xml") && e.line == Some(2), "{e}");
    assert!(e.to_string().contains("(included from "), "{e}");
    // ... and the errors found later, while building the scene, name the included file too.
    let dir = write_files(
        "include-bad-build",
        &[("bad.xml", br#"<bsdf version="3.0.0" type="no-such-bsdf"/>"#)],
    );
    let e = expect_err(
        load_in(
            &dir,
            &scene_xml(r#"<shape type="sphere"><include filename="bad.xml"/></shape>"#),
            &[],
        ),
        "no-such-bsdf",
    );
    assert!(e.file.ends_with("bad.xml"), "{e}");
    // The root of an included file needs its version, like any root.
    let dir = write_files(
        "include-no-version",
        &[("v.xml", br#"<bsdf type="diffuse"/>"#)],
    );
    expect_err(
        load_in(
            &dir,
            &scene_xml(r#"<shape type="sphere"><include filename="v.xml"/></shape>"#),
            &[],
        ),
        "missing required attribute \"version\"",
    );
}
