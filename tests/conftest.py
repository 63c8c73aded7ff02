import os
import sys

sys.path.insert(0, os.path.dirname(__file__))   # tests/naive.py

# hypothesis profiles of tests/test_fuzz.py (issue 6): MORTAR1D3D_HYPOTHESIS=fuzz for the long run
try:
    from hypothesis import HealthCheck, settings
except ImportError:     # hypothesis is a test extra; only test_fuzz.py needs it
    pass
else:
    _quiet = [HealthCheck.too_slow, HealthCheck.data_too_large, HealthCheck.filter_too_much]
    settings.register_profile("bounded", max_examples=6, derandomize=True, deadline=None,
                              suppress_health_check=_quiet, print_blob=True)
    settings.register_profile("fuzz", max_examples=int(os.environ.get("MORTAR1D3D_FUZZ_EXAMPLES", 1000)),
                              deadline=None, suppress_health_check=_quiet, print_blob=True)
    settings.load_profile(os.environ.get("MORTAR1D3D_HYPOTHESIS", "bounded"))
