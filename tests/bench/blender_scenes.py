"""The benchmarks' scenes, built in Blender (bpy) by scenes/make_scenes.py and exported by the
add-on, as a user's render would export them."""
import pathlib
import sys

ROOT = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "tools"))

import render_in_blender  # noqa: E402  (sets a temporary HOME, imports bpy and scenes/make_scenes.py)
import bpy  # noqa: E402

make_scenes = render_in_blender.make_scenes
def sunlit_closeup_scene():
    """The sunlit room seen close up: the glass ball and its caustic fill the frame."""
    make_scenes.sunlit_room_scene(closeup=True)


def frosted_glass_scene():
    """The demo with its sphere frosted (roughness 0.2): a soft caustic."""
    make_scenes.cornell_glass_scene(roughness=0.2)


def glossy_interior_scene():
    """The diffuse box with its blocks in rough metal, the tall one gold (roughness 0.3) and the
    short one aluminium (roughness 0.15): an interior of diffuse and glossy light without glass."""
    make_scenes.cornell_diffuse_scene()
    for name, colour, roughness in (("TallBlock", (1.0, 0.77, 0.34), 0.3), ("ShortBlock", (0.91, 0.92, 0.92), 0.15)):
        metal = make_scenes.material(f"{name} metal", colour, roughness=roughness)
        metal.node_tree.nodes["Principled BSDF"].inputs["Metallic"].default_value = 1.0
        block = bpy.data.objects[name]
        block.data.materials.clear()
        block.data.materials.append(metal)


SCENES = {
    "caustic": make_scenes.cornell_glass_scene,
    "diffuse": make_scenes.cornell_diffuse_scene,
    # The diffuse box with rough metal blocks (gold and aluminium): diffuse and glossy light.
    "glossy_interior": glossy_interior_scene,
    "spot": make_scenes.spot_glass_scene,
    # A spot light through a glass ball into fog: the volumetric caustic (media).
    "fog_spot": make_scenes.fog_spot_scene,
    # A pool of scattering water under the sun: caustics and sun shafts seen through waves.
    "pool": make_scenes.pool_scene,
    "frosted": frosted_glass_scene,
    # The demo with 10x its triangles (a finer sphere), for cost against scene size.
    "caustic_10x_triangles": lambda: make_scenes.cornell_glass_scene(sphere_segments=304),
    # A room lit by 2400 small bulbs (the light tree's scene).
    "many_lights": make_scenes.many_lights_scene,
    # A city block grid at night: street lamps and lit windows (the light tree's second scene).
    "night_city": make_scenes.night_city_scene,
    # A room lit through a small window by the sun and sky, inside a large ground plane (the
    # visibility-driven photons' scene).
    "sunlit_room": make_scenes.sunlit_room_scene,
    # The same room seen close up: the glass ball and its caustic fill the frame (the automatic
    # radius's close-up, beside sunlit_room's wide shot).
    "sunlit_closeup": sunlit_closeup_scene,
    # A small glass ball in a large hall lit by 64 ceiling lamps, seen close up (the
    # visibility-driven photons' second scene).
    "glass_in_hall": make_scenes.glass_in_hall_scene,
}


def build(name, resolution, binary):
    """Builds scene `name` in Blender at `resolution`, without the extras the add-on writes itself,
    and enables the add-on (Blender's factory reset, which starts every scene, disables it)."""
    SCENES[name]()
    render_in_blender.enable_addon(binary)
    for obj in bpy.data.objects:
        obj.pop("caustic", None)
        # The benchmarks' lights are seen by the camera (Blender's default hides them).
        obj.visible_camera = True
    scene = bpy.context.scene
    scene.pop("caustic", None)
    scene.render.resolution_x, scene.render.resolution_y = resolution
    scene.render.resolution_percentage = 100
    return scene


def export(scene, folder):
    """The scene as the add-on exports it for a render; gives the glTF's path."""
    path = folder / "scene.gltf"
    sys.modules["caustic.export"].export(scene, path)
    return path
