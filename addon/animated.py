"""Animated values the glTF file does not carry: a light's power and colour, a spot's cone, an
area light's power and colour, a focal-length zoom, and a Principled material's colour, factors and
emission, sampled once a frame and written as the scene's `caustic.tracks` (docs/extras.md): keys
on the pointers `KHR_animation_pointer` uses, so the renderer reads both the same way.

Blender's exporter can write these itself (`export_pointer_animation`), but together with
`export_apply` it raises an IndexError on a scene with an armature-skinned mesh and animated values
(Blender 5.0.1's glTF exporter), so Caustic samples them here, after the export, from the same frames.
"""

import math

import bpy

# glTF photometric units: a point or spot light of W watts is W / (4 pi) * 683 candela, a sun of
# W/m^2 is W * 683 lux (as Blender's exporter writes them).
LUMENS_PER_WATT = 683.0

# The Principled BSDF's inputs that glTF material pointers animate, with their pointer (relative to
# the material) and how many floats they hold.
PRINCIPLED_POINTERS = {
    "Base Color": ("pbrMetallicRoughness/baseColorFactor", 4),
    "Metallic": ("pbrMetallicRoughness/metallicFactor", 1),
    "Roughness": ("pbrMetallicRoughness/roughnessFactor", 1),
    "Transmission Weight": ("extensions/KHR_materials_transmission/transmissionFactor", 1),
    "Emission Color": ("emissiveFactor", 3),
    "Emission Strength": ("extensions/KHR_materials_emissive_strength/emissiveStrength", 1),
}


def is_animated(datablock):
    """Whether `datablock` (or its node tree) has keyframes or drivers."""
    if datablock is None:
        return False
    data = getattr(datablock, "animation_data", None)
    tree = getattr(datablock, "node_tree", None)
    own = data is not None and (data.action is not None or len(data.drivers) > 0)
    return own or (tree is not None and is_animated(tree))


def floats(value):
    """A value as a list of floats."""
    try:
        return [float(v) for v in value]
    except TypeError:
        return [float(value)]


def power(obj):
    """The power Cycles gives light object `obj`: its Power, times its area where Normalize is off."""
    light = obj.data
    normalized = getattr(light, "normalize", True)
    return light.energy if normalized else light.energy * light.area(matrix_world=obj.matrix_world)


def light_samplers(index, node_index, obj):
    """(pointer, reader) pairs for light object `obj`, glTF light `index` on node `node_index`."""
    light = obj.data
    if light.type == 'AREA':
        extras = f"/nodes/{node_index}/extras/caustic/area_light"
        return [(f"{extras}/power", lambda: power(obj)), (f"{extras}/color", lambda: light.color)]
    base = f"/extensions/KHR_lights_punctual/lights/{index}"
    per_watt = LUMENS_PER_WATT if light.type == 'SUN' else LUMENS_PER_WATT / (4 * math.pi)
    samplers = [(f"{base}/intensity", lambda: power(obj) * per_watt), (f"{base}/color", lambda: light.color)]
    if light.type == 'SPOT':
        samplers.append((f"{base}/spot/outerConeAngle", lambda: light.spot_size / 2))
    return samplers


def camera_samplers(index, camera, gltf_camera):
    """The zoom of camera data `camera` (glTF camera `index`): the field of view scales with the
    focal length at the exported one (the sensor stays)."""
    perspective = gltf_camera.get("perspective")
    if camera.type != 'PERSP' or perspective is None:
        return []
    tan_half, lens = math.tan(perspective["yfov"] / 2), camera.lens
    return [(f"/cameras/{index}/perspective/yfov", lambda: 2 * math.atan(tan_half * lens / camera.lens))]


def material_samplers(index, material):
    """The unlinked Principled inputs of `material` (glTF material `index`)."""
    tree = material.node_tree
    principled = next((n for n in tree.nodes if n.type == 'BSDF_PRINCIPLED'), None) if tree else None
    if principled is None:
        return []
    samplers = []
    for name, (pointer, width) in PRINCIPLED_POINTERS.items():
        socket = principled.inputs.get(name)
        if socket is not None and not socket.is_linked:
            samplers.append((f"/materials/{index}/{pointer}", lambda s=socket, w=width: floats(s.default_value)[:w]))
    return samplers


def samplers(scene, gltf):
    """Every animated value of `scene` that the exported `gltf` (its JSON) has a place for, as
    (pointer, reader) pairs."""
    nodes = {node.get("name"): (i, node) for i, node in enumerate(gltf.get("nodes", []))}
    found = []
    for obj in scene.objects:
        if obj.name not in nodes:
            continue
        node_index, node = nodes[obj.name]
        if obj.type == 'LIGHT' and is_animated(obj.data):
            light = node.get("extensions", {}).get("KHR_lights_punctual", {}).get("light")
            if light is not None or obj.data.type == 'AREA':
                found += light_samplers(light, node_index, obj)
        if obj.type == 'CAMERA' and obj == scene.camera and is_animated(obj.data) and "camera" in node:
            found += camera_samplers(node["camera"], obj.data, gltf["cameras"][node["camera"]])
    materials = {m.get("name"): i for i, m in enumerate(gltf.get("materials", []))}
    for material in bpy.data.materials:
        if material.name in materials and is_animated(material):
            found += material_samplers(materials[material.name], material)
    return found


def tracks(scene, gltf):
    """The `caustic.tracks` of `scene`: each animated value sampled at every frame of the range,
    kept where it changes."""
    readers = samplers(scene, gltf)
    if not readers:
        return []
    fps = scene.render.fps / scene.render.fps_base
    frames = range(scene.frame_start, scene.frame_end + 1)
    current = (scene.frame_current, scene.frame_subframe)
    keys = {pointer: [] for pointer, _ in readers}
    try:
        for frame in frames:
            scene.frame_set(frame)
            for pointer, read in readers:
                keys[pointer].append(floats(read()))
    finally:
        scene.frame_set(current[0], subframe=current[1])
    times = [frame / fps for frame in frames]
    changing = {pointer for pointer, values in keys.items() if any(v != values[0] for v in values)}
    # The exporter folds an Emission Strength of at most 1 into the emissive factor: an animated
    # strength needs the colour's track too (and the other way round).
    changing |= {partner for pointer in changing for partner in emission_partners(pointer) if partner in keys}
    return [{"pointer": pointer, "times": times, "values": [v for key in keys[pointer] for v in key]}
            for pointer in keys if pointer in changing]


def emission_partners(pointer):
    """The pointers that together with `pointer` make a material's emission (colour times strength)."""
    colour, strength = PRINCIPLED_POINTERS["Emission Color"][0], PRINCIPLED_POINTERS["Emission Strength"][0]
    for mine, other in ((colour, strength), (strength, colour)):
        if pointer.endswith("/" + mine):
            return [pointer[:-len(mine)] + other]
    return []


def animated_paths(datablock):
    """The data paths keyed or driven on `datablock` (Blender 5.0's slotted actions, or the older
    flat ones)."""
    data = getattr(datablock, "animation_data", None)
    if data is None:
        return set()
    paths = {driver.data_path for driver in data.drivers}
    action = data.action
    if action is None:
        return paths
    curves = list(getattr(action, "fcurves", []) or [])
    if not curves and data.action_slot is not None:
        from bpy_extras import anim_utils
        channelbag = anim_utils.action_get_channelbag_for_slot(action, data.action_slot)
        curves = list(channelbag.fcurves) if channelbag is not None else []
    return paths | {curve.data_path for curve in curves}


# What is rendered of an animated light and camera (the rest renders as at the exported frame).
RENDERED_LIGHT_PATHS = {"energy", "color", "spot_size"}
RENDERED_CAMERA_PATHS = {"lens"}


def unrendered_warnings(scene):
    """Animated values Caustic does not render (their value at the exported frame is)."""
    warnings = []
    for obj in scene.objects:
        if obj.type == 'LIGHT':
            rest = sorted(animated_paths(obj.data) - RENDERED_LIGHT_PATHS)
            if rest:
                warnings.append(f"light '{obj.data.name}': its animated {', '.join(rest)} renders as at the "
                                "current frame (power, colour and spot size are animated)")
        if obj.type == 'CAMERA' and obj == scene.camera:
            rest = sorted(animated_paths(obj.data) - RENDERED_CAMERA_PATHS)
            if rest:
                warnings.append(f"camera '{obj.data.name}': its animated {', '.join(rest)} renders as at the "
                                "current frame (the focal length is animated)")
    if scene.world is not None and is_animated(scene.world):
        warnings.append(f"world '{scene.world.name}': its animation is not rendered (the current frame's "
                        "world is)")
    return warnings
