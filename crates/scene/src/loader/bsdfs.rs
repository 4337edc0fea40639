//! BSDF plugins: one function per Mitsuba plugin name, dispatched in [`build_bsdf`].
//! To add a model, add an arm to the `match` and a function that reads its parameters
//! through [`Props`] (every parameter it does not read is reported as unknown).

use super::build::Builder;
use super::props::Props;
use super::xml::Kind;
use super::LoadError;
use glam::Vec3;
use radia_bsdf::{Bsdf, Diffuse, LobeFlags, TwoSided};

/// Nested BSDFs (twosided of twosided ...) deeper than this are refused.
const MAX_NESTING: usize = 32;

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
        "diffuse" => diffuse(p)?,
        "twosided" => twosided(b, p, nesting)?,
        other => {
            return Err(p.err(format!(
                "unsupported BSDF plugin type \"{other}\" (radia supports: diffuse, twosided)"
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
fn diffuse(mut p: Props<'_>) -> Result<Bsdf, LoadError> {
    let r = p.color("reflectance", 0.5, true)?;
    p.finish()?;
    Ok(Bsdf::Diffuse(Diffuse::new(r.as_vec3())))
}

/// `twosided` (`src/bsdfs/twosided.cpp`): one nested BSDF for both sides, or two (front,
/// back). Transmissive models cannot be nested.
fn twosided(b: &mut Builder<'_>, mut p: Props<'_>, nesting: usize) -> Result<Bsdf, LoadError> {
    let mut sides = Vec::new();
    for (i, n, kind) in p.objects() {
        if kind != Kind::Bsdf {
            continue;
        }
        if sides.len() == 2 {
            return Err(p.err_at(
                p.prop_pos(i),
                "twosided: at most two nested BSDFs can be specified",
            ));
        }
        p.take(i);
        let bsdf = build_bsdf(b, n, nesting + 1)?;
        if bsdf.flags().intersects(LobeFlags::TRANSMISSION) {
            return Err(p.err_at(
                p.prop_pos(i),
                "twosided: only materials without a transmission component can be nested",
            ));
        }
        sides.push(bsdf);
    }
    if sides.is_empty() {
        return Err(p.err("twosided: a nested one-sided BSDF is required"));
    }
    p.finish()?;
    // `sides` holds one or two models (checked above).
    let front = sides[0].clone();
    let back = sides.get(1).cloned().unwrap_or_else(|| front.clone());
    Ok(Bsdf::TwoSided(TwoSided::new(front, back)))
}
