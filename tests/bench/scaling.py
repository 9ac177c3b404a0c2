"""How a pass's cost grows with pixels, photons and triangles, and the peak memory of a full-HD
frame with a million photons a pass (a benchmark, not a test: run it on an idle machine):

    cargo build --release
    target/bpy-venv/bin/python tests/bench/scaling.py [--passes 16] [--threads 2]

Exports the demo scene and the demo with 10x its triangles (tests/bench/blender_scenes.py), runs
`caustic bench` on each case and prints the time of a pass with 2 threads against the base case:
2x the pixels at the same photons, 2x both (the default is one photon per pixel), 2x the photons
at the same pixels, 10x the triangles; then the peak heap memory at 1920x1080 with 1,000,000
photons a pass.
"""
import argparse
import pathlib
import re
import subprocess
import sys
import tempfile

HERE = pathlib.Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from blender_scenes import ROOT, build, export  # noqa: E402  (imports bpy)


def bench(binary, scene, resolution, passes, photons=None):
    """`caustic bench`'s output and its milliseconds a pass with 2 threads."""
    width, height = resolution
    command = [binary, "bench", str(scene), "--resolution", f"{width}x{height}", "--passes", str(passes)]
    if photons:
        command += ["--photons", str(photons)]
    printed = subprocess.run(command, check=True, capture_output=True, text=True).stdout
    ms = float(re.search(r"threads 2: [\d.]+ passes/s \(([\d.]+) ms a pass\)", printed).group(1))
    return printed, ms


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--passes", type=int, default=16)
    parser.add_argument("--binary", default=str(ROOT / "target" / "release" / "caustic"))
    args = parser.parse_args()
    work = pathlib.Path(tempfile.mkdtemp(prefix="caustic-scaling-"))
    base = (480, 360)
    scenes = {}
    for name in ("caustic", "caustic_10x_triangles"):
        folder = work / name
        folder.mkdir()
        scenes[name] = export(build(name, base, args.binary), folder)
    pixels = base[0] * base[1]
    cases = [
        ("base: 480x360, one photon per pixel", scenes["caustic"], base, None),
        ("2x pixels, same photons: 679x509", scenes["caustic"], (679, 509), pixels),
        ("2x pixels and photons: 679x509, one per pixel", scenes["caustic"], (679, 509), None),
        ("2x photons: 480x360, two per pixel", scenes["caustic"], base, 2 * pixels),
        ("10x triangles", scenes["caustic_10x_triangles"], base, None),
    ]
    results = []
    for label, scene, resolution, photons in cases:
        printed, ms = bench(args.binary, scene, resolution, args.passes, photons)
        print(f"--- {label}\n{printed}")
        results.append((label, ms))
    print("pass time with 2 threads against the base case:")
    for label, ms in results:
        print(f"  {label:<48} {ms:8.1f} ms  {ms / results[0][1]:.2f}x")
    printed, _ = bench(args.binary, scenes["caustic"], (1920, 1080), 2, 1_000_000)
    print(f"--- 1920x1080, 1,000,000 photons a pass\n{printed}")


if __name__ == "__main__":
    main()
