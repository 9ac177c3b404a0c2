"""Blender parity: scenes built in bpy as an artist builds them (tests/addon/parity_scenes.py),
rendered by Caustic through the add-on, against Cycles' renders of the same scenes (committed in
tests/references/parity/, made by make_parity_references.py; provenance in README.json there).

For each scene: every named object's mean radiance (its pixels away from its outline, by Cycles'
object-index pass) within 5% of Cycles' in each channel, and the median over 8x8-pixel blocks of
the relative difference of luminance under 5% (7% for scenes whose references are noisier, with
caustics: parity_scenes.TOLERANCES), and some regions' colour within 3% (parity_scenes.COLOURS).
Caustic renders PASSES passes of one photon a pixel (parity_scenes.PASSES and PHOTONS give some
scenes more); at that count its noise in an object's mean is well under 1%. A failing scene leaves Caustic's image, Cycles' and
their difference side by side in a PNG, named in the failure.
"""
import os
import pathlib
import sys
import tempfile
import unittest

HOME = tempfile.mkdtemp(prefix="caustic-parity-home-")
os.environ["HOME"] = HOME

import bpy  # noqa: E402
import numpy as np  # noqa: E402
import OpenEXR  # noqa: E402

HERE = pathlib.Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
import parity_scenes  # noqa: E402
from enable_addon import enable_addon  # noqa: E402

ROOT = HERE.parents[1]
REFERENCES = ROOT / "tests" / "references" / "parity"
BINARY = os.environ["CAUSTIC_BINARY"]
OUT = pathlib.Path(tempfile.mkdtemp(prefix="caustic-parity-out-"))
PASSES = 256
TOLERANCE = 0.05
LUMINANCE = np.array([0.2126, 0.7152, 0.0722])


def use_caustic(name, filepath):
    """Caustic as the engine at the scene's pass count, writing 32-bit EXRs to `filepath`."""
    scene = bpy.context.scene
    scene.render.engine = 'CAUSTIC'
    scene.caustic.passes = parity_scenes.PASSES.get(name, PASSES)
    scene.caustic.photons = parity_scenes.PHOTONS.get(name, 0)
    scene.render.image_settings.media_type = 'IMAGE'
    scene.render.image_settings.file_format = 'OPEN_EXR'
    scene.render.image_settings.color_depth = '32'
    scene.render.filepath = str(filepath)
    return scene


def render_caustic(name):
    scene = use_caustic(name, OUT / f"{name}.exr")
    bpy.ops.render.render(write_still=True)
    rgba = OpenEXR.File(scene.render.filepath).channels()["RGBA"].pixels.astype(np.float64)
    return rgba[..., :3], rgba[..., 3]


def render_animation(name):
    """Renders the scene's frame range through Render Animation; gives each frame's RGB."""
    use_caustic(name, OUT / f"{name}_####")
    bpy.ops.render.render(animation=True)
    read = lambda frame: OpenEXR.File(str(OUT / f"{name}_{frame:04d}.exr")).channels()["RGBA"].pixels
    return {frame: read(frame)[..., :3].astype(np.float64) for frame in parity_scenes.FRAMES[name]}


def silhouette_iou(image, reference):
    """The intersection over union of the two images' dark silhouettes (under a quarter of the
    reference's median luminance), and how many pixels the reference's covers."""
    threshold = 0.25 * np.median(reference @ LUMINANCE)
    ours, theirs = image @ LUMINANCE < threshold, reference @ LUMINANCE < threshold
    return float((ours & theirs).sum() / max((ours | theirs).sum(), 1)), int(theirs.sum())


def read_reference(name):
    channels = OpenEXR.File(str(REFERENCES / f"{name}.exr")).channels()
    alpha = channels["Alpha.X"].pixels.astype(np.float64) if "Alpha.X" in channels else None
    return channels["Combined"].pixels.astype(np.float64), channels["Index.X"].pixels, alpha


def block_median_difference(image, reference, block=8):
    h, w = reference.shape[:2]
    means = lambda x: (x @ LUMINANCE).reshape(h // block, block, w // block, block).mean(axis=(1, 3))
    a, b = means(image), means(reference)
    return float(np.median(np.abs(a - b) / np.maximum(b, 1e-3 * b.max())))


def peak_distance(image, reference, mask):
    """How far apart (pixels) the brightest pixels of `image` and `reference` within `mask` are."""
    where = lambda x: np.array(np.unravel_index(np.argmax(np.where(mask, x @ LUMINANCE, -1.0)), mask.shape))
    return float(np.linalg.norm(where(image) - where(reference)))


def dilated(mask):
    """`mask` grown by one pixel in every direction (diagonals too)."""
    padded = np.pad(mask, 1)
    h, w = mask.shape
    return np.any([padded[1 + dy:1 + dy + h, 1 + dx:1 + dx + w] for dy in (-1, 0, 1) for dx in (-1, 0, 1)], axis=0)


def silhouette_mismatch(image, reference):
    """The pixels of either image's silhouette (under half the reference's median luminance)
    farther than one pixel from the other's, and how many pixels the reference's covers."""
    threshold = 0.5 * np.median(reference @ LUMINANCE)
    ours, theirs = image @ LUMINANCE < threshold, reference @ LUMINANCE < threshold
    return int((ours & ~dilated(theirs)).sum() + (theirs & ~dilated(ours)).sum()), int(theirs.sum())


def save_sheet(name, image, reference):
    """Caustic, Cycles and 4x their difference side by side, in sRGB, each pixel 4 x 4."""
    difference = np.abs(image - reference) * 4.0
    sheet = np.concatenate([image, reference, difference], axis=1).repeat(4, axis=0).repeat(4, axis=1)
    srgb = np.where(sheet <= 0.0031308, 12.92 * sheet, 1.055 * np.power(np.clip(sheet, 0, None), 1 / 2.4) - 0.055)
    pixels = (np.clip(srgb, 0, 1) * 255 + 0.5).astype(np.uint8)
    h, w = pixels.shape[:2]
    img = bpy.data.images.new(f"{name}-sheet", w, h, alpha=True)
    rgba = np.concatenate([pixels, np.full((h, w, 1), 255, np.uint8)], axis=2)[::-1].astype(np.float32) / 255
    img.pixels.foreach_set(rgba.ravel())
    img.filepath_raw = str(OUT / f"{name}-sheet.png")
    img.file_format = 'PNG'
    img.save()
    return img.filepath_raw


class Parity(unittest.TestCase):
    def check_frames(self, name):
        """Each frame of parity_scenes.FRAMES[name], rendered in one Render Animation: every named
        object's mean within 5% of Cycles', the silhouettes' intersection over union at least 0.97,
        and the block median difference under 5%."""
        objects = parity_scenes.SCENES[name]()
        images = render_animation(name)
        failures = []
        for frame, image in images.items():
            reference, index, _ = read_reference(f"{name}_{frame}")
            sheet = save_sheet(f"{name}_{frame}", image, reference)
            for obj, value in objects.items():
                mask = parity_scenes.interior(index, value)
                self.assertGreater(mask.sum(), 20, f"{name} frame {frame}: '{obj}' covers too few pixels")
                ours, theirs = image[mask].mean(axis=0), reference[mask].mean(axis=0)
                ratio = ours / np.maximum(theirs, 1e-6)
                print(f"{name} frame {frame}: '{obj}' Caustic {ours.round(4)} Cycles {theirs.round(4)} "
                      f"ratio {ratio.round(3)}")
                if np.any(np.abs(ratio - 1) > TOLERANCE):
                    failures.append(f"frame {frame} '{obj}': Caustic {ours} against Cycles {theirs}")
            iou, covered = silhouette_iou(image, reference)
            median = block_median_difference(image, reference)
            print(f"{name} frame {frame}: silhouettes' intersection over union {iou:.3f} ({covered} pixels), "
                  f"block median difference {median:.4f} (sheet {sheet})")
            self.assertGreater(covered, 100, f"{name} frame {frame}: the silhouettes cover too few pixels")
            if iou < 0.97:
                failures.append(f"frame {frame}: silhouettes' intersection over union {iou:.3f}")
            if median > TOLERANCE:
                failures.append(f"frame {frame}: block median difference {median:.3f}")
        self.assertEqual(failures, [], f"{name} differs from Cycles (sheets in {OUT})")

    def test_animated(self):
        self.check_frames("animated")

    def check(self, name):
        objects = parity_scenes.SCENES[name]()
        tolerance = parity_scenes.TOLERANCES.get(name, TOLERANCE)
        colours = parity_scenes.COLOURS.get(name, {})
        peaks = parity_scenes.PEAKS.get(name, {})
        image, alpha = render_caustic(name)
        reference, index, reference_alpha = read_reference(name)
        sheet = save_sheet(name, image, reference)
        failures = []
        for obj, value in objects.items():
            mask = value(index, reference) if callable(value) else parity_scenes.interior(index, value)
            self.assertGreater(mask.sum(), 20, f"{name}: '{obj}' covers too few pixels")
            ours, theirs = image[mask].mean(axis=0), reference[mask].mean(axis=0)
            ratio = ours / np.maximum(theirs, 1e-6)
            if obj in parity_scenes.DIM_CHANNELS.get(name, ()):
                dim = theirs < 0.03 * theirs.max()
                ratio[dim] = 1 + (ours[dim] - theirs[dim]) / theirs.max()
            print(f"{name}: '{obj}' Caustic {ours.round(4)} Cycles {theirs.round(4)} ratio {ratio.round(3)}")
            if np.any(np.abs(ratio - 1) > tolerance):
                failures.append(f"'{obj}': Caustic {ours} against Cycles {theirs}")
            if obj in colours:
                shares = ours / ours.sum() / (theirs / theirs.sum())
                print(f"{name}: '{obj}' colour, Caustic's shares over Cycles' {shares.round(3)}")
                if np.any(np.abs(shares - 1) > colours[obj]):
                    failures.append(f"'{obj}' colour: Caustic's channel shares {shares} of Cycles'")
            if obj in peaks:
                distance = peak_distance(image, reference, mask)
                print(f"{name}: '{obj}' brightest pixel {distance:.1f} px from Cycles'")
                if distance > peaks[obj]:
                    failures.append(f"'{obj}': the brightest pixel lies {distance:.1f} px from Cycles'")
        if name in parity_scenes.SILHOUETTES:
            stray, covered = silhouette_mismatch(image, reference)
            print(f"{name}: {stray} silhouette pixels more than 1 px from Cycles' ({covered} pixels)")
            self.assertGreater(covered, 50, f"{name}: the silhouettes cover too few pixels")
            if stray:
                failures.append(f"{stray} silhouette pixels lie more than 1 px from Cycles'")
        if name in parity_scenes.ALPHA:
            difference = np.abs(alpha - reference_alpha)
            print(f"{name}: alpha differs from Cycles' by {difference.mean():.4f} on average, {difference.max():.3f} "
                  f"at most (Caustic's mean {alpha.mean():.3f}, Cycles' {reference_alpha.mean():.3f})")
            if difference.mean() > 0.02 or difference.max() > 0.25:
                failures.append(f"alpha differs from Cycles' by {difference.mean():.3f} on average, "
                                f"{difference.max():.3f} at most")
        median = block_median_difference(image, reference)
        print(f"{name}: block median difference {median:.4f} (sheet {sheet})")
        if median > tolerance:
            failures.append(f"block median difference {median:.3f}")
        self.assertEqual(failures, [], f"{name} differs from Cycles (sheet: {sheet})")

    def test_ortho_camera(self):
        self.check("ortho_camera")

    def test_shifted_camera(self):
        self.check("shifted_camera")

    def test_panorama_camera(self):
        self.check("panorama_camera")

    def test_film_and_holdouts(self):
        self.check("film_and_holdouts")

    def test_lights_seen(self):
        self.check("lights_seen")

    def test_spread_light(self):
        self.check("spread_light")

    def test_soft_falloff(self):
        self.check("soft_falloff")

    def test_soft_spot(self):
        self.check("soft_spot")

    def test_spot_light(self):
        self.check("spot_light")

    def test_sky(self):
        self.check("sky")

    def test_hdri(self):
        self.check("hdri")

    def test_glass(self):
        self.check("glass")

    def test_soft_light(self):
        self.check("soft_light")

    def test_warm_light(self):
        self.check("warm_light")

    def test_principled_spheres(self):
        self.check("principled_spheres")

    def test_textured(self):
        self.check("textured")

    def test_coated(self):
        self.check("coated")

    def test_leaf(self):
        self.check("leaf")

    def test_sheen(self):
        self.check("sheen")

    def test_normal_mapped(self):
        self.check("normal_mapped")

    def test_rigged(self):
        self.check("rigged")

    def test_attributes_and_images(self):
        self.check("attributes_and_images")

    def test_instances_and_points(self):
        self.check("instances_and_points")

    def test_normal_map_strengths(self):
        self.check("normal_map_strengths")

    def test_simple_surfaces(self):
        self.check("simple_surfaces")

    def test_baked_textures(self):
        self.check("baked_textures")

    def test_baked_bump(self):
        self.check("baked_bump")


if __name__ == "__main__":
    enable_addon(BINARY)
    unittest.main(argv=[sys.argv[0], "-v", *sys.argv[1:]])
