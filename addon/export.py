"""The scene as glTF 2.0 through Blender's own exporter, plus what the exporter drops: `export`
runs the exporter with Caustic's options while its hooks (`extras.py`) add the `caustic` extras
(docs/extras.md), around the work-arounds for the exporter's faults (`workarounds.py`), then adds
the animated values (`animated.py`) to the file.

Nothing in the user's data changes: every work-around is undone after the export, and the hooks
only add to what is being written.
"""

import json
import os
import pathlib
import time

import bpy
from bpy.props import StringProperty

from . import animated
from .extras import holdout_objects
from .workarounds import drop_dangling_channels, exporter_workarounds, run_exporter
from .world import world_extras
from .state import STATE


def export(scene, path):
    """Writes `scene` with its animation to `path` (.gltf) with Caustic's extras; returns the
    seconds it took."""
    start = time.perf_counter()
    STATE.world = world_extras(scene.world, pathlib.Path(path).parent)
    STATE.holdouts = holdout_objects(bpy.context.view_layer)
    # One timeline sampled once a frame (LINEAR keys); animated values are sampled by
    # `finish_file`, not by the exporter's pointer animation (which raises on rigged scenes).
    options = dict(filepath=str(path), export_format='GLTF_SEPARATE', export_cameras=True, export_lights=True,
                   export_extras=True, export_apply=True, export_yup=True, use_renderable=True,
                   use_active_scene=True, export_animations=True, export_animation_mode='SCENE',
                   export_force_sampling=True, export_frame_range=True, export_pointer_animation=False,
                   # Vertex colours only where a material reads them (by default the exporter
                   # writes the active colour attribute on every mesh, which glTF multiplies in).
                   export_vertex_color='MATERIAL', export_all_vertex_colors=False,
                   export_active_vertex_color_when_no_material=False,
                   # Geometry Nodes output as Cycles renders it, repeated meshes as glTF instances.
                   export_gn_mesh=True, export_gpu_instances=True)
    STATE.exporting = True
    STATE.fallbacks.clear()
    undo = []
    try:
        undo = exporter_workarounds(scene)
        result = run_exporter(scene, options)
    finally:
        for step in reversed(undo):
            step()
        STATE.temperatures.clear()
        STATE.exporting, STATE.world, STATE.holdouts = False, None, set()
        STATE.replaced.clear()
    if result != {'FINISHED'}:
        raise RuntimeError(f"Blender's glTF exporter did not finish ({result})")
    finish_file(scene, pathlib.Path(path))
    return time.perf_counter() - start


def finish_file(scene, path):
    """Adds the scene's animated values (`animated.tracks`) to the exported file's scene extras,
    and drops the animation channels Blender's exporter writes for nodes it did not write (the
    Geometry Nodes instances it folds into `EXT_mesh_gpu_instancing`, which move with their
    node)."""
    gltf = json.loads(path.read_text())
    found = animated.tracks(scene, gltf)
    dropped = drop_dangling_channels(gltf)
    if not found and not dropped:
        return
    if found:
        scene_index = gltf.get("scene", 0)
        extras = gltf["scenes"][scene_index].setdefault("extras", {})
        extras.setdefault("caustic", {})["tracks"] = found
    partial = path.with_suffix(".gltf.partial")
    partial.write_text(json.dumps(gltf))
    os.replace(partial, path)


class CAUSTIC_OT_export_scene(bpy.types.Operator):
    """Export the scene as Caustic reads it: glTF with the caustic extras (for `caustic render` on
    a farm: `blender -b shot.blend --python-expr "import bpy; bpy.ops.caustic.export_scene(filepath='shot.gltf')"`)"""

    bl_idname = "caustic.export_scene"
    bl_label = "Export Caustic Scene"

    filepath: StringProperty(name="File Path", subtype='FILE_PATH', description="The .gltf to write")

    def execute(self, context):
        if not self.filepath:
            self.report({'ERROR'}, "Caustic: no file path to export to")
            return {'CANCELLED'}
        path = pathlib.Path(bpy.path.abspath(self.filepath))
        path.parent.mkdir(parents=True, exist_ok=True)
        seconds = export(context.scene, path)
        self.report({'INFO'}, f"Caustic: exported {path} in {seconds:.2f} s")
        return {'FINISHED'}
