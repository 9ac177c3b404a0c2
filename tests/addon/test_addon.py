"""The Blender add-on, driven headless through `bpy` (Blender 5.0.1 as a Python module).

Run by tests/addon.rs (the README's test command) with the virtual environment it prepares;
CAUSTIC_BINARY names the renderer. The add-on is enabled through `addon_utils` in a temporary
HOME, as a user would enable it; each test builds its scene in bpy and renders through the add-on
with `bpy.ops.render.render()`, then reads the pixels Blender saved.
"""

import collections
import json
import math
import re
import os
import pathlib
import subprocess
import sys
import tempfile
import time
import unittest

HOME = tempfile.mkdtemp(prefix="caustic-addon-home-")
os.environ["HOME"] = HOME

import bpy  # noqa: E402  (first: it makes Blender's own modules importable)
import mathutils  # noqa: E402
import numpy as np  # noqa: E402
import OpenEXR  # noqa: E402
from bpy_extras.object_utils import world_to_camera_view  # noqa: E402

ROOT = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "tests" / "addon"))
import parity_scenes  # noqa: E402
from enable_addon import enable_addon  # noqa: E402

BINARY = os.environ["CAUSTIC_BINARY"]
OUT = pathlib.Path(tempfile.mkdtemp(prefix="caustic-addon-out-"))


ENGINE = enable_addon(BINARY)
STARTED = []  # every renderer process the add-on starts


class CountedProcess(ENGINE.RenderProcess):
    def __init__(self, args):
        super().__init__(args)
        STARTED.append(self)


ENGINE.RenderProcess = CountedProcess


def clear_scene():
    """An empty scene rendered by Caustic at 64x48, 32 passes."""
    for collection in (bpy.data.objects, bpy.data.meshes, bpy.data.materials, bpy.data.lights, bpy.data.cameras,
                       bpy.data.actions):
        for block in list(collection):
            collection.remove(block)
    scene = bpy.context.scene
    scene.render.engine = 'CAUSTIC'
    scene.render.resolution_x, scene.render.resolution_y, scene.render.resolution_percentage = 64, 48, 100
    scene.render.use_motion_blur = False
    scene.frame_start, scene.frame_end, scene.frame_step = 1, 1, 1
    scene.frame_set(1)
    scene.caustic.passes = 32
    scene.world = None
    scene.render.image_settings.media_type = 'IMAGE'
    scene.render.image_settings.file_format = 'OPEN_EXR'
    scene.render.image_settings.color_depth = '32'
    return scene


def material(name, colour=(0.8, 0.8, 0.8), transmission=0.0, ior=1.5):
    m = bpy.data.materials.new(name)
    bsdf = m.node_tree.nodes["Principled BSDF"]
    bsdf.inputs["Base Color"].default_value = (*colour, 1.0)
    bsdf.inputs["Roughness"].default_value = 0.0 if transmission else 1.0
    bsdf.inputs["Transmission Weight"].default_value = transmission
    bsdf.inputs["IOR"].default_value = ior
    bsdf.inputs["Specular IOR Level"].default_value = 0.5 if transmission else 0.0
    return m


def add(operator, material_=None, **kwargs):
    operator(**kwargs)
    obj = bpy.context.object
    if material_ is not None:
        obj.data.materials.append(material_)
    return obj


def look_at(obj, target):
    direction = mathutils.Vector(target) - obj.location
    obj.rotation_euler = direction.to_track_quat('-Z', 'Y').to_euler()


def camera(location, target):
    cam = add(bpy.ops.object.camera_add, location=location)
    look_at(cam, target)
    bpy.context.scene.camera = cam
    return cam


def glass_sphere_scene():
    """A white floor, a glass ball 1 above it and a small area light straight above the ball: the
    ball focuses a caustic onto the floor under it."""
    scene = clear_scene()
    add(bpy.ops.mesh.primitive_plane_add, material("Floor"), size=8)
    add(bpy.ops.mesh.primitive_uv_sphere_add, material("Glass", (1, 1, 1), 1.0), segments=64, ring_count=32,
        radius=0.5, location=(0, 0, 1.0))
    bpy.ops.object.shade_smooth()
    light = add(bpy.ops.object.light_add, type='AREA', location=(0, 0, 3.5))
    light.data.size, light.data.energy = 0.1, 60.0
    camera((0, -4, 4), (0, 0, 0.3))
    return scene


def read_exr(path):
    """The RGB pixels of an EXR (row 0 at the top), from its Combined or RGBA channels."""
    channels = OpenEXR.File(str(path)).channels()
    key = "Combined" if "Combined" in channels else "RGBA"
    return channels[key].pixels[..., :3].astype(np.float64)


def render_still(name):
    scene = bpy.context.scene
    scene.render.filepath = str(OUT / f"{name}.exr")
    bpy.ops.render.render(write_still=True)
    return read_exr(scene.render.filepath)


def pixel_of(scene, point):
    """The (row, column) where the scene's camera sees `point`."""
    v = world_to_camera_view(scene, scene.camera, mathutils.Vector(point))
    w, h = scene.render.resolution_x, scene.render.resolution_y
    return int((1.0 - v.y) * h), int(v.x * w)


def luminance(rgb):
    return rgb @ np.array([0.2126, 0.7152, 0.0722])


def block(image, centre, half=2):
    r, c = centre
    return luminance(image[r - half:r + half + 1, c - half:c + half + 1]).mean()


class StillRenders(unittest.TestCase):
    def test_glass_ball_caustic_is_brighter_than_the_floor_beside_it(self):
        scene = glass_sphere_scene()
        image = render_still("caustic")
        caustic, beside = block(image, pixel_of(scene, (0, 0, 0))), block(image, pixel_of(scene, (1.6, 0, 0)))
        print(f"caustic {caustic:.3f}, floor beside it {beside:.3f}")
        self.assertGreater(caustic, 3.0 * beside)
        self.assertGreater(beside, 0.0)

    def test_image_matches_the_command_line_render_of_the_same_export(self):
        scene = glass_sphere_scene()
        image = render_still("through_blender")
        exported = OUT / "same" / "scene.gltf"
        exported.parent.mkdir()
        sys.modules["caustic.export"].export(scene, exported)
        flags = ENGINE.render_flags(scene)
        subprocess.run([BINARY, "render", str(exported), "-o", str(OUT / "same"), "--progress", "none", *flags],
                       check=True)
        cli = read_exr(OUT / "same" / "frame_0001.exr")
        # The same scene, settings and seed: the same image, up to Blender's EXR round trip.
        np.testing.assert_allclose(image, cli, rtol=1e-5, atol=1e-6)

    def test_connection_and_merging_renders_through_blender_as_on_the_command_line(self):
        """The Method setting's Connection and Merging renders the ball's caustic through
        Blender, the same image the command line gives with `--method vcm`."""
        scene = glass_sphere_scene()
        scene.caustic.method = 'VCM'
        try:
            flags = ENGINE.render_flags(scene)
            image = render_still("vcm")
        finally:
            scene.caustic.method = 'SPPM'
        self.assertIn("vcm", flags)
        caustic, beside = block(image, pixel_of(scene, (0, 0, 0))), block(image, pixel_of(scene, (1.6, 0, 0)))
        self.assertGreater(caustic, 3.0 * beside)
        exported = OUT / "vcm_cli" / "scene.gltf"
        exported.parent.mkdir()
        sys.modules["caustic.export"].export(scene, exported)
        subprocess.run([BINARY, "render", str(exported), "-o", str(OUT / "vcm_cli"), "--progress", "none", *flags],
                       check=True)
        np.testing.assert_allclose(image, read_exr(OUT / "vcm_cli" / "frame_0001.exr"), rtol=1e-5, atol=1e-6)

    def test_a_render_region_renders_the_same_pixels_there(self):
        """A render region (Blender's border), cropped to or placed in the whole image, holds the
        pixels the whole image's render has there, and nothing elsewhere."""
        scene = glass_sphere_scene()
        scene.caustic.photons = 3072
        whole = render_still("region_whole")
        r = scene.render
        r.use_border, r.border_min_x, r.border_max_x, r.border_min_y, r.border_max_y = True, 0.25, 0.75, 0.5, 1.0
        x, y, width, height = sys.modules["caustic.extras"].render_region(scene)
        self.assertEqual((x, y, width, height), (16, 24, 32, 24))
        try:
            r.use_crop_to_border = True
            cropped = render_still("region_cropped")
            r.use_crop_to_border = False
            placed = render_still("region_placed")
        finally:
            r.use_border = r.use_crop_to_border = False
        window = whole[48 - (y + height):48 - y, x:x + width]  # rows from the top
        self.assertEqual(cropped.shape[:2], (height, width))
        np.testing.assert_allclose(cropped, window, rtol=1e-5, atol=1e-6)
        self.assertEqual(placed.shape[:2], (48, 64))
        np.testing.assert_allclose(placed[48 - (y + height):48 - y, x:x + width], window, rtol=1e-5, atol=1e-6)
        outside = np.ones((48, 64), bool)
        outside[48 - (y + height):48 - y, x:x + width] = False
        self.assertEqual(np.abs(placed[outside]).max(), 0.0)

    def test_the_status_line_shows_the_error_and_the_time_to_the_target(self):
        """With a target error the status line shows the error falling and the forecast time to
        the target, and the progress bar follows the forecast."""
        scene = glass_sphere_scene()
        scene.caustic.passes, scene.caustic.use_target_error, scene.caustic.target_error = 400, True, 0.25
        lines, fractions = [], []
        line, fraction = ENGINE.progress_line, ENGINE.progress_fraction
        ENGINE.progress_line = lambda event: lines.append(line(event)) or lines[-1]
        ENGINE.progress_fraction = lambda event: fractions.append(fraction(event)) or fractions[-1]
        try:
            render_still("status_line")
        finally:
            ENGINE.progress_line, ENGINE.progress_fraction = line, fraction
            scene.caustic.use_target_error = False
        forecasts = [l for l in lines if re.search(r", error \d+(\.\d+)?%, 25% in about \d+ s$", l)]
        self.assertTrue(forecasts, lines[-5:])
        errors = [float(re.search(r"error ([\d.]+)%", l).group(1)) for l in lines if "error" in l]
        self.assertLess(errors[-1], errors[0], "the error falls")
        self.assertTrue(all(0.0 <= f <= 1.0 for f in fractions if f is not None), fractions[-5:])

    def test_denoise_lowers_the_error_at_16_passes(self):
        """The Denoise option (Blender's Denoise node on Caustic's albedo and normal passes, set up
        in the compositor) brings a 16-pass render of a rough metal ball on a floor under a large
        soft light (whose noise is each pixel's own: light samples, paths through the metal's
        lobe) closer to a 512-pass one: its relative MSE at least halves."""
        scene = clear_scene()
        add(bpy.ops.mesh.primitive_plane_add, material("Floor"), size=8)
        metal = material("Metal", (0.9, 0.7, 0.4))
        metal.node_tree.nodes["Principled BSDF"].inputs["Metallic"].default_value = 1.0
        metal.node_tree.nodes["Principled BSDF"].inputs["Roughness"].default_value = 0.3
        add(bpy.ops.mesh.primitive_uv_sphere_add, metal, segments=48, ring_count=24, radius=0.8, location=(0, 0, 0.8))
        bpy.ops.object.shade_smooth()
        light = add(bpy.ops.object.light_add, type='AREA', location=(-1.5, -1.0, 3.0))
        light.data.size, light.data.energy = 3.0, 300.0
        look_at(light, (0, 0, 0))
        camera((0, -4, 2.5), (0, 0, 0.6))
        scene.caustic.passes = 512
        reference = render_still("denoise_reference")
        scene.caustic.passes = 16
        noisy = render_still("denoise_noisy")
        scene.caustic.denoise = True
        try:
            self.assertEqual(scene.compositing_node_group.name, "Caustic Denoise")
            denoised = render_still("denoise_denoised")
        finally:
            scene.caustic.denoise, scene.compositing_node_group = False, None
        relative_mse = {name: float(((image - reference) ** 2 / (reference ** 2 + 1e-2)).mean())
                        for name, image in (("noisy", noisy), ("denoised", denoised))}
        print(f"relative MSE against 512 passes: {relative_mse}")
        self.assertLess(relative_mse["denoised"], 0.5 * relative_mse["noisy"])

    def test_a_multilayer_exr_keeps_every_pass(self):
        """Render Animation saved as multilayer EXR by Blender holds Combined, Error and, with
        Denoise, the denoising passes."""
        scene = glass_sphere_scene()
        scene.caustic.passes = 4
        settings = scene.render.image_settings
        settings.media_type, settings.file_format = 'MULTI_LAYER_IMAGE', 'OPEN_EXR_MULTILAYER'
        scene.caustic.denoise = True
        try:
            scene.render.filepath = str(OUT / "multilayer" / "frame_")
            bpy.ops.render.render(animation=True)
        finally:
            scene.caustic.denoise, scene.compositing_node_group = False, None
            settings.media_type, settings.file_format = 'IMAGE', 'OPEN_EXR'
        written = OUT / "multilayer" / "frame_0001.exr"
        channels = {name for part in OpenEXR.File(str(written)).parts for name in part.channels}
        for name in ("ViewLayer.Combined", "ViewLayer.Error.Y", "ViewLayer.Denoising Albedo",
                     "ViewLayer.Denoising Normal.X", "ViewLayer.Denoising Normal.Z"):
            self.assertIn(name, channels)

    def test_dispersive_prism_separates_colours(self):
        """The dispersion regression prism (scenes/prism.gltf, imported): with the SF11 glass from the
        material's Caustic settings, the band's red and blue centroids lie pixels apart; with a
        constant index (SF11's n_d) they coincide."""
        scene = clear_scene()
        bpy.ops.import_scene.gltf(filepath=str(ROOT / "scenes" / "prism.gltf"))
        for block_ in [scene, *bpy.data.materials, *bpy.data.objects]:
            block_.pop("caustic", None)
        scene.camera = bpy.data.objects["Camera"]
        scene.render.resolution_x, scene.render.resolution_y = 128, 64
        prism = bpy.data.materials["Prism"]
        prism.node_tree.nodes["Principled BSDF"].inputs["IOR"].default_value = 1.78472
        separation = {}
        for mode in ("GLASS", "NONE"):
            prism.caustic.dispersion, prism.caustic.glass = mode, "SF11"
            image = render_still(f"prism_{mode}")
            band = np.clip(image.sum(axis=0) - np.median(image.sum(axis=0), axis=0), 0, None)
            x = np.arange(band.shape[0])
            red, blue = (band[:, c] @ x / band[:, c].sum() for c in (0, 2))
            separation[mode] = blue - red
        print(f"blue minus red centroid: {separation}")
        self.assertGreater(abs(separation["GLASS"]), 2.0)
        self.assertLess(abs(separation["NONE"]), 0.5)


class Animation(unittest.TestCase):
    def test_render_animation_renders_three_frames_with_one_process(self):
        scene = glass_sphere_scene()
        red = add(bpy.ops.mesh.primitive_cube_add, material("Red", (0.9, 0.05, 0.05)), size=0.4,
                  location=(-1.2, 0.8, 0.2))
        for frame, x in [(1, -1.2), (3, 1.2)]:
            red.location.x = x
            red.keyframe_insert("location", index=0, frame=frame)
        scene.frame_start, scene.frame_end = 1, 3
        scene.render.filepath = str(OUT / "anim_####")
        before = len(STARTED)
        start = time.perf_counter()
        bpy.ops.render.render(animation=True)
        print(f"Render Animation of 3 frames: {time.perf_counter() - start:.2f} s")
        self.assertEqual(len(STARTED) - before, 1, "one renderer process for the whole range")
        columns = []
        for frame in (1, 2, 3):
            image = read_exr(OUT / f"anim_{frame:04}.exr")
            redness = np.clip(image[..., 0] - image[..., 1:].max(axis=-1), 0, None)
            columns.append(redness.sum(axis=0) @ np.arange(image.shape[1]) / redness.sum())
        print(f"the red cube's column in frames 1, 2, 3: {columns}")
        self.assertLess(columns[0] + 5, columns[1])
        self.assertLess(columns[1] + 5, columns[2])


    def test_a_rig_shape_keys_under_a_modifier_a_zoom_and_a_keyed_light_under_a_world(self):
        """What once crashed the renderer (a keyed light under a world) and lost the shape keys (a
        modifier over them), in one Render Animation: an armature bending a red column, a green
        cube growing by its shape key under a Subdivision modifier, a zooming lens and a point
        light keyed from 200 to 800 W under a grey world. The frames render; the green cube grows
        (more pixels at frame 3 than at frame 1, beyond the zoom's share, which the column's size
        gives) and the floor brightens; the user's cube keeps its modifier and shape keys."""
        scene = glass_sphere_scene()
        world = bpy.data.worlds.new("Grey")
        world.node_tree.nodes["Background"].inputs["Color"].default_value = (0.2, 0.2, 0.2, 1.0)
        scene.world = world
        for obj in [obj for obj in scene.objects if obj.type == 'LIGHT']:
            bpy.data.objects.remove(obj)
        light = add(bpy.ops.object.light_add, type='POINT', location=(0, -1, 3))
        for frame, watts in ((1, 200.0), (3, 800.0)):
            light.data.energy = watts
            light.data.keyframe_insert("energy", frame=frame)
        cube = add(bpy.ops.mesh.primitive_cube_add, material("Green", (0.05, 0.8, 0.05)), size=0.5,
                   location=(1.2, 0.5, 0.25))
        cube.modifiers.new("Subdivision", 'SUBSURF').levels = 1
        cube.shape_key_add(name="Basis")
        grow = cube.shape_key_add(name="Grow")
        for point in grow.data:
            point.co *= 2.0
        for frame, value in ((1, 0.0), (3, 1.0)):
            grow.value = value
            grow.keyframe_insert("value", frame=frame)
        column = add(bpy.ops.mesh.primitive_cylinder_add, material("Red", (0.9, 0.05, 0.05)), radius=0.15, depth=1.0,
                     location=(-1.2, 0.5, 0.5))
        bpy.ops.object.armature_add(location=(-1.2, 0.5, 0.0))
        rig = bpy.context.object
        column.parent = rig
        parity_scenes.bind_to_bone(column, rig)
        bone = rig.pose.bones["Bone"]
        bone.rotation_mode = 'XYZ'
        for frame, angle in ((1, 0.0), (3, 0.5)):
            bone.rotation_euler.x = angle
            bone.keyframe_insert("rotation_euler", index=0, frame=frame)
        for frame, lens in ((1, 50.0), (3, 55.0)):
            scene.camera.data.lens = lens
            scene.camera.data.keyframe_insert("lens", frame=frame)
        scene.frame_start, scene.frame_end = 1, 3
        scene.render.filepath = str(OUT / "deform_####")
        bpy.ops.render.render(animation=True)
        frames = [read_exr(OUT / f"deform_{frame:04}.exr") for frame in (1, 2, 3)]
        self.assertTrue(all(np.all(np.isfinite(image)) for image in frames))
        green = [int(((image[..., 1] > 2 * image[..., 0]) & (image[..., 1] > 2 * image[..., 2])).sum())
                 for image in frames]
        print(f"the green cube's pixels in frames 1, 2, 3: {green}")
        self.assertGreater(green[2], 2.5 * green[0], "the shape key under the modifier did not grow the cube")
        self.assertGreater(luminance(frames[2]).mean(), 1.5 * luminance(frames[0]).mean())
        self.assertEqual([m.type for m in cube.modifiers], ['SUBSURF'])
        self.assertEqual(cube.name, "Cube")
        self.assertEqual([k.name for k in cube.data.shape_keys.key_blocks], ["Basis", "Grow"])


class Cancel(unittest.TestCase):
    def test_cancelling_ends_the_renderer_process(self):
        glass_sphere_scene().caustic.passes = 1_000_000
        asked = []

        def user_presses_esc(engine):
            asked.append(time.perf_counter())
            return len(asked) > 5

        ENGINE.cancelled, original = user_presses_esc, ENGINE.cancelled
        try:
            start = time.perf_counter()
            bpy.ops.render.render()
        finally:
            ENGINE.cancelled = original
        process = STARTED[-1].process
        print(f"cancelled after {time.perf_counter() - start:.2f} s; renderer exit code {process.returncode}")
        self.assertIsNotNone(process.returncode, "the renderer still runs")
        self.assertFalse(pathlib.Path(f"/proc/{process.pid}").exists(), "the renderer process is left behind")
        self.assertLess(time.perf_counter() - start, 60.0, "the render did not end when cancelled")


class Errors(unittest.TestCase):
    def test_a_wrong_program_path_fails_with_the_reason(self):
        glass_sphere_scene()
        preferences = bpy.context.preferences.addons["caustic"].preferences
        preferences.binary = "/no/such/caustic"
        try:
            with self.assertRaisesRegex(RuntimeError, "not an executable file: /no/such/caustic"):
                bpy.ops.render.render()
        finally:
            preferences.binary = BINARY

    def test_a_scene_the_renderer_rejects_fails_with_its_message(self):
        scene = glass_sphere_scene()
        dof = scene.camera.data.dof
        dof.use_dof, dof.aperture_fstop, dof.focus_distance = True, 2.8, 0.0
        with self.assertRaisesRegex(RuntimeError, "depth of field .* needs a positive focus distance"):
            bpy.ops.render.render()


class Export(unittest.TestCase):
    def test_what_the_exporter_drops_travels_in_the_extras(self):
        scene = glass_sphere_scene()
        scene.render.resolution_percentage = 50
        scene.render.use_motion_blur = True
        scene.render.motion_blur_shutter, scene.render.motion_blur_position = 0.25, 'START'
        scene.render.fps, scene.render.fps_base = 30, 1.001
        cam = scene.camera
        cam.data.dof.use_dof, cam.data.dof.aperture_fstop, cam.data.dof.focus_distance = True, 2.8, 4.5
        cam.data.dof.aperture_blades = 6
        light = bpy.data.objects["Area"]
        light.data.shape, light.data.size, light.data.size_y, light.data.color = 'RECTANGLE', 0.3, 0.2, (1, 0.5, 0.25)
        bpy.data.materials["Glass"].caustic.dispersion, bpy.data.materials["Glass"].caustic.abbe = 'ABBE', 30.0
        path = OUT / "extras" / "scene.gltf"
        path.parent.mkdir()
        sys.modules["caustic.export"].export(scene, path)
        gltf = json.loads(path.read_text())
        extras = gltf["scenes"][0]["extras"]["caustic"]
        self.assertEqual(extras["resolution"], [32, 24])
        self.assertAlmostEqual(extras["fps"], 30 / 1.001, places=4)
        self.assertEqual(extras["shutter"], {"length_frames": 0.25, "position": "START"})
        self.assertEqual(extras["camera"], cam.name)
        nodes = {n["name"]: n.get("extras", {}).get("caustic") for n in gltf["nodes"]}
        area = nodes["Area"]["area_light"]
        self.assertEqual((area["shape"], area["power"]), ("RECTANGLE", 60.0))
        np.testing.assert_allclose([area["size"], area["size_y"], *area["color"]], [0.3, 0.2, 1, 0.5, 0.25], rtol=1e-6)
        lens = nodes[cam.name]["lens"]
        self.assertEqual(lens["blades"], 6)
        np.testing.assert_allclose([lens["fstop"], lens["focus_distance"], lens["focal_length_mm"]], [2.8, 4.5, 50.0],
                                   rtol=1e-6)
        glass = next(m for m in gltf["materials"] if m["name"] == "Glass")
        self.assertEqual(glass["extras"]["caustic"], {"abbe": 30.0, "vertex_colours": False})
        # The operator farms run (`blender -b shot.blend --python-expr ...`) writes the same.
        operator_path = OUT / "extras" / "operator" / "scene.gltf"
        self.assertEqual(bpy.ops.caustic.export_scene(filepath=str(operator_path)), {'FINISHED'})
        self.assertEqual(json.loads(operator_path.read_text())["scenes"][0]["extras"], gltf["scenes"][0]["extras"])
        # The user's own glTF exports carry nothing of Caustic's.
        own = OUT / "extras" / "own.gltf"
        bpy.ops.export_scene.gltf(filepath=str(own), export_format='GLTF_SEPARATE', export_extras=True)
        self.assertNotIn("caustic", own.read_text())

    def test_volumes_travel_converted_exactly(self):
        """A Volume Absorption node (Color C, Density D) on a glass becomes KHR_materials_volume with
        attenuation distance 1/D and colour exp(-(1 - C)), which keeps exp(-(1 - C) D) per unit of
        length as Cycles does. A Principled Volume that scatters becomes a `caustic` medium
        (scattering Color * Density, absorption (1 - Color)(1 - sqrt(Absorption Color)) * Density);
        a Volume Scatter on an object without a surface becomes a medium inside a clear boundary of
        index 1; the world's Volume Scatter becomes the scene's fog; and Caustic reads them all."""
        scene = glass_sphere_scene()
        glass = bpy.data.materials["Glass"]
        nodes, links = glass.node_tree.nodes, glass.node_tree.links
        absorption = nodes.new("ShaderNodeVolumeAbsorption")
        absorption.inputs["Color"].default_value = (0.2, 0.6, 0.9, 1.0)
        absorption.inputs["Density"].default_value = 4.0
        links.new(absorption.outputs["Volume"], nodes["Material Output"].inputs["Volume"])
        principled = material("Smoky", transmission=1.0)
        add(bpy.ops.mesh.primitive_cube_add, principled, size=0.5, location=(2, 0, 0.25))
        volume = principled.node_tree.nodes.new("ShaderNodeVolumePrincipled")
        volume.inputs["Color"].default_value = (0.5, 0.5, 0.5, 1.0)
        volume.inputs["Absorption Color"].default_value = (0.25, 0.64, 1.0, 1.0)
        volume.inputs["Density"].default_value = 2.0
        principled.node_tree.links.new(volume.outputs["Volume"],
                                       principled.node_tree.nodes["Material Output"].inputs["Volume"])
        haze = material("Haze")
        add(bpy.ops.mesh.primitive_cube_add, haze, size=0.5, location=(-2, 0, 0.25))
        output = haze.node_tree.nodes["Material Output"]
        for link in list(output.inputs["Surface"].links):
            haze.node_tree.links.remove(link)
        scatter = haze.node_tree.nodes.new("ShaderNodeVolumeScatter")
        scatter.inputs["Color"].default_value = (0.8, 0.9, 1.0, 1.0)
        scatter.inputs["Density"].default_value = 0.5
        scatter.inputs["Anisotropy"].default_value = 0.3
        haze.node_tree.links.new(scatter.outputs["Volume"], output.inputs["Volume"])
        world = bpy.data.worlds.new("Foggy")
        scene.world = world
        fog = world.node_tree.nodes.new("ShaderNodeVolumeScatter")
        fog.inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)
        fog.inputs["Density"].default_value = 0.05
        world_output = next(n for n in world.node_tree.nodes if n.type == 'OUTPUT_WORLD')
        world.node_tree.links.new(fog.outputs["Volume"], world_output.inputs["Volume"])
        path = OUT / "volume" / "scene.gltf"
        path.parent.mkdir()
        try:
            sys.modules["caustic.export"].export(scene, path)
            warnings = sys.modules["caustic.unrendered"].scene_warnings(bpy.context.evaluated_depsgraph_get())
        finally:
            scene.world = None
        gltf = json.loads(path.read_text())
        materials = {m["name"]: m for m in gltf["materials"]}
        written = materials["Glass"]["extensions"]["KHR_materials_volume"]
        np.testing.assert_allclose(written["attenuationColor"], np.exp(-(1 - np.array([0.2, 0.6, 0.9]))), rtol=1e-6)
        self.assertAlmostEqual(written["attenuationDistance"], 0.25, places=6)
        self.assertGreater(written["thicknessFactor"], 0)
        smoky = materials["Smoky"]
        self.assertNotIn("KHR_materials_volume", smoky.get("extensions", {}))
        medium = smoky["extras"]["caustic"]["medium"]
        np.testing.assert_allclose(medium["scattering"], [1.0, 1.0, 1.0], rtol=1e-6)
        np.testing.assert_allclose(medium["absorption"], 0.5 * (1 - np.sqrt([0.25, 0.64, 1.0])) * 2.0, atol=1e-6)
        hazy = materials["Haze"]
        np.testing.assert_allclose(hazy["extras"]["caustic"]["medium"]["scattering"], [0.4, 0.45, 0.5], rtol=1e-6)
        self.assertAlmostEqual(hazy["extras"]["caustic"]["medium"]["anisotropy"], 0.3, places=6)
        self.assertEqual(hazy["extensions"]["KHR_materials_transmission"]["transmissionFactor"], 1.0)
        self.assertEqual(hazy["extensions"]["KHR_materials_ior"]["ior"], 1.0)
        np.testing.assert_allclose(gltf["scenes"][0]["extras"]["caustic"]["fog"]["scattering"], [0.05] * 3, rtol=1e-6)
        self.assertFalse([w for w in warnings if "volume" in w or "Volume" in w], warnings)
        info = json.loads(subprocess.run([BINARY, "info", str(path)], check=True,
                                         capture_output=True, text=True).stdout)
        self.assertTrue(info["needs"]["scattering"])
        self.assertEqual(sorted(m["material"] for m in info["media"]["materials"]), ["Glass", "Haze", "Smoky"])
        self.assertAlmostEqual(info["media"]["fog"]["scattering_550nm"], 0.05, places=4)

    def test_what_is_not_rendered_of_lights_and_cameras_is_named(self):
        scene = glass_sphere_scene()
        area = bpy.data.objects["Area"].data
        area.spread = math.radians(0.5)
        scene.camera.data.type, scene.camera.data.panorama_type = 'PANO', 'FISHEYE_EQUISOLID'
        try:
            warnings = sys.modules["caustic.unrendered"].scene_warnings(bpy.context.evaluated_depsgraph_get())
        finally:
            area.spread, scene.camera.data.type = math.pi, 'PERSP'
        self.assertIn("light 'Area': a Spread under 1 degree is rendered as 1 degree", warnings)
        self.assertIn(f"camera '{scene.camera.name}': the FISHEYE_EQUISOLID panorama is not rendered (Equirectangular "
                      "is); Caustic finds no camera to render with", warnings)

    def test_an_area_lights_spread_and_camera_visibility_are_exported(self):
        """Blender's Spread and Ray Visibility > Camera reach the renderer in the light's extras."""
        scene = glass_sphere_scene()
        light = bpy.data.objects["Area"]
        light.data.spread, light.visible_camera = math.radians(40), False
        path = OUT / "spread" / "scene.gltf"
        path.parent.mkdir()
        try:
            sys.modules["caustic.export"].export(scene, path)
        finally:
            light.data.spread, light.visible_camera = math.pi, True
        extras = {n["name"]: n.get("extras", {}).get("caustic") for n in json.loads(path.read_text())["nodes"]}
        self.assertAlmostEqual(extras["Area"]["area_light"]["spread_deg"], 40.0, places=4)
        self.assertIs(extras["Area"]["visible_to_camera"], False)

    def test_a_light_with_a_colour_temperature_exports_and_keeps_it(self):
        """Blender's glTF exporter raises on a light with a colour temperature; the add-on's export
        succeeds, writes the temperature in the light's extras and leaves the light as it was."""
        scene = glass_sphere_scene()
        light = bpy.data.objects["Area"]
        light.data.use_temperature, light.data.temperature = True, 3200.0
        path = OUT / "temperature" / "scene.gltf"
        path.parent.mkdir()
        sys.modules["caustic.export"].export(scene, path)
        nodes = {n["name"]: n.get("extras", {}).get("caustic") for n in json.loads(path.read_text())["nodes"]}
        self.assertEqual(nodes["Area"]["temperature_k"], 3200.0)
        self.assertTrue(light.data.use_temperature)
        self.assertEqual(light.data.temperature, 3200.0)

    def test_lights_without_normalize_export_with_the_power_cycles_gives_them(self):
        """Blender's exporter raises a TypeError on a light whose Normalize is off; the add-on's
        export succeeds, the point light's intensity and the area light's power are their Power
        times their area (4 pi r^2 for a point of radius r, the square's side squared), and the
        lights are left as they were."""
        scene = glass_sphere_scene()
        area = bpy.data.objects["Area"]
        area.data.normalize = False
        point = add(bpy.ops.object.light_add, type='POINT', location=(1, 1, 2))
        point.data.energy, point.data.shadow_soft_size, point.data.normalize = 100.0, 0.5, False
        path = OUT / "unnormalized" / "scene.gltf"
        path.parent.mkdir()
        sys.modules["caustic.export"].export(scene, path)
        gltf = json.loads(path.read_text())
        nodes = {n["name"]: n for n in gltf["nodes"]}
        light = gltf["extensions"]["KHR_lights_punctual"]["lights"][nodes[point.name]["extensions"]["KHR_lights_punctual"]["light"]]
        watts = 100.0 * 4 * math.pi * 0.5 ** 2
        self.assertAlmostEqual(light["intensity"], watts * 683 / (4 * math.pi), delta=1e-3 * light["intensity"])
        self.assertAlmostEqual(nodes["Area"]["extras"]["caustic"]["area_light"]["power"], 60.0 * 0.1 ** 2, places=4)
        self.assertEqual((point.data.energy, point.data.normalize), (100.0, False))
        self.assertEqual((area.data.energy, area.data.normalize), (60.0, False))

    def test_a_node_group_without_a_group_output_exports_with_a_warning(self):
        """Blender's exporter raises an IndexError on a material whose node group has no Group
        Output; the add-on's export succeeds, names the group in a warning, and leaves the group as
        it was."""
        scene = glass_sphere_scene()
        group = bpy.data.node_groups.new("No output", "ShaderNodeTree")
        group.interface.new_socket("Colour", in_out='OUTPUT', socket_type='NodeSocketColor')
        floor = bpy.data.materials["Floor"]
        node = floor.node_tree.nodes.new("ShaderNodeGroup")
        node.node_tree = group
        floor.node_tree.links.new(node.outputs[0], floor.node_tree.nodes["Principled BSDF"].inputs["Base Color"])
        path = OUT / "no-output" / "scene.gltf"
        path.parent.mkdir()
        sys.modules["caustic.export"].export(scene, path)
        self.assertTrue(path.exists())
        self.assertEqual([n.type for n in group.nodes], [])
        warnings = sys.modules["caustic.unrendered"].scene_warnings(bpy.context.evaluated_depsgraph_get())
        self.assertTrue(any("node group 'No output' has no Group Output" in w for w in warnings), warnings)

    def test_procedural_inputs_are_baked_and_other_surfaces_named(self):
        """A Checker Texture through a ColorRamp on the Base Color is baked by Blender into the
        image the exported material reads (the user's material keeps its nodes), and named; a Mix
        Shader surface is named in a warning that says what is not rendered."""
        glass_sphere_scene()
        floor = bpy.data.materials["Floor"]
        nodes, links = floor.node_tree.nodes, floor.node_tree.links
        checker, ramp = nodes.new("ShaderNodeTexChecker"), nodes.new("ShaderNodeValToRGB")
        links.new(checker.outputs["Fac"], ramp.inputs["Fac"])
        links.new(ramp.outputs["Color"], nodes["Principled BSDF"].inputs["Base Color"])
        mixed = bpy.data.materials["Glass"]
        mix = mixed.node_tree.nodes.new("ShaderNodeMixShader")
        mixed.node_tree.links.new(mix.outputs[0], mixed.node_tree.nodes["Material Output"].inputs["Surface"])
        warnings = sys.modules["caustic.unrendered"].scene_warnings(bpy.context.evaluated_depsgraph_get())
        self.assertIn("material 'Floor': its Base Color comes through nodes glTF cannot hold (Checker Texture, "
                      "Color Ramp); Blender bakes it into an image (Render Properties > Caustic > Bake Size)",
                      warnings)
        self.assertTrue(any(w.startswith("material 'Glass': the mix of its shaders") for w in warnings), warnings)
        before = sorted(n.name for n in nodes)
        path = OUT / "baked-inputs" / "scene.gltf"
        path.parent.mkdir()
        sys.modules["caustic.export"].export(bpy.context.scene, path)
        gltf = json.loads(path.read_text())
        floor_material = next(m for m in gltf["materials"] if m["name"] == "Floor")
        texture = floor_material["pbrMetallicRoughness"]["baseColorTexture"]["index"]
        image = gltf["images"][gltf["textures"][texture]["source"]]
        self.assertEqual(image["extras"]["caustic"]["colour_space"], "linear")
        self.assertEqual(sorted(n.name for n in nodes), before, "the user's material keeps its nodes")

    def test_curves_text_metaballs_and_vertex_instances_are_written_once(self):
        """What Blender evaluates to meshes (a bevelled curve, extruded text, a metaball) and a cube
        instanced on a plane's four vertices are each written once: with Geometry Nodes output on,
        Blender's exporter wrote the curve's and the text's meshes twice and the four cubes twice
        (surfaces over surfaces)."""
        scene = clear_scene()
        plane = add(bpy.ops.mesh.primitive_plane_add, size=2)
        cube = add(bpy.ops.mesh.primitive_cube_add, size=0.2)
        cube.parent, plane.instance_type = plane, 'VERTS'
        add(bpy.ops.object.metaball_add, location=(3, 0, 0))
        curve = add(bpy.ops.curve.primitive_bezier_circle_add, location=(-3, 0, 0))
        curve.data.bevel_depth = 0.1
        text = add(bpy.ops.object.text_add, location=(0, 3, 0))
        text.data.extrude = 0.05
        camera((0, -8, 5), (0, 0, 0))
        path = OUT / "written-once" / "scene.gltf"
        path.parent.mkdir()
        sys.modules["caustic.export"].export(scene, path)
        gltf = json.loads(path.read_text())
        drawn = collections.Counter()
        for node in gltf["nodes"]:
            if "mesh" in node:
                instancing = node.get("extensions", {}).get("EXT_mesh_gpu_instancing")
                count = gltf["accessors"][instancing["attributes"]["TRANSLATION"]]["count"] if instancing else 1
                drawn[gltf["meshes"][node["mesh"]]["name"]] += count
        self.assertEqual(drawn, {"Plane": 1, "Cube": 4, "BézierCircle": 1, "Text": 1, "Mesh": 1}, drawn)

    def test_an_exporter_failure_names_blender_the_exception_and_where(self):
        """What Blender's exporter raises reaches the user as one sentence: Blender's version, the
        exception and the place in the exporter, not a traceback."""
        traceback = ('Error: Python: Traceback (most recent call last):\n'
                     '  File "/x/io_scene_gltf2/blender/exp/material/search_node_tree.py", line 85, in f\n'
                     '    group_output_node = [...][0]\n'
                     'IndexError: list index out of range\n'
                     'Location: /x/bpy/ops.py:109')
        message = sys.modules["caustic.workarounds"].exporter_failure(RuntimeError(traceback))
        self.assertIn(f"Blender {bpy.app.version_string}'s glTF exporter failed in "
                      "blender/exp/material/search_node_tree.py:85: IndexError: list index out of range", message)


def environment_world(img, rotation_deg=0.0, vector_type='POINT'):
    """A world whose Background (strength 2) shows `img` through a Mapping node turned about Z."""
    world = bpy.data.worlds.new("Sky")
    nodes, links = world.node_tree.nodes, world.node_tree.links
    environment = nodes.new("ShaderNodeTexEnvironment")
    environment.image = img
    mapping = nodes.new("ShaderNodeMapping")
    mapping.vector_type = vector_type
    mapping.inputs["Rotation"].default_value = (0.0, 0.0, math.radians(rotation_deg))
    links.new(nodes.new("ShaderNodeTexCoord").outputs["Generated"], mapping.inputs["Vector"])
    links.new(mapping.outputs["Vector"], environment.inputs["Vector"])
    links.new(environment.outputs["Color"], nodes["Background"].inputs["Color"])
    nodes["Background"].inputs["Strength"].default_value = 2.0
    bpy.context.scene.world = world
    return world


class World(unittest.TestCase):
    def test_an_environment_texture_travels_as_a_linear_exr_beside_the_scene(self):
        """A packed 8-bit sRGB image becomes a linear EXR in the export folder, with the Background's
        strength and the Mapping node's turn (the other way for a Point mapping)."""
        scene = glass_sphere_scene()
        values = np.array([[25, 128, 230, 255], [77, 51, 179, 255], [255, 0, 64, 255], [153, 153, 153, 255]]) / 255
        img = bpy.data.images.new("packed-sky", 2, 2, alpha=True)
        img.pixels.foreach_set(values.astype(np.float32).ravel())
        img.pack()
        environment_world(img, rotation_deg=30.0, vector_type='TEXTURE')
        path = OUT / "environment" / "scene.gltf"
        path.parent.mkdir()
        sys.modules["caustic.export"].export(scene, path)
        world = json.loads(path.read_text())["scenes"][0]["extras"]["caustic"]["world"]
        self.assertEqual(world["image"], "environment.exr")
        np.testing.assert_allclose([world["strength"], world["rotation_deg"]], [2.0, 30.0], rtol=1e-6)
        written = OpenEXR.File(str(path.parent / world["image"])).channels()
        pixels = next(iter(written.values())).pixels[::-1].reshape(-1, 3)  # bottom row first, as Blender's
        srgb = values[:, :3]
        linear = np.where(srgb <= 0.04045, srgb / 12.92, ((srgb + 0.055) / 1.055) ** 2.4)
        np.testing.assert_allclose(pixels, linear, rtol=1e-5)
        environment_world(img, rotation_deg=30.0, vector_type='POINT')
        sys.modules["caustic.export"].export(scene, path)
        world = json.loads(path.read_text())["scenes"][0]["extras"]["caustic"]["world"]
        self.assertAlmostEqual(world["rotation_deg"], -30.0, places=4)

    def test_an_environment_image_that_cannot_be_read_is_magenta_and_named(self):
        """As Cycles renders it: the world is magenta (the floor lit by it has no green), the render
        goes on, and the warning names the image and its file."""
        scene = glass_sphere_scene()
        img = bpy.data.images.new("lost-sky", 4, 2, float_buffer=True)
        img.filepath = str(OUT / "no-such-folder" / "sky.hdr")
        img.source = 'FILE'
        environment_world(img)
        warnings = sys.modules["caustic.unrendered"].scene_warnings(bpy.context.evaluated_depsgraph_get())
        self.assertTrue(any("'lost-sky'" in w and "no-such-folder/sky.hdr" in w and "magenta" in w
                            for w in warnings), warnings)
        for light in [obj for obj in scene.objects if obj.type == 'LIGHT']:
            light.hide_render = True
        pixels = render_still("lost-sky")
        r, g, b = pixels.reshape(-1, 3).mean(axis=0)
        self.assertGreater(min(r, b), 0.1)
        self.assertLess(g, 0.01 * min(r, b))

    def test_a_world_read_no_other_way_is_baked_by_blender(self):
        """A Mix Shader of a red and a blue Background (a quarter blue) is baked by Cycles into an
        equirectangular image beside the scene: three quarters red and a quarter blue everywhere."""
        scene = glass_sphere_scene()
        world = bpy.data.worlds.new("Mixed")
        nodes, links = world.node_tree.nodes, world.node_tree.links
        red, blue, mix = nodes["Background"], nodes.new("ShaderNodeBackground"), nodes.new("ShaderNodeMixShader")
        red.inputs["Color"].default_value, blue.inputs["Color"].default_value = (1, 0, 0, 1), (0, 0, 1, 1)
        mix.inputs["Fac"].default_value = 0.25
        links.new(red.outputs[0], mix.inputs[1])
        links.new(blue.outputs[0], mix.inputs[2])
        links.new(mix.outputs[0], nodes["World Output"].inputs["Surface"])
        scene.world = world
        path = OUT / "baked" / "scene.gltf"
        path.parent.mkdir()
        sys.modules["caustic.export"].export(scene, path)
        extras = json.loads(path.read_text())["scenes"][0]["extras"]["caustic"]["world"]
        self.assertEqual(extras["image"], "world.exr")
        pixels = next(iter(OpenEXR.File(str(path.parent / "world.exr")).channels().values())).pixels[..., :3]
        self.assertEqual(pixels.shape[:2], (512, 1024))
        np.testing.assert_allclose(pixels.reshape(-1, 3).mean(axis=0), [0.75, 0.0, 0.25], atol=0.005)

    def test_a_baked_world_is_baked_again_only_when_it_changes(self):
        """A Sky Texture's bake is kept: exporting again reuses it (the same bytes, no second
        Blender), until the sun moves."""
        worlds = sys.modules["caustic.world"]
        scene = glass_sphere_scene()
        world = bpy.data.worlds.new("Cached sky")
        sky = world.node_tree.nodes.new("ShaderNodeTexSky")
        world.node_tree.links.new(sky.outputs["Color"], world.node_tree.nodes["Background"].inputs["Color"])
        scene.world = world
        folders = [OUT / f"cached-{i}" for i in range(2)]
        for folder in folders:
            folder.mkdir()
        worlds.bake_world(world, folders[0], width=64)
        cached = worlds.WORLD_CACHE / f"{worlds.world_fingerprint(world, 64)}.exr"
        self.assertTrue(cached.exists())
        # Marked, the kept bake shows where the next export's image comes from.
        cached.write_bytes(cached.read_bytes() + b"kept")
        worlds.bake_world(world, folders[1], width=64)
        self.assertTrue((folders[1] / "world.exr").read_bytes().endswith(b"kept"))
        cached.unlink()
        before = worlds.world_fingerprint(world, 64)
        sky.sun_elevation += 0.1
        self.assertNotEqual(worlds.world_fingerprint(world, 64), before)
        world.node_tree.nodes["Background"].inputs["Strength"].default_value = 3.0
        sky.sun_elevation -= 0.1
        self.assertNotEqual(worlds.world_fingerprint(world, 64), before)
        world.node_tree.nodes["Background"].location = (500.0, 0.0)
        world.node_tree.nodes["Background"].inputs["Strength"].default_value = 1.0
        self.assertEqual(worlds.world_fingerprint(world, 64), before, "moving a node changes no bake")


if __name__ == "__main__":
    unittest.main(verbosity=2)
