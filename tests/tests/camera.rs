//! Camera rays of a scene loaded from Mitsuba XML against hand-computed ones.
//!
//! The sensor below uses every `to_world` operation radia supports on sensors; its rays are
//! derived by hand from Mitsuba's conventions (`perspective.cpp`, `transform.h`): the camera
//! looks along local +z, image x runs towards local −x, image y downwards, and the origin
//! sits on the near plane. Render space is centred on the camera (the loader's
//! camera-relative coordinates), so ray origins are compared in the file's coordinates:
//! render-space origin + `world_origin`.

use glam::{Vec2, Vec3};
use radia_formats::load_mitsuba_xml;
use radia_scene::Scene;

/// The scene `body`, written to a temporary file (removed once read) and loaded.
fn load_scene(name: &str, body: &str) -> Scene {
    let dir = std::env::temp_dir().join(format!("radia-camera-test-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("scene.xml");
    std::fs::write(&path, body).unwrap();
    let loaded = load_mitsuba_xml(&path, &[]);
    let _ = std::fs::remove_dir_all(&dir);
    Scene::build(loaded.unwrap())
}

fn assert_close(a: Vec3, b: Vec3, what: &str) {
    assert!((a - b).length() < 2e-5, "{what}: {a} vs {b}");
}

#[test]
fn lookat_camera_rays_match_hand_computed() {
    // Camera at (1, 2, 3) looking at (1, 2, 0): dir = −z; left = up × dir = y × (−z) = −x;
    // up' = dir × left = (−z) × (−x) = +y. fov 90° along x on a 200×100 film:
    // tan(45°) = 1 horizontally, 0.5 vertically.
    let scene = load_scene(
        "lookat",
        r#"<scene version="3.0.0">
            <sensor type="perspective">
                <float name="fov" value="90"/>
                <float name="near_clip" value="0.5"/>
                <transform name="to_world">
                    <lookat origin="1, 2, 3" target="1, 2, 0" up="0, 1, 0"/>
                </transform>
                <film type="hdrfilm">
                    <integer name="width" value="200"/>
                    <integer name="height" value="100"/>
                    <rfilter type="box"/>
                </film>
            </sensor>
        </scene>"#,
    );
    let cam = &scene.camera;
    let eye = Vec3::new(1.0, 2.0, 3.0);
    assert_eq!(
        scene.world_origin.as_vec3(),
        eye,
        "render space is centred on the eye"
    );
    let file = |o: Vec3| o + scene.world_origin.as_vec3();

    // Centre of the film: straight ahead, starting on the near plane.
    let r = cam.generate_ray(Vec2::new(0.5, 0.5));
    assert_close(r.d, Vec3::new(0.0, 0.0, -1.0), "centre direction");
    assert_close(
        file(r.o),
        eye + Vec3::new(0.0, 0.0, -0.5),
        "centre origin on the near plane",
    );

    // Right edge of the image, middle row: local (−1, 0, 1) → world (+1, 0, −1)/√2.
    let r = cam.generate_ray(Vec2::new(1.0, 0.5));
    assert_close(r.d, Vec3::new(1.0, 0.0, -1.0).normalize(), "right edge");
    // The near plane is at local z = 0.5: t = 0.5 / cos 45°.
    assert_close(
        file(r.o),
        eye + r.d * (0.5 * 2f32.sqrt()),
        "right edge origin",
    );

    // Top-left corner: local (+1, +0.5, 1) → world (−1, 0.5, −1)/1.5.
    let r = cam.generate_ray(Vec2::new(0.0, 0.0));
    assert_close(r.d, Vec3::new(-1.0, 0.5, -1.0) / 1.5, "top-left corner");

    // Bottom row is below the horizon.
    let r = cam.generate_ray(Vec2::new(0.5, 1.0));
    assert_close(r.d, Vec3::new(0.0, -0.5, -1.0).normalize(), "bottom centre");
}

#[test]
fn composed_transform_and_fov_axis_y() {
    // rotate 90° about y then translate: M = T · R. Local +z (the view direction) goes to
    // R·z = (1, 0, 0)·sin + ... : rotating +z by 90° about +y gives +x.
    // fov 60° along y on a 100×50 film: tan_y = tan 30°, tan_x = 2 tan 30°.
    let scene = load_scene(
        "composed",
        r#"<scene version="3.0.0">
            <default name="fovy" value="60"/>
            <sensor type="perspective">
                <float name="fov" value="$fovy"/>
                <string name="fov_axis" value="y"/>
                <transform name="to_world">
                    <rotate y="1" angle="90"/>
                    <translate x="0" y="0" z="5"/>
                </transform>
                <film type="hdrfilm">
                    <integer name="width" value="100"/>
                    <integer name="height" value="50"/>
                    <rfilter type="box"/>
                </film>
            </sensor>
        </scene>"#,
    );
    let cam = &scene.camera;
    let r = cam.generate_ray(Vec2::new(0.5, 0.5));
    assert_close(r.d, Vec3::X, "view direction after rotation");
    assert_close(
        r.o + scene.world_origin.as_vec3(),
        Vec3::new(0.0, 0.0, 5.0) + Vec3::X * 0.01,
        "origin: translated eye + near clip",
    );
    // Top centre: local (0, tan 30°, 1); rotation about y keeps y.
    let t = 30f32.to_radians().tan();
    let r = cam.generate_ray(Vec2::new(0.5, 0.0));
    assert_close(r.d, Vec3::new(1.0, t, 0.0).normalize(), "top centre");
    // Right centre: local (−2t, 0, 1); R maps local x → −z (rotating +x by 90° about +y gives −z),
    // so local −x → +z.
    let r = cam.generate_ray(Vec2::new(1.0, 0.5));
    assert_close(
        r.d,
        Vec3::new(1.0, 0.0, 2.0 * t).normalize(),
        "right centre",
    );
}
