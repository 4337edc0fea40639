"""Issue #10: the glTF sphere grid (scenes/gltf/spheres.glb, 5 x 5 metallic x roughness) checked
at a few pixels against the glTF 2.0 metallic-roughness BRDF of the specification's Appendix B,
written out here in numpy and integrated numerically, independently of radia's code.

The scene is the glTF file placed in a Mitsuba XML scene by radia's <shape type="gltf"> (its
own lights left out), under a constant white environment of radiance 1, with direct lighting
only (path, max_depth 2) and a box pixel filter. A pixel at the centre of each sphere's image
is then

    L = (1 / pixel area) ∫_pixel ∫_H f(v, l) cos θ_l V(l) dω_l dA

with V the visibility of the environment past the neighbouring spheres. Both integrals are
Gauss-Legendre products: 3 x 3 points over the pixel, and over the hemisphere two 96 x 96 grids
through the inverse CDFs of the two lobes (cosine-weighted for the base, GGX normal
distribution for the specular), so that each integrand is smooth but for the visibility.

radia renders the image (48 x 48: a sphere is 6.6 pixels across, so the centre pixel lies
well inside it) in PASSES independent passes of 512 spp; the test requires the mean to be
within 4 standard errors of the integral, plus a 0.5% allowance for the spheres being
tessellated meshes (48 x 24 segments, smooth normals) where the integral uses exact spheres.
(Measured: at 24 passes the same pixels rendered with the meshes and with analytic `sphere`
shapes agree with each other and with the integral to within 1.5 standard errors, 0.3%.)

Run:  validation/.venv/bin/python -m unittest -v tests.test_gltf_brdf   (from validation/)
"""
import json
import os
import struct
import unittest

import numpy as np

from .helpers import VALIDATION, tmpdir
from radiaval.common import PackageRenderer

GLB = os.path.join(os.path.dirname(VALIDATION), "scenes", "gltf", "spheres.glb")
RES, SPP, PASSES = 48, 512, 8
EYE = np.array([0.0, 0.0, 9.0])
FOV_Y = 35.0  # degrees; the film is square
QUAD_PIXEL, QUAD_DIR = 3, 96


def read_glb_spheres(path):
    """(centre, radius, base colour, metallic, roughness) of every sphere node of the file:
    each node scales and places the same unit sphere mesh."""
    with open(path, "rb") as f:
        data = f.read()
    n = struct.unpack("<I", data[12:16])[0]
    doc = json.loads(data[20:20 + n])
    spheres = []
    for node in doc["nodes"]:
        if "mesh" not in node:
            continue
        mesh = doc["meshes"][node["mesh"]]
        mat = doc["materials"][mesh["primitives"][0]["material"]]["pbrMetallicRoughness"]
        spheres.append((np.array(node.get("translation", [0, 0, 0]), float),
                        float(node["scale"][0]),
                        np.array(mat["baseColorFactor"][:3], float),
                        float(mat.get("metallicFactor", 1.0)),
                        float(mat.get("roughnessFactor", 1.0))))
    return spheres


def scene_xml(dir_):
    path = os.path.join(dir_, "spheres-env.xml")
    with open(path, "w") as f:
        f.write(f"""<scene version="3.0.0">
    <integrator type="path"><integer name="max_depth" value="2"/></integrator>
    <sensor type="perspective">
        <float name="fov" value="{FOV_Y}"/>
        <string name="fov_axis" value="y"/>
        <transform name="to_world"><lookat origin="{EYE[0]}, {EYE[1]}, {EYE[2]}" target="0, 0, 0" up="0, 1, 0"/></transform>
        <film type="hdrfilm"><integer name="width" value="{RES}"/><integer name="height" value="{RES}"/></film>
    </sensor>
    <emitter type="constant"><rgb name="radiance" value="1"/></emitter>
    <shape type="gltf"><string name="filename" value="{GLB}"/></shape>
</scene>
""")
    return path


def camera_ray(px, py):
    """Direction through film position (px, py) in [0, 1]^2 (x right, y down) of the camera
    at EYE looking down -z with +y up."""
    t = np.tan(np.radians(FOV_Y) / 2)
    d = np.stack([(2 * px - 1) * t, (1 - 2 * py) * t, -np.ones_like(px)], axis=-1)
    return d / np.linalg.norm(d, axis=-1, keepdims=True)


def hit_sphere(o, d, c, r):
    """Nearest positive t of the rays o + t d (d unit) on the sphere (c, r), inf if none."""
    oc = o - c
    b = np.sum(oc * d, axis=-1)
    disc = b * b - (np.sum(oc * oc, axis=-1) - r * r)
    sq = np.sqrt(np.maximum(disc, 0))
    t0, t1 = -b - sq, -b + sq
    t = np.where(t0 > 1e-6, t0, np.where(t1 > 1e-6, t1, np.inf))
    return np.where(disc > 0, t, np.inf)


def gauss01(n):
    x, w = np.polynomial.legendre.leggauss(n)
    return (x + 1) / 2, w / 2


def frame(n):
    a = np.array([1.0, 0, 0]) if abs(n[0]) < 0.9 else np.array([0, 1.0, 0])
    s = np.cross(n, a)
    s /= np.linalg.norm(s)
    return s, np.cross(n, s)


def schlick(f0, cos):
    return f0 + (1 - f0) * (1 - np.abs(cos))[..., None] ** 5


def smith_g1(alpha2, c):
    c = np.abs(c)
    return 2 * c / (c + np.sqrt(alpha2 + (1 - alpha2) * c * c))


def radiance_at(p, n, v, sphere, others):
    """∫_H f(v, l) cos θ_l V(l) dω_l for the glTF material of `sphere` at the point p with
    normal n, viewed from direction v (towards the eye), under radiance 1 (RGB)."""
    _, _, base, metallic, roughness = sphere
    alpha = roughness ** 2
    alpha2 = alpha * alpha
    s, t = frame(n)
    u, w = gauss01(QUAD_DIR)
    u1, u2 = np.meshgrid(u, u, indexing="ij")
    weight = np.outer(w, w)
    nv = float(np.dot(n, v))

    def visible(l):
        o = p + n * 1e-5
        blocked = np.zeros(l.shape[0], bool)
        for c, r, *_ in others:
            blocked |= np.isfinite(hit_sphere(o, l, c, r))
        return ~blocked

    def to_world(x, y, z):
        return x[..., None] * s + y[..., None] * t + z[..., None] * n

    f0_dielectric = np.full(3, 0.04)
    # Base (diffuse) lobe, cosine-weighted: f cos / pdf = (1 - metallic) (1 - F(V.H)) base.
    ct = np.sqrt(1 - u1)
    st = np.sqrt(u1)
    phi = 2 * np.pi * u2
    l = to_world(st * np.cos(phi), st * np.sin(phi), ct).reshape(-1, 3)
    h = l + v
    h /= np.linalg.norm(h, axis=-1, keepdims=True)
    vh = h @ v
    g = (1 - metallic) * (1 - schlick(f0_dielectric, vh)) * base
    g *= visible(l)[:, None]
    diffuse = np.sum(g * weight.reshape(-1, 1), axis=0)

    # Specular lobe: h from D(h) cos θ_h, l the reflection of v; f cos / pdf(l) =
    # F G |v.h| / (|n.v| cos θ_h) where l is above the surface.
    tan2 = alpha2 * u1 / (1 - u1)
    ch = 1 / np.sqrt(1 + tan2)
    sh = np.sqrt(1 - ch * ch)
    h = to_world(sh * np.cos(phi), sh * np.sin(phi), ch).reshape(-1, 3)
    vh = h @ v
    l = 2 * vh[:, None] * h - v
    nl = l @ n
    fresnel = (1 - metallic) * schlick(f0_dielectric, vh) + metallic * schlick(base, vh)
    geom = smith_g1(alpha2, nl) * smith_g1(alpha2, nv)
    spec = fresnel * (geom * np.abs(vh) / (abs(nv) * ch.reshape(-1)))[:, None]
    ok = (nl > 0) & (vh > 0) & visible(l)
    specular = np.sum(np.where(ok[:, None], spec, 0) * weight.reshape(-1, 1), axis=0)
    return diffuse + specular


def pixel_of(centre):
    """The pixel whose centre is nearest the image of the sphere's centre."""
    d = centre - EYE
    t = np.tan(np.radians(FOV_Y) / 2)
    x = d[0] / -d[2] / t
    y = d[1] / -d[2] / t
    return int((x + 1) / 2 * RES), int((1 - y) / 2 * RES)


def expected_pixel(i, j, k, spheres):
    su, sw = gauss01(QUAD_PIXEL)
    total = np.zeros(3)
    others = [s for m, s in enumerate(spheres) if m != k]
    c, r = spheres[k][0], spheres[k][1]
    for a, wa in zip(su, sw):
        for b, wb in zip(su, sw):
            d = camera_ray(np.array((i + a) / RES), np.array((j + b) / RES))
            tk = hit_sphere(EYE, d, c, r)
            assert np.isfinite(tk), "the pixel is not inside the sphere's image"
            p = EYE + tk * d
            n = (p - c) / r
            total += wa * wb * radiance_at(p, n, -d, spheres[k], others)
    return total


class GltfSphereGridBrdfTest(unittest.TestCase):
    def test_sphere_centres_match_the_numerical_integral(self):
        spheres = read_glb_spheres(GLB)
        self.assertEqual(len(spheres), 25)
        r = PackageRenderer(scene_xml(tmpdir(self)), RES, SPP, sampler="independent")
        passes = np.stack([r.render(seed=100 + k) for k in range(PASSES)])
        mean = passes.mean(axis=0)
        se = passes.std(axis=0, ddof=1) / np.sqrt(PASSES)
        failures = []
        for k, sphere in enumerate(spheres):
            i, j = pixel_of(sphere[0])
            want = expected_pixel(i, j, k, spheres)
            got, err = mean[j, i, :3], se[j, i, :3]
            bound = 4 * err + 0.005 * want
            line = (f"metallic {sphere[3]:.2f} roughness {sphere[4]:.2f} pixel ({i}, {j}): "
                    f"radia {np.round(got, 4)} ± {np.round(err, 4)}, integral {np.round(want, 4)}")
            print(line)
            if np.any(np.abs(got - want) > bound):
                failures.append(line)
        self.assertEqual(failures, [], "\n".join(failures))


if __name__ == "__main__":
    unittest.main()
