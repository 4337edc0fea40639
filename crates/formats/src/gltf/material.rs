//! glTF's metallic-roughness material (specification §3.9 and Appendix B) on radia's
//! `cooktorrance` BSDF ([`radia_bsdf::CookTorrance`] in its metallic-roughness form).
//!
//! | glTF | radia |
//! | --- | --- |
//! | `baseColorFactor` (RGB; linear) | `base_color` |
//! | `metallicFactor` | `metallic`: F0 = mix(0.04, base_color, metallic), Lambertian base (1 − metallic)·base_color |
//! | `roughnessFactor` r | GGX with α = r² (Appendix B: "α = roughness²"), separable Smith masking-shadowing as Appendix B.3.2's G |
//! | `emissiveFactor` × `KHR_materials_emissive_strength` | radiance of an `area` emitter on the primitive's triangles |
//! | `doubleSided: true` | `twosided` around it: back faces are shaded as front faces with the normal reversed (§3.9.5) |
//! | `doubleSided: false` | the one-sided BSDF: back faces are black and opaque |
//! | `alphaMode` OPAQUE | opaque |
//! | `alphaMode` MASK | with factors only, a primitive whose `baseColorFactor` alpha is below `alphaCutoff` (default 0.5) is fully cut out (not rendered); else opaque |
//! | `alphaMode` BLEND | rendered opaque, with a warning |
//! | no material | the specification's default material: base colour 1, metallic 1, roughness 1, single-sided |
//!
//! Where radia departs from the specification, and why:
//! - **Diffuse/specular coupling.** Appendix B mixes the base and the specular layer with
//!   `fresnel_mix`, weighting the Lambertian base by 1 − F(V·H). `cooktorrance` weights it
//!   by the specular lobe's directional albedo instead (Kelemen and Szirmay-Kalos 2001, as
//!   Mitsuba's `roughplastic`), which conserves energy; see `crates/bsdf/src/cook_torrance.rs`.
//!   Both agree on the specular lobe (`tests/gltf_materials.rs` checks it against Appendix
//!   B's formula) and on the base at normal incidence of a smooth surface; they differ on the
//!   base elsewhere.
//! - **Back faces of single-sided materials.** A rasteriser culls them (§3.9.5): they are
//!   invisible. radia has no pass-through surface yet (Mitsuba's `null`/`mask`, issue #10),
//!   so they are black and opaque, like Mitsuba's one-sided BSDFs. A closed mesh, the usual
//!   case for single-sided materials, renders the same either way.
//! - **Emission is one-sided**: radia's area emitters, like Mitsuba's, emit from the front
//!   face only, also on double-sided materials.
//! - **Textures** are not applied yet (a warning says which): the factors alone are used.
//!   Occlusion textures are ignored on purpose: a path tracer computes the occlusion they
//!   approximate.

use radia_bsdf::microfacet::Shadowing;
use radia_bsdf::{
    Bsdf, CookTorrance, CookTorranceFresnel, MicrofacetDistribution, MicrofacetType, TwoSided,
};
use radia_math::Spectrum;
use std::collections::HashMap;

/// What a primitive with a given material becomes.
#[derive(Clone, Debug)]
pub struct MaterialDesc {
    pub bsdf: Bsdf,
    /// Radiance of the area emitter on its triangles, if any.
    pub emission: Option<Spectrum>,
    /// The primitive is entirely transparent (MASK below the cutoff): not rendered.
    pub cut_out: bool,
}

/// The BSDF of glTF's metallic-roughness model with these factors (one-sided).
pub fn metallic_roughness(base_color: Spectrum, metallic: f32, roughness: f32) -> Bsdf {
    let alpha = roughness.clamp(0.0, 1.0).powi(2);
    Bsdf::CookTorrance(CookTorrance::new(
        MicrofacetDistribution::new(MicrofacetType::Ggx, alpha, alpha, true),
        Shadowing::Separable,
        CookTorranceFresnel::MetallicRoughness {
            base_color: base_color.into(),
            metallic: metallic.clamp(0.0, 1.0),
        },
    ))
}

/// Materials by index, built once each (the default material under `None`).
pub(crate) struct Materials {
    built: HashMap<Option<usize>, MaterialDesc>,
    /// Materials whose textures were not applied, for one warning.
    textured: Vec<usize>,
}

impl Materials {
    pub fn new(_doc: &gltf::Document) -> Self {
        Self {
            built: HashMap::new(),
            textured: Vec::new(),
        }
    }

    pub fn get(&mut self, m: gltf::Material<'_>, warn: &mut dyn FnMut(String)) -> &MaterialDesc {
        let key = m.index();
        if !self.built.contains_key(&key) {
            let desc = build(&m, warn);
            if let Some(i) = key {
                if has_textures(&m) {
                    self.textured.push(i);
                }
            }
            self.built.insert(key, desc);
        }
        &self.built[&key]
    }

    /// The warning about textures not applied, once per file.
    pub fn report(&self, warn: &mut dyn FnMut(String)) {
        if !self.textured.is_empty() {
            let list: Vec<String> = self.textured.iter().map(|i| i.to_string()).collect();
            warn(format!(
                "textures are not applied yet (material(s) {}): their factors alone are used",
                list.join(", ")
            ));
        }
    }
}

fn has_textures(m: &gltf::Material<'_>) -> bool {
    let pbr = m.pbr_metallic_roughness();
    pbr.base_color_texture().is_some()
        || pbr.metallic_roughness_texture().is_some()
        || m.normal_texture().is_some()
        || m.emissive_texture().is_some()
}

fn build(m: &gltf::Material<'_>, warn: &mut dyn FnMut(String)) -> MaterialDesc {
    let name = match (m.index(), m.name()) {
        (Some(i), Some(n)) => format!("material {i} (\"{n}\")"),
        (Some(i), None) => format!("material {i}"),
        (None, _) => "the default material".to_string(),
    };
    let pbr = m.pbr_metallic_roughness();
    let [r, g, b, a] = pbr.base_color_factor();
    let base = Spectrum::new(r, g, b);
    let one_sided = metallic_roughness(base, pbr.metallic_factor(), pbr.roughness_factor());
    let bsdf = if m.double_sided() {
        Bsdf::TwoSided(TwoSided::new(one_sided.clone(), one_sided))
    } else {
        one_sided
    };

    let strength = m.emissive_strength().unwrap_or(1.0);
    // (The schema bounds the factor to [0, 1] and the strength to >= 0; clamp what a file
    // gets wrong rather than emit negative light.)
    let emission = (Spectrum::from_array(m.emissive_factor()) * strength).max(Spectrum::ZERO);
    let emission = (emission.max_element() > 0.0 && emission.is_finite()).then_some(emission);

    let cut_out = match m.alpha_mode() {
        gltf::material::AlphaMode::Opaque => false,
        gltf::material::AlphaMode::Mask => a < m.alpha_cutoff().unwrap_or(0.5),
        gltf::material::AlphaMode::Blend => {
            warn(format!(
                "{name}: alphaMode BLEND is rendered as OPAQUE (radia has no transparency yet)"
            ));
            false
        }
    };
    MaterialDesc {
        bsdf,
        emission,
        cut_out,
    }
}
