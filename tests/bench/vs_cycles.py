"""Caustic against Cycles at equal CPU time, on the same machine, in one run (a benchmark, not a
test: run it by hand on an idle machine, release build first):

    cargo build --release
    target/bpy-venv/bin/pip install matplotlib        # once; `cargo test` made the venv
    target/bpy-venv/bin/python tests/bench/vs_cycles.py [--budgets 10,30,100,300] [--threads 2]
                                                        [--scenes caustic,diffuse,spot] [-o bench-out]
                                                        [--caustic-flags "--radius 0.07"]

Each scene is built in Blender (bpy) by scenes/make_scenes.py, exported by the add-on for Caustic
and rendered by Cycles from the same in-memory .blend: CPU device, the same thread count,
denoising and adaptive sampling off, a 1-pixel box filter, no glossy filter, and path lengths up
to Caustic's 32 bounces (volume bounces too). Budgets are CPU seconds (threads x rendering wall
time; both renderers' times exclude loading and BVH building, as Cycles' time limit does). Cycles renders once per
budget; Caustic renders once for the largest budget with `--log` and `--reference`, whose lines
(four to each doubling of the passes) give its error along the way.

The error is the relative MSE of luminance, mean of (Y - Y_ref)^2 / (Y_ref^2 + f^2), f = 1% of
the reference's mean (`caustic compare`), against tests/bench/<scene>.exr: the mean of two long
Caustic renders with other seeds (older references: one render), whose provenance is in
tests/bench/references.json (`--make-reference PASSES` writes both, each half of PASSES). A
reference's own noise adds to every error measured against it: a quarter of the two halves'
relative MSE against each other estimates it (`own_relative_mse`), and the tables give each error
above that floor beside it (a ratio of raw errors understates the gap between two renderers). Prints,
per scene, both errors at each budget and the ratio of the time Caustic needs to reach Cycles'
error to Cycles' time; writes OUT/results.json, OUT/error_vs_time.svg and per scene
OUT/<scene>/sheet.png (Cycles at each budget above; Caustic below, with the reference).
The spot and fog_spot scenes (a point spot through glass, onto a floor and into fog, which
Cycles cannot render) are rendered by both at each budget; their Caustic images and error bounds
show them converging.
"""
import argparse
import datetime
import json
import math
import os
import pathlib
import resource
import subprocess
import sys
import tempfile
import time

ROOT = pathlib.Path(__file__).resolve().parents[2]
HERE = ROOT / "tests" / "bench"
sys.path.insert(0, str(HERE))

from blender_scenes import SCENES, build, export  # noqa: E402  (imports bpy)
import bpy  # noqa: E402

# The seeds of a reference's two halves.
REFERENCE_SEEDS = (777, 778)
BENCH_SEED = 1


def cpu_seconds(who):
    usage = resource.getrusage(who)
    return usage.ru_utime + usage.ru_stime


def render_cycles(scene, seconds, threads, path, samples=1 << 24, seed=0):
    """Cycles for `seconds` of rendering wall time (0: no limit) or `samples`, whichever ends
    first; gives (wall s, CPU s) of the whole call."""
    scene.render.engine = 'CYCLES'
    cycles = scene.cycles
    cycles.device = 'CPU'
    cycles.samples = samples
    cycles.seed = seed
    cycles.time_limit = seconds
    cycles.use_adaptive_sampling = False
    cycles.use_denoising = False
    cycles.pixel_filter_type = 'BOX'
    cycles.filter_width = 1.0
    cycles.blur_glossy = 0.0
    for bounces in ("max_bounces", "diffuse_bounces", "glossy_bounces", "transmission_bounces",
                    "volume_bounces", "transparent_max_bounces"):
        setattr(cycles, bounces, 32)
    scene.render.threads_mode = 'FIXED'
    scene.render.threads = threads
    scene.render.image_settings.file_format = 'OPEN_EXR'
    scene.render.image_settings.color_depth = '32'
    scene.render.filepath = str(path)
    wall, cpu = time.perf_counter(), cpu_seconds(resource.RUSAGE_SELF)
    bpy.ops.render.render(write_still=True)
    return time.perf_counter() - wall, cpu_seconds(resource.RUSAGE_SELF) - cpu


def render_caustic(binary, gltf, out, flags):
    """`caustic render` with `flags`; gives (wall s, CPU s) of the process."""
    wall, cpu = time.perf_counter(), cpu_seconds(resource.RUSAGE_CHILDREN)
    subprocess.run([binary, "render", str(gltf), "-o", str(out), "--progress", "none", *flags], check=True)
    return time.perf_counter() - wall, cpu_seconds(resource.RUSAGE_CHILDREN) - cpu


def relative_mse(binary, image, reference):
    printed = subprocess.run([binary, "compare", str(image), "--reference", str(reference)], check=True,
                             capture_output=True, text=True).stdout
    return json.loads(printed)["relative_mse"]


def caustic_curve(log, threads):
    """(CPU s, relative MSE, passes) after each logged pass of a `--log` file with a reference."""
    lines = [json.loads(line) for line in log.read_text().splitlines() if line.strip()]
    return [(threads * l["elapsed_s"], l["true"]["relative_mse"], l["passes"]) for l in lines]


def error_at(curve, seconds):
    """The curve's error at `seconds`, interpolated on log-log axes (None outside it)."""
    for (t0, e0, _), (t1, e1, _) in zip(curve, curve[1:]):
        if t0 <= seconds <= t1 and t0 > 0:
            s = math.log(seconds / t0) / math.log(t1 / t0) if t1 > t0 else 0.0
            return math.exp(math.log(e0) + s * math.log(e1 / e0))
    return None


def time_to_reach(curve, error):
    """The first time the curve's error falls to `error`, interpolated on log-log axes; None if it
    never does; the curve's first time if it starts below."""
    if curve[0][1] <= error:
        return curve[0][0]
    for (t0, e0, _), (t1, e1, _) in zip(curve, curve[1:]):
        if e1 <= error < e0:
            s = math.log(error / e0) / math.log(e1 / e0)
            return math.exp(math.log(t0) + s * math.log(t1 / t0))
    return None


def mean_exr(paths, out):
    """Writes the mean of the EXRs `paths` (their Combined colour) to `out`."""
    import numpy as np
    import OpenEXR
    files = [OpenEXR.File(str(p), separate_channels=True) for p in paths]
    header = files[0].header()
    names = [n for n in files[0].channels() if n.startswith("Combined.")]
    channels = {n: np.mean([f.channels()[n].pixels for f in files], axis=0, dtype=np.float64).astype(np.float32)
                for n in names}
    OpenEXR.File({"compression": header["compression"], "type": header["type"]}, channels).write(str(out))


def reference_floor(name):
    """The reference's own relative MSE (`own_relative_mse` in references.json), or None."""
    provenance_path = HERE / "references.json"
    provenance = json.loads(provenance_path.read_text()) if provenance_path.exists() else {}
    return provenance.get(name, {}).get("own_relative_mse")


def above_floor(error, floor):
    """`error` less the reference's own (None where either is unknown)."""
    return None if error is None or floor is None else error - floor


def method_of(flags):
    """The `--method` that Caustic's `flags` ask for (its default, `sppm`, where they ask none)."""
    words = flags.split()
    return words[words.index("--method") + 1] if "--method" in words[:-1] else "sppm"


def make_reference(binary, name, args):
    """Renders tests/bench/<name>.exr with Caustic, as the mean of two halves with other seeds, and
    records how, and its own error from the halves' difference, in references.json."""
    scene = build(name, args.resolution, args.binary)
    work = pathlib.Path(tempfile.mkdtemp(prefix=f"caustic-ref-{name}-"))
    gltf = export(scene, work)
    halves, wall, cpu = [], 0.0, 0.0
    for seed in REFERENCE_SEEDS:
        flags = ["--passes", str(args.make_reference // 2), "--seed", str(seed), "--threads", str(args.threads),
                 *args.caustic_flags.split()]
        half_wall, half_cpu = render_caustic(args.binary, gltf, work / f"seed_{seed}", flags)
        halves.append(work / f"seed_{seed}" / "frame_0001.exr")
        wall, cpu = wall + half_wall, cpu + half_cpu
    mean_exr(halves, HERE / f"{name}.exr")
    # The halves differ by twice one half's error; their mean has half of one half's.
    own = relative_mse(args.binary, halves[0], halves[1]) / 4
    commit = subprocess.run(["git", "-C", str(ROOT), "rev-parse", "--short", "HEAD"], capture_output=True,
                            text=True).stdout.strip()
    provenance_path = HERE / "references.json"
    provenance = json.loads(provenance_path.read_text()) if provenance_path.exists() else {}
    provenance[name] = {
        "renderer": f"caustic render ({method_of(args.caustic_flags).upper()}), this repository", "commit": commit,
        "scene": f"scenes/make_scenes.py {SCENES[name].__name__}(), exported by the add-on",
        "resolution": list(args.resolution), "passes": args.make_reference,
        "seeds": list(REFERENCE_SEEDS), "made_as": "the mean of two renders of half the passes, one per seed",
        "own_relative_mse": own,
        "photons_per_pass": "one per pixel (default)", "threads": args.threads,
        "flags": args.caustic_flags,
        "wall_s": round(wall, 1), "cpu_s": round(cpu, 1), "date": datetime.date.today().isoformat(),
    }
    provenance_path.write_text(json.dumps(provenance, indent=2) + "\n")
    print(f"{name}: reference of {args.make_reference} passes in {wall:.0f} s, own relative MSE {own:.3g} "
          f"-> {HERE / (name + '.exr')}")


def caustic_flags(args, budget, log):
    return ["--time-budget", str(budget / args.threads), "--threads", str(args.threads), "--seed", str(BENCH_SEED),
            "--log", str(log), *args.caustic_flags.split()]


def bench_scene(name, args, out):
    """Both renderers at every budget; gives the scene's results. With a reference, Caustic
    renders once (its log gives the error along the way); without one (the spot scene), once per
    budget, so that its images show it converging."""
    scene = build(name, args.resolution, args.binary)
    folder = out / name
    folder.mkdir(parents=True, exist_ok=True)
    gltf = export(scene, folder)
    reference = HERE / f"{name}.exr"
    has_reference = reference.exists()
    runs = [max(args.budgets)] if has_reference else args.budgets
    for budget in runs:
        log = folder / f"caustic_{budget:g}s.log"
        log.unlink(missing_ok=True)
        flags = caustic_flags(args, budget, log) + (["--reference", str(reference)] if has_reference else [])
        wall, cpu = render_caustic(args.binary, gltf, folder / f"caustic_{budget:g}s", flags)
        print(f"{name}: Caustic {budget:g} CPU s: ran {wall:.1f} s wall, {cpu:.1f} s CPU ({cpu / wall:.2f} cores busy)")
    cycles = []
    for budget in args.budgets:
        image = folder / f"cycles_{budget:g}s.exr"
        wall, cpu = render_cycles(scene, budget / args.threads, args.threads, image)
        error = relative_mse(args.binary, image, reference) if has_reference else None
        cycles.append({"budget_cpu_s": budget, "wall_s": wall, "cpu_s": cpu, "relative_mse": error})
        print(f"{name}: Cycles {budget:g} CPU s: call {wall:.1f} s wall, {cpu:.1f} s CPU, relative MSE {error}")
    result = {"scene": name, "cycles": cycles, "reference_floor": reference_floor(name)}
    last_log = folder / f"caustic_{max(args.budgets):g}s.log"
    lines = [json.loads(line) for line in last_log.read_text().splitlines() if line.strip()]
    result["caustic_bound"] = [(args.threads * l["elapsed_s"], l["error"]["mean"], l["passes"]) for l in lines]
    if has_reference:
        curve = caustic_curve(last_log, args.threads)
        result["caustic_curve"] = curve
        for row in cycles:
            row["caustic_relative_mse"] = error_at(curve, row["budget_cpu_s"])
            reach = time_to_reach(curve, row["relative_mse"])
            row["caustic_time_to_cycles_error_s"] = reach
            row["time_ratio"] = reach / row["budget_cpu_s"] if reach is not None else None
    contact_sheet(folder, runs, args.budgets, reference if has_reference else None)
    return result


def contact_sheet(folder, caustic_budgets, cycles_budgets, reference):
    """OUT/<scene>/sheet.png: Cycles at each budget above, Caustic below (and the reference)."""
    from PIL import Image
    from exr_to_png import srgb_image
    rows = [[srgb_image(folder / f"cycles_{b:g}s.exr") for b in cycles_budgets],
            [srgb_image(folder / f"caustic_{b:g}s" / "frame_0001.exr") for b in caustic_budgets]]
    if reference is not None:
        rows[1].append(srgb_image(reference))
    width, height = rows[0][0].size
    sheet = Image.new("RGB", (width * max(len(r) for r in rows), height * len(rows)))
    for y, row in enumerate(rows):
        for x, image in enumerate(row):
            sheet.paste(image, (x * width, y * height))
    sheet.save(folder / "sheet.png")


def fmt(value, spec):
    return "-" if value is None else format(value, spec)


def print_table(result):
    floor = result["reference_floor"]
    print(f"\n{result['scene']}: relative MSE at equal CPU time" +
          ("" if floor is None else f" (the reference's own: {floor:.3e}; above it in brackets)"))
    print(f"{'CPU s':>7} {'Cycles':>22} {'Caustic':>22} {'Cycles/Caustic':>15} {'Caustic time to Cycles error':>30}")
    for row in result["cycles"]:
        ours, theirs = row.get("caustic_relative_mse"), row["relative_mse"]
        ratio = theirs / ours if ours and theirs else None
        reach = row.get("caustic_time_to_cycles_error_s")
        both = [fmt(e, '.3e') + ("" if floor is None else f" ({fmt(above_floor(e, floor), '.2e')})")
                for e in (theirs, ours)]
        print(f"{row['budget_cpu_s']:>7g} {both[0]:>22} {both[1]:>22} {fmt(ratio, '.1f'):>14}x "
              f"{fmt(reach, '.2f'):>20} s ({fmt(row.get('time_ratio'), '.3f')}x)")


def chart(results, path):
    """Error against CPU time, one panel per scene: both renderers' relative MSE where there is a
    reference, else Caustic's own estimated error bound."""
    import matplotlib
    matplotlib.use("svg")
    import matplotlib.pyplot as plt
    figure, axes = plt.subplots(1, len(results), figsize=(5.5 * len(results), 4.5), squeeze=False)
    for ax, result in zip(axes[0], results):
        if "caustic_curve" in result:
            ax.loglog(*zip(*[(t, e) for t, e, _ in result["caustic_curve"] if t > 0]), "o-", label="Caustic (SPPM)")
            cycles = [(r["budget_cpu_s"], r["relative_mse"]) for r in result["cycles"]]
            ax.loglog(*zip(*cycles), "s--", label="Cycles (path tracing)")
            ax.set_ylabel("relative MSE of luminance")
        else:
            bound = [(t, e) for t, e, _ in result["caustic_bound"] if t > 0]
            ax.loglog(*zip(*bound), "o-", label="Caustic: estimated mean relative error bound")
            ax.set_ylabel("mean relative error (estimated)")
        ax.set_title(f"{result['scene']} scene")
        ax.set_xlabel("CPU seconds (threads x wall time)")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend()
    figure.tight_layout()
    figure.savefig(path)
    print(f"chart: {path}")


def parse_resolution(text):
    width, height = (int(v) for v in text.lower().split("x"))
    return width, height


def add_common_arguments(parser, budgets, scenes, out):
    """The options every equal-time benchmark takes, with its own defaults."""
    parser.add_argument("--budgets", default=budgets,
                        type=lambda s: [float(v) for v in s.split(",")], help="CPU seconds")
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--resolution", type=parse_resolution, default=(256, 192))
    parser.add_argument("--scenes", default=scenes, type=lambda s: s.split(","))
    parser.add_argument("-o", "--out", type=pathlib.Path, default=ROOT / out)
    parser.add_argument("--binary", default=str(ROOT / "target" / "release" / "caustic"))


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    add_common_arguments(parser, "10,30,100,300", "caustic,diffuse,spot", "bench-out")
    parser.add_argument("--caustic-flags", default="", help="more flags for caustic render, e.g. '--radius 0.07'")
    parser.add_argument("--make-reference", type=int, metavar="PASSES",
                        help="instead, render the scenes' references with this many passes")
    args = parser.parse_args()
    unknown = [s for s in args.scenes if s not in SCENES]
    if unknown:
        parser.error(f"unknown scene {unknown[0]!r}; the scenes are {', '.join(SCENES)}")
    if not os.access(args.binary, os.X_OK):
        parser.error(f"no caustic program at {args.binary}: run `cargo build --release` first")
    if args.make_reference:
        for name in args.scenes:
            make_reference(args.binary, name, args)
        return
    args.out.mkdir(parents=True, exist_ok=True)
    results = [bench_scene(name, args, args.out) for name in args.scenes]
    for result in results:
        if "caustic_curve" in result:
            print_table(result)
    (args.out / "results.json").write_text(json.dumps(results, indent=2) + "\n")
    chart(results, args.out / "error_vs_time.svg")


if __name__ == "__main__":
    main()
