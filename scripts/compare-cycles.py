#!/usr/bin/env python3
"""Compare rayterm's glTF metallic-roughness shading with Blender Cycles.

The script writes small glTF 2.0 test scenes (.glb, built here with json and
struct, so that it is known exactly what each file holds), renders each with
rayterm (its linear EXR film) and with Cycles (the same file through
Blender's own glTF importer, in the `bpy` module), and compares the two
linear images.  It is a manual check: nothing in the build or the tests
runs it.  docs/pbr-check.md has the results and what they mean.

Needs Python 3.11 with `bpy` 4.2 (pip install bpy==4.2.0) and numpy, and a
rayterm binary in which a glTF file with lights of its own gets no ambient
term.  Usage:

    scripts/compare-cycles.py [--rayterm target/release/rayterm]
                              [--out compare-cycles-out] [--size 160x120]
                              [--spp 256] [--scenes a,c]
                              [--distribution MULTI_GGX|GGX] [--analytic]
                              [--integrator path|whitted] [--depth 8]

Outputs, under --out (default compare-cycles-out/ in the repository, which
git ignores), per scene NAME and Cycles distribution DIST (multi_ggx, ggx;
multi_ggx-whitted and ggx-whitted with --integrator whitted):
    NAME.glb                 the test scene
    NAME.rayterm.exr         rayterm's linear film (the last run's)
    NAME.cycles-DIST.exr     Cycles' linear render
    NAME.DIST.side.png       rayterm | Cycles | heat map of the ratio (sRGB,
                             one exposure for both pictures)
    NAME.DIST.diff.png       the heat map alone: log2(rayterm / Cycles),
                             white equal, red rayterm brighter, blue darker,
                             saturated at one stop, black where unlit
    summary-DIST.json        the numbers printed at the end

The scenes (glTF is Y-up, in metres; each has a light of its own, since
rayterm gives a glTF file without lights a default key light and a grey
environment light, which the Cycles render would not have):
    a_spheres      six spheres, roughness 0.2, 0.5, 1 x metallic 0, 1, base
                   colour (0.8, 0.3, 0.2), on a grey (0.5) diffuse floor, one
                   point light of 300 cd
    b_diffuse      a grey diffuse sphere on the floor, a point light of 200 cd
    c_spot         a spot light (inner cone 20 deg, outer 35 deg, 500 cd) on
                   the floor
    d_directional  a directional light of 3 lx, oblique, on the floor and a
                   half-rough dielectric sphere
    e_emissive     an emissive quad (emissiveFactor (1, 0.5, 0.25), emissive
                   strength 4, black base colour) facing the camera; its
                   only light is behind it and lights nothing that is seen
    f_sky          a rough gold metal and a smooth red dielectric sphere on
                   the floor under a constant sky (0.5, 0.6, 0.8), no lights
    g_glow         a glowing sphere (emissive (1, 0.7, 0.4) x 6) beside a grey
                   sphere on the floor, in a black world: the emitter is the
                   only light
    h_textured     a sphere with a checker base colour texture, a
                   metallic-roughness texture (metal squares, roughness bands)
                   and a normal map of bumps, under a point light

Matching the two renderers
--------------------------
* Light units.  KHR_lights_punctual gives point and spot lights in candela
  and directional lights in lux; rayterm uses those numbers as they are (a
  point light of I cd gives I / d^2 on a surface facing it, and the film is
  in the same unit per steradian).  Blender's importer option
  `export_import_convert_lighting_mode` decides the conversion to watts:
    - 'SPEC' (the default, "Standard"): W = cd * 4 pi / 683 for point and
      spot lights, W/m^2 = lx / 683 for suns: right for Blender's radiometric
      watts, but the picture is then 683 times darker than one in
      photometric units, while emissive materials are imported unscaled
      (1 nit -> strength 1), so lights and emission would disagree;
    - 'COMPAT' ("Unitless"): W = cd * 4 pi, W/m^2 = lx.  A Cycles point
      light of P watts has a radiant intensity of P / (4 pi) per steradian,
      so 1 cd becomes 1 "W/sr" and 1 lx 1 "W/m^2": the numbers rayterm
      uses, and consistent with the unscaled emission.
  The script imports with 'COMPAT', so that neither image is scaled ('SPEC'
  and multiplying Cycles by 683 would be the same up to rounding).
* Punctual lights.  Point and spot lights get radius 0 and soft falloff off
  (Blender's defaults give them a radius and a soft falloff near the light);
  suns get angle 0 (Blender's default is about 0.53 deg), so that shadows
  and highlights come from a point or a single direction as in glTF.
* Spot cones.  glTF (and rayterm) ramp t = (cos - cos_outer) / (cos_inner -
  cos_outer) and square it between the two cones.  Cycles ramps with a
  smoothstep (3t^2 - 2t^3) from cos_outer over (1 - cos_outer) * spot_blend.
  The importer sets spot_blend from the ratio of the angles; the script sets
  spot_blend = (cos_inner - cos_outer) / (1 - cos_outer), so that both ramps
  start and end at the same angles.  Their shapes still differ.
* Light paths.  With --integrator path (the default) both renderers follow
  --depth bounces (default 8) after the first hit: rayterm with
  --integrator path --max-depth N, Cycles with max, diffuse and glossy
  bounces N and reflective caustics on (rayterm's paths carry them).  With
  --integrator whitted rayterm gives direct light plus specular reflection
  rays, and Cycles gets diffuse_bounces 0, glossy_bounces = max_bounces = 4
  (so that glossy rays see the direct light on what they hit, as rayterm's
  reflection rays do) and caustics off.  Either way transmission, volume
  and transparent bounces are 0, and there is no sample clamping, no glossy filter
  (rayterm: --no regularize), no light tree, no denoising, adaptive
  sampling off, and a black world, except for the scenes lit by a constant
  sky (WORLD below: rayterm's --env, Cycles' world colour).
* Film.  rayterm jitters its samples uniformly over each pixel (a box filter
  one pixel wide); Cycles gets the box filter of width 1.  Both write linear
  32-bit float EXR, exposure 0, Standard view transform; rayterm's EXR is
  its film before bloom (bloom is off anyway).
* Camera.  glTF's yfov is the vertical field of view and the horizontal one
  follows from the image's aspect; rayterm does that.  The script sets the
  imported camera to sensor_fit 'VERTICAL' with angle_y = yfov, which does
  the same in Blender whatever the image's aspect.
* The BSDF.  The importer maps a metallic-roughness material to a Principled
  BSDF, which is not glTF's Appendix B BRDF: by default its GGX is
  multiple-scattering (rough metals brighter), its dielectric Fresnel is the
  exact one for IOR 1.5 rather than Schlick with F0 = 0.04, and its diffuse
  base is scaled by one minus the specular layer's directional albedo
  rather than by 1 - F(v.h).  With --distribution GGX the script switches
  the Principled BSDFs to single-scattering GGX, which removes the first of
  these differences.

Comparison: over the pixels where either image's luminance exceeds 1 % of
the larger of the two images' 99.9th percentiles ("lit"), the script reports
the median of rayterm / Cycles (of luminance), the ratio of their means,
and the shares of pixels whose
ratio is within 10 % and 20 % of 1; then the same per object (the pixels
next to an outline left out, which the two renderers' jitter covers
differently) and, for the spot, inside the inner cone alone.

--analytic does not run Cycles: it renders a_spheres with rayterm's path
tracer at --max-depth 0 (direct light only), and compares each sphere's pixels
with glTF's Appendix B BRDF x cosine x I / d^2 evaluated here at the pixel
centres, printing quantiles of rayterm / analytic (red channel).
"""

import argparse
import json
import math
import os
import struct
import subprocess
import sys
import time
import zlib

import numpy as np

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))

# --------------------------------------------------------------------------
# A minimal glTF 2.0 (.glb) writer
# --------------------------------------------------------------------------


def normalize(v):
    n = math.sqrt(sum(c * c for c in v))
    return [c / n for c in v]


def cross(a, b):
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]


def sub(a, b):
    return [x - y for x, y in zip(a, b)]


def quat_from_basis(x, y, z):
    """Unit quaternion (x, y, z, w) of the rotation whose matrix has
    columns x, y, z (each unit, right-handed)."""
    m00, m01, m02 = x[0], y[0], z[0]
    m10, m11, m12 = x[1], y[1], z[1]
    m20, m21, m22 = x[2], y[2], z[2]
    tr = m00 + m11 + m22
    if tr > 0:
        s = math.sqrt(tr + 1.0) * 2
        w, qx, qy, qz = 0.25 * s, (m21 - m12) / s, (m02 - m20) / s, (m10 - m01) / s
    elif m00 > m11 and m00 > m22:
        s = math.sqrt(1.0 + m00 - m11 - m22) * 2
        w, qx, qy, qz = (m21 - m12) / s, 0.25 * s, (m01 + m10) / s, (m02 + m20) / s
    elif m11 > m22:
        s = math.sqrt(1.0 + m11 - m00 - m22) * 2
        w, qx, qy, qz = (m02 - m20) / s, (m01 + m10) / s, 0.25 * s, (m12 + m21) / s
    else:
        s = math.sqrt(1.0 + m22 - m00 - m11) * 2
        w, qx, qy, qz = (m10 - m01) / s, (m02 + m20) / s, (m12 + m21) / s, 0.25 * s
    return [qx, qy, qz, w]


def look_rotation(eye, target, up=(0.0, 1.0, 0.0)):
    """Rotation that turns a glTF camera or light (looking down its -Z, up
    +Y) to look from `eye` toward `target`."""
    f = normalize(sub(target, eye))
    if abs(sum(a * b for a, b in zip(f, up))) > 0.999:
        up = (0.0, 0.0, -1.0)
    r = normalize(cross(f, up))
    u = cross(r, f)
    return quat_from_basis(r, u, [-c for c in f])


class Gltf:
    """Collects meshes, materials, nodes, a camera and lights, then writes
    one .glb with a single binary buffer."""

    def __init__(self):
        self.bin = bytearray()
        self.doc = {
            "asset": {"version": "2.0", "generator": "rayterm scripts/compare-cycles.py"},
            "scene": 0,
            "scenes": [{"nodes": []}],
            "nodes": [],
            "meshes": [],
            "materials": [],
            "accessors": [],
            "bufferViews": [],
            "buffers": [],
            "cameras": [],
            "extensionsUsed": ["KHR_lights_punctual"],
            "extensions": {"KHR_lights_punctual": {"lights": []}},
        }
        # Kept for the per-object statistics (see object_labels).
        self.spheres = []  # (name, centre, radius)
        self.floors = []  # names of quads lying in y = 0
        self.view = None  # (eye, target, yfov)

    def _view(self, data, target):
        while len(self.bin) % 4:
            self.bin.append(0)
        self.doc["bufferViews"].append(
            {"buffer": 0, "byteOffset": len(self.bin), "byteLength": len(data), "target": target}
        )
        self.bin.extend(data)
        return len(self.doc["bufferViews"]) - 1

    def _accessor(self, values, kind, comps):
        if kind == "SCALAR":
            flat = list(values)
            data = struct.pack("<%dI" % len(flat), *flat)
            view = self._view(data, 34963)
            acc = {"bufferView": view, "componentType": 5125, "count": len(flat), "type": "SCALAR"}
        else:
            flat = [c for v in values for c in v]
            data = struct.pack("<%df" % len(flat), *flat)
            view = self._view(data, 34962)
            acc = {"bufferView": view, "componentType": 5126, "count": len(values), "type": kind}
            if comps == 3:
                acc["min"] = [min(v[i] for v in values) for i in range(3)]
                acc["max"] = [max(v[i] for v in values) for i in range(3)]
        self.doc["accessors"].append(acc)
        return len(self.doc["accessors"]) - 1

    def texture(self, rgb):
        """An embedded PNG texture of an (h, w, 3) uint8 array."""
        view = self._view(png_bytes(rgb), None)
        del self.doc["bufferViews"][view]["target"]
        self.doc.setdefault("images", []).append({"bufferView": view, "mimeType": "image/png"})
        self.doc.setdefault("textures", []).append({"source": len(self.doc["images"]) - 1})
        return len(self.doc["textures"]) - 1

    def material(self, name, base=(0.8, 0.8, 0.8), metallic=0.0, roughness=1.0,
                 emissive=None, emissive_strength=None, base_tex=None, mr_tex=None,
                 normal_tex=None):
        m = {
            "name": name,
            "pbrMetallicRoughness": {
                "baseColorFactor": [base[0], base[1], base[2], 1.0],
                "metallicFactor": metallic,
                "roughnessFactor": roughness,
            },
        }
        if base_tex is not None:
            m["pbrMetallicRoughness"]["baseColorTexture"] = {"index": base_tex}
        if mr_tex is not None:
            m["pbrMetallicRoughness"]["metallicRoughnessTexture"] = {"index": mr_tex}
        if normal_tex is not None:
            m["normalTexture"] = {"index": normal_tex}
        if emissive is not None:
            m["emissiveFactor"] = list(emissive)
        if emissive_strength is not None:
            m.setdefault("extensions", {})["KHR_materials_emissive_strength"] = {
                "emissiveStrength": emissive_strength
            }
            if "KHR_materials_emissive_strength" not in self.doc["extensionsUsed"]:
                self.doc["extensionsUsed"].append("KHR_materials_emissive_strength")
        self.doc["materials"].append(m)
        return len(self.doc["materials"]) - 1

    def mesh(self, name, positions, normals, indices, material, uvs=None):
        p = self._accessor(positions, "VEC3", 3)
        n = self._accessor(normals, "VEC3", 3)
        i = self._accessor(indices, "SCALAR", 1)
        attributes = {"POSITION": p, "NORMAL": n}
        if uvs is not None:
            attributes["TEXCOORD_0"] = self._accessor(uvs, "VEC2", 2)
        self.doc["meshes"].append(
            {"name": name, "primitives": [{"attributes": attributes,
                                           "indices": i, "material": material}]}
        )
        return len(self.doc["meshes"]) - 1

    def node(self, name, translation=None, rotation=None, **extra):
        n = {"name": name}
        if translation is not None:
            n["translation"] = list(translation)
        if rotation is not None:
            n["rotation"] = list(rotation)
        n.update(extra)
        self.doc["nodes"].append(n)
        self.doc["scenes"][0]["nodes"].append(len(self.doc["nodes"]) - 1)
        return len(self.doc["nodes"]) - 1

    def sphere(self, name, center, radius, material, segments=64, rings=32):
        pos, nor, idx, uv = [], [], [], []
        for j in range(rings + 1):
            theta = math.pi * j / rings
            for i in range(segments + 1):
                phi = 2 * math.pi * i / segments
                n = [math.sin(theta) * math.cos(phi), math.cos(theta), -math.sin(theta) * math.sin(phi)]
                nor.append(n)
                pos.append([radius * c for c in n])
                uv.append([i / segments, j / rings])
        w = segments + 1
        for j in range(rings):
            for i in range(segments):
                a, b, c, d = j * w + i, j * w + i + 1, (j + 1) * w + i, (j + 1) * w + i + 1
                if j != 0:
                    idx += [a, c, b]
                if j != rings - 1:
                    idx += [b, c, d]
        m = self.mesh(name, pos, nor, idx, material, uv)
        self.spheres.append((name, center, radius))
        return self.node(name, translation=center, mesh=m)

    def quad(self, name, center, half_x, half_y, material, facing="up"):
        """A square of 2*half_x by 2*half_y: on the floor (facing +Y) or
        upright (facing +Z)."""
        cx, cy, cz = center
        if facing == "up":
            pos = [[cx - half_x, cy, cz + half_y], [cx + half_x, cy, cz + half_y],
                   [cx + half_x, cy, cz - half_y], [cx - half_x, cy, cz - half_y]]
            n = [0.0, 1.0, 0.0]
        else:
            pos = [[cx - half_x, cy - half_y, cz], [cx + half_x, cy - half_y, cz],
                   [cx + half_x, cy + half_y, cz], [cx - half_x, cy + half_y, cz]]
            n = [0.0, 0.0, 1.0]
        m = self.mesh(name, pos, [n] * 4, [0, 1, 2, 0, 2, 3], material)
        if facing == "up" and cy == 0.0:
            self.floors.append(name)
        return self.node(name, mesh=m)

    def camera(self, name, eye, target, yfov, aspect):
        self.doc["cameras"].append(
            {"name": name, "type": "perspective",
             "perspective": {"yfov": yfov, "aspectRatio": aspect, "znear": 0.05, "zfar": 100.0}}
        )
        self.view = (eye, target, yfov)
        return self.node(name, translation=eye, rotation=look_rotation(eye, target),
                         camera=len(self.doc["cameras"]) - 1)

    def light(self, name, kind, intensity, position=None, target=None, color=(1.0, 1.0, 1.0),
              inner=None, outer=None):
        light = {"name": name, "type": kind, "intensity": intensity, "color": list(color)}
        if kind == "spot":
            light["spot"] = {"innerConeAngle": inner, "outerConeAngle": outer}
        lights = self.doc["extensions"]["KHR_lights_punctual"]["lights"]
        lights.append(light)
        ext = {"extensions": {"KHR_lights_punctual": {"light": len(lights) - 1}}}
        rot = look_rotation(position, target) if target is not None else None
        return self.node(name, translation=position, rotation=rot, **ext)

    def write(self, path):
        while len(self.bin) % 4:
            self.bin.append(0)
        self.doc["buffers"] = [{"byteLength": len(self.bin)}]
        doc = {k: v for k, v in self.doc.items() if v != []}
        js = json.dumps(doc, separators=(",", ":")).encode()
        js += b" " * ((4 - len(js) % 4) % 4)
        total = 12 + 8 + len(js) + 8 + len(self.bin)
        with open(path, "wb") as f:
            f.write(struct.pack("<III", 0x46546C67, 2, total))
            f.write(struct.pack("<II", len(js), 0x4E4F534A) + js)
            f.write(struct.pack("<II", len(self.bin), 0x004E4942) + bytes(self.bin))


# --------------------------------------------------------------------------
# The test scenes (glTF is Y-up, metres)
# --------------------------------------------------------------------------

ASPECT = 4.0 / 3.0
BASE = (0.8, 0.3, 0.2)
GREY = (0.5, 0.5, 0.5)


def floor(g, half=6.0):
    m = g.material("floor", base=GREY, metallic=0.0, roughness=1.0)
    g.quad("floor", (0.0, 0.0, 0.0), half, half, m)


def scene_a():
    """Spheres of roughness 0.2, 0.5, 1.0 (columns) x metallic 0 (front
    row) and 1 (back row), base colour BASE, on a grey diffuse floor, one
    point light of 300 cd."""
    g = Gltf()
    floor(g)
    for row, metallic in enumerate((0.0, 1.0)):
        for col, rough in enumerate((0.2, 0.5, 1.0)):
            m = g.material("m%g_r%g" % (metallic, rough), base=BASE, metallic=metallic, roughness=rough)
            g.sphere("sphere_m%g_r%g" % (metallic, rough), ((col - 1) * 1.1, 0.45, 0.6 - row * 1.2), 0.45, m)
    g.camera("cam", (0.0, 2.4, 4.6), (0.0, 0.35, 0.0), 0.62, ASPECT)
    g.light("key", "point", 300.0, position=(1.5, 4.0, 3.0))
    return g


def scene_b():
    """A grey diffuse sphere on the grey floor under a point light."""
    g = Gltf()
    floor(g)
    m = g.material("grey", base=GREY, metallic=0.0, roughness=1.0)
    g.sphere("sphere", (0.0, 0.6, 0.0), 0.6, m)
    g.camera("cam", (0.0, 1.8, 4.0), (0.0, 0.5, 0.0), 0.7, ASPECT)
    g.light("key", "point", 200.0, position=(-1.0, 3.0, 1.5))
    return g


def scene_c():
    """A spot light (inner 20 deg, outer 35 deg, 500 cd) on the floor."""
    g = Gltf()
    floor(g)
    g.camera("cam", (0.0, 3.0, 4.5), (0.0, 0.0, 0.0), 0.8, ASPECT)
    g.light("spot", "spot", 500.0, position=(0.0, 3.0, 0.0), target=(0.3, 0.0, 0.0),
            inner=math.radians(20.0), outer=math.radians(35.0))
    return g


def scene_d():
    """A directional light of 3 lux, falling obliquely, on a floor and a
    half-rough dielectric sphere."""
    g = Gltf()
    floor(g)
    m = g.material("sphere", base=BASE, metallic=0.0, roughness=0.5)
    g.sphere("sphere", (0.0, 0.6, 0.0), 0.6, m)
    g.camera("cam", (0.0, 1.8, 4.0), (0.0, 0.5, 0.0), 0.7, ASPECT)
    g.light("sun", "directional", 3.0, position=(2.0, 4.0, 2.0), target=(0.0, 0.0, 0.0))
    return g


def scene_e():
    """An upright emissive quad (emissiveFactor (1, 0.5, 0.25) at strength
    4, black base colour) facing the camera, alone; the only light sits
    behind it, facing its back, so that it adds nothing to the front."""
    g = Gltf()
    m = g.material("glow", base=(0.0, 0.0, 0.0), metallic=0.0, roughness=1.0,
                   emissive=(1.0, 0.5, 0.25), emissive_strength=4.0)
    g.quad("glow", (0.0, 1.0, 0.0), 0.8, 0.6, m, facing="camera")
    g.camera("cam", (0.6, 1.3, 3.5), (0.0, 1.0, 0.0), 0.6, ASPECT)
    g.light("behind", "point", 10.0, position=(0.0, 1.0, -3.0))
    return g


def scene_f():
    """A rough gold metal sphere and a smooth red dielectric one on the
    grey floor, lit only by a constant blue-grey sky of radiance (0.5, 0.6,
    0.8): what metals reflect and the floor's bounce light."""
    g = Gltf()
    floor(g)
    gold = g.material("gold", base=(1.0, 0.78, 0.34), metallic=1.0, roughness=0.35)
    red = g.material("red", base=BASE, metallic=0.0, roughness=0.15)
    g.sphere("sphere_gold", (-0.7, 0.6, 0.0), 0.6, gold)
    g.sphere("sphere_red", (0.7, 0.6, 0.0), 0.6, red)
    g.camera("cam", (0.0, 1.8, 4.0), (0.0, 0.5, 0.0), 0.7, ASPECT)
    return g


def scene_g():
    """A glowing sphere (emissiveFactor (1, 0.7, 0.4) at strength 6) beside
    a grey sphere on the grey floor, in a black world: the emitter is the
    only light."""
    g = Gltf()
    floor(g)
    glow = g.material("glow", base=(0.0, 0.0, 0.0), metallic=0.0, roughness=1.0,
                      emissive=(1.0, 0.7, 0.4), emissive_strength=6.0)
    grey = g.material("grey", base=GREY, metallic=0.0, roughness=0.6)
    g.sphere("sphere_glow", (-0.6, 0.9, -0.3), 0.35, glow)
    g.sphere("sphere_grey", (0.5, 0.5, 0.2), 0.5, grey)
    g.camera("cam", (0.0, 1.8, 4.0), (0.0, 0.5, 0.0), 0.7, ASPECT)
    return g


def scene_h():
    """A textured sphere on the floor under a point light of 250 cd: a
    checker base colour (sRGB), a metallic-roughness texture (metal
    squares of the checker, roughness in bands from 0.25 to 0.85) and a
    normal map of bumps (tangent space, from the texture coordinates)."""
    g = Gltf()
    floor(g)
    n = 256
    y, x = np.mgrid[0:n, 0:n] / n
    checker = ((np.floor(x * 8) + np.floor(y * 4)) % 2).astype(bool)
    base = np.where(checker[..., None], [230, 200, 120], [60, 110, 180]).astype(np.uint8)
    rough = 0.25 + 0.6 * np.floor(y * 6) / 5
    mr = np.zeros((n, n, 3), dtype=np.uint8)
    mr[..., 1] = (rough * 255).astype(np.uint8)
    mr[..., 2] = np.where(checker, 255, 0)
    # Bumps: the slope of sin(2 pi 16 u) sin(2 pi 8 v) as tangent-space normals.
    du = 0.35 * np.cos(2 * np.pi * 16 * x) * np.sin(2 * np.pi * 8 * y)
    dv = 0.35 * np.sin(2 * np.pi * 16 * x) * np.cos(2 * np.pi * 8 * y)
    nrm = np.stack([-du, -dv, np.ones_like(du)], -1)
    nrm /= np.linalg.norm(nrm, axis=-1, keepdims=True)
    normal = ((nrm * 0.5 + 0.5) * 255 + 0.5).astype(np.uint8)
    m = g.material("textured", base=(1.0, 1.0, 1.0), metallic=1.0, roughness=1.0,
                   base_tex=g.texture(base), mr_tex=g.texture(mr), normal_tex=g.texture(normal))
    g.sphere("sphere", (0.0, 0.7, 0.0), 0.7, m)
    g.camera("cam", (0.0, 1.8, 4.0), (0.0, 0.6, 0.0), 0.7, ASPECT)
    g.light("key", "point", 250.0, position=(-1.5, 3.5, 2.5))
    return g


def scene_i():
    """A cage: a sphere whose base colour texture's alpha cuts it into
    bands (alphaMode MASK, cutoff 0.5), on the floor under a point light
    of 250 cd: camera rays see the floor through the gaps, and the
    light's shadow rays pass them, so the shadow is striped too."""
    g = Gltf()
    floor(g)
    n = 256
    y, x = np.mgrid[0:n, 0:n] / n
    rgba = np.zeros((n, n, 4), dtype=np.uint8)
    rgba[..., :3] = (200, 120, 60)
    rgba[..., 3] = np.where((np.floor(y * 12) % 2) == 0, 255, 0)
    m = g.material("cage", base=(1.0, 1.0, 1.0), metallic=0.0, roughness=0.6,
                   base_tex=g.texture(rgba))
    g.doc["materials"][m]["alphaMode"] = "MASK"
    g.sphere("sphere", (0.0, 0.8, 0.0), 0.7, m)
    g.camera("cam", (0.0, 1.8, 4.0), (0.0, 0.6, 0.0), 0.7, ASPECT)
    g.light("key", "point", 250.0, position=(-1.0, 3.5, 1.5))
    return g


SCENES = {
    "a_spheres": scene_a,
    "b_diffuse": scene_b,
    "c_spot": scene_c,
    "d_directional": scene_d,
    "e_emissive": scene_e,
    "f_sky": scene_f,
    "g_glow": scene_g,
    "h_textured": scene_h,
    "i_alpha": scene_i,
}

# The world each scene is lit by besides its lights: a constant linear
# colour given to rayterm as --env and to Cycles as its world's colour.
# Scenes without lights of their own need one (black for none), or
# rayterm would give them its default light.
WORLD = {
    "f_sky": (0.5, 0.6, 0.8),
    "g_glow": (0.0, 0.0, 0.0),
}

# --------------------------------------------------------------------------
# Rendering
# --------------------------------------------------------------------------


def render_rayterm(binary, glb, exr, size, spp, extra=()):
    # No regularization: Cycles runs without its glossy filter too.
    cmd = [binary, "render", glb, "-o", exr, "--size", size, "--spp", str(spp), "--no", "bloom",
           "--no", "regularize",
           "--progress", "none", *extra]
    subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL)


def png_bytes(rgb):
    """An 8-bit RGB (or RGBA) PNG of an (h, w, 3 or 4) uint8 array."""
    h, w, channels = rgb.shape
    raw = b"".join(b"\0" + rgb[y].tobytes() for y in range(h))

    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))

    colour = {3: 2, 4: 6}[channels]
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, colour, 0, 0, 0))
            + chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b""))


def glb_json(glb):
    with open(glb, "rb") as f:
        data = f.read()
    n = struct.unpack("<I", data[12:16])[0]
    return json.loads(data[20:20 + n])


class quiet_stdout:
    """Silence a block's writes to file descriptor 1 (Cycles' progress)."""

    def __enter__(self):
        sys.stdout.flush()
        self.saved = os.dup(1)
        self.null = os.open(os.devnull, os.O_WRONLY)
        os.dup2(self.null, 1)

    def __exit__(self, *exc):
        sys.stdout.flush()
        os.dup2(self.saved, 1)
        os.close(self.null)
        os.close(self.saved)


def render_cycles(glb, exr, width, height, spp, distribution, depth, world):
    import bpy

    doc = glb_json(glb)
    bpy.ops.wm.read_factory_settings(use_empty=True)
    # 'COMPAT': 1 cd -> 4 pi W, 1 lx -> 1 W/m^2 (see the docstring).
    bpy.ops.import_scene.gltf(filepath=glb, export_import_convert_lighting_mode="COMPAT")
    scene = bpy.context.scene

    cam = next(o for o in scene.objects if o.type == "CAMERA")
    scene.camera = cam
    cam.data.sensor_fit = "VERTICAL"
    cam.data.angle_y = doc["cameras"][0]["perspective"]["yfov"]

    lights = doc.get("extensions", {}).get("KHR_lights_punctual", {}).get("lights", [])
    by_name = {light["name"]: light for light in lights}
    for o in scene.objects:
        if o.type != "LIGHT":
            continue
        ld = o.data
        if ld.type in ("POINT", "SPOT"):
            ld.shadow_soft_size = 0.0
            ld.use_soft_falloff = False
        if ld.type == "SUN":
            ld.angle = 0.0
        if ld.type == "SPOT":
            spot = by_name[ld.name]["spot"]
            ci, co = math.cos(spot["innerConeAngle"]), math.cos(spot["outerConeAngle"])
            ld.spot_blend = (ci - co) / (1.0 - co)

    for mat in bpy.data.materials:
        for node in mat.node_tree.nodes if mat.node_tree else ():
            if node.type == "BSDF_PRINCIPLED":
                node.distribution = distribution

    sky = bpy.data.worlds.new("world")
    sky.use_nodes = True
    sky.node_tree.nodes["Background"].inputs["Strength"].default_value = 1.0
    sky.node_tree.nodes["Background"].inputs["Color"].default_value = (*world, 1)
    scene.world = sky

    r = scene.render
    r.engine = "CYCLES"
    r.resolution_x, r.resolution_y, r.resolution_percentage = width, height, 100
    r.pixel_aspect_x = r.pixel_aspect_y = 1.0
    r.film_transparent = False
    r.use_compositing = False
    r.use_sequencer = False
    r.image_settings.file_format = "OPEN_EXR"
    r.image_settings.color_depth = "32"
    r.image_settings.color_mode = "RGB"
    r.image_settings.exr_codec = "ZIP"
    scene.view_settings.view_transform = "Standard"
    scene.view_settings.exposure = 0.0
    scene.view_settings.look = "None"

    c = scene.cycles
    c.device = "CPU"
    c.samples = spp
    c.use_adaptive_sampling = False
    c.use_denoising = False
    if depth is None:
        # Whitted: direct light, and glossy rays that see it.
        c.max_bounces = 4
        c.diffuse_bounces = 0
        c.glossy_bounces = 4
        c.caustics_reflective = False
    else:
        c.max_bounces = c.diffuse_bounces = c.glossy_bounces = depth
        c.caustics_reflective = True
    c.transmission_bounces = 0
    c.volume_bounces = 0
    # Alpha cut-outs: rayterm passes at most 64 such surfaces a ray.
    c.transparent_max_bounces = 64
    c.caustics_refractive = False
    c.sample_clamp_direct = 0.0
    c.sample_clamp_indirect = 0.0
    c.blur_glossy = 0.0
    # Blender 5 renamed the pixel filter's setting.
    if hasattr(c, "pixel_filter_type"):
        c.pixel_filter_type = "BOX"
    else:
        c.filter_type = "BOX"
    c.filter_width = 1.0
    c.film_exposure = 1.0  # a multiplier in Cycles: 1 is none
    c.use_light_tree = False
    c.seed = 1

    r.filepath = exr
    bpy.ops.render.render(write_still=True)


def read_exr(path):
    """RGB float array (rows top to bottom) of an EXR, through Blender's
    image loader."""
    import bpy

    img = bpy.data.images.load(path, check_existing=False)
    img.colorspace_settings.is_data = True
    w, h = img.size
    px = np.empty(w * h * 4, dtype=np.float32)
    img.pixels.foreach_get(px)
    bpy.data.images.remove(img)
    return px.reshape(h, w, 4)[::-1, :, :3].copy()


# --------------------------------------------------------------------------
# Comparison
# --------------------------------------------------------------------------


def camera_rays(view, width, height):
    """The camera's eye and the unit directions through the pixel centres
    (rows top to bottom), looking from eye to target with vertical field of
    view yfov."""
    eye, target, yfov = view
    f = np.array(normalize(sub(target, eye)))
    r = np.array(normalize(cross(list(f), [0.0, 1.0, 0.0])))
    u = np.cross(r, f)
    t = math.tan(yfov / 2)
    xs = ((np.arange(width) + 0.5) / width * 2 - 1) * t * width / height
    ys = (1 - (np.arange(height) + 0.5) / height * 2) * t
    d = f[None, None, :] + xs[None, :, None] * r[None, None, :] + ys[:, None, None] * u[None, None, :]
    return np.array(eye, dtype=float), d / np.linalg.norm(d, axis=2, keepdims=True)


def object_labels(g, width, height):
    """Per pixel, the name of the sphere (or 'floor') that the ray through
    its centre meets first, '' for none."""
    eye, d = camera_rays(g.view, width, height)
    best = np.full((height, width), np.inf)
    labels = np.full((height, width), "", dtype=object)
    for name, c, rad in g.spheres:
        oc = eye - np.array(c)
        b = (d * oc).sum(2)
        disc = b * b - (oc @ oc - rad * rad)
        t = -b - np.sqrt(np.maximum(disc, 0))
        hit = (disc > 0) & (t > 0) & (t < best)
        best[hit], labels[hit] = t[hit], name
    if g.floors:
        t = -eye[1] / np.where(d[..., 1] != 0, d[..., 1], 1e-12)
        hit = (t > 0) & (t < best)
        best[hit], labels[hit] = t[hit], "floor"
    return labels


def inner_cone_mask(g, width, height):
    """Floor pixels inside the (first) spot light's inner cone, where both
    renderers should give the full intensity."""
    eye, d = camera_rays(g.view, width, height)
    lights = g.doc["extensions"]["KHR_lights_punctual"]["lights"]
    i = next(k for k, light in enumerate(lights) if light["type"] == "spot")
    node = next(n for n in g.doc["nodes"]
                if n.get("extensions", {}).get("KHR_lights_punctual", {}).get("light") == i)
    pos = np.array(node["translation"])
    x, y, z, w = node["rotation"]
    axis = -np.array([2 * (x * z + w * y), 2 * (y * z - w * x), 1 - 2 * (x * x + y * y)])
    t = -eye[1] / np.where(d[..., 1] != 0, d[..., 1], 1e-12)
    p = eye + t[..., None] * d
    to = p - pos
    cos = (to @ axis) / np.linalg.norm(to, axis=2)
    return (t > 0) & (cos > math.cos(lights[i]["spot"]["innerConeAngle"]))


def erode(mask):
    """A mask without the pixels next to its border."""
    m = mask.copy()
    m[1:, :] &= mask[:-1, :]
    m[:-1, :] &= mask[1:, :]
    m[:, 1:] &= mask[:, :-1]
    m[:, :-1] &= mask[:, 1:]
    return m


LUMA = np.array([0.2126, 0.7152, 0.0722], dtype=np.float32)


def compare(rt, cy, within=None):
    lr, lc = rt @ LUMA, cy @ LUMA
    top = max(np.percentile(lr, 99.9), np.percentile(lc, 99.9))
    lit = (lr > 0.01 * top) | (lc > 0.01 * top)
    if within is not None:
        lit &= within
    ratio = np.where(lit, lr / np.maximum(lc, 1e-12), 1.0)
    dev = np.abs(ratio[lit] - 1.0)
    nan = float("nan")
    stats = {
        "lit_pixels": int(lit.sum()),
        "median_ratio": float(np.median(ratio[lit])) if lit.any() else nan,
        "mean_ratio": float(lr[lit].sum() / max(lc[lit].sum(), 1e-12)) if lit.any() else nan,
        "within_10": float((dev <= 0.10).mean() * 100) if lit.any() else nan,
        "within_20": float((dev <= 0.20).mean() * 100) if lit.any() else nan,
    }
    return stats, ratio, lit, top


# --------------------------------------------------------------------------
# Pictures
# --------------------------------------------------------------------------


def srgb(x):
    x = np.clip(x, 0.0, 1.0)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)


def heat(ratio, lit):
    """log2 ratio as colour: blue rayterm darker, red rayterm brighter,
    white equal, saturated at one stop; unlit pixels black."""
    s = np.clip(np.log2(np.maximum(ratio, 1e-6)), -1.0, 1.0)
    img = np.ones(ratio.shape + (3,), dtype=np.float32)
    pos, neg = np.clip(s, 0, 1), np.clip(-s, 0, 1)
    img[..., 1] -= pos + neg
    img[..., 2] -= pos
    img[..., 0] -= neg
    img = np.clip(img, 0, 1)
    img[~lit] = 0.0
    return img


def save_png(path, rgb01, scale=2):
    """An 8-bit RGB PNG of an array in 0..1, each pixel scale x scale."""
    img = np.repeat(np.repeat(rgb01, scale, axis=0), scale, axis=1)
    img = (np.clip(img, 0, 1) * 255 + 0.5).astype(np.uint8)
    h, w, _ = img.shape
    raw = b"".join(b"\0" + img[y].tobytes() for y in range(h))

    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data))

    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0))
                + chunk(b"IDAT", zlib.compress(raw, 9)) + chunk(b"IEND", b""))


# --------------------------------------------------------------------------
# The analytic check
# --------------------------------------------------------------------------


def gltf_brdf_cos(n, v, l, base, metal, rough):
    """glTF 2.0 Appendix B metallic-roughness BRDF times n.l."""
    base = np.array(base, float)
    cl, cv = n @ l, n @ v
    if cl <= 0 or cv <= 0:
        return np.zeros(3)
    h = (v + l) / np.linalg.norm(v + l)
    a2 = (rough * rough) ** 2
    f0 = 0.04 * (1 - metal) + base * metal
    fresnel = f0 + (1 - f0) * (1 - v @ h) ** 5
    nh = n @ h
    d = a2 / (math.pi * (nh * nh * (a2 - 1) + 1) ** 2)
    vis = 0.5 / (cl * math.sqrt(cv * cv * (1 - a2) + a2) + cv * math.sqrt(cl * cl * (1 - a2) + a2))
    return ((1 - fresnel) * base * (1 - metal) / math.pi + fresnel * d * vis) * cl


def analytic(args):
    w, h = 160, 120
    g = scene_a()
    glb = os.path.join(args.out, "a_spheres.glb")
    exr = os.path.join(args.out, "a_spheres.direct.exr")
    g.write(glb)
    render_rayterm(args.rayterm, glb, exr, "%dx%d" % (w, h), 64, ["--max-depth", "0"])
    direct = read_exr(exr)
    labels = object_labels(g, w, h)
    eye, d = camera_rays(g.view, w, h)
    light = g.doc["extensions"]["KHR_lights_punctual"]["lights"][0]
    lnode = next(n for n in g.doc["nodes"] if "extensions" in n)
    lpos, intensity = np.array(lnode["translation"]), light["intensity"]
    print("rayterm (direct light: --max-depth 0) / glTF Appendix B at pixel centres, red channel")
    print("%-16s %6s  %s" % ("sphere", "pixels", "quantiles 5 / 25 / 50 / 75 / 95 %"))
    results = {}
    for mat, (name, c, rad) in zip(g.doc["materials"][1:], g.spheres):
        pbr = mat["pbrMetallicRoughness"]
        ratios = []
        for y, x in zip(*np.nonzero(erode(erode(labels == name)))):
            oc, dd = eye - np.array(c), d[y, x]
            b = dd @ oc
            p = eye + (-b - math.sqrt(b * b - (oc @ oc - rad * rad))) * dd
            n = (p - np.array(c)) / rad
            lv = lpos - p
            d2 = lv @ lv
            a = gltf_brdf_cos(n, -dd, lv / math.sqrt(d2), pbr["baseColorFactor"][:3],
                              pbr["metallicFactor"], pbr["roughnessFactor"]) * intensity / d2
            if a[0] > 1e-3:
                ratios.append(direct[y, x, 0] / a[0])
        q = np.percentile(ratios, [5, 25, 50, 75, 95])
        results[name] = {"pixels": len(ratios), "quantiles": [float(v) for v in q]}
        print("%-16s %6d  %s" % (name, len(ratios), " / ".join("%.3f" % v for v in q)))
    with open(os.path.join(args.out, "summary-analytic.json"), "w") as f:
        json.dump(results, f, indent=1)


# --------------------------------------------------------------------------
# Main
# --------------------------------------------------------------------------


def compare_with_cycles(args):
    width, height = (int(v) for v in args.size.split("x"))
    dist = args.distribution.lower() + ("" if args.integrator == "path" else "-whitted")
    wanted = args.scenes.split(",")
    results = {}
    for name, build in SCENES.items():
        if not any(name.startswith(w) for w in wanted):
            continue
        g = build()
        glb = os.path.join(args.out, name + ".glb")
        g.write(glb)
        rt_exr = os.path.join(args.out, name + ".rayterm.exr")
        cy_exr = os.path.join(args.out, "%s.cycles-%s.exr" % (name, dist))
        world = WORLD.get(name)
        extra = ["--integrator", args.integrator]
        if args.integrator == "path":
            extra += ["--max-depth", str(args.depth)]
        if world is not None:
            extra += ["--env", ",".join("%g" % c for c in world)]
        depth = args.depth if args.integrator == "path" else None
        t0 = time.time()
        render_rayterm(args.rayterm, glb, rt_exr, args.size, args.spp, extra)
        t1 = time.time()
        with quiet_stdout():
            render_cycles(glb, cy_exr, width, height, args.spp, args.distribution, depth,
                          world or (0.0, 0.0, 0.0))
        t2 = time.time()
        rt, cy = read_exr(rt_exr), read_exr(cy_exr)

        stats, ratio, lit, top = compare(rt, cy)
        labels = object_labels(g, width, height)
        stats["objects"] = {}
        for obj in ["floor"] + [sp[0] for sp in g.spheres]:
            if (labels == obj).any():
                o, _, _, _ = compare(rt, cy, erode(labels == obj))
                stats["objects"][obj] = o
        if name.startswith("c_"):
            o, _, _, _ = compare(rt, cy, inner_cone_mask(g, width, height))
            stats["objects"]["inside inner cone"] = o
        stats["seconds_rayterm"], stats["seconds_cycles"] = round(t1 - t0, 1), round(t2 - t1, 1)
        results[name] = stats

        exposure = 0.8 / top  # one for both pictures, so that they compare by eye
        h = heat(ratio, lit)
        gap = np.ones((height, 4, 3), dtype=np.float32)
        side = np.concatenate([srgb(rt * exposure), gap, srgb(cy * exposure), gap, h], axis=1)
        save_png(os.path.join(args.out, "%s.%s.side.png" % (name, dist)), side)
        save_png(os.path.join(args.out, "%s.%s.diff.png" % (name, dist)), h)

    print("rayterm / Cycles (%s, %s), luminance over lit pixels" % (args.integrator, args.distribution))
    print("%-15s %7s %7s %7s %7s %7s" % ("scene", "lit px", "median", "mean", "<=10%", "<=20%"))
    for name, s in results.items():
        print("%-15s %7d %7.3f %7.3f %6.1f%% %6.1f%%" % (
            name, s["lit_pixels"], s["median_ratio"], s["mean_ratio"], s["within_10"], s["within_20"]))
    print("\nby object (pixels next to an outline left out):")
    for name, s in results.items():
        for obj, o in s["objects"].items():
            print("  %-15s %-18s %6d px  median %6.3f  mean %6.3f  <=10%% %5.1f%%  <=20%% %5.1f%%" % (
                name, obj, o["lit_pixels"], o["median_ratio"], o["mean_ratio"], o["within_10"],
                o["within_20"]))
    with open(os.path.join(args.out, "summary-%s.json" % dist), "w") as f:
        json.dump(results, f, indent=1)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--rayterm", default=os.path.join(REPO, "target", "release", "rayterm"),
                    help="the rayterm binary (default: target/release/rayterm)")
    ap.add_argument("--out", default=os.path.join(REPO, "compare-cycles-out"),
                    help="output folder (default: compare-cycles-out/ in the repository)")
    ap.add_argument("--size", default="160x120")
    ap.add_argument("--spp", type=int, default=256)
    ap.add_argument("--scenes", default=",".join(SCENES), help="comma-separated names or prefixes")
    ap.add_argument("--distribution", default="MULTI_GGX", choices=["MULTI_GGX", "GGX"],
                    help="the Principled BSDF's microfacet distribution in Cycles")
    ap.add_argument("--integrator", default="path", choices=["path", "whitted"],
                    help="rayterm's integrator; Cycles follows as many bounces (path) or "
                         "direct light and glossy rays (whitted)")
    ap.add_argument("--depth", type=int, default=8,
                    help="bounces after the first hit for both renderers (path)")
    ap.add_argument("--analytic", action="store_true",
                    help="compare rayterm's direct light with glTF's BRDF instead of Cycles")
    args = ap.parse_args()
    if not os.access(args.rayterm, os.X_OK):
        sys.exit("no rayterm binary at %s (cargo build --release, or --rayterm PATH)" % args.rayterm)
    os.makedirs(args.out, exist_ok=True)
    if args.analytic:
        analytic(args)
    else:
        compare_with_cycles(args)
    # bpy 4.2 can crash while the interpreter shuts down; the work is done.
    sys.stdout.flush()
    os._exit(0)


if __name__ == "__main__":
    main()
