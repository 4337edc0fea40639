//! Emitter plugins from Mitsuba XML: parameters, defaults, errors, and the envmap's image
//! formats (OpenEXR and Radiance RGBE linear, PNG sRGB-decoded).

use glam::{Affine3A, Vec3};
use radia_formats::load_mitsuba_xml;
use radia_scene::{Emitter, EmitterDesc, RgbImage, Scene, SceneDescription};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

fn temp_dir(name: &str) -> PathBuf {
    static N: AtomicUsize = AtomicUsize::new(0);
    let dir = std::env::temp_dir().join(format!(
        "radia-emitters-{}-{name}-{}",
        std::process::id(),
        N.fetch_add(1, Ordering::Relaxed)
    ));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn load_in(dir: &Path, body: &str) -> Result<SceneDescription, String> {
    let xml = format!(
        r#"<scene version="3.0.0"><sensor type="perspective"><film type="hdrfilm">
        <integer name="width" value="8"/><integer name="height" value="8"/></film></sensor>
        {body}</scene>"#
    );
    let path = dir.join("scene.xml");
    std::fs::write(&path, xml).unwrap();
    let r = load_mitsuba_xml(&path, &[]).map_err(|e| e.to_string());
    let _ = std::fs::remove_dir_all(dir);
    r
}

fn load(body: &str) -> Result<SceneDescription, String> {
    load_in(&temp_dir("xml"), body)
}

fn close(a: Vec3, b: Vec3, tol: f32) -> bool {
    (a - b).abs().max_element() <= tol
}

#[test]
fn point_spot_directional_constant() {
    let s = load(
        r#"<emitter type="point"><point name="position" x="1" y="2" z="3"/>
               <rgb name="intensity" value="4, 5, 6"/></emitter>
           <emitter type="point"><transform name="to_world"><translate x="-1"/></transform></emitter>
           <emitter type="spot"><float name="cutoff_angle" value="40"/>
               <transform name="to_world"><lookat origin="0,3,0" target="0,0,0" up="0,0,1"/></transform></emitter>
           <emitter type="spot"><float name="falloff_exponent" value="12"/></emitter>
           <emitter type="directional"><vector name="direction" x="0" y="-2" z="0"/>
               <float name="irradiance" value="3"/></emitter>
           <emitter type="directional"><transform name="to_world"><rotate x="1" angle="90"/></transform></emitter>
           <emitter type="constant"><rgb name="radiance" value="0.5"/></emitter>"#,
    )
    .unwrap();
    let e = &s.emitters;
    assert_eq!(e.len(), 7);
    assert_eq!(
        e[0],
        EmitterDesc::Point {
            position: Vec3::new(1.0, 2.0, 3.0),
            intensity: Vec3::new(4.0, 5.0, 6.0)
        }
    );
    assert_eq!(
        e[1],
        EmitterDesc::Point {
            position: Vec3::new(-1.0, 0.0, 0.0),
            intensity: Vec3::ONE
        }
    );
    match &e[2] {
        EmitterDesc::Spot {
            to_world,
            intensity,
            cutoff_angle,
            beam_width,
            falloff_exponent,
        } => {
            // Mitsuba's defaults: intensity 1, beam_width ¾ of the cutoff.
            assert_eq!(
                (*intensity, *cutoff_angle, *beam_width),
                (Vec3::ONE, 40.0, 30.0)
            );
            assert_eq!(*falloff_exponent, None);
            assert!(close(to_world.transform_vector3(Vec3::Z), -Vec3::Y, 1e-6));
            assert!(close(
                to_world.translation.into(),
                Vec3::new(0.0, 3.0, 0.0),
                1e-6
            ));
        }
        other => panic!("{other:?}"),
    }
    match &e[3] {
        EmitterDesc::Spot {
            cutoff_angle,
            beam_width,
            falloff_exponent,
            ..
        } => assert_eq!(
            (*cutoff_angle, *beam_width, *falloff_exponent),
            (20.0, 15.0, Some(12.0))
        ),
        other => panic!("{other:?}"),
    }
    assert_eq!(
        e[4],
        EmitterDesc::Directional {
            direction: -Vec3::Y,
            irradiance: Vec3::splat(3.0)
        }
    );
    match &e[5] {
        // +z rotated 90° about x is −y.
        EmitterDesc::Directional { direction, .. } => assert!(close(*direction, -Vec3::Y, 1e-6)),
        other => panic!("{other:?}"),
    }
    assert_eq!(
        e[6],
        EmitterDesc::Constant {
            radiance: Vec3::splat(0.5)
        }
    );
    let scene = Scene::build(s);
    assert_eq!(scene.environment, Some(6));
    assert_eq!(scene.lights.len(), 7);
    assert!(matches!(scene.emitters[2], Emitter::Spot(_)));
}

#[test]
fn emitter_errors() {
    for (body, needle) in [
        (
            r#"<emitter type="point"><point name="position" x="1" y="2" z="3"/>
               <transform name="to_world"><translate x="1"/></transform></emitter>"#,
            "only one of the parameters 'position' and 'to_world'",
        ),
        (
            r#"<emitter type="directional"><vector name="direction" x="0" y="0" z="0"/></emitter>"#,
            "must not be zero",
        ),
        (
            r#"<emitter type="constant"/><emitter type="constant"/>"#,
            "only one environment emitter",
        ),
        (
            r#"<emitter type="spot"><float name="falloff_exponent" value="-1"/></emitter>"#,
            "falloff_exponent",
        ),
        (
            r#"<emitter type="point"><float name="radiance" value="1"/></emitter>"#,
            "unexpected parameter \"radiance\"",
        ),
        (
            r#"<emitter type="envmap"/>"#,
            "\"filename\" parameter is required",
        ),
        (
            r#"<emitter type="envmap"><string name="filename" value="missing.exr"/></emitter>"#,
            "missing.exr",
        ),
    ] {
        match load(body) {
            Ok(_) => panic!("{body}: loaded, expected an error containing {needle:?}"),
            Err(e) => assert!(
                e.contains(needle),
                "{body}: {e:?} does not contain {needle:?}"
            ),
        }
    }
}

/// The envmap of a scene whose only emitter is `envmap` with `params` on `file`.
fn envmap_of(dir: &Path, file: &str, params: &str) -> Result<(RgbImage, f32, Affine3A), String> {
    let s = load_in(
        dir,
        &format!(
            r#"<emitter type="envmap"><string name="filename" value="{file}"/>{params}</emitter>"#
        ),
    )?;
    match s.emitters.into_iter().next() {
        Some(EmitterDesc::Envmap {
            image,
            scale,
            to_world,
            ..
        }) => Ok((image, scale, to_world)),
        other => panic!("{other:?}"),
    }
}

#[test]
fn envmap_reads_exr_hdr_png() {
    let (w, h) = (5usize, 3usize);
    let value = |x: usize, y: usize| {
        Vec3::new(
            x as f32 * 0.5 + 0.25,
            y as f32 * 2.0 + 1.0,
            1e3 * (x + 1) as f32,
        )
    };

    // OpenEXR, float32: read exactly.
    let dir = temp_dir("exr");
    {
        use exr::prelude::*;
        let channels = SpecificChannels::rgb(|Vec2(x, y): Vec2<usize>| {
            let v = value(x, y);
            (v.x, v.y, v.z)
        });
        Image::from_channels((w, h), channels)
            .write()
            .to_file(dir.join("sky.exr"))
            .unwrap();
    }
    let (img, scale, to_world) = envmap_of(
        &dir,
        "sky.exr",
        r#"<float name="scale" value="2"/><transform name="to_world"><rotate y="1" angle="30"/></transform>"#,
    )
    .unwrap();
    assert_eq!((img.width, img.height, scale), (w as u32, h as u32, 2.0));
    for y in 0..h {
        for x in 0..w {
            assert_eq!(img.pixels[y * w + x], value(x, y), "({x}, {y})");
        }
    }
    assert!(close(
        to_world.transform_vector3(Vec3::Z),
        Vec3::new(0.5, 0.0, 3f32.sqrt() / 2.0),
        1e-6
    ));

    // Radiance RGBE: 8-bit mantissas with a shared exponent, within 1% of the largest
    // component.
    let dir = temp_dir("hdr");
    {
        let pixels: Vec<image::Rgb<f32>> = (0..w * h)
            .map(|i| {
                let v = value(i % w, i / w);
                image::Rgb([v.x, v.y, v.z])
            })
            .collect();
        let f = std::fs::File::create(dir.join("sky.hdr")).unwrap();
        image::codecs::hdr::HdrEncoder::new(f)
            .encode(&pixels, w, h)
            .unwrap();
    }
    let (img, _, _) = envmap_of(&dir, "sky.hdr", "").unwrap();
    for y in 0..h {
        for x in 0..w {
            let (a, b) = (img.pixels[y * w + x], value(x, y));
            assert!(
                close(a, b, 0.01 * b.max_element()),
                "({x}, {y}): {a} vs {b}"
            );
        }
    }

    // PNG, 8-bit sRGB: decoded with the sRGB curve, grey expanded to RGB.
    let dir = temp_dir("png");
    let bytes: Vec<u8> = (0..w * h * 3).map(|i| (i * 17 % 256) as u8).collect();
    image::save_buffer(
        dir.join("sky.png"),
        &bytes,
        w as u32,
        h as u32,
        image::ColorType::Rgb8,
    )
    .unwrap();
    let (img, _, _) = envmap_of(&dir, "sky.png", "").unwrap();
    let srgb = |b: u8| {
        let c = b as f32 / 255.0;
        if c <= 0.04045 {
            c / 12.92
        } else {
            ((c + 0.055) / 1.055).powf(2.4)
        }
    };
    for i in 0..w * h {
        let expect = Vec3::new(
            srgb(bytes[3 * i]),
            srgb(bytes[3 * i + 1]),
            srgb(bytes[3 * i + 2]),
        );
        assert!(close(img.pixels[i], expect, 1e-6), "pixel {i}");
    }
    let dir = temp_dir("grey");
    image::save_buffer(
        dir.join("g.png"),
        &[0, 128, 255, 64],
        2,
        2,
        image::ColorType::L8,
    )
    .unwrap();
    let (img, _, _) = envmap_of(&dir, "g.png", "").unwrap();
    assert!(close(img.pixels[1], Vec3::splat(srgb(128)), 1e-6));

    // Not an image; a to_world that is not a rotation.
    let dir = temp_dir("bad");
    std::fs::write(dir.join("sky.txt"), "hello").unwrap();
    let e = envmap_of(&dir, "sky.txt", "").unwrap_err();
    assert!(e.contains("unsupported image format"), "{e}");
    let dir = temp_dir("scaled");
    image::save_buffer(
        dir.join("g.png"),
        &[0, 128, 255, 64],
        2,
        2,
        image::ColorType::L8,
    )
    .unwrap();
    let e = envmap_of(
        &dir,
        "g.png",
        r#"<transform name="to_world"><scale value="2"/></transform>"#,
    )
    .unwrap_err();
    assert!(e.contains("rotations only"), "{e}");
}
