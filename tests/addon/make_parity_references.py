"""Renders the Cycles references for the parity tests (tests/addon/parity_scenes.py) into
tests/references/parity/<scene>.exr, and their provenance into tests/references/parity/README.json:

    target/bpy-venv/bin/python tests/addon/make_parity_references.py [--samples 4096] [SCENE ...]

Cycles on the CPU, the scene's resolution (64x64 for most), a 1-pixel box filter, no denoising, no adaptive sampling,
no glossy filter, no clamping (Blender's default clamps indirect samples at 10, which darkens
caustics: light under a clear glass block read 19% of Cycles' own unclamped value), 32 bounces of
every kind; a scene of parity_scenes.FRAMES gets one reference a frame, <scene>_<frame>.exr; each EXR holds `Combined.R/G/B` and `Index.X` (the
object-index pass: which object each pixel sees), and for the scenes of parity_scenes.ALPHA
`Alpha.X` (Cycles' alpha).
"""
import argparse
import datetime
import json
import os
import pathlib
import sys
import tempfile

os.environ["HOME"] = tempfile.mkdtemp(prefix="caustic-parity-home-")
import bpy  # noqa: E402
import numpy as np  # noqa: E402
import OpenEXR  # noqa: E402

HERE = pathlib.Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
import parity_scenes  # noqa: E402

OUT = HERE.parents[0] / "references" / "parity"


def render_cycles(samples, path):
    scene = bpy.context.scene
    scene.render.engine = 'CYCLES'
    cycles = scene.cycles
    cycles.device, cycles.samples = 'CPU', samples
    cycles.use_adaptive_sampling = cycles.use_denoising = False
    cycles.pixel_filter_type, cycles.filter_width, cycles.blur_glossy = 'BOX', 1.0, 0.0
    cycles.sample_clamp_direct = cycles.sample_clamp_indirect = 0.0
    for bounces in ("max_bounces", "diffuse_bounces", "glossy_bounces", "transmission_bounces",
                    "transparent_max_bounces"):
        setattr(cycles, bounces, 32)
    bpy.context.view_layer.use_pass_object_index = True
    scene.render.image_settings.media_type = 'MULTI_LAYER_IMAGE'
    scene.render.image_settings.file_format = 'OPEN_EXR_MULTILAYER'
    scene.render.image_settings.color_depth = '32'
    scene.render.filepath = str(path)
    bpy.ops.render.render(write_still=True)
    # Blender 5.0 writes each pass as its own part.
    channels = {k: v for part in OpenEXR.File(str(path)).parts for k, v in part.channels.items()}
    combined = next(v for k, v in channels.items() if k.endswith("Combined"))
    index = next(v for k, v in channels.items() if k.endswith("Object Index.X"))
    return combined.pixels[..., :3], combined.pixels[..., 3], index.pixels.reshape(combined.pixels.shape[:2])


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--samples", type=int, default=4096)
    parser.add_argument("scenes", nargs="*", default=sorted(parity_scenes.SCENES))
    args = parser.parse_args()
    OUT.mkdir(parents=True, exist_ok=True)
    provenance_path = OUT / "README.json"
    provenance = json.loads(provenance_path.read_text()) if provenance_path.exists() else {}
    for name in args.scenes:
        parity_scenes.SCENES[name]()
        frames = parity_scenes.FRAMES.get(name)
        for frame in frames or [None]:
            if frame is not None:
                bpy.context.scene.frame_set(frame)
            with tempfile.TemporaryDirectory() as tmp:
                rgb, alpha, index = render_cycles(args.samples, pathlib.Path(tmp) / "cycles.exr")
            channels = {"Combined": rgb.astype(np.float32), "Index.X": index.astype(np.float32)}
            if name in parity_scenes.ALPHA:
                channels["Alpha.X"] = alpha.astype(np.float32)
            file = f"{name}.exr" if frame is None else f"{name}_{frame}.exr"
            OpenEXR.File({"compression": OpenEXR.ZIP_COMPRESSION}, channels).write(str(OUT / file))
            print(f"{file}: mean {rgb.mean(axis=(0, 1))}")
        scene = bpy.context.scene
        provenance[name] = {
            "renderer": f"Cycles (bpy {bpy.app.version_string}), CPU",
            "samples": args.samples,
            "settings": f"{scene.render.resolution_x}x{scene.render.resolution_y}, 1-pixel box filter, no denoising, "
                        "no adaptive sampling, no glossy filter, no clamping, 32 bounces",
            "scene": f"tests/addon/parity_scenes.py: {name}()",
            "made": datetime.date.today().isoformat(),
        }
        if frames:
            provenance[name]["frames"] = frames
    provenance_path.write_text(json.dumps(provenance, indent=1, sort_keys=True) + "\n")


if __name__ == "__main__":
    main()
