"""Caustic's fog against Mitsuba 3's volumetric path tracer (`volpath`, `scalar_spectral`) on one
scene: a spot light straight down into fog over a grey floor, seen from the side (a benchmark, not
a test: run it by hand, release build first; Mitsuba 3 from PyPI in a virtual environment):

    cargo build --release
    python3.11 -m venv /tmp/mi && /tmp/mi/bin/pip install mitsuba numpy
    /tmp/mi/bin/python tests/bench/vs_mitsuba_fog.py [--spp 4096] [--passes 4096] [-o bench-out/fog]

Both renderers see the same scene: the spot (1 W/sr at its centre, Mitsuba's `intensity`, and 683
cd in glTF, Caustic's light units), its cone (Mitsuba's `cutoff_angle` and `beam_width` as glTF's
outer and inner cone angles, 0.1 degree apart: Mitsuba's falloff between them is linear in the
angle, glTF's the square of a ramp in its cosine, and over 16 to 20 degrees that alone made
Caustic's whole image 6.5% darker), the floor (albedo 0.5), the fog (scattering 0.15 and absorption 0.01
per unit, isotropic) around everything, the camera inside it. Prints the median, over 8 x 8 pixel
blocks that are not black in either image, of the blocks' relative difference in luminance, and
writes both images and OUT/results.json.
"""
import argparse
import base64
import json
import math
import pathlib
import struct
import subprocess
import time

import numpy as np

ROOT = pathlib.Path(__file__).resolve().parents[2]
SCATTERING, ABSORPTION = 0.15, 0.01
SPOT = {"position": [0.0, 3.0, 0.0], "outer_deg": 20.0, "inner_deg": 19.9, "intensity_w_sr": 1.0}
CAMERA = {"position": [0.0, 1.5, 5.0], "target": [0.0, 1.2, 0.0], "fov_deg": 45.0}
FLOOR_HALF = 3.0
RESOLUTION = (160, 120)


def gltf_scene(path):
    """The scene as glTF with Caustic's extras."""
    floor = [[-FLOOR_HALF, 0.0, -FLOOR_HALF], [-FLOOR_HALF, 0.0, FLOOR_HALF], [FLOOR_HALF, 0.0, FLOOR_HALF],
             [FLOOR_HALF, 0.0, -FLOOR_HALF]]
    data = b"".join(struct.pack("<3f", *v) for v in floor) + struct.pack("<6H", 0, 1, 2, 0, 2, 3)
    uri = "data:application/octet-stream;base64," + base64.b64encode(data).decode()
    direction = np.subtract(CAMERA["target"], CAMERA["position"])
    direction = direction / np.linalg.norm(direction)
    # The camera looks along -z of its node: the rotation turning -z onto `direction` (about x).
    pitch = math.asin(direction[1])
    camera_rotation = [math.sin(pitch / 2), 0.0, 0.0, math.cos(pitch / 2)]
    down = [-math.sin(math.pi / 4), 0.0, 0.0, math.cos(math.pi / 4)]  # -z onto -y
    doc = {
        "asset": {"version": "2.0"},
        "extensionsUsed": ["KHR_lights_punctual", "KHR_materials_specular"],
        "buffers": [{"uri": uri, "byteLength": len(data)}],
        "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 48}, {"buffer": 0, "byteOffset": 48, "byteLength": 12}],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
             "min": [-FLOOR_HALF, 0.0, -FLOOR_HALF], "max": [FLOOR_HALF, 0.0, FLOOR_HALF]},
            {"bufferView": 1, "componentType": 5123, "count": 6, "type": "SCALAR"}],
        "materials": [{"name": "Floor", "pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.5, 0.5, 1.0],
                                                                 "metallicFactor": 0.0, "roughnessFactor": 1.0},
                       "extensions": {"KHR_materials_specular": {"specularFactor": 0.0}}}],
        "meshes": [{"name": "Floor", "primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "material": 0}]}],
        "cameras": [{"type": "perspective", "perspective": {
            "yfov": math.radians(CAMERA["fov_deg"]),
            "znear": 0.01, "aspectRatio": RESOLUTION[0] / RESOLUTION[1]}}],
        "extensions": {"KHR_lights_punctual": {"lights": [{"type": "spot", "intensity": 683.0 * SPOT["intensity_w_sr"],
            "spot": {"innerConeAngle": math.radians(SPOT["inner_deg"]), "outerConeAngle": math.radians(SPOT["outer_deg"])}}]}},
        "nodes": [
            {"name": "Floor", "mesh": 0},
            {"name": "Camera", "camera": 0, "translation": CAMERA["position"], "rotation": camera_rotation},
            {"name": "Spot", "translation": SPOT["position"], "rotation": down,
             "extensions": {"KHR_lights_punctual": {"light": 0}}}],
        "scenes": [{"nodes": [0, 1, 2], "extras": {"caustic": {"resolution": list(RESOLUTION), "fog": {
            "scattering": [SCATTERING] * 3, "absorption": [ABSORPTION] * 3}}}}],
        "scene": 0,
    }
    path.write_text(json.dumps(doc))


def mitsuba_scene(mi):
    """The scene as a Mitsuba dictionary: the fog inside a large null-surfaced sphere holding
    everything, the camera and the floor in it."""
    fog = {"type": "homogeneous", "albedo": SCATTERING / (SCATTERING + ABSORPTION),
           "sigma_t": SCATTERING + ABSORPTION, "phase": {"type": "isotropic"}}
    return {
        "type": "scene",
        "integrator": {"type": "volpath", "max_depth": 64, "rr_depth": 16},
        "fog": fog,
        "sensor": {"type": "perspective", "fov": CAMERA["fov_deg"], "fov_axis": "y",
                   "to_world": mi.ScalarTransform4f().look_at(origin=CAMERA["position"], target=CAMERA["target"],
                                                              up=[0, 1, 0]),
                   "medium": {"type": "ref", "id": "fog"},
                   "film": {"type": "hdrfilm", "width": RESOLUTION[0], "height": RESOLUTION[1],
                            "rfilter": {"type": "box"}, "pixel_format": "rgb"},
                   "sampler": {"type": "independent"}},
        "spot": {"type": "spot", "intensity": {"type": "d65", "scale": SPOT["intensity_w_sr"]},
                 "cutoff_angle": SPOT["outer_deg"], "beam_width": SPOT["inner_deg"],
                 "to_world": mi.ScalarTransform4f().look_at(origin=SPOT["position"],
                                                            target=[0.0, 0.0, 0.0], up=[0, 0, 1])},
        "floor": {"type": "rectangle", "bsdf": {"type": "diffuse", "reflectance": {"type": "spectrum", "value": 0.5}},
                  "exterior": {"type": "ref", "id": "fog"},
                  "to_world": mi.ScalarTransform4f().rotate([1, 0, 0], -90).scale(FLOOR_HALF)},
        "bounds": {"type": "sphere", "radius": 100.0, "bsdf": {"type": "null"},
                   "interior": {"type": "ref", "id": "fog"}},
    }


def luminance(rgb):
    return rgb[..., :3] @ np.array([0.2126, 0.7152, 0.0722])


def read_exr(path):
    """An EXR's colour as an array (Caustic's Combined layer, or Mitsuba's RGB)."""
    import OpenEXR
    channels = OpenEXR.File(str(path)).channels()
    name = next(k for k in ("Combined", "RGB", "RGBA") if k in channels)
    return np.asarray(channels[name].pixels, dtype=np.float64)


def block_median_difference(a, b, block=8):
    h, w = a.shape
    diffs = []
    for y in range(0, h - block + 1, block):
        for x in range(0, w - block + 1, block):
            ma, mb = a[y:y + block, x:x + block].mean(), b[y:y + block, x:x + block].mean()
            if max(ma, mb) > 1e-3 * max(a.mean(), b.mean()):
                diffs.append(abs(ma / mb - 1.0) if mb > 0 else 1.0)
    return float(np.median(diffs)), len(diffs)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--spp", type=int, default=4096)
    parser.add_argument("--passes", type=int, default=4096)
    parser.add_argument("--binary", default=str(ROOT / "target" / "release" / "caustic"))
    parser.add_argument("-o", "--out", default=str(ROOT / "bench-out" / "fog"))
    args = parser.parse_args()
    out = pathlib.Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    import mitsuba as mi
    mi.set_variant("scalar_spectral")
    start = time.time()
    image = mi.render(mi.load_dict(mitsuba_scene(mi)), spp=args.spp)
    mitsuba_s = time.time() - start
    mi.util.write_bitmap(str(out / "mitsuba.exr"), image)
    mitsuba = luminance(np.asarray(image, dtype=np.float64))
    gltf = out / "fog.gltf"
    gltf_scene(gltf)
    start = time.time()
    subprocess.run([args.binary, "render", str(gltf), "-o", str(out / "caustic"), "--passes", str(args.passes),
                    "--progress", "none"], check=True)
    caustic_s = time.time() - start
    caustic = luminance(read_exr(out / "caustic" / "frame_0001.exr"))
    median, blocks = block_median_difference(caustic, mitsuba)
    result = {"mitsuba_spp": args.spp, "mitsuba_wall_s": round(mitsuba_s, 1), "caustic_passes": args.passes,
              "caustic_wall_s": round(caustic_s, 1), "block_median_relative_difference": median,
              "blocks_compared": blocks, "mean_ratio": float(caustic.mean() / mitsuba.mean())}
    (out / "results.json").write_text(json.dumps(result, indent=2) + "\n")
    print(json.dumps(result, indent=2))


if __name__ == "__main__":
    main()
