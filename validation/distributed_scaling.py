#!/usr/bin/env python3
"""How radia.distributed scales from 1 to 2 local Ray workers, and what a task costs besides
its render: one scene rendered by `radia render --threads 1` and `--threads 2` (the whole
process, load included: the baseline) and by radia.distributed on a local Ray cluster with 1
and with 2 workers of 1 thread each, in the same number of pieces. Prints markdown tables:
wall times (medians of --repeats), speed-ups, and per task the render time against the
overheads: the scene load in the worker (once per worker), the transfer of the piece back to
the driver, and its merge there.

  validation/.venv/bin/python validation/distributed_scaling.py            # cornell-box, 256², 128 spp
  validation/.venv/bin/python validation/distributed_scaling.py SCENE --res 128 --spp 64 --pieces 4

Needs Ray (validation/requirements.txt) and the radia package (validation/setup), and the
binary (cargo build --release -p radia-cli). Not part of CI: it measures, on an idle machine.
"""
import argparse
import os
import pickle
import statistics
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import numpy as np  # noqa: E402

from radiaval.common import DEFAULT_RADIA, REPO_ROOT, check_radia, radia_package, read_exr  # noqa: E402

CORNELL = os.path.join(REPO_ROOT, "scenes", "cornell-box.xml")


def cli_wall(binary, scene, res, spp, seed, threads, out):
    """Wall and CPU (user + system) seconds of one `radia render` process, load and write
    included. CPU over wall below the thread count says another process had the cores."""
    cmd = [binary, "render", scene, "-q", "-D", f"res={res}", "--spp", str(spp),
           "--seed", str(seed), "--threads", str(threads), "-o", out]
    t0 = time.perf_counter()
    p = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    output = p.stdout.read()
    _, status, usage = os.wait4(p.pid, 0)
    p.returncode = os.waitstatus_to_exitcode(status)
    wall = time.perf_counter() - t0
    if p.returncode != 0:
        raise SystemExit(f"radia failed: {' '.join(cmd)}\n{output[-2000:]}")
    return wall, usage.ru_utime + usage.ru_stime


def distributed_run(rd, scene, res, spp, seed, pieces, workers):
    """One radia.distributed render: (wall s, image, [per-piece info])."""
    infos = []
    t0 = time.perf_counter()
    image = rd.render(scene, spp=spp, seed=seed, defines={"res": res}, pieces=pieces,
                      workers=workers, cpus_per_worker=1, progress=False,
                      on_piece=lambda frame, info: infos.append(info))
    return time.perf_counter() - t0, image, infos


def med(xs):
    return statistics.median(xs) if xs else float("nan")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("scene", nargs="?", default=CORNELL)
    ap.add_argument("--res", type=int, default=256, help="film size (-D res=; default 256)")
    ap.add_argument("--spp", type=int, default=128, help="samples per pixel (default 128)")
    ap.add_argument("--pieces", type=int, default=8, help="pieces of the render (default 8)")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--repeats", type=int, default=3, help="runs of each, medians (default 3)")
    ap.add_argument("--radia", default=DEFAULT_RADIA, help="the binary for the baseline")
    a = ap.parse_args(argv)
    binary = check_radia(a.radia)
    radia = radia_package(binary_option=False)  # --radia is only the baseline's binary
    import radia.distributed as rd
    import ray

    scene = os.path.abspath(a.scene)
    name = os.path.relpath(scene, REPO_ROOT)
    tmp = tempfile.mkdtemp(prefix="radia-scaling-")
    cli_out = os.path.join(tmp, "cli.exr")
    t0 = time.perf_counter()
    ray.init(num_cpus=2, include_dashboard=False, _node_ip_address="127.0.0.1",
             log_to_driver=False)
    ray_init = time.perf_counter() - t0

    walls = {k: [] for k in ("t1", "t2", "w1", "w2")}
    cpus = {"t1": [], "t2": []}
    tasks = {1: [], 2: []}
    image = None
    for r in range(a.repeats):
        for threads in (1, 2):
            wall, cpu = cli_wall(binary, scene, a.res, a.spp, a.seed, threads, cli_out)
            walls[f"t{threads}"].append(wall)
            cpus[f"t{threads}"].append(cpu)
        for workers in (1, 2):
            wall, image, infos = distributed_run(rd, scene, a.res, a.spp, a.seed, a.pieces,
                                                 workers)
            walls[f"w{workers}"].append(wall)
            tasks[workers].append(infos)
        print(f"run {r + 1}/{a.repeats}: " + ", ".join(
            f"{k} {v[-1]:.2f} s" for k, v in walls.items()), file=sys.stderr, flush=True)
    ray.shutdown()

    # The pieces merged equal the CLI's single render (float rounding apart).
    ref = read_exr(cli_out)
    rel = float(np.max(np.abs(image - ref) / np.maximum(np.abs(ref), 1e-6)))
    part = radia.render(radia.load_file(scene, res=a.res), spp=a.spp, seed=a.seed,
                        samples=(0, 16))
    piece_mb = len(pickle.dumps(part)) / 1e6

    def per_task(workers, key):
        return med([i[key] for run in tasks[workers] for i in run])

    def loads(workers):
        return med([i["load_secs"] for run in tasks[workers] for i in run if i["load_secs"]])

    def transfer(workers):
        return med([i["arrived_at"] - i["finished_at"] for run in tasks[workers] for i in run])

    def busiest(workers):
        """Per run, the busiest worker's render + load seconds; the median over runs."""
        out = []
        for run in tasks[workers]:
            by_pid = {}
            for i in run:
                by_pid[i["pid"]] = by_pid.get(i["pid"], 0.0) + i["render_secs"] + i["load_secs"]
            out.append(max(by_pid.values()))
        return med(out)

    m = {k: med(v) for k, v in walls.items()}
    c = {k: med(v) for k, v in cpus.items()}

    def worker_cpu(workers):
        """Per run, the render CPU seconds of all pieces; the median over runs."""
        return med([sum(i["render_cpu_secs"] for i in run) for run in tasks[workers]])
    n_pieces = len(tasks[1][0])
    print(f"\n{name} at {a.res}x{a.res}, {a.spp} spp, seed {a.seed}; {n_pieces} pieces; "
          f"medians of {a.repeats} runs; {os.cpu_count()} CPUs; ray.init {ray_init:.1f} s "
          "(not counted)\n")
    print("| run | wall s | CPU s | speed-up (wall) |")
    print("| --- | ---: | ---: | ---: |")
    print(f"| `radia render --threads 1` (process: load, render, write) | {m['t1']:.2f} | "
          f"{c['t1']:.2f} | 1.00 |")
    print(f"| `radia render --threads 2` | {m['t2']:.2f} | {c['t2']:.2f} | "
          f"{m['t1'] / m['t2']:.2f} |")
    print(f"| radia.distributed, 1 worker × 1 thread | {m['w1']:.2f} | {worker_cpu(1):.2f} "
          f"(renders) | {m['t1'] / m['w1']:.2f} |")
    print(f"| radia.distributed, 2 workers × 1 thread | {m['w2']:.2f} | {worker_cpu(2):.2f} "
          f"(renders) | {m['t1'] / m['w2']:.2f} (× {m['w1'] / m['w2']:.2f} over 1 worker) |")
    print()
    print("| per task (median) | 1 worker | 2 workers |")
    print("| --- | ---: | ---: |")
    print(f"| render of the piece ({a.spp // max(1, n_pieces)} spp) in the worker, wall | "
          f"{per_task(1, 'render_secs'):.3f} s | {per_task(2, 'render_secs'):.3f} s |")
    print(f"| the same, CPU | {per_task(1, 'render_cpu_secs'):.3f} s | "
          f"{per_task(2, 'render_cpu_secs'):.3f} s |")
    print(f"| scene load in the worker (once per worker) | {loads(1):.3f} s | {loads(2):.3f} s |")
    print(f"| transfer of the piece to the driver ({piece_mb:.2f} MB pickled) | "
          f"{transfer(1) * 1e3:.1f} ms | {transfer(2) * 1e3:.1f} ms |")
    print(f"| merge on the driver | {per_task(1, 'merge_secs') * 1e3:.1f} ms | "
          f"{per_task(2, 'merge_secs') * 1e3:.1f} ms |")
    print(f"| rest of the wall (actor start, first call, scheduling; whole run) | "
          f"{m['w1'] - busiest(1):.2f} s | {m['w2'] - busiest(2):.2f} s |")
    print(f"\nThe 2-worker image against `radia render`'s: max relative difference {rel:.2g} "
          "(at most float rounding; 0 is bit for bit, as with a box filter and pieces of whole "
          "16-sample passes).")
    return 0


if __name__ == "__main__":
    sys.exit(main())
