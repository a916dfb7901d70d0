"""numba's ``njit`` where the compiled kernels are available, else a no-op decorator.

``SHAKEDOWN_KERNEL=numpy`` (or ``python``, ``off``, ``0``) in the environment switches the
compiled kernels off: the bounds engine's pivots (:mod:`shakedown.bounds.basis_kernel`,
:mod:`shakedown.bounds.walk_kernel`) then run in NumPy, pivot for pivot the same rules (the
kernels choose some pivots from single-precision passes: ties within their rounding may break
otherwise; every choice is rechecked in double and every answer certified as before).  The
cyclic solver's kernels read the same switch through :mod:`shakedown.evolution.kernel_jit`,
which also stamps their on-disk cache (those files may not import the package, so the switch
is read there on its own).
"""

from __future__ import annotations

import os

try:  # pragma: no cover - which branch runs depends on the environment
    if os.environ.get("SHAKEDOWN_KERNEL", "").lower() in ("numpy", "python", "off", "0"):
        raise ImportError("disabled by SHAKEDOWN_KERNEL")
    from numba import njit
    HAVE_KERNEL = True
except ImportError:  # pragma: no cover
    HAVE_KERNEL = False

    def njit(*args, **kwargs):  # noqa: D103 - the decorated functions are not called then
        return (lambda fn: fn) if not (args and callable(args[0])) else args[0]

#: The floating-point liberties the bounds kernels take (``fastmath=FAST``): sums may be
#: reassociated (so that the dot products of their ``O(m^2)`` and ``O(N m)`` passes vectorize)
#: and multiply-adds fused; nothing about NaN, infinities or signed zeros is assumed.  The sums
#: then round differently from NumPy's (whose BLAS reassociates too); every answer is
#: certified in Python as before (issue 26: a working-basis product at ``m = 800`` 0.61 ->
#: 0.13 ms).  numba's on-disk cache of a kernel is stamped by its own file only: a change here
#: reaches the cached kernels once their files change too (or their ``__pycache__`` is cleared).
#: Each kernel file keeps its compiled helpers to itself for the same reason.
FAST = {"reassoc", "contract"}

__all__ = ["njit", "HAVE_KERNEL", "FAST"]
