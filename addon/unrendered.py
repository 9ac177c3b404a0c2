"""What Caustic does not render of a scene, as sentences naming the object or material: shown
by the render engine and by `caustic` as the scene loads."""

import math

from . import animated
from .bakes import BAKED_INPUTS, procedural_bakes
from .extras import SIMPLE_SURFACES
from .nodes import TEXTURED_INPUTS, colour_attributes_read, image_place, linked_node, principled_node, surface_node, unexported_nodes, unreadable_images
from .volumes import volume_warnings, world_volume_warnings
from .workarounds import MOST_POINTS, groups_without_output
from .world import world_image_warnings
from .state import STATE


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


def missing_image_warnings(material):
    """What of `material` reads an image that cannot be read."""
    surface = principled_node(material)
    base = linked_node(surface.inputs["Base Color"]) if surface is not None else None
    return [f"material '{material.name}': its image {image_place(node.image)} cannot be read; "
            + ("its Base Color is rendered magenta, as Cycles renders a missing image" if node == base
               else "what it feeds is rendered without it (Cycles shows it magenta)")
            for node in unreadable_images(material)]


# Principled BSDF inputs Caustic renders (everything else is ignored, with a warning).
SUPPORTED_INPUTS = {"Base Color", "Metallic", "Roughness", "IOR", "Transmission Weight", "Emission Color",
                    "Emission Strength", "Specular IOR Level"}


# Inputs that change the look when set away from these values, and that Caustic ignores.
# The narrowest area-light Spread Caustic renders (radians; the renderer's NARROWEST_SPREAD).
NARROWEST_SPREAD = math.radians(1.0)


IGNORED_INPUTS = {"Subsurface Weight": 0.0, "Anisotropic": 0.0, "Thin Film Thickness": 0.0}


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
    warnings += STATE.fallbacks
    warnings += [f"node group '{group.name}' has no Group Output: its outputs give their default values (Blender's "
                 "glTF exporter raises on it; Caustic adds one while it exports)" for group in groups_without_output()]
    warnings += camera_warnings(depsgraph.scene)
    warnings += animated.unrendered_warnings(depsgraph.scene)
    for light in {obj.data for obj in depsgraph.scene.objects if obj.type == 'LIGHT'}:
        if light.type == 'AREA' and light.spread < NARROWEST_SPREAD:
            warnings.append(f"light '{light.name}': a Spread under 1 degree is rendered as 1 degree")
    return warnings
