//! The `<transform>` operations, in double precision as Mitsuba parses them
//! (`src/core/parser.cpp`, `include/mitsuba/core/transform.h`, Dr.Jit's `transform.h`).
//! Every function returns the matrix of one operation; the parser composes them in document
//! order, M = T_last ⋯ T_first.

use glam::{DMat3, DMat4, DVec3, DVec4};

pub(crate) fn translate(v: DVec3) -> DMat4 {
    DMat4::from_translation(v)
}

pub(crate) fn scale(v: DVec3) -> DMat4 {
    DMat4::from_scale(v)
}

/// Rotation by `angle_deg` degrees about `axis`, right-handed. As in Dr.Jit's `rotate`, the
/// axis is used as given (Mitsuba does not normalize it).
pub(crate) fn rotate(axis: DVec3, angle_deg: f64) -> DMat4 {
    let (s, c) = angle_deg.to_radians().sin_cos();
    let k = 1.0 - c;
    let (x, y, z) = (axis.x, axis.y, axis.z);
    // Rows of the 3x3 rotation (Rodrigues' formula).
    let r0 = DVec3::new(x * x * k + c, x * y * k - z * s, x * z * k + y * s);
    let r1 = DVec3::new(y * x * k + z * s, y * y * k + c, y * z * k - x * s);
    let r2 = DVec3::new(z * x * k - y * s, z * y * k + x * s, z * z * k + c);
    DMat4::from_mat3(DMat3::from_cols(r0, r1, r2).transpose())
}

/// A 4x4 matrix given row by row (the order of `<matrix value="...">`).
pub(crate) fn from_rows(rows: [[f64; 4]; 4]) -> DMat4 {
    DMat4::from_cols(
        DVec4::from_array(rows[0]),
        DVec4::from_array(rows[1]),
        DVec4::from_array(rows[2]),
        DVec4::from_array(rows[3]),
    )
    .transpose()
}

/// Duff et al.'s orthonormal basis around the unit vector `n` (Mitsuba's `coordinate_system`).
pub(crate) fn coordinate_system(n: DVec3) -> (DVec3, DVec3) {
    let sign = if n.z >= 0.0 { 1.0 } else { -1.0 };
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    (
        DVec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x),
        DVec3::new(b, sign + n.y * n.y * a, -n.y),
    )
}

/// Mitsuba's `look_at`: columns (left, up', dir, origin) with dir = normalize(target − origin),
/// left = normalize(up × dir), up' = dir × left. A zero `up` is replaced by a vector
/// perpendicular to dir. `None` when the result is not finite (target = origin, or up ∥ dir).
pub(crate) fn look_at(origin: DVec3, target: DVec3, up: DVec3) -> Option<DMat4> {
    let dir = (target - origin).normalize();
    let up = if up == DVec3::ZERO {
        coordinate_system(dir).0
    } else {
        up
    };
    let left = up.cross(dir).normalize();
    let new_up = dir.cross(left);
    let m = DMat4::from_cols(
        left.extend(0.0),
        new_up.extend(0.0),
        dir.extend(0.0),
        origin.extend(1.0),
    );
    m.is_finite().then_some(m)
}

/// The upper-left 3x3 block.
pub(crate) fn linear_part(m: &DMat4) -> DMat3 {
    DMat3::from_mat4(*m)
}

/// True when the bottom row is (0, 0, 0, 1).
pub(crate) fn is_affine(m: &DMat4) -> bool {
    m.row(3) == DVec4::new(0.0, 0.0, 0.0, 1.0)
}

/// Mitsuba's `Transform::has_scale`: the linear part is not orthonormal (tolerance 1e-3).
pub(crate) fn has_scale(m: &DMat4) -> bool {
    let l = linear_part(m);
    let cols = [l.x_axis, l.y_axis, l.z_axis];
    for i in 0..3 {
        for j in i..3 {
            let expected = if i == j { 1.0 } else { 0.0 };
            if (cols[i].dot(cols[j]) - expected).abs() > 1e-3 {
                return true;
            }
        }
    }
    false
}
