//! The scene fingerprint (`SceneDescription::fingerprint`, which split renders check
//! before merging) of scenes read from Mitsuba XML: the same content under another path
//! agrees, any change of content disagrees.

use radia_formats::load_mitsuba_xml_with_warnings;
use radia_scene::SceneDescription;

fn load(xml: &str, name: &str) -> SceneDescription {
    let dir = std::env::temp_dir().join(format!("radia-fingerprint-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(name);
    std::fs::write(&path, xml).unwrap();
    let loaded = load_mitsuba_xml_with_warnings(&path, &[]);
    let _ = std::fs::remove_dir_all(&dir);
    loaded.unwrap().0
}

const SCENE: &str = r#"<scene version="3.0.0">
    <default name="r" value="1"/>
    <sensor type="perspective"><film type="hdrfilm"><integer name="width" value="8"/>
    <integer name="height" value="8"/></film></sensor>
    <shape type="sphere"><float name="radius" value="$r"/></shape>
    <emitter type="constant"/>
</scene>"#;

#[test]
fn same_content_under_another_path_agrees() {
    let a = load(SCENE, "a.xml");
    let b = load(&format!("\n\n{SCENE}"), "b.xml");
    assert_eq!(a.fingerprint(), b.fingerprint());
}

#[test]
fn any_change_of_content_disagrees() {
    let a = load(SCENE, "c.xml");
    let b = load(
        &SCENE.replace(r#"value="1"/>"#, r#"value="1.01"/>"#),
        "d.xml",
    );
    assert_ne!(a.fingerprint(), b.fingerprint());
    let mut c = a.clone();
    c.film.width = 9;
    assert_ne!(a.fingerprint(), c.fingerprint());
    let mut d = a.clone();
    d.integrator.max_depth = 3;
    assert_ne!(a.fingerprint(), d.fingerprint());
}
