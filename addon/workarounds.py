"""Work-arounds for faults of Blender's bundled glTF exporter (checked with Blender 5.0.1), each
undone after the export so that nothing of the user's data changes. Each names the fault; remove
one when Blender no longer has it."""

import math
import re

import bpy

from . import animated
from .bakes import bake_procedural_inputs
from .state import STATE


def run_exporter(scene, options):
    """Runs Blender's glTF exporter with `options`. Where it raises with Geometry Nodes instances
    (Blender 5.0.1's can on animated scenes: a KeyError in its sampling cache), it runs once more without
    them, and `STATE.fallbacks` says so; a failure it cannot get past is named (`exporter_failure`)."""
    with bpy.context.temp_override(scene=scene):
        try:
            return bpy.ops.export_scene.gltf(**options)
        except RuntimeError as error:
            if not options.get("export_gn_mesh"):
                raise RuntimeError(exporter_failure(error)) from error
            first = error
        try:
            result = bpy.ops.export_scene.gltf(**{**options, "export_gn_mesh": False})
        except RuntimeError:
            raise RuntimeError(exporter_failure(first)) from first
    STATE.fallbacks.append(f"{exporter_failure(first).split('. This is')[0]}; the scene was exported again without "
                      "Geometry Nodes instances, which are not rendered")
    return result


def exporter_workarounds(scene):
    """Changes to the scene that keep Blender's bundled glTF exporter from raising, each undone by
    the function returned with it (in reverse order, after the export), so that nothing of the
    user's data changes:
    - a light with a colour temperature raises a TypeError (Blender 5.0.1): the temperature is switched off and
      travels in the extras (`STATE.temperatures`);
    - a light whose Normalize is off raises a TypeError (Blender 5.0.1: the exporter calls `Light.area` with a
      wrong keyword): it is normalized with its power times its area, the power Cycles gives it;
    - a node group without a Group Output raises an IndexError (Blender 5.0.1): one is added to it (its outputs
      then give their defaults, as without one)."""
    undo = []
    for light in [light for light in bpy.data.lights if getattr(light, "use_temperature", False)]:
        STATE.temperatures[light.name] = light.temperature
        light.use_temperature = False
        undo.append(lambda light=light: setattr(light, "use_temperature", True))
    # One object a light datablock (its area, where objects that share it are scaled differently).
    unnormalized = {obj.data: obj for obj in scene.objects if obj.type == 'LIGHT'
                    and not getattr(obj.data, "normalize", True)}
    for light, obj in unnormalized.items():
        energy = light.energy
        light.energy, light.normalize = animated.power(obj), True

        def restore(light=light, energy=energy):
            light.energy, light.normalize = energy, False
        undo.append(restore)
    for group in groups_without_output():
        node = group.nodes.new("NodeGroupOutput")
        undo.append(lambda group=group, node=node: group.nodes.remove(node))
    for obj in shape_keys_with_modifiers(scene):
        undo += bake_shape_keys(scene, obj)
    undo += point_clouds_as_spheres(scene)
    undo += bake_procedural_inputs(scene)
    return undo


# The most points of one point cloud rendered as spheres.
MOST_POINTS = 100_000


def point_clouds_as_spheres(scene):
    """Every point cloud Cycles renders (a Point Cloud object, or one a Geometry Nodes modifier
    makes), which Blender's exporter drops, as a mesh of spheres of each point's radius (shaded
    smooth), in an object of its own for the export, with the point cloud's material. Returns the
    steps that remove them."""
    found = []
    # Read while the depsgraph is iterated, made after: new data would change the depsgraph.
    for instance in bpy.context.evaluated_depsgraph_get().object_instances:
        if instance.object.type != 'POINTCLOUD' or len(instance.object.data.points) == 0:
            continue
        owner = instance.parent if instance.is_instance and instance.parent is not None else instance.object
        # Cycles shades points without a material of their own with its default surface.
        material = next((m.original for m in instance.object.data.materials if m is not None), None)
        found.append((f"{owner.name} points", sphere_geometry(instance.object.data), material,
                      instance.matrix_world.copy()))
    undo = []
    for name, (vertices, faces), material, matrix in found:
        mesh = bpy.data.meshes.new(name)
        mesh.from_pydata(vertices, [], faces)
        mesh.shade_smooth()
        if material is not None:
            mesh.materials.append(material)
        obj = bpy.data.objects.new(name, mesh)
        scene.collection.objects.link(obj)
        obj.matrix_world = matrix

        def remove(obj=obj, mesh=mesh):
            bpy.data.objects.remove(obj)
            bpy.data.meshes.remove(mesh)
        undo.append(remove)
    return undo


def sphere_geometry(points, rings=12, segments=24):
    """The vertices and faces of one UV sphere a point of `points` (a PointCloud), of the point's
    radius."""
    import numpy as np
    count = min(len(points.points), MOST_POINTS)
    # Finer spheres where there are few: a 12 x 6 sphere renders a point about 4% dark.
    rings, segments = (rings, segments) if count <= 10_000 else (6, 12)
    centres = np.empty(len(points.points) * 3, np.float32)
    points.attributes["position"].data.foreach_get("vector", centres)
    radii = np.full(len(points.points), 0.01, np.float32)
    if "radius" in points.attributes:
        points.attributes["radius"].data.foreach_get("value", radii)
    centres, radii = centres.reshape(-1, 3)[:count], radii[:count]
    theta = np.linspace(0.0, math.pi, rings + 1)[1:-1]
    phi = np.linspace(0.0, 2 * math.pi, segments, endpoint=False)
    ring = np.stack([np.outer(np.sin(theta), np.cos(phi)), np.outer(np.sin(theta), np.sin(phi)),
                     np.outer(np.cos(theta), np.ones_like(phi))], axis=-1).reshape(-1, 3)
    unit = np.concatenate([[[0.0, 0.0, 1.0]], ring, [[0.0, 0.0, -1.0]]])
    faces = []
    for s in range(segments):
        t = (s + 1) % segments
        faces.append((0, 1 + s, 1 + t))
        for r in range(rings - 2):
            a, b = 1 + r * segments, 1 + (r + 1) * segments
            faces.append((a + s, b + s, b + t, a + t))
        last = 1 + (rings - 2) * segments
        faces.append((last + t, last + s, len(unit) - 1))
    vertices = (centres[:, None, :] + radii[:, None, None] * unit[None, :, :]).reshape(-1, 3)
    return vertices.tolist(), [tuple(v + p * len(unit) for v in f) for p in range(count) for f in faces]


def shape_keys_with_modifiers(scene):
    """Meshes whose shape keys are animated under modifiers other than an Armature: Blender's
    exporter applies the modifiers and drops the shape keys (glTF holds one or the other)."""
    return [obj for obj in scene.objects if obj.type == 'MESH' and obj.data.shape_keys is not None
            and animated.is_animated(obj.data.shape_keys) and obj.modifiers
            and all(modifier.type != 'ARMATURE' for modifier in obj.modifiers)]


def bake_shape_keys(scene, obj):
    """Replaces `obj`, for the export, by a copy without modifiers whose mesh is `obj` as Cycles
    sees it at the first frame and whose shape keys are its shape at every frame (each key's
    weight 1 at its frame, 0 at the frames beside it, linear between): the modified mesh animates
    as its shape keys animate it. Returns the steps that undo it; none where the modified mesh
    changes its vertex count between frames (it is exported as Blender's exporter exports it)."""
    frames = range(scene.frame_start, scene.frame_end + 1)
    current = scene.frame_current
    depsgraph = bpy.context.evaluated_depsgraph_get()
    shapes, mesh = [], None
    try:
        for frame in frames:
            scene.frame_set(frame)
            evaluated = obj.evaluated_get(depsgraph)
            if mesh is None:
                mesh = bpy.data.meshes.new_from_object(evaluated, preserve_all_data_layers=True, depsgraph=depsgraph)
            shape = evaluated.to_mesh()
            positions = [0.0] * (3 * len(shape.vertices))
            shape.vertices.foreach_get("co", positions)
            evaluated.to_mesh_clear()
            if len(positions) != 3 * len(mesh.vertices):
                bpy.data.meshes.remove(mesh)
                return []
            shapes.append(positions)
    finally:
        scene.frame_set(current)
    name = obj.name
    baked = obj.copy()
    baked.modifiers.clear()
    baked.data = mesh
    for collection in obj.users_collection:
        collection.objects.link(baked)
    preferences = bpy.context.preferences.edit
    interpolation, preferences.keyframe_new_interpolation_type = preferences.keyframe_new_interpolation_type, 'LINEAR'
    try:
        baked.shape_key_add(name="Basis")
        for frame, positions in zip(frames, shapes):
            block = baked.shape_key_add(name=f"Frame {frame}", from_mix=False)
            block.data.foreach_set("co", positions)
            for at, value in ((frame - 1, 0.0), (frame, 1.0), (frame + 1, 0.0)):
                block.value = value
                block.keyframe_insert("value", frame=at)
    finally:
        preferences.keyframe_new_interpolation_type = interpolation
    obj.name = f"{name} (modifiers and shape keys)"
    baked.name = name
    STATE.replaced.add(obj.name)

    def undo():
        STATE.replaced.discard(obj.name)
        bpy.data.objects.remove(baked)
        bpy.data.meshes.remove(mesh)  # with its shape keys
        obj.name = name
    return [undo]


def groups_without_output():
    """The shader node groups that have outputs but no Group Output node."""
    return [group for group in bpy.data.node_groups if group.bl_idname == 'ShaderNodeTree'
            and any(item.item_type == 'SOCKET' and item.in_out == 'OUTPUT' for item in group.interface.items_tree)
            and not any(node.type == 'GROUP_OUTPUT' for node in group.nodes)]


def exporter_failure(error):
    """What to tell the user when Blender's glTF exporter raised `error`: Blender's version, the
    exception's own last line and where in the exporter it was raised."""
    lines = [line.strip() for line in str(error).splitlines() if line.strip()]
    raised = next((line for line in reversed(lines) if re.match(r"^[A-Za-z_.]*(Error|Exception)\b", line)),
                  lines[-1] if lines else "no message")
    places = [re.search(r'io_scene_gltf2/(.*?)", line (\d+)', line) for line in lines]
    place = next((f" in {m.group(1)}:{m.group(2)}" for m in reversed(places) if m), "")
    return (f"Blender {bpy.app.version_string}'s glTF exporter failed{place}: {raised}. This is a fault of "
            "Blender's exporter on something in the scene; Caustic worked around the ones it knows (lights "
            "with a colour temperature or without Normalize, node groups without a Group Output)")


def drop_dangling_channels(gltf):
    """Removes the animation channels whose target node the file does not have, and animations
    left without channels (Blender 5.0.1's exporter writes channels for the Geometry Nodes
    instances it folds into `EXT_mesh_gpu_instancing`); returns how many channels it removed."""
    nodes = len(gltf.get("nodes", []))
    dropped = 0
    for animation in gltf.get("animations", []):
        channels = animation.get("channels", [])
        kept = [c for c in channels if c.get("target", {}).get("node", 0) < nodes]
        dropped += len(channels) - len(kept)
        animation["channels"] = kept
    if dropped:
        gltf["animations"] = [a for a in gltf["animations"] if a["channels"]]
        if not gltf["animations"]:
            del gltf["animations"]
    return dropped
