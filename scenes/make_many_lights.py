#!/usr/bin/env python3
"""Writes many-lights.xml: 144 small emitters (alternately spheres of radius 0.04 and
0.12 x 0.12 squares facing down, in eight colours, radiances over a range of 30) on a
jittered 12 x 12 grid between 0.2 and 1.4 above a 12 x 12 floor with a few diffuse blocks
and balls. Each point of the floor is lit mostly by the handful of lights near it: the case
for choosing lights by a light BVH rather than uniformly.

    python3 scenes/make_many_lights.py
"""
import os
import random

COLOURS = [(1.0, 0.55, 0.25), (0.3, 0.6, 1.0), (1.0, 0.9, 0.7), (0.4, 1.0, 0.45),
           (1.0, 0.35, 0.6), (0.85, 0.85, 1.0), (1.0, 0.75, 0.2), (0.6, 0.4, 1.0)]

HEADER = """<?xml version="1.0" encoding="utf-8"?>
<!-- Written by make_many_lights.py: 144 small emitters (spheres of radius 0.04 and
     0.12 x 0.12 squares facing down) over a floor with a few diffuse blocks and balls, no
     other light. Loads in Mitsuba 3.9.1 too; render small with -D spp=16 -D res=64 (radia)
     or spp=16, res=64 (mi.load_file). -->
<scene version="3.0.0">
    <default name="spp" value="64"/>
    <default name="res" value="128"/>

    <integrator type="path"/>

    <sensor type="perspective">
        <float name="fov" value="48"/>
        <transform name="to_world">
            <lookat origin="0, 7, 9" target="0, 0, -0.5" up="0, 1, 0"/>
        </transform>
        <sampler type="independent">
            <integer name="sample_count" value="$spp"/>
        </sampler>
        <film type="hdrfilm">
            <integer name="width" value="$res"/>
            <integer name="height" value="$res"/>
            <string name="pixel_format" value="rgb"/>
            <string name="component_format" value="float32"/>
            <rfilter type="box"/>
        </film>
    </sensor>

    <bsdf type="diffuse" id="floor">
        <rgb name="reflectance" value="0.55"/>
    </bsdf>
    <bsdf type="diffuse" id="block">
        <rgb name="reflectance" value="0.7, 0.65, 0.6"/>
    </bsdf>

    <shape type="rectangle">
        <transform name="to_world">
            <scale value="6"/>
            <rotate x="1" angle="-90"/>
        </transform>
        <ref id="floor"/>
    </shape>
"""


def main():
    rng = random.Random(5)
    out = [HEADER]
    for (x, z, sx, sy, sz, a) in [(-2.5, -1.5, 0.5, 0.8, 0.5, 20), (1.8, 0.8, 0.7, 0.35, 0.4, -35),
                                  (-0.3, -3.2, 1.6, 0.5, 0.3, 5), (3.2, -2.6, 0.4, 1.1, 0.4, 45)]:
        out.append(f"""    <shape type="cube">
        <transform name="to_world">
            <scale x="{sx}" y="{sy}" z="{sz}"/>
            <rotate y="1" angle="{a}"/>
            <translate x="{x}" y="{sy}" z="{z}"/>
        </transform>
        <ref id="block"/>
    </shape>
""")
    for (x, z, r) in [(-0.8, 1.6, 0.45), (0.9, -1.2, 0.6), (-3.4, 2.4, 0.35), (2.9, 3.0, 0.5)]:
        out.append(f"""    <shape type="sphere">
        <point name="center" x="{x}" y="{r}" z="{z}"/>
        <float name="radius" value="{r}"/>
        <ref id="block"/>
    </shape>
""")
    n = 12
    for i in range(n):
        for j in range(n):
            x = -5.5 + 11.0 * (i + 0.5) / n + rng.uniform(-0.25, 0.25)
            z = -5.5 + 11.0 * (j + 0.5) / n + rng.uniform(-0.25, 0.25)
            y = rng.uniform(0.2, 1.4)
            c = COLOURS[rng.randrange(len(COLOURS))]
            k = rng.choice([1.0, 2.0, 4.0, 8.0, 30.0])
            if (i + j) % 2 == 0:
                l = ", ".join(f"{10 * k * v:.4g}" for v in c)
                out.append(f"""    <shape type="sphere">
        <point name="center" x="{x:.4f}" y="{y:.4f}" z="{z:.4f}"/>
        <float name="radius" value="0.04"/>
        <emitter type="area"><rgb name="radiance" value="{l}"/></emitter>
    </shape>
""")
            else:
                l = ", ".join(f"{4 * k * v:.4g}" for v in c)
                out.append(f"""    <shape type="rectangle">
        <transform name="to_world">
            <scale value="0.06"/>
            <rotate x="1" angle="90"/>
            <translate x="{x:.4f}" y="{y:.4f}" z="{z:.4f}"/>
        </transform>
        <emitter type="area"><rgb name="radiance" value="{l}"/></emitter>
    </shape>
""")
    out.append("</scene>\n")
    path = os.path.join(os.path.dirname(os.path.abspath(__file__)), "many-lights.xml")
    with open(path, "w") as f:
        f.write("".join(out))
    print("wrote", path)


if __name__ == "__main__":
    main()
