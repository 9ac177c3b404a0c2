"""The `caustic` extras the exporter's hooks add to what it writes (docs/extras.md): the scene's
resolution, shutter and world, cameras' lenses, lights' sizes and temperatures, materials'
dispersion and priorities, images' colour spaces; and the materials the exporter writes short
(layers it leaves out, simple surfaces it does not convert, a normal map's strength)."""

import math

import bpy

from .nodes import MISSING_IMAGE, colour_attributes_read, linked_node, principled_node, surface_node, unreadable_images
from .volumes import add_volume
from .world import world_fog
from .state import STATE


def resolution(scene):
    """The render size in pixels, with Blender's percentage applied."""
    r = scene.render
    scale = r.resolution_percentage / 100.0
    return [max(1, round(r.resolution_x * scale)), max(1, round(r.resolution_y * scale))]


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
        if light.name in STATE.temperatures:
            extras["temperature_k"] = STATE.temperatures[light.name]
        return extras or None
    if blender_object.type == 'CAMERA':
        return camera_extras(blender_object, bpy.context.scene)
    if blender_object.name in STATE.holdouts:
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


def add_extras(gltf_object, caustic):
    """Adds `caustic` under the object's extras, beside what is there."""
    if caustic:
        extras = gltf_object.extras if isinstance(gltf_object.extras, dict) else {}
        gltf_object.extras = {**extras, "caustic": caustic}


class glTF2ExportUserExtension:
    """The exporter's hooks (found by the exporter on enabled add-ons)."""

    def gather_scene_hook(self, gltf_scene, blender_scene, export_settings):
        if STATE.exporting:
            add_extras(gltf_scene, scene_extras(blender_scene, STATE.world))

    def gather_tree_filter_tag_hook(self, tree, export_settings):
        """Leaves out the objects of collections excluded from the view layer (Blender's
        exporter keeps them: they are not hidden from renders, only excluded), but not where a
        collection instance shows them (a collection excluded so that only its instances
        render), and the objects replaced for the export (`STATE.replaced`)."""
        if not STATE.exporting:
            return
        in_view_layer = set(bpy.context.view_layer.objects)
        for node in tree.nodes.values():
            obj = node.blender_object
            if obj is None:
                node.keep_tag = node.keep_tag and not exported_twice(tree, node)
            elif not instanced(tree, node) and (obj not in in_view_layer or obj.name in STATE.replaced):
                node.keep_tag = False

    def gather_node_hook(self, gltf_node, blender_object, export_settings):
        if STATE.exporting:
            add_extras(gltf_node, node_extras(blender_object))

    def gather_image_hook(self, gltf_image, export_image, blender_shader_sockets, export_settings):
        if STATE.exporting:
            add_extras(gltf_image, image_extras(export_image))

    def gather_camera_hook(self, gltf_camera, blender_camera, export_settings):
        if STATE.exporting:
            fit_orthographic(gltf_camera, blender_camera, bpy.context.scene)

    def gather_material_hook(self, gltf_material, blender_material, export_settings):
        if STATE.exporting:
            add_extras(gltf_material, material_extras(blender_material))
            complete_layers(gltf_material, blender_material)
            add_volume(gltf_material, blender_material)
            show_missing_base_colour(gltf_material, blender_material)
            move_normal_map_strength(gltf_material)
            convert_simple_surface(gltf_material, blender_material)


# Objects Blender evaluates to a mesh that its glTF exporter writes itself (a curve, text, a
# surface): with Geometry Nodes export on, Blender 5.0.1's exporter writes that mesh a second time
# as an instance.
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
