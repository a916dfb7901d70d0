"""numba's ``njit`` when the compiled kernel is available, else a no-op decorator.

``SHAKEDOWN_KERNEL=numpy`` (or ``off``) in the environment switches the kernel off: every step
then runs in Python (:meth:`~.complementarity.StepSolver.solve`), with the same answers to the
solver tolerance.
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

__all__ = ["njit", "HAVE_KERNEL"]
