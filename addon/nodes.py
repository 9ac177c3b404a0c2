"""Reading Blender node trees: what feeds a socket, the material's output and surface, the
nodes Blender's glTF exporter turns into glTF, and images that cannot be read."""

import bpy


def linked_node(socket):
    """The node linked into `socket` (through reroutes), or None."""
    while socket.is_linked:
        node = socket.links[0].from_node
        if node.type != 'REROUTE':
            return node
        socket = node.inputs[0]
    return None


# The colour Cycles shows for an image it cannot read.
MISSING_IMAGE = (1.0, 0.0, 1.0)


def readable(image):
    """Whether Blender can read `image`'s pixels (loading it if it has not yet)."""
    width, height = image.size
    return width > 0 and height > 0 and image.has_data


def image_place(image):
    """An image's name and file, for messages."""
    return f"'{image.name}' ({bpy.path.abspath(image.filepath, library=image.library) or 'packed'})"


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


def volume_node(material):
    """The node that feeds the material's active output's volume, or None."""
    output = output_node(material)
    return output.inputs["Volume"].links[0].from_node if output and output.inputs["Volume"].links else None


def world_volume_node(world):
    """The node that feeds the world's active output's volume, or None."""
    if world is None or world.node_tree is None:
        return None
    output = next((n for n in world.node_tree.nodes if n.type == 'OUTPUT_WORLD' and n.is_active_output), None)
    return output.inputs["Volume"].links[0].from_node if output and output.inputs["Volume"].links else None


def unreadable_images(material):
    """The Image Texture nodes of `material` in use whose image Blender cannot read (a missing
    file): Blender's exporter drops their textures, Cycles shows them magenta."""
    tree = material.node_tree if material is not None else None
    if tree is None:
        return []
    return [node for node in tree.nodes if node.type == 'TEX_IMAGE' and node.image is not None
            and any(output.is_linked for output in node.outputs) and not readable(node.image)]


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
