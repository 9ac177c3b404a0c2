"""The add-on's zips (tools/build_addon.py): the extension carries the `caustic` program and names
its platform, installs and enables in Blender 5.0.1 through the extension system, registers the
Caustic engine, and renders with no `caustic` on PATH and no repository beside it (as a Blender
user who never ran cargo has it); the plain add-on zip holds the package in its `caustic/` folder.
Run by tests/addon.rs in its own Blender, CAUSTIC_BINARY naming the program to carry."""

import os
import pathlib
import subprocess
import sys
import tempfile
import unittest
import zipfile

os.environ["HOME"] = tempfile.mkdtemp(prefix="caustic-package-home-")

import bpy  # noqa: E402
import numpy as np  # noqa: E402
import OpenEXR  # noqa: E402

ROOT = pathlib.Path(__file__).resolve().parents[2]
BINARY = os.environ["CAUSTIC_BINARY"]


def without_caustic_on_path():
    """PATH with every folder that holds a `caustic` left out."""
    folders = os.environ.get("PATH", "").split(os.pathsep)
    return os.pathsep.join(f for f in folders if f and not (pathlib.Path(f) / "caustic").exists())


def lit_cube_scene():
    """A grey cube on a plane under a sun, seen by a camera: 32x24, 4 passes."""
    bpy.ops.wm.read_homefile(use_empty=True)
    scene = bpy.context.scene
    bpy.ops.mesh.primitive_plane_add(size=10)
    bpy.ops.mesh.primitive_cube_add(size=1, location=(0, 0, 0.5))
    bpy.ops.object.light_add(type='SUN', location=(0, 0, 5))
    bpy.context.object.data.energy = 3.0
    bpy.ops.object.camera_add(location=(4, -4, 3), rotation=(1.1, 0.0, 0.785))
    scene.camera = bpy.context.object
    scene.render.engine = 'CAUSTIC'
    scene.render.resolution_x, scene.render.resolution_y, scene.render.resolution_percentage = 32, 24, 100
    scene.caustic.passes = 4
    scene.render.image_settings.file_format = 'OPEN_EXR'
    return scene


class Package(unittest.TestCase):
    def test_the_zip_installs_as_an_extension_and_registers_the_engine(self):
        out = pathlib.Path(tempfile.mkdtemp(prefix="caustic-dist-"))
        subprocess.run([sys.executable, str(ROOT / "tools" / "build_addon.py"), "-o", str(out), "--binary", BINARY],
                       check=True)
        legacy = next(out.glob("*-addon.zip"))
        extension = next(p for p in out.glob("*.zip") if p != legacy)
        with zipfile.ZipFile(extension) as z:
            self.assertIn("blender_manifest.toml", z.namelist())
            self.assertIn("bin/caustic", z.namelist())
            self.assertNotIn("caustic/__init__.py", z.namelist())
            self.assertIn('platforms = ["linux-x64"]', z.read("blender_manifest.toml").decode())
        with zipfile.ZipFile(legacy) as z:
            self.assertIn("caustic/__init__.py", z.namelist())
            self.assertIn("caustic/bin/caustic", z.namelist())
        os.environ["PATH"] = without_caustic_on_path()
        result = bpy.ops.extensions.package_install_files(filepath=str(extension), repo="user_default",
                                                          enable_on_install=True)
        self.assertEqual(result, {'FINISHED'})
        self.assertIn("bl_ext.user_default.caustic", bpy.context.preferences.addons.keys())
        bpy.context.scene.render.engine = 'CAUSTIC'
        self.assertEqual(bpy.context.scene.render.engine, 'CAUSTIC')
        self.assertEqual(bpy.context.scene.caustic.passes, 64)
        # The installed add-on lies in Blender's extensions folder, with no repository beside it:
        # the program it runs is the one it carries.
        import importlib
        properties = importlib.import_module("bl_ext.user_default.caustic.properties")
        program, problem = properties.find_binary("")
        self.assertIsNone(problem)
        self.assertEqual(pathlib.Path(program).parent.parent, pathlib.Path(properties.__file__).parent)
        scene = lit_cube_scene()
        scene.render.filepath = str(out / "cube.exr")
        bpy.ops.render.render(write_still=True)
        channels = OpenEXR.File(str(out / "cube.exr")).channels()
        pixels = channels["Combined" if "Combined" in channels else "RGBA"].pixels[..., :3]
        self.assertTrue(np.isfinite(pixels).all())
        self.assertGreater(float(pixels.mean()), 0.01, "the render through the installed extension is black")


if __name__ == "__main__":
    unittest.main(verbosity=2)
