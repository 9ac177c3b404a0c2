"""The add-on enabled as a user enables it, for the bpy test scripts: addon/ linked into the
user's add-ons (in the temporary HOME the script set before importing bpy) as `caustic` and
enabled in the preferences (exporter hooks are found only for enabled add-ons), with the
renderer's path set."""
import pathlib
import sys

import addon_utils
import bpy

ROOT = pathlib.Path(__file__).resolve().parents[2]


def enable_addon(binary):
    """Enables the add-on with `binary` as its renderer and gives its `engine` module."""
    addons = pathlib.Path(bpy.utils.user_resource('SCRIPTS', path="addons", create=True))
    (addons / "caustic").symlink_to(ROOT / "addon")
    bpy.utils.refresh_script_paths()
    addon_utils.enable("caustic", default_set=True, handle_error=None)
    bpy.context.preferences.addons["caustic"].preferences.binary = binary
    return sys.modules["caustic.engine"]
