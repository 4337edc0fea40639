#!/usr/bin/env python3
"""Writes the bad-input corpus: scenes (and the meshes and images they reference) that radia
must refuse with a non-zero exit and one line naming the file (and the line and column where
there is one), without panicking, aborting or writing an image.

Every case is one entry of CASES: the scene file's name, the location the error must name
(FILE, FILE:LINE or FILE:LINE:COL, relative to this folder) and the file's content. The data
files (broken meshes and images) are written by data_files(). EXPECTED, written from CASES,
is what tests/tests/bad_inputs.rs checks. Run from anywhere: python3 tests/bad-inputs/make_corpus.py
"""

import os
import struct
import zlib

HERE = os.path.dirname(os.path.abspath(__file__))

HEAD = '<scene version="3.0.0">\n'
SENSOR = """    <sensor type="perspective">
        <film type="hdrfilm">
            <integer name="width" value="8"/>
            <integer name="height" value="8"/>
        </film>
    </sensor>
"""


def scene(body, sensor=SENSOR):
    """A small valid scene around `body` (lines 1-7 are the header and the sensor)."""
    return HEAD + sensor + body + "</scene>\n"


def sensor_with(film="", sampler="", extra=""):
    return f"""    <sensor type="perspective">
{extra}        <film type="hdrfilm">
            <integer name="width" value="8"/>
            <integer name="height" value="8"/>
{film}        </film>
{sampler}    </sensor>
"""


def shape_with_bsdf(bsdf):
    return f'    <shape type="sphere">\n{bsdf}    </shape>\n'


SPHERE = '    <shape type="sphere"/>\n'

# (scene file, location the error names, content)
CASES = [
    # ---- XML syntax ----
    ("xml-unclosed-element.xml", "xml-unclosed-element.xml:1:1", HEAD + SENSOR + '    <shape type="sphere">\n'),
    ("xml-mismatched-tag.xml", "xml-mismatched-tag.xml:8:", scene('    <shape type="sphere"></bsdf>\n')),
    ("xml-unquoted-attribute.xml", "xml-unquoted-attribute.xml:8:", scene("    <shape type=sphere/>\n")),
    ("xml-undefined-entity.xml", "xml-undefined-entity.xml:8:", scene('    <shape type="&sphere;"/>\n')),
    ("xml-empty-file.xml", "xml-empty-file.xml", ""),
    ("xml-binary-garbage.xml", "xml-binary-garbage.xml", None),  # written by data_files()
    ("xml-wrong-root.xml", "xml-wrong-root.xml:1:1", '<scenery version="3.0.0">\n' + SPHERE + "</scenery>\n"),
    ("xml-missing-version.xml", "xml-missing-version.xml:1:1", "<scene>\n" + SENSOR + SPHERE + "</scene>\n"),
    ("xml-bad-version.xml", "xml-bad-version.xml:1:1", '<scene version="three">\n' + SENSOR + SPHERE + "</scene>\n"),
    ("xml-deep-nesting.xml", "xml-deep-nesting.xml:", scene("<bsdf type=\"twosided\">" * 5000 + "\n")),
    # ---- unknown plugins, elements, parameters ----
    ("unknown-bsdf-plugin.xml", "unknown-bsdf-plugin.xml:9:9", scene(shape_with_bsdf('        <bsdf type="velvet"/>\n'))),
    ("unknown-shape-plugin.xml", "unknown-shape-plugin.xml:8:5", scene('    <shape type="teapot"/>\n')),
    ("unknown-emitter-plugin.xml", "unknown-emitter-plugin.xml:8:5", scene('    <emitter type="laser"/>\n' + SPHERE)),
    ("unknown-integrator-plugin.xml", "unknown-integrator-plugin.xml:8:5", scene('    <integrator type="magic"/>\n' + SPHERE)),
    ("unknown-element.xml", "unknown-element.xml:8:5", scene("    <teapot/>\n" + SPHERE)),
    ("unknown-parameter.xml", "unknown-parameter.xml:9:9", scene('    <shape type="sphere">\n        <float name="raduis" value="1"/>\n    </shape>\n')),
    # ---- missing or wrongly typed attributes ----
    ("missing-type-attribute.xml", "missing-type-attribute.xml:9:9", scene(shape_with_bsdf("        <bsdf/>\n"))),
    ("missing-name-attribute.xml", "missing-name-attribute.xml:9:9", scene('    <shape type="sphere">\n        <float value="1"/>\n    </shape>\n')),
    ("missing-value-attribute.xml", "missing-value-attribute.xml:9:9", scene('    <shape type="sphere">\n        <float name="radius"/>\n    </shape>\n')),
    ("wrong-type-parameter.xml", "wrong-type-parameter.xml:9:9", scene('    <shape type="sphere">\n        <string name="radius" value="1"/>\n    </shape>\n')),
    ("not-a-number.xml", "not-a-number.xml:9:9", scene('    <shape type="sphere">\n        <float name="radius" value="one"/>\n    </shape>\n')),
    ("fractional-integer.xml", "fractional-integer.xml:", scene(SPHERE, sensor_with(sampler='        <sampler type="independent"><integer name="sample_count" value="4.5"/></sampler>\n'))),
    ("bad-rgb.xml", "bad-rgb.xml:10:13", scene(shape_with_bsdf('        <bsdf type="diffuse">\n            <rgb name="reflectance" value="0.5, 0.5"/>\n        </bsdf>\n'))),
    # ---- ids, references, includes, parameters ----
    ("unknown-ref-id.xml", "unknown-ref-id.xml:9:9", scene(shape_with_bsdf('        <ref id="gold"/>\n'))),
    ("duplicate-id.xml", "duplicate-id.xml:9:5", scene('    <bsdf type="diffuse" id="a"/>\n    <bsdf type="diffuse" id="a"/>\n' + SPHERE)),
    ("ref-cycle.xml", "ref-cycle.xml:", scene('    <bsdf type="twosided" id="a">\n        <ref id="a"/>\n    </bsdf>\n' + SPHERE)),
    ("ref-wrong-kind.xml", "ref-wrong-kind.xml:", scene('    <emitter type="point" id="lamp"/>\n' + shape_with_bsdf('        <ref id="lamp"/>\n'))),
    ("recursive-include.xml", "recursive-include.xml:8:5", scene('    <include filename="recursive-include.xml"/>\n')),
    ("include-missing.xml", "include-missing.xml:8:5", scene('    <include filename="data/no-such-include.xml"/>\n')),
    ("include-cycle.xml", "data/include-cycle-b.xml:2:5", scene('    <include filename="data/include-cycle-b.xml"/>\n')),
    ("include-bad-content.xml", "data/include-bad-bsdf.xml:1:1", scene('    <shape type="sphere">\n        <include filename="data/include-bad-bsdf.xml"/>\n    </shape>\n')),
    ("undefined-parameter.xml", "undefined-parameter.xml:9:9", scene('    <shape type="sphere">\n        <float name="radius" value="$size"/>\n    </shape>\n')),
    # ---- missing files ----
    ("missing-mesh-file.xml", "missing-mesh-file.xml:8:5", scene('    <shape type="ply">\n        <string name="filename" value="data/no-such-mesh.ply"/>\n    </shape>\n')),
    ("missing-envmap-file.xml", "missing-envmap-file.xml:9:9", scene('    <emitter type="envmap">\n        <string name="filename" value="data/no-such-sky.exr"/>\n    </emitter>\n')),
    ("mesh-is-a-directory.xml", "mesh-is-a-directory.xml:8:5", scene('    <shape type="obj">\n        <string name="filename" value="data"/>\n    </shape>\n')),
    ("mesh-is-a-device.xml", "mesh-is-a-device.xml:8:5", scene('    <shape type="ply">\n        <string name="filename" value="/dev/zero"/>\n    </shape>\n')),
    ("envmap-is-a-device.xml", "envmap-is-a-device.xml:9:9", scene('    <emitter type="envmap">\n        <string name="filename" value="/dev/zero"/>\n    </emitter>\n')),
    ("gltf-shape-missing-file.xml", "gltf-shape-missing-file.xml:8:5", scene('    <shape type="gltf">\n        <string name="filename" value="data/no-such-model.glb"/>\n    </shape>\n')),
    ("gltf-shape-bad-file.xml", "gltf-shape-bad-file.xml:8:5", scene('    <shape type="gltf">\n        <string name="filename" value="gltf-index-out-of-range.gltf"/>\n    </shape>\n')),
    ("gltf-shape-with-bsdf.xml", "gltf-shape-with-bsdf.xml:9:9", scene('    <shape type="gltf">\n        <bsdf type="diffuse"/>\n        <string name="filename" value="gltf-index-out-of-range.gltf"/>\n    </shape>\n')),
    # ---- broken meshes ----
    ("ply-truncated.xml", "data/truncated.ply", scene('    <shape type="ply">\n        <string name="filename" value="data/truncated.ply"/>\n    </shape>\n')),
    ("ply-bad-header.xml", "data/bad-header.ply", scene('    <shape type="ply">\n        <string name="filename" value="data/bad-header.ply"/>\n    </shape>\n')),
    ("ply-index-out-of-range.xml", "data/bad-index.ply", scene('    <shape type="ply">\n        <string name="filename" value="data/bad-index.ply"/>\n    </shape>\n')),
    ("ply-huge-count.xml", "data/huge-count.ply", scene('    <shape type="ply">\n        <string name="filename" value="data/huge-count.ply"/>\n    </shape>\n')),
    ("ply-huge-list.xml", "data/huge-list.ply", scene('    <shape type="ply">\n        <string name="filename" value="data/huge-list.ply"/>\n    </shape>\n')),
    ("ply-nan-vertex.xml", "data/nan-vertex.ply", scene('    <shape type="ply">\n        <string name="filename" value="data/nan-vertex.ply"/>\n    </shape>\n')),
    ("ply-not-a-ply.xml", "data/garbage.ply", scene('    <shape type="ply">\n        <string name="filename" value="data/garbage.ply"/>\n    </shape>\n')),
    ("obj-index-out-of-range.xml", "data/bad-index.obj:", scene('    <shape type="obj">\n        <string name="filename" value="data/bad-index.obj"/>\n    </shape>\n')),
    ("obj-bad-number.xml", "data/bad-number.obj:", scene('    <shape type="obj">\n        <string name="filename" value="data/bad-number.obj"/>\n    </shape>\n')),
    ("obj-nan-vertex.xml", "data/nan-vertex.obj", scene('    <shape type="obj">\n        <string name="filename" value="data/nan-vertex.obj"/>\n    </shape>\n')),
    ("obj-binary-garbage.xml", "data/garbage.obj", scene('    <shape type="obj">\n        <string name="filename" value="data/garbage.obj"/>\n    </shape>\n')),
    ("obj-no-faces.xml", "data/no-faces.obj", scene('    <shape type="obj">\n        <string name="filename" value="data/no-faces.obj"/>\n    </shape>\n')),
    # ---- broken images (envmaps) ----
    ("png-truncated.xml", "data/truncated.png", scene('    <emitter type="envmap">\n        <string name="filename" value="data/truncated.png"/>\n    </emitter>\n')),
    ("png-corrupt-data.xml", "data/corrupt.png", scene('    <emitter type="envmap">\n        <string name="filename" value="data/corrupt.png"/>\n    </emitter>\n')),
    ("png-huge-dimensions.xml", "data/huge.png", scene('    <emitter type="envmap">\n        <string name="filename" value="data/huge.png"/>\n    </emitter>\n')),
    ("exr-truncated.xml", "data/truncated.exr", scene('    <emitter type="envmap">\n        <string name="filename" value="data/truncated.exr"/>\n    </emitter>\n')),
    ("exr-garbage.xml", "data/garbage.exr", scene('    <emitter type="envmap">\n        <string name="filename" value="data/garbage.exr"/>\n    </emitter>\n')),
    ("exr-huge-dimensions.xml", "data/huge.exr", scene('    <emitter type="envmap">\n        <string name="filename" value="data/huge.exr"/>\n    </emitter>\n')),
    ("exr-large-dimensions.xml", "data/large.exr", scene('    <emitter type="envmap">\n        <string name="filename" value="data/large.exr"/>\n    </emitter>\n')),
    ("hdr-truncated.xml", "data/truncated.hdr", scene('    <emitter type="envmap">\n        <string name="filename" value="data/truncated.hdr"/>\n    </emitter>\n')),
    ("hdr-huge-dimensions.xml", "data/huge.hdr", scene('    <emitter type="envmap">\n        <string name="filename" value="data/huge.hdr"/>\n    </emitter>\n')),
    ("image-unknown-format.xml", "data/bad-number.obj", scene('    <emitter type="envmap">\n        <string name="filename" value="data/bad-number.obj"/>\n    </emitter>\n')),
    ("image-nan-pixels.xml", "data/nan.exr", scene('    <emitter type="envmap">\n        <string name="filename" value="data/nan.exr"/>\n    </emitter>\n')),
    # ---- absurd sizes ----
    ("film-huge.xml", "film-huge.xml:4:13", scene(SPHERE, '    <sensor type="perspective">\n        <film type="hdrfilm">\n            <integer name="width" value="4000000000"/>\n            <integer name="height" value="4000000000"/>\n        </film>\n    </sensor>\n')),
    ("film-width-zero.xml", "film-width-zero.xml:4:13", scene(SPHERE, '    <sensor type="perspective">\n        <film type="hdrfilm">\n            <integer name="width" value="0"/>\n        </film>\n    </sensor>\n')),
    ("film-width-negative.xml", "film-width-negative.xml:4:13", scene(SPHERE, '    <sensor type="perspective">\n        <film type="hdrfilm">\n            <integer name="width" value="-64"/>\n        </film>\n    </sensor>\n')),
    ("sample-count-zero.xml", "sample-count-zero.xml:", scene(SPHERE, sensor_with(sampler='        <sampler type="independent"><integer name="sample_count" value="0"/></sampler>\n'))),
    ("sample-count-huge.xml", "sample-count-huge.xml:", scene(SPHERE, sensor_with(sampler='        <sampler type="independent"><integer name="sample_count" value="100000000000"/></sampler>\n'))),
    ("sample-count-overflow.xml", "sample-count-overflow.xml:", scene(SPHERE, sensor_with(sampler='        <sampler type="stratified"><integer name="sample_count" value="4294967295"/></sampler>\n'))),
    ("max-depth-negative.xml", "max-depth-negative.xml:9:9", scene('    <integrator type="path">\n        <integer name="max_depth" value="-7"/>\n    </integrator>\n' + SPHERE)),
    ("max-depth-huge.xml", "max-depth-huge.xml:9:9", scene('    <integrator type="path">\n        <integer name="max_depth" value="99999999999"/>\n    </integrator>\n' + SPHERE)),
    # ---- negative, zero, NaN parameters ----
    ("alpha-negative.xml", "alpha-negative.xml:10:13", scene(shape_with_bsdf('        <bsdf type="roughconductor">\n            <float name="alpha" value="-0.3"/>\n        </bsdf>\n'))),
    ("alpha-nan.xml", "alpha-nan.xml:10:13", scene(shape_with_bsdf('        <bsdf type="roughdielectric">\n            <float name="alpha" value="nan"/>\n        </bsdf>\n'))),
    ("alpha-v-negative.xml", "alpha-v-negative.xml:11:13", scene(shape_with_bsdf('        <bsdf type="roughconductor">\n            <float name="alpha_u" value="0.1"/>\n            <float name="alpha_v" value="-1"/>\n        </bsdf>\n'))),
    ("principled-eta-and-specular.xml", "principled-eta-and-specular.xml:9:9", scene(shape_with_bsdf('        <bsdf type="principled">\n            <float name="eta" value="1.5"/>\n            <float name="specular" value="0.5"/>\n        </bsdf>\n'))),
    ("principled-metallic-above-one.xml", "principled-metallic-above-one.xml:10:13", scene(shape_with_bsdf('        <bsdf type="principled">\n            <float name="metallic" value="1.5"/>\n        </bsdf>\n'))),
    ("ior-negative.xml", "ior-negative.xml:9:9", scene(shape_with_bsdf('        <bsdf type="dielectric">\n            <float name="int_ior" value="-1.5"/>\n        </bsdf>\n'))),
    ("ior-nan.xml", "ior-nan.xml:", scene(shape_with_bsdf('        <bsdf type="plastic">\n            <float name="int_ior" value="nan"/>\n        </bsdf>\n'))),
    ("reflectance-nan.xml", "reflectance-nan.xml:10:13", scene(shape_with_bsdf('        <bsdf type="diffuse">\n            <float name="reflectance" value="nan"/>\n        </bsdf>\n'))),
    ("reflectance-above-one.xml", "reflectance-above-one.xml:10:13", scene(shape_with_bsdf('        <bsdf type="diffuse">\n            <rgb name="reflectance" value="0.5, 2, 0.5"/>\n        </bsdf>\n'))),
    ("radiance-nan.xml", "radiance-nan.xml:10:13", scene('    <shape type="sphere">\n        <emitter type="area">\n            <rgb name="radiance" value="1, nan, 1"/>\n        </emitter>\n    </shape>\n')),
    ("radiance-negative.xml", "radiance-negative.xml:10:13", scene('    <shape type="sphere">\n        <emitter type="area">\n            <rgb name="radiance" value="-1, 1, 1"/>\n        </emitter>\n    </shape>\n')),
    ("intensity-infinite.xml", "intensity-infinite.xml:9:9", scene('    <emitter type="point">\n        <float name="intensity" value="inf"/>\n    </emitter>\n' + SPHERE)),
    ("radius-nan.xml", "radius-nan.xml:8:5", scene('    <shape type="sphere">\n        <float name="radius" value="nan"/>\n    </shape>\n')),
    ("fov-zero.xml", "fov-zero.xml:3:9", scene(SPHERE, sensor_with(extra='        <float name="fov" value="0"/>\n'))),
    ("fov-nan.xml", "fov-nan.xml:3:9", scene(SPHERE, sensor_with(extra='        <float name="fov" value="nan"/>\n'))),
    ("near-clip-negative.xml", "near-clip-negative.xml:3:9", scene(SPHERE, sensor_with(extra='        <float name="near_clip" value="-1"/>\n'))),
    ("gaussian-stddev-zero.xml", "gaussian-stddev-zero.xml:", scene(SPHERE, sensor_with(film='            <rfilter type="gaussian"><float name="stddev" value="0"/></rfilter>\n'))),
    ("scale-zero.xml", "scale-zero.xml:8:5", scene('    <shape type="sphere">\n        <transform name="to_world">\n            <scale value="0"/>\n        </transform>\n    </shape>\n')),
    ("translate-nan.xml", "translate-nan.xml:", scene('    <shape type="sphere">\n        <transform name="to_world">\n            <translate x="nan"/>\n        </transform>\n    </shape>\n')),
    ("lookat-degenerate.xml", "lookat-degenerate.xml:", scene(SPHERE, sensor_with(extra='        <transform name="to_world"><lookat origin="0, 0, 1" target="0, 0, 1" up="0, 1, 0"/></transform>\n'))),
    ("spot-cutoff-negative.xml", "spot-cutoff-negative.xml:9:9", scene('    <emitter type="spot">\n        <float name="cutoff_angle" value="-10"/>\n    </emitter>\n' + SPHERE)),
    ("envmap-scale-nan.xml", "envmap-scale-nan.xml:", scene('    <emitter type="envmap">\n        <string name="filename" value="../../scenes/textures/sky-sun.exr"/>\n        <float name="scale" value="nan"/>\n    </emitter>\n')),
    ("displacement-subdivisions-huge.xml", "displacement-subdivisions-huge.xml:8:5", scene('    <shape type="cube">\n        <integer name="subdivisions" value="16"/>\n    </shape>\n')),
    ("displacement-scale-nan.xml", "displacement-scale-nan.xml:10:9", scene('    <shape type="rectangle">\n        <float name="displacement" value="0.5"/>\n        <float name="displacement_scale" value="nan"/>\n    </shape>\n')),
    # ---- instancing (src/shapes/shapegroup.cpp, instance.cpp) ----
    ("instance-missing-group.xml", "instance-missing-group.xml:9:9",
     scene('    <shape type="instance">\n        <ref id="no_such_group"/>\n    </shape>\n')),
    ("instance-not-a-group.xml", "instance-not-a-group.xml:10:9",
     scene('    <shape type="sphere" id="ball"/>\n    <shape type="instance">\n        <ref id="ball"/>\n    </shape>\n')),
    ("instance-without-group.xml", "instance-without-group.xml:8:5", scene('    <shape type="instance"/>\n')),
    ("shapegroup-emitter.xml", "shapegroup-emitter.xml:9:9",
     scene('    <shape type="shapegroup" id="g">\n        <shape type="sphere">\n            <emitter type="area"/>\n'
           '        </shape>\n    </shape>\n    <shape type="instance">\n        <ref id="g"/>\n    </shape>\n')),
    ("shapegroup-nested.xml", "shapegroup-nested.xml:9:9",
     scene('    <shape type="shapegroup" id="g">\n        <shape type="shapegroup" id="h">\n            <shape type="sphere"/>\n'
           '        </shape>\n    </shape>\n')),
    ("shapegroup-instance-inside.xml", "shapegroup-instance-inside.xml:12:9",
     scene('    <shape type="shapegroup" id="g">\n        <shape type="sphere"/>\n    </shape>\n'
           '    <shape type="shapegroup" id="h">\n        <shape type="instance">\n            <ref id="g"/>\n'
           '        </shape>\n    </shape>\n')),
    ("shapegroup-bsdf.xml", "shapegroup-bsdf.xml:9:9",
     scene('    <shape type="shapegroup" id="g">\n        <bsdf type="diffuse"/>\n        <shape type="sphere"/>\n    </shape>\n')),
    # ---- glTF (written by gltf_files()) ----
    ("gltf-truncated.gltf", "gltf-truncated.gltf", '{"asset": {"version": "2.0"}, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0'),
    ("glb-bad-magic.glb", "glb-bad-magic.glb", None),  # written by data_files()
    ("gltf-missing-buffer.gltf", "gltf-missing-buffer.gltf: buffer 0 (uri \"no-such-file.bin\")",
     None),
    ("gltf-short-buffer.gltf", "gltf-short-buffer.gltf: buffer 0 has 24 bytes, fewer than its byteLength 36", None),
    ("gltf-bad-accessor.gltf", "gltf-bad-accessor.gltf: mesh 0 primitive 0: POSITION accessor 0 has type VEC2", None),
    ("gltf-accessor-past-view.gltf", "gltf-accessor-past-view.gltf: mesh 0 primitive 0: POSITION accessor 0", None),
    ("gltf-index-out-of-range.gltf", "gltf-index-out-of-range.gltf: mesh 0 primitive 0: index 7", None),
    ("gltf-required-extension.gltf", "gltf-required-extension.gltf: the file requires the extension KHR_draco_mesh_compression", None),
    ("gltf-bad-image.gltf", "gltf-bad-image.gltf: material 0: texture 0: image 0", None),
    ("glb-truncated.glb", "glb-truncated.glb: not a valid GLB file", None),
]


def gltf_triangle(**change):
    """A valid one-triangle glTF (positions in a data-URI buffer) as a dict, with changes."""
    import base64
    import json
    data = struct.pack("<9f", 0, 0, 0, 1, 0, 0, 0, 1, 0)
    doc = {
        "asset": {"version": "2.0"},
        "scene": 0, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                       "min": [0, 0, 0], "max": [1, 1, 0]}],
        "bufferViews": [{"buffer": 0, "byteLength": 36}],
        "buffers": [{"byteLength": 36,
                     "uri": "data:application/octet-stream;base64," + base64.b64encode(data).decode()}],
    }
    for path, value in change.items():
        *parents, last = path.split("__")
        node = doc
        for k in parents:
            node = node[int(k)] if isinstance(node, list) else node[k]
        if isinstance(node, list):
            node[int(last)] = value
        else:
            node[last] = value
    return json.dumps(doc, indent=1) + "\n"


def gltf_files(write):
    """The malformed glTF files: each one fault in an otherwise valid file."""
    import base64
    import json
    write("gltf-missing-buffer.gltf", gltf_triangle(buffers__0={"byteLength": 36, "uri": "no-such-file.bin"}))
    short = base64.b64encode(bytes(24)).decode()
    write("gltf-short-buffer.gltf", gltf_triangle(
        buffers__0={"byteLength": 36, "uri": "data:application/octet-stream;base64," + short}))
    write("gltf-bad-accessor.gltf", gltf_triangle(accessors__0__type="VEC2"))
    write("gltf-accessor-past-view.gltf", gltf_triangle(accessors__0__count=30))
    idx = struct.pack("<3H", 0, 1, 7) + b"\0\0"
    data = struct.pack("<9f", 0, 0, 0, 1, 0, 0, 0, 1, 0) + idx
    b64 = base64.b64encode(data).decode()
    write("gltf-index-out-of-range.gltf", gltf_triangle(
        meshes__0={"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]},
        accessors=[{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                    "min": [0, 0, 0], "max": [1, 1, 0]},
                   {"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"}],
        bufferViews=[{"buffer": 0, "byteLength": 36}, {"buffer": 0, "byteOffset": 36, "byteLength": 6}],
        buffers__0={"byteLength": len(data), "uri": "data:application/octet-stream;base64," + b64}))
    write("gltf-required-extension.gltf", gltf_triangle(
        extensionsUsed=["KHR_draco_mesh_compression"], extensionsRequired=["KHR_draco_mesh_compression"]))
    garbage_png = base64.b64encode(b"\x89PNG\r\n\x1a\n" + bytes(40)).decode()
    write("gltf-bad-image.gltf", gltf_triangle(
        meshes__0={"primitives": [{"attributes": {"POSITION": 0}, "material": 0}]},
        materials=[{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}],
        textures=[{"source": 0}],
        images=[{"uri": "data:image/png;base64," + garbage_png}]))
    # A GLB whose header promises more bytes than the file has.
    good = json.dumps({"asset": {"version": "2.0"}}).encode()
    good += b" " * (-len(good) % 4)
    glb = b"glTF" + struct.pack("<II", 2, 12 + 8 + len(good) + 4000) + struct.pack("<I", len(good) + 4000) + b"JSON" + good
    write("glb-truncated.glb", glb)


def png_chunk(kind, data):
    return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))


def png(width, height, rows):
    ihdr = struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)
    return (b"\x89PNG\r\n\x1a\n" + png_chunk(b"IHDR", ihdr)
            + png_chunk(b"IDAT", zlib.compress(rows)) + png_chunk(b"IEND", b""))


def exr_header(width, height):
    """A scanline RGB float OpenEXR header (no offset table or pixels)."""
    def attr(name, kind, value):
        return name + b"\0" + kind + b"\0" + struct.pack("<i", len(value)) + value
    chans = b"".join(c + b"\0" + struct.pack("<iBBBBii", 2, 0, 0, 0, 0, 1, 1) for c in (b"B", b"G", b"R")) + b"\0"
    box = struct.pack("<iiii", 0, 0, width - 1, height - 1)
    return (struct.pack("<ii", 20000630, 2)
            + attr(b"channels", b"chlist", chans)
            + attr(b"compression", b"compression", b"\0")
            + attr(b"dataWindow", b"box2i", box)
            + attr(b"displayWindow", b"box2i", box)
            + attr(b"lineOrder", b"lineOrder", b"\0")
            + attr(b"pixelAspectRatio", b"float", struct.pack("<f", 1.0))
            + attr(b"screenWindowCenter", b"v2f", struct.pack("<ff", 0, 0))
            + attr(b"screenWindowWidth", b"float", struct.pack("<f", 1.0))
            + b"\0")


def exr_image(width, height, pixels):
    """A complete uncompressed scanline RGB float OpenEXR image of `pixels` ([r, g, b], row major)."""
    head = exr_header(width, height)
    line_bytes = 3 * 4 * width
    table_end = len(head) + 8 * height
    offsets = b"".join(struct.pack("<Q", table_end + y * (8 + line_bytes)) for y in range(height))
    lines = b""
    for y in range(height):
        row = pixels[y * width:(y + 1) * width]
        data = b"".join(struct.pack(f"<{width}f", *(p[c] for p in row)) for c in (2, 1, 0))
        lines += struct.pack("<ii", y, len(data)) + data
    return head + offsets + lines


def data_files():
    d = os.path.join(HERE, "data")
    os.makedirs(d, exist_ok=True)

    def write(name, data):
        mode = "wb" if isinstance(data, bytes) else "w"
        with open(os.path.join(HERE, name), mode) as f:
            f.write(data)

    garbage = bytes((i * 7919 + 13) % 256 for i in range(512))
    write("xml-binary-garbage.xml", garbage)
    write("glb-bad-magic.glb", b"glTX" + struct.pack("<II", 2, 64) + garbage[:52])
    gltf_files(write)
    # Included by include-cycle.xml, and including it again; a lone <bsdf> of no known type.
    write("data/include-cycle-b.xml", '<scene version="3.0.0">\n    <include filename="../include-cycle.xml"/>\n</scene>\n')
    write("data/include-bad-bsdf.xml", '<bsdf version="3.0.0" type="no-such-bsdf"/>\n')

    # PLY: a valid binary triangle, then faults.
    hdr = ("ply\nformat binary_little_endian 1.0\nelement vertex {n}\nproperty float x\n"
           "property float y\nproperty float z\nelement face {f}\n"
           "property list uchar int vertex_indices\nend_header\n")
    verts = struct.pack("<9f", 0, 0, 0, 1, 0, 0, 0, 1, 0)
    face = struct.pack("<Biii", 3, 0, 1, 2)
    write("data/truncated.ply", hdr.format(n=3, f=1).encode() + verts[:20])
    write("data/bad-header.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty flaot y\nend_header\n")
    write("data/bad-index.ply", hdr.format(n=3, f=1).encode() + verts + struct.pack("<Biii", 3, 0, 1, 7))
    write("data/huge-count.ply", hdr.format(n=4000000000, f=1).encode() + verts + face)
    write("data/huge-list.ply", hdr.format(n=3, f=1).encode() + verts + struct.pack("<B", 255) + b"\0" * 8)
    write("data/nan-vertex.ply", hdr.format(n=3, f=1).encode()
          + struct.pack("<9f", 0, 0, 0, float("nan"), 0, 0, 0, 1, 0) + face)
    write("data/garbage.ply", garbage)

    write("data/bad-index.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n")
    write("data/bad-number.obj", "v 0 0 0\nv 1 zero 0\nv 0 1 0\nf 1 2 3\n")
    write("data/nan-vertex.obj", "v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n")
    write("data/garbage.obj", garbage)
    write("data/no-faces.obj", "# only vertices\nv 0 0 0\nv 1 0 0\nv 0 1 0\n")

    good_png = png(4, 2, b"".join(b"\0" + bytes(12) for _ in range(2)))
    write("data/truncated.png", good_png[:45])
    corrupt = bytearray(good_png)
    idat = corrupt.index(b"IDAT") + 4
    corrupt[idat:idat + 6] = b"\xde\xad\xbe\xef\x00\x01"
    write("data/corrupt.png", bytes(corrupt))
    write("data/huge.png", png(1000000, 1000000, b"\0" * 16))

    write("data/truncated.exr", exr_header(64, 32) + b"\0" * 40)
    write("data/garbage.exr", struct.pack("<ii", 20000630, 2) + garbage)
    write("data/huge.exr", exr_header(2000000000, 2000000000) + b"\0" * 64)

    hdr_head = b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n"
    write("data/truncated.hdr", hdr_head + b"-Y 16 +X 16\n" + b"\x80\x80\x80\x81" * 10)
    write("data/huge.hdr", hdr_head + b"-Y 1000000 +X 1000000\n" + b"\x80\x80\x80\x81" * 16)
    write("data/large.exr", exr_header(100000, 100000) + b"\0" * 64)
    write("data/nan.exr", exr_image(4, 2, [[1.0, float("nan"), 1.0]] * 8))


def main():
    data_files()
    lines = []
    for name, where, text in CASES:
        if text is not None:
            with open(os.path.join(HERE, name), "w") as f:
                f.write(text)
        lines.append(f"{name} {where}")
    with open(os.path.join(HERE, "EXPECTED"), "w") as f:
        f.write("# scene file, then the location its one-line error must name (written by make_corpus.py)\n")
        f.write("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
