//! BSDF plugins: one function per Mitsuba plugin name, dispatched in [`build_bsdf`].
//! To add a model, add an arm to the `match` and a function that reads its parameters
//! through [`Props`] (every parameter it does not read is reported as unknown).
//!
//! Names, defaults and checks follow Mitsuba 3.9.1's `src/bsdfs/*.cpp`,
//! `include/mitsuba/render/microfacet.h` and `ior.h`. radia's own models (`phong`,
//! `blinnphong`, `cooktorrance`) and options (`height_correlated`) are marked as such; a
//! scene using them does not load in Mitsuba.

use super::build::Builder;
use super::props::Props;
use super::textures::{build_texture, is_texture, texture_param};
use super::xml::{Kind, Value};
use super::LoadError;
use glam::Vec3;
use radia_bsdf::ior::{
    lookup_conductor, lookup_dielectric_ior, CONDUCTOR_PRESETS, DIELECTRIC_IORS,
};
use radia_bsdf::microfacet::{RoughnessTextures, Shadowing};
use radia_bsdf::{
    Blend, BlinnPhong, Bsdf, BumpMap, Conductor, CookTorrance, CookTorranceFresnel, Dielectric,
    Diffuse, LobeFlags, Mask, MicrofacetDistribution, MicrofacetType, NormalMap, Null,
    PerturbOptions, Phong, Plastic, Principled, PrincipledIor, PrincipledThin, RoughConductor,
    RoughDielectric, RoughPlastic, ShadingPoint, Texture, ThinDielectric, TwoSided,
};

/// Nested BSDFs (twosided of twosided ...) deeper than this are refused.
const MAX_NESTING: usize = 32;

/// The plugin names [`build_bsdf`] knows, for the error message.
const SUPPORTED: &str = "diffuse, conductor, roughconductor, dielectric, thindielectric, \
roughdielectric, plastic, roughplastic, principled, principledthin, blendbsdf, twosided, normalmap, bumpmap, mask, null, and radia's \
phong, blinnphong, cooktorrance";

/// Builds the BSDF of node `idx`. A node referenced several times is built once.
pub(crate) fn build_bsdf(
    b: &mut Builder<'_>,
    idx: usize,
    nesting: usize,
) -> Result<Bsdf, LoadError> {
    if let Some(bsdf) = b.bsdf_cache.get(&idx) {
        return Ok(bsdf.clone());
    }
    let p = Props::new(b.doc, idx);
    if nesting > MAX_NESTING {
        return Err(p.err(format!(
            "BSDFs are nested more than {MAX_NESTING} levels deep"
        )));
    }
    let bsdf = match p.node.plugin.as_str() {
        "diffuse" => diffuse(b, p)?,
        "conductor" => conductor(b, p)?,
        "roughconductor" => rough_conductor(b, p)?,
        "dielectric" => dielectric(b, p)?,
        "thindielectric" => thin_dielectric(b, p)?,
        "roughdielectric" => rough_dielectric(b, p)?,
        "plastic" => plastic(b, p)?,
        "roughplastic" => rough_plastic(b, p)?,
        "principled" => principled(b, p)?,
        "principledthin" => principled_thin(b, p)?,
        "blendbsdf" => blend(b, p, nesting)?,
        "twosided" => twosided(b, p, nesting)?,
        "normalmap" => normal_map(b, p, nesting)?,
        "bumpmap" => bump_map(b, p, nesting)?,
        "mask" => mask(b, p, nesting)?,
        "null" => {
            p.finish()?;
            Bsdf::Null(Null)
        }
        "phong" => phong(b, p, false)?,
        "blinnphong" => phong(b, p, true)?,
        "cooktorrance" => cook_torrance(b, p)?,
        other => {
            return Err(p.err(format!(
                "unsupported BSDF plugin type \"{other}\" (radia supports: {SUPPORTED})"
            )))
        }
    };
    b.bsdf_cache.insert(idx, bsdf.clone());
    Ok(bsdf)
}

/// Mitsuba's default material: `diffuse` with reflectance 0.5, or 0 on an emitter
/// (`src/render/shape.cpp`).
pub(crate) fn default_bsdf(is_emitter: bool) -> Bsdf {
    let r = if is_emitter { 0.0 } else { 0.5 };
    Bsdf::Diffuse(Diffuse::new(Vec3::splat(r)))
}

/// `diffuse` (`src/bsdfs/diffuse.cpp`): `reflectance`, default 0.5.
fn diffuse(b: &mut Builder<'_>, mut p: Props<'_>) -> Result<Bsdf, LoadError> {
    let r = texture_param(b, &mut p, "reflectance", 0.5, true)?;
    p.finish()?;
    Ok(Bsdf::Diffuse(Diffuse::new(r)))
}

// ---------------------------------------------------------------------------------------------
// Shared parameter groups
// ---------------------------------------------------------------------------------------------

/// The raw value of parameter `name`, without marking it read (to choose how to read it).
fn peek<'a>(p: &Props<'a>, name: &str) -> Option<&'a Value> {
    p.node
        .props
        .iter()
        .find(|x| x.name == name && !matches!(x.value, Value::Object(_)))
        .map(|x| &x.value)
}

/// An index of refraction given as a number or one of Mitsuba's names (`lookup_ior` in
/// `include/mitsuba/render/ior.h`), default `default`.
fn ior(p: &mut Props<'_>, name: &str, default: &str) -> Result<f32, LoadError> {
    let pos = p.pos_of(name);
    let value = match peek(p, name) {
        Some(Value::String(_)) => {
            let s = p.string_opt(name)?.unwrap_or(default);
            lookup_dielectric_ior(s).ok_or_else(|| {
                let names: Vec<&str> = DIELECTRIC_IORS.iter().map(|(n, _)| *n).collect();
                p.err_at(
                    pos,
                    format!(
                        "unable to find an IOR value for \"{}\" (\"{name}\"); valid choices are: {}",
                        s.to_lowercase(),
                        names.join(", ")
                    ),
                )
            })? as f64
        }
        Some(_) => p.float(name, 0.0)?,
        None => lookup_dielectric_ior(default).expect("default IOR names exist") as f64,
    };
    if !value.is_finite() {
        return Err(p.err_at(pos, format!("\"{name}\" must be finite")));
    }
    Ok(value as f32)
}

/// `int_ior` and `ext_ior`, checked to be positive as Mitsuba does (and to differ where it
/// asks for that: the rough interfaces).
fn ior_pair(
    p: &mut Props<'_>,
    int_default: &str,
    must_differ: bool,
) -> Result<(f32, f32), LoadError> {
    let int_ior = ior(p, "int_ior", int_default)?;
    let ext_ior = ior(p, "ext_ior", "air")?;
    if int_ior < 0.0 || ext_ior < 0.0 || (must_differ && int_ior == ext_ior) {
        let what = if must_differ {
            "must be positive and differ"
        } else {
            "must be positive"
        };
        return Err(p.err(format!(
            "the interior and exterior indices of refraction {what} (int_ior {int_ior}, ext_ior {ext_ior})"
        )));
    }
    // Zero is allowed by Mitsuba's check but makes no interface.
    if int_ior == 0.0 || ext_ior == 0.0 {
        return Err(p.err(format!(
            "the indices of refraction must be positive (int_ior {int_ior}, ext_ior {ext_ior})"
        )));
    }
    Ok((int_ior, ext_ior))
}

/// A conductor's complex IOR: `eta`/`k` (defaults 0 and 1) or a `material` preset, default
/// "none" (= eta 0, k 1: F = 1), as `conductor.cpp`/`roughconductor.cpp`.
fn complex_ior(p: &mut Props<'_>) -> Result<(Vec3, Vec3), LoadError> {
    let material_pos = p.pos_of("material");
    let material = p.string_opt("material")?.unwrap_or("none");
    if p.has("eta") || material == "none" {
        let eta = p.color("eta", 0.0, false)?;
        let k = p.color("k", 1.0, false)?;
        if material != "none" {
            return Err(p.err_at(
                material_pos,
                "should specify either (eta, k) or material, not both",
            ));
        }
        return Ok((eta.as_vec3(), k.as_vec3()));
    }
    match lookup_conductor(material) {
        Some(preset) => Ok((preset.eta.into(), preset.k.into())),
        None => {
            let names: Vec<&str> = CONDUCTOR_PRESETS.iter().map(|c| c.name).collect();
            Err(p.err_at(
                material_pos,
                format!(
                    "unknown conductor material \"{material}\"; radia knows Mitsuba 3.9.1's: none, {}",
                    names.join(", ")
                ),
            ))
        }
    }
}

/// `distribution` ("beckmann" or "ggx", case-insensitive; `default` when absent).
fn distribution_type(
    p: &mut Props<'_>,
    default: MicrofacetType,
) -> Result<MicrofacetType, LoadError> {
    let pos = p.pos_of("distribution");
    match p.string_opt("distribution")? {
        None => Ok(default),
        Some(s) => match s.to_lowercase().as_str() {
            "beckmann" => Ok(MicrofacetType::Beckmann),
            "ggx" => Ok(MicrofacetType::Ggx),
            other => Err(p.err_at(
                pos,
                format!("specified an invalid distribution \"{other}\", must be \"beckmann\" or \"ggx\""),
            )),
        },
    }
}

/// `alpha` (default 0.1), or both `alpha_u` and `alpha_v`, as Mitsuba's microfacet plugins
/// (used as given, clamped to ≥ 10⁻⁴ by the distribution), with the textures when any of
/// them is one (`get_unbounded_texture` in `roughconductor.cpp`/`roughdielectric.cpp`; the
/// constant α returned then is unused). `textures_ok` is false where Mitsuba takes a plain
/// float (roughplastic, whose tables are built for one α). With `roughness_too`, radia's
/// `roughness` (glTF's: α = roughness²) is a third alternative.
fn alphas_textured(
    b: &mut Builder<'_>,
    p: &mut Props<'_>,
    roughness_too: bool,
    textures_ok: bool,
) -> Result<(f32, f32, Option<RoughnessTextures>), LoadError> {
    let textured = ["alpha", "alpha_u", "alpha_v"]
        .iter()
        .any(|n| is_texture(p, n));
    if !textured {
        let (au, av) = alphas(p, roughness_too)?;
        return Ok((au, av, None));
    }
    if !textures_ok {
        return Err(p.err(format!(
            "{}: the roughness must be a <float> (Mitsuba's {} takes no texture for it)",
            p.node.plugin, p.node.plugin
        )));
    }
    let has_uv = p.has_any("alpha_u") || p.has_any("alpha_v");
    if has_uv && p.has_any("alpha") || roughness_too && p.has_any("roughness") {
        return Err(p.err("microfacet model: please specify either 'alpha' or 'alpha_u'/'alpha_v'"));
    }
    let (alpha_u, alpha_v) = if has_uv {
        if !(p.has_any("alpha_u") && p.has_any("alpha_v")) {
            return Err(p.err("microfacet model: both 'alpha_u' and 'alpha_v' must be specified"));
        }
        (
            texture_param(b, p, "alpha_u", 0.1, false)?,
            texture_param(b, p, "alpha_v", 0.1, false)?,
        )
    } else {
        let t = texture_param(b, p, "alpha", 0.1, false)?;
        (t.clone(), t)
    };
    Ok((0.1, 0.1, Some(RoughnessTextures { alpha_u, alpha_v })))
}

/// The constant form of [`alphas_textured`].
fn alphas(p: &mut Props<'_>, roughness_too: bool) -> Result<(f32, f32), LoadError> {
    let has_uv = p.has("alpha_u") || p.has("alpha_v");
    let count =
        p.has("alpha") as u32 + has_uv as u32 + (roughness_too && p.has("roughness")) as u32;
    if count > 1 {
        let what = if roughness_too {
            "either 'alpha', 'alpha_u'/'alpha_v' or 'roughness'"
        } else {
            "either 'alpha' or 'alpha_u'/'alpha_v'"
        };
        return Err(p.err(format!("microfacet model: please specify {what}")));
    }
    let (au, av) = if has_uv {
        if !(p.has("alpha_u") && p.has("alpha_v")) {
            return Err(p.err("microfacet model: both 'alpha_u' and 'alpha_v' must be specified"));
        }
        (roughness(p, "alpha_u", 0.1)?, roughness(p, "alpha_v", 0.1)?)
    } else if roughness_too && p.has("roughness") {
        let r = roughness(p, "roughness", 0.0)?;
        (r * r, r * r)
    } else {
        let a = roughness(p, "alpha", 0.1)?;
        (a, a)
    };
    Ok((au as f32, av as f32))
}

/// One roughness parameter, finite and >= 0. Mitsuba clamps a negative alpha to its floor
/// (a near mirror) without a word; radia refuses it, as it is most likely a typo.
fn roughness(p: &mut Props<'_>, name: &str, default: f64) -> Result<f64, LoadError> {
    let v = p.float(name, default)?;
    if !(v.is_finite() && v >= 0.0) {
        return Err(p.err_at(
            p.pos_of(name),
            format!("microfacet model: \"{name}\" must be a finite number >= 0, got {v}"),
        ));
    }
    Ok(v)
}

/// radia's `height_correlated` option (default false: Mitsuba's separable Smith G).
fn shadowing(p: &mut Props<'_>) -> Result<Shadowing, LoadError> {
    Ok(if p.boolean("height_correlated", false)? {
        Shadowing::HeightCorrelated
    } else {
        Shadowing::Separable
    })
}

// ---------------------------------------------------------------------------------------------
// Conductors
// ---------------------------------------------------------------------------------------------

/// `conductor` (`src/bsdfs/conductor.cpp`).
fn conductor(b: &mut Builder<'_>, mut p: Props<'_>) -> Result<Bsdf, LoadError> {
    let spec = texture_param(b, &mut p, "specular_reflectance", 1.0, true)?;
    let (eta, k) = complex_ior(&mut p)?;
    p.finish()?;
    Ok(Bsdf::Conductor(Conductor::new(eta, k, spec)))
}

/// `roughconductor` (`src/bsdfs/roughconductor.cpp`): Beckmann by default, α 0.1, visible
/// normals; radia's `height_correlated` option.
fn rough_conductor(b: &mut Builder<'_>, mut p: Props<'_>) -> Result<Bsdf, LoadError> {
    let (eta, k) = complex_ior(&mut p)?;
    let kind = distribution_type(&mut p, MicrofacetType::Beckmann)?;
    let visible = p.boolean("sample_visible", true)?;
    let (au, av, alpha_tex) = alphas_textured(b, &mut p, false, true)?;
    let spec = texture_param(b, &mut p, "specular_reflectance", 1.0, true)?;
    let g = shadowing(&mut p)?;
    p.finish()?;
    let d = MicrofacetDistribution::new(kind, au, av, visible);
    Ok(Bsdf::RoughConductor(
        RoughConductor::new(d, eta, k, spec)
            .with_shadowing(g)
            .with_roughness(alpha_tex),
    ))
}

/// radia's `cooktorrance`: GGX by default; `F0`, or glTF's `base_color` (default 0.5) and
/// `metallic` (default 0, in [0, 1]; both may be textures); `alpha`, `alpha_u`/`alpha_v` or
/// `roughness`.
fn cook_torrance(b: &mut Builder<'_>, mut p: Props<'_>) -> Result<Bsdf, LoadError> {
    let kind = distribution_type(&mut p, MicrofacetType::Ggx)?;
    let visible = p.boolean("sample_visible", true)?;
    let (au, av) = alphas(&mut p, true)?;
    let g = shadowing(&mut p)?;
    let gltf = p.has_any("base_color") || p.has("metallic");
    let fresnel = if p.has_any("F0") {
        if gltf {
            return Err(p.err("cooktorrance: specify either F0 or base_color/metallic, not both"));
        }
        CookTorranceFresnel::Schlick {
            f0: texture_param(b, &mut p, "F0", 0.04, true)?,
        }
    } else {
        let pos = p.pos_of("metallic");
        let base_color = texture_param(b, &mut p, "base_color", 0.5, true)?;
        let metallic = texture_param(b, &mut p, "metallic", 0.0, false)?;
        if let Some(m) = metallic.as_constant() {
            if !(0.0..=1.0).contains(&m.x) || m.x != m.y || m.y != m.z {
                return Err(p.err_at(
                    pos,
                    format!("cooktorrance: metallic {} must be one value in [0, 1]", m.x),
                ));
            }
        }
        CookTorranceFresnel::MetallicRoughness {
            base_color,
            metallic,
        }
    };
    p.finish()?;
    let d = MicrofacetDistribution::new(kind, au, av, visible);
    Ok(Bsdf::CookTorrance(CookTorrance::new(d, g, fresnel)))
}

// ---------------------------------------------------------------------------------------------
// Dielectrics
// ---------------------------------------------------------------------------------------------

/// `dielectric` (`src/bsdfs/dielectric.cpp`): bk7 inside, air outside by default.
fn dielectric(b: &mut Builder<'_>, mut p: Props<'_>) -> Result<Bsdf, LoadError> {
    let (int_ior, ext_ior) = ior_pair(&mut p, "bk7", false)?;
    let r = texture_param(b, &mut p, "specular_reflectance", 1.0, true)?;
    let t = texture_param(b, &mut p, "specular_transmittance", 1.0, true)?;
    p.finish()?;
    let mut m = Dielectric::new(int_ior, ext_ior);
    m.specular_reflectance = r;
    m.specular_transmittance = t;
    Ok(Bsdf::Dielectric(m))
}

/// `thindielectric` (`src/bsdfs/thindielectric.cpp`).
fn thin_dielectric(b: &mut Builder<'_>, mut p: Props<'_>) -> Result<Bsdf, LoadError> {
    let (int_ior, ext_ior) = ior_pair(&mut p, "bk7", false)?;
    let r = texture_param(b, &mut p, "specular_reflectance", 1.0, true)?;
    let t = texture_param(b, &mut p, "specular_transmittance", 1.0, true)?;
    p.finish()?;
    let mut m = ThinDielectric::new(int_ior, ext_ior);
    m.specular_reflectance = r;
    m.specular_transmittance = t;
    Ok(Bsdf::ThinDielectric(m))
}

/// `roughdielectric` (`src/bsdfs/roughdielectric.cpp`): Beckmann, α 0.1, bk7/air.
fn rough_dielectric(b: &mut Builder<'_>, mut p: Props<'_>) -> Result<Bsdf, LoadError> {
    let r = texture_param(b, &mut p, "specular_reflectance", 1.0, true)?;
    let t = texture_param(b, &mut p, "specular_transmittance", 1.0, true)?;
    let (int_ior, ext_ior) = ior_pair(&mut p, "bk7", true)?;
    let kind = distribution_type(&mut p, MicrofacetType::Beckmann)?;
    let visible = p.boolean("sample_visible", true)?;
    let (au, av, alpha_tex) = alphas_textured(b, &mut p, false, true)?;
    p.finish()?;
    let d = MicrofacetDistribution::new(kind, au, av, visible);
    let mut m = RoughDielectric::new(d, int_ior, ext_ior).with_roughness(alpha_tex);
    m.specular_reflectance = r;
    m.specular_transmittance = t;
    Ok(Bsdf::RoughDielectric(m))
}

// ---------------------------------------------------------------------------------------------
// Plastics
// ---------------------------------------------------------------------------------------------

/// `plastic` (`src/bsdfs/plastic.cpp`): polypropylene (1.49) in air, diffuse 0.5.
fn plastic(b: &mut Builder<'_>, mut p: Props<'_>) -> Result<Bsdf, LoadError> {
    let (int_ior, ext_ior) = ior_pair(&mut p, "polypropylene", false)?;
    let d = texture_param(b, &mut p, "diffuse_reflectance", 0.5, true)?;
    let s = texture_param(b, &mut p, "specular_reflectance", 1.0, true)?;
    let nonlinear = p.boolean("nonlinear", false)?;
    p.finish()?;
    Ok(Bsdf::Plastic(Plastic::new(
        int_ior, ext_ior, d, s, nonlinear,
    )))
}

/// `roughplastic` (`src/bsdfs/roughplastic.cpp`): Beckmann α 0.1, isotropic only.
fn rough_plastic(b: &mut Builder<'_>, mut p: Props<'_>) -> Result<Bsdf, LoadError> {
    let (int_ior, ext_ior) = ior_pair(&mut p, "polypropylene", true)?;
    let d = texture_param(b, &mut p, "diffuse_reflectance", 0.5, true)?;
    let s = texture_param(b, &mut p, "specular_reflectance", 1.0, true)?;
    let nonlinear = p.boolean("nonlinear", false)?;
    let kind = distribution_type(&mut p, MicrofacetType::Beckmann)?;
    let visible = p.boolean("sample_visible", true)?;
    let (au, av, _) = alphas_textured(b, &mut p, false, false)?;
    if au != av {
        return Err(p.err(
            "the 'roughplastic' plugin currently does not support anisotropic microfacet distributions",
        ));
    }
    p.finish()?;
    Ok(Bsdf::RoughPlastic(RoughPlastic::new(
        kind, au, visible, int_ior, ext_ior, d, s, nonlinear,
    )))
}

// ---------------------------------------------------------------------------------------------
// The Disney principled BSDF
// ---------------------------------------------------------------------------------------------

/// Mitsuba's `get_flag` (`principledhelpers.h`): a lobe is on when its parameter is given
/// and is not the float 0.
fn principled_flag(p: &Props<'_>, name: &str) -> bool {
    match peek(p, name) {
        Some(Value::Float(x)) => *x != 0.0,
        Some(Value::Integer(k)) => *k != 0,
        Some(_) => true,
        None => p.has_any(name),
    }
}

/// A principled weight: a texture or a constant in [0, 1] (Mitsuba's documentation asks for
/// that range but does not check it; a weight out of it makes negative lobes). `None` when
/// [`principled_flag`] is false (the value is still read, as Mitsuba reads it).
fn principled_weight(
    b: &mut Builder<'_>,
    p: &mut Props<'_>,
    name: &str,
    default: f64,
) -> Result<Option<Texture>, LoadError> {
    let on = principled_flag(p, name);
    let t = principled_texture(b, p, name, default)?;
    Ok(on.then_some(t))
}

/// [`principled_weight`] for the parameters Mitsuba always reads (no flag).
fn principled_texture(
    b: &mut Builder<'_>,
    p: &mut Props<'_>,
    name: &str,
    default: f64,
) -> Result<Texture, LoadError> {
    principled_texture_max(b, p, name, default, 1.0)
}

/// [`principled_texture`] with constants in [0, `max`].
fn principled_texture_max(
    b: &mut Builder<'_>,
    p: &mut Props<'_>,
    name: &str,
    default: f64,
    max: f32,
) -> Result<Texture, LoadError> {
    let pos = p.pos_of(name);
    let t = texture_param(b, p, name, default, true)?;
    if let Some(c) = t.as_constant() {
        if c.max_element() > max {
            return Err(p.err_at(
                pos,
                format!(
                    "{}: \"{name}\" must be in [0, {max}], got {}",
                    p.node.plugin,
                    c.max_element()
                ),
            ));
        }
    }
    Ok(t)
}

/// A sampling rate: a `<float>` ≥ 0, default 1.
fn sampling_rate(p: &mut Props<'_>, name: &str) -> Result<f32, LoadError> {
    let pos = p.pos_of(name);
    let v = p.float(name, 1.0)?;
    if !(v.is_finite() && v >= 0.0) {
        return Err(p.err_at(
            pos,
            format!(
                "{}: \"{name}\" must be a finite number >= 0, got {v}",
                p.node.plugin
            ),
        ));
    }
    Ok(v as f32)
}

/// `principled` (`src/bsdfs/principled.cpp`): base_color 0.5, roughness 0.5, the lobe weights
/// (metallic, spec_trans, anisotropic, spec_tint, sheen, sheen_tint, flatness, clearcoat;
/// default 0, each a float or texture), clearcoat_gloss 0, `eta` or `specular` (0.5: η 1.5;
/// not both), and the three sampling rates (1 each).
fn principled(b: &mut Builder<'_>, mut p: Props<'_>) -> Result<Bsdf, LoadError> {
    let mut m = Principled::new(principled_texture(b, &mut p, "base_color", 0.5)?);
    m.roughness = principled_texture(b, &mut p, "roughness", 0.5)?;
    m.anisotropic = principled_weight(b, &mut p, "anisotropic", 0.0)?;
    m.spec_trans = principled_weight(b, &mut p, "spec_trans", 0.0)?;
    m.sheen = principled_weight(b, &mut p, "sheen", 0.0)?;
    m.sheen_tint = principled_weight(b, &mut p, "sheen_tint", 0.0)?;
    m.flatness = principled_weight(b, &mut p, "flatness", 0.0)?;
    m.spec_tint = principled_weight(b, &mut p, "spec_tint", 0.0)?;
    m.metallic = principled_weight(b, &mut p, "metallic", 0.0)?;
    m.clearcoat = principled_weight(b, &mut p, "clearcoat", 0.0)?;
    m.clearcoat_gloss = principled_texture(b, &mut p, "clearcoat_gloss", 0.0)?;
    m.spec_srate = sampling_rate(&mut p, "main_specular_sampling_rate")?;
    m.clearcoat_srate = sampling_rate(&mut p, "clearcoat_sampling_rate")?;
    m.diff_refl_srate = sampling_rate(&mut p, "diffuse_reflectance_sampling_rate")?;
    if m.spec_srate == 0.0 && m.diff_refl_srate == 0.0 {
        return Err(p.err(
            "principled: main_specular_sampling_rate and diffuse_reflectance_sampling_rate cannot both be 0",
        ));
    }
    let ior = if p.has_any("eta") && p.has_any("specular") {
        return Err(p.err(
            "principled: specified an invalid index of refraction property, either use \"eta\" or \"specular\"",
        ));
    } else if p.has_any("eta") {
        let pos = p.pos_of("eta");
        let eta = p.float("eta", 1.5)?;
        if !(eta.is_finite() && eta > 0.0) {
            return Err(p.err_at(
                pos,
                format!("principled: \"eta\" must be a finite number > 0, got {eta}"),
            ));
        }
        PrincipledIor::Eta(eta as f32)
    } else {
        let pos = p.pos_of("specular");
        let s = p.float("specular", 0.5)?;
        // η = 2/(1 − √(0.08 s)) − 1 is finite for s < 12.5.
        if !(s.is_finite() && (0.0..12.5).contains(&s)) {
            return Err(p.err_at(
                pos,
                format!("principled: \"specular\" must be in [0, 12.5), got {s}"),
            ));
        }
        PrincipledIor::Specular(s as f32)
    };
    p.finish()?;
    Ok(Bsdf::Principled(m.with_ior(ior)))
}

/// `principledthin` (`src/bsdfs/principledthin.cpp`): base_color 0.5, roughness 0.5, the
/// weights anisotropic, spec_trans, spec_tint, sheen, sheen_tint, flatness (in [0, 1]) and
/// diff_trans (in [0, 2]), `eta` (1.5, a float or texture), and four sampling rates.
fn principled_thin(b: &mut Builder<'_>, mut p: Props<'_>) -> Result<Bsdf, LoadError> {
    let mut m = PrincipledThin::new(principled_texture(b, &mut p, "base_color", 0.5)?);
    m.roughness = principled_texture(b, &mut p, "roughness", 0.5)?;
    m.anisotropic = principled_weight(b, &mut p, "anisotropic", 0.0)?;
    m.spec_trans = principled_weight(b, &mut p, "spec_trans", 0.0)?;
    m.sheen = principled_weight(b, &mut p, "sheen", 0.0)?;
    m.sheen_tint = principled_weight(b, &mut p, "sheen_tint", 0.0)?;
    m.flatness = principled_weight(b, &mut p, "flatness", 0.0)?;
    m.spec_tint = principled_weight(b, &mut p, "spec_tint", 0.0)?;
    let on = principled_flag(&p, "diff_trans");
    let dt = principled_texture_max(b, &mut p, "diff_trans", 0.0, 2.0)?;
    m.diff_trans = on.then_some(dt);
    let pos = p.pos_of("eta");
    m.eta = texture_param(b, &mut p, "eta", 1.5, false)?;
    if let Some(e) = m.eta.as_constant() {
        if e.min_element().is_nan() || e.min_element() <= 0.0 {
            return Err(p.err_at(
                pos,
                format!(
                    "principledthin: \"eta\" must be > 0, got {}",
                    e.min_element()
                ),
            ));
        }
    }
    m.spec_refl_srate = sampling_rate(&mut p, "specular_reflectance_sampling_rate")?;
    m.spec_trans_srate = sampling_rate(&mut p, "specular_transmittance_sampling_rate")?;
    m.diff_trans_srate = sampling_rate(&mut p, "diffuse_transmittance_sampling_rate")?;
    m.diff_refl_srate = sampling_rate(&mut p, "diffuse_reflectance_sampling_rate")?;
    if m.spec_refl_srate + m.spec_trans_srate + m.diff_trans_srate + m.diff_refl_srate == 0.0 {
        return Err(p.err("principledthin: the sampling rates cannot all be 0"));
    }
    p.finish()?;
    Ok(Bsdf::PrincipledThin(m))
}

// ---------------------------------------------------------------------------------------------
// radia's Phong models
// ---------------------------------------------------------------------------------------------

/// radia's `phong` and `blinnphong`: `diffuse_reflectance` kd (0.5), `specular_reflectance`
/// ks (0.2), `exponent` n ≥ 0 (30). kd + ks > 1 reflects more than it receives: a warning.
fn phong(b: &mut Builder<'_>, mut p: Props<'_>, blinn: bool) -> Result<Bsdf, LoadError> {
    let kd = texture_param(b, &mut p, "diffuse_reflectance", 0.5, true)?;
    let ks = texture_param(b, &mut p, "specular_reflectance", 0.2, true)?;
    let pos = p.pos_of("exponent");
    let n = p.float("exponent", 30.0)?;
    if !(n >= 0.0 && n.is_finite()) {
        return Err(p.err_at(pos, format!("exponent {n} must be finite and ≥ 0")));
    }
    if kd.max_value() + ks.max_value() > 1.0 && sum_exceeds_one(&kd, &ks) {
        b.warnings.push(format!(
            "{}:{}: {}: diffuse_reflectance + specular_reflectance exceeds 1: the material creates energy",
            b.doc.file_of(p.node).display(),
            p.node.pos,
            p.node.plugin
        ));
    }
    p.finish()?;
    Ok(if blinn {
        Bsdf::BlinnPhong(BlinnPhong::new(kd, ks, n as f32))
    } else {
        Bsdf::Phong(Phong::new(kd, ks, n as f32))
    })
}

/// kd + ks > 1 in some channel: exactly for constants, by the channel maxima otherwise.
fn sum_exceeds_one(kd: &Texture, ks: &Texture) -> bool {
    match (kd.as_constant(), ks.as_constant()) {
        (Some(a), Some(b)) => (a + b).max_element() > 1.0,
        _ => true,
    }
}

// ---------------------------------------------------------------------------------------------
// Adapters
// ---------------------------------------------------------------------------------------------

/// The nested BSDFs of an adapter (at most two), in document order.
fn nested(
    b: &mut Builder<'_>,
    p: &mut Props<'_>,
    nesting: usize,
    plugin: &str,
) -> Result<Vec<(Bsdf, super::TextPos)>, LoadError> {
    let mut out = Vec::new();
    for (i, n, kind) in p.objects() {
        if kind != Kind::Bsdf {
            continue;
        }
        if out.len() == 2 {
            return Err(p.err_at(
                p.prop_pos(i),
                format!("{plugin}: at most two nested BSDFs can be specified"),
            ));
        }
        p.take(i);
        out.push((build_bsdf(b, n, nesting + 1)?, p.prop_pos(i)));
    }
    Ok(out)
}

/// `blendbsdf` (`src/bsdfs/blendbsdf.cpp`): `weight` (required, clamped to [0, 1]) and
/// exactly two nested BSDFs; f = (1 − w) f₀ + w f₁.
fn blend(b: &mut Builder<'_>, mut p: Props<'_>, nesting: usize) -> Result<Bsdf, LoadError> {
    let bsdfs = nested(b, &mut p, nesting, "blendbsdf")?;
    if !p.has_any("weight") {
        return Err(p.err("blendbsdf: the parameter \"weight\" is required"));
    }
    let w = if is_texture(&p, "weight") {
        texture_param(b, &mut p, "weight", 0.0, false)?
    } else {
        let w = p.float("weight", 0.0)?;
        if !w.is_finite() {
            return Err(p.err_at(p.pos_of("weight"), "blendbsdf: weight must be finite"));
        }
        Texture::from(w as f32)
    };
    if bsdfs.len() != 2 {
        return Err(p.err("blendbsdf: two child BSDFs must be specified"));
    }
    p.finish()?;
    let mut it = bsdfs.into_iter().map(|(b, _)| b);
    let (first, second) = (it.next().unwrap(), it.next().unwrap());
    Ok(Bsdf::Blend(Blend::textured(w, first, second)))
}

/// `twosided` (`src/bsdfs/twosided.cpp`): one nested BSDF for both sides, or two (front,
/// back). Transmissive models cannot be nested.
fn twosided(b: &mut Builder<'_>, mut p: Props<'_>, nesting: usize) -> Result<Bsdf, LoadError> {
    let sides = nested(b, &mut p, nesting, "twosided")?;
    for (bsdf, pos) in &sides {
        if bsdf.flags().intersects(LobeFlags::TRANSMISSION) {
            return Err(p.err_at(
                *pos,
                "twosided: only materials without a transmission component can be nested",
            ));
        }
    }
    if sides.is_empty() {
        return Err(p.err("twosided: a nested one-sided BSDF is required"));
    }
    p.finish()?;
    let front = sides[0].0.clone();
    let back = sides.get(1).map_or_else(|| front.clone(), |s| s.0.clone());
    Ok(Bsdf::TwoSided(TwoSided::new(front, back)))
}

/// The single nested BSDF of `normalmap`/`bumpmap`, and their two options.
fn perturbing(
    b: &mut Builder<'_>,
    p: &mut Props<'_>,
    nesting: usize,
    plugin: &str,
) -> Result<(Bsdf, PerturbOptions), LoadError> {
    let mut bsdfs = nested(b, p, nesting, plugin)?;
    if bsdfs.len() > 1 {
        return Err(p.err_at(
            bsdfs[1].1,
            format!("{plugin}: only a single BSDF child object can be specified"),
        ));
    }
    let Some((nested_bsdf, pos)) = bsdfs.pop() else {
        return Err(p.err(format!(
            "{plugin}: exactly one BSDF child object must be specified"
        )));
    };
    if nested_bsdf.flags().is_null() {
        // (Its shadow rays would need the null transmission in the perturbed frame.)
        return Err(p.err_at(
            pos,
            format!("{plugin}: a mask or null BSDF cannot be nested in it (nest the {plugin} in the mask instead)"),
        ));
    }
    let options = PerturbOptions {
        flip_invalid_normals: p.boolean("flip_invalid_normals", true)?,
        use_shadowing_function: p.boolean("use_shadowing_function", true)?,
    };
    Ok((nested_bsdf, options))
}

/// `normalmap` (`src/bsdfs/normalmap.cpp`): the texture `normalmap` (required) and one
/// nested BSDF.
fn normal_map(b: &mut Builder<'_>, mut p: Props<'_>, nesting: usize) -> Result<Bsdf, LoadError> {
    let (nested_bsdf, options) = perturbing(b, &mut p, nesting, "normalmap")?;
    if !p.has_any("normalmap") {
        return Err(p.err("normalmap: the parameter \"normalmap\" (a texture) is required"));
    }
    let normals = texture_param(b, &mut p, "normalmap", 0.5, true)?;
    p.finish()?;
    Ok(Bsdf::NormalMap(NormalMap::new(
        normals,
        nested_bsdf,
        options,
    )))
}

/// `bumpmap` (`src/bsdfs/bumpmap.cpp`): one nested texture of any name (the height), one
/// nested BSDF, `scale` (1).
fn bump_map(b: &mut Builder<'_>, mut p: Props<'_>, nesting: usize) -> Result<Bsdf, LoadError> {
    let (nested_bsdf, options) = perturbing(b, &mut p, nesting, "bumpmap")?;
    let mut height = None;
    for (i, n, kind) in p.objects() {
        if kind != Kind::Texture {
            continue;
        }
        if height.is_some() {
            return Err(p.err_at(
                p.prop_pos(i),
                "bumpmap: only a single Texture child object can be specified",
            ));
        }
        p.take(i);
        let t = build_texture(b, n, 1)?;
        if t.eval_1_grad(&ShadingPoint::default()).is_none() {
            return Err(p.err_at(
                p.prop_pos(i),
                "bumpmap: the height texture has no gradient (use a bitmap; Mitsuba's checkerboard does not implement eval_1_grad)",
            ));
        }
        height = Some(t);
    }
    let Some(height) = height else {
        return Err(p.err("bumpmap: exactly one Texture child object must be specified"));
    };
    let scale = p.float("scale", 1.0)?;
    if !scale.is_finite() {
        return Err(p.err_at(p.pos_of("scale"), "bumpmap: scale must be finite"));
    }
    p.finish()?;
    Ok(Bsdf::BumpMap(BumpMap::new(
        height,
        scale as f32,
        nested_bsdf,
        options,
    )))
}

/// `mask` (`src/bsdfs/mask.cpp`): `opacity` (float, colour or texture, default 0.5; its
/// `eval_1`, clamped to [0, 1]) and exactly one nested BSDF.
fn mask(b: &mut Builder<'_>, mut p: Props<'_>, nesting: usize) -> Result<Bsdf, LoadError> {
    let mut bsdfs = nested(b, &mut p, nesting, "mask")?;
    if bsdfs.len() > 1 {
        return Err(p.err_at(bsdfs[1].1, "mask: cannot specify more than one child BSDF"));
    }
    let Some((nested_bsdf, _)) = bsdfs.pop() else {
        return Err(p.err("mask: a child BSDF must be specified"));
    };
    let opacity = texture_param(b, &mut p, "opacity", 0.5, false)?;
    p.finish()?;
    Ok(Bsdf::Mask(Mask::new(opacity, nested_bsdf)))
}

#[cfg(test)]
mod tests {
    //! The BSDF plugins' parameters: defaults, alternatives and errors. (Loading whole
    //! scenes is tested in `loader/tests.rs`.)
    use crate::mitsuba::load_mitsuba_xml_with_warnings;
    use glam::{Vec2, Vec3};
    use radia_bsdf::{Bsdf, ShadingPoint};
    use radia_scene::SceneDescription;

    /// A scene with one sphere whose BSDF is `bsdf` (XML), loaded from a temporary file.
    fn load(bsdf: &str) -> Result<(SceneDescription, Vec<String>), String> {
        let xml = format!(
            r#"<scene version="3.0.0">
<sensor type="perspective"><film type="hdrfilm"><integer name="width" value="4"/><integer name="height" value="4"/></film></sensor>
<shape type="sphere">{bsdf}</shape>
</scene>"#
        );
        // A folder per call (tests run on several threads), removed once loaded.
        let n = COUNTER.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        let dir =
            std::env::temp_dir().join(format!("radia-bsdf-loader-{}-{n}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("scene.xml");
        std::fs::write(&path, xml).unwrap();
        let r = load_mitsuba_xml_with_warnings(&path, &[]).map_err(|e| e.to_string());
        let _ = std::fs::remove_dir_all(&dir);
        r
    }

    static COUNTER: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);

    fn bsdf(xml: &str) -> Bsdf {
        match load(xml) {
            Ok((s, _)) => s.shapes[0].bsdf.clone(),
            Err(e) => panic!("{xml}: {e}"),
        }
    }

    #[track_caller]
    fn load_err(xml: &str, needle: &str) {
        match load(xml) {
            Ok(_) => panic!("{xml} loaded, expected an error containing {needle:?}"),
            Err(e) => assert!(e.contains(needle), "{xml}: error {e:?} lacks {needle:?}"),
        }
    }

    const SP: ShadingPoint = ShadingPoint::at_uv(Vec2::ZERO);

    #[test]
    fn loader_bsdfs_conductors() {
        let Bsdf::RoughConductor(r) = bsdf(r#"<bsdf type="roughconductor"/>"#) else {
            panic!()
        };
        // Mitsuba's defaults: Beckmann, α 0.1, visible normals, material "none".
        assert_eq!(
            r.distribution,
            radia_bsdf::MicrofacetDistribution::new(
                radia_bsdf::MicrofacetType::Beckmann,
                0.1,
                0.1,
                true
            )
        );
        assert_eq!((r.eta, r.k), (Vec3::ZERO, Vec3::ONE));
        let Bsdf::RoughConductor(r) = bsdf(
            r#"<bsdf type="roughconductor"><string name="distribution" value="GGX"/><float name="alpha_u" value="0.05"/><float name="alpha_v" value="0.3"/><string name="material" value="Au"/><boolean name="sample_visible" value="false"/></bsdf>"#,
        ) else {
            panic!()
        };
        assert_eq!(r.distribution.kind, radia_bsdf::MicrofacetType::Ggx);
        assert_eq!(
            (
                r.distribution.alpha_u,
                r.distribution.alpha_v,
                r.distribution.sample_visible
            ),
            (0.05, 0.3, false)
        );
        assert!((r.eta.x - 0.143036).abs() < 1e-5 && (r.k.z - 1.60336).abs() < 1e-5);
        let Bsdf::RoughConductor(r) = bsdf(
            r#"<bsdf type="roughconductor"><rgb name="eta" value="0.2, 0.9, 1.1"/><float name="k" value="3"/></bsdf>"#,
        ) else {
            panic!()
        };
        assert_eq!((r.eta, r.k), (Vec3::new(0.2, 0.9, 1.1), Vec3::splat(3.0)));
        let Bsdf::Conductor(c) = bsdf(
            r#"<bsdf type="conductor"><string name="material" value="Cu"/><rgb name="specular_reflectance" value="0.5"/></bsdf>"#,
        ) else {
            panic!()
        };
        assert!((c.k.x - 3.91326).abs() < 1e-5);
        let s = Bsdf::Conductor(c)
            .sample(&SP, Vec3::Z, 0.5, Vec2::splat(0.5))
            .unwrap();
        assert!(s.weight.max_element() <= 0.5);

        load_err(
            r#"<bsdf type="conductor"><string name="material" value="Au"/><float name="eta" value="1"/></bsdf>"#,
            "not both",
        );
        load_err(
            r#"<bsdf type="conductor"><string name="material" value="Unobtainium"/></bsdf>"#,
            "unknown conductor material",
        );
        load_err(
            r#"<bsdf type="roughconductor"><float name="alpha" value="0.1"/><float name="alpha_u" value="0.1"/><float name="alpha_v" value="0.1"/></bsdf>"#,
            "either 'alpha'",
        );
        load_err(
            r#"<bsdf type="roughconductor"><float name="alpha_u" value="0.1"/></bsdf>"#,
            "both 'alpha_u' and 'alpha_v'",
        );
        load_err(
            r#"<bsdf type="roughconductor"><string name="distribution" value="phong"/></bsdf>"#,
            "invalid distribution",
        );
        load_err(
            r#"<bsdf type="roughconductor"><float name="alpah" value="0.1"/></bsdf>"#,
            "alpah",
        );
        load_err(
            r#"<bsdf type="roughconductor"><rgb name="specular_reflectance" value="2"/></bsdf>"#,
            "range [0, 1]",
        );
    }

    #[test]
    fn loader_bsdfs_dielectrics() {
        let Bsdf::Dielectric(d) = bsdf(r#"<bsdf type="dielectric"/>"#) else {
            panic!()
        };
        // bk7 inside, air (1.000277) outside.
        assert!((d.eta - 1.5046 / 1.000277).abs() < 1e-6);
        let Bsdf::Dielectric(d) = bsdf(
            r#"<bsdf type="dielectric"><string name="int_ior" value="Water"/><float name="ext_ior" value="1"/></bsdf>"#,
        ) else {
            panic!()
        };
        assert_eq!(d.eta, 1.333);
        let Bsdf::ThinDielectric(t) = bsdf(
            r#"<bsdf type="thindielectric"><float name="int_ior" value="1.5"/><float name="ext_ior" value="1"/></bsdf>"#,
        ) else {
            panic!()
        };
        assert_eq!(t.eta, 1.5);
        let Bsdf::RoughDielectric(r) = bsdf(
            r#"<bsdf type="roughdielectric"><string name="distribution" value="ggx"/><float name="alpha" value="0.3"/><string name="int_ior" value="diamond"/></bsdf>"#,
        ) else {
            panic!()
        };
        assert!((r.eta - 2.419 / 1.000277).abs() < 1e-6);
        assert_eq!(r.distribution.alpha_u, 0.3);

        load_err(
            r#"<bsdf type="dielectric"><string name="int_ior" value="glass"/></bsdf>"#,
            "unable to find an IOR value for \"glass\"",
        );
        load_err(
            r#"<bsdf type="dielectric"><float name="int_ior" value="-1"/></bsdf>"#,
            "must be positive",
        );
        load_err(
            r#"<bsdf type="roughdielectric"><float name="int_ior" value="1.2"/><float name="ext_ior" value="1.2"/></bsdf>"#,
            "must be positive and differ",
        );
        // Transmissive models cannot be two-sided.
        load_err(
            r#"<bsdf type="twosided"><bsdf type="dielectric"/></bsdf>"#,
            "transmission",
        );
        load_err(
            r#"<bsdf type="twosided"><bsdf type="thindielectric"/></bsdf>"#,
            "transmission",
        );
    }

    #[test]
    fn loader_bsdfs_plastics_and_adapters() {
        let Bsdf::Plastic(p) = bsdf(r#"<bsdf type="plastic"/>"#) else {
            panic!()
        };
        assert!((p.eta - 1.49 / 1.000277).abs() < 1e-6);
        let Bsdf::RoughPlastic(r) = bsdf(
            r#"<bsdf type="roughplastic"><string name="distribution" value="ggx"/><float name="alpha" value="0.2"/><float name="int_ior" value="1.5"/><float name="ext_ior" value="1"/></bsdf>"#,
        ) else {
            panic!()
        };
        // The table Mitsuba 3.9.1 computes for these parameters (MITSUBA-SEMANTICS.md).
        assert!((r.internal_reflectance() - 0.4863).abs() < 5e-4);
        load_err(
            r#"<bsdf type="roughplastic"><float name="alpha_u" value="0.1"/><float name="alpha_v" value="0.2"/></bsdf>"#,
            "anisotropic",
        );

        let Bsdf::Blend(b) = bsdf(
            r#"<bsdf type="blendbsdf"><float name="weight" value="0.3"/><bsdf type="diffuse"/><bsdf type="roughconductor"/></bsdf>"#,
        ) else {
            panic!()
        };
        assert_eq!(b.weight, 0.3);
        assert!(
            matches!(b.bsdfs[0], Bsdf::Diffuse(_)) && matches!(b.bsdfs[1], Bsdf::RoughConductor(_))
        );
        let Bsdf::Blend(b) = bsdf(
            r#"<bsdf type="blendbsdf"><float name="weight" value="1.5"/><bsdf type="diffuse"/><bsdf type="diffuse"/></bsdf>"#,
        ) else {
            panic!()
        };
        assert_eq!(b.weight, 1.0);
        load_err(
            r#"<bsdf type="blendbsdf"><bsdf type="diffuse"/><bsdf type="diffuse"/></bsdf>"#,
            "\"weight\" is required",
        );
        load_err(
            r#"<bsdf type="blendbsdf"><float name="weight" value="0.5"/><bsdf type="diffuse"/></bsdf>"#,
            "two child BSDFs",
        );
        load_err(
            r#"<bsdf type="blendbsdf"><float name="weight" value="0.5"/><bsdf type="diffuse"/><bsdf type="diffuse"/><bsdf type="diffuse"/></bsdf>"#,
            "at most two",
        );

        let Bsdf::TwoSided(t) = bsdf(
            r#"<bsdf type="twosided"><bsdf type="roughconductor"/><bsdf type="diffuse"/></bsdf>"#,
        ) else {
            panic!()
        };
        assert!(
            matches!(t.sides[0], Bsdf::RoughConductor(_)) && matches!(t.sides[1], Bsdf::Diffuse(_))
        );
    }

    #[test]
    fn loader_bsdfs_radia_models() {
        let Bsdf::Phong(p) =
            bsdf(r#"<bsdf type="phong"><float name="exponent" value="12"/></bsdf>"#)
        else {
            panic!()
        };
        assert_eq!(p.exponent, 12.0);
        let Bsdf::BlinnPhong(p) = bsdf(r#"<bsdf type="blinnphong"/>"#) else {
            panic!()
        };
        assert_eq!(p.exponent, 30.0);
        load_err(
            r#"<bsdf type="phong"><float name="exponent" value="-1"/></bsdf>"#,
            "exponent",
        );
        let (_, warnings) = load(r#"<bsdf type="phong"><float name="diffuse_reflectance" value="0.9"/><float name="specular_reflectance" value="0.5"/></bsdf>"#).unwrap();
        assert!(
            warnings.iter().any(|w| w.contains("creates energy")),
            "{warnings:?}"
        );

        let Bsdf::CookTorrance(c) = bsdf(
            r#"<bsdf type="cooktorrance"><float name="roughness" value="0.5"/><rgb name="base_color" value="0.9, 0.6, 0.3"/><float name="metallic" value="1"/></bsdf>"#,
        ) else {
            panic!()
        };
        // glTF: α = roughness², GGX.
        assert_eq!(c.distribution().alpha_u, 0.25);
        assert_eq!(c.distribution().kind, radia_bsdf::MicrofacetType::Ggx);
        let Bsdf::CookTorrance(c) = bsdf(
            r#"<bsdf type="cooktorrance"><rgb name="F0" value="0.9"/><boolean name="height_correlated" value="true"/></bsdf>"#,
        ) else {
            panic!()
        };
        assert_eq!(
            c.shadowing(),
            radia_bsdf::microfacet::Shadowing::HeightCorrelated
        );
        load_err(
            r#"<bsdf type="cooktorrance"><rgb name="F0" value="0.9"/><float name="metallic" value="1"/></bsdf>"#,
            "not both",
        );
        load_err(
            r#"<bsdf type="cooktorrance"><float name="metallic" value="2"/></bsdf>"#,
            "[0, 1]",
        );
        load_err(
            r#"<bsdf type="cooktorrance"><float name="alpha" value="0.1"/><float name="roughness" value="0.1"/></bsdf>"#,
            "either 'alpha'",
        );
        load_err(
            r#"<bsdf type="velvet"/>"#,
            "unsupported BSDF plugin type \"velvet\"",
        );
    }

    #[test]
    fn loader_bsdfs_principled() {
        let Bsdf::Principled(m) = bsdf(r#"<bsdf type="principled"/>"#) else {
            panic!()
        };
        // Mitsuba's defaults: base 0.5, roughness 0.5, specular 0.5 (η 1.5), no optional lobe.
        assert_eq!(m.base_color.as_constant(), Some(Vec3::splat(0.5)));
        assert!((m.eta - 1.5).abs() < 1e-6);
        assert!(m.metallic.is_none() && m.spec_trans.is_none() && m.clearcoat.is_none());
        assert_eq!(
            m.flags(),
            radia_bsdf::LobeFlags::DIFFUSE_REFLECTION | radia_bsdf::LobeFlags::GLOSSY_REFLECTION
        );
        let Bsdf::Principled(m) = bsdf(
            r#"<bsdf type="principled"><rgb name="base_color" value="0.8, 0.2, 0.1"/><float name="metallic" value="0"/><float name="spec_trans" value="0.6"/><float name="eta" value="1"/><float name="clearcoat" value="0.5"/><float name="clearcoat_gloss" value="0.3"/><float name="main_specular_sampling_rate" value="2"/><texture type="checkerboard" name="roughness"/><float name="anisotropic" value="0.5"/><float name="sheen" value="0.2"/><float name="sheen_tint" value="0.2"/><float name="spec_tint" value="0.2"/><float name="flatness" value="0.2"/><float name="clearcoat_sampling_rate" value="0.5"/><float name="diffuse_reflectance_sampling_rate" value="0.5"/></bsdf>"#,
        ) else {
            panic!()
        };
        // A float 0 turns its lobe off (Mitsuba's get_flag); η = 1 with transmission is 1.001.
        assert!(m.metallic.is_none() && m.spec_trans.is_some() && m.clearcoat.is_some());
        assert_eq!(m.eta, 1.001);
        assert_eq!(
            (m.spec_srate, m.clearcoat_srate, m.diff_refl_srate),
            (2.0, 0.5, 0.5)
        );
        assert!(!m.roughness.is_constant());
        assert!(m
            .flags()
            .intersects(radia_bsdf::LobeFlags::GLOSSY_TRANSMISSION));
        let Bsdf::Principled(m) =
            bsdf(r#"<bsdf type="principled"><float name="specular" value="0.2"/></bsdf>"#)
        else {
            panic!()
        };
        assert!((m.eta - (2.0 / (1.0 - (0.016f32).sqrt()) - 1.0)).abs() < 1e-6);

        load_err(
            r#"<bsdf type="principled"><float name="eta" value="1.5"/><float name="specular" value="0.5"/></bsdf>"#,
            "either use \"eta\" or \"specular\"",
        );
        load_err(
            r#"<bsdf type="principled"><float name="metallic" value="1.5"/></bsdf>"#,
            "\"metallic\" must be in [0, 1]",
        );
        load_err(
            r#"<bsdf type="principled"><rgb name="base_color" value="1.5, 0, 0"/></bsdf>"#,
            "range [0, 1]",
        );
        load_err(
            r#"<bsdf type="principled"><float name="eta" value="-1"/></bsdf>"#,
            "\"eta\" must be a finite number > 0",
        );
        load_err(
            r#"<bsdf type="principled"><float name="specular" value="20"/></bsdf>"#,
            "\"specular\" must be in [0, 12.5)",
        );
        load_err(
            r#"<bsdf type="principled"><float name="clearcoat_sampling_rate" value="-1"/></bsdf>"#,
            "must be a finite number >= 0",
        );
        load_err(
            r#"<bsdf type="principled"><float name="main_specular_sampling_rate" value="0"/><float name="diffuse_reflectance_sampling_rate" value="0"/></bsdf>"#,
            "cannot both be 0",
        );
        load_err(
            r#"<bsdf type="principled"><float name="metalic" value="1"/></bsdf>"#,
            "metalic",
        );
        load_err(
            r#"<bsdf type="twosided"><bsdf type="principled"><float name="spec_trans" value="1"/></bsdf></bsdf>"#,
            "transmission",
        );
    }

    #[test]
    fn loader_bsdfs_principled_thin() {
        let Bsdf::PrincipledThin(m) = bsdf(r#"<bsdf type="principledthin"/>"#) else {
            panic!()
        };
        assert_eq!(m.eta.as_constant(), Some(Vec3::splat(1.5)));
        assert!(m.spec_trans.is_none() && m.diff_trans.is_none());
        let Bsdf::PrincipledThin(m) = bsdf(
            r#"<bsdf type="principledthin"><float name="diff_trans" value="1.5"/><float name="spec_trans" value="0.3"/><float name="eta" value="1.33"/><float name="specular_transmittance_sampling_rate" value="2"/><float name="sheen" value="0"/></bsdf>"#,
        ) else {
            panic!()
        };
        assert!(m.diff_trans.is_some() && m.spec_trans.is_some() && m.sheen.is_none());
        assert_eq!((m.spec_trans_srate, m.spec_refl_srate), (2.0, 1.0));
        load_err(
            r#"<bsdf type="principledthin"><float name="diff_trans" value="2.5"/></bsdf>"#,
            "\"diff_trans\" must be in [0, 2]",
        );
        load_err(
            r#"<bsdf type="principledthin"><float name="eta" value="0"/></bsdf>"#,
            "\"eta\" must be > 0",
        );
        load_err(
            r#"<bsdf type="principledthin"><float name="clearcoat" value="0.5"/></bsdf>"#,
            "clearcoat",
        );
        // Mitsuba's principledthin always has a diffuse transmission lobe: not two-sided.
        load_err(
            r#"<bsdf type="twosided"><bsdf type="principledthin"/></bsdf>"#,
            "transmission",
        );
    }

    #[test]
    fn loader_bsdfs_mask_and_null() {
        let sp = ShadingPoint::at_uv(Vec2::new(0.25, 0.25));
        // The default opacity is 0.5.
        let b = bsdf(r#"<bsdf type="mask"><bsdf type="diffuse"/></bsdf>"#);
        let Bsdf::Mask(m) = &b else { panic!("{b:?}") };
        assert!(matches!(*m.nested, Bsdf::Diffuse(_)));
        assert_eq!(b.null_transmission(&sp), 0.5);
        let b = bsdf(
            r#"<bsdf type="mask"><float name="opacity" value="0.2"/><bsdf type="twosided"><bsdf type="diffuse"/></bsdf></bsdf>"#,
        );
        assert!((b.null_transmission(&sp) - 0.8).abs() < 1e-6);
        // Values out of [0, 1] are clamped.
        let b = bsdf(
            r#"<bsdf type="mask"><float name="opacity" value="1.5"/><bsdf type="diffuse"/></bsdf>"#,
        );
        assert_eq!(b.null_transmission(&sp), 0.0);
        // A texture (a checkerboard's scalar lookup has color0 where the parities of 2u and
        // 2v differ, as Mitsuba's `eval_1`).
        let b = bsdf(
            r#"<bsdf type="mask"><texture type="checkerboard" name="opacity"><float name="color0" value="1"/><float name="color1" value="0"/></texture><bsdf type="diffuse"/></bsdf>"#,
        );
        assert_eq!(b.null_transmission(&sp), 1.0);
        assert_eq!(
            b.null_transmission(&ShadingPoint::at_uv(Vec2::new(0.75, 0.25))),
            0.0
        );
        assert!(matches!(bsdf(r#"<bsdf type="null"/>"#), Bsdf::Null(_)));
        load_err(
            r#"<bsdf type="mask"/>"#,
            "mask: a child BSDF must be specified",
        );
        load_err(
            r#"<bsdf type="mask"><bsdf type="diffuse"/><bsdf type="diffuse"/></bsdf>"#,
            "more than one child BSDF",
        );
        load_err(
            r#"<bsdf type="mask"><float name="opacities" value="1"/><bsdf type="diffuse"/></bsdf>"#,
            "opacities",
        );
        load_err(
            r#"<bsdf type="null"><float name="opacity" value="1"/></bsdf>"#,
            "opacity",
        );
        // twosided refuses transmission, null included, as Mitsuba's; normalmap refuses a
        // null lobe (radia).
        load_err(
            r#"<bsdf type="twosided"><bsdf type="mask"><bsdf type="diffuse"/></bsdf></bsdf>"#,
            "without a transmission component",
        );
        load_err(
            r#"<bsdf type="normalmap"><rgb name="normalmap" value="0.5, 0.5, 1"/><bsdf type="null"/></bsdf>"#,
            "cannot be nested",
        );
    }
}
