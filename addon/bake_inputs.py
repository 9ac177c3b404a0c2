"""Bakes Principled inputs that glTF cannot hold (a procedural texture, a ColorRamp, a Mix node
on the Base Color, Roughness, Metallic or Emission Color) into images with Cycles: run by the
add-on in a separate Blender (a bake cannot start inside a render), as

    blender --background --factory-startup --python bake_inputs.py -- OBJECTS.blend JOBS.json
    python bake_inputs.py -- OBJECTS.blend JOBS.json             (with the bpy module)

OBJECTS.blend holds the objects (with their meshes and materials); JOBS.json lists
`{"object", "material", "input", "out", "size"}`: for each, the input's node tree feeds an
Emission shader that Cycles bakes (EMIT) over the object's active UV map into a `size` x `size`
image, saved to `out` as a 16-bit PNG of linear values (Non-Color). A Normal input (a Bump node,
a procedural texture) is baked as Cycles shades it (NORMAL, in tangent space): a normal map.
"""
import json
import sys

import bpy


def bake(blend, jobs):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    names = sorted({job["object"] for job in jobs})
    with bpy.data.libraries.load(blend, link=False) as (source, target):
        target.objects = names
    scene = bpy.context.scene
    for obj in target.objects:
        scene.collection.objects.link(obj)
    scene.render.engine = 'CYCLES'
    scene.cycles.device, scene.cycles.samples = 'CPU', 4
    for job in jobs:
        bake_one(scene, bpy.data.objects[job["object"]], bpy.data.materials[job["material"]], job)


def bake_one(scene, obj, material, job):
    """Bakes `job["input"]` of `material` on `obj` into `job["out"]`."""
    tree = material.node_tree
    nodes, links = tree.nodes, tree.links
    normal = job["input"] == "Normal"
    if not normal:
        principled = next(n for n in nodes if n.type == 'BSDF_PRINCIPLED')
        output = next(n for n in nodes if n.type == 'OUTPUT_MATERIAL' and n.is_active_output)
        source = principled.inputs[job["input"]].links[0].from_socket
        emission = nodes.new("ShaderNodeEmission")
        links.new(source, emission.inputs["Color"])
        links.new(emission.outputs[0], output.inputs["Surface"])
    size = job["size"]
    image = bpy.data.images.new("baked", size, size, float_buffer=True)
    image.colorspace_settings.name = 'Non-Color'
    target = nodes.new("ShaderNodeTexImage")
    target.image = image
    nodes.active = target
    for other in scene.objects:
        other.select_set(other == obj)
    bpy.context.view_layer.objects.active = obj
    if normal:
        bpy.ops.object.bake(type='NORMAL', normal_space='TANGENT', margin=4)
    else:
        bpy.ops.object.bake(type='EMIT', margin=4)
    image.filepath_raw, image.file_format = job["out"], 'PNG'
    settings = scene.render.image_settings
    settings.color_depth, settings.color_mode = '16', 'RGB'
    image.save()


if __name__ == "__main__":
    blend, jobs = sys.argv[sys.argv.index("--") + 1:][:2]
    with open(jobs) as listed:
        bake(blend, json.load(listed))
