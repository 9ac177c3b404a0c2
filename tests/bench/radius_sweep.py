"""A default setting against the best of a sweep, at equal CPU time: the first radius, or the
photons a pass (a benchmark, not a test: run it by hand on an idle machine, release build first):

    cargo build --release
    target/bpy-venv/bin/python tests/bench/radius_sweep.py [--scenes sunlit_closeup,sunlit_room]
        [--setting radius|photons] [--budgets 10,60] [--factors 0.25,0.35,0.5,0.7,1.4,2,2.8,4]
        [--threads 2] [--caustic-flags "--photon-sampling visible"] [-o bench-out/radius]

Each scene is built in Blender and exported by the add-on (tests/bench/blender_scenes.py). Caustic
renders it once with the setting's default (no `--radius` or `--photons`: what `caustic info`
reports as `initial_radius` and `per_pass`) and once for each factor times that default, each for
the largest budget with `--log` and `--reference`; the error (relative MSE of luminance against
tests/bench/<scene>.exr, as vs_cycles.py measures it) at each budget is read from the log. Prints,
per scene and budget, the error at every value, the best, and the default's error over the
best's, both above the reference's own error where references.json gives it (the floor every
error measured against it shares); writes OUT/results.json. References: `vs_cycles.py
--make-reference PASSES --scenes ...`.
"""
import argparse
import json
import pathlib
import subprocess
import sys
import tempfile

HERE = pathlib.Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from vs_cycles import (BENCH_SEED, ROOT, above_floor, caustic_curve, error_at, parse_resolution,  # noqa: E402
                       reference_floor, render_caustic)
from blender_scenes import SCENES, build, export  # noqa: E402


# The settings swept: the flag, the key of `caustic info`'s `photons` that gives its default, and
# how a value is written.
SETTINGS = {"radius": ("--radius", "initial_radius", lambda v: f"{v:.6g}"),
            "photons": ("--photons", "per_pass", lambda v: str(max(1, round(v))))}


def default_value(binary, gltf, setting, flags):
    """The value Caustic chooses for `setting` in `gltf` with `flags` (`caustic info`)."""
    printed = subprocess.run([binary, "info", str(gltf), *flags], check=True, capture_output=True, text=True)
    return json.loads(printed.stdout)["photons"][SETTINGS[setting][1]]


def error_curve(args, name, gltf, work, value):
    """Caustic's (CPU s, relative MSE, passes) curve with the setting at `value` (None: the
    default)."""
    log = work / f"log-{value}.jsonl"
    flags = ["--time-budget", str(max(args.budgets) / args.threads), "--threads", str(args.threads),
             "--seed", str(BENCH_SEED), "--log", str(log), "--reference", str(HERE / f"{name}.exr"),
             *args.caustic_flags.split()]
    if value is not None:
        flag, _, written = SETTINGS[args.setting]
        flags += [flag, written(value)]
    render_caustic(args.binary, gltf, work / "out", flags)
    return caustic_curve(log, args.threads)


def sweep_scene(name, args):
    scene = build(name, args.resolution, args.binary)
    work = pathlib.Path(tempfile.mkdtemp(prefix=f"caustic-sweep-{name}-"))
    gltf = export(scene, work)
    default = default_value(args.binary, gltf, args.setting, args.caustic_flags.split())
    rows = [{"value": default, "factor": 1.0, "default": True, "curve": error_curve(args, name, gltf, work, None)}]
    for factor in args.factors:
        value = default * factor
        rows.append({"value": value, "factor": factor, "default": False,
                     "curve": error_curve(args, name, gltf, work, value)})
    floor = reference_floor(name)
    for row in rows:
        row["errors"] = {str(b): error_at(row["curve"], b) for b in args.budgets}
        row["above_floor"] = {b: above_floor(e, floor) for b, e in row["errors"].items()}
    return {"scene": name, "setting": args.setting, "flags": args.caustic_flags, "default": default,
            "reference_floor": floor, "rows": rows}


def print_table(result, budgets):
    floor = result["reference_floor"]
    # The errors compared: above the reference's own where it is known.
    key = "errors" if floor is None else "above_floor"
    print(f"\n{result['scene']} {result['flags']}: relative MSE at equal CPU time, default {result['setting']} "
          f"{result['default']:.4g}" + ("" if floor is None else f"; above the reference's own ({floor:.3g})"))
    print(f"{result['setting']:>9} {'x default':>9} " + " ".join(f"{f'{b:g} CPU s':>12}" for b in budgets))
    for row in sorted(result["rows"], key=lambda r: r["value"]):
        errors = " ".join(f"{row[key][str(b)]:>12.4g}" if row[key][str(b)] else f"{'-':>12}" for b in budgets)
        print(f"{row['value']:>9.4g} {row['factor']:>9.3g} {errors}" + ("   (default)" if row["default"] else ""))
    for b in budgets:
        measured = [r for r in result["rows"] if r[key][str(b)]]
        best = min(measured, key=lambda r: r[key][str(b)])
        default = next(r for r in measured if r["default"])
        ratio = default[key][str(b)] / best[key][str(b)]
        result.setdefault("default_over_best", {})[str(b)] = ratio
        print(f"{b:g} CPU s: best {result['setting']} {best['value']:.4g} ({best['factor']:g}x the default); "
              f"the default's error is {ratio:.3f}x the best's")


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--scenes", default="sunlit_closeup,sunlit_room", type=lambda s: s.split(","))
    parser.add_argument("--setting", choices=SETTINGS, default="radius")
    parser.add_argument("--budgets", default="10,60", type=lambda s: [float(v) for v in s.split(",")],
                        help="CPU seconds")
    parser.add_argument("--factors", default="0.25,0.35,0.5,0.7,1.4,2,2.8,4",
                        type=lambda s: [float(v) for v in s.split(",")], help="radii, as multiples of the default")
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--resolution", type=parse_resolution, default=(256, 192))
    parser.add_argument("-o", "--out", type=pathlib.Path, default=ROOT / "bench-out" / "radius")
    parser.add_argument("--binary", default=str(ROOT / "target" / "release" / "caustic"))
    parser.add_argument("--caustic-flags", default="", help="more flags for caustic render and info (--photon-sampling, --photons)")
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
