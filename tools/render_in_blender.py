"""Renders the demo box (or, with --studio, a studio shot lit by an HDRI) through the add-on in
headless Blender (bpy) and saves what Blender's render result holds as a PNG, with Blender's own
view transform:

    target/bpy-venv/bin/python tools/render_in_blender.py [-o docs/blender_render.png] [--passes N]
                                                          [--animation-timing]
    target/bpy-venv/bin/python tools/render_in_blender.py --studio -o docs/studio.png --passes 512

(the environment `cargo test` prepares; any Python with `pip install bpy==5.0.1` works). With
--animation-timing it also renders frames 1-3 of the demo with a sliding cube through Render
Animation and the same frames from the command line, and prints the export time and both totals.
"""
import argparse
import os
import pathlib
import subprocess
import sys
import tempfile
import math
import time

ROOT = pathlib.Path(__file__).resolve().parent.parent
os.environ["HOME"] = tempfile.mkdtemp(prefix="caustic-render-home-")
sys.path.insert(0, str(ROOT / "scenes"))

import bpy  # noqa: E402
import addon_utils  # noqa: E402
import make_scenes  # noqa: E402  (the bundled scenes' own building blocks)


def demo_box():
    """scenes/cornell_glass as make_scenes.py builds it, without exporting it."""
    make_scenes.cornell_glass_scene()
    for obj in bpy.data.objects:
        obj.pop("caustic", None)  # the add-on writes the extras itself
    return bpy.context.scene


def studio_hdri(width=1024, height=512):
    """A photo studio as an equirectangular HDRI, made here (this machine has no HDRI library): a
    dark backdrop, a warm softbox key light to the front left, a small bright cool back light
    behind the objects and a dim overhead panel; saved as an EXR and loaded from disk, as an
    artist's HDRI is."""
    import numpy as np
    rows = (np.arange(height) + 0.5) / height  # from the bottom
    columns = (np.arange(width) + 0.5) / width
    elevation = np.degrees((rows - 0.5) * np.pi)[:, None]
    # Blender's mapping: column 0.5 faces +X, azimuth grows toward +Y to the left of the image.
    azimuth = np.degrees((0.5 - columns) * 2 * np.pi)[None, :]
    rgb = np.zeros((height, width, 3))
    rgb[:] = np.where((elevation < 0)[..., None], [0.03, 0.03, 0.03], [0.05, 0.05, 0.055])

    def panel(centre_az, centre_el, half_az, half_el, colour):
        distance = np.maximum(np.abs((azimuth - centre_az + 180) % 360 - 180) / half_az,
                              np.abs(elevation - centre_el) / half_el)
        return np.clip((1.15 - distance) / 0.3, 0, 1)[..., None] * np.array(colour)
    rgb += panel(-140, 35, 20, 13, [8.0, 6.8, 5.4])   # key: front left of a camera looking along +Y
    rgb += panel(100, 25, 9, 9, [30.0, 34.0, 40.0])   # back light: behind the objects (their caustics fall toward the camera)
    rgb += panel(0, 80, 40, 8, [1.2, 1.2, 1.2])          # overhead
    rgba = np.concatenate([rgb, np.ones((height, width, 1))], axis=2).astype(np.float32)
    image = bpy.data.images.new("studio", width, height, alpha=False, float_buffer=True)
    image.colorspace_settings.name = 'Non-Color'
    image.pixels.foreach_set(rgba.ravel())
    image.filepath_raw = str(pathlib.Path(tempfile.mkdtemp(prefix="caustic-studio-")) / "studio.exr")
    image.file_format = 'OPEN_EXR'
    image.save()
    return bpy.data.images.load(image.filepath_raw)


def studio():
    """A glass sphere (dispersive flint), a gold ring, a red clear-coated ball and a diamond on a
    grey floor, lit only by the studio HDRI through a Mapping node."""
    for blocks in (bpy.data.objects, bpy.data.meshes, bpy.data.materials, bpy.data.lights, bpy.data.cameras,
                   bpy.data.worlds):
        for block in list(blocks):
            blocks.remove(block)
    scene = bpy.context.scene
    world = bpy.data.worlds.new("Studio")
    nodes, links = world.node_tree.nodes, world.node_tree.links
    environment = nodes.new("ShaderNodeTexEnvironment")
    environment.image = studio_hdri()
    mapping = nodes.new("ShaderNodeMapping")
    mapping.inputs["Rotation"].default_value = (0.0, 0.0, math.radians(15))
    links.new(nodes.new("ShaderNodeTexCoord").outputs["Generated"], mapping.inputs["Vector"])
    links.new(mapping.outputs["Vector"], environment.inputs["Vector"])
    links.new(environment.outputs["Color"], nodes["Background"].inputs["Color"])
    scene.world = world
    make_scenes.plane("Floor", 30, (0, 0, 0), (0, 0, 0), make_scenes.material("Floor", (0.35, 0.35, 0.37),
                                                                               roughness=0.45))
    glass = make_scenes.material("Flint", (1.0, 1.0, 1.0), roughness=0.0, transmission=1.0, ior=1.75)
    glass.caustic.dispersion, glass.caustic.abbe = 'ABBE', 28.0
    make_scenes.glass_sphere((-0.55, 0.1, 0.4), 0.4, glass)
    gold = make_scenes.material("Gold", (1.0, 0.76, 0.33), roughness=0.2)
    gold.node_tree.nodes["Principled BSDF"].inputs["Metallic"].default_value = 1.0
    bpy.ops.mesh.primitive_torus_add(major_radius=0.28, minor_radius=0.06, location=(0.35, -0.25, 0.06))
    bpy.ops.object.shade_smooth()
    bpy.context.object.data.materials.append(gold)
    red = make_scenes.material("Red ceramic", (0.55, 0.04, 0.03), roughness=0.5)
    red.node_tree.nodes["Principled BSDF"].inputs["Coat Weight"].default_value = 1.0
    bpy.ops.mesh.primitive_uv_sphere_add(segments=64, ring_count=32, radius=0.3, location=(0.45, 0.45, 0.3))
    bpy.ops.object.shade_smooth()
    bpy.context.object.data.materials.append(red)
    diamond = make_scenes.material("Diamond", (1.0, 1.0, 1.0), roughness=0.0, transmission=1.0, ior=2.417)
    diamond.caustic.dispersion, diamond.caustic.glass = 'GLASS', 'diamond'
    make_scenes.brilliant("Diamond", 0.14, (-0.05, -0.55, 0.12), diamond)
    make_scenes.camera((0.0, -3.0, 1.1), (0.0, 0.05, 0.3), lens_mm=45.0)
    scene.render.resolution_x, scene.render.resolution_y, scene.render.resolution_percentage = 480, 270, 100
    return scene


def enable_addon(binary):
    addons = pathlib.Path(bpy.utils.user_resource('SCRIPTS', path="addons", create=True))
    link = addons / "caustic"
    if not link.exists():
        link.symlink_to(ROOT / "addon")
    bpy.utils.refresh_script_paths()
    addon_utils.enable("caustic", default_set=True, handle_error=None)
    if binary:
        bpy.context.preferences.addons["caustic"].preferences.binary = binary


def animation_timing(out, binary):
    """Render Animation of frames 1-3 against the same frames from the command line."""
    scene = bpy.context.scene
    bpy.ops.mesh.primitive_cube_add(size=0.2, location=(-0.7, 0.3, 0.1))
    cube = bpy.context.object
    for frame, x in [(1, -0.7), (3, -0.4)]:
        cube.location.x = x
        cube.keyframe_insert("location", index=0, frame=frame)
    scene.frame_start, scene.frame_end = 1, 3
    scene.render.image_settings.file_format = 'OPEN_EXR'
    scene.render.filepath = str(out / "anim_####")
    export = sys.modules["caustic.export"]
    start = time.perf_counter()
    bpy.ops.render.render(animation=True)
    blender_s = time.perf_counter() - start
    exported = out / "cli" / "scene.gltf"
    exported.parent.mkdir(parents=True, exist_ok=True)
    export_s = export.export(scene, exported)
    flags = sys.modules["caustic.engine"].render_flags(scene.caustic)
    start = time.perf_counter()
    subprocess.run([binary or "caustic", "render", str(exported), "-o", str(out / "cli"), "--frames", "1-3",
                    "--progress", "none", *flags], check=True)
    cli_s = time.perf_counter() - start
    print(f"export {export_s:.3f} s; Render Animation of frames 1-3 {blender_s:.2f} s in all; "
          f"the command line on the same export {cli_s:.2f} s")


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("-o", "--out", type=pathlib.Path, default=ROOT / "docs" / "blender_render.png")
    parser.add_argument("--passes", type=int, default=256)
    parser.add_argument("--binary", help="the caustic program (default: found by the add-on)")
    parser.add_argument("--animation-timing", action="store_true")
    parser.add_argument("--studio", action="store_true", help="the studio shot lit by an HDRI")
    args = parser.parse_args(sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else sys.argv[1:])
    enable_addon(args.binary)
    scene = studio() if args.studio else demo_box()
    scene.render.engine = 'CAUSTIC'
    scene.caustic.passes = args.passes
    scene.view_settings.view_transform = 'Standard'
    scene.render.image_settings.file_format = 'PNG'
    scene.render.filepath = str(args.out)
    start = time.perf_counter()
    bpy.ops.render.render(write_still=True)
    print(f"rendered {args.out} through the add-on in {time.perf_counter() - start:.1f} s")
    if args.animation_timing:
        animation_timing(pathlib.Path(tempfile.mkdtemp(prefix="caustic-timing-")), args.binary)


if __name__ == "__main__":
    main()
