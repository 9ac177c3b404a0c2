"""A Blender scene (bpy) as a Mitsuba 3 scene dictionary, for the benchmarks' path-tracing peer.

Converts what the benchmarks' scenes hold and refuses the rest by name, so a comparison never
runs on a scene Mitsuba sees differently:
- meshes, in world space, with their corner normals (smooth spheres stay smooth), written as PLY
  files into a folder;
- Principled BSDFs: transmission -> `dielectric` (`roughdielectric` with GGX, alpha = roughness^2),
  metallic -> `principled` with metallic 1 (GGX, Schlick's Fresnel from the base colour: glTF's
  conductor), Specular IOR Level 0 -> `diffuse`; emission -> an `area` emitter;
- square and rectangular area lights: one-sided rectangles emitting P / (pi A) (Caustic's and
  Cycles' conversion of a Blender area light's power), along the light's -Z as Blender's;
- the scene camera (perspective, its horizontal or vertical field of view as Blender fits it);
- a world of one colour (a `constant` emitter), or none.
Mitsuba's path tracer (`path`, `max_depth` 33: Caustic's and the benchmark's 32 bounces), an
independent sampler, a 1-pixel box filter and an RGB film at the render resolution.
"""
import math
import pathlib
import struct

import bpy


class Unconvertible(Exception):
    """The scene holds something the Mitsuba scene would render differently."""


def write_ply(path, positions, normals):
    """Unindexed triangles (3 vertices each) as a binary PLY with normals."""
    count = len(positions)
    header = ("ply\nformat binary_little_endian 1.0\n"
              f"element vertex {count}\nproperty float x\nproperty float y\nproperty float z\n"
              "property float nx\nproperty float ny\nproperty float nz\n"
              f"element face {count // 3}\nproperty list uchar int vertex_indices\nend_header\n")
    with open(path, "wb") as out:
        out.write(header.encode("ascii"))
        out.write(b"".join(struct.pack("<6f", *p, *n) for p, n in zip(positions, normals)))
        out.write(b"".join(struct.pack("<B3i", 3, i, i + 1, i + 2) for i in range(0, count, 3)))


def world_triangles(obj, depsgraph):
    """The evaluated mesh's triangles in world space: (positions, corner normals), 3 per triangle."""
    evaluated = obj.evaluated_get(depsgraph)
    mesh = evaluated.to_mesh()
    try:
        mesh.calc_loop_triangles()
        matrix = obj.matrix_world
        normal_matrix = matrix.to_3x3().inverted_safe().transposed()
        corner_normals = mesh.corner_normals
        positions, normals = [], []
        for triangle in mesh.loop_triangles:
            for corner, vertex in zip(triangle.loops, triangle.vertices):
                positions.append(tuple(matrix @ mesh.vertices[vertex].co))
                normals.append(tuple((normal_matrix @ corner_normals[corner].vector).normalized()))
        return positions, normals
    finally:
        evaluated.to_mesh_clear()


def principled_inputs(obj):
    """The Principled BSDF's inputs of the object's one material."""
    materials = [slot.material for slot in obj.material_slots if slot.material is not None]
    if len(materials) != 1:
        raise Unconvertible(f"object '{obj.name}': {len(materials)} materials (one is converted)")
    nodes = materials[0].node_tree.nodes if materials[0].node_tree else []
    bsdfs = [n for n in nodes if n.type == "BSDF_PRINCIPLED"]
    if len(bsdfs) != 1 or any(link.from_node.type != "BSDF_PRINCIPLED" and link.to_node == bsdfs[0]
                              for link in materials[0].node_tree.links):
        raise Unconvertible(f"material '{materials[0].name}': not one Principled BSDF of constant inputs")
    return materials[0].name, {i.name: i.default_value for i in bsdfs[0].inputs if hasattr(i, "default_value")}


def rgb(value):
    return {"type": "rgb", "value": [float(value[0]), float(value[1]), float(value[2])]}


def bsdf(name, inputs):
    """The Mitsuba BSDF for a Principled BSDF's inputs."""
    roughness = float(inputs["Roughness"])
    if inputs["Transmission Weight"] > 0.5:
        if roughness == 0.0:
            return {"type": "dielectric", "int_ior": float(inputs["IOR"]), "ext_ior": 1.0}
        return {"type": "roughdielectric", "distribution": "ggx", "alpha": roughness ** 2,
                "int_ior": float(inputs["IOR"]), "ext_ior": 1.0}
    if inputs["Metallic"] > 0.5:
        return {"type": "principled", "base_color": rgb(inputs["Base Color"]), "metallic": 1.0,
                "roughness": roughness, "spec_tint": 0.0, "specular": 0.5}
    if inputs["Specular IOR Level"] == 0.0 and inputs["Coat Weight"] == 0.0 and inputs["Sheen Weight"] == 0.0:
        return {"type": "diffuse", "reflectance": rgb(inputs["Base Color"])}
    raise Unconvertible(f"material '{name}': a dielectric with a specular layer (Mitsuba's layers differ from "
                        "glTF's and Cycles')")


def mesh_shape(obj, depsgraph, folder):
    positions, normals = world_triangles(obj, depsgraph)
    path = folder / f"{len(list(folder.glob('*.ply'))):04d}.ply"
    write_ply(path, positions, normals)
    name, inputs = principled_inputs(obj)
    shape = {"type": "ply", "filename": str(path), "face_normals": False, "bsdf": bsdf(name, inputs)}
    strength = float(inputs["Emission Strength"])
    if strength > 0.0 and any(inputs["Emission Color"][:3]):
        shape["emitter"] = {"type": "area", "radiance": rgb([c * strength for c in inputs["Emission Color"][:3]])}
    return shape


def area_light(obj, mi):
    light = obj.data
    if light.shape not in ("SQUARE", "RECTANGLE"):
        raise Unconvertible(f"light '{obj.name}': a {light.shape.lower()} area light")
    if light.spread < math.pi - 1e-4:
        raise Unconvertible(f"light '{obj.name}': a spread below 180 degrees")
    size_x = light.size
    size_y = light.size if light.shape == "SQUARE" else light.size_y
    scale = obj.matrix_world.to_scale()
    area = size_x * scale.x * size_y * scale.y
    radiance = light.energy / (math.pi * area)
    matrix = [list(row) for row in obj.matrix_world]
    # Mitsuba's rectangle spans [-1, 1]^2 facing +Z; Blender's area light emits along its -Z.
    to_world = (mi.ScalarTransform4f(matrix) @ mi.ScalarTransform4f().rotate([1, 0, 0], 180.0)
                @ mi.ScalarTransform4f().scale([size_x / 2, size_y / 2, 1.0]))
    return {"type": "rectangle", "to_world": to_world, "bsdf": {"type": "diffuse", "reflectance": rgb((0, 0, 0))},
            "emitter": {"type": "area", "radiance": rgb([c * radiance for c in light.color])}}


def sensor(scene, mi):
    camera = scene.camera
    width, height = scene.render.resolution_x, scene.render.resolution_y
    data = camera.data
    if data.type != "PERSP" or data.dof.use_dof:
        raise Unconvertible(f"camera '{camera.name}': only a pinhole perspective camera is converted")
    horizontal = data.sensor_fit == "HORIZONTAL" or (data.sensor_fit == "AUTO" and width >= height)
    fov = math.degrees(data.angle_x if horizontal else data.angle_y)
    matrix = camera.matrix_world
    origin = matrix.translation
    forward = -matrix.col[2].xyz
    up = matrix.col[1].xyz
    return {"type": "perspective", "fov": fov, "fov_axis": "x" if horizontal else "y",
            "near_clip": 0.001, "far_clip": 1e5,
            "to_world": mi.ScalarTransform4f().look_at(origin=list(origin), target=list(origin + forward), up=list(up)),
            "film": {"type": "hdrfilm", "width": width, "height": height, "rfilter": {"type": "box"},
                     "pixel_format": "rgb"},
            "sampler": {"type": "independent"}}


def world(scene):
    if scene.world is None or not scene.world.use_nodes:
        return None
    nodes = scene.world.node_tree.nodes
    background = [n for n in nodes if n.type == "BACKGROUND"]
    if len(background) != 1 or background[0].inputs["Color"].is_linked:
        raise Unconvertible("the world: only one constant Background colour is converted")
    colour = background[0].inputs["Color"].default_value
    strength = background[0].inputs["Strength"].default_value
    if strength == 0.0 or not any(colour[:3]):
        return None
    return {"type": "constant", "radiance": rgb([c * strength for c in colour[:3]])}


def mitsuba_scene(scene, folder, mi):
    """The Mitsuba scene dictionary for `scene`; meshes are written into `folder`. Raises
    Unconvertible naming what it cannot convert."""
    folder = pathlib.Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    depsgraph = bpy.context.evaluated_depsgraph_get()
    result = {"type": "scene", "integrator": {"type": "path", "max_depth": 33},
              "sensor": sensor(scene, mi)}
    for obj in scene.objects:
        if obj.hide_render:
            continue
        if obj.type == "MESH":
            result[f"mesh_{obj.name}"] = mesh_shape(obj, depsgraph, folder)
        elif obj.type == "LIGHT" and obj.data.type == "AREA":
            result[f"light_{obj.name}"] = area_light(obj, mi)
        elif obj.type == "LIGHT":
            raise Unconvertible(f"light '{obj.name}': a {obj.data.type.lower()} light")
        elif obj.type not in ("CAMERA", "EMPTY"):
            raise Unconvertible(f"object '{obj.name}': a {obj.type.lower()}")
    background = world(scene)
    if background is not None:
        result["world"] = background
    return result
