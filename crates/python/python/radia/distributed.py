"""Renders on a Ray cluster: one image, or the frames of an animation (one scene file per frame).

    import ray, radia.distributed as rd
    ray.init()                                    # local CPUs; ray.init(address="auto") on a cluster
    image = rd.render("scenes/cornell-box.xml", spp=1024, defines={"res": 512})
    frames = rd.render_frames(["f000.xml", "f001.xml"], spp=256, outputs="frame-{:03d}.exr")

How: a pool of Ray actors (``workers`` of them, ``cpus_per_worker`` threads each) load each
scene once, on first use, and render ranges of sample indices of it (:func:`radia.render` with
``samples=(a, b)``). The driver merges the pieces of a frame as they arrive, in ascending order
of their first sample whatever the order of arrival, so the image has the same bits however
the pieces were scheduled, and it equals one render of all the samples up to float rounding
(exactly, with a box filter, when pieces are single passes of 16 samples).

Ray does the scheduling and the recovery (no scheduler of our own): pieces go to idle actors
through ``ray.util.ActorPool``; an actor whose process dies is restarted by Ray
(``max_restarts``), reloads its scene, and the piece it was rendering is re-run by Ray
(``max_task_retries``); the log says so ("restarted"). The samples of a pixel depend only on
the seed, the pixel and the sample index, so the re-run piece is the same piece.

Scene paths must be readable by every worker (a shared file system, or the same checkout on
every node); relative paths are made absolute on the driver.
"""
import os
import sys
import time
import warnings

import numpy as np

from . import _native

__all__ = ["render", "render_frames", "piece_ranges"]

#: Samples of one pass of the renderer: pieces whose ends are multiples of it group their
#: samples exactly as one render does.
PASS_SPP = 16


def piece_ranges(spp, pieces):
    """Splits [0, spp) into at most ``pieces`` ranges whose ends are multiples of 16 (but the
    last), as even as possible."""
    passes = max(1, -(-spp // PASS_SPP))
    pieces = max(1, min(pieces, passes))
    ends = [min(spp, PASS_SPP * (passes * i // pieces)) for i in range(pieces + 1)]
    ends[-1] = spp
    return [(a, b) for a, b in zip(ends[:-1], ends[1:]) if a < b]


def _worker_class(ray):
    """The actor, defined once Ray is imported (the module imports without Ray)."""

    @ray.remote
    class RadiaWorker:
        """Loads scenes once (cached by path and defines) and renders sample ranges of them."""

        def __init__(self, threads):
            self.threads = threads
            self.scenes = {}
            self.unreported = set()   # scenes whose load time no piece has reported yet
            with warnings.catch_warnings():   # Ray 2.60 warns from inside this property
                warnings.simplefilter("ignore", DeprecationWarning)
                self.restarted = ray.get_runtime_context().was_current_actor_reconstructed
            if self.restarted:
                print(f"radia.distributed: worker restarted after a failure (pid {os.getpid()});"
                      " it reloads its scenes", file=sys.stderr, flush=True)

        def pid(self):
            return os.getpid()

        def _scene(self, path, defines):
            key = (path, defines)
            if key not in self.scenes:
                t0 = time.perf_counter()
                self.scenes[key] = (_native.load_file(path, **dict(defines)),
                                    time.perf_counter() - t0)
                self.unreported.add(key)
            return self.scenes[key]

        def _report_load(self, path, defines):
            """The load time of the scene with the first piece of it this worker renders (it
            may have loaded it for info()), 0 with the others."""
            key = (path, defines)
            if key in self.unreported:
                self.unreported.discard(key)
                return self.scenes[key][1]
            return 0.0

        def info(self, path, defines, spp):
            scene, load_secs = self._scene(path, defines)
            return {"spp": scene.render_spp(spp), "resolution": scene.resolution,
                    "load_secs": load_secs}

        def render(self, frame, path, defines, spp, seed, samples):
            scene, _ = self._scene(path, defines)
            t0, cpu0 = time.perf_counter(), time.process_time()
            part = _native.render(scene, spp=spp, seed=seed, threads=self.threads,
                                  samples=samples)
            return frame, part, {"pid": os.getpid(), "render_secs": time.perf_counter() - t0,
                                 "render_cpu_secs": time.process_time() - cpu0,
                                 "load_secs": self._report_load(path, defines),
                                 "finished_at": time.time(),
                                 "restarted": self.restarted, "samples": samples}

    return RadiaWorker


def _import_ray():
    try:
        import ray
    except ImportError as e:
        raise ImportError("radia.distributed needs Ray: pip install ray") from e
    return ray


class _Frame:
    """One frame's pieces merged in ascending order of first sample as they arrive."""

    def __init__(self, index, ranges):
        self.index = index
        self.total = len(ranges)
        self.next = 0            # first sample of the next piece to add
        self.waiting = {}        # first sample -> part, arrived early
        self.merged = None
        self.received = 0

    def add(self, part):
        self.received += 1
        self.waiting[part.samples[0][0]] = part
        while self.next in self.waiting:
            p = self.waiting.pop(self.next)
            self.merged = p if self.merged is None else _native._merge([self.merged, p])
            self.next = p.samples[-1][1]

    @property
    def done(self):
        return self.received == self.total


def render_frames(scenes, spp=None, seed=0, *, defines=None, outputs=None, pieces=None,
                  workers=None, cpus_per_worker=1, address=None, progress=True,
                  max_restarts=4, max_task_retries=4, on_piece=None):
    """Renders each scene file of ``scenes`` (the frames of an animation) on Ray and returns
    their images, float32 (height, width, 3) arrays, in order.

    spp, seed: as :func:`radia.render` (spp defaults to each scene's).
    defines: dict of scene parameters (as ``radia.load_file(path, **defines)``), for every frame.
    outputs: a format string with one ``{}`` for the frame index (``"frame-{:04d}.exr"``) or a
        list of paths: each frame is written (EXR or PNG) as soon as its last piece is merged.
    pieces: sample ranges per frame (default: 2 per worker, each a multiple of 16 samples).
    workers: actors to start (default: the cluster's CPUs // cpus_per_worker).
    cpus_per_worker: CPUs (render threads) of each actor.
    address: passed to ``ray.init`` if Ray is not initialised yet (None: a local cluster).
    progress: print progress to stderr.
    max_restarts, max_task_retries: Ray's recovery of dead actors and of their pieces.
    on_piece: called as ``on_piece(frame, info)`` on the driver when a piece arrives and is
        merged. info: pid, samples, restarted; render_secs and render_cpu_secs (the render
        in the worker: wall and CPU seconds of its process),
        load_secs (this worker's load of the scene, with the first piece of it the worker
        renders; 0 with the others),
        finished_at and arrived_at (``time.time()`` at the end of the task in the worker and
        when the driver had the piece: their difference is the transfer, on one clock only on
        one machine), merge_secs (merging it on the driver).
    """
    ray = _import_ray()
    if not ray.is_initialized():
        ray.init(address=address, log_to_driver=True)
    paths = [os.path.abspath(os.fspath(p)) for p in scenes]
    defs = tuple(sorted((str(k), str(v)) for k, v in (defines or {}).items()))
    if workers is None:
        workers = max(1, int(ray.cluster_resources().get("CPU", 1)) // cpus_per_worker)
    worker_cls = _worker_class(ray).options(num_cpus=cpus_per_worker,
                                            max_restarts=max_restarts,
                                            max_task_retries=max_task_retries)
    actors = [worker_cls.remote(cpus_per_worker) for _ in range(workers)]
    log = (lambda msg: print("radia.distributed: " + msg, file=sys.stderr, flush=True)) \
        if progress else (lambda msg: None)
    try:
        return _run(ray, actors, paths, defs, spp, seed, outputs, pieces or 2 * workers,
                    log, progress, on_piece)
    finally:
        for a in actors:
            ray.kill(a, no_restart=True)


def _run(ray, actors, paths, defs, spp, seed, outputs, pieces, log, progress, on_piece):
    from ray.util.actor_pool import ActorPool
    t0 = time.perf_counter()
    # Each frame's sample count (rounded as its sampler requires) from a worker, which keeps
    # the scene it loaded for it.
    infos = ray.get([actors[i % len(actors)].info.remote(p, defs, spp)
                     for i, p in enumerate(paths)])
    frames, jobs = [], []
    for f, (path, info) in enumerate(zip(paths, infos)):
        ranges = piece_ranges(info["spp"], pieces)
        frames.append(_Frame(f, ranges))
        jobs += [(f, path, info["spp"], r) for r in ranges]
    log(f"{len(paths)} frame(s), {len(jobs)} pieces on {len(actors)} workers "
        f"(scene load {max(i['load_secs'] for i in infos):.2f} s)")
    pool = ActorPool(actors)
    for f, path, frame_spp, r in jobs:
        pool.submit(lambda a, job: a.render.remote(job[0], job[1], defs, job[2], seed, job[3]),
                    (f, path, frame_spp, r))
    images = [None] * len(paths)
    done = 0
    while pool.has_next():
        f, part, info = pool.get_next_unordered()
        info["arrived_at"] = time.time()
        done += 1
        frame = frames[f]
        t_merge = time.perf_counter()
        frame.add(part)
        info["merge_secs"] = time.perf_counter() - t_merge
        if info["restarted"]:
            log(f"frame {f} samples {info['samples'][0]}..{info['samples'][1]}: rendered by a "
                f"restarted worker (pid {info['pid']}), a retry")
        if on_piece is not None:
            on_piece(f, info)
        if progress:
            log(f"{done}/{len(jobs)} pieces, {time.perf_counter() - t0:.1f} s")
        if frame.done:
            images[f] = frame.merged.develop()
            frame.merged = None
            if outputs is not None:
                out = outputs.format(f) if isinstance(outputs, str) else outputs[f]
                _native.write_image(images[f], out)
                log(f"frame {f} -> {out}")
    return images


def render(scene, spp=None, seed=0, **kwargs):
    """Renders one scene file on Ray; the image as a float32 (height, width, 3) array. Takes
    the keyword arguments of :func:`render_frames` (``outputs`` a path)."""
    out = kwargs.pop("outputs", None)
    return render_frames([scene], spp, seed, outputs=[out] if out else None, **kwargs)[0]
