//! The surface interactions of a packet's hits on mesh triangles, spheres and disks, sixteen
//! at once.
//!
//! [`Shape::interaction`](super::Shape::interaction) computed one lane after another is a
//! chain of three square roots and three divisions per hit, which a core runs one lane at a
//! time: 14% of a Cornell-box render at one thread. Here the hits' vertices, normals and
//! texture coordinates are gathered into lanes and the same formulas run over all of them
//! at once ([`radia_math::lanes`], whose operations are the scalar ones in the same order),
//! so every lane holds bit for bit what `Shape::interaction` gives.
//!
//! Lanes that would take a rare branch of the scalar code (tangent frames of normal-mapped
//! glTF meshes, a degenerate uv triangle, a shading frame whose tangent vanishes, a sphere's
//! pole or a disk's centre, where their atan2 defers to the C library) are left to it: the
//! `interactions` methods return them. Measured at one thread against the lane-by-lane
//! interactions: the Cornell box 0.915× the time, `scenes/furnace.xml` (one sphere) 0.82×,
//! `scenes/glass.xml` 0.885×.

use crate::description::Mesh;
use crate::shape::SurfaceInteraction;
use crate::{PacketHits, RayPacket, PACKET_LANES};
use glam::Vec3;
use radia_math::float::gamma;
use radia_math::lanes::{self, f32x16, lanes_of, mask, Mat3s, Vec3s, WIDTH};
use radia_math::real::{FrameR, Vector2};
use radia_math::{INV_TWO_PI, PI};

const _: () = assert!(WIDTH == PACKET_LANES);

type Rows = [[f32; WIDTH]; 3];

/// shape.rs' `triangle_point` in lanes: v0 + b1·e1 + b2·e2 and its error bound.
#[inline(always)]
pub(super) fn triangle_point(
    v0: Vec3s,
    e1: Vec3s,
    e2: Vec3s,
    b1: f32x16,
    b2: f32x16,
) -> (Vec3s, Vec3s) {
    let p = v0 + (e1 * b1 + e2 * b2);
    let extent = (e1.abs() + e2.abs()).max_element();
    let slack = extent * f32x16::splat(gamma(32));
    (
        p,
        p.abs() * f32x16::splat(gamma(1)) + Vec3s::splat_lanes(slack),
    )
}

/// The hits of a packet on mesh triangles, gathered lane by lane ([`MeshHits::push`]).
pub(crate) struct MeshHits {
    /// Lanes pushed.
    lanes: u32,
    /// The primitive each lane hit (0 in the others: a valid index to gather from).
    prim: [u32; WIDTH],
    /// Lanes whose mesh has shading normals, and the normals of their three vertices.
    with_normals: u32,
    normals: [Rows; 3],
    /// Lanes whose mesh has texture coordinates, and those of their three vertices:
    /// `uvs[k][0 or 1][lane]`.
    with_uvs: u32,
    uvs: [[[f32; WIDTH]; 2]; 3],
    /// Lanes whose mesh has `flip_normals`.
    flipped: u32,
    shape: [u32; WIDTH],
    face: [u32; WIDTH],
}

impl MeshHits {
    pub(crate) fn new() -> Self {
        Self {
            lanes: 0,
            prim: [0; WIDTH],
            with_normals: 0,
            normals: [[[0.0; WIDTH]; 3]; 3],
            with_uvs: 0,
            uvs: [[[0.0; WIDTH]; 2]; 3],
            flipped: 0,
            shape: [0; WIDTH],
            face: [0; WIDTH],
        }
    }

    /// Whether [`MeshHits::push`] takes hits on `mesh` (normal-mapped glTF meshes, with
    /// tangents, are left to the scalar code).
    #[inline(always)]
    pub(crate) fn takes(mesh: &Mesh) -> bool {
        mesh.tangents.is_none()
    }

    /// Lane `lane` hit triangle `face` of `mesh` (shape `shape`), primitive `prim` of the
    /// BVH (whose copy of the vertices the scalar code reads too).
    #[inline(always)]
    pub(crate) fn push(&mut self, lane: usize, mesh: &Mesh, shape: u32, face: u32, prim: u32) {
        let bit = 1 << lane;
        self.lanes |= bit;
        self.shape[lane] = shape;
        self.face[lane] = face;
        self.prim[lane] = prim;
        let idx = mesh.indices[face as usize];
        if let Some(ns) = &mesh.normals {
            self.with_normals |= bit;
            for (k, &i) in idx.iter().enumerate() {
                let n = ns[i as usize];
                for axis in 0..3 {
                    self.normals[k][axis][lane] = n[axis];
                }
            }
        }
        if let Some(uvs) = &mesh.uvs {
            self.with_uvs |= bit;
            for (k, &i) in idx.iter().enumerate() {
                let uv = uvs[i as usize];
                self.uvs[k][0][lane] = uv.x;
                self.uvs[k][1][lane] = uv.y;
            }
        }
        if mesh.flip_normals {
            self.flipped |= bit;
        }
    }

    /// Writes the interactions of the pushed lanes to `out` (their hits in `hits`, their
    /// rays in `rays`), as `Shape::interaction` computes them, and returns the lanes left to
    /// it (see the module docs), whose `out` is untouched.
    #[inline(always)]
    pub(crate) fn interactions(
        &self,
        accel: &crate::Accel,
        hits: &PacketHits,
        rays: &RayPacket,
        out: &mut SurfaceLanes,
    ) -> u32 {
        if self.lanes == 0 {
            return 0;
        }
        let v = accel.triangles(&self.prim);
        let b1 = f32x16::new(hits.bary.map(|b| b.x));
        let b2 = f32x16::new(hits.bary.map(|b| b.y));
        let b0 = f32x16::ONE - b1 - b2;
        let dp0 = v[1] - v[0];
        let dp1 = v[2] - v[0];

        // The point and its error bound.
        let (p, p_error) = triangle_point(v[0], dp0, dp1, b1, b2);

        // Normals: geometric, and interpolated where the mesh has them (falling back to the
        // geometric one where the interpolation is not finite).
        let n_face = dp0.cross(dp1).normalize();
        let ns = self.normals.map(|rows| Vec3s::from_rows(&rows));
        let s = (ns[0] * b0 + ns[1] * b1 + ns[2] * b2).normalize();
        let sh_n = Vec3s::select(mask(self.with_normals) & s.is_finite(), s, n_face);
        let flip = mask(self.flipped);
        let n = Vec3s::select(flip, -n_face, n_face);
        let sh_n = Vec3s::select(flip, -sh_n, sh_n);

        // uv and ∂p/∂u, ∂p/∂v (Mitsuba's `mesh.cpp`; barycentric without texture
        // coordinates). A degenerate uv triangle is left to the scalar code.
        let t = self.uvs.map(|[u, v]| (f32x16::new(u), f32x16::new(v)));
        let uv_u = t[0].0 * b0 + t[1].0 * b1 + t[2].0 * b2;
        let uv_v = t[0].1 * b0 + t[1].1 * b1 + t[2].1 * b2;
        let duv0 = (t[1].0 - t[0].0, t[1].1 - t[0].1);
        let duv1 = (t[2].0 - t[0].0, t[2].1 - t[0].1);
        let det = duv0.0 * duv1.1 - duv0.1 * duv1.0;
        let inv = f32x16::ONE / det;
        let dpdu_uv = (dp0 * duv1.1 - dp1 * duv0.1) * inv;
        let dpdv_uv = (dp1 * duv0.0 - dp0 * duv1.0) * inv;
        let with_uvs = mask(self.with_uvs);
        let degenerate_uv = with_uvs & det.simd_eq(f32x16::ZERO);
        let uv_u = with_uvs.select(uv_u, b1);
        let uv_v = with_uvs.select(uv_v, b2);
        let dpdu = Vec3s::select(with_uvs, dpdu_uv, dp0);
        let dpdv = Vec3s::select(with_uvs, dpdv_uv, dp1);

        let surface = Surface {
            p,
            p_error,
            n,
            sh_n,
            dpdu,
            dpdv,
            uv: (uv_u, uv_v),
        };
        let scalar = self.lanes & degenerate_uv.to_bitmask();
        scalar
            | surface.write(
                self.lanes & !scalar,
                hits,
                rays,
                &self.shape,
                &self.face,
                out,
            )
    }
}

/// The packet's hits on spheres, gathered lane by lane ([`SphereHits::push`]).
pub(crate) struct SphereHits {
    lanes: u32,
    center: Rows,
    radius: [f32; WIDTH],
    /// The linear parts of the spheres' transforms, `[column][axis][lane]`.
    to_world: [Rows; 3],
    to_object: [Rows; 3],
    flipped: u32,
    shape: [u32; WIDTH],
}

impl SphereHits {
    pub(crate) fn new() -> Self {
        Self {
            lanes: 0,
            center: [[0.0; WIDTH]; 3],
            radius: [0.0; WIDTH],
            to_world: [[[0.0; WIDTH]; 3]; 3],
            to_object: [[[0.0; WIDTH]; 3]; 3],
            flipped: 0,
            shape: [0; WIDTH],
        }
    }

    /// Lane `lane` hit sphere `shape` (whose kind must be `ShapeKind::Sphere`).
    #[inline(always)]
    pub(crate) fn push(&mut self, lane: usize, shape: u32, kind: &super::ShapeKind) {
        let super::ShapeKind::Sphere {
            center,
            radius,
            to_world,
            to_object,
            flip_normals,
        } = kind
        else {
            unreachable!("SphereHits::push takes spheres");
        };
        self.lanes |= 1 << lane;
        self.shape[lane] = shape;
        self.radius[lane] = *radius;
        for axis in 0..3 {
            self.center[axis][lane] = center[axis];
            for col in 0..3 {
                self.to_world[col][axis][lane] = to_world.col(col)[axis];
                self.to_object[col][axis][lane] = to_object.col(col)[axis];
            }
        }
        if *flip_normals {
            self.flipped |= 1 << lane;
        }
    }

    /// As [`MeshHits::interactions`], for the spheres (the sphere branch of
    /// `Shape::interaction`, with `sphere_point_error`, `sphere_tangents` and `sphere_uv`).
    #[inline(always)]
    pub(crate) fn interactions(
        &self,
        hits: &PacketHits,
        rays: &RayPacket,
        out: &mut SurfaceLanes,
    ) -> u32 {
        if self.lanes == 0 {
            return 0;
        }
        let center = Vec3s::from_rows(&self.center);
        let radius = f32x16::new(self.radius);
        let matrix = |m: &[Rows; 3]| Mat3s {
            cols: m.map(|c| Vec3s::from_rows(&c)),
        };
        let (to_world, to_object) = (matrix(&self.to_world), matrix(&self.to_object));
        let (o, d) = (Vec3s::from_rows(&rays.o), Vec3s::from_rows(&rays.d));
        let t = f32x16::new(hits.t);

        // The hit point, reprojected onto the surface.
        let offset = (o + d * t) - center;
        let offset = offset * (radius / offset.length_squared().sqrt());
        let p = center + offset;
        let p_error = offset.abs() * f32x16::splat(gamma(8))
            + (center + offset).abs() * f32x16::splat(gamma(1));
        let n = offset.div(radius);
        let n = Vec3s::select(mask(self.flipped), -n, n);

        // ∂p/∂u, ∂p/∂v and uv from the point in object space (Mitsuba's sphere.cpp).
        let local = to_object.mul_vec3(offset);
        let two_pi = f32x16::splat(2.0 * PI);
        let dpdu = Vec3s {
            x: -local.y * two_pi,
            y: local.x * two_pi,
            z: f32x16::ZERO * two_pi,
        };
        let rxy = (local.x * local.x + local.y * local.y).sqrt();
        let pi = f32x16::splat(PI);
        let off_pole = rxy.simd_gt(f32x16::ZERO);
        let dpdv = Vec3s::select(
            off_pole,
            Vec3s {
                x: local.z * local.x / rxy,
                y: local.z * local.y / rxy,
                z: -rxy,
            } * pi,
            Vec3s::splat(Vec3::new(PI, 0.0, 0.0)),
        );
        let (dpdu, dpdv) = (to_world.mul_vec3(dpdu), to_world.mul_vec3(dpdv));
        let (phi, phi_ok) = lanes::atan2(local.y, local.x);
        let u = phi * f32x16::splat(INV_TWO_PI);
        let u = u.simd_lt(f32x16::ZERO).select(u + f32x16::ONE, u);
        let (theta, theta_ok) = lanes::unit_angle_z(local);
        let surface = Surface {
            p,
            p_error,
            n,
            sh_n: n,
            dpdu,
            dpdv,
            uv: (u, theta / pi),
        };
        let scalar = self.lanes & !(phi_ok & theta_ok).to_bitmask();
        let faces = [0; WIDTH];
        scalar | surface.write(self.lanes & !scalar, hits, rays, &self.shape, &faces, out)
    }
}

/// The packet's hits on disks, gathered lane by lane ([`DiskHits::push`]).
pub(crate) struct DiskHits {
    lanes: u32,
    /// The disks' transforms, `[column][axis][lane]`, columns 0–2 linear, 3 the translation.
    to_world: [Rows; 4],
    to_local: [Rows; 4],
    normal: Rows,
    flipped: u32,
    shape: [u32; WIDTH],
}

impl DiskHits {
    pub(crate) fn new() -> Self {
        Self {
            lanes: 0,
            to_world: [[[0.0; WIDTH]; 3]; 4],
            to_local: [[[0.0; WIDTH]; 3]; 4],
            normal: [[0.0; WIDTH]; 3],
            flipped: 0,
            shape: [0; WIDTH],
        }
    }

    /// Lane `lane` hit disk `shape` (whose kind must be `ShapeKind::Disk`).
    #[inline(always)]
    pub(crate) fn push(&mut self, lane: usize, shape: u32, kind: &super::ShapeKind) {
        let super::ShapeKind::Disk {
            to_world,
            to_local,
            normal,
            flip_normals,
        } = kind
        else {
            unreachable!("DiskHits::push takes disks");
        };
        self.lanes |= 1 << lane;
        self.shape[lane] = shape;
        let columns = |m: &glam::Affine3A| {
            [
                m.matrix3.x_axis,
                m.matrix3.y_axis,
                m.matrix3.z_axis,
                m.translation,
            ]
        };
        for (col, (w, l)) in columns(to_world).iter().zip(columns(to_local)).enumerate() {
            for axis in 0..3 {
                self.to_world[col][axis][lane] = w[axis];
                self.to_local[col][axis][lane] = l[axis];
            }
        }
        for axis in 0..3 {
            self.normal[axis][lane] = normal[axis];
        }
        if *flip_normals {
            self.flipped |= 1 << lane;
        }
    }

    /// As [`MeshHits::interactions`], for the disks (the disk branch of
    /// `Shape::interaction`, with `disk_point_error`).
    #[inline(always)]
    pub(crate) fn interactions(
        &self,
        hits: &PacketHits,
        rays: &RayPacket,
        out: &mut SurfaceLanes,
    ) -> u32 {
        if self.lanes == 0 {
            return 0;
        }
        let affine = |m: &[Rows; 4]| {
            let [x, y, z, t] = m.map(|c| Vec3s::from_rows(&c));
            (Mat3s { cols: [x, y, z] }, t)
        };
        let ((world, world_t), (local_m, local_t)) =
            (affine(&self.to_world), affine(&self.to_local));
        let (o, d) = (Vec3s::from_rows(&rays.o), Vec3s::from_rows(&rays.d));
        let t = f32x16::new(hits.t);
        let zero = f32x16::ZERO;

        // glam's `Affine3A::transform_point3`: ((c₀x + c₁y) + c₂z) + t.
        let local = local_m.mul_vec3(o + d * t) + local_t;
        let on_disk = Vec3s {
            x: local.x,
            y: local.y,
            z: zero,
        };
        let p = world.mul_vec3(on_disk) + world_t;
        // disk_point_error: (|M| |local| + |t|) γ₁₂.
        let abs_m = Mat3s {
            cols: world.cols.map(Vec3s::abs),
        };
        let p_error = (abs_m.mul_vec3(local.abs()) + world_t.abs()) * f32x16::splat(gamma(12));
        let r = (local.x * local.x + local.y * local.y).sqrt();
        let (phi, phi_ok) = lanes::atan2(local.y, local.x);
        let v = phi * f32x16::splat(INV_TWO_PI);
        let v = v.simd_lt(zero).select(v + f32x16::ONE, v);
        let off_centre = r.simd_gt(zero);
        let (c, s) = (
            off_centre.select(local.x / r, f32x16::ONE),
            off_centre.select(local.y / r, zero),
        );
        let dpdu = world.mul_vec3(Vec3s {
            x: c,
            y: s,
            z: zero,
        });
        // Mitsuba's disk.cpp: dp/dv = (−y, x, 0) · 2π in local coordinates.
        let two_pi = f32x16::splat(2.0 * PI);
        let dpdv = world.mul_vec3(Vec3s {
            x: -local.y * two_pi,
            y: local.x * two_pi,
            z: zero * two_pi,
        });
        let normal = Vec3s::from_rows(&self.normal);
        let n = Vec3s::select(mask(self.flipped), -normal, normal);
        let surface = Surface {
            p,
            p_error,
            n,
            sh_n: n,
            dpdu,
            dpdv,
            uv: (r, v),
        };
        let scalar = self.lanes & !phi_ok.to_bitmask();
        let faces = [0; WIDTH];
        scalar | surface.write(self.lanes & !scalar, hits, rays, &self.shape, &faces, out)
    }
}

/// The geometry of sixteen hits, up to their shading frames.
struct Surface {
    p: Vec3s,
    p_error: Vec3s,
    /// Geometric and shading normals (flipped where the shape says so).
    n: Vec3s,
    sh_n: Vec3s,
    dpdu: Vec3s,
    dpdv: Vec3s,
    uv: (f32x16, f32x16),
}

impl Surface {
    /// Completes the interactions of `lanes` (their shading frames and incoming directions)
    /// into `out`, except where the frame's tangent vanishes: those lanes, whose `out` is
    /// untouched, are returned.
    #[inline(always)]
    fn write(
        &self,
        lanes: u32,
        hits: &PacketHits,
        rays: &RayPacket,
        shape: &[u32; WIDTH],
        face: &[u32; WIDTH],
        out: &mut SurfaceLanes,
    ) -> u32 {
        let (sh_n, dpdu) = (self.sh_n, self.dpdu);
        // The shading frame: ∂p/∂u made orthogonal to the shading normal
        // (`Frame::try_from_normal_tangent`); where it vanishes, the scalar code's fallback.
        let s = dpdu - sh_n * sh_n.dot(dpdu);
        let len2 = s.length_squared();
        let frame_ok = len2.simd_gt(f32x16::splat(1e-20)) & len2.is_finite();
        let s = s.div(len2.sqrt());
        let t_axis = sh_n.cross(s);

        // The incoming direction in the shading frame.
        let back = -Vec3s::from_rows(&rays.d);
        let wi = Vec3s {
            x: back.dot(s),
            y: back.dot(t_axis),
            z: back.dot(sh_n),
        };

        let scalar = lanes & !frame_ok.to_bitmask();
        let done = lanes & !scalar;
        if done == 0 {
            return scalar;
        }
        let m = mask(done);
        let blend = |new: Vec3s, old: &mut Vec3s| *old = Vec3s::select(m, new, *old);
        blend(self.p, &mut out.p);
        blend(self.p_error, &mut out.p_error);
        blend(self.n, &mut out.n);
        blend(s, &mut out.frame.s);
        blend(t_axis, &mut out.frame.t);
        blend(sh_n, &mut out.frame.n);
        blend(self.dpdu, &mut out.dp_du);
        blend(self.dpdv, &mut out.dp_dv);
        blend(wi, &mut out.wi);
        out.uv.x = m.select(self.uv.0, out.uv.x);
        out.uv.y = m.select(self.uv.1, out.uv.y);
        out.t = m.select(f32x16::new(hits.t), out.t);
        out.hit |= done;
        for k in lanes_of(done) {
            out.shape[k] = shape[k];
            out.face[k] = face[k];
            out.instance[k] = None;
        }
        scalar
    }
}

/// The surface interactions of a packet's closest hits, by component over the lanes: what
/// [`SurfaceInteraction`] holds for one hit, sixteen at a time, for the steps of the packet
/// loop that run over lanes. Lanes outside `hit` hold stale values.
#[derive(Clone, Copy, Debug)]
pub struct SurfaceLanes {
    /// Lanes whose ray hit a surface.
    pub hit: u32,
    pub p: Vec3s,
    pub p_error: Vec3s,
    pub t: f32x16,
    pub n: Vec3s,
    pub frame: FrameR<f32x16>,
    pub uv: Vector2<f32x16>,
    pub dp_du: Vec3s,
    pub dp_dv: Vec3s,
    pub wi: Vec3s,
    pub shape: [u32; WIDTH],
    pub instance: [Option<u32>; WIDTH],
    pub face: [u32; WIDTH],
}

impl Default for SurfaceLanes {
    fn default() -> Self {
        Self::new()
    }
}

impl SurfaceLanes {
    pub fn new() -> Self {
        let zero = Vec3s::splat(Vec3::ZERO);
        Self {
            hit: 0,
            p: zero,
            p_error: zero,
            t: f32x16::ZERO,
            n: zero,
            frame: FrameR {
                s: zero,
                t: zero,
                n: zero,
            },
            uv: Vector2 {
                x: f32x16::ZERO,
                y: f32x16::ZERO,
            },
            dp_du: zero,
            dp_dv: zero,
            wi: zero,
            shape: [0; WIDTH],
            instance: [None; WIDTH],
            face: [0; WIDTH],
        }
    }

    /// Lane `k`'s interaction, if its ray hit something.
    #[inline(always)]
    pub fn get(&self, k: usize) -> Option<SurfaceInteraction> {
        use radia_math::real::Real;
        (self.hit & (1 << k) != 0).then(|| SurfaceInteraction {
            p: self.p.lane(k),
            p_error: self.p_error.lane(k),
            t: self.t.lane(k),
            n: self.n.lane(k),
            frame: self.frame.lane(k),
            uv: self.uv.lane(k),
            dp_du: self.dp_du.lane(k),
            dp_dv: self.dp_dv.lane(k),
            shape: self.shape[k],
            instance: self.instance[k],
            face: self.face[k],
            wi: self.wi.lane(k),
        })
    }

    /// The origins of rays leaving the surfaces along `d` (world space), lane by lane
    /// [`SurfaceInteraction::spawn_ray`]'s.
    #[inline(always)]
    pub fn spawn_origins(&self, d: Vec3s) -> Vec3s {
        crate::shadow_lanes::offset_origin(self.p, self.p_error, self.n, d)
    }

    /// Makes lane `k` hold `si` (or no hit).
    #[inline(always)]
    pub fn set(&mut self, k: usize, si: Option<&SurfaceInteraction>) {
        use radia_math::real::Real;
        let Some(si) = si else {
            self.hit &= !(1 << k);
            return;
        };
        self.hit |= 1 << k;
        self.p.set_lane(k, si.p);
        self.p_error.set_lane(k, si.p_error);
        self.t.set_lane(k, si.t);
        self.n.set_lane(k, si.n);
        self.frame.set_lane(k, &si.frame);
        self.uv.set_lane(k, si.uv);
        self.dp_du.set_lane(k, si.dp_du);
        self.dp_dv.set_lane(k, si.dp_dv);
        self.wi.set_lane(k, si.wi);
        self.shape[k] = si.shape;
        self.instance[k] = si.instance;
        self.face[k] = si.face;
    }
}
