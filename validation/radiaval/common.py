"""Paths, Mitsuba set-up, scene hashing, image I/O and pass rendering shared by
compare.py and benchmark.py: radia's passes with the Python package (PackageRenderer, one
load, no files) or the binary (RadiaRenderer, one process per pass, as benchmark.py times it)."""
import glob
import hashlib
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
import warnings
import weakref
import xml.etree.ElementTree as ET

import numpy as np

VALIDATION_DIR = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
REPO_ROOT = os.path.dirname(VALIDATION_DIR)
REFERENCE_DIR = os.path.join(VALIDATION_DIR, "references")
OUT_DIR = os.path.join(VALIDATION_DIR, "out")
DEFAULT_RADIA = os.path.join(REPO_ROOT, "target", "release", "radia")

# Seeds. Mitsuba's scalar variants seed pixel i of a render with seed*pixels+i
# and the JIT variants hash (seed, lane), so distinct seeds are independent.
# Candidate passes use seeds 0..K-1, references REF_SEED_BASE + k.
REF_SEED_BASE = 4000


class ValidationError(Exception):
    """An error that makes the run meaningless (exit code 2): missing or stale
    reference, missing binary, failed render."""


def log(*a):
    print(*a, flush=True)


# ---------------------------------------------------------------------------
# Mitsuba
# ---------------------------------------------------------------------------

_mi = None


def _find_llvm19():
    for pat in ("/usr/lib/*/libLLVM.so.19*", "/usr/lib/*/libLLVM-19.so*",
                "/usr/lib/llvm-19/lib/libLLVM*.so*"):
        hits = sorted(glob.glob(pat))
        if hits:
            return hits[0]
    return None


def mitsuba(variant):
    """Import mitsuba and set the variant. For llvm variants point Dr.Jit at
    LLVM 19 (LLVM 14/15, also installed on Debian bookworm, abort)."""
    global _mi
    if "llvm" in variant and "DRJIT_LIBLLVM_PATH" not in os.environ:
        lib = _find_llvm19()
        if lib:
            os.environ["DRJIT_LIBLLVM_PATH"] = lib
    if _mi is None:
        import mitsuba as mi
        _mi = mi
    if "llvm" in variant and _find_llvm19() is None and "DRJIT_LIBLLVM_PATH" not in os.environ:
        raise ValidationError("variant %s needs Debian's libllvm19: run validation/setup" % variant)
    _mi.set_variant(variant)
    return _mi


def mitsuba_version():
    import mitsuba as mi
    return mi.__version__


def set_mitsuba_threads(n):
    """Worker threads of Dr.Jit's pool, used by scalar and llvm variants."""
    import drjit as dr
    if n:
        dr.set_thread_count(int(n))
    return dr.thread_count()


MITSUBA_SAMPLERS = ("independent", "stratified", "multijitter", "orthogonal", "ldsampler")
# "NAME+adaptive": radia's adaptive sampling (--adaptive) over that sampler.
RADIA_SAMPLERS = MITSUBA_SAMPLERS + ("sobol", "sobol+adaptive")


def split_sampler(name):
    """(sampler, adaptive) of a radia sampler name such as "sobol+adaptive"."""
    if name and name.endswith("+adaptive"):
        return name[:-len("+adaptive")], True
    return name, False
FILTERS = ("box", "gaussian")


def _set_property(parent, tag, name, value):
    """Replace parent's property `name` (whatever its tag) by <tag name= value=>."""
    for c in list(parent):
        if c.get("name") == name and c.tag not in ("film", "sampler", "rfilter"):
            parent.remove(c)
    ET.SubElement(parent, tag, name=name, value=str(value))


def scene_sensor(root, scene_path="scene"):
    """The sensor Mitsuba renders by default (and radia renders): the first one."""
    for e in root.iter("sensor"):
        return e
    raise ValidationError(f"{scene_path} has no <sensor> (Mitsuba 3.9 and radia both need one)")


def mitsuba_scene_xml(scene_path, res=None, spp=None, sampler=None, rfilter=None):
    """The scene's XML as written, with the first sensor's film size, sampler
    (type and sample_count) and reconstruction filter overridden where given
    (None keeps the scene's own). A sensor without a <film> or <sampler> gets
    Mitsuba's defaults (hdrfilm 768x576 with a gaussian filter, independent
    4 spp) plus the overrides. <default>s and $-references elsewhere are left to
    Mitsuba. res is an int (square) or (width, height). Returns the XML text."""
    try:
        root = ET.parse(scene_path).getroot()
    except ET.ParseError as e:
        raise ValidationError(f"cannot parse {scene_path}: {e}")
    defs = _defaults(root)
    sensor = scene_sensor(root, scene_path)
    if res is not None or rfilter is not None:
        film = sensor.find("film")
        if film is None:
            film = ET.SubElement(sensor, "film", type="hdrfilm")
        if res is not None:
            w, h = (res, res) if isinstance(res, int) else res
            _set_property(film, "integer", "width", int(w))
            _set_property(film, "integer", "height", int(h))
            for c in list(film):   # a crop window would make the image smaller than asked
                if (c.get("name") or "").startswith("crop_"):
                    film.remove(c)
        if rfilter is not None:
            for c in film.findall("rfilter"):
                film.remove(c)
            ET.SubElement(film, "rfilter", type=rfilter)
    if sampler is not None or spp is not None:
        smp = sensor.find("sampler")
        if smp is None:
            smp = ET.SubElement(sensor, "sampler", type="independent")
        if sampler is not None and _subst(smp.get("type"), defs) != sampler:
            # another plugin: keep only the properties every sampler takes
            keep = [c for c in smp if c.get("name") in ("sample_count", "seed")]
            smp.clear()
            smp.set("type", sampler)
            for c in keep:
                smp.append(c)
        if spp is not None:
            _set_property(smp, "integer", "sample_count", int(spp))
    return ET.tostring(root, encoding="unicode")


def used_defines(xml_text, scene_path, defines):
    """The -D NAME=VALUE defines that the scene still references as $NAME
    (Mitsuba refuses unused parameters; e.g. -D spp=... once sample_count is
    overridden). Returns (dict used, list dropped names)."""
    texts = [xml_text] + [open(p).read() for p in scene_files(scene_path)[1:]
                          if p.endswith(".xml") and os.path.exists(p)]
    used, dropped = {}, []
    for d in defines:
        k, v = d.split("=", 1) if isinstance(d, str) else d
        k = k.strip()
        if any(re.search(r"\$" + re.escape(k) + r"(?![A-Za-z0-9_])", t) for t in texts):
            used[k] = v
        else:
            dropped.append(k)
    return used, dropped


def load_mitsuba_scene(mi, scene_path, res=None, spp=None, sampler=None, rfilter=None,
                       defines=(), xml_text=None):
    """mi.load_string of mitsuba_scene_xml(...) with the scene's directory
    prepended to Mitsuba's file resolver (as mi.load_file does), so relative
    filenames resolve; the resolver is restored afterwards."""
    if xml_text is None:
        xml_text = mitsuba_scene_xml(scene_path, res, spp, sampler, rfilter)
    params, _ = used_defines(xml_text, scene_path, defines)
    fr = mi.file_resolver()
    saved = [fr[i] for i in range(len(fr))]
    fr.prepend(os.path.dirname(os.path.abspath(scene_path)))
    try:
        return mi.load_string(xml_text, **params)
    finally:
        fr.clear()
        for p in saved:
            fr.append(p)


def mitsuba_scene_spp(scene):
    """The spp the scene's (first) sensor's sampler renders, after its rounding."""
    return int(scene.sensors()[0].sampler().sample_count())


class MitsubaRenderer:
    """Renders passes of one scene in-process. By default with an independent
    sampler and a box filter (whatever the scene says), so that pixels are
    independent as compare.py's test assumes for the reference; sampler=None or
    rfilter=None keep the scene's own. self.spp is the spp actually rendered
    (samplers round it)."""

    def __init__(self, scene_path, res, spp, variant="scalar_rgb", threads=None, defines=(),
                 sampler="independent", rfilter="box"):
        self.mi = mitsuba(variant)
        self.variant = variant
        self.threads = set_mitsuba_threads(threads)
        self.res = res
        t0 = time.perf_counter()
        self.scene = load_mitsuba_scene(self.mi, scene_path, res=res, spp=spp, sampler=sampler,
                                        rfilter=rfilter, defines=defines)
        self.load_time = time.perf_counter() - t0
        self.spp = mitsuba_scene_spp(self.scene)

    def render(self, seed, spp=None):
        """One pass -> float32 (H, W, 3) array; also sets self.last_time."""
        import drjit as dr
        t0 = time.perf_counter()
        if spp and spp != self.spp:
            img = self.mi.render(self.scene, seed=seed, spp=spp)
        else:
            img = self.mi.render(self.scene, seed=seed)
        arr = np.array(img, dtype=np.float32, copy=True)
        dr.sync_thread()
        self.last_time = time.perf_counter() - t0
        return arr[..., :3]

    def passes(self, k, seed0=0, spp=None, progress=None):
        out = np.empty((k, self.res, self.res, 3), np.float32)
        t0 = time.perf_counter()
        for i in range(k):
            out[i] = self.render(seed0 + i, spp)
            if progress:
                progress(i + 1, k)
        self.passes_time = time.perf_counter() - t0
        return out


def read_exr(path):
    mi = _mi or mitsuba("scalar_rgb")
    bmp = mi.Bitmap(path)
    arr = np.array(bmp, dtype=np.float32, copy=True)
    if arr.ndim == 2:
        arr = np.repeat(arr[..., None], 3, axis=2)
    if arr.shape[2] == 1:
        arr = np.repeat(arr, 3, axis=2)
    return arr[..., :3]


def write_exr(path, arr):
    mi = _mi or mitsuba("scalar_rgb")
    mi.Bitmap(np.ascontiguousarray(arr, dtype=np.float32),
              mi.Bitmap.PixelFormat.RGB).write(path)


# ---------------------------------------------------------------------------
# radia
# ---------------------------------------------------------------------------

_RADIA_FINAL = re.compile(
    r"radia:\s*(\d+)x(\d+),\s*(\d+)\s*spp,\s*([\d.eE+-]+)\s*s render"
    r"(?:,\s*([\d.eE+-]+)\s*Msamples/s)?(?:,\s*([\d.eE+-]+)\s*Mrays/s)?"
    r"(?:,\s*(\d+)\s*invalid samples)?")
_RADIA_LOAD = re.compile(r"radia:\s*loaded\b.*?\bin\s*([\d.eE+-]+)\s*s\b")
_RADIA_SAMPLER = re.compile(r"radia:\s*loaded\b.*\((\w+) sampler\)")


def parse_radia_output(text):
    info = {}
    m = _RADIA_LOAD.search(text)
    if m:
        info["load_s"] = float(m.group(1))
    m = _RADIA_SAMPLER.search(text)
    if m:
        info["sampler"] = m.group(1)
    m = None
    for m in _RADIA_FINAL.finditer(text):
        pass
    if m:
        info["width"], info["height"], info["spp"] = int(m.group(1)), int(m.group(2)), int(m.group(3))
        info["render_s"] = float(m.group(4))
        if m.group(5):
            info["msamples_s"] = float(m.group(5))
        if m.group(6):
            info["mrays_s"] = float(m.group(6))
        if m.group(7):
            info["invalid"] = int(m.group(7))
    return info


def check_radia(binary):
    if not (os.path.isfile(binary) and os.access(binary, os.X_OK)):
        raise ValidationError(
            f"radia binary not found at {binary}: build it first with "
            "`cargo build --release -p radia-cli` (or pass --radia PATH)")
    return binary


class RadiaRenderer:
    """Renders passes of one scene by running the radia binary once per pass,
    with the film size (--resolution), filter (--rfilter, default box: the
    reference's) and sampler (--sampler; None: the scene's own) overridden on
    radia's command line. The spp radia actually rendered (samplers round it)
    is in self.infos[-1]["spp"]."""

    def __init__(self, scene_path, res, spp, binary=DEFAULT_RADIA, threads=None,
                 extra_defines=(), bias=1.0, sampler=None, rfilter="box"):
        self.binary = check_radia(binary)
        self.scene_path, self.res, self.spp = scene_path, res, spp
        self.threads = threads
        self.sampler, self.rfilter = sampler, rfilter
        self.extra_defines = list(extra_defines)
        self.bias = bias  # multiply output (only for demonstrating the test's teeth)
        # Removed with this object (or at exit): every test and benchmark makes several.
        self.tmp = tempfile.mkdtemp(prefix="radia-val-")
        weakref.finalize(self, shutil.rmtree, self.tmp, True)
        self.invalid = 0
        self.infos = []

    def command(self, out, seed, spp):
        cmd = [self.binary, "render", self.scene_path, "-o", out,
               "--spp", str(spp), "--seed", str(seed), "--resolution", f"{self.res}x{self.res}"]
        if self.threads:
            cmd += ["--threads", str(self.threads)]
        if self.rfilter:
            cmd += ["--rfilter", self.rfilter]
        if self.sampler:
            sampler, adaptive = split_sampler(self.sampler)
            cmd += ["--sampler", sampler] + (["--adaptive"] if adaptive else [])
        for d in self.extra_defines:
            cmd += ["-D", d]
        return cmd

    def render(self, seed, spp=None):
        spp = spp or self.spp
        out = os.path.join(self.tmp, f"pass{seed}.exr")
        cmd = self.command(out, seed, spp)
        t0 = time.perf_counter()
        proc = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        self.last_wall = time.perf_counter() - t0
        if proc.returncode != 0 or not os.path.exists(out):
            raise ValidationError("radia failed (exit %d): %s\n%s" % (
                proc.returncode, " ".join(cmd), proc.stdout[-3000:]))
        info = parse_radia_output(proc.stdout)
        info["wall_s"] = self.last_wall
        info["output"] = proc.stdout
        self.infos.append(info)
        self.invalid += info.get("invalid", 0)
        arr = read_exr(out)
        os.unlink(out)
        if arr.shape[:2] != (self.res, self.res):
            raise ValidationError(f"radia wrote a {arr.shape[1]}x{arr.shape[0]} image, "
                                  f"expected {self.res}x{self.res}: {' '.join(cmd)}")
        if self.bias != 1.0:
            arr = arr * np.float32(self.bias)
        return arr

    def passes(self, k, seed0=0, spp=None, progress=None):
        out = np.empty((k, self.res, self.res, 3), np.float32)
        t0 = time.perf_counter()
        for i in range(k):
            out[i] = self.render(seed0 + i, spp)
            if progress:
                progress(i + 1, k)
        self.passes_time = time.perf_counter() - t0
        return out


class PackageRenderer:
    """Renders passes of one scene with the radia Python package (crates/python): the scene
    is loaded once with the film size and filter overridden (``radia.load_file(...,
    resolution=, rfilter=)``, as RadiaRenderer's --resolution and --rfilter), then each pass
    is one ``radia.render`` into a numpy array, with the sampler overridden by name if given:
    no process and no EXR per pass. The images are RadiaRenderer's bit for bit at the same
    seed and spp (tests/test_radia_package.py: radia.render equals the CLI). self.infos has
    one dict per pass with RadiaRenderer's keys; the load is counted in the first."""

    def __init__(self, scene_path, res, spp, threads=None, extra_defines=(), bias=1.0,
                 sampler=None, rfilter="box"):
        self.radia = radia_package()
        self.scene_path, self.res, self.spp = scene_path, res, spp
        self.threads, self.sampler, self.bias = threads, sampler, bias
        defines = {}
        for d in extra_defines:
            k, sep, v = d.partition("=")
            if not sep:
                raise ValidationError(f"-D expects NAME=VALUE, got {d!r}")
            defines[k.strip()] = v
        t0 = time.perf_counter()
        try:
            self.scene = self.radia.load_file(scene_path, resolution=res, rfilter=rfilter,
                                              **defines)
        except (self.radia.LoadError, ValueError) as e:
            raise ValidationError(f"radia cannot load {scene_path}: {e}")
        self.load_s = time.perf_counter() - t0
        self.invalid = 0
        self.infos = []

    def render(self, seed, spp=None):
        spp = spp or self.spp
        t0 = time.perf_counter()
        with warnings.catch_warnings():
            # "the stratified sampler renders 9 spp, not 8": every pass would say it;
            # infos[-1]["spp"] records it (as for the binary, whose stderr is not shown).
            warnings.filterwarnings("ignore", message="the .* sampler renders")
            sampler, adaptive = split_sampler(self.sampler)
            arr, st = self.radia.render(self.scene, spp=spp, seed=seed, threads=self.threads,
                                        sampler=sampler, stats=True, adaptive=adaptive)
        self.last_wall = time.perf_counter() - t0
        info = dict(spp=st.spp, render_s=st.seconds, wall_s=self.last_wall,
                    load_s=0.0 if self.infos else self.load_s,
                    sampler=self.sampler or self.scene.sampler,
                    mrays_s=st.rays / st.seconds / 1e6 if st.seconds > 0 else None,
                    invalid=st.invalid_samples)
        info["output"] = (f"radia (package): {self.res}x{self.res}, {st.spp} spp, "
                          f"{st.seconds:.3f} s render, {st.invalid_samples} invalid samples dropped")
        self.infos.append(info)
        self.invalid += st.invalid_samples
        if self.bias != 1.0:
            arr = arr * np.float32(self.bias)
        return arr

    passes = RadiaRenderer.passes


def radia_package(binary_option=True):
    """The radia Python package, refused with the remedy when it is missing or was built from
    other sources than the checkout's (validation/setup stamps the venv with the hash of the
    sources it built; radiaval/sources.py computes both). `binary_option`: the calling tool
    takes --radia, so the remedy names it too."""
    or_binary = (", or pass --radia target/release/radia to render with the binary"
                 if binary_option else "")
    try:
        import radia
    except ImportError as e:
        raise ValidationError(
            f"the radia Python package is not installed in {sys.prefix} ({e}): run "
            f"`bash validation/setup` (it builds crates/python into validation/.venv){or_binary}")
    stamp = os.path.join(sys.prefix, ".radia-package-stamp")
    if os.path.exists(stamp):
        from .sources import source_hash
        with open(stamp) as f:
            built = f.read().strip()
        if built != source_hash(REPO_ROOT):
            raise ValidationError(
                f"the radia Python package in {sys.prefix} was built from other sources than "
                f"{REPO_ROOT}'s crates/ now: run `bash validation/setup` to rebuild it{or_binary}")
    return radia


def make_radia_renderer(scene_path, res, spp, binary=None, **kw):
    """The package's renderer, or the binary's when a binary is named (benchmark.py times
    the binary; tests/fake_radia.py stands in for it)."""
    if binary is None:
        return PackageRenderer(scene_path, res, spp, **kw)
    return RadiaRenderer(scene_path, res, spp, binary=binary, **kw)


# ---------------------------------------------------------------------------
# Scene hashing
# ---------------------------------------------------------------------------

def _defaults(root):
    return {e.get("name"): e.get("value") for e in root.iter("default")
            if e.get("name") is not None}


def _subst(value, defs):
    if value is None or "$" not in value:
        return value
    for name in sorted(defs, key=len, reverse=True):
        value = value.replace("$" + name, str(defs[name]))
    return value


def scene_files(scene_path, params=None, _seen=None):
    """The scene XML and every file it refers to (includes, meshes, textures,
    spectra), found by parsing: attributes named 'filename' and
    <string name="filename" value=...>. Returns absolute paths, in order."""
    scene_path = os.path.abspath(scene_path)
    seen = _seen if _seen is not None else []
    if scene_path in seen:
        return seen
    seen.append(scene_path)
    try:
        root = ET.parse(scene_path).getroot()
    except ET.ParseError as e:
        raise ValidationError(f"cannot parse {scene_path}: {e}")
    defs = _defaults(root)
    defs.update({k: str(v) for k, v in (params or {}).items()})
    base = os.path.dirname(scene_path)
    for e in root.iter():
        names = []
        if e.get("filename") is not None:
            names.append(e.get("filename"))
        if e.tag == "string" and e.get("name") == "filename" and e.get("value") is not None:
            names.append(e.get("value"))
        for n in names:
            n = _subst(n, defs)
            p = n if os.path.isabs(n) else os.path.join(base, n)
            p = os.path.abspath(p)
            if p.endswith(".xml") and os.path.exists(p):
                scene_files(p, params, seen)
            elif p not in seen:
                seen.append(p)
    return seen


def sha256_file(path):
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for chunk in iter(lambda: f.read(1 << 20), b""):
            h.update(chunk)
    return h.hexdigest()


def rel_to_repo(path):
    path = os.path.abspath(path)
    try:
        r = os.path.relpath(path, REPO_ROOT)
    except ValueError:
        return path
    return path if r.startswith("..") else r


def scene_hash(scene_path, params):
    """sha256 over the scene's files (path relative to the scene + content)
    and the render parameters. Returns (hash, {relpath: file hash})."""
    files = scene_files(scene_path)
    base = os.path.dirname(os.path.abspath(scene_path))
    h = hashlib.sha256()
    per_file = {}
    for p in files:
        rel = os.path.relpath(p, base)
        if not os.path.exists(p):
            raise ValidationError(f"{scene_path} refers to missing file {p}")
        fh = sha256_file(p)
        per_file[rel] = fh
        h.update(rel.encode() + b"\0" + fh.encode() + b"\0")
    h.update(json.dumps(params, sort_keys=True).encode())
    return h.hexdigest(), per_file


def scene_key(scene_path):
    """Name of a scene in the reference cache: its path relative to the repo."""
    return rel_to_repo(scene_path)


def derive_scene(src, dst_dir, replacements):
    """Copy scene src into dst_dir with text replacements [(old, new)], making
    its file references absolute so that they still resolve. Returns the path."""
    text = open(src).read()
    for old, new in replacements:
        if old not in text:
            raise ValueError(f"{old!r} not in {src}")
        text = text.replace(old, new)
    base = os.path.dirname(os.path.abspath(src))

    def absolutise(m):
        v = m.group(2)
        return m.group(1) + (v if os.path.isabs(v) or "$" in v else os.path.join(base, v)) + m.group(3)
    text = re.sub(r'(<string\s+name="filename"\s+value=")([^"]*)(")', absolutise, text)
    text = re.sub(r'(\sfilename=")([^"]*)(")', absolutise, text)
    os.makedirs(dst_dir, exist_ok=True)
    dst = os.path.join(dst_dir, os.path.basename(src))
    with open(dst, "w") as f:
        f.write(text)
    return dst


def list_scenes(dirpath=os.path.join(REPO_ROOT, "scenes")):
    return sorted(glob.glob(os.path.join(dirpath, "*.xml")))
