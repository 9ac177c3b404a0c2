"""The glossy benchmark (a benchmark, not a test: run it by hand on an idle machine, release build
first): a studio scene, a gold sphere of roughness 0.3 and a glass ball on a floor under an area
light, built in bpy and exported by the add-on; the gold sphere's relative MSE at equal CPU time,
Caustic (each `--method` asked for) against Cycles, and against another Caustic binary (the build
before a change):

    cargo build --release
    target/bpy-venv/bin/python tests/bench/glossy.py [--budgets 10,60] [--threads 2]
        [--reference-seconds 600] [--baseline path/to/caustic] [--resolution 96x72]
        [--gold-roughness 0.3] [--methods sppm,vcm] [--seeds 1] [--first-seed 1] [-o OUT]

Budgets are CPU seconds (threads x wall time; both renderers get the same threads). Cycles: CPU
device, denoising and adaptive sampling off, a 1-pixel box filter, no glossy filter, 32 bounces.
Each renderer is measured against its own converged render (`--reference-seconds` of wall time,
another seed): the two models differ by a few percent on a rough metal, and a shared reference
would count that difference as error. The error is the relative MSE of luminance over the gold
sphere's pixels (from Cycles' object-index pass, its rim left out), mean of
(Y - Y_ref)^2 / (Y_ref^2 + f^2) with f = 1% of the reference's mean there. With `--seeds K` each
renderer renders each budget with seeds 1..K and the figure is the mean of their errors, printed
with the smallest and largest (one run's ratio to Cycles varied by 1.4x between two seeds at 60 s).
`--first-seed S` starts at seed S instead (S..S+K-1), so a second run can confirm a first one with
fresh seeds: a render with the same seed and budget differs between runs only by the few passes
its wall time allows, so rerunning seeds 1..K is not a new sample.
Prints the figures and writes OUT/results.json and OUT/*.exr.
"""
import argparse
import json
import os
import pathlib
import resource
import subprocess
import sys
import tempfile
import time

ROOT = pathlib.Path(__file__).resolve().parents[2]
os.environ["HOME"] = tempfile.mkdtemp(prefix="caustic-glossy-home-")
sys.path.insert(0, str(ROOT / "tests" / "addon"))
import bpy  # noqa: E402
import numpy as np  # noqa: E402
import OpenEXR  # noqa: E402

import parity_scenes as ps  # noqa: E402
from enable_addon import enable_addon  # noqa: E402

GOLD = 2


def studio(resolution, roughness):
    """The gold sphere (index 2) and the glass ball (index 3) on the default floor (index 1)."""
    scene = ps.clear()
    ps.studio(ps.principled("Floor", Base_Color=(0.5, 0.5, 0.5, 1.0)))
    gold = ps.principled("Gold", Base_Color=(1.0, 0.77, 0.34, 1.0), Metallic=1.0, Roughness=roughness)
    glass = ps.principled("Glass", Transmission_Weight=1.0, Roughness=0.0, IOR=1.5)
    for material, x, index in ((gold, -1.1, GOLD), (glass, 1.1, 3)):
        ps.add(bpy.ops.mesh.primitive_uv_sphere_add, material, index=index, segments=64, ring_count=32, radius=1.0,
               location=(x, 0.0, 1.0))
        bpy.ops.object.shade_smooth()
    ps.camera((0.0, -7.0, 3.0), (0.0, 0.0, 0.8))
    scene.render.resolution_x, scene.render.resolution_y = resolution
    return scene


def cpu_seconds(who):
    usage = resource.getrusage(who)
    return usage.ru_utime + usage.ru_stime


def cycles(scene, seconds, threads, path, seed):
    """Cycles for `seconds` of wall time; gives the CPU seconds it used."""
    scene.render.engine = 'CYCLES'
    c = scene.cycles
    c.device, c.samples, c.time_limit, c.seed = 'CPU', 1 << 24, seconds, seed
    c.use_adaptive_sampling = c.use_denoising = False
    c.pixel_filter_type, c.filter_width, c.blur_glossy = 'BOX', 1.0, 0.0
    for bounces in ("max_bounces", "diffuse_bounces", "glossy_bounces", "transmission_bounces",
                    "transparent_max_bounces"):
        setattr(c, bounces, 32)
    scene.render.threads_mode, scene.render.threads = 'FIXED', threads
    bpy.context.view_layer.use_pass_object_index = True
    scene.render.image_settings.media_type = 'MULTI_LAYER_IMAGE'
    scene.render.image_settings.file_format = 'OPEN_EXR_MULTILAYER'
    scene.render.image_settings.color_depth = '32'
    scene.render.filepath = str(path)
    cpu = cpu_seconds(resource.RUSAGE_SELF)
    bpy.ops.render.render(write_still=True)
    return cpu_seconds(resource.RUSAGE_SELF) - cpu


def caustic(binary, method, gltf, seconds, threads, out, seed):
    """`caustic render --method method` for `seconds` of wall time; gives the CPU seconds it used."""
    cpu = cpu_seconds(resource.RUSAGE_CHILDREN)
    subprocess.run([binary, "render", str(gltf), "-o", str(out), "--progress", "none", "--time-budget", str(seconds),
                    "--threads", str(threads), "--seed", str(seed), "--method", method], check=True)
    return cpu_seconds(resource.RUSAGE_CHILDREN) - cpu


def channels(path):
    return {k: v.pixels for part in OpenEXR.File(str(path)).parts for k, v in part.channels.items()}


def luminance(path):
    rgb = next(v for k, v in channels(path).items() if k.endswith("Combined"))[..., :3]
    return rgb @ np.array([0.2126, 0.7152, 0.0722], dtype=np.float32)


def gold_mask(path):
    index = next(v for k, v in channels(path).items() if k.endswith("Object Index.X"))
    return ps.interior(index, GOLD)


def relative_mse(image, reference, mask):
    y, ref = luminance(image)[mask], luminance(reference)[mask]
    f = 0.01 * ref.mean()
    return float(np.mean((y - ref) ** 2 / (ref ** 2 + f ** 2)))


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--budgets", default="10,60", help="CPU seconds, comma-separated")
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--reference-seconds", type=float, default=600.0)
    parser.add_argument("--baseline", help="another caustic binary to measure beside this build's")
    parser.add_argument("--binary", default=str(ROOT / "target" / "release" / "caustic"))
    parser.add_argument("--resolution", default="96x72")
    parser.add_argument("--gold-roughness", type=float, default=0.3)
    parser.add_argument("--methods", default="sppm,vcm", type=lambda s: s.split(","),
                        help="Caustic's methods to measure, each against its own reference")
    parser.add_argument("--seeds", type=int, default=1, help="renders per renderer and budget, seeds 1..K")
    parser.add_argument("--first-seed", type=int, default=1, help="the first seed of --seeds")
    parser.add_argument("-o", "--out", default="bench-glossy")
    args = parser.parse_args()
    out = pathlib.Path(args.out).resolve()
    out.mkdir(parents=True, exist_ok=True)
    resolution = tuple(int(v) for v in args.resolution.split("x"))
    enable_addon(args.binary)
    scene = studio(resolution, args.gold_roughness)
    gltf = out / "studio.gltf"
    sys.modules["caustic.export"].export(scene, gltf)
    binaries = {f"caustic_{method}": (args.binary, method) for method in args.methods}
    binaries |= {"baseline": (args.baseline, args.methods[0])} if args.baseline else {}
    references = {"cycles": out / "cycles_reference.exr"}
    references |= {name: out / f"{name}_reference" / "frame_0001.exr" for name in binaries}
    wall = args.reference_seconds
    if not references["cycles"].exists():
        cycles(scene, wall, args.threads, references["cycles"], seed=777)
    for name, (binary, method) in binaries.items():
        if not references[name].exists():
            caustic(binary, method, gltf, wall, args.threads, references[name].parent, seed=777)
    mask = gold_mask(references["cycles"])
    results = {"pixels": int(mask.sum()), "resolution": list(resolution), "threads": args.threads,
               "gold_roughness": args.gold_roughness,
               "reference_wall_s": wall, "seeds": args.seeds, "first_seed": args.first_seed, "runs": []}
    for budget in (float(b) for b in args.budgets.split(",")):
        seconds = budget / args.threads
        runs = {"cycles": lambda path, seed: cycles(scene, seconds, args.threads, path / "frame_0001.exr", seed)}
        runs |= {name: (lambda path, seed, b=binary, m=method: caustic(b, m, gltf, seconds, args.threads, path, seed))
                 for name, (binary, method) in binaries.items()}
        row = {"cpu_s_budget": budget}
        for name, run in runs.items():
            errors, cpus, walls = [], [], []
            for seed in range(args.first_seed, args.first_seed + args.seeds):
                folder = out / (f"{name}_{budget:g}s" + (f"_seed{seed}" if args.seeds > 1 else ""))
                folder.mkdir(exist_ok=True)
                start = time.perf_counter()
                cpus.append(round(run(folder, seed), 1))
                walls.append(round(time.perf_counter() - start, 1))
                errors.append(relative_mse(folder / "frame_0001.exr", references[name], mask))
            error = float(np.mean(errors))
            row[name] = {"relative_mse": error, "per_seed": errors, "cpu_s": cpus, "wall_s": walls}
            spread = f" (seeds {min(errors):.3e} .. {max(errors):.3e})" if args.seeds > 1 else ""
            print(f"{budget:g} CPU s: {name} relative MSE {error:.3e}{spread} ({np.mean(cpus):.1f} CPU s)", flush=True)
        for method in args.methods:
            ratio = row["cycles"]["relative_mse"] / row[f"caustic_{method}"]["relative_mse"]
            row[f"cycles_over_caustic_{method}"] = ratio
            print(f"{budget:g} CPU s: Cycles' error / Caustic {method}'s = {ratio:.2f}", flush=True)
        results["runs"].append(row)
    (out / "results.json").write_text(json.dumps(results, indent=1) + "\n")


if __name__ == "__main__":
    main()
