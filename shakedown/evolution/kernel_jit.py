"""numba's ``njit`` when the compiled kernel is available, else a no-op decorator; and the stamp
that keeps numba's on-disk cache of the kernel honest.

``SHAKEDOWN_KERNEL=numpy`` (or ``off``) in the environment switches the kernel off: every step
then runs in Python (:meth:`~.complementarity.StepSolver.solve`), with the same answers to the
solver tolerance.

Cache freshness.  numba (``cache=True``) stamps each function's cache entry with the source of
the one file that defines it, but the machine code of a compiled function contains the
compiled functions of *other* files that it calls (and the module constants it reads).  Editing
only the callee's file (a ``git pull`` on an editable install, a developer's edit) would then
load the caller's stale code with the old callee in it.  Importing this module therefore puts
cache locators for the kernel's own files (:data:`KERNEL_SOURCES`) first in numba's list
(:func:`install_stamp`): same cache paths as numba's (``NUMBA_CACHE_DIR``, ``__pycache__``
beside the sources, or the user-wide cache), but the stamp of every kernel function is one
digest of the contents of *all* the kernel files, so any change to any of them recompiles
every kernel function once (and overwrites its entry); an unchanged tree loads from the cache
as before.  The locator list is numba's private API (``numba.core.caching``, names checked for
numba 0.59 to 0.68; ``NUMBA_CACHE_LOCATOR_CLASSES``, which replaces numba's list, also
bypasses this one): if it is missing, numba's own per-file stamps are kept (the behaviour
before this guard) and :data:`STAMPED` is False.
"""

from __future__ import annotations

import hashlib
import os

#: The files (relative to this folder) whose compiled functions call one another or whose
#: constants they read; a change to any of them invalidates every cache entry of every one
#: (tests/evolution/test_kernel_stamp.py checks that every ``cache=True`` file of this folder
#: and every module of the package they import is listed).
KERNEL_SOURCES = ("kernel.py", "kernel_cache.py", "kernel_shortcut.py", "kernel_updates.py",
                  "cone_kernel.py", "cone_linear.py", "cone_reduced.py", "cone_states.py",
                  "kernel_jit.py")

#: Whether numba's cache of the kernel is stamped by :func:`sources_digest` (False: numba's
#: own per-file stamp; the kernel is off or numba's private locator API has changed).
STAMPED = False


def sources_digest(paths) -> str:
    """SHA-256 (hex) of the contents of the files ``paths`` (in the given order, each with its
    base name; a missing file counts as such, it does not raise)."""
    h = hashlib.sha256()
    for p in paths:
        h.update(os.path.basename(p).encode() + b"\0")
        try:
            with open(p, "rb") as f:
                h.update(f.read())
        except OSError:
            h.update(b"<missing>")
        h.update(b"\0")
    return h.hexdigest()


def _locator_bases(caching) -> list:
    """numba's user-provided, in-tree and user-wide locator classes (public names since numba
    0.62, underscored before); an empty list when any is missing."""
    bases = []
    for name in ("UserProvidedCacheLocator", "InTreeCacheLocator", "UserWideCacheLocator"):
        cls = getattr(caching, name, None) or getattr(caching, "_" + name, None)
        if not isinstance(cls, type) or not callable(getattr(cls, "from_function", None)):
            return []
        bases.append(cls)
    return bases


def stamp_locators(paths, caching=None) -> list:
    """Locator classes for numba's cache of the functions defined in the files ``paths``
    (absolute): numba's user-provided, in-tree and user-wide locators (same cache paths) whose
    source stamp is :func:`sources_digest` of all of ``paths`` (read once, at the first
    stamp asked for); ``from_function`` answers None for any other file.  An empty list when
    numba's locator classes are not found (``caching``: ``numba.core.caching``)."""
    if caching is None:
        import numba.core.caching as caching
    files = tuple(os.path.realpath(p) for p in paths)
    own = frozenset(files)
    memo = []

    class _Stamp:
        def get_source_stamp(self):
            if not memo:
                memo.append(("shakedown-sources", sources_digest(files)))
            return memo[0]

        @classmethod
        def from_function(cls, py_func, py_file):
            if os.path.realpath(py_file) not in own:
                return None
            return super().from_function(py_func, py_file)

    marks = {"_shakedown_stamp": True, "__module__": __name__}
    return [type("Stamped" + b.__name__.lstrip("_"), (_Stamp, b), dict(marks))
            for b in _locator_bases(caching)]


def install_stamp(paths, caching=None) -> bool:
    """Put :func:`stamp_locators` of ``paths`` first in numba's list of cache locators
    (replacing those of an earlier call); False, and numba left as it is, when numba's private
    API is not there (``caching``: ``numba.core.caching``)."""
    if caching is None:
        import numba.core.caching as caching
    impl = getattr(caching, "CacheImpl", None)
    current = getattr(impl, "_locator_classes", None)
    if not isinstance(current, list):
        return False
    new = stamp_locators(paths, caching)
    if not new:
        return False
    kept = [c for c in current if not getattr(c, "_shakedown_stamp", False)]
    impl._locator_classes = new + kept
    return True


try:  # pragma: no cover - which branch runs depends on the environment
    if os.environ.get("SHAKEDOWN_KERNEL", "").lower() in ("numpy", "python", "off", "0"):
        raise ImportError("disabled by SHAKEDOWN_KERNEL")
    from numba import njit
    HAVE_KERNEL = True
except ImportError:  # pragma: no cover
    HAVE_KERNEL = False

    def njit(*args, **kwargs):  # noqa: D103 - the decorated functions are not called then
        return (lambda fn: fn) if not (args and callable(args[0])) else args[0]

#: The floating-point liberty of the 3-D step's Krylov solver (``fastmath=FAST``): its dot
#: products may be reassociated (so that they vectorize) and multiply-adds fused; nothing about
#: NaN, infinities or signed zeros is assumed.  The Newton method checks its own residual after
#: every step in plain arithmetic.
FAST = {"reassoc", "contract"}

if HAVE_KERNEL:
    _here = os.path.dirname(os.path.abspath(__file__))
    try:
        STAMPED = install_stamp([os.path.join(_here, f) for f in KERNEL_SOURCES])
    except Exception:  # pragma: no cover - numba's internals changed: its own stamps are kept
        STAMPED = False

__all__ = ["njit", "FAST", "HAVE_KERNEL", "KERNEL_SOURCES", "STAMPED", "install_stamp", "sources_digest"]
