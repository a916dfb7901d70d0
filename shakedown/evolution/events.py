"""Exact event-driven evolution for loads piecewise linear between samples (MODEL.md s.4).

Between events the node states are fixed and everything (slips, gaps, reactions) is affine in
``t``.  At the current point the nodes are classified (tolerance ``feas_tol * force_scale``):
separated (``w > 0``: held separated, ``q' = p' = 0``), strictly inside the friction cone (held
stuck), at the forward / backward friction limit (may stick or slip that way), or touching
with zero normal reaction (may take any state).  The *rate problem* -- the complementarity
problem of MODEL.md s.4 written for the rates, with the classified nodes held -- gives the
rates, solved by :meth:`StepSolver.solve_mixed` (same active-set machinery and factor cache as
the implicit step).  The next event is found exactly by a ratio test on the affine path: a
stuck node reaching ``|q| = f p``, a contact node's ``p`` reaching 0, a separated node's gap
closing, or the end of the load segment (where the load's slope, hence the slip rates, may
change sign).  The dissipation of a segment is ``sum f_j (p_a + p_b) / 2 |v_b - v_a|`` over its
slipping nodes: exact, since ``p`` is affine on the segment.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .complementarity import BACKWARD, FORWARD, SEPARATED, STICK, kinematic_states


@dataclass
class CycleRecord:
    """Time series of one simulated load period (internal).

    ``t`` (K+1,) absolute times; ``v, w, q, p`` (K+1, N) with row 0 the state at the start of
    the period; ``states`` (K+1, N) the kinematic state of the step / segment ending at each
    point (row 0: that of the previous period's last one).
    """

    t: np.ndarray
    v: np.ndarray
    w: np.ndarray
    q: np.ndarray
    p: np.ndarray
    states: np.ndarray
    dissipation: float
    active_sets: np.ndarray | None = None
    ok: bool = True
    message: str = ""
    n_steps: int = 0
    max_residual: float = 0.0
    statuses: dict | None = None


class EventIntegrator:
    """Follows the exact path over load periods (one :meth:`cycle` call per period)."""

    def __init__(self, solver, load, lam, force_scale, max_events_per_cycle=None):
        self.solver = solver
        self.n = solver.n
        self.load = load
        self.lam = float(lam)
        S = self.S = load.n_samples
        tb = np.arange(S + 1) / S
        self.qs, self.ps = load.evaluate(tb, lam)
        self.dq = np.diff(self.qs, axis=0) * S  # slope per unit time (cycles)
        self.dp = np.diff(self.ps, axis=0) * S
        self.F = force_scale
        self.ft = solver.feas_tol * force_scale
        self.dtol = self.ft / solver.diag
        self.f = solver.f
        n = self.n
        self.max_events = (100 * (n + S) if max_events_per_cycle is None
                           else int(max_events_per_cycle))
        self.n_events = 0
        self.rate_solves = 0
        self.lemke_fallbacks = 0

    def _reactions(self, v, w, i, tau):
        qw = self.qs[i] + tau * self.dq[i]
        pw = self.ps[i] + tau * self.dp[i]
        n = self.n
        r = self.solver.K @ np.concatenate([v, w])
        return qw + r[:n], pw + r[n:], qw, pw

    def _classify(self, w, q, p):
        n = self.n
        open_ = w > self.dtol[n:]
        f, ft = self.f, self.ft
        allowed = np.zeros((n, 4), bool)
        c = ~open_
        allowed[c, STICK] = True
        allowed[c, FORWARD] = f[c] * p[c] + q[c] <= ft
        allowed[c, BACKWARD] = f[c] * p[c] - q[c] <= ft
        allowed[c, SEPARATED] = p[c] <= ft
        allowed[open_, SEPARATED] = True
        return allowed, open_

    def cycle(self, c, v, w, prev_states, guess):
        """Simulate period ``c`` (times ``c - 1 .. c``) from ``(v, w)``; returns a record."""
        n, S, f = self.n, self.S, self.f
        solver = self.solver
        v, w = v.copy(), w.copy()
        q, p, _, _ = self._reactions(v, w, 0, 0.0)
        ts, vs, ws, qs, ps, st = [c - 1.0], [v.copy()], [w.copy()], [q], [p], [prev_states]
        W = 0.0
        s = guess.copy()
        events = 0
        worst = 0.0
        for i in range(S):
            tau, h_seg = 0.0, 1.0 / S
            rate_scale = float(max(np.abs(self.dq[i]).max(), np.abs(self.dp[i]).max()))
            while tau < h_seg:
                events += 1
                if events > self.max_events:
                    return self._record(ts, vs, ws, qs, ps, st, W, False,
                                        f"more than {self.max_events} events in period {c}: "
                                        "the path does not progress (chattering?)", events, worst)
                allowed, open_ = self._classify(w, q, p)
                w[~open_] = 0.0
                if rate_scale == 0.0:
                    zr = np.zeros(2 * n)
                    qr = pr = np.zeros(n)
                    s = np.where(open_, SEPARATED, STICK).astype(np.int8)
                else:
                    sol = solver.solve_mixed(self.dq[i], self.dp[i], allowed, s, rate_scale)
                    self.rate_solves += 1
                    if sol.method != "active_set":
                        self.lemke_fallbacks += 1
                    if not sol.success:
                        return self._record(ts, vs, ws, qs, ps, st, W, False,
                                            f"rate problem without a verified solution at "
                                            f"t = {c - 1 + i / S + tau:.12g}", events, worst)
                    held = allowed.sum(axis=1) == 1
                    worst = max(worst, solver.residuals(sol.z, sol.q, sol.p, allowed, held,
                                                        rate_scale))
                    zr, qr, pr, s = sol.z, sol.q, sol.p, sol.s
                vr, wr = zr[:n], zr[n:]
                h, close = self._ratio_test(s, open_, w, q, p, wr, qr, pr, h_seg - tau)
                new_tau = tau + h
                if h_seg - new_tau <= 1e-13 * h_seg:
                    new_tau, h = h_seg, h_seg - tau
                v_new = v + h * vr
                w_new = np.maximum(w + h * wr, 0.0)
                if close >= 0:
                    w_new[close] = 0.0
                i_eval, t_eval = (i + 1, 0.0) if new_tau == h_seg else (i, new_tau)
                if i_eval == S:
                    i_eval = 0  # periodic: the end of the last segment is the next t = 0
                if t_eval == 0.0:  # a sample: recomputed with K (no drift across samples)
                    q_new, p_new, _, _ = self._reactions(v_new, w_new, min(i_eval, S - 1),
                                                         t_eval)
                else:  # inside a segment everything is affine: O(N) instead of O(N^2)
                    q_new, p_new = q + h * qr, p + h * pr
                dv = v_new - v
                slip = (s == FORWARD) | (s == BACKWARD)
                W += float(np.sum(f[slip] * 0.5 * (p[slip] + p_new[slip]) * np.abs(dv[slip])))
                kin = kinematic_states(dv, np.maximum(w, w_new), self.dtol)
                v, w, q, p, tau = v_new, w_new, q_new, p_new, new_tau
                ts.append(c - 1.0 + (i + new_tau / h_seg) / S if new_tau < h_seg
                          else c - 1.0 + (i + 1) / S)
                vs.append(v.copy()), ws.append(w.copy()), qs.append(q), ps.append(p)
                st.append(kin)
        self.n_events += events
        rec = self._record(ts, vs, ws, qs, ps, st, W, True, "", events, worst)
        rec.active_sets = s
        return rec

    def _ratio_test(self, s, open_, w, q, p, wr, qr, pr, h_max):
        """Time to the first event on the affine path (``h_max`` if none); closing node."""
        f, ft = self.f, self.ft
        n = self.n
        sp, sm = f * p + q, f * p - q
        spr, smr = f * pr + qr, f * pr - qr
        contact = ~open_
        best, close = h_max, -1
        with np.errstate(divide="ignore", invalid="ignore"):
            cand = []
            stick = contact & (s == STICK)
            cand.append(np.where(stick & (sp > ft) & (spr < 0), sp / -spr, np.inf))
            cand.append(np.where(stick & (sm > ft) & (smr < 0), sm / -smr, np.inf))
            cand.append(np.where(contact & (s != SEPARATED) & (p > ft) & (pr < 0), p / -pr,
                                 np.inf))
            gap = np.where((s == SEPARATED) & (w > self.dtol[n:]) & (wr < 0), w / -wr, np.inf)
        for arr in cand:
            m = float(arr.min(initial=np.inf))
            if m < best:
                best, close = m, -1
        m = float(gap.min(initial=np.inf))
        if m < best:
            best, close = m, int(np.argmin(gap))
        return max(best, 0.0), close

    @staticmethod
    def _record(ts, vs, ws, qs, ps, st, W, ok, msg, events, worst):
        return CycleRecord(
            t=np.asarray(ts), v=np.asarray(vs), w=np.asarray(ws), q=np.asarray(qs),
            p=np.asarray(ps), states=np.asarray(st, np.int8), dissipation=W, ok=ok,
            message=msg, n_steps=events, max_residual=worst,
        )
