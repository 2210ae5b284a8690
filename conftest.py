"""Collection of the source tree, whose modules pytest imports for their doctests (``--doctest-modules``).

``sigmatau.core.compiled`` and ``sigmatau.core.fused`` import numba, the optional extra ``fast``:
without it they are not collected, as ``tests/test_fused_kernels.py`` skips itself (the package
imports them only when numba is there, through ``sigmatau.core.accel``).
"""

try:
    import numba  # noqa: F401
except ImportError:
    collect_ignore = ["src/sigmatau/core/compiled.py", "src/sigmatau/core/fused.py"]
