"""End to end on a real distributed engine: Dask, with a local cluster of two worker processes
started and stopped here. farm/dask_render.py renders scenes/shot.gltf as 2 frames x 4 pass
chunks, merges each frame, and the merged EXRs must equal a single-process render of the same
passes (frame by frame, as the tasks render them) byte for byte. Prints the wall times.

    CAUSTIC_BINARY=target/debug/caustic python tests/farm/dask_test.py   (needs distributed)
"""
import argparse
import os
import pathlib
import subprocess
import sys
import tempfile
import time

from dask.distributed import Client, LocalCluster, get_task_stream

ROOT = pathlib.Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "farm"))
import dask_render  # noqa: E402

BINARY = os.environ["CAUSTIC_BINARY"]
FLAGS = ["--resolution", "64x48", "--photons", "4000", "--seed", "3"]


def main():
    out = pathlib.Path(tempfile.mkdtemp(prefix="caustic-dask-"))
    scene = ROOT / "scenes" / "shot.gltf"
    args = argparse.Namespace(scene=str(scene), frames="1-2", passes=16, chunks=4, out=str(out / "farm"),
                              caustic=BINARY)
    start = time.perf_counter()
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster, \
            Client(cluster) as client:
        with get_task_stream(client) as stream:
            dask_render.render_on(client, args, FLAGS)
        farm_s = time.perf_counter() - start
    renders = [task for task in stream.data if "render_chunk" in str(task["key"])]
    workers, chunks = {task["worker"] for task in renders}, len(renders)
    # One process, the same passes. Frames rendered apart trace each frame's paths alone, as
    # `--no-reuse` does (rendered together, frames share paths and their sums differ in rounding).
    single_s = {}
    for mode in ("--no-reuse", "--memory-budget=4G"):
        start = time.perf_counter()
        subprocess.run([BINARY, "render", str(scene), "--frames", "1,2", "--passes", "16", "--progress", "none",
                        "-o", str(out / mode.strip("-")), mode, *FLAGS], check=True, capture_output=True)
        single_s[mode] = time.perf_counter() - start
    print(f"dask: {chunks} render tasks on {len(workers)} workers and 2 merges in {farm_s:.2f} s (cluster start "
          f"included); one process, same passes: {single_s['--no-reuse']:.2f} s frame by frame, "
          f"{single_s['--memory-budget=4G']:.2f} s with the frames sharing paths")
    assert chunks == 8, f"{chunks} render tasks, expected 2 frames x 4 chunks"
    assert len(workers) >= 2, f"the render tasks ran on {len(workers)} worker(s)"
    for frame in ("frame_0001.exr", "frame_0002.exr"):
        merged, single = (out / "farm" / frame).read_bytes(), (out / "no-reuse" / frame).read_bytes()
        assert merged == single, f"{frame}: the merged frame differs from the single-process render"
    print("dask end-to-end: merged frames equal the single-process render")


if __name__ == "__main__":
    main()
