use crate::Vec3;

/// A ray `o + t d` for t in (0, `t_max`). `d` need not be normalized, but every ray the
/// integrator traces has a unit direction so `t` is a distance.
#[derive(Clone, Copy, Debug)]
pub struct Ray {
    pub o: Vec3,
    pub d: Vec3,
    pub t_max: f32,
}

impl Ray {
    #[inline]
    pub fn new(o: Vec3, d: Vec3, t_max: f32) -> Self {
        Self { o, d, t_max }
    }

    #[inline]
    pub fn at(&self, t: f32) -> Vec3 {
        self.o + self.d * t
    }
}
