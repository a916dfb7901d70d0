"""Pivoting and enumeration fallbacks of the step and rate problems (MODEL.md s.4).

Used when the active-set iteration cycles or meets a singular assignment: lexicographic Lemke
on a copositive reaction-based LCP (step problem), Lemke on the ``(w, dv+, dv-)`` LCP or
enumeration (rate problems), and the enumeration of all ``4^N`` assignments that decides
uniqueness for small systems above the critical friction.
"""

from __future__ import annotations

import itertools
from functools import cached_property

import numpy as np
import scipy.linalg as sla

from .lemke import lemke
from .step_types import BACKWARD, FORWARD, SEPARATED, STICK, MixedSolution, kinematic_states


class Fallbacks:
    """Mixin of :class:`~.complementarity.StepSolver`: Lemke and enumeration."""

    @cached_property
    def flexibility(self) -> np.ndarray:
        """``G = K^-1`` (computed once, only when the Lemke fallback is needed; dense, also for
        a sparse ``K``: Lemke's tableau is dense)."""
        K = self.K.toarray() if self.sparse else np.block([[self.A, self.B], [self.Bt, self.C]])
        return sla.cho_solve(sla.cho_factor(K), np.eye(2 * self.n))

    def _lemke_flexibility(self, q0, p0, scale) -> MixedSolution:
        """Lemke on the reaction-based LCP of the step, which is copositive for any friction.

        Unknowns ``x = (p, b+, b-, lam) >= 0`` with ``q = b+ - b-`` and ``(dv, w) = G (r - r0)``,
        ``G = K^-1``; complementary slacks ``w``, ``lam + dv``, ``lam - dv``, ``f p - b+ - b-``
        (the quasi-static analogue of the Stewart-Trinkle formulation).  ``x^T M x = r^T G r +
        lam^T F p >= 0`` for ``x >= 0``, and a secondary ray would need ``q^T x < 0`` on a
        direction with ``r = 0``, which the constant terms exclude; so lexicographic Lemke ends
        with a solution (Cottle, Pang & Stone 1992, Thm 4.4.13 argument as in Anitescu & Potra
        1997).
        """
        n = self.n
        self.totals["lemke_calls"] += 1
        G = self.flexibility
        c = -G @ np.concatenate([q0, p0])
        Gvq, Gvp, Gwq, Gwp = G[:n, :n], G[:n, n:], G[n:, :n], G[n:, n:]
        I, Z = np.eye(n), np.zeros((n, n))
        M = np.block([
            [Gwp, Gwq, -Gwq, Z],
            [Gvp, Gvq, -Gvq, I],
            [-Gvp, -Gvq, Gvq, I],
            [np.diag(self.f), -I, -I, Z],
        ])
        qv = np.concatenate([c[n:], c[:n], -c[:n], np.zeros(n)])
        # scale rows (displacements by K_jj) so that Lemke's tolerances are relative
        rs = np.concatenate([self.diag[n:], self.diag[:n], self.diag[:n], np.ones(n)])
        # ... and divide by the force scale: Lemke's tie tolerances then see O(1) numbers in
        # any units (the LCP is homogeneous in (q, z))
        # ... and measure lam (a displacement) by lam K_jj: every entry of the LCP is then
        # dimensionless (without it the lam columns carry K_jj and rounding depends on units)
        Ms = rs[:, None] * M
        Ms[:, 3 * n:] /= self.diag[:n]
        res = lemke(Ms, rs * qv / scale)
        self.totals["lemke_pivots"] += res.pivots
        x = res.z * scale
        p = x[:n]
        q = x[n:2 * n] - x[2 * n:3 * n]
        z = G @ (np.concatenate([q, p]) - np.concatenate([q0, p0]))
        allowed = np.ones((n, 4), bool)
        forced = np.zeros(n, bool)
        dtol = self.feas_tol * scale / self.diag
        s = kinematic_states(z[:n], z[n:], dtol)
        # re-solve with the assignment (clean answer, cached factors) when it verifies
        return self._lemke_answer(s, z, q0, p0, allowed, forced, scale, res, clean=True)

    def _lemke_answer(self, s, z, q0, p0, allowed, forced, scale, res, *, clean) -> MixedSolution:
        """A Lemke answer ``z`` with states ``s``: replaced by the solve of assignment ``s`` on
        the cached factors when that verifies (``clean``), then verified itself."""
        if clean:
            z2 = self._solve_set(s, q0, p0, scale)
            if z2 is not None:
                q2, p2 = self._reactions(z2, q0, p0)
                if self.residuals(z2, q2, p2, allowed, forced, scale) <= self.feas_tol:
                    z = z2
        q, p = self._reactions(z, q0, p0)
        ok = res.success and self.residuals(z, q, p, allowed, forced, scale) <= 10 * self.feas_tol
        return MixedSolution(s, z, q, p, bool(ok), "lemke", 0, res.pivots, self._counters)

    def _enumerate_mixed(self, q0, p0, allowed, forced, scale) -> MixedSolution:
        """Try every assignment of the non-held nodes (rate problems: few boundary nodes)."""
        n = self.n
        free = np.flatnonzero(~forced)
        base = np.argmax(allowed, axis=1).astype(np.int8)
        choices = [np.flatnonzero(allowed[j]) for j in free]
        best = None
        for combo in itertools.product(*choices):
            s = base.copy()
            s[free] = combo
            z = self._solve_set(s, q0, p0, scale)
            if z is None:
                continue
            q, p = self._reactions(z, q0, p0)
            r = self.residuals(z, q, p, allowed, forced, scale)
            if best is None or r < best[0]:
                best = (r, s, z, q, p)
            if r <= self.feas_tol:
                break
        if best is None:
            z = np.zeros(2 * n)
            q, p = self._reactions(z, q0, p0)
            return MixedSolution(base, z, q, p, False, "enumeration", 0, 0, self._counters)
        r, s, z, q, p = best
        return MixedSolution(s, z, q, p, bool(r <= self.feas_tol), "enumeration", 0, 0,
                             self._counters)

    def _lemke(self, q0, p0, allowed, forced, scale) -> MixedSolution:
        """Lexicographic Lemke on the LCP in (w, dv+, dv-) after condensing held-open nodes."""
        n = self.n
        self.totals["lemke_calls"] += 1
        held_open = forced & allowed[:, SEPARATED]
        act = np.flatnonzero(~forced)
        o = np.flatnonzero(held_open)
        ocols = np.concatenate([o, n + o])
        acols = np.concatenate([act, n + act])
        r0 = np.concatenate([q0, p0])
        Kaa = np.vstack([self._Kq(act, acols), self._Kp(act, acols)])
        ra = r0[acols]
        if o.size:
            Kao = np.vstack([self._Kq(act, ocols), self._Kp(act, ocols)])
            Koo = np.vstack([self._Kq(o, ocols), self._Kp(o, ocols)])
            Koa = np.vstack([self._Kq(o, acols), self._Kp(o, acols)])
            X = np.linalg.solve(Koo, np.column_stack([Koa, r0[ocols]]))
            Kaa = Kaa - Kao @ X[:, :-1]
            ra = ra - Kao @ X[:, -1]
        m = act.size
        fa = self.f[act]
        Qv, Qw, Pv, Pw = Kaa[:m, :m], Kaa[:m, m:], Kaa[m:, :m], Kaa[m:, m:]
        qa, pa = ra[:m], ra[m:]
        # rows: p, f p + q, f p - q ; columns: g (gap), a (dv+), b (dv-)
        Rv = [Pv, fa[:, None] * Pv + Qv, fa[:, None] * Pv - Qv]
        Rw = [Pw, fa[:, None] * Pw + Qw, fa[:, None] * Pw - Qw]
        Mfull = np.block([[Rw[i], Rv[i], -Rv[i]] for i in range(3)])
        qfull = np.concatenate([pa, fa * pa + qa, fa * pa - qa])
        use = np.concatenate([allowed[act, SEPARATED], allowed[act, FORWARD],
                              allowed[act, BACKWARD]])
        idx = np.flatnonzero(use)
        # dimensionless LCP (stiffness / ks, forces / scale): Lemke's tie tolerances are then
        # relative in any units; z = z' scale / ks
        ks = float(self.diag.max())
        res = lemke(Mfull[np.ix_(idx, idx)] / ks, qfull[idx] / scale)
        self.totals["lemke_pivots"] += res.pivots
        x = np.zeros(3 * m)
        x[idx] = res.z * (scale / ks)
        basic = np.zeros(3 * m, bool)
        nb = res.basis[(res.basis >= idx.size) & (res.basis < 2 * idx.size)] - idx.size
        basic[idx[nb]] = True
        s = np.zeros(n, np.int8)
        s[held_open] = SEPARATED
        sa = np.where(basic[:m] | (x[:m] > 0), SEPARATED,
                      np.where(basic[m:2 * m], FORWARD, np.where(basic[2 * m:], BACKWARD, STICK)))
        s[act] = sa
        z = np.zeros(2 * n)
        za = np.concatenate([x[m:2 * m] - x[2 * m:], x[:m]])
        z[acols] = za
        if o.size:
            z[ocols] = -(X[:, -1] + X[:, :-1] @ za)
        return self._lemke_answer(s, z, q0, p0, allowed, forced, scale, res,
                                  clean=res.success)

    def enumerate_solutions(self, q0, p0, scale):
        """Every solution of the step problem, by trying all ``4^N`` assignments."""
        n = self.n
        self.totals["enumerations"] += 1
        allowed = np.ones((n, 4), bool)
        forced = np.zeros(n, bool)
        sols = []
        ds = scale / self.diag
        for combo in itertools.product(range(4), repeat=n):
            s = np.array(combo, np.int8)
            free, coef, jv, jw = self._layout(s)
            z = np.zeros(2 * n)
            if free.size:
                Ms = self._dense(self._G_rows(s, free, coef, jv, jw, free))
                try:
                    z[free] = np.linalg.solve(Ms, self._rhs(coef, jv, jw, q0, p0))
                except np.linalg.LinAlgError:
                    continue
            q, p = self._reactions(z, q0, p0)
            if self.residuals(z, q, p, allowed, forced, scale) <= self.feas_tol:
                if not any(np.all(np.abs(z - z2) <= 1e3 * self.feas_tol * ds) for z2, *_ in sols):
                    sols.append((z, q, p, s))
        return sols
