"""``python -m shakedown`` behaves as the ``shakedown`` command."""

from .scenes.cli import main

if __name__ == "__main__":
    raise SystemExit(main())
