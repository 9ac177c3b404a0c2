"""Caustic: spectral progressive photon mapping as a Blender render engine.

Installs as an extension (blender_manifest.toml, Blender 4.2 and later) or as a plain add-on
(bl_info). The renderer itself is the `caustic` program; this add-on exports the scene, runs it and
loads its images.
"""

bl_info = {
    "name": "Caustic",
    "author": "The Caustic developers",
    "version": (0, 1, 0),
    "blender": (4, 2, 0),
    "location": "Properties > Render > Render Engine",
    "description": "Spectral progressive photon mapping: caustics, dispersion, animation",
    "category": "Render",
}

import bpy  # noqa: E402

from . import engine, properties, ui  # noqa: E402
from .export import CAUSTIC_OT_export_scene  # noqa: E402
from .extras import glTF2ExportUserExtension  # noqa: E402,F401 - found here by Blender's glTF exporter


def register():
    properties.register()
    bpy.utils.register_class(engine.CausticRenderEngine)
    bpy.utils.register_class(CAUSTIC_OT_export_scene)
    ui.register()


def unregister():
    engine.close_session()
    ui.unregister()
    bpy.utils.unregister_class(CAUSTIC_OT_export_scene)
    bpy.utils.unregister_class(engine.CausticRenderEngine)
    properties.unregister()
