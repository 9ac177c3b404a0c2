"""The world: a colour, an environment image written beside the scene, or any other world baked
by Blender into an image (`bake_world`, kept between renders by its fingerprint), and the world's
volume as the scene's fog."""

import math
import os
import pathlib
import shutil
import tempfile

import bpy

from .bakes import last_line, run_blender_script
from .nodes import MISSING_IMAGE, image_place, linked_node, readable, world_volume_node
from .volumes import volume_medium


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
