"""Bakes a world into an equirectangular image with Cycles, for worlds Caustic cannot read node by
node (a Sky Texture, gradients, mixes of backgrounds): run by the add-on in a separate Blender (a
render cannot start inside a render), as

    blender --background --factory-startup --python bake_world.py -- WORLD.blend NAME OUT.exr WIDTH
    python bake_world.py -- WORLD.blend NAME OUT.exr WIDTH            (with the bpy module)

It appends world NAME from WORLD.blend into an empty scene, looks from the origin through Cycles'
equirectangular panoramic camera turned so that the image maps as an Environment Texture does
(its centre column toward +X, its top row straight up) and renders WIDTH x WIDTH/2 pixels, a
1-pixel box filter, 64 samples, into OUT.exr (linear, 32-bit float).
"""
import math
import sys

import bpy


def bake(blend, name, out, width):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    with bpy.data.libraries.load(blend, link=False) as (source, target):
        target.worlds = [name]
    scene = bpy.context.scene
    scene.world = target.worlds[0]
    camera = bpy.data.cameras.new("Panorama")
    camera.type, camera.panorama_type = 'PANO', 'EQUIRECTANGULAR'
    obj = bpy.data.objects.new("Panorama", camera)
    scene.collection.objects.link(obj)
    # Look along +X with +Z up.
    obj.rotation_euler = (math.pi / 2, 0.0, -math.pi / 2)
    scene.camera = obj
    scene.render.engine = 'CYCLES'
    cycles = scene.cycles
    cycles.device, cycles.samples, cycles.use_adaptive_sampling, cycles.use_denoising = 'CPU', 64, False, False
    cycles.pixel_filter_type, cycles.filter_width = 'BOX', 1.0
    render = scene.render
    render.resolution_x, render.resolution_y, render.resolution_percentage = width, width // 2, 100
    render.film_transparent = False
    render.image_settings.media_type = 'IMAGE'
    render.image_settings.file_format = 'OPEN_EXR'
    render.image_settings.color_depth = '32'
    render.filepath = out
    bpy.ops.render.render(write_still=True)


if __name__ == "__main__":
    blend, name, out, width = sys.argv[sys.argv.index("--") + 1:][:4]
    bake(blend, name, out, int(width))
