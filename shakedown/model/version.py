"""The package version (one place: ``shakedown.__version__``, ``shakedown --version``, manifests).

Keep equal to ``version`` in ``pyproject.toml`` (``tests/scenes/test_manifest.py`` checks it).
"""

__version__ = "0.2.0"
