"""Matplotlib helpers (each takes ``ax=None`` and returns the axes).

Functions are re-exported lazily from the topic modules so that importing
``shakedown.plotting`` does not import every analysis.
"""

from importlib import import_module as _imp

_TOPICS = ("bounds", "cycles", "cones", "stability", "sweep", "contact_patch")


def __getattr__(name):
    for topic in _TOPICS:
        try:
            mod = _imp(f".{topic}", __name__)
        except ModuleNotFoundError:
            continue
        if hasattr(mod, name) and not name.startswith("_"):
            return getattr(mod, name)
    raise AttributeError(f"module 'shakedown.plotting' has no attribute {name!r}")
