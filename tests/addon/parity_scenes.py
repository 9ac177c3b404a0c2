"""Blender scenes for parity with Cycles: each is built in bpy the way an artist would build it,
rendered by Caustic through the add-on (tests/addon/test_parity.py) and by Cycles
(tests/addon/make_parity_references.py, whose references are committed in
tests/references/parity/). Every object gets a pass index, so that Cycles' object-index pass
gives each object's pixels.

Each scene function clears the file, builds the scene at 64x64 and returns the names of the
objects whose mean radiance is compared, with their pass indices, or of floor regions (a caustic,
a penumbra) with a function that gives their pixels from the object-index image and Cycles'
reference image.
"""
import math
import pathlib
import tempfile

import bpy
import mathutils
import numpy as np
from bpy_extras.object_utils import world_to_camera_view

SIZE = 64


def interior(index, value):
    """The pixels of object `value` in an object-index image whose four neighbours are the same
    object (its rim left out)."""
    mask = index == value
    inner = mask.copy()
    inner[1:, :] &= mask[:-1, :]
    inner[:-1, :] &= mask[1:, :]
    inner[:, 1:] &= mask[:, :-1]
    inner[:, :-1] &= mask[:, 1:]
    return inner


def clear():
    for blocks in (bpy.data.objects, bpy.data.meshes, bpy.data.materials, bpy.data.lights, bpy.data.cameras,
                   bpy.data.images, bpy.data.worlds, bpy.data.collections, bpy.data.armatures, bpy.data.actions):
        for block in list(blocks):
            blocks.remove(block)
    scene = bpy.context.scene
    scene.render.film_transparent = False
    scene.render.resolution_x = scene.render.resolution_y = SIZE
    scene.render.resolution_percentage = 100
    scene.render.use_motion_blur = False
    scene.frame_start = scene.frame_end = 1
    scene.frame_set(1)
    scene.view_settings.view_transform = 'Standard'
    return scene


def world(colour, strength=1.0):
    w = bpy.data.worlds.new("World")
    w.use_nodes = True
    background = w.node_tree.nodes["Background"]
    background.inputs["Color"].default_value = (*colour, 1.0)
    background.inputs["Strength"].default_value = strength
    bpy.context.scene.world = w


def principled(name, **inputs):
    """A Principled BSDF material at Blender's defaults but for `inputs` (socket name: value)."""
    m = bpy.data.materials.new(name)
    bsdf = m.node_tree.nodes["Principled BSDF"]
    for socket, value in inputs.items():
        bsdf.inputs[socket.replace("_", " ")].default_value = value
    return m


def add(operator, material=None, index=0, **kwargs):
    operator(**kwargs)
    obj = bpy.context.object
    if material is not None:
        obj.data.materials.append(material)
    obj.pass_index = index
    return obj


def camera(location, target, lens=50.0):
    cam = add(bpy.ops.object.camera_add, location=location)
    cam.rotation_euler = (mathutils.Vector(target) - cam.location).to_track_quat('-Z', 'Y').to_euler()
    cam.data.lens = lens
    bpy.context.scene.camera = cam
    return cam


def area_light(location, target, size, power):
    light = add(bpy.ops.object.light_add, type='AREA', location=location)
    light.rotation_euler = (mathutils.Vector(target) - light.location).to_track_quat('-Z', 'Y').to_euler()
    light.data.size, light.data.energy = size, power
    return light


def studio(floor_material):
    """A floor, a dim grey world and a soft area light above and to the side."""
    add(bpy.ops.mesh.primitive_plane_add, floor_material, index=1, size=20)
    world((0.05, 0.05, 0.05))
    area_light((2.0, -2.0, 4.0), (0.0, 0.0, 0.0), 2.0, 400.0)


def principled_spheres():
    """Two spheres at Blender's Principled defaults (IOR 1.5, Specular IOR Level 0.5): a grey one of
    roughness 0.5 and a black glossy one of roughness 0.2, whose only light is its specular layer,
    on a floor at the defaults too."""
    clear()
    studio(principled("Floor", Base_Color=(0.5, 0.5, 0.5, 1.0)))
    for name, x, colour, roughness, index in (("Grey", -1.1, 0.8, 0.5, 2), ("Black", 1.1, 0.0, 0.2, 3)):
        sphere = add(bpy.ops.mesh.primitive_uv_sphere_add, principled(name, Base_Color=(colour, colour, colour, 1.0),
                                                                     Roughness=roughness),
                     index=index, segments=64, ring_count=32, radius=1.0, location=(x, 0.0, 1.0))
        bpy.ops.object.shade_smooth()
    camera((0.0, -7.0, 3.0), (0.0, 0.0, 0.8))
    return {"Floor": 1, "Grey": 2, "Black": 3}


def image(name, width, height, texel, colorspace='sRGB'):
    """A packed image of `width` x `height` whose texel (x, y from the bottom, as Blender counts)
    is the RGBA `texel(x, y)`."""
    img = bpy.data.images.new(name, width, height, alpha=True)
    img.colorspace_settings.name = colorspace
    img.pixels.foreach_set([c for y in range(height) for x in range(width) for c in texel(x, y)])
    img.pack()
    return img


def texture_node(material, img, location=(-600, 0)):
    node = material.node_tree.nodes.new("ShaderNodeTexImage")
    node.image = img
    node.location = location
    return node


def checker_floor():
    """A floor with a checker texture through a Mapping node (scaled and rotated)."""
    m = principled("Checker floor", Roughness=0.8)
    nodes, links = m.node_tree.nodes, m.node_tree.links
    # Closest: Cycles interpolates 8-bit sRGB texels before decoding them and Caustic after,
    # which differs along the cells' edges (up to 9% of the floor's mean with Linear).
    cell = lambda x, y: (0.9, 0.9, 0.9, 1) if (x // 8 + y // 8) % 2 else (0.05, 0.2, 0.6, 1)
    tex = texture_node(m, image("checker", 64, 64, cell))
    tex.interpolation = 'Closest'
    mapping = nodes.new("ShaderNodeMapping")
    mapping.inputs["Scale"].default_value = (2.0, 2.0, 1.0)
    mapping.inputs["Rotation"].default_value = (0.0, 0.0, math.radians(30))
    coords = nodes.new("ShaderNodeTexCoord")
    links.new(coords.outputs["UV"], mapping.inputs["Vector"])
    links.new(mapping.outputs["Vector"], tex.inputs["Vector"])
    links.new(tex.outputs["Color"], nodes["Principled BSDF"].inputs["Base Color"])
    return m


def metal_with_map():
    """Gold whose metallic and roughness come from one image through Separate Color: metal in
    stripes, roughness rising across."""
    m = principled("Striped metal", Base_Color=(1.0, 0.77, 0.34, 1.0))
    nodes, links = m.node_tree.nodes, m.node_tree.links
    tex = texture_node(m, image("metal-rough", 8, 8, lambda x, y: (0, 0.2 + 0.1 * x, 1.0 if y % 4 < 2 else 0.0, 1),
                                'Non-Color'))
    separate = nodes.new("ShaderNodeSeparateColor")
    links.new(tex.outputs["Color"], separate.inputs["Color"])
    links.new(separate.outputs["Blue"], nodes["Principled BSDF"].inputs["Metallic"])
    links.new(separate.outputs["Green"], nodes["Principled BSDF"].inputs["Roughness"])
    return m


def bumpy(name="Bumpy", strength=1.0, coat=0.0):
    """A grey material whose Normal Map node (of `strength`) tilts the normal along u and v in a
    pattern, under a coat of weight `coat`."""
    m = principled(name, Base_Color=(0.6, 0.6, 0.6, 1.0), Roughness=0.9, Coat_Weight=coat)
    nodes, links = m.node_tree.nodes, m.node_tree.links
    tilt = lambda x, y: (0.5 + (0.3 if x % 32 < 16 else -0.3), 0.5 + (0.3 if y % 32 < 16 else -0.3), 0.8, 1)
    tex = texture_node(m, image("normals", 64, 64, tilt, 'Non-Color'))
    normal_map = nodes.new("ShaderNodeNormalMap")
    normal_map.inputs["Strength"].default_value = strength
    links.new(tex.outputs["Color"], normal_map.inputs["Color"])
    links.new(normal_map.outputs["Normal"], nodes["Principled BSDF"].inputs["Normal"])
    return m


def vertex_coloured(obj):
    """Colours `obj`'s corners by position through a Color Attribute node."""
    mesh = obj.data
    attribute = mesh.color_attributes.new("Col", 'FLOAT_COLOR', 'CORNER')
    for loop in mesh.loops:
        p = mesh.vertices[loop.vertex_index].co
        attribute.data[loop.index].color = (0.5 + 0.5 * p.x, 0.5 + 0.5 * p.y, 0.5 + 0.5 * p.z, 1.0)
    m = principled("Vertex coloured", Roughness=0.6)
    node = m.node_tree.nodes.new("ShaderNodeVertexColor")
    node.layer_name = "Col"
    m.node_tree.links.new(node.outputs["Color"], m.node_tree.nodes["Principled BSDF"].inputs["Base Color"])
    obj.data.materials.append(m)


def colour_attribute(obj, name, colour):
    """A colour attribute `name` of one `colour` (RGBA) on `obj`'s corners."""
    attribute = obj.data.color_attributes.new(name, 'FLOAT_COLOR', 'CORNER')
    for corner in attribute.data:
        corner.color = colour
    return attribute


def reads_colour_attribute(material, name, alpha=False):
    """Links a Color Attribute node reading `name` into the material's Base Color (and Alpha)."""
    nodes, links = material.node_tree.nodes, material.node_tree.links
    node = nodes.new("ShaderNodeVertexColor")
    node.layer_name = name
    links.new(node.outputs["Color"], nodes["Principled BSDF"].inputs["Base Color"])
    if alpha:
        links.new(node.outputs["Alpha"], nodes["Principled BSDF"].inputs["Alpha"])
    return material


def textured_by(name, img):
    """A material whose Base Color is `img` through an Image Texture node."""
    m = principled(name, Roughness=0.7)
    node = texture_node(m, img)
    m.node_tree.links.new(node.outputs["Color"], m.node_tree.nodes["Principled BSDF"].inputs["Base Color"])
    return m


def webp_image(name, grey):
    """An image of one grey (stored value) saved as a WebP file and loaded from it, as a user's
    .webp texture is."""
    img = image(name + "-source", 4, 4, lambda x, y: (grey, grey, grey, 1.0))
    path = pathlib.Path(tempfile.gettempdir()) / f"caustic-parity-{name}.webp"
    img.filepath_raw, img.file_format = str(path), 'WEBP'
    img.save()
    return bpy.data.images.load(str(path))


def seen_through(obj, half):
    """The pixels within `half` pixels of where the camera sees `obj`'s centre (an object that
    alpha makes see-through has no pixels of its own in Cycles' object-index pass)."""
    scene = bpy.context.scene
    bpy.context.view_layer.update()
    x, y, _ = world_to_camera_view(scene, scene.camera, obj.matrix_world.translation)
    row, column = int((1 - y) * SIZE), int(x * SIZE)

    def mask(index, reference):
        block = np.zeros(index.shape, bool)
        block[row - half:row + half + 1, column - half:column + half + 1] = True
        return block
    return mask


def attributes_and_images():
    """What real files combine and glTF carries differently: a cube whose active colour attribute
    (red) its material never reads ('Unused'), one whose material reads a named attribute that is
    not the active one ('Painted'), one whose attribute's alpha (0.4) feeds Alpha ('Faded'); a
    Non-Color image as a base colour (read undecoded), an image whose file is missing (magenta),
    and a WebP image."""
    clear()
    studio(principled("Floor", Base_Color=(0.5, 0.5, 0.5, 1.0)))
    row = []
    unused = add(bpy.ops.mesh.primitive_cube_add, principled("Blue", Base_Color=(0.2, 0.4, 0.8, 1.0)), index=2,
                 size=0.9)
    colour_attribute(unused, "Red", (0.9, 0.05, 0.05, 1.0))
    row.append(unused)
    painted = add(bpy.ops.mesh.primitive_cube_add, reads_colour_attribute(principled("Paint"), "Paint"), index=3,
                  size=0.9)
    colour_attribute(painted, "Paint", (0.9, 0.6, 0.1, 1.0))
    painted.data.color_attributes.active_color = colour_attribute(painted, "Other", (0.1, 0.1, 0.9, 1.0))
    row.append(painted)
    faded = add(bpy.ops.mesh.primitive_cube_add, reads_colour_attribute(principled("Faded"), "Veil", alpha=True),
                index=4, size=0.9)
    colour_attribute(faded, "Veil", (0.1, 0.8, 0.2, 0.4))
    row.append(faded)
    data = image("noncolour", 4, 4, lambda x, y: (0.3, 0.3, 0.3, 1.0), colorspace='Non-Color')
    row.append(add(bpy.ops.mesh.primitive_cube_add, textured_by("Non-Color", data), index=5, size=0.9))
    lost = bpy.data.images.new("lost", 4, 4)
    lost.source, lost.filepath = 'FILE', str(pathlib.Path(tempfile.gettempdir()) / "no-such-folder" / "lost.png")
    row.append(add(bpy.ops.mesh.primitive_cube_add, textured_by("Missing", lost), index=6, size=0.9))
    row.append(add(bpy.ops.mesh.primitive_cube_add, textured_by("WebP", webp_image("webp", 0.6)), index=7, size=0.9))
    for i, obj in enumerate(row):
        obj.location = (-1.5 + 1.5 * (i % 3), 1.0 - 1.6 * (i // 3), 0.45)
    camera((0.0, -7.0, 4.0), (0.0, 0.2, 0.3))
    return {"Floor": 1, "Unused": 2, "Painted": 3, "Faded": seen_through(faded, 3), "Non-Color": 5, "Missing": 6,
            "WebP": 7}


def bind_to_bone(obj, rig):
    """Skins `obj` wholly to the bone "Bone" of armature object `rig`."""
    group = obj.vertex_groups.new(name="Bone")
    group.add(list(range(len(obj.data.vertices))), 1.0, 'REPLACE')
    obj.modifiers.new("Armature", 'ARMATURE').object = rig


def geometry_nodes(host, points, material, realize=False):
    """A Geometry Nodes modifier on `host`: 0.6 m cubes instanced on its vertices (left as
    instances, or realized), or its vertices as a point cloud of radius 0.22, of `material` (a Set
    Material node)."""
    tree = bpy.data.node_groups.new("Points" if points else "Scatter", 'GeometryNodeTree')
    tree.interface.new_socket("Geometry", in_out='INPUT', socket_type='NodeSocketGeometry')
    tree.interface.new_socket("Geometry", in_out='OUTPUT', socket_type='NodeSocketGeometry')
    nodes, links = tree.nodes, tree.links
    given, out = nodes.new('NodeGroupInput'), nodes.new('NodeGroupOutput')
    if points:
        made = nodes.new('GeometryNodeMeshToPoints')
        made.inputs["Radius"].default_value = 0.22
        links.new(given.outputs[0], made.inputs["Mesh"])
        painted = nodes.new('GeometryNodeSetMaterial')
        painted.inputs["Material"].default_value = material
        links.new(made.outputs["Points"], painted.inputs["Geometry"])
        links.new(painted.outputs["Geometry"], out.inputs[0])
    else:
        made = nodes.new('GeometryNodeInstanceOnPoints')
        cube = nodes.new('GeometryNodeMeshCube')
        cube.inputs["Size"].default_value = (0.6, 0.6, 0.6)
        painted = nodes.new('GeometryNodeSetMaterial')
        painted.inputs["Material"].default_value = material
        links.new(cube.outputs["Mesh"], painted.inputs["Geometry"])
        links.new(given.outputs[0], made.inputs["Points"])
        links.new(painted.outputs["Geometry"], made.inputs["Instance"])
        if realize:
            realized = nodes.new('GeometryNodeRealizeInstances')
            links.new(made.outputs["Instances"], realized.inputs["Geometry"])
            links.new(realized.outputs["Geometry"], out.inputs[0])
        else:
            links.new(made.outputs["Instances"], out.inputs[0])
    host.modifiers.new("Geometry Nodes", 'NODES').node_group = tree


def instances_and_points():
    """What Blender's exporter leaves out unless told, or drops: an orange ball in a collection
    outside the scene, instanced by an empty and (nested) by an empty instancing a collection that
    instances it; red cubes a Geometry Nodes modifier instances on a plane's corners; and a point
    cloud Geometry Nodes makes of a plane's vertices (blue spheres of radius 0.22)."""
    clear()
    studio(principled("Floor", Base_Color=(0.5, 0.5, 0.5, 1.0)))
    props = bpy.data.collections.new("Props")
    bpy.ops.mesh.primitive_uv_sphere_add(segments=32, ring_count=16, radius=0.4)
    ball = bpy.context.object
    bpy.ops.object.shade_smooth()
    bpy.context.scene.collection.objects.unlink(ball)
    props.objects.link(ball)
    ball.data.materials.append(principled("Orange", Base_Color=(0.9, 0.4, 0.05, 1.0)))
    ball.pass_index = 2
    outer = bpy.data.collections.new("Nested props")
    inner = bpy.data.objects.new("Inner instance", None)
    outer.objects.link(inner)
    inner.instance_type, inner.instance_collection = 'COLLECTION', props
    for name, collection, location in (("Props instance", props, (-1.8, 0.6, 0.4)),
                                       ("Nested instance", outer, (-1.8, -0.6, 0.4))):
        holder = bpy.data.objects.new(name, None)
        bpy.context.scene.collection.objects.link(holder)
        holder.instance_type, holder.instance_collection, holder.location = 'COLLECTION', collection, location
    scattered = add(bpy.ops.mesh.primitive_plane_add, index=3, size=1.5, location=(0.1, 0.4, 0.3))
    geometry_nodes(scattered, False, principled("Red", Base_Color=(0.8, 0.05, 0.05, 1.0)))
    dotted = add(bpy.ops.mesh.primitive_plane_add, index=4, size=1.3, location=(2.0, 0.3, 0.22))
    geometry_nodes(dotted, True, principled("Blue", Base_Color=(0.05, 0.2, 0.8, 1.0)))
    camera((0.0, -6.0, 3.5), (0.1, 0.2, 0.2))
    return {"Floor": 1, "Instanced": 2, "Scattered": 3, "Points": 4}


def textured():
    """A checker floor through a Mapping node, a gold sphere with a metallic-roughness map and a
    vertex-coloured cube."""
    clear()
    studio(checker_floor())
    add(bpy.ops.mesh.primitive_uv_sphere_add, metal_with_map(), index=2, segments=64, ring_count=32, radius=0.9,
        location=(-1.3, 0.3, 0.9))
    bpy.ops.object.shade_smooth()
    coloured = add(bpy.ops.mesh.primitive_cube_add, index=4, size=1.4, location=(0.9, 0.8, 0.7))
    vertex_coloured(coloured)
    camera((0.0, -7.0, 3.5), (0.0, 0.3, 0.6))
    return {"Floor": 1, "Gold": 2, "Coloured": 4}


def normal_mapped():
    """A normal-mapped cube (a Normal Map node) on the checker floor."""
    clear()
    studio(checker_floor())
    cube = add(bpy.ops.mesh.primitive_cube_add, bumpy(), index=3, size=1.8, location=(0.0, 0.0, 0.9))
    cube.rotation_euler = (0.0, 0.0, math.radians(30))
    camera((0.0, -7.0, 3.5), (0.0, 0.0, 0.8))
    return {"Floor": 1, "Bumpy": 3}


def normal_map_strengths():
    """Five normal-mapped cubes: at strength 1 and 2 under Blender's default coat and without one,
    and at strength 0.5 without a coat (where Cycles' strength and glTF's scale differ)."""
    clear()
    studio(principled("Floor", Base_Color=(0.5, 0.5, 0.5, 1.0)))
    cubes = ((1.0, 1.0), (2.0, 1.0), (0.5, 0.0), (1.0, 0.0), (2.0, 0.0))
    for i, (strength, coat) in enumerate(cubes):
        cube = add(bpy.ops.mesh.primitive_cube_add, bumpy(f"Strength {strength:g} coat {coat:g}", strength, coat),
                   index=2 + i, size=0.9, location=(-2.4 + 1.2 * i, 0.3, 0.45))
        cube.rotation_euler = (0.0, 0.0, math.radians(30))
    camera((0.0, -6.0, 3.0), (0.0, 0.3, 0.4), lens=35.0)
    scene = bpy.context.scene
    scene.render.resolution_x, scene.render.resolution_y = 128, 64
    return {"Floor": 1, "Strength 1 coated": 2, "Strength 2 coated": 3, "Strength 0.5": 4, "Strength 1": 5,
            "Strength 2": 6}


def surface_of(name, kind, **inputs):
    """A material whose surface is a `kind` shader node (not a Principled BSDF) of `inputs`."""
    m = bpy.data.materials.new(name)
    nodes = m.node_tree.nodes
    nodes.remove(nodes["Principled BSDF"])
    node = nodes.new(kind)
    for socket, value in inputs.items():
        node.inputs[socket].default_value = value
    m.node_tree.links.new(node.outputs[0], nodes["Material Output"].inputs["Surface"])
    return m


def simple_surfaces():
    """A Diffuse BSDF cube and a Glossy BSDF ball (roughness 0.3, gold-tinted): Blender's exporter
    writes neither (glTF's default, a rough white metal); the add-on writes what Cycles renders."""
    clear()
    studio(principled("Floor", Base_Color=(0.5, 0.5, 0.5, 1.0)))
    add(bpy.ops.mesh.primitive_cube_add, surface_of("Diffuse", "ShaderNodeBsdfDiffuse", Color=(0.2, 0.45, 0.8, 1.0)),
        index=2, size=1.4, location=(-1.1, 0.3, 0.7))
    add(bpy.ops.mesh.primitive_uv_sphere_add, surface_of("Glossy", "ShaderNodeBsdfGlossy", Color=(0.9, 0.7, 0.3, 1.0),
                                                         Roughness=0.3),
        index=3, segments=64, ring_count=32, radius=0.8, location=(1.1, 0.3, 0.8))
    bpy.ops.object.shade_smooth()
    camera((0.0, -7.0, 3.5), (0.0, 0.3, 0.6))
    return {"Floor": 1, "Diffuse": 2, "Glossy": 3}


def procedural_material(name, ramp=False):
    """A Principled material whose Base Color is a Checker Texture (red and white), or a Noise
    Texture through a ColorRamp (blue to yellow): nodes glTF cannot hold."""
    m = principled(name, Roughness=0.6)
    nodes, links = m.node_tree.nodes, m.node_tree.links
    if ramp:
        noise, colours = nodes.new("ShaderNodeTexNoise"), nodes.new("ShaderNodeValToRGB")
        noise.inputs["Scale"].default_value = 3.0
        colours.color_ramp.elements[0].color = (0.05, 0.1, 0.8, 1.0)
        colours.color_ramp.elements[1].color = (0.9, 0.8, 0.1, 1.0)
        links.new(noise.outputs["Fac"], colours.inputs["Fac"])
        source = colours.outputs["Color"]
    else:
        checker = nodes.new("ShaderNodeTexChecker")
        checker.inputs["Color1"].default_value, checker.inputs["Color2"].default_value = (0.8, 0.1, 0.1, 1), (0.9, 0.9, 0.9, 1)
        checker.inputs["Scale"].default_value = 3.0
        source = checker.outputs["Color"]
    links.new(source, nodes["Principled BSDF"].inputs["Base Color"])
    return m


def baked_textures():
    """A cube with a Checker Texture and a ball with a Noise Texture through a ColorRamp on their
    Base Color, which the add-on has Blender bake into images."""
    clear()
    studio(principled("Floor", Base_Color=(0.5, 0.5, 0.5, 1.0)))
    add(bpy.ops.mesh.primitive_cube_add, procedural_material("Checker"), index=2, size=1.4, location=(-1.1, 0.3, 0.7))
    add(bpy.ops.mesh.primitive_uv_sphere_add, procedural_material("Noise ramp", ramp=True), index=3, segments=64,
        ring_count=32, radius=0.8, location=(1.1, 0.3, 0.8))
    bpy.ops.object.shade_smooth()
    camera((0.0, -7.0, 3.5), (0.0, 0.3, 0.6))
    return {"Floor": 1, "Checker": 2, "Noise ramp": 3}


def baked_bump():
    """A ball whose Normal comes from a Noise Texture through a Bump node (Distance 0.5), which the
    add-on has Blender bake into a normal map: 1.02 of Cycles, 1.18 without the bake (a smooth
    ball). A baked map renders a strong bump brighter than Cycles' Bump node does, in Cycles too:
    at Distance 1 Cycles with its own baked map reads 1.085 of Cycles with the Bump node, and
    Caustic (1.015 of Cycles with the same map) 1.10."""
    clear()
    studio(principled("Floor", Base_Color=(0.5, 0.5, 0.5, 1.0)))
    m = principled("Bumped", Base_Color=(0.7, 0.5, 0.3, 1.0), Roughness=0.4)
    nodes, links = m.node_tree.nodes, m.node_tree.links
    noise, bump = nodes.new("ShaderNodeTexNoise"), nodes.new("ShaderNodeBump")
    noise.inputs["Scale"].default_value = 6.0
    noise.inputs["Detail"].default_value = 1.0
    bump.inputs["Strength"].default_value = 1.0
    bump.inputs["Distance"].default_value = 0.5
    links.new(noise.outputs["Fac"], bump.inputs["Height"])
    links.new(bump.outputs["Normal"], nodes["Principled BSDF"].inputs["Normal"])
    add(bpy.ops.mesh.primitive_uv_sphere_add, m, index=2, segments=64, ring_count=32, radius=1.0,
        location=(0.0, 0.3, 1.0))
    bpy.ops.object.shade_smooth()
    camera((0.0, -4.0, 2.2), (0.0, 0.3, 0.9))
    return {"Floor": 1, "Bumped": 2}


def coated():
    """Two clear-coated spheres on the default floor: a red one under Blender's default coat
    (weight 1, roughness 0.03: a near mirror over a rough base) and a blue one under half a rough
    coat (weight 0.5, roughness 0.4)."""
    clear()
    studio(principled("Floor", Base_Color=(0.5, 0.5, 0.5, 1.0)))
    for name, x, colour, weight, roughness, index in (("Red coated", -1.1, (0.6, 0.05, 0.05, 1.0), 1.0, 0.03, 2),
                                                      ("Blue coated", 1.1, (0.05, 0.1, 0.5, 1.0), 0.5, 0.4, 3)):
        material = principled(name, Base_Color=colour, Roughness=0.5, Coat_Weight=weight, Coat_Roughness=roughness)
        add(bpy.ops.mesh.primitive_uv_sphere_add, material, index=index, segments=64, ring_count=32, radius=1.0,
            location=(x, 0.0, 1.0))
        bpy.ops.object.shade_smooth()
    camera((0.0, -7.0, 3.0), (0.0, 0.0, 0.8))
    return {"Floor": 1, "Red coated": 2, "Blue coated": 3}


def sheen():
    """A velvet cushion (a flattened sphere, dark red, Sheen Weight 1, roughness 0.5) beside a grey
    ball with a faint pale-blue sheen (weight 0.5, roughness 0.3)."""
    clear()
    studio(principled("Floor", Base_Color=(0.5, 0.5, 0.5, 1.0)))
    velvet = principled("Velvet", Base_Color=(0.3, 0.03, 0.05, 1.0), Roughness=0.8, Sheen_Weight=1.0,
                        Sheen_Roughness=0.5)
    cushion = add(bpy.ops.mesh.primitive_uv_sphere_add, velvet, index=2, segments=64, ring_count=32, radius=1.0,
                  location=(-1.1, 0.0, 0.45))
    cushion.scale = (1.0, 1.0, 0.45)
    bpy.ops.object.shade_smooth()
    dusty = principled("Dusty", Base_Color=(0.4, 0.4, 0.4, 1.0), Roughness=0.6, Sheen_Weight=0.5,
                       Sheen_Roughness=0.3, Sheen_Tint=(0.7, 0.8, 1.0, 1.0))
    add(bpy.ops.mesh.primitive_uv_sphere_add, dusty, index=3, segments=64, ring_count=32, radius=0.8,
        location=(1.1, 0.0, 0.8))
    bpy.ops.object.shade_smooth()
    camera((0.0, -7.0, 3.0), (0.0, 0.0, 0.6))
    return {"Floor": 1, "Velvet": 2, "Dusty": 3}


def leaf_material():
    """A green leaf: an elliptic image alpha rounded to 0 or 1 by a Math node (what Blender's glTF
    exporter writes as alphaMode MASK)."""
    m = principled("Leaf", Roughness=0.7)
    nodes, links = m.node_tree.nodes, m.node_tree.links

    def texel(x, y):
        u, v = (x + 0.5) / 32 - 0.5, (y + 0.5) / 32 - 0.5
        return (0.1, 0.45, 0.08, 1.0 if (u / 0.45) ** 2 + (v / 0.22) ** 2 < 1 else 0.0)

    tex = texture_node(m, image("leaf", 32, 32, texel))
    tex.interpolation = 'Closest'
    cut = nodes.new("ShaderNodeMath")
    cut.operation = 'ROUND'
    links.new(tex.outputs["Color"], nodes["Principled BSDF"].inputs["Base Color"])
    links.new(tex.outputs["Alpha"], cut.inputs[0])
    links.new(cut.outputs[0], nodes["Principled BSDF"].inputs["Alpha"])
    return m


def leaf():
    """An alpha-clipped leaf held over the floor under a small area light: the leaf's shape, and
    its shadow's, on the floor."""
    clear()
    add(bpy.ops.mesh.primitive_plane_add, principled("Floor", Base_Color=(0.5, 0.5, 0.5, 1.0)), index=1, size=20)
    world((0.05, 0.05, 0.05))
    area_light((0.5, -1.0, 5.0), (0.0, 0.0, 0.0), 0.3, 300.0)
    blade = add(bpy.ops.mesh.primitive_plane_add, leaf_material(), index=2, size=2.4, location=(0.0, 0.0, 1.0))
    blade.rotation_euler = (math.radians(20), 0.0, math.radians(25))
    camera((0.0, -6.0, 4.0), (0.0, 0.0, 0.4))
    return {"Floor": 1, "Leaf": 2}


def floor_disc(centre, radius, floor_index=1):
    """The floor's pixels (by the object-index image, rim left out) that see the floor within
    `radius` of `centre` (x, y on the floor), for the current camera."""
    scene = bpy.context.scene
    bpy.context.view_layer.update()
    pixels = set()
    for r in np.linspace(0.0, radius, 24):
        for a in np.linspace(0.0, 2 * math.pi, 96, endpoint=False):
            p = mathutils.Vector((centre[0] + r * math.cos(a), centre[1] + r * math.sin(a), 0.0))
            x, y, _ = world_to_camera_view(scene, scene.camera, p)
            if 0 <= x < 1 and 0 <= y < 1:
                pixels.add((int((1 - y) * SIZE), int(x * SIZE)))

    def mask(index, reference):
        disc = np.zeros(index.shape, bool)
        for row, column in pixels:
            disc[row, column] = True
        return disc & interior(index, floor_index)
    return mask


def glass():
    """Frosted glass and coloured glass as artists make them: a sphere of Principled glass at
    roughness 0.2 (frosted) and a block of clear glass with a Volume Absorption node (blue-green,
    density 1.5), each under its own small area light, casting a soft caustic and a coloured light
    onto the floor."""
    clear()
    add(bpy.ops.mesh.primitive_plane_add, principled("Floor", Base_Color=(0.5, 0.5, 0.5, 1.0)), index=1, size=20)
    world((0.02, 0.02, 0.02))
    frosted = principled("Frosted", Base_Color=(1.0, 1.0, 1.0, 1.0), Roughness=0.2, Transmission_Weight=1.0)
    add(bpy.ops.mesh.primitive_uv_sphere_add, frosted, index=2, segments=64, ring_count=32, radius=0.6,
        location=(-1.0, 0.0, 0.9))
    bpy.ops.object.shade_smooth()
    tinted = principled("Tinted", Base_Color=(1.0, 1.0, 1.0, 1.0), Roughness=0.0, Transmission_Weight=1.0)
    nodes = tinted.node_tree.nodes
    absorption = nodes.new("ShaderNodeVolumeAbsorption")
    absorption.inputs["Color"].default_value = (0.25, 0.6, 0.85, 1.0)
    absorption.inputs["Density"].default_value = 1.5
    tinted.node_tree.links.new(absorption.outputs["Volume"], nodes["Material Output"].inputs["Volume"])
    add(bpy.ops.mesh.primitive_cube_add, tinted, index=3, size=0.9, location=(1.0, 0.0, 0.9))
    # Behind the objects, so that what they send onto the floor falls in front of them, in view.
    for x in (-1.0, 1.0):
        area_light((x, 1.5, 4.0), (x, 0.0, 0.0), 0.6, 150.0)
    camera((0.0, -4.5, 2.5), (0.0, 0.0, 0.5))
    return {"Frosted": 2, "Frosted caustic": floor_disc((-1.0, -0.45), 0.25), "Tinted": 3,
            "Tinted light": floor_disc((1.0, -0.3), 0.3)}


def matte_floor_and_ball(radius, location, segments=64):
    """A matte white floor and a matte grey ball (no specular layer) under a nearly black world,
    for scenes about a light."""
    add(bpy.ops.mesh.primitive_plane_add, principled("Floor", Base_Color=(0.8, 0.8, 0.8, 1.0), Roughness=1.0,
                                                     Specular_IOR_Level=0.0), index=1, size=20)
    add(bpy.ops.mesh.primitive_uv_sphere_add, principled("Grey", Base_Color=(0.5, 0.5, 0.5, 1.0), Roughness=1.0,
                                                         Specular_IOR_Level=0.0),
        index=2, segments=segments, ring_count=segments // 2, radius=radius, location=location)
    bpy.ops.object.shade_smooth()
    world((0.01, 0.01, 0.01))


def warm_light():
    """A grey sphere on the floor under a point light of colour temperature 3000 K (Blender's
    Temperature, which Blender's glTF exporter cannot write) and a cool blue-tinted fill light
    of 12000 K."""
    clear()
    matte_floor_and_ball(0.8, (0.0, 0.0, 0.8))
    for location, kelvin, power in (((1.5, -1.5, 3.0), 3000.0, 800.0), ((-2.5, -1.0, 2.0), 12000.0, 200.0)):
        light = add(bpy.ops.object.light_add, type='POINT', location=location)
        light.data.energy, light.data.shadow_soft_size = power, 0.0
        light.data.use_temperature, light.data.temperature = True, kelvin
    camera((0.0, -6.0, 3.5), (0.0, 0.0, 0.6))
    return {"Floor": 1, "Grey": 2}


def penumbra(index, reference, floor_index=1):
    """The floor's pixels (rim left out) that Cycles shows between 20% and 80% of the lit floor's
    luminance (its brightest tenth): the penumbra as Cycles renders it."""
    floor = interior(index, floor_index)
    luminance = reference @ np.array([0.2126, 0.7152, 0.0722])
    lit = np.percentile(luminance[floor], 90)
    return floor & (luminance > 0.2 * lit) & (luminance < 0.8 * lit)


def soft_light():
    """A cube on the floor under a point light of radius 0.4 (a sphere light, without Blender's
    Soft Falloff): a wide penumbra."""
    clear()
    add(bpy.ops.mesh.primitive_plane_add, principled("Floor", Base_Color=(0.8, 0.8, 0.8, 1.0), Roughness=1.0,
                                                     Specular_IOR_Level=0.0), index=1, size=20)
    add(bpy.ops.mesh.primitive_cube_add, principled("Block", Base_Color=(0.6, 0.3, 0.2, 1.0), Roughness=1.0,
                                                    Specular_IOR_Level=0.0), index=2, size=1.0, location=(0, 0, 0.5))
    world((0.01, 0.01, 0.01))
    light = add(bpy.ops.object.light_add, type='POINT', location=(1.2, -0.4, 2.0))
    light.data.energy, light.data.shadow_soft_size = 500.0, 0.4
    # A sphere of light: Blender's default Soft Falloff dims what lies near it (`I / (d^2 + r^2)`,
    # a disc facing each point, as lights were before Blender 4.0), which Caustic does not do.
    light.data.use_soft_falloff = False
    light.visible_camera = True  # Caustic shows lights to the camera; Cycles only when told
    camera((0.0, -5.5, 4.5), (0.0, 0.3, 0.2))
    return {"Floor": 1, "Block": 2, "Penumbra": penumbra}


def sky_image(width=256, height=128, sun=(0.0833, 15.0)):
    """An equirectangular sky as a float image saved as Radiance HDR and loaded from disk, as an
    artist's HDRI is: blue overhead, pale at the horizon, brown ground, and a sun of 2 x 2 texels
    at image column `sun[0]` (0 to 1) and elevation `sun[1]` degrees."""
    rows = (np.arange(height) + 0.5) / height  # 0 at the bottom
    elevation = (rows - 0.5) * 180.0
    t = np.clip(elevation / 60.0, 0.0, 1.0)[:, None]
    sky = (1 - t) * np.array([0.7, 0.75, 0.8]) + t * np.array([0.15, 0.3, 0.8])
    rgb = np.where((elevation < 0)[:, None], np.array([0.15, 0.1, 0.07]), sky)
    pixels = np.repeat(rgb[:, None, :], width, axis=1)
    row = int((sun[1] + 90.0) / 180.0 * height)
    column = int(sun[0] * width)
    pixels[row:row + 2, column:column + 2] = 20000.0
    rgba = np.concatenate([pixels, np.ones((height, width, 1))], axis=2).astype(np.float32)
    img = bpy.data.images.new("sky", width, height, alpha=False, float_buffer=True)
    img.pixels.foreach_set(rgba.ravel())
    img.filepath_raw = str(tempfile.mkdtemp(prefix="caustic-sky-")) + "/sky.hdr"
    img.file_format = 'HDR'
    img.save()
    return bpy.data.images.load(img.filepath_raw)


def hdri():
    """A grey ball and a mirror ball on a floor lit only by an HDRI (an Environment Texture
    through a Mapping node turned 60 degrees about Z, Background strength 0.8), whose sun shows
    in the sky behind the balls and casts their shadows toward the camera."""
    clear()
    w = bpy.data.worlds.new("World")
    w.use_nodes = True
    nodes, links = w.node_tree.nodes, w.node_tree.links
    environment = nodes.new("ShaderNodeTexEnvironment")
    environment.image = sky_image()
    mapping = nodes.new("ShaderNodeMapping")
    mapping.inputs["Rotation"].default_value = (0.0, 0.0, math.radians(60))
    coords = nodes.new("ShaderNodeTexCoord")
    links.new(coords.outputs["Generated"], mapping.inputs["Vector"])
    links.new(mapping.outputs["Vector"], environment.inputs["Vector"])
    links.new(environment.outputs["Color"], nodes["Background"].inputs["Color"])
    nodes["Background"].inputs["Strength"].default_value = 0.8
    bpy.context.scene.world = w
    add(bpy.ops.mesh.primitive_plane_add, principled("Floor", Base_Color=(0.5, 0.5, 0.5, 1.0)), index=1, size=20)
    add(bpy.ops.mesh.primitive_uv_sphere_add, principled("Grey", Base_Color=(0.6, 0.6, 0.6, 1.0), Roughness=0.5),
        index=2, segments=64, ring_count=32, radius=0.8, location=(-1.0, 0.0, 0.8))
    bpy.ops.object.shade_smooth()
    add(bpy.ops.mesh.primitive_uv_sphere_add, principled("Mirror", Base_Color=(0.9, 0.9, 0.9, 1.0), Metallic=1.0,
                                                         Roughness=0.0),
        index=3, segments=64, ring_count=32, radius=0.6, location=(1.0, -0.5, 0.6))
    bpy.ops.object.shade_smooth()
    camera((0.0, -7.0, 1.5), (0.0, 0.0, 2.0))
    return {"Floor": 1, "Grey": 2, "Mirror": 3, "Sky": 0, "Shadow": floor_disc((-1.0, -1.6), 0.3)}


def silhouettes(resolution):
    """Black objects (a cube, a sphere, a cone at different depths) under a uniform white world:
    the camera's framing shows as their silhouettes."""
    clear()
    scene = bpy.context.scene
    scene.render.resolution_x, scene.render.resolution_y = resolution
    world((1.0, 1.0, 1.0))
    black = principled("Black", Base_Color=(0.0, 0.0, 0.0, 1.0), Specular_IOR_Level=0.0, Roughness=1.0)
    add(bpy.ops.mesh.primitive_cube_add, black, index=1, size=1.0, location=(-1.5, 1.0, 0.5))
    add(bpy.ops.mesh.primitive_uv_sphere_add, black, index=2, segments=32, ring_count=16, radius=0.7,
        location=(0.5, -0.5, 0.7))
    add(bpy.ops.mesh.primitive_cone_add, black, index=3, radius1=0.5, depth=1.5, location=(1.8, 2.5, 0.75))
    return scene


def ortho_camera():
    """Orthographic, 64 x 48, the scale fitted to the height (Sensor Fit Vertical, which Blender's
    glTF exporter ignores)."""
    silhouettes((64, 48))
    cam = camera((6.0, -8.0, 6.0), (0.0, 0.5, 0.5))
    cam.data.type, cam.data.ortho_scale, cam.data.sensor_fit = 'ORTHO', 5.0, 'VERTICAL'
    return {"World": 0}


def shifted_camera():
    """Perspective, portrait 48 x 64, 35 mm, shifted right and down (glTF has no shift)."""
    silhouettes((48, 64))
    cam = camera((0.0, -9.0, 3.0), (0.0, 0.5, 0.8), lens=35.0)
    cam.data.shift_x, cam.data.shift_y = 0.15, -0.1
    return {"World": 0}


def panorama_camera():
    """Blender's equirectangular panoramic camera, 64 x 32, all around, among the objects."""
    silhouettes((64, 32))
    cam = camera((0.0, 0.8, 1.0), (1.0, 0.8, 1.0))
    cam.data.type, cam.data.panorama_type = 'PANO', 'EQUIRECTANGULAR'
    return {"World": 0}


def collection(name, *objects, parent=None):
    """A new collection (under the scene's, or `parent`) holding `objects` (moved out of the
    scene's collection)."""
    new = bpy.data.collections.new(name)
    (parent or bpy.context.scene.collection).children.link(new)
    for obj in objects:
        for old in list(obj.users_collection):
            old.objects.unlink(obj)
        new.objects.link(obj)
    return new


def layer_collection(name):
    """The view layer's entry of the collection `name`."""
    def find(layer):
        if layer.collection.name == name:
            return layer
        return next((found for child in layer.children if (found := find(child)) is not None), None)
    return find(bpy.context.view_layer.layer_collection)


def film_and_holdouts():
    """A transparent film over a floor that ends in view, a grey ball, a ball of Blender's Holdout
    shader, a cube in a collection set to Holdout in the view layer, and a red cube in a collection
    excluded from the view layer (which must not render), under a soft area light."""
    clear()
    bpy.context.scene.render.film_transparent = True
    world((0.3, 0.35, 0.4))
    add(bpy.ops.mesh.primitive_plane_add, principled("Floor", Base_Color=(0.5, 0.5, 0.5, 1.0)), index=1, size=6)
    area_light((2.0, -2.0, 4.0), (0.0, 0.0, 0.0), 2.0, 300.0)
    add(bpy.ops.mesh.primitive_uv_sphere_add, principled("Grey", Base_Color=(0.6, 0.6, 0.6, 1.0)), index=2,
        segments=48, ring_count=24, radius=0.6, location=(-1.3, 0.0, 0.6))
    bpy.ops.object.shade_smooth()
    holdout = bpy.data.materials.new("Holdout")
    nodes = holdout.node_tree.nodes
    nodes.remove(nodes["Principled BSDF"])
    holdout.node_tree.links.new(nodes.new("ShaderNodeHoldout").outputs[0], nodes["Material Output"].inputs["Surface"])
    add(bpy.ops.mesh.primitive_uv_sphere_add, holdout, index=3, segments=48, ring_count=24, radius=0.6,
        location=(0.0, 0.5, 0.6))
    bpy.ops.object.shade_smooth()
    masked = add(bpy.ops.mesh.primitive_cube_add, principled("Masked", Base_Color=(0.2, 0.6, 0.2, 1.0)), index=4,
                 size=1.0, location=(1.3, 0.0, 0.5))
    collection("Mask", masked)
    layer_collection("Mask").holdout = True
    excluded = add(bpy.ops.mesh.primitive_cube_add, principled("Excluded", Base_Color=(0.9, 0.1, 0.1, 1.0)),
                   index=5, size=0.8, location=(0.0, -1.5, 0.4))
    collection("Excluded", excluded)
    layer_collection("Excluded").exclude = True
    camera((0.0, -7.0, 2.5), (0.0, 0.0, 0.6))
    return {"Floor": 1, "Grey": 2}


def spot_light(radius=0.0):
    """A spot light of 70 degrees with Blender's Spot Blend 0.6 above a floor and a ball: the
    pool of light and its soft edge (and with a `radius`, the ball's soft shadow)."""
    clear()
    matte_floor_and_ball(0.5, (0.8, 0.3, 0.5), segments=48)
    spot = add(bpy.ops.object.light_add, type='SPOT', location=(0.0, 0.0, 3.0))
    spot.data.energy, spot.data.shadow_soft_size = 1000.0, radius
    spot.data.spot_size, spot.data.spot_blend = math.radians(70), 0.6
    spot.data.use_soft_falloff = False  # as in soft_light: Caustic's sphere has no Soft Falloff
    camera((0.0, -6.0, 5.0), (0.0, 0.0, 0.0))
    regions = {"Floor": 1, "Grey": 2, "Edge": floor_ring((0.0, 0.0), 1.2, 2.1)}
    return {**regions, "Penumbra": penumbra} if radius else regions


def soft_spot():
    """The spot light with Blender's default radius, 0.25: the ball's shadow is soft."""
    return spot_light(radius=0.25)


def seen_sphere(centre, radius):
    """The pixels within 0.6 of the projected radius of a sphere of `radius` at `centre`, for the
    current camera (the sphere's edge left out)."""
    scene = bpy.context.scene
    bpy.context.view_layer.update()
    centre = mathutils.Vector(centre)
    right = scene.camera.matrix_world.to_3x3() @ mathutils.Vector((1.0, 0.0, 0.0))
    (x, y, _), (x1, y1, _) = (world_to_camera_view(scene, scene.camera, p) for p in (centre, centre + radius * right))
    reach = 0.6 * math.hypot(x1 - x, y1 - y) * SIZE
    rows, columns = np.mgrid[0:SIZE, 0:SIZE] + 0.5
    inside = np.hypot(rows - (1 - y) * SIZE, columns - x * SIZE) < reach
    return lambda index, reference: inside


def lights_seen():
    """A mirror ball on a matte floor reflecting a point light and a spot light of radius 0.4
    (Blender's spheres) and an area light. The camera sees the point light (its Ray Visibility >
    Camera on) but not the spot light (off, Blender's default): where the spot light stands, the
    floor shows."""
    clear()
    matte_floor = principled("Floor", Base_Color=(0.5, 0.5, 0.5, 1.0), Roughness=1.0, Specular_IOR_Level=0.0)
    add(bpy.ops.mesh.primitive_plane_add, matte_floor, index=1, size=20)
    add(bpy.ops.mesh.primitive_uv_sphere_add, principled("Mirror", Metallic=1.0, Roughness=0.0), index=2,
        segments=96, ring_count=48, radius=1.0, location=(0.0, 0.5, 1.0))
    bpy.ops.object.shade_smooth()
    world((0.02, 0.02, 0.02))
    point = add(bpy.ops.object.light_add, type='POINT', location=(1.6, -1.0, 0.8))
    spot = add(bpy.ops.object.light_add, type='SPOT', location=(-1.6, -1.0, 0.8))
    spot.rotation_euler = (mathutils.Vector((0.0, 0.5, 0.5)) - spot.location).to_track_quat('-Z', 'Y').to_euler()
    for light in (point, spot):
        light.data.energy, light.data.shadow_soft_size, light.data.use_soft_falloff = 200.0, 0.4, False
    spot.data.spot_size, spot.data.spot_blend = math.radians(90), 0.3
    point.visible_camera, spot.visible_camera = True, False
    area_light((0.0, -2.0, 3.0), (0.0, 0.5, 1.0), 0.8, 100.0)
    camera((0.0, -6.0, 1.2), (0.0, 0.0, 0.9))
    return {"Floor": 1, "Mirror": 2, "Point light": seen_sphere(point.location, 0.4),
            "Behind the spot light": seen_sphere(spot.location, 0.4)}


def spread_light():
    """A square area light 1 m wide, 2 m above the floor, with Blender's Spread narrowed to 40
    degrees (a soft box's grid): a pool of light with a soft edge around a grey ball, where a
    light spreading over 180 degrees lights the whole floor."""
    clear()
    matte_floor_and_ball(0.4, (0.5, 0.2, 0.4), segments=48)
    light = area_light((0.0, 0.0, 2.0), (0.0, 0.0, 0.0), 1.0, 300.0)
    light.data.spread = math.radians(40)
    camera((0.0, -6.0, 5.0), (0.0, 0.0, 0.0))
    return {"Floor": 1, "Grey": 2, "Pool": floor_disc((-0.5, -0.3), 0.5),
            "Edge": floor_ring((0.0, 0.0), 1.0, 1.4), "Beyond": floor_ring((0.0, 0.0), 1.8, 2.5)}


def soft_falloff():
    """Blender's default point light (Soft Falloff on) with a radius of 0.5, 1 m above the floor
    beside a ball: close to it, Cycles' disc facing each point lights the floor a fifth less than
    a sphere would."""
    clear()
    matte_floor_and_ball(0.4, (0.9, 0.0, 0.4), segments=48)
    light = add(bpy.ops.object.light_add, type='POINT', location=(0.0, 0.0, 1.0))
    light.data.energy, light.data.shadow_soft_size = 100.0, 0.5
    assert light.data.use_soft_falloff
    camera((0.0, -6.0, 4.0), (0.0, 0.0, 0.3))
    return {"Floor": 1, "Grey": 2, "Under": floor_disc((0.0, 0.0), 0.4), "Around": floor_ring((0.0, 0.0), 1.5, 2.5)}


def floor_ring(centre, inner, outer, floor_index=1):
    """The floor's pixels (rim left out) between `inner` and `outer` of `centre` (x, y on the
    floor), for the current camera."""
    outside, within = floor_disc(centre, inner, floor_index), floor_disc(centre, outer, floor_index)
    return lambda index, reference: within(index, reference) & ~outside(index, reference)


def sky():
    """A grey ball and a white block on a floor under Blender's Sky Texture (Nishita, the sun 25
    degrees up): a world Caustic reads as the image Blender bakes of it. (No glossy metal: its
    highlight of the sun speckles for thousands of passes, issue 22's matter, not the world's.)"""
    clear()
    w = bpy.data.worlds.new("Sky")
    nodes, links = w.node_tree.nodes, w.node_tree.links
    texture = nodes.new("ShaderNodeTexSky")
    texture.sun_elevation, texture.sun_rotation = math.radians(25), math.radians(60)
    links.new(texture.outputs["Color"], nodes["Background"].inputs["Color"])
    nodes["Background"].inputs["Strength"].default_value = 0.2
    bpy.context.scene.world = w
    add(bpy.ops.mesh.primitive_plane_add, principled("Floor", Base_Color=(0.5, 0.5, 0.5, 1.0)), index=1, size=20)
    add(bpy.ops.mesh.primitive_uv_sphere_add, principled("Grey", Base_Color=(0.6, 0.6, 0.6, 1.0), Roughness=0.6),
        index=2, segments=64, ring_count=32, radius=0.8, location=(-0.9, 0.0, 0.8))
    bpy.ops.object.shade_smooth()
    block = add(bpy.ops.mesh.primitive_cube_add, principled("White", Base_Color=(0.8, 0.8, 0.8, 1.0)), index=3,
                size=1.0, location=(1.0, -0.4, 0.5))
    block.rotation_euler = (0.0, 0.0, math.radians(30))
    camera((0.0, -7.0, 2.0), (0.0, 0.0, 1.0))
    return {"Floor": 1, "Grey": 2, "White": 3, "Sky": 0}


def bent_column(material, index, last_frame):
    """A column on the floor at x = -0.8 bent by a two-bone armature from frame 1 to `last_frame`."""
    column = add(bpy.ops.mesh.primitive_cylinder_add, material, index=index, vertices=16, radius=0.2, depth=2.0,
                 location=(-0.8, 0.0, 1.0))
    bpy.ops.object.mode_set(mode='EDIT')
    bpy.ops.mesh.select_all(action='SELECT')
    bpy.ops.mesh.subdivide(number_cuts=8)
    bpy.ops.object.mode_set(mode='OBJECT')
    rig = add(bpy.ops.object.armature_add, location=(-0.8, 0.0, 0.0))
    bpy.ops.object.mode_set(mode='EDIT')
    lower = rig.data.edit_bones[0]
    lower.head, lower.tail = (0, 0, 0), (0, 0, 1)
    upper = rig.data.edit_bones.new("Upper")
    upper.head, upper.tail, upper.parent = (0, 0, 1), (0, 0, 2), lower
    bpy.ops.object.mode_set(mode='OBJECT')
    column.select_set(True)
    bpy.context.view_layer.objects.active = rig
    bpy.ops.object.parent_set(type='ARMATURE_AUTO')
    bend = rig.pose.bones["Upper"]
    bend.rotation_mode = 'XYZ'
    for frame, angle in ((1, 0.0), (last_frame, 80.0)):
        bend.rotation_euler = (math.radians(angle), 0.0, math.radians(angle) / 2)
        bend.keyframe_insert("rotation_euler", frame=frame)


def raised_box(material, index, last_frame):
    """A box on the floor at x = 1 sheared upward by a shape key from frame 1 to `last_frame`."""
    box = add(bpy.ops.mesh.primitive_cube_add, material, index=index, size=0.8, location=(1.0, 0.5, 0.4))
    box.shape_key_add(name="Basis")
    tall = box.shape_key_add(name="Tall")
    for point in tall.data:
        point.co.z += 1.2 if point.co.z > 0 else 0.0
        point.co.x += 0.6 if point.co.z > 0 else 0.0
    for frame, value in ((1, 0.0), (last_frame, 1.0)):
        tall.value = value
        tall.keyframe_insert("value", frame=frame)


def rigged():
    """A column bent by a two-bone armature and a box raised by a shape key, both animated and
    seen at a frame between their keys, as black silhouettes against a white world (64 x 48)."""
    scene = silhouettes((64, 48))
    for obj in list(bpy.data.objects):
        bpy.data.objects.remove(obj)
    black = bpy.data.materials["Black"]
    bent_column(black, 1, 9)
    raised_box(black, 2, 9)
    scene.frame_start, scene.frame_end = 1, 9
    scene.frame_set(5)
    camera((5.0, -7.0, 3.0), (0.0, 0.0, 1.0))
    return {"World": 0}


def animated():
    """Everything that moves in an ordinary shot, keyed from frame 1 to 10 and seen at frames 1, 5
    and 10 (FRAMES) through Render Animation: an armature-bent column and a shape-keyed box (black,
    as silhouettes on the floor), a glowing panel whose Emission Strength is keyed, a sun whose
    strength is keyed and a camera that zooms from 30 to 60 mm, over a white floor under a grey
    world (96 x 72)."""
    scene = clear()
    scene.render.resolution_x, scene.render.resolution_y = 96, 72
    world((0.3, 0.3, 0.3))
    white = principled("White", Base_Color=(0.8, 0.8, 0.8, 1.0), Specular_IOR_Level=0.0, Roughness=1.0)
    black = principled("Black", Base_Color=(0.0, 0.0, 0.0, 1.0), Specular_IOR_Level=0.0, Roughness=1.0)
    add(bpy.ops.mesh.primitive_plane_add, white, index=1, size=30)
    bent_column(black, 2, 10)
    raised_box(black, 3, 10)
    glow = principled("Glow", Base_Color=(0.0, 0.0, 0.0, 1.0), Specular_IOR_Level=0.0,
                      Emission_Color=(1.0, 0.6, 0.2, 1.0), Emission_Strength=0.5)
    add(bpy.ops.mesh.primitive_plane_add, glow, index=4, size=1.0, location=(0.1, 1.2, 1.0),
        rotation=(math.radians(90), 0.0, math.radians(34)))
    strength = glow.node_tree.nodes["Principled BSDF"].inputs["Emission Strength"]
    sun = add(bpy.ops.object.light_add, type='SUN', rotation=(math.radians(30), 0.0, math.radians(20)))
    for frame, emission, power in ((1, 0.5, 1.0), (10, 2.0, 5.0)):
        strength.default_value = emission
        strength.keyframe_insert("default_value", frame=frame)
        sun.data.energy = power
        sun.data.keyframe_insert("energy", frame=frame)
    lens = camera((4.0, -6.0, 2.5), (0.0, 0.5, 0.8), lens=30.0).data
    for frame, millimetres in ((1, 30.0), (10, 60.0)):
        lens.lens = millimetres
        lens.keyframe_insert("lens", frame=frame)
    scene.frame_start, scene.frame_end = 1, 10
    scene.frame_set(1)
    return {"Floor": 1, "Glow": 4}


# Scenes rendered through Render Animation and compared at several frames (each frame's reference
# is <scene>_<frame>.exr); their dark silhouettes must overlap Cycles' (intersection over union).
FRAMES = {"animated": [1, 5, 10]}

# Scenes whose alpha (a transparent film, holdouts) must match Cycles': a mean absolute difference
# under 0.02 over the image and no pixel's over 0.25 (noise is under 0.1 at these sample counts;
# an object that should not render shows).
ALPHA = {"film_and_holdouts"}

# Scenes whose dark silhouettes (pixels under half the world's brightness) must match Cycles' within a pixel.
SILHOUETTES = {"ortho_camera", "shifted_camera", "panorama_camera", "rigged"}

# The scenes compared at a wider tolerance than 5% (their references are noisier: caustics).
TOLERANCES = {"glass": 0.07}

# The scenes Caustic renders with more passes than the test's default: a focused caustic's
# kernel blur (the radius sequence's bias) takes its peak 7% down at 256 passes, 1.5% at 2048;
# the small reflections of lights in a mirror ball reach Cycles' from about a thousand passes, and
# so does a ring of floor lit only by a ball's bounce (spread_light's 'Beyond': 0.96 to 1.05 of
# Cycles over seeds at 256 passes), and the sides of small cubes the floor lights (their light
# gathered near the floor's edge: 0.91 of Cycles' at 256 passes, 0.94 at 1024 for 0.45 m cubes).
PASSES = {"glass": 1024, "lights_seen": 1024, "spread_light": 1024, "instances_and_points": 1024}

# The scenes Caustic renders with more photons a pass than one a pixel. The sky lights a 20 m
# floor of which the 64x64 view sees a few metres: at 4,096 photons a pass few land in view, the
# first radius is the largest the rule gives (a fifth of the view), and its blur darkens the
# white block's faces toward their edges, the block 0.86-0.94 of Cycles over seeds at 1,024
# passes; at 65,536 a pass it is 0.97-0.98, and 256 passes take less time than those 1,024.
PHOTONS = {"sky": 65536}

# Regions whose brightest pixel lands where Cycles' does, within this many pixels.
PEAKS = {"hdri": {"Sky": 2.0}}

# Regions whose colour (each channel's share of their sum) is compared, with its tolerance.
COLOURS = {"glass": {"Tinted light": 0.03}, "warm_light": {"Floor": 0.03, "Grey": 0.03},
           "attributes_and_images": {"Unused": 0.03, "Painted": 0.03}}

# Objects of a saturated colour whose channels under 3% of their brightest (the green of magenta:
# only the specular layer's) are compared within 5% of the brightest channel, not of their own
# value: a spectral renderer's specular reflection of an out-of-gamut colour differs there by a
# few thousandths.
DIM_CHANNELS = {"attributes_and_images": {"Missing"}}

SCENES = {"glass": glass, "principled_spheres": principled_spheres, "textured": textured, "normal_mapped": normal_mapped,
          "coated": coated, "sheen": sheen, "leaf": leaf, "warm_light": warm_light, "soft_light": soft_light,
          "hdri": hdri, "ortho_camera": ortho_camera, "shifted_camera": shifted_camera,
          "panorama_camera": panorama_camera, "film_and_holdouts": film_and_holdouts,
          "spot_light": spot_light, "soft_spot": soft_spot, "sky": sky, "lights_seen": lights_seen,
          "spread_light": spread_light, "soft_falloff": soft_falloff, "rigged": rigged, "animated": animated,
          "attributes_and_images": attributes_and_images, "instances_and_points": instances_and_points,
          "normal_map_strengths": normal_map_strengths, "baked_bump": baked_bump, "simple_surfaces": simple_surfaces,
          "baked_textures": baked_textures}
