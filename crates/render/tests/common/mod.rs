//! Set-up shared by the render crate's integration tests: a scene from XML text, rendered.

#![allow(dead_code)] // each test binary uses its own part

use radia_formats::load_mitsuba_xml;
use radia_render::{render, RenderOptions, RenderOutput};
use radia_sampling::SamplerKind;
use radia_scene::Scene;
use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;

/// Writes `xml` as `scene.xml` in a fresh temporary folder named after `name` (so the
/// tests of one binary, running at once, do not share files); the folder goes when the
/// returned file does.
pub fn write_scene(name: &str, xml: &str) -> SceneFile {
    let dir = std::env::temp_dir().join(format!("radia-render-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("scene.xml");
    std::fs::write(&path, xml).unwrap();
    SceneFile { dir, path }
}

/// A scene file in a temporary folder of its own, deleted with the folder when dropped (so
/// the tests' files do not pile up in /tmp).
pub struct SceneFile {
    dir: PathBuf,
    path: PathBuf,
}

impl std::ops::Deref for SceneFile {
    type Target = Path;
    fn deref(&self) -> &Path {
        &self.path
    }
}

impl Drop for SceneFile {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.dir);
    }
}

/// Loads `xml` and renders it with the independent sampler at `spp` and `seed`.
pub fn render_xml(name: &str, xml: &str, spp: u32, seed: u64) -> RenderOutput {
    let path = write_scene(name, xml);
    let scene = Scene::build(load_mitsuba_xml(&path, &[]).unwrap_or_else(|e| panic!("{e}")));
    let options = RenderOptions {
        spp,
        seed,
        sampler: SamplerKind::Independent,
        adaptive: false,
    };
    render(&scene, &options, &AtomicBool::new(false), &|_| {})
}

/// A perspective sensor at `origin` looking at `target` (y up), `fov` degrees, a `w`×`h`
/// film with a box filter (every sample lands in its own pixel).
pub fn sensor(origin: &str, target: &str, fov: f32, w: u32, h: u32) -> String {
    format!(
        r#"<sensor type="perspective"><float name="fov" value="{fov}"/>
        <transform name="to_world"><lookat origin="{origin}" target="{target}" up="0, 1, 0"/></transform>
        <film type="hdrfilm"><integer name="width" value="{w}"/><integer name="height" value="{h}"/>
            <rfilter type="box"/></film></sensor>"#
    )
}

/// The developed AOV channel `name` (such as `s.I`) of a render.
pub fn aov_plane<'a>(out: &'a RenderOutput, name: &str) -> &'a [f32] {
    let aovs = out.aovs.as_ref().expect("the render has AOVs");
    let i = aovs.names.iter().position(|n| n == name);
    &aovs.planes[i.unwrap_or_else(|| panic!("no AOV channel {name} in {:?}", aovs.names))]
}
