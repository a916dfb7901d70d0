"""Writing files without following symbolic links (kept for its old import path).

The writer is :mod:`shakedown.model.safe_files`, the one every file of the package goes through
(results, plots, provenance, caches, stores); this module re-exports its names.
"""

from __future__ import annotations

from ..model.safe_files import check_no_links, fsync_dir, make_folder, refuse_link, write_atomic

__all__ = ["check_no_links", "fsync_dir", "make_folder", "refuse_link", "write_atomic"]
