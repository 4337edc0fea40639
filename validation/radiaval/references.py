"""High-spp Mitsuba references: mean and variance-of-the-mean images of K
independent passes, cached as .npz with a JSON manifest."""
import datetime
import json
import os
import time

import numpy as np

from .common import (REF_SEED_BASE, REFERENCE_DIR, MitsubaRenderer, ValidationError,
                     log, mitsuba_version, rel_to_repo, scene_hash, scene_key)
from .stats import pass_moments

MANIFEST = "manifest.json"
DEFAULT_REF_PASSES = 64
DEFAULT_REF_SPP = 256          # per pass: 64 x 256 = 16384 spp in all
DEFAULT_REF_VARIANT = "llvm_ad_rgb"


def _manifest_path(ref_dir):
    return os.path.join(ref_dir, MANIFEST)


def load_manifest(ref_dir=REFERENCE_DIR):
    p = _manifest_path(ref_dir)
    if not os.path.exists(p):
        return {"format": 1, "references": {}}
    with open(p) as f:
        return json.load(f)


def save_manifest(man, ref_dir=REFERENCE_DIR):
    os.makedirs(ref_dir, exist_ok=True)
    tmp = _manifest_path(ref_dir) + ".tmp"
    with open(tmp, "w") as f:
        json.dump(man, f, indent=2, sort_keys=True)
        f.write("\n")
    os.replace(tmp, _manifest_path(ref_dir))


def entry_key(scene_path, res):
    return f"{scene_key(scene_path)}@{res}"


def _file_name(scene_path, res):
    return scene_key(scene_path).replace("/", "__").replace("\\", "__") + f"@{res}.npz"


def render_params(res, spp, passes, variant, seed_base=REF_SEED_BASE, defines=()):
    """What the reference's hash covers besides the scene's files. Every
    reference is rendered with Mitsuba's independent sampler and a box filter
    at res x res, whatever the scene declares: a constant, so not hashed (the
    hash of references made before those overrides existed stays valid).
    -D defines are hashed only when there are some, for the same reason."""
    p = {"res": int(res), "spp_per_pass": int(spp), "passes": int(passes),
         "variant": variant, "seed_base": int(seed_base)}
    if defines:
        p["defines"] = sorted(defines)
    return p


def make_reference(scene_path, res, spp=DEFAULT_REF_SPP, passes=DEFAULT_REF_PASSES,
                   variant=DEFAULT_REF_VARIANT, ref_dir=REFERENCE_DIR, threads=None, defines=()):
    """Render and store a reference (independent sampler, box filter, res x res,
    whatever the scene declares); returns its manifest entry."""
    params = render_params(res, spp, passes, variant, defines=defines)
    h, files = scene_hash(scene_path, params)
    log(f"reference: {rel_to_repo(scene_path)} {res}x{res}, {passes} passes x {spp} spp "
        f"({passes * spp} spp), {variant}")
    t0 = time.perf_counter()
    r = MitsubaRenderer(scene_path, res, spp, variant=variant, threads=threads, defines=defines,
                        sampler="independent", rfilter="box")
    imgs = r.passes(passes, seed0=REF_SEED_BASE,
                    progress=lambda i, n: (i % max(1, n // 8) == 0 or i == n) and
                    log(f"  pass {i}/{n}  {time.perf_counter() - t0:.1f} s"))
    total = time.perf_counter() - t0
    mean, var, k = pass_moments(imgs)
    os.makedirs(ref_dir, exist_ok=True)
    fname = _file_name(scene_path, res)
    np.savez_compressed(os.path.join(ref_dir, fname),
                        mean=mean.astype(np.float32), var=var.astype(np.float32))
    entry = dict(scene=scene_key(scene_path), file=fname, hash=h, files=files,
                 mitsuba_version=mitsuba_version(), threads=r.threads,
                 total_spp=passes * spp, render_time_s=round(total, 3),
                 load_time_s=round(r.load_time, 4),
                 created=datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
                 mean_rgb=[float(x) for x in mean.mean(axis=(0, 1))], **params)
    man = load_manifest(ref_dir)
    man["references"][entry_key(scene_path, res)] = entry
    save_manifest(man, ref_dir)
    log(f"  wrote {os.path.join(rel_to_repo(ref_dir), fname)} in {total:.1f} s, "
        f"mean RGB {entry['mean_rgb']}")
    return entry


class Reference:
    def __init__(self, entry, mean, var):
        self.entry = entry
        self.mean = mean
        self.var = var
        self.passes = entry["passes"]
        self.total_spp = entry["total_spp"]


def check_entry(scene_path, entry):
    """Raise ValidationError if the cached reference no longer matches the scene."""
    params = {k: entry[k] for k in ("res", "spp_per_pass", "passes", "variant", "seed_base",
                                    "defines") if k in entry}
    h, files = scene_hash(scene_path, params)
    if h != entry["hash"]:
        changed = sorted(set(f for f in set(files) | set(entry.get("files", {}))
                             if files.get(f) != entry.get("files", {}).get(f)))
        raise ValidationError(
            f"STALE reference for {scene_key(scene_path)} at res {entry['res']}: the scene "
            f"changed since the reference was made (changed: {', '.join(changed) or 'parameters'}). "
            f"Regenerate it: validation/.venv/bin/python validation/compare.py "
            f"--make-references {rel_to_repo(scene_path)} --res {entry['res']}")
    if entry.get("mitsuba_version") != mitsuba_version():
        raise ValidationError(
            f"reference for {scene_key(scene_path)} was made with Mitsuba "
            f"{entry.get('mitsuba_version')}, installed is {mitsuba_version()}: regenerate it")


def load_reference(scene_path, res, ref_dir=REFERENCE_DIR):
    man = load_manifest(ref_dir)
    key = entry_key(scene_path, res)
    entry = man["references"].get(key)
    if entry is None:
        have = sorted(k for k in man["references"] if k.startswith(scene_key(scene_path) + "@"))
        raise ValidationError(
            f"no reference for {scene_key(scene_path)} at res {res} in {rel_to_repo(ref_dir)}"
            + (f" (have: {', '.join(have)})" if have else "")
            + f". Make one: validation/.venv/bin/python validation/compare.py "
              f"--make-references {rel_to_repo(scene_path)} --res {res}")
    check_entry(scene_path, entry)
    path = os.path.join(ref_dir, entry["file"])
    if not os.path.exists(path):
        raise ValidationError(f"reference file {path} listed in the manifest is missing")
    with np.load(path) as z:
        mean, var = z["mean"].astype(np.float64), z["var"].astype(np.float64)
    if mean.shape != (res, res, 3):
        raise ValidationError(f"reference {path} has shape {mean.shape}, expected ({res}, {res}, 3)")
    return Reference(entry, mean, var)
