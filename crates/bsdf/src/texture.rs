use crate::ShadingPoint;
use radia_math::Spectrum;

/// A spatially varying parameter. Only constants so far; bitmaps and procedural textures
/// join as variants, evaluated at the [`ShadingPoint`]'s uv.
#[derive(Clone, Debug, PartialEq)]
pub enum Texture {
    Constant(Spectrum),
}

impl Texture {
    #[inline]
    pub fn eval(&self, _sp: &ShadingPoint) -> Spectrum {
        match self {
            Texture::Constant(c) => *c,
        }
    }

    /// The mean over the texture and the three channels (Mitsuba's `Texture::mean()`), for
    /// lobe sampling weights fixed at load time.
    pub fn mean(&self) -> f32 {
        match self {
            Texture::Constant(c) => crate::mean(*c),
        }
    }

    /// True when the texture has the same value everywhere.
    pub fn is_constant(&self) -> bool {
        matches!(self, Texture::Constant(_))
    }
}

impl From<Spectrum> for Texture {
    fn from(c: Spectrum) -> Self {
        Texture::Constant(c)
    }
}
