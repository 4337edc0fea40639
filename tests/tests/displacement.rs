//! Displacement mapping (radia's `displacement` on mesh shapes, `crates/formats/src/
//! mitsuba/displacement.rs`): a displaced plane and the same surface modelled directly as a mesh are
//! the same geometry and render the same.
//!
//! The displaced plane is Mitsuba's `rectangle`, subdivided 4 times (a 16 × 16 grid) and
//! moved along +z by a 16 × 16 raw 8-bit height image read with `nearest` filtering and
//! `clamp` wrapping, so the vertex at grid (i, j), uv = (i, j)/16, takes texel
//! (min(i, 15), min(j, 15)): a height this test computes without radia's texture code. The
//! direct model is an OBJ file of the 17 × 17 displaced vertices written by the test, with the
//! rectangle's triangulation (each cell cut along the same diagonal) and no normals. Both
//! shapes have the same non-uniformly scaling `to_world`: the displacement is in object
//! space, before it.

use radia_formats::load_mitsuba_xml;
use radia_render::Image;
use radia_sampling::SamplerKind;
use radia_scene::{Geometry, Mesh, Scene, SceneDescription};
use radia_tests::render_with;
use std::collections::HashMap;
use std::path::{Path, PathBuf};

const N: usize = 16;
const SCALE: f32 = 0.3;

fn temp_dir(name: &str) -> PathBuf {
    let dir =
        std::env::temp_dir().join(format!("radia-displacement-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// The height image's bytes, row j at v = j/16: smooth bumps over the whole byte range.
fn texels() -> Vec<u8> {
    let mut t = Vec::with_capacity(N * N);
    for j in 0..N {
        for i in 0..N {
            let h = 0.5 + 0.5 * ((i as f64 * 0.8).sin() * (j as f64 * 0.6 + 0.3).cos());
            t.push((h * 255.0).round() as u8);
        }
    }
    t
}

/// The OBJ of the displaced grid: vertex (i, j) at (−1 + i/8, −1 + j/8, scale·texel/255) with
/// uv (i, j)/16, cells split along the diagonal from (i + 1, j) to (i, j + 1) as the
/// rectangle's two triangles are.
fn direct_obj(scale: f32) -> String {
    let t = texels();
    let mut s = String::new();
    for j in 0..=N {
        for i in 0..=N {
            let k = t[j.min(N - 1) * N + i.min(N - 1)];
            // As a raw 8-bit texel decodes (byte/255), times the scale.
            let z = scale * (k as f32 / 255.0) + 0.0;
            let (x, y) = (-1.0 + i as f32 / 8.0, -1.0 + j as f32 / 8.0);
            // `{}` prints the shortest decimal that reads back as the same f32.
            s += &format!(
                "v {x} {y} {z}\nvt {} {}\n",
                i as f32 / 16.0,
                j as f32 / 16.0
            );
        }
    }
    let v = |i: usize, j: usize| j * (N + 1) + i + 1;
    for j in 0..N {
        for i in 0..N {
            let (a, b, c, d) = (v(i, j), v(i + 1, j), v(i, j + 1), v(i + 1, j + 1));
            s += &format!("f {b}/{b} {c}/{c} {a}/{a}\nf {b}/{b} {d}/{d} {c}/{c}\n");
        }
    }
    s
}

/// A scene around `shape`: a camera looking down at the plane at 45°, a point light low on
/// one side (so the bumps cast shadows) and a dim environment.
fn scene_xml(shape: &str) -> String {
    format!(
        r#"<scene version="3.0.0">
    <integrator type="path"><integer name="max_depth" value="4"/></integrator>
    <sensor type="perspective">
        <float name="fov" value="50"/>
        <transform name="to_world"><lookat origin="0, -2.6, 2.4" target="0, 0, 0.1" up="0, 0, 1"/></transform>
        <sampler type="independent"><integer name="sample_count" value="8"/></sampler>
        <film type="hdrfilm"><integer name="width" value="64"/><integer name="height" value="64"/>
            <rfilter type="box"/></film>
    </sensor>
    <emitter type="constant"><rgb name="radiance" value="0.2"/></emitter>
    <emitter type="point"><point name="position" x="2.5" y="0.5" z="1.2"/><rgb name="intensity" value="8"/></emitter>
    {shape}
</scene>"#
    )
}

fn displaced_shape(scale: f32) -> String {
    format!(
        r#"<shape type="rectangle">
        <texture type="bitmap" name="displacement">
            <string name="filename" value="height.png"/>
            <boolean name="raw" value="true"/>
            <string name="filter_type" value="nearest"/>
            <string name="wrap_mode" value="clamp"/>
        </texture>
        <float name="displacement_scale" value="{scale}"/>
        <integer name="subdivisions" value="4"/>
        <transform name="to_world"><scale x="1.2" y="0.9" z="1.5"/><rotate z="1" angle="20"/></transform>
        <bsdf type="diffuse"><rgb name="reflectance" value="0.7"/></bsdf>
    </shape>"#
    )
}

const DIRECT_SHAPE: &str = r#"<shape type="obj">
        <string name="filename" value="direct.obj"/>
        <boolean name="flip_tex_coords" value="false"/>
        <transform name="to_world"><scale x="1.2" y="0.9" z="1.5"/><rotate z="1" angle="20"/></transform>
        <bsdf type="diffuse"><rgb name="reflectance" value="0.7"/></bsdf>
    </shape>"#;

/// Writes the height image, the direct OBJ and the two scenes; returns their paths.
fn write_pair(dir: &Path, displaced_scale: f32) -> (PathBuf, PathBuf) {
    image::GrayImage::from_raw(N as u32, N as u32, texels())
        .unwrap()
        .save(dir.join("height.png"))
        .unwrap();
    std::fs::write(dir.join("direct.obj"), direct_obj(SCALE)).unwrap();
    let displaced = dir.join("displaced.xml");
    std::fs::write(&displaced, scene_xml(&displaced_shape(displaced_scale))).unwrap();
    let direct = dir.join("direct.xml");
    std::fs::write(&direct, scene_xml(DIRECT_SHAPE)).unwrap();
    (displaced, direct)
}

fn mesh(desc: &SceneDescription) -> &Mesh {
    match &desc.shapes[0].geometry {
        Geometry::Mesh(m) => m,
        _ => panic!("not a mesh"),
    }
}

/// The triangles as (position, uv) bit patterns, each rotated to start at its smallest
/// corner (winding kept), sorted: equal lists are the same triangles, bit for bit.
fn triangle_set(m: &Mesh) -> Vec<[[u32; 5]; 3]> {
    let uvs = m.uvs.as_ref().expect("uvs");
    let corner = |i: u32| {
        let (p, uv) = (m.positions[i as usize], uvs[i as usize]);
        [p.x, p.y, p.z, uv.x, uv.y].map(f32::to_bits)
    };
    let mut tris: Vec<[[u32; 5]; 3]> = m
        .indices
        .iter()
        .map(|t| {
            let c = t.map(corner);
            let first = (0..3).min_by_key(|&k| c[k]).unwrap();
            [c[first], c[(first + 1) % 3], c[(first + 2) % 3]]
        })
        .collect();
    tris.sort();
    tris
}

fn render_image(path: &Path) -> Image {
    let scene = Scene::build(load_mitsuba_xml(path, &[]).unwrap());
    let out = render_with(&scene, 8, SamplerKind::Independent);
    assert_eq!(
        out.stats.invalid_samples,
        0,
        "{}: NaN or Inf samples",
        path.display()
    );
    out.image
}

/// Mean |a − b| over every pixel and channel, relative to the mean of a.
fn relative_difference(a: &Image, b: &Image) -> f64 {
    let (mut diff, mut sum) = (0.0, 0.0);
    for (p, q) in a.pixels.iter().zip(&b.pixels) {
        diff += (*p - *q).abs().element_sum() as f64;
        sum += p.element_sum() as f64;
    }
    diff / sum
}

#[test]
fn a_displaced_plane_is_the_directly_modelled_mesh() {
    let dir = temp_dir("geometry");
    let (displaced, direct) = write_pair(&dir, SCALE);
    let a = load_mitsuba_xml(&displaced, &[]).unwrap();
    let b = load_mitsuba_xml(&direct, &[]).unwrap();
    let (ma, mb) = (mesh(&a), mesh(&b));
    assert_eq!(ma.indices.len(), 2 * N * N);
    assert_eq!(
        triangle_set(ma),
        triangle_set(mb),
        "not the same triangles, bit for bit"
    );
    // Both get recomputed (angle-weighted) normals: the same up to the summation order.
    let (na, nb) = (
        ma.normals.as_ref().expect("smooth"),
        mb.normals.as_ref().expect("smooth"),
    );
    let by_position: HashMap<[u32; 3], glam::Vec3> = mb
        .positions
        .iter()
        .zip(nb)
        .map(|(p, n)| (p.to_array().map(f32::to_bits), *n))
        .collect();
    for (p, n) in ma.positions.iter().zip(na) {
        let m = by_position[&p.to_array().map(f32::to_bits)];
        assert!(
            (*n - m).length() < 1e-6,
            "normal at {p}: {n} displaced, {m} direct"
        );
    }
    // The surface is not flat (the test would prove nothing on a plane).
    let zs: Vec<f32> = ma.positions.iter().map(|p| p.z).collect();
    let (lo, hi) = zs
        .iter()
        .fold((f32::MAX, f32::MIN), |(l, h), &z| (l.min(z), h.max(z)));
    assert!(hi - lo > 0.25, "heights {lo}..{hi}");
    let _ = std::fs::remove_dir_all(dir);
}

#[test]
fn a_displaced_plane_renders_as_the_directly_modelled_mesh() {
    let dir = temp_dir("render");
    let (displaced, direct) = write_pair(&dir, SCALE);
    let (a, b) = (render_image(&displaced), render_image(&direct));
    let same = relative_difference(&a, &b);
    // The same seed and sampler on the same surface: the same paths, up to rounding in the
    // normals and in hit points on differently ordered triangles.
    // A 3% taller displacement, as a control, is far outside that bound.
    let (taller, _) = write_pair(&dir, SCALE * 1.03);
    let c = render_image(&taller);
    let other = relative_difference(&c, &b);
    eprintln!("relative difference: same surface {same:.3e}, 3% taller {other:.3e}");
    // Measured (seed 3): 9.8e-9 and 1.1e-2.
    assert!(
        same < 1e-6,
        "the displaced plane renders differently: {same:.3e}"
    );
    assert!(other > 1e-3, "the control is not told apart: {other:.3e}");
    let _ = std::fs::remove_dir_all(dir);
}

/// Bad modifier parameters are load errors naming the file and the shape's line.
#[test]
fn bad_displacement_parameters_are_refused_naming_file_and_line() {
    let dir = temp_dir("errors");
    write_pair(&dir, SCALE);
    std::fs::write(
        dir.join("no-uv.obj"),
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
    )
    .unwrap();
    // (shape, line of the error in the scene, message): the shape starts on line 12.
    let cases = [
        (displaced_shape(SCALE).replace(r#"value="4""#, r#"value="-1""#), 20, "parameter \"subdivisions\": value -1 is out of bounds"),
        (
            displaced_shape(SCALE).replace(r#"value="4""#, r#"value="13""#),
            12,
            "\"rectangle\": 13 subdivision level(s) of 2 triangles would make 134217728 triangles, more than the limit of 67108864",
        ),
        (displaced_shape(SCALE).replace("0.3", "nan"), 19, "parameter \"displacement_scale\": NaN is not a finite number"),
        (displaced_shape(SCALE).replace("0.3", "1e39"), 19, "parameter \"displacement_scale\": 1e39 is not a finite number"),
        (
            r#"<shape type="obj"><string name="filename" value="no-uv.obj"/>
        <texture type="checkerboard" name="displacement"/></shape>"#
                .to_string(),
            12,
            "\"no-uv.obj\": a displacement texture needs texture coordinates, and the mesh has none",
        ),
        (
            r#"<shape type="cube"><float name="displacement_scale" value="2"/></shape>"#.to_string(),
            12,
            "given without a \"displacement\" texture or value",
        ),
        (r#"<shape type="sphere"><integer name="subdivisions" value="2"/></shape>"#.to_string(), 12, "subdivisions"),
    ];
    for (k, (shape, line, expected)) in cases.iter().enumerate() {
        let path = dir.join(format!("bad-{k}.xml"));
        std::fs::write(&path, scene_xml(shape)).unwrap();
        let e = load_mitsuba_xml(&path, &[])
            .err()
            .unwrap_or_else(|| panic!("case {k} loaded"))
            .to_string();
        assert!(e.contains(&format!("bad-{k}.xml:{line}:")), "case {k}: {e}");
        assert!(e.contains(expected), "case {k}: {e}");
    }
    let _ = std::fs::remove_dir_all(dir);
}
