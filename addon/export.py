"""The scene as glTF 2.0 through Blender's own exporter, plus what the exporter drops, written into
the `caustic` extras (docs/extras.md) by the exporter's hooks while Caustic exports: area lights,
the sun's angle, point lights' radius, spot lights' blend, lights' colour temperature, the camera's depth of field, the shutter, the frame
rate, the resolution (with its percentage), the active camera, the world (its colour, an
Environment Texture's image written beside the scene as a linear EXR, or an image of any other
world baked by Blender: `bake_world`), dispersion and volume priorities; a glass's volume absorption
as `KHR_materials_volume` (`volume_absorption`); a volume that scatters as a `caustic` medium
(`volume_medium`, with a clear boundary where a volume object has no surface), and the world's
volume as the scene's fog (`world_fog`).

The hooks change nothing in the user's data: they add extras to what is being written, and
complete two values of the layers the exporter leaves out (`complete_layers`). Lights with a colour
temperature have it switched off while the exporter runs (it raises on them) and back on after.
"""

import json
import math
import os
import pathlib
import re
import shutil
import subprocess
import sys
import tempfile
import time

import bpy
from bpy.props import StringProperty

from . import animated

# True only while Caustic exports: the hooks stay out of the user's own glTF exports.
_exporting = False

# While Caustic exports, the world's extras (an environment image is written before the exporter
# runs, so that an image that cannot be read stops the export with its name).
_world = None

# While Caustic exports, the names of the objects rendered as holdouts (`holdout_objects`).
_holdouts = set()

# While Caustic exports, the objects replaced by a copy with their shape keys baked
# (`bake_shape_keys`): the exporter leaves them out.
_replaced = set()

# While Caustic exports, the colour temperature (kelvin) of each light that uses one, by name:
# Blender's exporter raises a TypeError on a light with `use_temperature`, so it is switched off
# for the export and the temperature travels in the extras (the renderer multiplies the colour
# by a black body's).
_temperatures = {}


def resolution(scene):
    """The render size in pixels, with Blender's percentage applied."""
    r = scene.render
    scale = r.resolution_percentage / 100.0
    return [max(1, round(r.resolution_x * scale)), max(1, round(r.resolution_y * scale))]


def linked_node(socket):
    """The node linked into `socket` (through reroutes), or None."""
    while socket.is_linked:
        node = socket.links[0].from_node
        if node.type != 'REROUTE':
            return node
        socket = node.inputs[0]
    return None


class WorldPlan:
    """How Caustic renders a world: a uniform colour, an Environment Texture's image (through a
    Mapping node's turn about Z), or, for any other node tree, an image of the world that
    Blender bakes (`bake_world`)."""

    def __init__(self, background=None, environment=None, mapping=None, bake=False):
        self.background, self.environment, self.mapping, self.bake = background, environment, mapping, bake


def world_plan(world):
    """The plan for `world`'s node tree: read node by node where it is a Background of a colour
    or of an equirectangular Environment Texture (turned about Z at most), else baked."""
    tree = world.node_tree if world is not None else None
    output = next((n for n in tree.nodes if n.type == 'OUTPUT_WORLD' and n.is_active_output), None) if tree else None
    surface = linked_node(output.inputs["Surface"]) if output is not None else None
    if surface is None:
        return WorldPlan()
    if surface.type != 'BACKGROUND' or surface.inputs["Strength"].is_linked:
        return WorldPlan(bake=True)
    colour = linked_node(surface.inputs["Color"])
    if colour is None:
        return WorldPlan(background=surface)
    if colour.type != 'TEX_ENVIRONMENT' or colour.projection != 'EQUIRECTANGULAR' or colour.image is None:
        return WorldPlan(bake=True)
    mapping = None if generated(colour.inputs["Vector"]) else linked_node(colour.inputs["Vector"])
    if mapping is not None and not turns_about_z(mapping):
        return WorldPlan(bake=True)
    return WorldPlan(background=surface, environment=colour, mapping=mapping)


def generated(socket):
    """Whether a vector input takes the world's own directions: unlinked, or linked straight to
    a Texture Coordinate node's Generated output."""
    if not socket.is_linked:
        return True
    link = socket.links[0]
    return link.from_node.type == 'TEX_COORD' and link.from_socket.name == "Generated"


def turns_about_z(mapping):
    """Whether a node is a Mapping node that only turns the world's directions about Z (fed by a
    Texture Coordinate node's Generated output; unlinked, it looks up one direction)."""
    if mapping.type != 'MAPPING':
        return False
    inputs = mapping.inputs
    if any(socket.is_linked for socket in inputs if socket.name != "Vector"):
        return False
    if not (inputs["Vector"].is_linked and generated(inputs["Vector"])):
        return False
    rotation = inputs["Rotation"].default_value
    moved = mapping.vector_type in ('POINT', 'TEXTURE') and any(abs(c) > 1e-6 for c in inputs["Location"].default_value)
    scaled = "Scale" in inputs and any(abs(c - 1.0) > 1e-6 for c in inputs["Scale"].default_value)
    return abs(rotation[0]) <= 1e-6 and abs(rotation[1]) <= 1e-6 and not moved and not scaled


def environment_rotation_deg(mapping):
    """The turn about the up axis of the environment a Mapping node gives (Caustic's
    `rotation_deg`): a Point, Vector or Normal mapping rotates the direction looked up, which turns
    the image the other way; a Texture mapping rotates by the inverse."""
    if mapping is None:
        return 0.0
    turn = math.degrees(mapping.inputs["Rotation"].default_value[2])
    return turn if mapping.vector_type == 'TEXTURE' else -turn


def srgb_to_linear(values):
    """The sRGB transfer function undone (values in [0, 1])."""
    import numpy as np
    return np.where(values <= 0.04045, values / 12.92, np.power((values + 0.055) / 1.055, 2.4))


def write_environment(image, folder):
    """Writes `image` (any format Blender loads, packed or on disk) into `folder` as a linear
    OpenEXR and returns its file name. Float images are linear already in Blender; 8-bit ones in
    sRGB are decoded. Saved through a Non-Color image: Blender converts a Linear Rec.709 image's
    pixels to display sRGB when it saves them as EXR."""
    import numpy as np
    width, height = image.size
    pixels = np.empty(width * height * 4, np.float32)
    image.pixels.foreach_get(pixels)
    pixels = pixels.reshape(-1, 4)
    if not image.is_float and image.colorspace_settings.name == 'sRGB':
        pixels[:, :3] = srgb_to_linear(pixels[:, :3])
    copy = bpy.data.images.new("caustic-environment", width, height, alpha=False, float_buffer=True)
    try:
        copy.colorspace_settings.name = 'Non-Color'
        copy.pixels.foreach_set(pixels.ravel())
        copy.filepath_raw = str(folder / "environment.exr")
        copy.file_format = 'OPEN_EXR'
        copy.save()
    finally:
        bpy.data.images.remove(copy)
    return "environment.exr"


def render_region(scene):
    """Blender's render region in pixels as `(x, y, width, height)`: x from the left, y from the
    bottom as Blender counts (Blender truncates the border's fractions), or None without one."""
    r = scene.render
    if not r.use_border:
        return None
    width, height = resolution(scene)
    x0, x1 = int(r.border_min_x * width), int(r.border_max_x * width)
    y0, y1 = int(r.border_min_y * height), int(r.border_max_y * height)
    if x1 <= x0 or y1 <= y0:
        return None
    return x0, y0, x1 - x0, y1 - y0


def world_extras(world, folder):
    """The world: an environment image (written or baked into `folder`) with its rotation and
    the Background's strength, or the Background's colour and strength (or the world's colour)."""
    if world is None:
        return None
    if world.node_tree is None:
        return {"color": list(world.color), "strength": 1.0}
    plan = world_plan(world)
    if plan.bake:
        return {"image": bake_world(world, folder), "strength": 1.0}
    if plan.background is None:
        return {"color": [0.0, 0.0, 0.0], "strength": 1.0}
    strength = plan.background.inputs["Strength"].default_value
    if plan.environment is None:
        colour = plan.background.inputs["Color"].default_value
        return {"color": [colour[0], colour[1], colour[2]], "strength": strength}
    if not readable(plan.environment.image):
        return {"color": list(MISSING_IMAGE), "strength": strength}
    return {"image": write_environment(plan.environment.image, folder), "strength": strength,
            "rotation_deg": environment_rotation_deg(plan.mapping)}


# The colour Cycles shows for an image it cannot read.
MISSING_IMAGE = (1.0, 0.0, 1.0)


def readable(image):
    """Whether Blender can read `image`'s pixels (loading it if it has not yet)."""
    width, height = image.size
    return width > 0 and height > 0 and image.has_data


def image_place(image):
    """An image's name and file, for messages."""
    return f"'{image.name}' ({bpy.path.abspath(image.filepath, library=image.library) or 'packed'})"


def world_image_warnings(world):
    """A world's environment image that cannot be read: rendered magenta, as Cycles renders it."""
    plan = world_plan(world) if world is not None and world.node_tree is not None else WorldPlan()
    if plan.environment is None or readable(plan.environment.image):
        return []
    return [f"world '{world.name}': its environment image {image_place(plan.environment.image)} cannot be read; "
            "the world is rendered magenta, as Cycles renders a missing image"]


# The width of a baked world's image (its height is half): 0.35 degrees a pixel.
BAKED_WORLD_WIDTH = 1024


def bake_world(world, folder, width=BAKED_WORLD_WIDTH):
    """Renders `world` as Cycles sees it into `folder` as an equirectangular EXR, in a separate
    Blender (a render cannot start inside a render; bake_world.py says how) and returns its file
    name. The world travels in a .blend of its own. A bake is kept in WORLD_CACHE under the
    world's fingerprint, so that rendering again (F12 after F12, each frame of an animation) does
    not bake again until something the bake shows changes."""
    image = folder / "world.exr"
    cached = WORLD_CACHE / f"{world_fingerprint(world, width)}.exr"
    if cached.exists():
        shutil.copyfile(cached, image)
        return image.name
    blend = folder / "world.blend"
    # Absolute paths: images the world uses by paths relative to the user's .blend still load.
    bpy.data.libraries.write(str(blend), {world}, fake_user=True, path_remap='ABSOLUTE')
    done = run_blender_script("bake_world.py", [str(blend), world.name, str(image), str(width)])
    if done.returncode != 0 or not image.exists():
        raise RuntimeError(f"Blender could not bake world '{world.name}' into an image: {last_line(done)}")
    WORLD_CACHE.mkdir(parents=True, exist_ok=True)
    partial = cached.with_suffix(f".{os.getpid()}.part")
    shutil.copyfile(image, partial)
    partial.replace(cached)
    return image.name


def run_blender_script(script, arguments):
    """Runs `script` (beside this file) in a separate Blender, with `arguments` after "--"."""
    path = pathlib.Path(__file__).resolve().parent / script
    if bpy.app.binary_path:
        command = [bpy.app.binary_path, "--background", "--factory-startup", "--python", str(path), "--", *arguments]
    else:  # Blender as a Python module: its Python imports bpy
        command = [sys.executable, str(path), "--", *arguments]
    return subprocess.run(command, capture_output=True, text=True)


def last_line(done):
    """The last line a finished process printed, for messages."""
    return ((done.stderr or done.stdout).strip().splitlines()[-1:] or ["no output"])[0]


# Where baked worlds are kept between renders (the system's temporary folder: a cache, not data).
WORLD_CACHE = pathlib.Path(tempfile.gettempdir()) / "caustic-baked-worlds"


def world_fingerprint(world, width):
    """A hash of everything a bake of `world` at `width` shows: each node's kind and own settings,
    its inputs' values, the links, node groups within, and each image's file and the time it was
    last changed (or its packed bytes), with Blender's version and the bake's own script."""
    import hashlib
    digest = hashlib.sha256(f"{bpy.app.version_string} {width}".encode())
    digest.update((pathlib.Path(__file__).resolve().parent / "bake_world.py").read_bytes())
    node_tree_fingerprint(world.node_tree, digest, set())
    return digest.hexdigest()[:32]


# Settings every node has that change nothing a render shows (where it is drawn, whether selected).
_NODE_BASICS = {p.identifier for p in bpy.types.ShaderNode.bl_rna.properties}


def node_tree_fingerprint(tree, digest, seen):
    """Feeds `digest` with what a render of node tree `tree` depends on (see world_fingerprint)."""
    if tree is None or tree.name in seen:
        return
    seen.add(tree.name)
    for node in sorted(tree.nodes, key=lambda n: n.name):
        digest.update(f"node {node.name} {node.bl_idname} {node.mute}".encode())
        for prop in node.bl_rna.properties:
            if prop.identifier not in _NODE_BASICS:
                setting_fingerprint(getattr(node, prop.identifier), digest, seen)
        for socket in node.inputs:
            value = getattr(socket, "default_value", None)
            digest.update(f"input {socket.identifier} {value_text(value)}".encode())
    for link in tree.links:
        digest.update(f"link {link.from_node.name}:{link.from_socket.identifier} "
                      f"{link.to_node.name}:{link.to_socket.identifier}".encode())


def setting_fingerprint(value, digest, seen):
    """Feeds `digest` with one node setting: an image by its file, a node group by its tree."""
    if isinstance(value, bpy.types.Image):
        if value.packed_file is not None:
            digest.update(bytes(value.packed_file.data))
        else:
            path = pathlib.Path(bpy.path.abspath(value.filepath, library=value.library))
            changed = path.stat().st_mtime_ns if path.exists() else None
            digest.update(f"image {path} {changed} {value.colorspace_settings.name}".encode())
    elif isinstance(value, bpy.types.NodeTree):
        node_tree_fingerprint(value, digest, seen)
    elif isinstance(value, bpy.types.ID):
        digest.update(f"id {value.name}".encode())
    elif not isinstance(value, bpy.types.bpy_struct):
        digest.update(f"setting {value_text(value)}".encode())


def value_text(value):
    """A value as text: arrays (colours, vectors) element by element."""
    try:
        return repr(tuple(value)) if not isinstance(value, str) else value
    except TypeError:
        return repr(value)


def scene_extras(scene, world):
    """The scene's `caustic` extras, with the world's (`world_extras`)."""
    r = scene.render
    extras = {"resolution": resolution(scene), "fps": r.fps / r.fps_base}
    if scene.camera is not None:
        extras["camera"] = scene.camera.name
    if r.film_transparent:
        extras["transparent_film"] = True
    if r.use_motion_blur:
        extras["shutter"] = {"length_frames": r.motion_blur_shutter, "position": r.motion_blur_position}
    if world is not None:
        extras["world"] = world
    fog = world_fog(scene.world)
    if fog is not None:
        extras["fog"] = fog
    return extras


def focus_distance(camera_object):
    """Blender's focus distance: the focus object's depth along the view, else the distance set."""
    dof = camera_object.data.dof
    if dof.focus_object is None:
        return dof.focus_distance
    view = camera_object.matrix_world.inverted() @ dof.focus_object.matrix_world.translation
    return max(0.0, -view.z)


def lens_extras(camera_object):
    """The camera's thin lens, or None when depth of field is off."""
    camera = camera_object.data
    if not camera.dof.use_dof:
        return None
    return {"fstop": camera.dof.aperture_fstop, "focus_distance": focus_distance(camera_object),
            "focal_length_mm": camera.lens, "blades": camera.dof.aperture_blades,
            "blade_rotation_deg": math.degrees(camera.dof.aperture_rotation)}


def fitted_side(scene, camera):
    """The side of the image (pixels, with the pixel aspect) that the camera's sensor or
    orthographic scale spans: the wider one under Blender's Auto sensor fit."""
    r = scene.render
    width, height = r.resolution_x * r.pixel_aspect_x, r.resolution_y * r.pixel_aspect_y
    return {'HORIZONTAL': width, 'VERTICAL': height}.get(camera.sensor_fit, max(width, height)), width, height


def camera_extras(camera_object, scene):
    """The camera's lens, its shift in image heights (Blender's is in the side its sensor fits)
    and, for an equirectangular panorama (which glTF cannot hold), its ranges."""
    camera = camera_object.data
    extras = {}
    lens = lens_extras(camera_object)
    if lens:
        extras["lens"] = lens
    side, _, height = fitted_side(scene, camera)
    if camera.shift_x or camera.shift_y:
        extras["shift"] = [camera.shift_x * side / height, camera.shift_y * side / height]
    if camera.type == 'PANO' and camera.panorama_type == 'EQUIRECTANGULAR':
        extras["panorama"] = {"longitude_deg": [math.degrees(camera.longitude_min), math.degrees(camera.longitude_max)],
                              "latitude_deg": [math.degrees(camera.latitude_min), math.degrees(camera.latitude_max)]}
    return extras or None


def fit_orthographic(gltf_camera, camera, scene):
    """Blender's exporter spans the orthographic scale across the wider side whatever the sensor
    fit; Cycles spans it across the side the sensor fits."""
    if gltf_camera.orthographic is None:
        return
    side, width, height = fitted_side(scene, camera)
    gltf_camera.orthographic.xmag = camera.ortho_scale / 2 * width / side
    gltf_camera.orthographic.ymag = camera.ortho_scale / 2 * height / side


def area_light_extras(light):
    """A Blender area light: shape, size, power (W), colour and spread."""
    extras = {"shape": light.shape, "size": light.size, "power": light.energy, "color": list(light.color)}
    if light.shape in ('RECTANGLE', 'ELLIPSE'):
        extras["size_y"] = light.size_y
    if light.spread < math.pi:
        extras["spread_deg"] = math.degrees(light.spread)
    return extras


def holdout_objects(view_layer):
    """The objects Cycles renders as holdouts in `view_layer`: those in a collection set to
    Holdout there (and its children), and those with their own Holdout (Visibility > Mask)."""
    held = set()

    def visit(layer_collection, inherited):
        holdout = inherited or layer_collection.holdout
        if holdout:
            held.update(obj.name for obj in layer_collection.collection.objects)
        for child in layer_collection.children:
            visit(child, holdout)
    visit(view_layer.layer_collection, False)
    return held | {obj.name for obj in view_layer.objects if obj.is_holdout}


def node_extras(blender_object):
    """What the exporter drops from an object: area lights, the sun's angle, a point or spot
    light's radius and Soft Falloff, a light's colour temperature and whether the camera sees it, the camera's
    lens, shift and panorama."""
    if blender_object.type == 'LIGHT':
        light = blender_object.data
        extras = {}
        if light.type == 'AREA':
            extras["area_light"] = area_light_extras(light)
        if light.type == 'SUN':
            extras["sun_angle_deg"] = math.degrees(light.angle)
        if light.type in ('POINT', 'SPOT') and light.shadow_soft_size > 0:
            extras["radius"] = light.shadow_soft_size
            if getattr(light, "use_soft_falloff", False):
                extras["soft_falloff"] = True
        if light.type == 'SPOT':
            extras["spot_blend"] = light.spot_blend
        if not blender_object.visible_camera:
            extras["visible_to_camera"] = False
        if light.name in _temperatures:
            extras["temperature_k"] = _temperatures[light.name]
        return extras or None
    if blender_object.type == 'CAMERA':
        return camera_extras(blender_object, bpy.context.scene)
    if blender_object.name in _holdouts:
        return {"holdout": True}
    return None


def material_extras(material):
    """Dispersion and the volume's priority from the material's Caustic settings."""
    settings = getattr(material, "caustic", None)
    if settings is None:
        return None
    surface = surface_node(material)
    if surface is not None and surface.type == 'HOLDOUT':
        return {"holdout": True}
    extras = {"priority": settings.priority} if settings.priority else {}
    if not colour_attributes_read(material):
        extras["vertex_colours"] = False
    if settings.dispersion == 'ABBE':
        extras["abbe"] = settings.abbe
    elif settings.dispersion == 'GLASS':
        extras["glass"] = settings.glass
    return extras or None


def colour_space(image):
    """How Cycles reads `image`'s stored values: "linear" (Non-Color, or a Linear colour space),
    "srgb", or None for a float image or another colour space (glTF's rule for the slot then)."""
    settings = image.colorspace_settings
    if settings.is_data or (not image.is_float and settings.name.startswith("Linear")):
        return "linear"
    if not image.is_float and settings.name == "sRGB":
        return "srgb"
    return None


def image_extras(export_image):
    """The colour space of an image the exporter writes (from one Blender image, or packed from
    several of one colour space): glTF reads a base colour as sRGB and data as linear whatever
    Blender's label, so the label travels (a Non-Color image as base colour stays undecoded, an
    sRGB roughness is decoded, as in Cycles)."""
    sources = {fill.image for fill in export_image.fills.values() if getattr(fill, "image", None) is not None}
    if export_image.original is not None:
        sources.add(export_image.original)
    spaces = {colour_space(image) for image in sources}
    return {"colour_space": spaces.pop()} if len(spaces) == 1 and None not in spaces else None


def colour_attributes_read(material, tree=None):
    """The colour attributes `material`'s nodes read (Color Attribute nodes with an output in use;
    "" for the active one), in its node groups too."""
    tree = tree or (material.node_tree if material is not None else None)
    if tree is None:
        return set()
    read = set()
    for node in tree.nodes:
        if node.type == 'VERTEX_COLOR' and any(output.is_linked for output in node.outputs):
            read.add(node.layer_name)
        elif node.type == 'GROUP' and node.node_tree is not None:
            read |= colour_attributes_read(material, node.node_tree)
    return read


# What Cycles renders of an object's evaluated geometry and Caustic does not, by object type.
UNRENDERED_GEOMETRY = {'VOLUME': "volume grids", 'CURVES': "hair curves", 'GREASEPENCIL': "grease pencil strokes"}


def unrendered_geometry_warnings(depsgraph):
    """Geometry Cycles renders that Caustic does not, named by the object that holds it (the
    instancer, for Geometry Nodes output and instances), once an object and kind."""
    found = set()
    for instance in depsgraph.object_instances:
        owner = instance.parent if instance.is_instance and instance.parent is not None else instance.object
        kind = UNRENDERED_GEOMETRY.get(instance.object.type)
        if kind is not None and instance.show_self:
            found.add((owner.name, kind))
        if instance.object.type == 'POINTCLOUD' and len(instance.object.data.points) > MOST_POINTS:
            found.add((owner.name, f"points past the first {MOST_POINTS}"))
    return [f"object '{name}': its {kind} are not rendered (Cycles renders them)" for name, kind in sorted(found)]


def colour_attribute_warnings(objects):
    """Meshes whose materials read different colour attributes: glTF carries one set of vertex
    colours a mesh, so every material on it shows the one the exporter picks."""
    warnings = []
    for obj in objects:
        if obj.type != 'MESH':
            continue
        read = set().union(*(colour_attributes_read(slot.material) for slot in obj.material_slots))
        if len(read) > 1:
            names = ", ".join(f"'{name}'" if name else "the active one" for name in sorted(read))
            warnings.append(f"object '{obj.name}': its materials read different colour attributes ({names}); "
                            "every one of them is rendered with the same one (glTF carries one a mesh)")
    return warnings


def add_extras(gltf_object, caustic):
    """Adds `caustic` under the object's extras, beside what is there."""
    if caustic:
        extras = gltf_object.extras if isinstance(gltf_object.extras, dict) else {}
        gltf_object.extras = {**extras, "caustic": caustic}


class glTF2ExportUserExtension:
    """The exporter's hooks (found by the exporter on enabled add-ons)."""

    def gather_scene_hook(self, gltf_scene, blender_scene, export_settings):
        if _exporting:
            add_extras(gltf_scene, scene_extras(blender_scene, _world))

    def gather_tree_filter_tag_hook(self, tree, export_settings):
        """Leaves out the objects of collections excluded from the view layer (Blender's
        exporter keeps them: they are not hidden from renders, only excluded), but not where a
        collection instance shows them (a collection excluded so that only its instances
        render), and the objects replaced for the export (`_replaced`)."""
        if not _exporting:
            return
        in_view_layer = set(bpy.context.view_layer.objects)
        for node in tree.nodes.values():
            obj = node.blender_object
            if obj is None:
                node.keep_tag = node.keep_tag and not exported_twice(tree, node)
            elif not instanced(tree, node) and (obj not in in_view_layer or obj.name in _replaced):
                node.keep_tag = False

    def gather_node_hook(self, gltf_node, blender_object, export_settings):
        if _exporting:
            add_extras(gltf_node, node_extras(blender_object))

    def gather_image_hook(self, gltf_image, export_image, blender_shader_sockets, export_settings):
        if _exporting:
            add_extras(gltf_image, image_extras(export_image))

    def gather_camera_hook(self, gltf_camera, blender_camera, export_settings):
        if _exporting:
            fit_orthographic(gltf_camera, blender_camera, bpy.context.scene)

    def gather_material_hook(self, gltf_material, blender_material, export_settings):
        if _exporting:
            add_extras(gltf_material, material_extras(blender_material))
            complete_layers(gltf_material, blender_material)
            add_volume(gltf_material, blender_material)
            show_missing_base_colour(gltf_material, blender_material)
            move_normal_map_strength(gltf_material)
            convert_simple_surface(gltf_material, blender_material)


# Objects Blender evaluates to a mesh that its glTF exporter writes itself (a curve, text, a
# surface): with Geometry Nodes export on, it writes that mesh a second time as an instance.
CONVERTED_TYPES = {'CURVE', 'FONT', 'SURFACE'}


def exported_twice(tree, node):
    """Whether the exporter's tree node `node` (one it made for a Geometry Nodes instance) repeats
    what it writes anyway, and would render over it: a curve's, text's or surface's own mesh, or
    the instances of an object instancing on its vertices or faces (written as duplis too)."""
    parent = tree.nodes.get(node.parent_uuid) if node.parent_uuid is not None else None
    owner = getattr(parent, "blender_object", None)
    if owner is not None and owner.type in CONVERTED_TYPES and isinstance(node.data, bpy.types.Mesh):
        return True
    host = getattr(node, "original_object", None)
    return host is not None and host.instance_type in ('VERTS', 'FACES')


def instanced(tree, node):
    """Whether the exporter's tree node `node` is inside a collection instance (an ancestor
    instances a collection)."""
    uuid = node.parent_uuid
    while uuid is not None and uuid in tree.nodes:
        parent = tree.nodes[uuid]
        if parent.blender_type == type(parent).INST_COLLECTION or getattr(parent.blender_object, "is_instancer", False):
            return True
        uuid = parent.parent_uuid
    return False


def volume_node(material):
    """The node that feeds the material's active output's volume, or None."""
    output = output_node(material)
    return output.inputs["Volume"].links[0].from_node if output and output.inputs["Volume"].links else None


def volume_absorption(material):
    """The absorption of the material's volume (a Volume Absorption node, or a Principled Volume's
    absorption) as `KHR_materials_volume`'s attenuation colour and distance, or None where nothing
    absorbs. Converted exactly: Cycles absorbs `k = (1 - Color) * Density` per unit of length (a
    Principled Volume `(1 - Color)(1 - sqrt(Absorption Color)) * Density`, each factor at least 0),
    and glTF keeps `attenuationColor ^ (length / attenuationDistance)`; so the distance is
    `1 / Density` and each channel of the colour `exp(-k / Density)`. (Blender's glTF exporter
    writes the Color itself as the attenuation colour, which absorbs differently.)"""
    node = volume_node(material)
    if node is None or node.type not in ('VOLUME_ABSORPTION', 'PRINCIPLED_VOLUME'):
        return None
    colour = [max(c, 0.0) for c in node.inputs["Color"].default_value[:3]]
    density = node.inputs["Density"].default_value
    per_density = [max(1.0 - c, 0.0) for c in colour]
    if node.type == 'PRINCIPLED_VOLUME':
        absorption = node.inputs["Absorption Color"].default_value[:3]
        per_density = [k * max(1.0 - math.sqrt(max(a, 0.0)), 0.0) for k, a in zip(per_density, absorption)]
    if density <= 0.0 or max(per_density) <= 0.0:
        return None
    return {"attenuationColor": [math.exp(-k) for k in per_density], "attenuationDistance": 1.0 / density}


def volume_medium(node):
    """A volume node that scatters (a Volume Scatter, or a Principled Volume of some colour and
    density) as a `caustic` medium, converted as Cycles defines it: a Volume Scatter scatters
    `Color * Density` per unit of length and absorbs nothing; a Principled Volume scatters
    `Color * Density` and absorbs `(1 - Color)(1 - sqrt(Absorption Color)) * Density` (each factor
    at least 0); both with Henyey-Greenstein's anisotropy. None for other nodes and where nothing
    scatters (a Volume Absorption travels as KHR_materials_volume, exactly)."""
    if node is None or node.type not in ('VOLUME_SCATTER', 'PRINCIPLED_VOLUME'):
        return None
    colour = [max(c, 0.0) for c in node.inputs["Color"].default_value[:3]]
    density = max(node.inputs["Density"].default_value, 0.0)
    scattering = [c * density for c in colour]
    if max(scattering) <= 0.0:
        return None
    absorption = [0.0, 0.0, 0.0]
    if node.type == 'PRINCIPLED_VOLUME':
        tint = node.inputs["Absorption Color"].default_value[:3]
        absorption = [max(1.0 - c, 0.0) * max(1.0 - math.sqrt(max(a, 0.0)), 0.0) * density
                      for c, a in zip(colour, tint)]
    anisotropy = min(max(node.inputs["Anisotropy"].default_value, -0.99), 0.99)
    return {"absorption": absorption, "scattering": scattering, "anisotropy": anisotropy}


def add_volume(gltf_material, material):
    """Writes the material's volume: one that scatters as a `caustic` medium (with a clear
    boundary of index 1 where the material has no surface, as a Blender volume object has none),
    one that only absorbs as `KHR_materials_volume`, keeping the thickness factor the exporter
    wrote (from a glTF Material Output node) or 1 (glTF reads 0 as no volume; the factor matters
    only on open meshes, which render as thin walls of that thickness)."""
    from io_scene_gltf2.io.com.gltf2_io_extensions import Extension
    extensions = gltf_material.extensions or {}
    medium = volume_medium(volume_node(material))
    if medium is not None:
        extras = gltf_material.extras if isinstance(gltf_material.extras, dict) else {}
        gltf_material.extras = {**extras, "caustic": {**extras.get("caustic", {}), "medium": medium}}
        extensions.pop("KHR_materials_volume", None)
        if surface_node(material) is None:
            extensions["KHR_materials_transmission"] = Extension(
                "KHR_materials_transmission", {"transmissionFactor": 1.0}, required=False)
            extensions["KHR_materials_ior"] = Extension("KHR_materials_ior", {"ior": 1.0}, required=False)
            pbr = gltf_material.pbr_metallic_roughness
            if pbr is not None:
                pbr.base_color_factor, pbr.metallic_factor, pbr.roughness_factor = [1.0, 1.0, 1.0, 1.0], 0.0, 0.0
        gltf_material.extensions = extensions
        return
    absorption = volume_absorption(material)
    if absorption is None:
        return
    written = extensions.get("KHR_materials_volume")
    thickness = written.extension.get("thicknessFactor", 1.0) if written is not None else 1.0
    extension = {**absorption, "thicknessFactor": thickness}
    extensions["KHR_materials_volume"] = Extension("KHR_materials_volume", extension, required=False)
    gltf_material.extensions = extensions


def world_volume_node(world):
    """The node that feeds the world's active output's volume, or None."""
    if world is None or world.node_tree is None:
        return None
    output = next((n for n in world.node_tree.nodes if n.type == 'OUTPUT_WORLD' and n.is_active_output), None)
    return output.inputs["Volume"].links[0].from_node if output and output.inputs["Volume"].links else None


def world_fog(world):
    """The world's volume (a Volume Scatter, Volume Absorption or Principled Volume on the World
    Output's Volume) as the scene's `fog`, or None. Like Cycles' world volume, it fills all space,
    so the world's light and suns do not reach the scene through it."""
    node = world_volume_node(world)
    if node is None:
        return None
    medium = volume_medium(node)
    if medium is None and node.type == 'VOLUME_ABSORPTION':
        density = max(node.inputs["Density"].default_value, 0.0)
        absorption = [max(1.0 - c, 0.0) * density for c in node.inputs["Color"].default_value[:3]]
        medium = {"absorption": absorption} if max(absorption) > 0.0 else None
    return medium


def unreadable_images(material):
    """The Image Texture nodes of `material` in use whose image Blender cannot read (a missing
    file): Blender's exporter drops their textures, Cycles shows them magenta."""
    tree = material.node_tree if material is not None else None
    if tree is None:
        return []
    return [node for node in tree.nodes if node.type == 'TEX_IMAGE' and node.image is not None
            and any(output.is_linked for output in node.outputs) and not readable(node.image)]


# The surfaces other than the Principled BSDF that Caustic renders as one (Blender's exporter
# writes nothing for them: glTF's default, a rough white metal): what each becomes, as
# (metallic, transmission, whether it keeps a specular layer).
SIMPLE_SURFACES = {'BSDF_DIFFUSE': (0.0, 0.0, False), 'BSDF_GLOSSY': (1.0, 0.0, True),
                   'BSDF_GLASS': (0.0, 1.0, True)}


def convert_simple_surface(gltf_material, material):
    """Writes a Diffuse, Glossy or Glass BSDF as the Principled BSDF that renders as it does in
    Cycles: a Diffuse BSDF a Lambertian of its colour (no specular layer), a Glossy BSDF a metal of
    its colour and roughness, a Glass BSDF a transmissive dielectric of its colour, roughness and
    IOR. Linked inputs keep their unlinked values (`material_warnings` says so)."""
    from io_scene_gltf2.io.com.gltf2_io import MaterialPBRMetallicRoughness
    from io_scene_gltf2.io.com.gltf2_io_extensions import Extension
    surface = surface_node(material)
    if surface is None or surface.type not in SIMPLE_SURFACES:
        return
    metallic, transmission, specular = SIMPLE_SURFACES[surface.type]
    colour = list(surface.inputs["Color"].default_value)[:3] + [1.0]
    roughness = surface.inputs["Roughness"].default_value if "Roughness" in surface.inputs else 1.0
    if surface.type == 'BSDF_DIFFUSE':
        roughness = 1.0
    gltf_material.pbr_metallic_roughness = MaterialPBRMetallicRoughness(
        base_color_factor=colour, base_color_texture=None, extensions=None, extras=None,
        metallic_factor=metallic, metallic_roughness_texture=None, roughness_factor=roughness)
    extensions = gltf_material.extensions or {}
    if not specular:
        extensions["KHR_materials_specular"] = Extension("KHR_materials_specular", {"specularFactor": 0.0},
                                                         required=False)
    if transmission:
        extensions["KHR_materials_transmission"] = Extension(
            "KHR_materials_transmission", {"transmissionFactor": transmission}, required=False)
        extensions["KHR_materials_ior"] = Extension("KHR_materials_ior", {"ior": surface.inputs["IOR"].default_value},
                                                    required=False)
    gltf_material.extensions = extensions or None


# Nodes Blender's glTF exporter turns into glTF (images, their coordinates and channels, normal
# maps, colour attributes, alpha's rounding); a Principled input fed through any other is not
# written as Cycles shades it.
EXPORTED_NODES = {'TEX_IMAGE', 'MAPPING', 'UVMAP', 'TEX_COORD', 'SEPARATE_COLOR', 'SEPARATE_RGB', 'NORMAL_MAP',
                  'VERTEX_COLOR', 'REROUTE', 'MATH'}

# The Principled inputs whose node trees are checked.
TEXTURED_INPUTS = ("Base Color", "Metallic", "Roughness", "Alpha", "Normal", "Emission Color", "Coat Weight",
                   "Coat Roughness", "Coat Normal", "Transmission Weight", "Specular Tint", "Sheen Tint")


def unexported_nodes(socket, seen=None):
    """The nodes upstream of `socket` that Blender's exporter does not turn into glTF."""
    seen = set() if seen is None else seen
    found = []
    for link in socket.links:
        node = link.from_node
        if node.name in seen:
            continue
        seen.add(node.name)
        if node.type not in EXPORTED_NODES:
            found.append(node)
        for upstream in node.inputs:
            found += unexported_nodes(upstream, seen)
    return found


def procedural_input_warnings(material, baked):
    """Principled inputs fed by nodes glTF cannot hold (procedural textures, ColorRamp, Mix, Bump),
    named with the nodes: baked into images where they are among `baked` (`procedural_bakes`), else
    as Blender's exporter writes them (their unlinked value or nothing)."""
    surface = principled_node(material)
    if surface is None:
        return []
    warnings = []
    for name in TEXTURED_INPUTS:
        socket = surface.inputs.get(name)
        nodes = unexported_nodes(socket) if socket is not None and socket.is_linked else []
        if not nodes:
            continue
        kinds = ", ".join(sorted({node.bl_label or node.type for node in nodes}))
        where = f"material '{material.name}': its {name} comes through nodes glTF cannot hold ({kinds}); "
        if name in BAKED_INPUTS and any(m == material and n == name for _, m, n in baked):
            warnings.append(where + "Blender bakes it into an image (Render Properties > Caustic > Bake Size)")
        else:
            warnings.append(where + "it is rendered as Blender's glTF exporter writes it (without them), "
                                    "not as Cycles shades it")
    return warnings


def surface_warnings(material, surface):
    """What of a surface other than the Principled BSDF Caustic does not render, as sentences."""
    name = f"material '{material.name}'"
    if surface.type in SIMPLE_SURFACES:
        linked = [socket.name for socket in surface.inputs if socket.is_linked and socket.name != "Weight"]
        return [f"{name}: the {surface.name}'s {socket} is linked; its unlinked value is rendered" for socket in linked]
    if surface.type == 'EMISSION':
        return []
    lost = {'MIX_SHADER': "the mix of its shaders (Blender's exporter keeps none of them)",
            'ADD_SHADER': "the sum of its shaders (Blender's exporter keeps none of them)",
            'BSDF_TRANSPARENT': "its transparency", 'BSDF_TRANSLUCENT': "its translucency",
            'BSDF_SHEEN': "its sheen", 'BSDF_TOON': "its toon shading", 'SUBSURFACE_SCATTERING': "its subsurface scattering",
            'GROUP': "the node group's shading"}.get(surface.type, f"its {surface.name}")
    return [f"{name}: {lost} is not rendered; the surface renders as glTF's default (a rough white metal), "
            "as Blender's glTF exporter writes it: use a Principled BSDF"]


def move_normal_map_strength(gltf_material):
    """Blender's exporter writes a Normal Map node's Strength as `normalTexture.scale`, which
    scales the normal's x and y; Cycles moves the mapped normal from the smooth one by the
    strength instead. The strength travels in the extras (`normal_map_strength`), the scale is 1."""
    normal = gltf_material.normal_texture
    scale = getattr(normal, "scale", None) if normal is not None else None
    if scale is None or scale == 1.0:
        return
    normal.scale = None
    extras = gltf_material.extras if isinstance(gltf_material.extras, dict) else {}
    gltf_material.extras = {**extras, "caustic": {**extras.get("caustic", {}), "normal_map_strength": scale}}


def show_missing_base_colour(gltf_material, material):
    """A Base Color read from an image that cannot be read is magenta, as Cycles shows it."""
    surface = principled_node(material)
    pbr = gltf_material.pbr_metallic_roughness
    if surface is None or pbr is None:
        return
    if linked_node(surface.inputs["Base Color"]) in unreadable_images(material):
        pbr.base_color_factor = [*MISSING_IMAGE, 1.0]
        pbr.base_color_texture = None


def missing_image_warnings(material):
    """What of `material` reads an image that cannot be read."""
    surface = principled_node(material)
    base = linked_node(surface.inputs["Base Color"]) if surface is not None else None
    return [f"material '{material.name}': its image {image_place(node.image)} cannot be read; "
            + ("its Base Color is rendered magenta, as Cycles renders a missing image" if node == base
               else "what it feeds is rendered without it (Cycles shows it magenta)")
            for node in unreadable_images(material)]


def complete_layers(gltf_material, material):
    """Writes what Blender's glTF exporter leaves out of the layers it exports: the Sheen Weight
    (it writes the Sheen Tint alone as the sheen's colour) and a Coat Roughness of 0.03 (Blender's
    default, which it takes for glTF's, 0: a smooth coat)."""
    surface = principled_node(material)
    extensions = gltf_material.extensions or {}
    if surface is None:
        return
    sheen = extensions.get("KHR_materials_sheen")
    weight = surface.inputs["Sheen Weight"]
    if sheen is not None and "sheenColorFactor" in sheen.extension and not weight.is_linked:
        sheen.extension["sheenColorFactor"] = [c * weight.default_value for c in sheen.extension["sheenColorFactor"]]
    coat = extensions.get("KHR_materials_clearcoat")
    roughness = surface.inputs["Coat Roughness"]
    if coat is not None and "clearcoatFactor" in coat.extension and not roughness.is_linked:
        coat.extension.setdefault("clearcoatRoughnessFactor", roughness.default_value)


# Principled BSDF inputs Caustic renders (everything else is ignored, with a warning).
SUPPORTED_INPUTS = {"Base Color", "Metallic", "Roughness", "IOR", "Transmission Weight", "Emission Color",
                    "Emission Strength", "Specular IOR Level"}

# Inputs that change the look when set away from these values, and that Caustic ignores.
# The narrowest area-light Spread Caustic renders (radians; the renderer's NARROWEST_SPREAD).
NARROWEST_SPREAD = math.radians(1.0)

IGNORED_INPUTS = {"Subsurface Weight": 0.0, "Anisotropic": 0.0, "Thin Film Thickness": 0.0}


def output_node(material):
    """The material's active output node, or None."""
    if material is None or material.node_tree is None:
        return None
    return next((n for n in material.node_tree.nodes if n.type == 'OUTPUT_MATERIAL' and n.is_active_output), None)


def surface_node(material):
    """The node that feeds the material's active output's surface, or None."""
    output = output_node(material)
    return output.inputs["Surface"].links[0].from_node if output and output.inputs["Surface"].links else None


def principled_node(material):
    """The Principled BSDF that feeds the material's surface, or None."""
    surface = surface_node(material)
    return surface if surface is not None and surface.type == 'BSDF_PRINCIPLED' else None


def volume_node_warnings(node, name):
    """What of the volume node `node` (feeding `name`, a material or the world) Caustic does not
    render, as sentences."""
    if node.type not in ('VOLUME_ABSORPTION', 'VOLUME_SCATTER', 'PRINCIPLED_VOLUME'):
        return [f"{name}: its volume ({node.name}) is not rendered (Volume Absorption, Volume Scatter and a "
                "Principled Volume are)"]
    warnings = [f"{name}: the volume's {socket.name} is linked; its unlinked value is rendered"
                for socket in node.inputs
                if socket.name in ("Color", "Density", "Absorption Color", "Anisotropy") and socket.is_linked]
    if node.type == 'VOLUME_SCATTER' and node.phase != 'HENYEY_GREENSTEIN':
        warnings.append(f"{name}: the Volume Scatter's {node.phase.replace('_', '-').title()} phase is rendered as "
                        "Henyey-Greenstein of its Anisotropy")
    if node.type == 'PRINCIPLED_VOLUME':
        glows = node.inputs["Emission Strength"].default_value > 0 or node.inputs["Blackbody Intensity"].default_value > 0
        if glows:
            warnings.append(f"{name}: the Principled Volume's emission and blackbody are not rendered")
    if node.type in ('VOLUME_SCATTER', 'PRINCIPLED_VOLUME') and abs(node.inputs["Anisotropy"].default_value) > 0.99:
        warnings.append(f"{name}: the volume's Anisotropy is rendered at 0.99 (Henyey-Greenstein needs |g| < 1)")
    return warnings


def world_volume_warnings(world):
    """What of the world's volume Caustic does not render, as sentences."""
    node = world_volume_node(world)
    return [] if node is None else volume_node_warnings(node, f"world '{world.name}'")


def volume_warnings(material):
    """What of `material`'s volume Caustic does not render, as sentences."""
    node = volume_node(material)
    return [] if node is None else volume_node_warnings(node, f"material '{material.name}'")


def material_warnings(material, baked=()):
    """What of `material` Caustic does not render, as sentences (`baked`: `procedural_bakes`)."""
    surface = surface_node(material)
    if surface is None:
        return volume_warnings(material)
    if surface.type == 'HOLDOUT':
        return volume_warnings(material)
    if surface.type != 'BSDF_PRINCIPLED':
        return surface_warnings(material, surface) + volume_warnings(material)
    warnings = volume_warnings(material) + procedural_input_warnings(material, baked)
    for name, neutral in IGNORED_INPUTS.items():
        socket = surface.inputs.get(name)
        if socket is not None and (socket.is_linked or abs(socket.default_value - neutral) > 1e-6):
            warnings.append(f"material '{material.name}': {name} is not supported and is ignored")
    return warnings


def camera_warnings(scene):
    """What of the active camera Caustic does not render."""
    if scene.camera is None:
        return []
    camera, name = scene.camera.data, f"camera '{scene.camera.name}'"
    warnings = []
    if camera.type == 'PANO' and camera.panorama_type != 'EQUIRECTANGULAR':
        warnings.append(f"{name}: the {camera.panorama_type} panorama is not rendered (Equirectangular is); "
                        "Caustic finds no camera to render with")
    if scene.render.pixel_aspect_x != scene.render.pixel_aspect_y:
        warnings.append(f"{name}: a pixel aspect other than 1 is not rendered (pixels are square)")
    return warnings


def scene_warnings(depsgraph):
    """What of the scene Caustic does not render, once per material."""
    materials = {slot.material for obj in depsgraph.scene.objects if obj.type == 'MESH'
                 for slot in obj.material_slots if slot.material is not None}
    baked = procedural_bakes(depsgraph.scene)
    warnings = [w for m in sorted(materials, key=lambda m: m.name) for w in material_warnings(m, baked)]
    warnings += [w for m in sorted(materials, key=lambda m: m.name) for w in missing_image_warnings(m)]
    warnings += world_volume_warnings(depsgraph.scene.world)
    warnings += world_image_warnings(depsgraph.scene.world)
    warnings += colour_attribute_warnings(depsgraph.scene.objects)
    warnings += unrendered_geometry_warnings(depsgraph)
    warnings += _fallbacks
    warnings += [f"node group '{group.name}' has no Group Output: its outputs give their default values (Blender's "
                 "glTF exporter raises on it; Caustic adds one while it exports)" for group in groups_without_output()]
    warnings += camera_warnings(depsgraph.scene)
    warnings += animated.unrendered_warnings(depsgraph.scene)
    for light in {obj.data for obj in depsgraph.scene.objects if obj.type == 'LIGHT'}:
        if light.type == 'AREA' and light.spread < NARROWEST_SPREAD:
            warnings.append(f"light '{light.name}': a Spread under 1 degree is rendered as 1 degree")
    return warnings


def export(scene, path):
    """Writes `scene` with its animation to `path` (.gltf) with Caustic's extras; returns the
    seconds it took."""
    global _exporting, _world, _holdouts
    start = time.perf_counter()
    _world = world_extras(scene.world, pathlib.Path(path).parent)
    _holdouts = holdout_objects(bpy.context.view_layer)
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
    _exporting = True
    _fallbacks.clear()
    undo = []
    try:
        undo = exporter_workarounds(scene)
        result = run_exporter(scene, options)
    finally:
        for step in reversed(undo):
            step()
        _temperatures.clear()
        _exporting, _world, _holdouts = False, None, set()
        _replaced.clear()
    if result != {'FINISHED'}:
        raise RuntimeError(f"Blender's glTF exporter did not finish ({result})")
    finish_file(scene, pathlib.Path(path))
    return time.perf_counter() - start


# What the last export left out because Blender's exporter failed with it (`run_exporter`).
_fallbacks = []


def run_exporter(scene, options):
    """Runs Blender's glTF exporter with `options`. Where it raises with Geometry Nodes instances
    (it can on animated scenes: a KeyError in its sampling cache), it runs once more without
    them, and `_fallbacks` says so; a failure it cannot get past is named (`exporter_failure`)."""
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
    _fallbacks.append(f"{exporter_failure(first).split('. This is')[0]}; the scene was exported again without "
                      "Geometry Nodes instances, which are not rendered")
    return result


def exporter_workarounds(scene):
    """Changes to the scene that keep Blender's bundled glTF exporter from raising, each undone by
    the function returned with it (in reverse order, after the export), so that nothing of the
    user's data changes:
    - a light with a colour temperature raises a TypeError: the temperature is switched off and
      travels in the extras (`_temperatures`);
    - a light whose Normalize is off raises a TypeError (the exporter calls `Light.area` with a
      wrong keyword): it is normalized with its power times its area, the power Cycles gives it;
    - a node group without a Group Output raises an IndexError: one is added to it (its outputs
      then give their defaults, as without one)."""
    undo = []
    for light in [light for light in bpy.data.lights if getattr(light, "use_temperature", False)]:
        _temperatures[light.name] = light.temperature
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


# The Principled inputs that are baked where nodes glTF cannot hold feed them.
BAKED_INPUTS = ("Base Color", "Metallic", "Roughness", "Emission Color", "Normal")


def procedural_bakes(scene):
    """(object, material, input) for each Principled input of BAKED_INPUTS fed through nodes glTF
    cannot hold, on the first mesh with texture coordinates that uses its material."""
    found, seen = [], set()
    for obj in scene.objects:
        if obj.type != 'MESH' or not obj.data.uv_layers:
            continue
        for material in {slot.material for slot in obj.material_slots if slot.material is not None}:
            surface = principled_node(material)
            if surface is None or material.name in seen:
                continue
            inputs = [name for name in BAKED_INPUTS if unexported_nodes(surface.inputs[name])]
            if inputs:
                seen.add(material.name)
                found += [(obj, material, name) for name in inputs]
    return found


def bake_procedural_inputs(scene):
    """Bakes the inputs `procedural_bakes` finds into images (in a separate Blender:
    bake_inputs.py) at the scene's Bake Size, and feeds each input its image for the export.
    Returns the steps that restore the materials."""
    jobs = procedural_bakes(scene)
    if not jobs:
        return []
    folder = pathlib.Path(tempfile.mkdtemp(prefix="caustic-bake-"))
    blend = folder / "objects.blend"
    bpy.data.libraries.write(str(blend), {obj for obj, _, _ in jobs}, fake_user=True, path_remap='ABSOLUTE')
    size = scene.caustic.bake_size
    listed = [{"object": obj.name, "material": material.name, "input": name, "out": str(folder / f"{i}.png"),
               "size": size} for i, (obj, material, name) in enumerate(jobs)]
    (folder / "jobs.json").write_text(json.dumps(listed))
    done = run_blender_script("bake_inputs.py", [str(blend), str(folder / "jobs.json")])
    undo = [lambda: shutil.rmtree(folder, ignore_errors=True)]
    if done.returncode != 0:
        _fallbacks.append(f"Blender could not bake the material inputs glTF cannot hold: {last_line(done)}")
        return undo
    return undo + [use_image(material, name, job["out"]) for job, (_, material, name) in zip(listed, jobs)]


def use_image(material, name, path):
    """Feeds the Principled input `name` of `material` the image at `path` (linear values; for the
    Normal, a tangent-space normal map through a Normal Map node) in place of what fed it; returns
    the step that puts the original link back."""
    tree = material.node_tree
    socket = principled_node(material).inputs[name]
    original = socket.links[0].from_socket
    image = bpy.data.images.load(path)
    image.colorspace_settings.name = 'Non-Color'
    added = [tree.nodes.new("ShaderNodeTexImage")]
    added[0].image = image
    if name == "Normal":
        added.append(tree.nodes.new("ShaderNodeNormalMap"))
        tree.links.new(added[0].outputs["Color"], added[1].inputs["Color"])
    tree.links.new(added[-1].outputs[0], socket)

    def restore():
        for node in added:
            tree.nodes.remove(node)
        tree.links.new(original, socket)
        bpy.data.images.remove(image)
    return restore


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
    _replaced.add(obj.name)

    def undo():
        _replaced.discard(obj.name)
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


def drop_dangling_channels(gltf):
    """Removes the animation channels whose target node the file does not have (and animations
    left without channels); returns how many channels it removed."""
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
