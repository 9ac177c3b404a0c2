"""Caustic's two methods (SPPM and VCM) against two path tracers, Mitsuba 3 (`scalar_spectral`,
its `path` integrator) and Cycles, at equal CPU time, on the same machine, in one run: error
against time for all four (a benchmark, not a test: run it by hand on an idle machine, release
build first):

    cargo build --release
    target/bpy-venv/bin/pip install matplotlib mitsuba     # once; `cargo test` made the venv
    target/bpy-venv/bin/python tests/bench/vs_peers.py [--budgets 10,30,100,300,600] [--threads 2]
        [--scenes caustic,glossy_interior] [--peers mitsuba,cycles] [--side-by-side] [-o bench-peers]

The scenes are built in Blender (bpy) by tests/bench/blender_scenes.py: the caustic box (the demo)
and the glossy interior (the diffuse box with rough gold and aluminium blocks: diffuse and glossy
light, no glass). Caustic renders what the add-on exports; Cycles renders the same in-memory
.blend with vs_cycles.py's settings (CPU, no denoising or adaptive sampling, a 1-pixel box filter,
no glossy filter, 32 bounces); Mitsuba renders the same scene converted by mitsuba_scene.py
(which refuses what it would render differently): `path` to 33 vertices (32 bounces), an
independent sampler, a 1-pixel box filter.

Budgets are CPU seconds. Each renderer renders once up to the largest budget and its error is
read along the way: Caustic from its `--log` with `--reference` (threads x wall time, four lines
to each doubling of the passes), Mitsuba and Cycles as running means of renders of 1, 1, 2, 4, ... samples with
other seeds (the CPU time of the render calls, measured, without loading and BVH building; Cycles
keeps its data between calls). Errors at the budgets are interpolated on log-log axes.
`--side-by-side` renders Caustic's two methods at once, each with half the threads, so that a
machine whose speed drifts between runs (this one's by up to 25%) slows both alike: their ratio
is then measured at equal CPU time by construction.

The error is the relative MSE of luminance against tests/bench/<scene>.exr (`caustic compare`;
vs_cycles.py's `--make-reference` makes a reference and records its provenance and its own noise
floor in references.json). Mitsuba's and Cycles' models differ slightly from Caustic's (Mitsuba's
diffuse box comes out 0.7% darker: a floor near 5e-5), so their errors level off where that
difference is reached.

Prints, per scene, each renderer's error at every budget, Caustic's ratios to the best peer and
to SPPM, and the slope of log error against log time over the budgets; writes OUT/results.json,
OUT/error_vs_time.svg and OUT/<scene>/sheet.png (each renderer at the largest budget, then the
reference).
"""
import argparse
import json
import math
import os
import pathlib
import resource
import subprocess
import sys

ROOT = pathlib.Path(__file__).resolve().parents[2]
HERE = ROOT / "tests" / "bench"
sys.path.insert(0, str(HERE))

import numpy as np  # noqa: E402
import OpenEXR  # noqa: E402

from blender_scenes import SCENES, build, export  # noqa: E402  (imports bpy)
from vs_cycles import (BENCH_SEED, add_common_arguments, cpu_seconds, error_at, caustic_curve, fmt,  # noqa: E402
                       reference_floor, relative_mse, render_caustic, render_cycles)

METHODS = ("sppm", "vcm")


def read_rgb(path):
    """An EXR's colour (Combined, RGB or RGBA) as an (h, w, 3) array."""
    channels = OpenEXR.File(str(path)).channels()
    name = next(k for k in ("Combined", "RGB", "RGBA") if k in channels)
    return np.asarray(channels[name].pixels, dtype=np.float64)[..., :3]


def write_rgb(path, rgb):
    OpenEXR.File({"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage},
                 {"RGB": rgb.astype(np.float32)}).write(str(path))


def progressive(render_chunk, budget, folder, binary, reference):
    """A peer's error along the way to `budget` CPU s: `render_chunk(samples, seed)` gives (an
    image, its CPU s); chunks of 1, 1, 2, 4, ... samples, the last sized to end past the budget,
    are averaged by samples. Gives [(CPU s, relative MSE, samples)]."""
    total, samples, cpu, seed, chunk, curve = None, 0, 0.0, 0, 1, []
    running = folder / "running.exr"
    while cpu < budget:
        image, seconds = render_chunk(chunk, seed)
        total = image * chunk if total is None else total + image * chunk
        samples, cpu, seed = samples + chunk, cpu + seconds, seed + 1
        write_rgb(running, total / samples)
        curve.append((cpu, relative_mse(binary, running, reference), samples))
        per_sample = cpu / samples
        chunk = samples if cpu + samples * per_sample < budget else max(1, math.ceil((budget - cpu) / per_sample * 1.02))
    running.rename(folder / "final.exr")
    return curve


def mitsuba_curve(scene, folder, args, reference):
    import drjit as dr
    import mitsuba as mi
    mi.set_variant("scalar_spectral")
    from mitsuba_scene import mitsuba_scene
    if hasattr(dr, "set_thread_count"):
        dr.set_thread_count(args.threads)
    loaded = mi.load_dict(mitsuba_scene(scene, folder / "meshes", mi))

    def chunk(samples, seed):
        start = cpu_seconds(resource.RUSAGE_SELF)
        image = np.asarray(mi.render(loaded, spp=samples, seed=seed), dtype=np.float64)[..., :3]
        return image, cpu_seconds(resource.RUSAGE_SELF) - start
    return progressive(chunk, max(args.budgets), folder, args.binary, reference)


def cycles_curve(scene, folder, args, reference):
    scene.render.use_persistent_data = True

    def chunk(samples, seed):
        path = folder / "chunk.exr"
        _, cpu = render_cycles(scene, 0, args.threads, path, samples=samples, seed=seed)
        return read_rgb(path), cpu
    return progressive(chunk, max(args.budgets), folder, args.binary, reference)


def caustic_flags(folder, method, threads, args, reference):
    """`caustic render`'s flags for `--method method` on `threads` threads to the largest budget,
    logging to folder/render.log (emptied first)."""
    folder.mkdir(parents=True, exist_ok=True)
    log = folder / "render.log"
    log.unlink(missing_ok=True)
    return ["--method", method, "--time-budget", str(max(args.budgets) / threads), "--threads", str(threads),
            "--seed", str(BENCH_SEED), "--log", str(log), "--reference", str(reference)]


def caustic_runs(gltf, folder, args, reference):
    """Caustic with each method in turn, on all the threads; gives their curves."""
    curves = []
    for method in METHODS:
        out = folder / f"caustic_{method}"
        render_caustic(args.binary, gltf, out, caustic_flags(out, method, args.threads, args, reference))
        curves.append(caustic_curve(out / "render.log", args.threads))
    return curves


def caustic_runs_side_by_side(gltf, folder, args, reference):
    """Caustic with both methods at once, each on half the threads; gives their curves."""
    threads = max(1, args.threads // len(METHODS))
    outs = [folder / f"caustic_{method}" for method in METHODS]
    runs = []
    for method, out in zip(METHODS, outs):
        flags = caustic_flags(out, method, threads, args, reference)
        command = [args.binary, "render", str(gltf), "-o", str(out), "--progress", "none", *flags]
        runs.append(subprocess.Popen(command))
    for method, run in zip(METHODS, runs):
        if run.wait() != 0:
            raise SystemExit(f"caustic --method {method} failed (exit status {run.returncode})")
    return [caustic_curve(out / "render.log", threads) for out in outs]


def slope(curve, low, high, floor=0.0):
    """The least-squares slope of log error against log CPU time over [low, high], of the error
    less `floor` (the reference's own, which adds to every error measured against it)."""
    points = [(math.log(t), math.log(e - floor)) for t, e, _ in curve if low * 0.9 <= t <= high * 1.1 and e > floor]
    if len(points) < 2:
        return None
    mx = sum(x for x, _ in points) / len(points)
    my = sum(y for _, y in points) / len(points)
    sxx = sum((x - mx) ** 2 for x, _ in points)
    return sum((x - mx) * (y - my) for x, y in points) / sxx if sxx > 0 else None


def bench_scene(name, args):
    scene = build(name, args.resolution, args.binary)
    folder = args.out / name
    folder.mkdir(parents=True, exist_ok=True)
    reference = HERE / f"{name}.exr"
    if not reference.exists():
        raise SystemExit(f"no reference {reference}: make one with vs_cycles.py --make-reference PASSES --scenes {name}")
    gltf = export(scene, folder)
    curves, images = {}, {}
    runs = caustic_runs_side_by_side if args.side_by_side else caustic_runs
    for method, curve in zip(METHODS, runs(gltf, folder, args, reference)):
        curves[f"caustic_{method}"] = curve
        images[f"caustic_{method}"] = folder / f"caustic_{method}" / "frame_0001.exr"
    peers = {"mitsuba": mitsuba_curve, "cycles": cycles_curve}
    for peer in args.peers:
        out = folder / peer
        out.mkdir(exist_ok=True)
        curves[peer] = peers[peer](scene, out, args, reference)
        images[peer] = out / "final.exr"
    for who, curve in curves.items():
        print(f"{name}: {who}: {curve[-1][2]} passes or samples in {curve[-1][0]:.0f} CPU s, "
              f"relative MSE {curve[-1][1]:.3e}")
    budgets = [b for b in args.budgets]
    table = {who: [error_at(curve, b) for b in budgets] for who, curve in curves.items()}
    floor = reference_floor(name)
    slopes = {who: slope(curve, min(budgets), max(budgets)) for who, curve in curves.items()}
    slopes_above_floor = {who: slope(curve, min(budgets), max(budgets), floor) if floor else None
                          for who, curve in curves.items()}
    contact_sheet(folder, images, reference)
    return {"scene": name, "budgets_cpu_s": budgets, "relative_mse": table, "slopes": slopes,
            "slopes_above_floor": slopes_above_floor, "curves": curves, "reference_floor": floor}


def contact_sheet(folder, images, reference):
    from PIL import Image
    from exr_to_png import srgb_image
    tiles = [srgb_image(path) for path in [*images.values(), reference]]
    width, height = tiles[0].size
    sheet = Image.new("RGB", (width * len(tiles), height))
    for x, tile in enumerate(tiles):
        sheet.paste(tile, (x * width, 0))
    sheet.save(folder / "sheet.png")


def print_table(result):
    floor = result["reference_floor"]
    table = result["relative_mse"]
    who = list(table)
    peers = [w for w in who if not w.startswith("caustic")]
    print(f"\n{result['scene']}: relative MSE at equal CPU time"
          + ("" if floor is None else f" (the reference's own: {floor:.2e})"))
    print(f"{'CPU s':>7} " + " ".join(f"{w:>13}" for w in who) + "  best peer/VCM  SPPM/VCM")
    for i, budget in enumerate(result["budgets_cpu_s"]):
        vcm, sppm = table["caustic_vcm"][i], table["caustic_sppm"][i]
        best = min((table[p][i] for p in peers if table[p][i] is not None), default=None)
        ratios = [best / vcm if best and vcm else None, sppm / vcm if sppm and vcm else None]
        print(f"{budget:>7g} " + " ".join(f"{fmt(table[w][i], '.3e'):>13}" for w in who)
              + f"  {fmt(ratios[0], '.2f'):>12}x {fmt(ratios[1], '.2f'):>8}x")
    print(f"{'slope':>7} " + " ".join(f"{fmt(result['slopes'][w], '.2f'):>13}" for w in who))
    if floor is not None:
        print(f"{'> floor':>7} " + " ".join(f"{fmt(result['slopes_above_floor'][w], '.2f'):>13}" for w in who)
              + "  (slopes of the error less the reference's own)")


def chart(results, path):
    import matplotlib
    matplotlib.use("svg")
    import matplotlib.pyplot as plt
    labels = {"caustic_sppm": "Caustic SPPM", "caustic_vcm": "Caustic VCM", "mitsuba": "Mitsuba 3 (path)",
              "cycles": "Cycles (path)"}
    figure, axes = plt.subplots(1, len(results), figsize=(5.5 * len(results), 4.5), squeeze=False)
    for ax, result in zip(axes[0], results):
        for who, curve in result["curves"].items():
            ax.loglog(*zip(*[(t, e) for t, e, _ in curve if t > 0]), "o-" if who.startswith("caustic") else "s--",
                      label=labels[who], markersize=3)
        if result["reference_floor"]:
            ax.axhline(result["reference_floor"], color="grey", lw=0.8, ls=":", label="reference's own error")
        ax.set_title(f"{result['scene']} scene")
        ax.set_xlabel("CPU seconds")
        ax.set_ylabel("relative MSE of luminance")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend()
    figure.tight_layout()
    figure.savefig(path)
    print(f"chart: {path}")


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    add_common_arguments(parser, "10,30,100,300,600", "caustic,glossy_interior", "bench-peers")
    parser.add_argument("--peers", default="mitsuba,cycles", type=lambda s: [p for p in s.split(",") if p])
    parser.add_argument("--side-by-side", action="store_true",
                        help="render Caustic's two methods at once, each on half the threads")
    args = parser.parse_args()
    unknown = [s for s in args.scenes if s not in SCENES] + [p for p in args.peers if p not in ("mitsuba", "cycles")]
    if unknown:
        parser.error(f"unknown scene or peer {unknown[0]!r}; the scenes are {', '.join(SCENES)}; "
                     "the peers mitsuba and cycles")
    if not os.access(args.binary, os.X_OK):
        parser.error(f"no caustic program at {args.binary}: run `cargo build --release` first")
    args.out.mkdir(parents=True, exist_ok=True)
    results = [bench_scene(name, args) for name in args.scenes]
    for result in results:
        print_table(result)
    (args.out / "results.json").write_text(json.dumps(results, indent=2) + "\n")
    chart(results, args.out / "error_vs_time.svg")


if __name__ == "__main__":
    main()
