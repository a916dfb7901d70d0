"""The steady table of 3-D runs (:class:`~.cycle_results.CycleRun` of a ``dim = 3`` system)."""

from __future__ import annotations

import numpy as np

from .cone_step import STATE_NAMES_3D


def table_3d(records):
    """The time series of 3-D records, one row per (time, node): ``cycle``, ``t``, ``node``,
    ``slip_x``, ``slip_y``, ``gap``, ``q_x``, ``q_y``, ``p``, ``state``
    (:data:`~.cone_step.STATE_NAMES_3D`)."""
    import pandas as pd

    frames = []
    for i, rec in enumerate(records):
        sl = slice(0, None) if i == 0 else slice(1, None)
        t = rec.t[sl]
        K, n = rec.w[sl].shape
        frames.append(pd.DataFrame({
            "cycle": np.full(K * n, int(round(rec.t[-1])) if rec.t.size else 0),
            "t": np.repeat(t, n), "node": np.tile(np.arange(n), K),
            "slip_x": rec.v[sl][..., 0].ravel(), "slip_y": rec.v[sl][..., 1].ravel(),
            "gap": rec.w[sl].ravel(),
            "q_x": rec.q[sl][..., 0].ravel(), "q_y": rec.q[sl][..., 1].ravel(),
            "p": rec.p[sl].ravel(),
            "state": pd.Categorical.from_codes(rec.states[sl].ravel().astype(int),
                                               categories=list(STATE_NAMES_3D)),
        }))
    cols = ["cycle", "t", "node", "slip_x", "slip_y", "gap", "q_x", "q_y", "p", "state"]
    return pd.concat(frames, ignore_index=True) if frames else pd.DataFrame(columns=cols)


__all__ = ["table_3d"]
