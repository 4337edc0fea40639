import os
import sys

import pytest

VALIDATION = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, VALIDATION)

FIXTURES = os.path.join(VALIDATION, "tests", "fixtures")
SIMPLE = os.path.join(FIXTURES, "simple.xml")
RES = 32


@pytest.fixture(scope="session")
def ref_dir(tmp_path_factory):
    """A reference of the fixture scene at 32x32 (32 passes x 128 spp), made
    once per test session into a temporary cache."""
    from radiaval.references import make_reference
    d = str(tmp_path_factory.mktemp("refs"))
    make_reference(SIMPLE, RES, spp=128, passes=32, variant="llvm_ad_rgb", ref_dir=d)
    return d
