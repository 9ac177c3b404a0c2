"""The add-on's zips (tools/build_addon.py): the extension installs and enables in Blender 5.0.1
through the extension system, and registers the Caustic engine; the plain add-on zip holds the
package in its `caustic/` folder. Run by tests/addon.rs in its own Blender."""

import os
import pathlib
import subprocess
import sys
import tempfile
import unittest
import zipfile

os.environ["HOME"] = tempfile.mkdtemp(prefix="caustic-package-home-")

import bpy  # noqa: E402

ROOT = pathlib.Path(__file__).resolve().parents[2]


class Package(unittest.TestCase):
    def test_the_zip_installs_as_an_extension_and_registers_the_engine(self):
        out = pathlib.Path(tempfile.mkdtemp(prefix="caustic-dist-"))
        subprocess.run([sys.executable, str(ROOT / "tools" / "build_addon.py"), "-o", str(out)], check=True)
        legacy = next(out.glob("*-addon.zip"))
        extension = next(p for p in out.glob("*.zip") if p != legacy)
        with zipfile.ZipFile(extension) as z:
            self.assertIn("blender_manifest.toml", z.namelist())
            self.assertNotIn("caustic/__init__.py", z.namelist())
        with zipfile.ZipFile(legacy) as z:
            self.assertIn("caustic/__init__.py", z.namelist())
        result = bpy.ops.extensions.package_install_files(filepath=str(extension), repo="user_default",
                                                          enable_on_install=True)
        self.assertEqual(result, {'FINISHED'})
        self.assertIn("bl_ext.user_default.caustic", bpy.context.preferences.addons.keys())
        bpy.context.scene.render.engine = 'CAUSTIC'
        self.assertEqual(bpy.context.scene.render.engine, 'CAUSTIC')
        self.assertEqual(bpy.context.scene.caustic.passes, 64)


if __name__ == "__main__":
    unittest.main(verbosity=2)
