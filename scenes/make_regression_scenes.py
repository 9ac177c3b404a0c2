"""Writes the dispersion regression scenes (plain glTF 2.0, buffers embedded; no Blender needed).

    python scenes/make_regression_scenes.py

Each scene carries its analytic question in its scene extras under `caustic.regression`
(the renderer ignores it; tests/dispersion.rs reads it):
- prism.gltf: a narrow spot beam through an equilateral SF11 prism onto a white screen, at the
  prism's minimum deviation for the d line. Answer: where each wavelength lands (Snell's law).
- prism_constant.gltf: the same prism with a constant index (n_d of SF11): one white band.
- rainbow.gltf: a water sphere lit by a distant, nearly parallel spot; a white screen with a
  hole for the beam catches the back-scattered light. Answer: the primary bow's angle
  (Descartes' minimum deviation for water's index at each wavelength).
Coordinates are glTF's (y up); cameras and lights look down their local -z.
"""
import base64
import json
import math
import pathlib
import struct

HERE = pathlib.Path(__file__).resolve().parent


class Gltf:
    def __init__(self):
        self.buffer = bytearray()
        self.doc = {"asset": {"version": "2.0", "generator": "caustic make_regression_scenes.py"},
                    "scene": 0, "scenes": [{"nodes": []}], "nodes": [], "meshes": [], "materials": [],
                    "accessors": [], "bufferViews": [], "cameras": [], "extensionsUsed": []}

    def _accessor(self, values, kind):
        offset = len(self.buffer)
        flat = [v for item in values for v in item]
        self.buffer += struct.pack(f"<{len(flat)}f", *flat)
        self.doc["bufferViews"].append({"buffer": 0, "byteOffset": offset, "byteLength": 4 * len(flat)})
        accessor = {"bufferView": len(self.doc["bufferViews"]) - 1, "componentType": 5126,
                    "count": len(values), "type": kind}
        if kind == "VEC3":
            accessor["min"] = [min(v[k] for v in values) for k in range(3)]
            accessor["max"] = [max(v[k] for v in values) for k in range(3)]
        self.doc["accessors"].append(accessor)
        return len(self.doc["accessors"]) - 1

    def node(self, node):
        self.doc["nodes"].append(node)
        self.doc["scenes"][0]["nodes"].append(len(self.doc["nodes"]) - 1)

    def material(self, material):
        self.doc["materials"].append(material)
        return len(self.doc["materials"]) - 1

    def mesh(self, name, triangles, material, normals=None):
        """triangles: list of 3 corners; normals: per-corner normals (flat when None)."""
        positions, flat_normals = [], []
        for k, t in enumerate(triangles):
            n = normals[k] if normals else [face_normal(t)] * 3
            positions += t
            flat_normals += n
        attributes = {"POSITION": self._accessor(positions, "VEC3"),
                      "NORMAL": self._accessor(flat_normals, "VEC3")}
        self.doc["meshes"].append({"name": name, "primitives": [{"attributes": attributes, "material": material}]})
        self.node({"name": name, "mesh": len(self.doc["meshes"]) - 1})

    def indexed_mesh(self, name, positions, normals, indices, material):
        offset = len(self.buffer)
        self.buffer += struct.pack(f"<{len(indices)}I", *indices)
        self.doc["bufferViews"].append({"buffer": 0, "byteOffset": offset, "byteLength": 4 * len(indices)})
        self.doc["accessors"].append({"bufferView": len(self.doc["bufferViews"]) - 1, "componentType": 5125,
                                      "count": len(indices), "type": "SCALAR"})
        index_accessor = len(self.doc["accessors"]) - 1
        attributes = {"POSITION": self._accessor(positions, "VEC3"), "NORMAL": self._accessor(normals, "VEC3")}
        primitive = {"attributes": attributes, "indices": index_accessor, "material": material}
        self.doc["meshes"].append({"name": name, "primitives": [primitive]})
        self.node({"name": name, "mesh": len(self.doc["meshes"]) - 1})

    def extension(self, name):
        if name not in self.doc["extensionsUsed"]:
            self.doc["extensionsUsed"].append(name)

    def write(self, name):
        uri = "data:application/octet-stream;base64," + base64.b64encode(bytes(self.buffer)).decode()
        self.doc["buffers"] = [{"byteLength": len(self.buffer), "uri": uri}]
        (HERE / f"{name}.gltf").write_text(json.dumps(self.doc, indent=1) + "\n")


def sub(a, b):
    return [x - y for x, y in zip(a, b)]


def cross(a, b):
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]


def normalize(v):
    length = math.sqrt(sum(x * x for x in v))
    return [x / length for x in v]


def face_normal(t):
    return normalize(cross(sub(t[1], t[0]), sub(t[2], t[0])))


def look_rotation(direction):
    """Quaternion (x, y, z, w) turning -z onto `direction`."""
    d = normalize(direction)
    axis = cross([0, 0, -1], d)
    dot = -d[2]
    if dot < -0.999999:
        return [0.0, 1.0, 0.0, 0.0]
    w = 1.0 + dot
    q = [axis[0], axis[1], axis[2], w]
    length = math.sqrt(sum(x * x for x in q))
    return [x / length for x in q]


def look_rotation_up(direction, up):
    """Quaternion (x, y, z, w) turning -z onto `direction` and +y toward `up`."""
    f = normalize(direction)
    r = normalize(cross(f, up))
    u = cross(r, f)
    m = [r, u, [-f[0], -f[1], -f[2]]]  # columns x, y, z
    trace = m[0][0] + m[1][1] + m[2][2]
    if trace > 0:
        s = 0.5 / math.sqrt(trace + 1.0)
        return [(m[1][2] - m[2][1]) * s, (m[2][0] - m[0][2]) * s, (m[0][1] - m[1][0]) * s, 0.25 / s]
    i = max(range(3), key=lambda k: m[k][k])
    j, k = (i + 1) % 3, (i + 2) % 3
    s = 2.0 * math.sqrt(1.0 + m[i][i] - m[j][j] - m[k][k])
    q = [0.0, 0.0, 0.0, (m[j][k] - m[k][j]) / s]
    q[i] = 0.25 * s
    q[j] = (m[i][j] + m[j][i]) / s
    q[k] = (m[i][k] + m[k][i]) / s
    return q


def quad(centre, u, v, half_u, half_v):
    """Two triangles of the rectangle centre +- half_u u +- half_v v, facing u x v."""
    c = [[centre[k] + su * half_u * u[k] + sv * half_v * v[k] for k in range(3)]
         for su, sv in [(-1, -1), (1, -1), (1, 1), (-1, 1)]]
    return [[c[0], c[1], c[2]], [c[0], c[2], c[3]]]


# A Lambertian screen: no specular layer (KHR_materials_specular with a factor of 0).
WHITE = {"name": "Screen", "pbrMetallicRoughness": {"baseColorFactor": [1, 1, 1, 1], "metallicFactor": 0, "roughnessFactor": 1},
         "extensions": {"KHR_materials_specular": {"specularFactor": 0}}}


def glass_material(gltf, name, extras=None, ior=None):
    gltf.extension("KHR_materials_transmission")
    material = {"name": name, "pbrMetallicRoughness": {"baseColorFactor": [1, 1, 1, 1], "metallicFactor": 0, "roughnessFactor": 0},
                "extensions": {"KHR_materials_transmission": {"transmissionFactor": 1}}}
    if ior is not None:
        gltf.extension("KHR_materials_ior")
        material["extensions"]["KHR_materials_ior"] = {"ior": ior}
    if extras:
        material["extras"] = {"caustic": extras}
    return gltf.material(material)


def spot(gltf, position, direction, half_angle_deg, intensity):
    gltf.extension("KHR_lights_punctual")
    lights = gltf.doc.setdefault("extensions", {}).setdefault("KHR_lights_punctual", {"lights": []})["lights"]
    outer = math.radians(half_angle_deg)
    lights.append({"type": "spot", "intensity": intensity, "color": [1, 1, 1],
                   "spot": {"innerConeAngle": 0.98 * outer, "outerConeAngle": outer}})
    gltf.node({"name": "Beam", "translation": position, "rotation": look_rotation(direction),
               "extensions": {"KHR_lights_punctual": {"light": len(lights) - 1}}})


def camera(gltf, position, direction, yfov, up=(0.0, 1.0, 0.0), aspect=1.0):
    gltf.doc["cameras"].append({"type": "perspective", "perspective": {"yfov": yfov, "znear": 0.01, "aspectRatio": aspect}})
    gltf.node({"name": "Camera", "camera": len(gltf.doc["cameras"]) - 1, "translation": position,
               "rotation": look_rotation_up(direction, list(up))})


# The prism: equilateral (apex 60 degrees), apex up, extruded along z over [-1, 1].
PRISM_2D = [[-0.5, 0.0], [0.5, 0.0], [0.0, math.sqrt(3) / 2]]
SF11_N_D = 1.78472


def prism_scene(name, glass_extras, ior):
    gltf = Gltf()
    material = glass_material(gltf, "Prism", glass_extras, ior)
    a, b, c = ([x, y] for x, y in PRISM_2D)
    front = [[p[0], p[1], 1.0] for p in (a, b, c)]
    back = [[p[0], p[1], -1.0] for p in (a, b, c)]
    triangles = [[front[0], front[1], front[2]], [back[0], back[2], back[1]]]
    for i, j in [(0, 1), (1, 2), (2, 0)]:
        triangles += [[back[i], back[j], front[j]], [back[i], front[j], front[i]]]
    gltf.mesh("Prism", triangles, material)
    # Minimum deviation at n_d: incidence i = asin(n sin 30 deg) on the left face's middle.
    incidence = math.asin(SF11_N_D * 0.5)
    inward = [math.cos(math.radians(-30)), math.sin(math.radians(-30))]
    angle = math.radians(-30) + incidence
    beam = [math.cos(angle), math.sin(angle), 0.0]
    entry = [(a[0] + c[0]) / 2, (a[1] + c[1]) / 2, 0.0]
    light = [entry[k] - 3.0 * beam[k] for k in range(3)]
    spot(gltf, light, beam, 0.25, 20000.0)
    # The screen: 3 beyond the prism along the exit direction at n_d, facing back.
    exit_angle = angle - (2 * incidence - math.radians(60))
    exit_dir = [math.cos(exit_angle), math.sin(exit_angle), 0.0]
    exit_point = [(b[0] + c[0]) / 2, (b[1] + c[1]) / 2, 0.0]
    centre = [exit_point[k] + 3.0 * exit_dir[k] for k in range(3)]
    across = [-exit_dir[1], exit_dir[0], 0.0]  # in the x-y plane, perpendicular to the exit beam
    screen = quad(centre, [0, 0, 1], across, 1.5, 1.5)
    if face_normal(screen[0])[0] * exit_dir[0] + face_normal(screen[0])[1] * exit_dir[1] > 0:
        screen = [[t[0], t[2], t[1]] for t in screen]
    gltf.extension("KHR_materials_specular")
    gltf.mesh("Screen", screen, gltf.material(WHITE))
    # The camera's up is the prism's axis, so the spectrum spreads across the image.
    camera(gltf, [centre[k] - 2.5 * exit_dir[k] for k in range(3)], exit_dir, 0.2, up=(0.0, 0.0, 1.0), aspect=2.0)
    gltf.doc["scenes"][0]["extras"] = {"caustic": {"resolution": [256, 128], "regression": {
        "prism_2d": PRISM_2D, "beam_origin": light, "beam_direction": beam,
        "screen_point": centre, "screen_normal": [-exit_dir[0], -exit_dir[1], 0.0]}}}
    gltf.write(name)


def uv_sphere(radius, segments, rings):
    """Shared vertices with exact normals, and triangles wound counter-clockwise from outside."""
    positions, normals = [], []
    for j in range(rings + 1):
        theta = math.pi * j / rings
        for i in range(segments + 1):
            phi = 2 * math.pi * i / segments
            n = [math.sin(theta) * math.cos(phi), math.cos(theta), -math.sin(theta) * math.sin(phi)]
            normals.append(n)
            positions.append([radius * x for x in n])
    indices = []
    for j in range(rings):
        for i in range(segments):
            a, b = j * (segments + 1) + i, (j + 1) * (segments + 1) + i
            if j > 0:
                indices += [a, b, a + 1]
            if j < rings - 1:
                indices += [a + 1, b, b + 1]
    return positions, normals, indices


SCREEN_Z = 20.0


def rainbow_scene():
    gltf = Gltf()
    water = glass_material(gltf, "Water", {"glass": "water"})
    positions, normals, indices = uv_sphere(1.0, 96, 48)
    gltf.indexed_mesh("WaterDrop", positions, normals, indices, water)
    # A nearly parallel beam from far along +z, just covering the drop.
    spot(gltf, [0.0, 0.0, 1000.0], [0.0, 0.0, -1.0], math.degrees(math.atan(1.02 / 1000.0)), 2.0e9)
    # The screen at z = 20 facing the drop, with a 3 x 3 hole for the beam.
    screen = []
    for cx, cy, hx, hy in [(0, 14.25, 30, 12.75), (0, -14.25, 30, 12.75), (-16.5, 0, 13.5, 1.5), (16.5, 0, 13.5, 1.5)]:
        screen += quad([cx, cy, SCREEN_Z], [0, 1, 0], [1, 0, 0], hy, hx)
    gltf.extension("KHR_materials_specular")
    gltf.mesh("Screen", screen, gltf.material(WHITE))
    # The camera looks at where the bow crosses the screen's +x axis, close enough to resolve
    # 0.1 degree of bow angle per pixel.
    camera(gltf, [0.0, 0.0, 2.0], [17.6, 0.0, 18.0], 0.12, aspect=2.0)
    gltf.doc["scenes"][0]["extras"] = {"caustic": {"resolution": [256, 128], "regression": {
        "drop_radius": 1.0, "beam_origin_z": 1000.0, "screen_z": SCREEN_Z}}}
    gltf.write("rainbow")


def fog_spot_scene():
    """A spot light straight down through a glass ball into fog over a floor: the beam, the ball's
    shadow in it and the bright cone the ball focuses (a volumetric caustic), seen from the side."""
    gltf = Gltf()
    glass = glass_material(gltf, "Glass", {"glass": "BK7"})
    positions, normals, indices = uv_sphere(0.5, 64, 32)
    gltf.indexed_mesh("Ball", [[x, y + 2.0, z] for x, y, z in positions], normals, indices, glass)
    spot(gltf, [0.0, 4.0, 0.0], [0.0, -1.0, 0.0], 14.0, 12000.0)
    gltf.extension("KHR_materials_specular")
    floor = dict(WHITE, name="Floor", pbrMetallicRoughness=dict(WHITE["pbrMetallicRoughness"], baseColorFactor=[0.5, 0.5, 0.5, 1]))
    gltf.mesh("Floor", quad([0.0, 0.0, 0.0], [0, 0, 1], [1, 0, 0], 4.0, 4.0), gltf.material(floor))
    camera(gltf, [0.0, 1.9, 6.0], [0.0, -0.08, -1.0], 0.75, aspect=4 / 3)
    gltf.doc["scenes"][0]["extras"] = {"caustic": {"resolution": [320, 240], "fog": {
        "scattering": [0.12, 0.12, 0.12], "absorption": [0.01, 0.01, 0.01], "anisotropy": 0.2}}}
    gltf.write("fog_spot")


if __name__ == "__main__":
    prism_scene("prism", {"glass": "SF11"}, None)
    prism_scene("prism_constant", None, SF11_N_D)
    rainbow_scene()
    fog_spot_scene()
