"""Shared set-up of the validation tests (works under unittest and pytest)."""
import atexit
import os
import shutil
import sys
import tempfile

VALIDATION = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
if VALIDATION not in sys.path:
    sys.path.insert(0, VALIDATION)

FIXTURES = os.path.join(VALIDATION, "tests", "fixtures")
SIMPLE = os.path.join(FIXTURES, "simple.xml")
NODEFAULTS = os.path.join(FIXTURES, "nodefaults.xml")     # no $res/$spp, gaussian filter, stratified
SENSOR_ONLY = os.path.join(FIXTURES, "sensor-only.xml")   # a sensor without film and sampler
RES = 32

_ref_dir = None


def shared_ref_dir():
    """A reference of the fixture scene at 32x32 (32 passes x 128 spp, llvm_ad_rgb),
    made once per test process into a temporary cache."""
    global _ref_dir
    if _ref_dir is None:
        from radiaval.references import make_reference
        d = tempfile.mkdtemp(prefix="radia-val-refs-")
        atexit.register(shutil.rmtree, d, True)
        make_reference(SIMPLE, RES, spp=128, passes=32, variant="llvm_ad_rgb", ref_dir=d)
        _ref_dir = d
    return _ref_dir


def tmpdir(case):
    d = tempfile.mkdtemp(prefix="radia-val-test-")
    case.addCleanup(shutil.rmtree, d, True)
    return d
