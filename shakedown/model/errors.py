"""Small exception hierarchy.

Every error raised on bad input subclasses the matching builtin (``ValueError`` or
``TypeError``) so that generic ``except ValueError`` keeps working.  Physical outcomes
(infeasible LP, no steady state, ...) are *statuses* on result objects, not exceptions.
"""

from __future__ import annotations


class ShakedownError(Exception):
    """Base class of every error raised by the package."""


class InputError(ShakedownError, ValueError):
    """An argument has the wrong value; the message names the field, the value and the fix."""


class ShapeError(InputError):
    """An array argument has the wrong shape."""


class NotSymmetricError(InputError):
    """The stiffness matrix ``K`` is not symmetric to the stated tolerance."""


class NotPositiveDefiniteError(InputError):
    """The stiffness matrix ``K`` is not positive definite (Cholesky failed)."""


class SceneError(InputError):
    """A scene file is invalid: the message names the file, the key, the value and what is allowed."""


class MissingDependencyError(ShakedownError, ImportError):
    """An optional package is not installed; the message names the ``pip install`` command."""


class UnsafePathError(InputError):
    """A name or path would write outside the output folder or through a symbolic link."""


class OutputError(ShakedownError, OSError):
    """A result file could not be written (read-only or full disk); the message names the file."""


class DamagedFileError(InputError):
    """A file the package wrote earlier (a store part, a cache) fails its own check and cannot
    be repaired; the message names the file and what to do."""


class SolverError(ShakedownError, RuntimeError):
    """A numerical solver failed unexpectedly; ``partial`` holds whatever was computed."""

    def __init__(self, message: str, partial=None):
        super().__init__(message)
        self.partial = partial
