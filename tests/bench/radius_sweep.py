"""The default first radius against the best of a sweep, at equal CPU time (a benchmark, not a
test: run it by hand on an idle machine, release build first):

    cargo build --release
    target/bpy-venv/bin/python tests/bench/radius_sweep.py [--scenes sunlit_closeup,sunlit_room]
        [--budgets 10,60] [--factors 0.25,0.35,0.5,0.7,1.4,2,2.8,4] [--threads 2]
        [--caustic-flags "--photon-sampling visible"] [-o bench-out/radius]

Each scene is built in Blender and exported by the add-on (tests/bench/blender_scenes.py). Caustic
renders it once with its default radius (no `--radius`: what `caustic info` reports as
`initial_radius`) and once for each factor times that radius, each for the largest budget with
`--log` and `--reference`; the error (relative MSE of luminance against tests/bench/<scene>.exr,
as vs_cycles.py measures it) at each budget is read from the log. Prints, per scene and budget,
the error at every radius, the best radius, and the default's error over the best's; writes
OUT/results.json. References: `vs_cycles.py --make-reference PASSES --scenes ...`.
"""
import argparse
import json
import pathlib
import subprocess
import sys
import tempfile

HERE = pathlib.Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from vs_cycles import BENCH_SEED, ROOT, caustic_curve, error_at, parse_resolution, render_caustic  # noqa: E402
from blender_scenes import SCENES, build, export  # noqa: E402


def default_radius(binary, gltf, flags):
    """The first radius Caustic chooses for `gltf` with `flags` (`caustic info`)."""
    printed = subprocess.run([binary, "info", str(gltf), *flags], check=True, capture_output=True, text=True)
    return json.loads(printed.stdout)["photons"]["initial_radius"]


def error_curve(args, name, gltf, work, radius):
    """Caustic's (CPU s, relative MSE, passes) curve with first radius `radius` (None: the
    default)."""
    log = work / f"log-{radius}.jsonl"
    flags = ["--time-budget", str(max(args.budgets) / args.threads), "--threads", str(args.threads),
             "--seed", str(BENCH_SEED), "--log", str(log), "--reference", str(HERE / f"{name}.exr"),
             *args.caustic_flags.split()]
    if radius is not None:
        flags += ["--radius", f"{radius:.6g}"]
    render_caustic(args.binary, gltf, work / "out", flags)
    return caustic_curve(log, args.threads)


def sweep_scene(name, args):
    scene = build(name, args.resolution, args.binary)
    work = pathlib.Path(tempfile.mkdtemp(prefix=f"caustic-sweep-{name}-"))
    gltf = export(scene, work)
    default = default_radius(args.binary, gltf, args.caustic_flags.split())
    rows = [{"radius": default, "factor": 1.0, "default": True, "curve": error_curve(args, name, gltf, work, None)}]
    for factor in args.factors:
        radius = default * factor
        rows.append({"radius": radius, "factor": factor, "default": False,
                     "curve": error_curve(args, name, gltf, work, radius)})
    for row in rows:
        row["errors"] = {str(b): error_at(row["curve"], b) for b in args.budgets}
    return {"scene": name, "default_radius": default, "rows": rows}


def print_table(result, budgets):
    print(f"\n{result['scene']}: relative MSE at equal CPU time, default radius {result['default_radius']:.4g}")
    print(f"{'radius':>9} {'x default':>9} " + " ".join(f"{f'{b:g} CPU s':>12}" for b in budgets))
    for row in sorted(result["rows"], key=lambda r: r["radius"]):
        errors = " ".join(f"{row['errors'][str(b)]:>12.4g}" if row["errors"][str(b)] else f"{'-':>12}"
                          for b in budgets)
        print(f"{row['radius']:>9.4g} {row['factor']:>9.3g} {errors}" + ("   (default)" if row["default"] else ""))
    for b in budgets:
        measured = [r for r in result["rows"] if r["errors"][str(b)]]
        best = min(measured, key=lambda r: r["errors"][str(b)])
        default = next(r for r in measured if r["default"])
        ratio = default["errors"][str(b)] / best["errors"][str(b)]
        result.setdefault("default_over_best", {})[str(b)] = ratio
        print(f"{b:g} CPU s: best radius {best['radius']:.4g} ({best['factor']:g}x the default); "
              f"the default's error is {ratio:.3f}x the best's")


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--scenes", default="sunlit_closeup,sunlit_room", type=lambda s: s.split(","))
    parser.add_argument("--budgets", default="10,60", type=lambda s: [float(v) for v in s.split(",")],
                        help="CPU seconds")
    parser.add_argument("--factors", default="0.25,0.35,0.5,0.7,1.4,2,2.8,4",
                        type=lambda s: [float(v) for v in s.split(",")], help="radii, as multiples of the default")
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--resolution", type=parse_resolution, default=(256, 192))
    parser.add_argument("-o", "--out", type=pathlib.Path, default=ROOT / "bench-out" / "radius")
    parser.add_argument("--binary", default=str(ROOT / "target" / "release" / "caustic"))
    parser.add_argument("--caustic-flags", default="", help="more flags for caustic render and info")
    args = parser.parse_args()
    unknown = [s for s in args.scenes if s not in SCENES]
    if unknown:
        parser.error(f"unknown scene {unknown[0]!r}; the scenes are {', '.join(SCENES)}")
    missing = [s for s in args.scenes if not (HERE / f"{s}.exr").exists()]
    if missing:
        parser.error(f"no reference tests/bench/{missing[0]}.exr: make it with vs_cycles.py --make-reference")
    args.out.mkdir(parents=True, exist_ok=True)
    results = [sweep_scene(name, args) for name in args.scenes]
    for result in results:
        print_table(result, args.budgets)
    (args.out / "results.json").write_text(json.dumps(results, indent=2) + "\n")


if __name__ == "__main__":
    main()
