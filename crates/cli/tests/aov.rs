//! AOVs end to end: `radia render --aov LIST` and the scene's `aov` integrator write the
//! AOV channels under Mitsuba's names beside an unchanged image; split renders and PNG
//! output are refused with a clear error rather than dropping the AOVs.
//! (Parity of the values with Mitsuba: validation/compare_aov.py.)

mod common;

use common::{assert_clean_failure, assert_success, temp_dir, write_scene};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Output;

/// A unit sphere at the origin seen from z = −4 along +z, 25×17 pixels, box filter.
fn scene(integrator: &str) -> String {
    format!(
        r#"<scene version="3.0.0">
    {integrator}
    <sensor type="perspective">
        <float name="fov" value="40"/>
        <transform name="to_world"><lookat origin="0, 0, -4" target="0, 0, 0" up="0, 1, 0"/></transform>
        <sampler type="independent"><integer name="sample_count" value="16"/></sampler>
        <film type="hdrfilm">
            <integer name="width" value="25"/><integer name="height" value="17"/>
            <rfilter type="box"/>
        </film>
    </sensor>
    <shape type="sphere"><bsdf type="diffuse"><rgb name="reflectance" value="0.2, 0.4, 0.6"/></bsdf></shape>
    <emitter type="constant"><rgb name="radiance" value="0.5"/></emitter>
</scene>"#
    )
}

/// Every channel of an EXR by name, row-major f32.
fn channels(path: &Path) -> BTreeMap<String, Vec<f32>> {
    use exr::prelude::*;
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .all_layers()
        .all_attributes()
        .from_file(path)
        .expect("an EXR radia wrote");
    let mut out = BTreeMap::new();
    for layer in &image.layer_data {
        for ch in &layer.channel_data.list {
            out.insert(
                ch.name.to_string(),
                ch.sample_data.values_as_f32().collect(),
            );
        }
    }
    out
}

/// Renders `xml` (written into `dir`) to `dir/out` with `extra` arguments.
fn render(dir: &Path, xml: &str, out: &str, extra: &[&str]) -> (Output, PathBuf) {
    let out_path = dir.join(out);
    (
        common::render(&write_scene(dir, xml), &out_path, extra),
        out_path,
    )
}

#[test]
fn aov_flag_adds_mitsuba_named_channels_and_leaves_the_image_alone() {
    let dir = temp_dir("aov-flag");
    let xml = scene("");
    let (plain, plain_path) = render(&dir, &xml, "plain.exr", &[]);
    assert_success(&plain);
    let (out, path) = render(
        &dir,
        &xml,
        "aov.exr",
        &["--aov", "dd.y:depth,nn:sh_normal,a:albedo,s:shape_index"],
    );
    assert_success(&out);
    let ch = channels(&path);
    let names: Vec<&str> = ch.keys().map(String::as_str).collect();
    assert_eq!(
        names,
        ["B", "G", "R", "a.B", "a.G", "a.R", "dd.y.T", "nn.X", "nn.Y", "nn.Z", "s.I"]
    );
    let plain = channels(&plain_path);
    for c in ["R", "G", "B"] {
        assert_eq!(ch[c], plain[c], "the AOVs changed the image's {c}");
    }
    // The centre pixel sees the sphere's pole facing the camera: distance 3 from the
    // pinhole less the near clip (0.01: rays start on the near plane, as Mitsuba's).
    let centre = 8 * 25 + 12;
    assert!(
        (ch["dd.y.T"][centre] - 2.99).abs() < 2e-3,
        "{}",
        ch["dd.y.T"][centre]
    );
    assert!((ch["nn.Z"][centre] + 1.0).abs() < 1e-3);
    assert!((ch["a.G"][centre] - 0.4).abs() < 1e-6);
    assert_eq!(ch["s.I"][centre], 1.0);
    // A corner pixel sees the environment only: every AOV is 0 there.
    for c in ["dd.y.T", "nn.Z", "a.R", "s.I"] {
        assert_eq!(ch[c][0], 0.0, "{c}");
    }
}

#[test]
fn aov_integrator_writes_the_nested_image_as_its_layer() {
    let dir = temp_dir("aov-xml");
    let xml = scene(
        r#"<integrator type="aov"><string name="aovs" value="p:position"/>
               <integrator type="path" name="my_image"><integer name="max_depth" value="3"/></integrator>
           </integrator>"#,
    );
    let (out, path) = render(&dir, &xml, "aov.exr", &[]);
    assert_success(&out);
    let ch = channels(&path);
    let names: Vec<&str> = ch.keys().map(String::as_str).collect();
    assert_eq!(
        names,
        [
            "B",
            "G",
            "R",
            "my_image.A",
            "my_image.B",
            "my_image.G",
            "my_image.R",
            "p.X",
            "p.Y",
            "p.Z"
        ]
    );
    assert_eq!(ch["R"], ch["my_image.R"]);
    // The image is the nested path integrator's.
    let path_xml =
        scene(r#"<integrator type="path"><integer name="max_depth" value="3"/></integrator>"#);
    let (plain, plain_path) = render(&dir, &path_xml, "plain.exr", &[]);
    assert!(plain.status.success());
    assert_eq!(channels(&plain_path)["G"], ch["G"]);
    // Alpha is 1 everywhere: the constant environment is visible where the sphere is not.
    assert!(ch["my_image.A"].iter().all(|&a| a == 1.0));
}

#[test]
fn aovs_refuse_split_renders_and_png() {
    let dir = temp_dir("aov-refuse");
    let xml = scene("");
    for (out_name, extra, needle) in [
        (
            "a.exr",
            vec!["--aov", "d:depth", "--samples", "0..8"],
            "split renders do not carry aovs",
        ),
        ("a.png", vec!["--aov", "d:depth"], "need an openexr output"),
        (
            "b.exr",
            vec!["--aov", "d:deepth"],
            "invalid aov type \"deepth\"",
        ),
    ] {
        let (out, path) = render(&dir, &xml, out_name, &extra);
        let stderr = assert_clean_failure(&out, &format!("{extra:?}")).to_lowercase();
        assert!(stderr.contains(needle), "{extra:?}: {stderr}");
        assert!(!path.exists());
    }
}
