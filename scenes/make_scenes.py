"""Builds the bundled scenes in Blender (bpy) and exports them with Blender's own glTF exporter.

Run from the repository root (needs `pip install bpy==5.0.1`, CPython 3.11, x86_64):

    python scenes/make_scenes.py

Writes scenes/<name>.gltf and scenes/<name>.bin:
- cornell_glass: a Cornell box with a glass sphere lit by a small area light (the demo scene:
  the sphere focuses a caustic onto the floor);
- cornell_diffuse: the demo box without glass (two white blocks), all light interreflection;
- furnace: a closed cube whose walls are diffuse (albedo 0.5) and emit radiance 1, seen from
  inside (the analytic answer is Le / (1 - a) = 2 everywhere);
- spot_glass: a spot light shining through a glass sphere onto a diffuse floor;
- cornell_animated: the demo box over 24 frames with a rolling sphere, a dolly, motion blur and
  depth of field;
- shot / shot_moving_camera: the demo box over 24 frames with its glass sphere standing still and
  a small cube sliding across the floor, seen from a still camera (or a dollying one): the shot
  that reuse across frames is measured on (`caustic bench --frames`);
- gems: a diamond and a blue sapphire, cut with facets, dispersive, the sapphire coloured by a
  Volume Absorption node, under a small bright light;
- water_glass: a tumbler of blue-green water (a Volume Absorption node, dispersive water) with a
  frosted ice cube floating in it, under a low sun-like light;
- many_lights: a room lit only by 2400 small coloured bulbs of varied strength strung under its
  ceiling, with a glass sphere on a table (the light tree's scene);
- sunlit_room: a closed room on a 20 m ground plane, lit through one small window by a low sun
  and a blue sky, a glass ball on a table in the sun's patch (visibility-driven photons' scene:
  about 0.1% of uniform photon paths reach a point the camera sees);
- night_city (built for the benchmark, tests/bench/blender_scenes.py, not exported here): a city
  at night seen from above, 928 street lamps and 1485 lit windows (the light tree's second scene);
- glass_in_hall (built for the benchmark, not exported here): a small glass ball on a table in a
  24 m hall lit by 64 ceiling lamps, seen close up (visibility-driven photons' second scene); the
  sunlit room's close-up (`sunlit_room_scene(closeup=True)`) is built for the benchmark too.

Blender's exporter drops area lights and the render resolution, so they travel as `caustic`
custom properties, which the exporter writes as glTF extras (see docs/extras.md). The gems and the
glass of water are exported through the add-on (addon/), as an artist's would be: it writes their
dispersion, volume priorities and absorption.
"""
import math
import os
import pathlib
import sys
import tempfile

# The add-on is enabled in a temporary home, not the user's own Blender settings (unless a script
# that imported bpy first chose the home).
if "bpy" not in sys.modules:
    os.environ["HOME"] = tempfile.mkdtemp(prefix="caustic-scenes-home-")
import bpy  # noqa: E402
import bmesh  # noqa: E402

HERE = pathlib.Path(__file__).resolve().parent


def reset():
    bpy.ops.wm.read_factory_settings(use_empty=True)


def material(name, colour=(0.8, 0.8, 0.8), roughness=1.0, transmission=0.0, ior=1.5,
             emission=None, emission_strength=1.0):
    m = bpy.data.materials.new(name)
    bsdf = m.node_tree.nodes["Principled BSDF"] if m.node_tree else None
    if bsdf is None:
        m.use_nodes = True
        bsdf = m.node_tree.nodes["Principled BSDF"]
    bsdf.inputs["Base Color"].default_value = (*colour, 1.0)
    bsdf.inputs["Roughness"].default_value = roughness
    bsdf.inputs["Transmission Weight"].default_value = transmission
    bsdf.inputs["IOR"].default_value = ior
    # No specular layer on diffuse walls: the exporter writes KHR_materials_specular factor 0.
    bsdf.inputs["Specular IOR Level"].default_value = 0.5 if transmission > 0 else 0.0
    if emission is not None:
        bsdf.inputs["Emission Color"].default_value = (*emission, 1.0)
        bsdf.inputs["Emission Strength"].default_value = emission_strength
    return m


def plane(name, size, location, rotation, mat):
    bpy.ops.mesh.primitive_plane_add(size=size, location=location, rotation=rotation)
    obj = bpy.context.object
    obj.name = name
    obj.data.materials.append(mat)
    return obj


def glass_sphere(location, radius, mat, segments=96):
    bpy.ops.mesh.primitive_uv_sphere_add(segments=segments, ring_count=segments // 2, radius=radius,
                                         location=location)
    obj = bpy.context.object
    obj.name = "GlassSphere"
    bpy.ops.object.shade_smooth()
    obj.data.materials.append(mat)
    return obj


def camera(location, look_at, lens_mm=35.0):
    bpy.ops.object.camera_add(location=location)
    cam = bpy.context.object
    direction = [t - l for t, l in zip(look_at, location)]
    import mathutils
    cam.rotation_euler = mathutils.Vector(direction).to_track_quat("-Z", "Y").to_euler()
    cam.data.lens = lens_mm
    bpy.context.scene.camera = cam
    return cam


def area_light(name, location, size, power):
    bpy.ops.object.light_add(type="AREA", location=location)
    light = bpy.context.object
    light.name = name
    light.data.shape = "SQUARE"
    light.data.size = size
    light.data.energy = power
    light["caustic"] = {"area_light": {"shape": "SQUARE", "size": size, "power": power, "color": [1.0, 1.0, 1.0]}}
    return light


def set_resolution(width, height):
    scene = bpy.context.scene
    scene.render.resolution_x = width
    scene.render.resolution_y = height
    scene["caustic"] = {"resolution": [width, height]}


def export(name, animated=False):
    options = dict(
        filepath=str(HERE / f"{name}.gltf"),
        export_format="GLTF_SEPARATE",
        export_cameras=True,
        export_lights=True,
        export_extras=True,
        export_apply=True,
        export_animations=animated,
        export_yup=True,
    )
    if animated:
        # One timeline, sampled once a frame (LINEAR keys), no KHR_animation_pointer (the gltf
        # crate cannot read it).
        options.update(export_animation_mode="SCENE", export_force_sampling=True, export_frame_range=True,
                       export_pointer_animation=False)
    bpy.ops.export_scene.gltf(**options)


def reset_with_addon():
    """An empty file with the add-on enabled (as a user enables it), for the material settings it
    adds and its export."""
    reset()
    enable_addon()


def enable_addon():
    """Enables the add-on (linked into the user's add-ons), as a user enables it."""
    import addon_utils
    addons = pathlib.Path(bpy.utils.user_resource('SCRIPTS', path="addons", create=True))
    if not (addons / "caustic").exists():
        (addons / "caustic").symlink_to(HERE.parent / "addon")
        bpy.utils.refresh_script_paths()
    addon_utils.enable("caustic", default_set=True, handle_error=None)


def export_with_addon(name):
    """Exports the scene through the add-on, which writes what Blender's exporter drops or writes
    otherwise (dispersion, volume priority, absorption)."""
    sys.modules["caustic.export"].export(bpy.context.scene, HERE / f"{name}.gltf")


def absorbing(m, colour, density):
    """Gives material `m` a Volume Absorption node of `colour` and `density`."""
    nodes = m.node_tree.nodes
    node = nodes.new("ShaderNodeVolumeAbsorption")
    node.inputs["Color"].default_value = (*colour, 1.0)
    node.inputs["Density"].default_value = density
    m.node_tree.links.new(node.outputs["Volume"], nodes["Material Output"].inputs["Volume"])
    return m


def brilliant(name, radius, location, mat, facets=16):
    """A round brilliant cut (approximately): a table, a crown of facets down to the girdle and a
    pavilion down to the culet, flat-shaded."""
    mesh = bpy.data.meshes.new(name)
    bm = bmesh.new()
    ring = lambda r, z, turn: [bm.verts.new((r * math.cos(2 * math.pi * (i + turn) / facets),
                                             r * math.sin(2 * math.pi * (i + turn) / facets), z))
                               for i in range(facets)]
    table, girdle_top = ring(0.55 * radius, 0.33 * radius, 0.5), ring(radius, 0.03 * radius, 0.0)
    girdle_bottom, culet = ring(radius, -0.03 * radius, 0.0), bm.verts.new((0, 0, -0.86 * radius))
    bm.faces.new(table)
    for i in range(facets):
        j = (i + 1) % facets
        bm.faces.new((girdle_top[i], girdle_top[j], table[i]))
        bm.faces.new((table[i], girdle_top[j], table[j]))
        bm.faces.new((girdle_bottom[i], girdle_bottom[j], girdle_top[j], girdle_top[i]))
        bm.faces.new((girdle_bottom[j], girdle_bottom[i], culet))
    bmesh.ops.recalc_face_normals(bm, faces=bm.faces)
    bm.to_mesh(mesh)
    bm.free()
    obj = bpy.data.objects.new(name, mesh)
    bpy.context.scene.collection.objects.link(obj)
    obj.location = location
    mesh.materials.append(mat)
    return obj


def world(colour, strength=1.0):
    """A uniform world of `colour` (a Background node)."""
    w = bpy.data.worlds.new("World")
    w.use_nodes = True
    w.node_tree.nodes["Background"].inputs["Color"].default_value = (*colour, 1.0)
    w.node_tree.nodes["Background"].inputs["Strength"].default_value = strength
    bpy.context.scene.world = w


def make_gems():
    """A diamond and a blue sapphire on a dark stone, under a small bright light: dispersion
    (fire) in both, absorption in the sapphire."""
    reset_with_addon()
    plane("Stone", 6, (0, 0, 0), (0, 0, 0), material("Stone", (0.05, 0.05, 0.06), roughness=0.6))
    diamond = material("Diamond", (1.0, 1.0, 1.0), roughness=0.0, transmission=1.0, ior=2.417)
    diamond.caustic.dispersion, diamond.caustic.glass = 'GLASS', 'diamond'
    sapphire = absorbing(material("Sapphire", (1.0, 1.0, 1.0), roughness=0.0, transmission=1.0, ior=1.768),
                         (0.1, 0.3, 0.95), 6.0)
    sapphire.caustic.dispersion, sapphire.caustic.glass = 'GLASS', 'sapphire'
    world((0.25, 0.25, 0.27))
    brilliant("Diamond", 0.35, (-0.45, 0.0, 0.32), diamond)
    brilliant("Sapphire", 0.3, (0.45, 0.1, 0.28), sapphire)
    area_light("Spot", (-1.0, -1.5, 3.0), 0.15, 120.0).rotation_euler = (math.radians(30), 0.0, math.radians(-30))
    camera((0.0, -2.2, 1.4), (0.0, 0.0, 0.2), lens_mm=50.0)
    set_resolution(480, 320)
    export_with_addon("gems")


def make_water_glass():
    """A tumbler of blue-green water with a frosted ice cube floating in it on a white table,
    under a small low light: the glass and water refract and disperse, the water absorbs, the ice
    (of higher volume priority) fills where it lies in the water, and the water (of lower priority
    than the glass) is modelled into the glass's wall, as artists avoid coincident faces."""
    reset_with_addon()
    plane("Table", 8, (0, 0, 0), (0, 0, 0), material("Table", (0.8, 0.8, 0.78), roughness=0.7))
    glass = material("Tumbler glass", (1.0, 1.0, 1.0), roughness=0.0, transmission=1.0, ior=1.517)
    glass.caustic.dispersion, glass.caustic.glass, glass.caustic.priority = 'GLASS', 'BK7', 2
    bpy.ops.mesh.primitive_cylinder_add(vertices=64, radius=0.4, depth=1.0, location=(0, 0, 0.5))
    tumbler = bpy.context.object
    tumbler.name = "Tumbler"
    bm = bmesh.new()
    bm.from_mesh(tumbler.data)
    bmesh.ops.delete(bm, geom=[f for f in bm.faces if f.normal.z > 0.9], context='FACES')
    bm.to_mesh(tumbler.data)
    bm.free()
    solidify = tumbler.modifiers.new("Wall", 'SOLIDIFY')
    solidify.thickness, solidify.offset = 0.04, -1.0
    bpy.ops.object.shade_smooth()
    tumbler.data.materials.append(glass)
    water = absorbing(material("Water", (1.0, 1.0, 1.0), roughness=0.0, transmission=1.0, ior=1.333),
                      (0.55, 0.85, 0.8), 1.5)
    water.caustic.dispersion, water.caustic.glass = 'GLASS', 'water'
    # Into the glass's wall and floor by 0.01 (the glass, of higher priority, fills the overlap).
    bpy.ops.mesh.primitive_cylinder_add(vertices=64, radius=0.37, depth=0.68, location=(0, 0, 0.37))
    bpy.ops.object.shade_smooth()
    bpy.context.object.name = "Water"
    bpy.context.object.data.materials.append(water)
    ice = material("Ice", (1.0, 1.0, 1.0), roughness=0.25, transmission=1.0, ior=1.309)
    ice.caustic.priority = 3
    bpy.ops.mesh.primitive_cube_add(size=0.3, location=(0.05, -0.08, 0.7), rotation=(0.2, 0.3, 0.5))
    bpy.context.object.name = "Ice"
    bpy.context.object.data.materials.append(ice)
    world((0.3, 0.32, 0.35))
    area_light("Sun", (-2.5, 2.0, 1.6), 0.4, 400.0).rotation_euler = (math.radians(60), 0.0, math.radians(-130))
    camera((0.0, -2.8, 1.5), (0.0, 0.0, 0.45), lens_mm=45.0)
    set_resolution(320, 400)
    export_with_addon("water_glass")


def glass_material(roughness=0.0):
    return material("Glass", (1.0, 1.0, 1.0), roughness=roughness, transmission=1.0, ior=1.5)


def cornell_box_with_glass(roughness=0.0):
    """The demo box's walls (white, red and green) and the glass material (smooth, or frosted by
    `roughness`); gives the glass."""
    white = material("White", (0.75, 0.75, 0.75))
    red = material("Red", (0.63, 0.065, 0.05))
    green = material("Green", (0.14, 0.45, 0.091))
    cornell_box(white, red, green)
    return glass_material(roughness)


def cornell_box(white, red, green):
    plane("Floor", 2, (0, 0, 0), (0, 0, 0), white)
    plane("Ceiling", 2, (0, 0, 2), (math.pi, 0, 0), white)
    plane("BackWall", 2, (0, 1, 1), (math.pi / 2, 0, 0), white)
    plane("LeftWall", 2, (-1, 0, 1), (0, math.pi / 2, 0), red)
    plane("RightWall", 2, (1, 0, 1), (0, -math.pi / 2, 0), green)


def cornell_glass_scene(sphere_segments=96, roughness=0.0):
    """The demo scene, built but not exported (`sphere_segments` around the sphere; the glass
    frosted by `roughness`)."""
    reset()
    glass = cornell_box_with_glass(roughness)
    # A sphere of radius R and index 1.5 focuses at about 1.5 R beyond its centre: floating it
    # 0.2 above the floor puts the light's image near the floor, a sharp caustic.
    glass_sphere((0.3, -0.3, 0.55), 0.35, glass, sphere_segments)
    area_light("CeilingLight", (-0.3, 0.4, 1.98), 0.2, 25.0)
    camera((0, -3.9, 1.0), (0, 0, 1.0))
    set_resolution(480, 360)


def make_cornell_glass():
    cornell_glass_scene()
    export("cornell_glass")


def block(name, size, location, angle, mat):
    """A diffuse box standing on the floor, turned by `angle` about the vertical."""
    bpy.ops.mesh.primitive_cube_add(size=1, location=location, rotation=(0, 0, angle))
    obj = bpy.context.object
    obj.name = name
    obj.scale = size
    obj.data.materials.append(mat)
    return obj


def cornell_diffuse_scene():
    """The demo box without glass: a tall and a short white block, the same small light; every
    surface diffuse, so all light is interreflection (the benchmark's diffuse-only scene)."""
    reset()
    white = material("White", (0.75, 0.75, 0.75))
    cornell_box(white, material("Red", (0.63, 0.065, 0.05)), material("Green", (0.14, 0.45, 0.091)))
    block("TallBlock", (0.55, 0.55, 1.2), (-0.35, 0.3, 0.6), 0.3, white)
    block("ShortBlock", (0.55, 0.55, 0.55), (0.35, -0.35, 0.275), -0.3, white)
    area_light("CeilingLight", (0.0, 0.0, 1.98), 0.4, 40.0)
    camera((0, -3.9, 1.0), (0, 0, 1.0))
    set_resolution(480, 360)


def make_cornell_diffuse():
    cornell_diffuse_scene()
    export("cornell_diffuse")


def make_furnace():
    reset()
    wall = material("EmissiveGrey", (0.5, 0.5, 0.5), emission=(1.0, 1.0, 1.0), emission_strength=1.0)
    bpy.ops.mesh.primitive_cube_add(size=2, location=(0, 0, 0))
    cube = bpy.context.object
    cube.name = "Enclosure"
    cube.data.materials.append(wall)
    camera((0, 0, 0), (0, 1, 0.2), lens_mm=20)
    set_resolution(64, 64)
    export("furnace")


def point_spot(location, power, size_deg, blend):
    """A spot light pointing down from `location`: `power` W, a cone `size_deg` degrees across,
    of radius 0 (a point spot, as glTF's KHR_lights_punctual has it)."""
    bpy.ops.object.light_add(type="SPOT", location=location)
    spot = bpy.context.object
    spot.data.energy = power
    spot.data.spot_size = math.radians(size_deg)
    spot.data.spot_blend = blend
    spot.data.shadow_soft_size = 0.0
    return spot


def spot_glass_scene():
    """A spot light through a glass sphere onto a floor, built but not exported."""
    reset()
    floor = material("Floor", (0.7, 0.7, 0.7))
    glass = glass_material()
    plane("Floor", 6, (0, 0, 0), (0, 0, 0), floor)
    glass_sphere((0, 0, 1.0), 0.5, glass)
    point_spot((0, 0, 3.0), 500.0, 40, 0.1)
    camera((0, -4.0, 3.0), (0, 0, 0.3))
    set_resolution(320, 240)


def fog_spot_scene():
    """A spot light straight down through a glass ball into fog (the world's volume: a Volume
    Scatter, 0.12 per unit, g 0.2) over a grey floor, seen from the side, built but not exported:
    the beam, the ball's shadow in it and the cone the ball focuses (a volumetric caustic, which a
    path tracer cannot find from a point light)."""
    reset()
    floor = material("Floor", (0.5, 0.5, 0.5))
    plane("Floor", 8, (0, 0, 0), (0, 0, 0), floor)
    glass_sphere((0, 0, 2.0), 0.5, glass_material())
    point_spot((0, 0, 4.0), 1000.0, 28, 0.05)
    fog = bpy.data.worlds.new("Fog")
    fog.use_nodes = True
    nodes = fog.node_tree.nodes
    nodes["Background"].inputs["Strength"].default_value = 0.0
    scatter = nodes.new("ShaderNodeVolumeScatter")
    scatter.inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)
    scatter.inputs["Density"].default_value = 0.12
    scatter.inputs["Anisotropy"].default_value = 0.2
    fog.node_tree.links.new(scatter.outputs["Volume"], nodes["World Output"].inputs["Volume"])
    bpy.context.scene.world = fog
    camera((0, -6.0, 1.9), (0, 0, 1.4))
    set_resolution(320, 240)


def make_spot_glass():
    spot_glass_scene()
    export("spot_glass")


def make_cornell_animated():
    """The demo box over 24 frames: the glass sphere rolls across, the camera dollies in, with
    motion blur (half a frame, centred) and depth of field (f/1.4, focused on the sphere's path)."""
    reset()
    scene = bpy.context.scene
    scene.frame_start, scene.frame_end = 1, 24
    scene.render.fps = 24
    glass = cornell_box_with_glass()
    sphere = glass_sphere((-0.5, -0.2, 0.55), 0.35, glass)
    for frame, x in [(1, -0.5), (24, 0.5)]:
        sphere.location.x = x
        sphere.keyframe_insert("location", index=0, frame=frame)
    area_light("CeilingLight", (-0.3, 0.4, 1.98), 0.2, 25.0)
    cam = camera((0, -3.9, 1.0), (0, 0, 1.0))
    for frame, y in [(1, -3.9), (24, -3.3)]:
        cam.location.y = y
        cam.keyframe_insert("location", index=1, frame=frame)
    cam.data.dof.use_dof = True
    cam.data.dof.aperture_fstop = 1.4
    cam.data.dof.focus_distance = 3.4
    cam["caustic"] = {"lens": {"fstop": 1.4, "focus_distance": 3.4, "focal_length_mm": cam.data.lens}}
    scene.render.use_motion_blur = True
    scene.render.motion_blur_shutter = 0.5
    set_resolution(240, 180)
    scene["caustic"] = {"resolution": [240, 180], "fps": 24.0,
                        "shutter": {"length_frames": 0.5, "position": "CENTER"}}
    export("cornell_animated", animated=True)


def make_shot(moving_camera):
    """The demo box over 24 frames: the glass sphere and its caustic stand still while a small
    cube slides across the floor behind it, with a half-frame shutter; the camera stands still
    (or dollies in, for `shot_moving_camera`)."""
    reset()
    scene = bpy.context.scene
    scene.frame_start, scene.frame_end = 1, 24
    scene.render.fps = 24
    glass = cornell_box_with_glass()
    yellow = material("Yellow", (0.8, 0.6, 0.1))
    glass_sphere((0.3, -0.3, 0.55), 0.35, glass)
    bpy.ops.mesh.primitive_cube_add(size=0.2, location=(-0.7, 0.3, 0.1))
    cube = bpy.context.object
    cube.name = "SlidingCube"
    cube.data.materials.append(yellow)
    for frame, x in [(1, -0.7), (24, 0.0)]:
        cube.location.x = x
        cube.keyframe_insert("location", index=0, frame=frame)
    area_light("CeilingLight", (-0.3, 0.4, 1.98), 0.2, 25.0)
    cam = camera((0, -3.9, 1.0), (0, 0, 1.0))
    if moving_camera:
        for frame, y in [(1, -3.9), (24, -3.5)]:
            cam.location.y = y
            cam.keyframe_insert("location", index=1, frame=frame)
    scene.render.use_motion_blur = True
    scene.render.motion_blur_shutter = 0.5
    set_resolution(320, 240)
    scene["caustic"] = {"resolution": [320, 240], "fps": 24.0,
                        "shutter": {"length_frames": 0.5, "position": "CENTER"}}
    export("shot_moving_camera" if moving_camera else "shot", animated=True)


# The colours of the many-light scene's bulbs (linear) and the emission strengths they come in.
BULB_COLOURS = {"Warm": (1.0, 0.75, 0.45), "Red": (1.0, 0.1, 0.05), "Green": (0.1, 1.0, 0.2),
                "Blue": (0.15, 0.3, 1.0), "Amber": (1.0, 0.5, 0.05), "Pink": (1.0, 0.3, 0.6)}
BULB_STRENGTHS = (2.0, 8.0, 32.0)


def string_lights(strings=12, bulbs_per_string=200, size=0.025):
    """Strings of small two-sided emissive quads (bulbs) sagging across a room's ceiling from wall
    to wall, of varied colour and strength: one mesh, a material per colour and strength. Gives
    the bulbs' number."""
    import random
    rng = random.Random(7)
    materials = [material(f"Bulb {name} {strength:g}", (0.0, 0.0, 0.0), emission=colour, emission_strength=strength)
                 for name, colour in BULB_COLOURS.items() for strength in BULB_STRENGTHS]
    mesh = bpy.data.meshes.new("String lights")
    obj = bpy.data.objects.new("String lights", mesh)
    bpy.context.scene.collection.objects.link(obj)
    for m in materials:
        mesh.materials.append(m)
    bm = bmesh.new()
    for s in range(strings):
        y = -1.8 + 3.6 * (s + 0.5) / strings
        for b in range(bulbs_per_string):
            t = (b + 0.5) / bulbs_per_string
            x = -1.95 + 3.9 * t
            z = 2.4 - 0.5 * math.sin(math.pi * t) - 0.05 * rng.random()
            normal = [rng.uniform(-1, 1) for _ in range(3)]
            length = math.sqrt(sum(c * c for c in normal)) or 1.0
            nx, ny, nz = (c / length for c in normal)
            # Two edges across the normal.
            ax, ay, az = (ny, -nx, 0.0) if abs(nz) < 0.9 else (0.0, nz, -ny)
            a_len = math.sqrt(ax * ax + ay * ay + az * az)
            ax, ay, az = ax / a_len * size, ay / a_len * size, az / a_len * size
            bx, by, bz = ny * az - nz * ay, nz * ax - nx * az, nx * ay - ny * ax
            corners = [(x + sx * ax + sy * bx, y + sx * ay + sy * by, z + sx * az + sy * bz)
                       for sx, sy in ((-0.5, -0.5), (0.5, -0.5), (0.5, 0.5), (-0.5, 0.5))]
            face = bm.faces.new([bm.verts.new(c) for c in corners])
            face.material_index = rng.randrange(len(materials))
    bm.to_mesh(mesh)
    bm.free()
    return strings * bulbs_per_string


def many_lights_scene():
    """A room lit only by 2400 small bulbs of six colours and three strengths (16x apart) strung
    under its ceiling, with a glass sphere on a white table: next-event estimation must find,
    among thousands, the bulbs near each point (the light tree's scene), built but not exported."""
    reset()
    white = material("White", (0.7, 0.7, 0.7))
    plane("Floor", 4, (0, 0, 0), (0, 0, 0), white)
    plane("Ceiling", 4, (0, 0, 2.5), (math.pi, 0, 0), white)
    plane("BackWall", 4, (0, 2, 1.25), (math.pi / 2, 0, 0), material("Blue wall", (0.2, 0.3, 0.6)))
    plane("LeftWall", 4, (-2, 0, 1.25), (0, math.pi / 2, 0), white)
    plane("RightWall", 4, (2, 0, 1.25), (0, -math.pi / 2, 0), white)
    block("Table", (1.2, 0.8, 0.7), (0.0, 0.3, 0.35), 0.3, white)
    glass_sphere((0.0, 0.3, 0.95), 0.25, glass_material())
    string_lights()
    camera((0.0, -3.6, 1.3), (0.0, 0.5, 1.2), lens_mm=24.0)
    set_resolution(320, 240)


def emissive_quads(name, quads, materials):
    """One mesh of quads, each given as (centre, edge a, edge b, material index)."""
    mesh = bpy.data.meshes.new(name)
    obj = bpy.data.objects.new(name, mesh)
    bpy.context.scene.collection.objects.link(obj)
    for m in materials:
        mesh.materials.append(m)
    bm = bmesh.new()
    for centre, a, b, index in quads:
        corners = [tuple(c + sx * ea + sy * eb for c, ea, eb in zip(centre, a, b))
                   for sx, sy in ((-0.5, -0.5), (0.5, -0.5), (0.5, 0.5), (-0.5, 0.5))]
        face = bm.faces.new([bm.verts.new(c) for c in corners])
        face.material_index = index
    bm.to_mesh(mesh)
    bm.free()
    return len(quads)


def night_city_scene(blocks=7, block_size=6.0, street=4.0):
    """A city block grid at night seen from above: street lamps facing down along every street
    and lit windows on the facades, of varied colour and strength (928 lamps and 1485 windows),
    and a glass sphere on the central square. Each point is lit mostly by the few
    lamps near it: the light tree's second scene, built but not exported."""
    import random
    rng = random.Random(11)
    reset()
    pitch = block_size + street
    extent = blocks * pitch + street
    plane("Ground", extent + 8, (0, 0, 0), (0, 0, 0), material("Asphalt", (0.25, 0.25, 0.25)))
    facade = material("Facade", (0.55, 0.5, 0.45))
    lamps = [material(f"Lamp {s:g}", (0.0, 0.0, 0.0), emission=(1.0, 0.7, 0.4), emission_strength=s)
             for s in (15.0, 45.0)]
    windows = [material(f"Window {n} {s:g}", (0.0, 0.0, 0.0), emission=c, emission_strength=s)
               for n, c in (("Warm", (1.0, 0.75, 0.45)), ("Cool", (0.6, 0.75, 1.0)), ("TV", (0.3, 0.5, 1.0)))
               for s in (3.0, 12.0)]
    half = extent / 2
    lamp_quads, window_quads = [], []
    down, x_edge, y_edge, z_edge = (0, 0, 1), (0.4, 0, 0), (0, 0.4, 0), (0, 0, 1)
    for i in range(blocks):
        for j in range(blocks):
            if (i, j) == (blocks // 2, blocks // 2):
                continue  # the square
            x0, y0 = -half + street + i * pitch, -half + street + j * pitch
            height = rng.choice((4.0, 7.0, 10.0, 13.0))
            block(f"Block {i} {j}", (block_size, block_size, height),
                  (x0 + block_size / 2, y0 + block_size / 2, height / 2), 0.0, facade)
            for floor in range(int(height / 3)):
                z = 1.8 + 3.0 * floor
                for k in range(5):
                    along = 0.6 + (k + 0.5) * (block_size - 1.2) / 5
                    for centre, a in (((x0 + along, y0 - 0.01, z), (0.7, 0, 0)),
                                      ((x0 + along, y0 + block_size + 0.01, z), (-0.7, 0, 0)),
                                      ((x0 - 0.01, y0 + along, z), (0, -0.7, 0)),
                                      ((x0 + block_size + 0.01, y0 + along, z), (0, 0.7, 0))):
                        if rng.random() < 0.6:
                            window_quads.append((centre, a, (0, 0, 1.0), rng.randrange(len(windows))))
    for k in range(blocks + 1):
        road = -half + street / 2 + k * pitch
        steps = int(extent / 2.5)
        for s in range(steps):
            along = -half + (s + 0.5) * extent / steps
            for side in (-1, 1):
                across = road + side * 1.6
                lamp_quads.append(((along, across, 5.0), (0.4, 0, 0), (0, -0.4, 0), rng.randrange(2)))
                lamp_quads.append(((across, along, 5.0), (0, 0.4, 0), (0.4, 0, 0), rng.randrange(2)))
    emissive_quads("Lamps", lamp_quads, lamps)
    emissive_quads("Windows", window_quads, windows)
    glass_sphere((0, 0, 1.5), 1.5, glass_material())
    camera((0.0, -half - 4.0, 34.0), (0.0, -4.0, 0.0), lens_mm=24.0)
    set_resolution(320, 240)


def sun(elevation_deg, azimuth_deg, strength, angle_deg=0.5):
    """A sun light `elevation_deg` above the horizon, shining from azimuth `azimuth_deg` (0: from
    +y, 90: from +x), of irradiance `strength` W/m^2."""
    bpy.ops.object.light_add(type="SUN")
    light = bpy.context.object
    light.name = "Sun"
    # A sun shines along its -Z: tilt it down from the zenith toward the azimuth it comes from.
    light.rotation_euler = (math.radians(90.0 - elevation_deg), 0.0, math.radians(180.0 - azimuth_deg))
    light.data.energy = strength
    light.data.angle = math.radians(angle_deg)
    return light


def sunlit_room_scene(ground=20.0, closeup=False):
    """A closed room (4 x 4 x 2.5 m) on a large sunlit ground plane (`ground` m square), lit
    through one small window (1 x 1 m) by a low sun and a blue sky: the sun's patch falls on
    a table where a glass ball focuses it into a caustic. Nearly every photon from the sun and
    the sky lands outside, where the camera (inside) sees nothing: the visibility-driven photons'
    scene (Hachisuka & Jensen 2011's sunlit room). `closeup` frames the glass ball and its
    caustic instead of the room (the automatic radius's close-up)."""
    reset()
    white = material("Plaster", (0.75, 0.73, 0.7))
    plane("Ground", ground, (0, 0, 0), (0, 0, 0), material("Grass", (0.15, 0.3, 0.08)))
    wall = 0.1
    block("Roof", (4.0 + 2 * wall, 4.0 + 2 * wall, wall), (0, 0, 2.5 + wall / 2), 0.0, white)
    block("FrontWall", (4.0 + 2 * wall, wall, 2.5), (0, -2.0 - wall / 2, 1.25), 0.0, white)
    block("LeftWall", (wall, 4.0, 2.5), (-2.0 - wall / 2, 0, 1.25), 0.0, white)
    block("RightWall", (wall, 4.0, 2.5), (2.0 + wall / 2, 0, 1.25), 0.0, white)
    # The back wall (y = 2) around a window 1 m wide and high, from 1.2 m to 2.2 m.
    back = material("Back plaster", (0.6, 0.65, 0.75))
    y = 2.0 + wall / 2
    block("BackWallLeft", (1.5 + wall, wall, 2.5), (-1.25 - wall / 2, y, 1.25), 0.0, back)
    block("BackWallRight", (1.5 + wall, wall, 2.5), (1.25 + wall / 2, y, 1.25), 0.0, back)
    block("BackWallBelow", (1.0, wall, 1.2), (0, y, 0.6), 0.0, back)
    block("BackWallAbove", (1.0, wall, 0.3), (0, y, 2.35), 0.0, back)
    block("Table", (1.2, 0.8, 0.75), (0.0, 0.55, 0.375), 0.0, material("Table top", (0.8, 0.8, 0.8)))
    glass_sphere((0.0, 0.9, 0.9), 0.15, glass_material())
    sun(40.0, 0.0, 5.0)
    world((0.35, 0.5, 0.9), 0.6)
    if closeup:
        camera((0.45, 0.2, 1.25), (0.0, 0.85, 0.8), lens_mm=35.0)
    else:
        camera((1.3, -1.8, 1.5), (0.0, 0.55, 0.8), lens_mm=24.0)
    set_resolution(256, 192)


def glass_in_hall_scene(size=24.0, height=6.0, lamps=8):
    """A small glass ball on a small table in a large hall (`size` m square, `height` m high) lit
    by `lamps` x `lamps` ceiling lamps facing down, seen close up: the camera sees about a metre
    of the hall, which the lamps light all over (visibility-driven photons' second scene), built
    for the benchmark, not exported."""
    reset()
    grey = material("Hall walls", (0.6, 0.6, 0.6))
    plane("Floor", size, (0, 0, 0), (0, 0, 0), material("Floor", (0.45, 0.4, 0.35)))
    plane("Ceiling", size, (0, 0, height), (math.pi, 0, 0), grey)
    for name, location, rotation in (("WallN", (0, size / 2, height / 2), (math.pi / 2, 0, 0)),
                                     ("WallS", (0, -size / 2, height / 2), (-math.pi / 2, 0, 0)),
                                     ("WallW", (-size / 2, 0, height / 2), (0, math.pi / 2, 0)),
                                     ("WallE", (size / 2, 0, height / 2), (0, -math.pi / 2, 0))):
        bpy.ops.mesh.primitive_plane_add(size=1, location=location, rotation=rotation)
        wall = bpy.context.object
        wall.name = name
        wall.scale = (size, height, 1) if name in ("WallN", "WallS") else (height, size, 1)
        wall.data.materials.append(grey)
    lamp = material("Lamp", (0.0, 0.0, 0.0), emission=(1.0, 0.85, 0.7), emission_strength=40.0)
    pitch = size / lamps
    quads = [((-size / 2 + (i + 0.5) * pitch, -size / 2 + (j + 0.5) * pitch, height - 0.01), (0.4, 0, 0),
              (0, -0.4, 0), 0) for i in range(lamps) for j in range(lamps)]
    emissive_quads("Lamps", quads, [lamp])
    table = (2.0, 1.5)
    block("Table", (0.8, 0.8, 0.75), (*table, 0.375), 0.0, material("Table top", (0.8, 0.8, 0.8)))
    glass_sphere((table[0], table[1], 0.83), 0.08, glass_material())
    camera((table[0] + 0.55, table[1] - 0.85, 1.3), (table[0], table[1], 0.78), lens_mm=50.0)
    set_resolution(256, 192)


def water_surface(size, depth, level, waves, grid=96):
    """A closed body of water `size` m square and `depth` m deep whose top, at `level` on
    average, is a grid of `grid` x `grid` quads raised by `waves`: (amplitude m, wavelength m,
    direction in degrees) summed as sines."""
    import bmesh
    half = size / 2

    def height(x, y):
        return level + sum(a * math.sin(2 * math.pi / length * (x * math.cos(math.radians(d)) +
                                                               y * math.sin(math.radians(d))))
                           for a, length, d in waves)
    mesh = bpy.data.meshes.new("Water")
    b = bmesh.new()
    top = [[b.verts.new((-half + size * i / grid, -half + size * j / grid,
                         height(-half + size * i / grid, -half + size * j / grid)))
            for j in range(grid + 1)] for i in range(grid + 1)]
    for i in range(grid):
        for j in range(grid):
            b.faces.new((top[i][j], top[i + 1][j], top[i + 1][j + 1], top[i][j + 1]))
    bottom = level - depth
    rim = ([top[i][0] for i in range(grid + 1)] + [top[grid][j] for j in range(1, grid + 1)] +
           [top[i][grid] for i in range(grid - 1, -1, -1)] + [top[0][j] for j in range(grid - 1, 0, -1)])
    low = [b.verts.new((v.co.x, v.co.y, bottom)) for v in rim]
    for k in range(len(rim)):
        n = (k + 1) % len(rim)
        b.faces.new((rim[k], low[k], low[n], rim[n]))
    b.faces.new(low)
    bmesh.ops.recalc_face_normals(b, faces=b.faces)
    b.to_mesh(mesh)
    b.free()
    obj = bpy.data.objects.new("Water", mesh)
    bpy.context.collection.objects.link(obj)
    for polygon in mesh.polygons:
        polygon.use_smooth = True
    return obj


def pool_scene():
    """A swimming pool (4 x 4 m, 1.5 m deep) of slightly scattering, blue-green water whose
    surface carries small waves, lit by a high sun and a blue sky and seen from its edge: the
    sun's caustic net on the floor and walls seen through the surface, and the sun's shafts in the
    water (the photons' through the beams: next-event estimation cannot see the sun through the
    surface)."""
    reset()
    tiles = material("Tiles", (0.55, 0.75, 0.8))
    size, depth, rim = 4.0, 1.5, 0.3
    plane("PoolFloor", size, (0, 0, 0), (0, 0, 0), tiles)
    for name, location, rotation in (("WallN", (0, size / 2, depth / 2 + rim / 2), (math.pi / 2, 0, 0)),
                                     ("WallS", (0, -size / 2, depth / 2 + rim / 2), (-math.pi / 2, 0, 0)),
                                     ("WallW", (-size / 2, 0, depth / 2 + rim / 2), (0, math.pi / 2, 0)),
                                     ("WallE", (size / 2, 0, depth / 2 + rim / 2), (0, -math.pi / 2, 0))):
        bpy.ops.mesh.primitive_plane_add(size=1, location=location, rotation=rotation)
        wall = bpy.context.object
        wall.name = name
        wall.scale = (size, depth + rim, 1) if name in ("WallN", "WallS") else (depth + rim, size, 1)
        wall.data.materials.append(tiles)
    stone = material("Paving", (0.6, 0.58, 0.55))
    for name, location, dimensions in (("PavingN", (0, size / 2 + 1.5, depth + rim), (size + 6, 3)),
                                       ("PavingS", (0, -size / 2 - 1.5, depth + rim), (size + 6, 3)),
                                       ("PavingW", (-size / 2 - 1.5, 0, depth + rim), (3, size)),
                                       ("PavingE", (size / 2 + 1.5, 0, depth + rim), (3, size))):
        bpy.ops.mesh.primitive_plane_add(size=1, location=location)
        paving = bpy.context.object
        paving.name = name
        paving.scale = (*dimensions, 1)
        paving.data.materials.append(stone)
    # The water stops a millimetre short of the tiles, so that no face of it lies on one.
    water = water_surface(size - 0.002, depth - 0.001, depth, [(0.012, 0.9, 20.0), (0.008, 0.55, 115.0),
                                                               (0.005, 0.33, 250.0)])
    water_material = material("Water", (1.0, 1.0, 1.0), roughness=0.0, transmission=1.0, ior=1.33)
    nodes, links = water_material.node_tree.nodes, water_material.node_tree.links
    volume = nodes.new("ShaderNodeVolumePrincipled")
    volume.inputs["Color"].default_value = (0.5, 0.85, 1.0, 1.0)
    volume.inputs["Density"].default_value = 0.25
    volume.inputs["Absorption Color"].default_value = (0.2, 0.7, 0.9, 1.0)
    output = next(n for n in nodes if n.type == 'OUTPUT_MATERIAL')
    links.new(volume.outputs["Volume"], output.inputs["Volume"])
    water.data.materials.append(water_material)
    sun(65.0, 30.0, 2.0)
    world((0.4, 0.55, 0.85), 0.3)
    camera((0.3, -3.3, 3.0), (0.0, 0.5, 0.3), lens_mm=24.0)
    set_resolution(320, 240)


def make_pool():
    """Exported through the add-on, which writes the water's medium and the world."""
    pool_scene()
    enable_addon()
    export_with_addon("pool")


def make_many_lights():
    many_lights_scene()
    export("many_lights")


def make_sunlit_room():
    """Exported through the add-on, which writes the world (Blender's exporter drops it)."""
    sunlit_room_scene()
    enable_addon()
    export_with_addon("sunlit_room")


if __name__ == "__main__":
    make_gems()
    make_water_glass()
    make_shot(moving_camera=False)
    make_shot(moving_camera=True)
    make_cornell_animated()
    make_cornell_glass()
    make_cornell_diffuse()
    make_furnace()
    make_spot_glass()
    make_many_lights()
    make_sunlit_room()
    make_pool()
