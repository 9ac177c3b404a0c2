"""Renders a shot on a Dask cluster: every frame in pass chunks (`caustic render --pass-range A..B
--partial`), then one `caustic merge` per frame that waits for that frame's chunks.

    pip install "distributed==2026.8.0"
    python farm/dask_render.py SCENE.gltf --frames 1-2 --passes 64 --chunks 4 -o OUT
                               [--scheduler tcp://host:8786 | --workers 2] [--caustic PATH]
                               [-- more caustic render flags]

With `--scheduler` it uses a running cluster (`dask scheduler` on one machine, `dask worker
tcp://host:8786` on each render node, all seeing OUT and the scene at the same paths); otherwise it
starts a local cluster of `--workers` worker processes and stops it at the end. Prints the frames
written and the wall time.
"""
import argparse
import pathlib
import subprocess
import sys
import time

from dask.distributed import Client, LocalCluster


def render_chunk(caustic, scene, frame, first, end, partials, flags):
    """One task: passes first..end of one frame, as a partial result. Returns its file."""
    subprocess.run([caustic, "render", scene, "--frames", str(frame), "--pass-range", f"{first}..{end}", "--partial",
                    "--progress", "none", "--threads", "1", "-o", partials, *flags],
                   check=True, capture_output=True, text=True)
    return str(pathlib.Path(partials) / f"frame_{frame:04}.passes_{first}-{end}.partial")


def merge_frame(caustic, out, *files):
    """One task: a frame's partial results into OUT/frame_####.exr."""
    result = subprocess.run([caustic, "merge", *files, "-o", out], check=True, capture_output=True, text=True)
    return result.stderr.strip()


def pass_chunks(passes, chunks):
    """`chunks` contiguous [first, end) ranges covering 0..passes."""
    bounds = [round(passes * k / chunks) for k in range(chunks + 1)]
    return [(a, b) for a, b in zip(bounds, bounds[1:]) if b > a]


def frame_list(spec):
    frames = []
    for item in spec.split(","):
        first, _, last = item.partition("-")
        frames.extend(range(int(first), int(last or first) + 1))
    return frames


def render_on(client, args, flags):
    """Submits the shot's tasks to `client` and waits for the merged frames."""
    out = pathlib.Path(args.out).resolve()
    partials = str(out / "partials")
    merges = []
    for frame in frame_list(args.frames):
        chunks = [client.submit(render_chunk, args.caustic, str(pathlib.Path(args.scene).resolve()), frame, first, end,
                                partials, flags, pure=False)
                  for first, end in pass_chunks(args.passes, args.chunks)]
        merges.append(client.submit(merge_frame, args.caustic, str(out), *chunks, pure=False))
    return client.gather(merges)


def main(argv=None):
    argv = sys.argv[1:] if argv is None else argv
    own, flags = (argv[:argv.index("--")], argv[argv.index("--") + 1:]) if "--" in argv else (argv, [])
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("scene")
    parser.add_argument("--frames", default="1")
    parser.add_argument("--passes", type=int, default=64)
    parser.add_argument("--chunks", type=int, default=4, help="pass chunks per frame")
    parser.add_argument("-o", "--out", default="renders")
    parser.add_argument("--scheduler", help="address of a running Dask scheduler")
    parser.add_argument("--workers", type=int, default=2, help="local worker processes without --scheduler")
    parser.add_argument("--caustic", default="caustic", help="the caustic program on the workers")
    args = parser.parse_args(own)
    start = time.perf_counter()
    if args.scheduler:
        with Client(args.scheduler) as client:
            written = render_on(client, args, flags)
    else:
        with LocalCluster(n_workers=args.workers, threads_per_worker=1, processes=True,
                          dashboard_address=None) as cluster, Client(cluster) as client:
            written = render_on(client, args, flags)
    for line in written:
        print(line)
    print(f"wall time {time.perf_counter() - start:.2f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
