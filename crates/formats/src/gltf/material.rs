//! glTF's metallic-roughness material (specification §3.9 and Appendix B) on radia's
//! `cooktorrance` BSDF ([`radia_bsdf::CookTorrance`] in its metallic-roughness form, which
//! is Appendix B's BRDF: see `crates/bsdf/src/cook_torrance.rs`).
//!
//! | glTF | radia |
//! | --- | --- |
//! | `baseColorFactor` × `baseColorTexture` (sRGB) | `base_color` |
//! | `metallicFactor` × B of `metallicRoughnessTexture` | `metallic`: F0 = mix(0.04, base_color, metallic), base (1 − metallic)·base_color weighted by 1 − F(V·H) |
//! | `roughnessFactor` × G of `metallicRoughnessTexture` = r | GGX with α = r² (Appendix B: "α = roughness²"), separable Smith masking-shadowing as Appendix B.3.2's G |
//! | `normalTexture` with `scale` | `normalmap` around it (tangent space; see below) |
//! | `emissiveFactor` × `emissiveTexture` (sRGB) × `KHR_materials_emissive_strength` | radiance of an `area` emitter on the primitive's triangles |
//! | `doubleSided: true` | `twosided` around it: back faces are shaded as front faces with the normal reversed (§3.9.5) |
//! | `doubleSided: false` | the one-sided BSDF: back faces are black and opaque |
//! | `alphaMode` OPAQUE | opaque |
//! | `alphaMode` MASK | the alpha value, `baseColorFactor`'s alpha × the `baseColorTexture`'s (linear, filtered as the colour is), is compared to `alphaCutoff` (default 0.5) at every hit (§3.9.4): opaque where ≥, fully transparent below, through a `mask` adapter with that cutoff ([`radia_bsdf::Mask::with_cutoff`]; shadow rays pass through the holes). Without a texture, or with one whose every texel is on one side, the whole primitive is opaque or not rendered |
//! | `alphaMode` BLEND | rendered opaque, with a warning |
//! | no material | the specification's default material: base colour 1, metallic 1, roughness 1, single-sided |
//!
//! Textures (`textures.rs`) use the uv set their `texCoord` names; a primitive's mesh
//! carries one set, so a material whose textures name different sets uses the base
//! colour's (else the first textured slot's) set, with a warning.
//!
//! Where radia departs from the specification, and why:
//! - **Normal-map tangents.** §3.7.2.1 defines the tangent space by the TANGENT attribute
//!   (xyz the tangent, w = ±1), else by MikkTSpace. Primitives whose material has a
//!   `normalTexture` carry per-vertex tangents (`Mesh::tangents`, see `tangents.rs`): the
//!   file's TANGENT, or MikkTSpace's computed from the positions, normals (face normals
//!   without NORMAL) and the normal texture's uv set. At a hit the shading frame is then
//!   glTF's (and the Khronos sample viewer's): s = the interpolated tangent made orthogonal
//!   to the shading normal n, t = cross(n, s)·w, so the map's green channel tilts towards
//!   −cross(n, s) where w = −1 (mirrored uv). radia's `normalmap` (Mitsuba's) perturbs
//!   within that frame. A mirroring node transform multiplies w by the sign of its
//!   determinant, so that the bitangent keeps following the mapped +v. Primitives without a
//!   normal map, and every Mitsuba mesh, keep the ∂p/∂u frame and carry no tangents; a
//!   normal-mapped primitive without uv (no MikkTSpace possible) falls back to it with a
//!   warning.
//! - **Back faces of single-sided materials.** A rasteriser culls them (§3.9.5): they are
//!   invisible. radia shades them black and opaque, like Mitsuba's one-sided BSDFs (making
//!   them invisible would take a `null` back side on every single-sided material). A closed
//!   mesh, the usual case for single-sided materials, renders the same either way.
//! - **MASK** has no vertex-colour alpha (radia reads no `COLOR_0`); the alpha of a
//!   `baseColorTexture` is bilinearly filtered before the comparison unless its sampler
//!   says NEAREST, as a GPU's would be.
//! - **Emission is one-sided**: radia's area emitters, like Mitsuba's, emit from the front
//!   face only, also on double-sided materials.
//! - **Occlusion textures** are ignored on purpose: a path tracer computes the occlusion
//!   they approximate.

use super::textures::{Channels, Images};
use radia_bsdf::microfacet::Shadowing;
use radia_bsdf::{
    Bsdf, CookTorrance, CookTorranceFresnel, Mask, MicrofacetDistribution, MicrofacetType,
    NormalMap, PerturbOptions, Texture, TwoSided,
};
use radia_math::Spectrum;
use std::collections::HashMap;

/// What a primitive with a given material becomes.
#[derive(Clone, Debug)]
pub struct MaterialDesc {
    pub bsdf: Bsdf,
    /// Radiance of the area emitter on its triangles, if any.
    pub emission: Option<Texture>,
    /// The primitive is entirely transparent (MASK below the cutoff): not rendered.
    pub cut_out: bool,
    /// The uv set (`TEXCOORD_n`) the material's textures read; `None` without textures.
    pub tex_coord: Option<u32>,
    /// The material has a `normalTexture`: its primitives carry tangents (`TANGENT`, else
    /// MikkTSpace's).
    pub normal_mapped: bool,
}

/// The BSDF of glTF's metallic-roughness model with these factors (one-sided).
pub fn metallic_roughness(base_color: Spectrum, metallic: f32, roughness: f32) -> Bsdf {
    metallic_roughness_textured(base_color.into(), metallic.into(), roughness, None)
}

/// [`metallic_roughness`] with textures: `roughness` is the factor, used as a constant when
/// there is no `roughness_texture` (which then already includes the factor).
pub fn metallic_roughness_textured(
    base_color: Texture,
    metallic: Texture,
    roughness: f32,
    roughness_texture: Option<Texture>,
) -> Bsdf {
    let alpha = roughness.clamp(0.0, 1.0).powi(2);
    let ct = CookTorrance::new(
        MicrofacetDistribution::new(MicrofacetType::Ggx, alpha, alpha, true),
        Shadowing::Separable,
        CookTorranceFresnel::MetallicRoughness {
            base_color,
            metallic,
        },
    );
    Bsdf::CookTorrance(match roughness_texture {
        Some(t) => ct.with_roughness_texture(t),
        None => ct,
    })
}

/// Materials by index, built once each (the default material under `None`).
pub(crate) struct Materials {
    built: HashMap<Option<usize>, MaterialDesc>,
}

impl Materials {
    pub fn new() -> Self {
        Self {
            built: HashMap::new(),
        }
    }

    pub fn get(
        &mut self,
        m: gltf::Material<'_>,
        images: &mut Images<'_>,
        warn: &mut dyn FnMut(String),
    ) -> Result<&MaterialDesc, String> {
        use std::collections::hash_map::Entry;
        Ok(match self.built.entry(m.index()) {
            Entry::Occupied(e) => e.into_mut(),
            Entry::Vacant(e) => e.insert(build(&m, images, warn)?),
        })
    }
}

fn build(
    m: &gltf::Material<'_>,
    images: &mut Images<'_>,
    warn: &mut dyn FnMut(String),
) -> Result<MaterialDesc, String> {
    let name = match (m.index(), m.name()) {
        (Some(i), Some(n)) => format!("material {i} (\"{n}\")"),
        (Some(i), None) => format!("material {i}"),
        (None, _) => "the default material".to_string(),
    };
    let fail = |e: String| format!("{name}: {e}");
    let pbr = m.pbr_metallic_roughness();

    // The uv set: every textured slot should name the same one.
    let slots: Vec<(&str, u32)> = [
        pbr.base_color_texture()
            .map(|t| ("baseColorTexture", t.tex_coord())),
        pbr.metallic_roughness_texture()
            .map(|t| ("metallicRoughnessTexture", t.tex_coord())),
        m.normal_texture().map(|t| ("normalTexture", t.tex_coord())),
        m.emissive_texture()
            .map(|t| ("emissiveTexture", t.tex_coord())),
    ]
    .into_iter()
    .flatten()
    .collect();
    let tex_coord = slots.first().map(|s| s.1);
    if let Some(set) = tex_coord {
        let others: Vec<String> = slots
            .iter()
            .filter(|s| s.1 != set)
            .map(|s| format!("{} (TEXCOORD_{})", s.0, s.1))
            .collect();
        if !others.is_empty() {
            warn(format!(
                "{name}: radia reads one uv set per primitive: {} read TEXCOORD_{set}",
                others.join(", ")
            ));
        }
    }
    if m.occlusion_texture().is_some() {
        // (Said once per material; a path tracer computes the occlusion itself.)
        warn(format!(
            "{name}: occlusionTexture ignored (the path tracer computes the occlusion)"
        ));
    }

    let [r, g, b, a] = pbr.base_color_factor();
    let base_color = match pbr.base_color_texture() {
        Some(t) => images
            .texture(&t.texture(), Channels::SrgbColor([r, g, b]))
            .map_err(fail)?,
        None => Spectrum::new(r, g, b).into(),
    };
    let (metallic, roughness_texture) = match pbr.metallic_roughness_texture() {
        Some(t) => (
            images
                .texture(&t.texture(), Channels::Linear(2, pbr.metallic_factor()))
                .map_err(fail)?,
            Some(
                images
                    .texture(&t.texture(), Channels::Linear(1, pbr.roughness_factor()))
                    .map_err(fail)?,
            ),
        ),
        None => (pbr.metallic_factor().into(), None),
    };
    let mut one_sided = metallic_roughness_textured(
        base_color,
        metallic,
        pbr.roughness_factor(),
        roughness_texture,
    );
    if let Some(n) = m.normal_texture() {
        let map = images
            .texture(&n.texture(), Channels::Normal(n.scale()))
            .map_err(fail)?;
        one_sided = Bsdf::NormalMap(NormalMap::new(map, one_sided, PerturbOptions::default()));
    }
    let bsdf = if m.double_sided() {
        Bsdf::TwoSided(TwoSided::new(one_sided.clone(), one_sided))
    } else {
        one_sided
    };

    let strength = m.emissive_strength().unwrap_or(1.0);
    // (The schema bounds the factor to [0, 1] and the strength to >= 0; clamp what a file
    // gets wrong rather than emit negative light.)
    let factor = (Spectrum::from_array(m.emissive_factor()) * strength).max(Spectrum::ZERO);
    let emission = if !(factor.max_element() > 0.0 && factor.is_finite()) {
        None
    } else {
        Some(match m.emissive_texture() {
            Some(t) => images
                .texture(&t.texture(), Channels::SrgbColor(factor.to_array()))
                .map_err(fail)?,
            None => factor.into(),
        })
    };

    let mut bsdf = bsdf;
    let cut_out = match m.alpha_mode() {
        gltf::material::AlphaMode::Opaque => false,
        gltf::material::AlphaMode::Mask => {
            let cutoff = m.alpha_cutoff().unwrap_or(0.5);
            match pbr.base_color_texture() {
                None => a < cutoff,
                Some(t) => {
                    let alpha = images
                        .texture(&t.texture(), Channels::Linear(3, a))
                        .map_err(fail)?;
                    // (A filtered value lies between texel values: all on one side, one
                    // answer everywhere.)
                    let (lo, hi) = (alpha.min_value(), alpha.max_value());
                    if hi < cutoff {
                        true
                    } else {
                        if lo < cutoff {
                            bsdf = Bsdf::Mask(Mask::with_cutoff(alpha, cutoff, bsdf));
                        }
                        false
                    }
                }
            }
        }
        gltf::material::AlphaMode::Blend => {
            warn(format!(
                "{name}: alphaMode BLEND is rendered as OPAQUE (radia has no transparency yet)"
            ));
            false
        }
    };
    Ok(MaterialDesc {
        bsdf,
        emission,
        cut_out,
        tex_coord,
        normal_mapped: m.normal_texture().is_some(),
    })
}
