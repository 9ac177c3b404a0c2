"""Scenes that combine, at random, what Blender shots contain, exported through the add-on and
rendered: no panic, no non-finite pixel, no failure without a message that names it.

Each seed builds one scene in bpy (`build`): a world (none, a colour, an HDRI, fog), lights of
every kind with their power, colour, size and cone animated or not (Normalize off, a colour
temperature), one to three cameras with an animated lens, focus and shift, Principled materials
with animated values, colour attributes, images (one missing), glass with absorption, a volume
object, a skinned mesh, shape keys (with a modifier), modifiers, collection instances (nested, of a
collection outside the scene), Geometry Nodes instances and point clouds, holdouts and an excluded
collection, motion blur and depth of field. It is exported with the add-on's exporter, then
`caustic info` and a render of three frames at 32x24 run on it.

Run by tests/addon.rs with a few dozen seeds (CAUSTIC_COMBINATION_SEEDS, "0:24" by default); a soak
run is the same script with more:

    CAUSTIC_BINARY=target/release/caustic target/bpy-venv/bin/python tests/addon/test_combinations.py 0:2000

which prints one line a failing seed and a summary of what failed.
"""
import collections
import math
import os
import pathlib
import random
import subprocess
import sys
import tempfile

HOME = tempfile.mkdtemp(prefix="caustic-combinations-home-")
os.environ["HOME"] = HOME

import bpy  # noqa: E402
import numpy as np  # noqa: E402
import OpenEXR  # noqa: E402

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))
import parity_scenes  # noqa: E402
from enable_addon import enable_addon  # noqa: E402

BINARY = os.environ["CAUSTIC_BINARY"]
OUT = pathlib.Path(tempfile.mkdtemp(prefix="caustic-combinations-"))
FRAMES = (1, 3)


def clear():
    """An empty scene (the data removed one kind at a time: reading factory settings would turn
    the add-on off)."""
    for blocks in (bpy.data.objects, bpy.data.meshes, bpy.data.materials, bpy.data.lights, bpy.data.cameras,
                   bpy.data.images, bpy.data.worlds, bpy.data.collections, bpy.data.armatures, bpy.data.actions,
                   bpy.data.node_groups):
        for block in list(blocks):
            blocks.remove(block)
    scene = bpy.context.scene
    scene.render.use_motion_blur = False
    scene.render.engine = 'CAUSTIC'
    scene.render.resolution_x, scene.render.resolution_y, scene.render.resolution_percentage = 32, 24, 100
    scene.frame_start, scene.frame_end = FRAMES
    scene.frame_set(FRAMES[0])
    return scene


def key(datablock, path, values, index=-1):
    """Keys `datablock.path` at the scene's first and last frame with `values`."""
    for frame, value in zip(FRAMES, values):
        target = datablock
        *parents, leaf = path.split(".")
        for part in parents:
            target = getattr(target, part)
        if index >= 0:
            getattr(target, leaf)[index] = value
        else:
            setattr(target, leaf, value)
        datablock.keyframe_insert(path, frame=frame, index=index)


def new_object(name, data, collection=None):
    obj = bpy.data.objects.new(name, data)
    (collection or bpy.context.scene.collection).objects.link(obj)
    return obj


def mesh_object(name, kind, collection=None, location=(0, 0, 0), size=1.0):
    """A cube, a sphere, a plane or a cylinder as its own object (built through bmesh, without
    operators)."""
    import bmesh
    mesh = bpy.data.meshes.new(name)
    bm = bmesh.new()
    if kind == "sphere":
        bmesh.ops.create_uvsphere(bm, u_segments=16, v_segments=8, radius=size / 2)
    elif kind == "plane":
        bmesh.ops.create_grid(bm, x_segments=2, y_segments=2, size=size / 2)
    elif kind == "cylinder":
        bmesh.ops.create_cone(bm, cap_ends=True, segments=12, radius1=size / 4, radius2=size / 4, depth=size)
    else:
        bmesh.ops.create_cube(bm, size=size)
    bm.to_mesh(mesh)
    bm.free()
    obj = new_object(name, mesh, collection)
    obj.location = location
    return obj


def principled(rng, name, animated=False):
    m = bpy.data.materials.new(name)
    bsdf = m.node_tree.nodes["Principled BSDF"]
    bsdf.inputs["Base Color"].default_value = (rng.random(), rng.random(), rng.random(), 1.0)
    bsdf.inputs["Roughness"].default_value = rng.random()
    bsdf.inputs["Metallic"].default_value = rng.choice([0.0, 0.0, 1.0])
    if rng.random() < 0.3:
        bsdf.inputs["Transmission Weight"].default_value = 1.0
    if rng.random() < 0.2:
        bsdf.inputs["Coat Weight"].default_value = rng.random()
    if rng.random() < 0.2:
        bsdf.inputs["Emission Strength"].default_value = rng.uniform(0.5, 5.0)
        bsdf.inputs["Emission Color"].default_value = (1.0, 0.8, 0.6, 1.0)
    if animated:
        socket = bsdf.inputs[rng.choice(["Base Color", "Roughness", "Emission Strength"])]
        if socket.name == "Base Color":
            key(socket, "default_value", [0.2, 0.9], index=0)
        else:
            key(socket, "default_value", [socket.default_value, socket.default_value * 0.5 + 0.1])
    return m


def link_input(material, node, output, socket):
    material.node_tree.links.new(node.outputs[output], material.node_tree.nodes["Principled BSDF"].inputs[socket])


def add_texture(rng, material):
    """An image (packed, Non-Color, or a file that is missing) on the Base Color or Roughness."""
    node = material.node_tree.nodes.new("ShaderNodeTexImage")
    kind = rng.choice(["packed", "noncolour", "missing"])
    if kind == "missing":
        image = bpy.data.images.new("lost", 4, 4)
        image.source, image.filepath = 'FILE', str(OUT / "no-such-folder" / "lost.png")
    else:
        image = bpy.data.images.new(kind, 4, 4)
        image.pixels.foreach_set([rng.random() for _ in range(64)])
        image.pack()
        if kind == "noncolour":
            image.colorspace_settings.name = 'Non-Color'
    node.image = image
    link_input(material, node, "Color", rng.choice(["Base Color", "Roughness"]))


def add_colour_attribute(rng, obj, material):
    """A colour attribute on `obj`, read by `material` (colour, and alpha) or not."""
    attribute = obj.data.color_attributes.new("Col", 'FLOAT_COLOR', 'CORNER')
    for corner in attribute.data:
        corner.color = (rng.random(), rng.random(), rng.random(), rng.choice([1.0, 0.5]))
    if rng.random() < 0.6:
        node = material.node_tree.nodes.new("ShaderNodeVertexColor")
        node.layer_name = "Col"
        link_input(material, node, "Color", "Base Color")
        if rng.random() < 0.4:
            link_input(material, node, "Alpha", "Alpha")


def add_world(rng, scene):
    kind = rng.choice(["none", "colour", "hdri", "fog"])
    if kind == "none":
        scene.world = None
        return kind
    world = bpy.data.worlds.new("World")
    scene.world = world
    nodes, links = world.node_tree.nodes, world.node_tree.links
    background = nodes["Background"]
    background.inputs["Color"].default_value = (0.3, 0.35, 0.4, 1.0)
    if kind == "hdri":
        image = bpy.data.images.new("sky", 16, 8, float_buffer=True)
        image.pixels.foreach_set([v for y in range(8) for x in range(16) for v in (y / 4, y / 4, 1.0, 1.0)])
        image.pack()
        environment = nodes.new("ShaderNodeTexEnvironment")
        environment.image = image
        links.new(environment.outputs["Color"], background.inputs["Color"])
    elif kind == "fog":
        scatter = nodes.new("ShaderNodeVolumeScatter")
        scatter.inputs["Density"].default_value = 0.02
        links.new(scatter.outputs[0], nodes["World Output"].inputs["Volume"])
    return kind


def add_light(rng, scene, index):
    kind = rng.choice(['POINT', 'SPOT', 'SUN', 'AREA'])
    light = bpy.data.lights.new(f"{kind.title()} {index}", kind)
    light.energy = {'SUN': 3.0}.get(kind, rng.uniform(50, 500))
    obj = new_object(light.name, light)
    obj.location = (rng.uniform(-3, 3), rng.uniform(-3, 3), rng.uniform(2, 5))
    obj.rotation_euler = (rng.uniform(-0.5, 0.5), rng.uniform(-0.5, 0.5), 0.0)
    if kind in ('POINT', 'SPOT'):
        light.shadow_soft_size = rng.choice([0.0, 0.1, 0.5])
    if kind == 'AREA':
        light.shape = rng.choice(['SQUARE', 'RECTANGLE', 'DISK', 'ELLIPSE'])
        light.size = rng.uniform(0.2, 2.0)
    if rng.random() < 0.2:
        light.normalize = False
    if rng.random() < 0.2:
        light.use_temperature, light.temperature = True, rng.uniform(2000, 9000)
    animated = []
    if rng.random() < 0.5:
        key(light, "energy", [light.energy, light.energy * 4])
        animated.append("power")
    if rng.random() < 0.3:
        key(light, "color", [1.0, 0.3], index=1)
        animated.append("colour")
    if kind in ('POINT', 'SPOT') and rng.random() < 0.3:
        key(light, "shadow_soft_size", [0.05, 0.4])
        animated.append("size")
    if kind == 'AREA' and rng.random() < 0.3:
        key(light, "size", [0.3, 1.5])
        animated.append("size")
    if kind == 'SPOT' and rng.random() < 0.4:
        key(light, "spot_size", [0.6, 1.4])
        animated.append("cone")
    return f"{kind.lower()}" + (f" animated ({', '.join(animated)})" if animated else "")


def add_camera(rng, scene, index):
    camera = bpy.data.cameras.new(f"Camera {index}")
    obj = new_object(camera.name, camera)
    obj.location = (rng.uniform(-1, 1), -8 + rng.uniform(-1, 1), rng.uniform(2, 4))
    obj.rotation_euler = (math.radians(rng.uniform(65, 80)), 0.0, rng.uniform(-0.2, 0.2))
    camera.lens = rng.uniform(25, 60)
    if rng.random() < 0.3:
        camera.dof.use_dof, camera.dof.aperture_fstop = True, rng.uniform(1.4, 8)
        camera.dof.focus_distance = 8.0
        if rng.random() < 0.5:
            key(camera, "dof.focus_distance", [6.0, 10.0])
    if rng.random() < 0.3:
        key(camera, "lens", [camera.lens, camera.lens * 1.5])
    if rng.random() < 0.2:
        key(camera, "shift_x", [0.0, 0.1])
    return obj


def add_skinned(rng, collection=None):
    armature = bpy.data.armatures.new("Rig")
    rig = new_object("Rig", armature, collection)
    bpy.context.view_layer.objects.active = rig
    bpy.ops.object.mode_set(mode='EDIT')
    bone = armature.edit_bones.new("Bone")
    bone.head, bone.tail = (0, 0, 0), (0, 0, 1)
    bpy.ops.object.mode_set(mode='OBJECT')
    body = mesh_object("Skinned", "cylinder", collection, location=(0, 0, 0.5))
    body.parent = rig
    parity_scenes.bind_to_bone(body, rig)
    pose = rig.pose.bones["Bone"]
    pose.rotation_mode = 'XYZ'
    key(pose, "rotation_euler", [0.0, 0.6], index=0)
    rig.location = (rng.uniform(-2, 2), rng.uniform(-1, 1), 0.0)
    return body


def add_shape_keys(rng, obj):
    obj.shape_key_add(name="Basis")
    bulge = obj.shape_key_add(name="Bulge")
    for point in bulge.data:
        point.co *= 1.3
    key(bulge, "value", [0.0, 1.0])
    if rng.random() < 0.5:
        obj.modifiers.new("Subdivision", 'SUBSURF').levels = 1


def add_collection_instances(rng, scene, material):
    """A collection outside the scene instanced by an empty, and (nested) a collection that
    instances it."""
    props = bpy.data.collections.new("Props")
    prop = mesh_object("Prop", rng.choice(["cube", "sphere"]), props, size=0.4)
    prop.data.materials.append(material)
    holder = new_object("Props instance", None)
    holder.instance_type, holder.instance_collection = 'COLLECTION', props
    holder.location = (rng.uniform(-2, 2), rng.uniform(-2, 2), 0.2)
    if rng.random() < 0.5:
        outer = bpy.data.collections.new("Nested")
        inner = new_object("Inner instance", None, outer)
        inner.instance_type, inner.instance_collection = 'COLLECTION', props
        nested = new_object("Nested instance", None)
        nested.instance_type, nested.instance_collection = 'COLLECTION', outer
        nested.location = (rng.uniform(-2, 2), rng.uniform(-2, 2), 0.6)


def add_volume_object(rng):
    cube = mesh_object("Fog box", "cube", location=(rng.uniform(-2, 2), rng.uniform(-1, 1), 0.6), size=1.2)
    m = bpy.data.materials.new("Fog")
    nodes, links = m.node_tree.nodes, m.node_tree.links
    nodes.remove(nodes["Principled BSDF"])
    volume = nodes.new(rng.choice(["ShaderNodeVolumeScatter", "ShaderNodeVolumePrincipled", "ShaderNodeVolumeAbsorption"]))
    volume.inputs["Density"].default_value = rng.uniform(0.1, 2.0)
    links.new(volume.outputs[0], nodes["Material Output"].inputs["Volume"])
    cube.data.materials.append(m)


def build(seed):
    """Builds scene `seed`; returns what it holds, for messages."""
    rng = random.Random(seed)
    scene = clear()
    holds = [f"world {add_world(rng, scene)}"]
    floor = mesh_object("Floor", "plane", size=12)
    floor.data.materials.append(principled(rng, "Floor"))
    for i in range(rng.randint(1, 3)):
        holds.append(f"light {add_light(rng, scene, i)}")
    cameras = [add_camera(rng, scene, i) for i in range(rng.randint(1, 3))]
    scene.camera = rng.choice(cameras)
    holds.append(f"{len(cameras)} cameras")
    for i in range(rng.randint(1, 4)):
        kind = rng.choice(["cube", "sphere", "cylinder"])
        obj = mesh_object(f"Object {i}", kind, location=(rng.uniform(-2.5, 2.5), rng.uniform(-1.5, 2), 0.5))
        material = principled(rng, f"Material {i}", animated=rng.random() < 0.3)
        obj.data.materials.append(material)
        if rng.random() < 0.3:
            add_colour_attribute(rng, obj, material)
            holds.append("colour attribute")
        if rng.random() < 0.3:
            add_texture(rng, material)
            holds.append("image")
        if rng.random() < 0.3:
            add_shape_keys(rng, obj)
            holds.append("shape keys" + (" and a modifier" if obj.modifiers else ""))
        elif rng.random() < 0.3:
            obj.modifiers.new("Bevel", 'BEVEL')
            holds.append("modifier")
        if rng.random() < 0.2:
            parity_scenes.geometry_nodes(obj, rng.random() < 0.4, material, realize=rng.random() < 0.5)
            holds.append("geometry nodes")
        if rng.random() < 0.15:
            obj.is_holdout = True
            holds.append("holdout")
        if rng.random() < 0.2:
            key(obj, "location", [obj.location.x, obj.location.x + 0.5], index=0)
            holds.append("moving object")
    if rng.random() < 0.3:
        add_skinned(rng)
        holds.append("skin")
    if rng.random() < 0.3:
        add_collection_instances(rng, scene, principled(rng, "Prop"))
        holds.append("collection instances")
    if rng.random() < 0.2:
        add_volume_object(rng)
        holds.append("volume object")
    if rng.random() < 0.2:
        hidden = bpy.data.collections.new("Excluded")
        scene.collection.children.link(hidden)
        mesh_object("Excluded cube", "cube", hidden)
        bpy.context.view_layer.layer_collection.children["Excluded"].exclude = True
        holds.append("excluded collection")
    if rng.random() < 0.3:
        scene.render.use_motion_blur = True
        holds.append("motion blur")
    return ", ".join(holds)


def exr_pixels(path):
    channels = OpenEXR.File(str(path)).channels()
    return np.concatenate([np.asarray(c.pixels, dtype=np.float64).ravel() for c in channels.values()])


def check(seed):
    """Builds, exports and renders scene `seed`; returns the reason it failed, or None."""
    export, unrendered = sys.modules["caustic.export"], sys.modules["caustic.unrendered"]
    holds = build(seed)
    folder = OUT / f"seed-{seed}"
    folder.mkdir()
    path = folder / "scene.gltf"
    try:
        unrendered.scene_warnings(bpy.context.evaluated_depsgraph_get())
        export.export(bpy.context.scene, path)
    except Exception as error:  # noqa: BLE001 - every failure is a finding
        return f"export raised {type(error).__name__}: {error} ({holds})"
    info = subprocess.run([BINARY, "info", str(path)], capture_output=True, text=True)
    if info.returncode != 0 or "panicked" in info.stderr or "internal error" in info.stderr:
        return f"caustic info failed: {info.stderr.strip()[-400:]} ({holds})"
    frames = f"{FRAMES[0]}-{FRAMES[1]}"
    render = subprocess.run([BINARY, "render", str(path), "-o", str(folder / "frames"), "--passes", "2",
                             "--frames", frames, "--progress", "none", "--threads", "2"],
                            capture_output=True, text=True)
    if render.returncode != 0 or "panicked" in render.stderr or "internal error" in render.stderr:
        return f"caustic render failed: {render.stderr.strip()[-400:]} ({holds})"
    for frame in range(FRAMES[0], FRAMES[1] + 1):
        exr = folder / "frames" / f"frame_{frame:04d}.exr"
        if not exr.exists():
            return f"frame {frame} was not written ({holds})"
        if not np.all(np.isfinite(exr_pixels(exr))):
            return f"frame {frame} has pixels that are not finite ({holds})"
    return None


def seeds(text):
    start, end = (int(v) for v in text.split(":"))
    return range(start, end)


def main():
    enable_addon(BINARY)
    chosen = seeds(sys.argv[1] if len(sys.argv) > 1 else os.environ.get("CAUSTIC_COMBINATION_SEEDS", "0:24"))
    failures = {}
    for seed in chosen:
        reason = check(seed)
        if reason is not None:
            failures[seed] = reason
            print(f"seed {seed}: {reason}", flush=True)
    kinds = collections.Counter(reason.split(":")[0] for reason in failures.values())
    print(f"{len(chosen)} scenes, {len(failures)} failed: {dict(kinds)}")
    sys.exit(1 if failures else 0)


if __name__ == "__main__":
    main()
