"""Renders the demo box through the add-on in headless Blender (bpy) and saves what Blender's
render result holds as a PNG, with Blender's own view transform:

    target/bpy-venv/bin/python tools/render_in_blender.py [-o docs/blender_render.png] [--passes N]
                                                          [--animation-timing]

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
    args = parser.parse_args(sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else sys.argv[1:])
    scene = demo_box()
    enable_addon(args.binary)
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
