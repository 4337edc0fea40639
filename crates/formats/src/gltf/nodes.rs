//! The node hierarchy of the scene, flattened into instances with world transforms
//! (specification §3.5: a node's global transform is its parent's times its local one;
//! `matrix`, or translation · rotation · scale).

use glam::DMat4;

/// A mesh placed in the world.
pub(crate) struct MeshInstance<'a> {
    pub mesh: gltf::Mesh<'a>,
    pub node: usize,
    pub to_world: DMat4,
}

/// A camera placed in the world.
pub(crate) struct CameraInstance<'a> {
    pub camera: gltf::Camera<'a>,
    pub node: usize,
    pub to_world: DMat4,
}

/// A `KHR_lights_punctual` light placed in the world.
pub(crate) struct LightInstance<'a> {
    pub light: gltf::khr_lights_punctual::Light<'a>,
    pub node: usize,
    pub to_world: DMat4,
}

#[derive(Default)]
pub(crate) struct Instances<'a> {
    pub meshes: Vec<MeshInstance<'a>>,
    /// In the order of the nodes (depth first, children in order).
    pub cameras: Vec<CameraInstance<'a>>,
    pub lights: Vec<LightInstance<'a>>,
}

/// Walks the default scene (`scene`, else `scenes[0]`, else every root node) depth first.
pub(crate) fn flatten<'a>(
    doc: &'a gltf::Document,
    warn: &mut dyn FnMut(String),
) -> Result<Instances<'a>, String> {
    let roots: Vec<gltf::Node<'a>> = match doc.default_scene().or_else(|| doc.scenes().next()) {
        Some(scene) => scene.nodes().collect(),
        None => {
            // No scene: every node that is nobody's child.
            let mut is_child = vec![false; doc.nodes().len()];
            for n in doc.nodes() {
                for c in n.children() {
                    is_child[c.index()] = true;
                }
            }
            doc.nodes().filter(|n| !is_child[n.index()]).collect()
        }
    };
    if doc.scenes().len() > 1 {
        warn(format!(
            "the file has {} scenes; radia renders the default one",
            doc.scenes().len()
        ));
    }
    let mut out = Instances::default();
    let mut visited = vec![false; doc.nodes().len()];
    let mut ignored = Ignored::default();
    // Depth first with an explicit stack (a deep hierarchy must not overflow the stack).
    let mut stack: Vec<(gltf::Node<'a>, DMat4)> = roots
        .into_iter()
        .rev()
        .map(|n| (n, DMat4::IDENTITY))
        .collect();
    while let Some((node, parent)) = stack.pop() {
        let i = node.index();
        if visited[i] {
            return Err(format!(
                "node {i} is reached twice in the scene (glTF nodes must form disjoint trees: a cycle, or a node with two parents)"
            ));
        }
        visited[i] = true;
        let local = glam::Mat4::from_cols_array_2d(&node.transform().matrix()).as_dmat4();
        let to_world = parent * local;
        if !to_world.is_finite() {
            return Err(format!("node {i} has a non-finite transform"));
        }
        if let Some(mesh) = node.mesh() {
            ignored.skin |= node.skin().is_some();
            ignored.morph |= mesh.primitives().any(|p| p.morph_targets().len() > 0);
            out.meshes.push(MeshInstance {
                mesh,
                node: i,
                to_world,
            });
        }
        if let Some(camera) = node.camera() {
            out.cameras.push(CameraInstance {
                camera,
                node: i,
                to_world,
            });
        }
        if let Some(light) = node.light() {
            out.lights.push(LightInstance {
                light,
                node: i,
                to_world,
            });
        }
        let children: Vec<_> = node.children().collect();
        for c in children.into_iter().rev() {
            stack.push((c, to_world));
        }
    }
    if ignored.skin {
        warn("skins are ignored: skinned meshes render in their bind pose".into());
    }
    if ignored.morph {
        warn("morph targets are ignored: meshes render with their base geometry".into());
    }
    if doc.animations().len() > 0 {
        warn("animations are ignored: the scene renders at rest".into());
    }
    Ok(out)
}

#[derive(Default)]
struct Ignored {
    skin: bool,
    morph: bool,
}
