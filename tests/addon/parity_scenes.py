"""Blender scenes for parity with Cycles: each is built in bpy the way an artist would build it,
rendered by Caustic through the add-on (tests/addon/test_parity.py) and by Cycles
(tests/addon/make_parity_references.py, whose references are committed in
tests/references/parity/). Every object gets a pass index, so that Cycles' object-index pass
gives each object's pixels.

Each scene function clears the file, builds the scene at 64x64 and returns the names of the
objects whose mean radiance is compared, with their pass indices.
"""
import math

import bpy
import mathutils

SIZE = 64


def clear():
    for collection in (bpy.data.objects, bpy.data.meshes, bpy.data.materials, bpy.data.lights, bpy.data.cameras,
                       bpy.data.images, bpy.data.worlds):
        for block in list(collection):
            collection.remove(block)
    scene = bpy.context.scene
    scene.render.resolution_x = scene.render.resolution_y = SIZE
    scene.render.resolution_percentage = 100
    scene.render.use_motion_blur = False
    scene.frame_start = scene.frame_end = 1
    scene.frame_set(1)
    scene.view_settings.view_transform = 'Standard'
    return scene


def world(colour, strength=1.0):
    w = bpy.data.worlds.new("World")
    w.use_nodes = True
    background = w.node_tree.nodes["Background"]
    background.inputs["Color"].default_value = (*colour, 1.0)
    background.inputs["Strength"].default_value = strength
    bpy.context.scene.world = w


def principled(name, **inputs):
    """A Principled BSDF material at Blender's defaults but for `inputs` (socket name: value)."""
    m = bpy.data.materials.new(name)
    bsdf = m.node_tree.nodes["Principled BSDF"]
    for socket, value in inputs.items():
        bsdf.inputs[socket.replace("_", " ")].default_value = value
    return m


def add(operator, material=None, index=0, **kwargs):
    operator(**kwargs)
    obj = bpy.context.object
    if material is not None:
        obj.data.materials.append(material)
    obj.pass_index = index
    return obj


def camera(location, target, lens=50.0):
    cam = add(bpy.ops.object.camera_add, location=location)
    cam.rotation_euler = (mathutils.Vector(target) - cam.location).to_track_quat('-Z', 'Y').to_euler()
    cam.data.lens = lens
    bpy.context.scene.camera = cam
    return cam


def area_light(location, target, size, power):
    light = add(bpy.ops.object.light_add, type='AREA', location=location)
    light.rotation_euler = (mathutils.Vector(target) - light.location).to_track_quat('-Z', 'Y').to_euler()
    light.data.size, light.data.energy = size, power
    return light


def studio(floor_material):
    """A floor, a dim grey world and a soft area light above and to the side."""
    add(bpy.ops.mesh.primitive_plane_add, floor_material, index=1, size=20)
    world((0.05, 0.05, 0.05))
    area_light((2.0, -2.0, 4.0), (0.0, 0.0, 0.0), 2.0, 400.0)


def principled_spheres():
    """Two spheres at Blender's Principled defaults (IOR 1.5, Specular IOR Level 0.5): a grey one of
    roughness 0.5 and a black glossy one of roughness 0.2, whose only light is its specular layer,
    on a floor at the defaults too."""
    clear()
    studio(principled("Floor", Base_Color=(0.5, 0.5, 0.5, 1.0)))
    for name, x, colour, roughness, index in (("Grey", -1.1, 0.8, 0.5, 2), ("Black", 1.1, 0.0, 0.2, 3)):
        sphere = add(bpy.ops.mesh.primitive_uv_sphere_add, principled(name, Base_Color=(colour, colour, colour, 1.0),
                                                                     Roughness=roughness),
                     index=index, segments=64, ring_count=32, radius=1.0, location=(x, 0.0, 1.0))
        bpy.ops.object.shade_smooth()
    camera((0.0, -7.0, 3.0), (0.0, 0.0, 0.8))
    return {"Floor": 1, "Grey": 2, "Black": 3}


SCENES = {"principled_spheres": principled_spheres}
