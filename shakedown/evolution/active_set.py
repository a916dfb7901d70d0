"""The active-set iteration of the step and rate problems (MODEL.md s.4).

The guess is the previous step's assignment; after each solve the nodes whose signs are
violated switch state (all at once; on a repeated assignment one at a time, the most violated
first; on a second repetition, a singular matrix or an exhausted iteration budget, a pivoting
fallback of :mod:`.fallbacks` takes over).
"""

from __future__ import annotations

import numpy as np

from .step_types import BACKWARD, FORWARD, SEPARATED, STICK, MixedSolution


class ActiveSet:
    """Mixin of :class:`~.complementarity.StepSolver`: sign checks and the active-set loop."""

    # ------------------------------------------------------------------ sign checks
    def _violations(self, s, z, q, p, allowed, forced, ft, dtol):
        """Normalised violation (> 1: violated) and target state per node."""
        n = self.n
        dv, w = z[:n], z[n:]
        f = self.f
        sp, sm = f * p + q, f * p - q
        cand = np.full((n, 4), -np.inf)  # magnitude of the violation that points to state k
        dvt, dwt = dtol[:n], dtol[n:]
        isS, isF, isB, isO = (s == STICK), (s == FORWARD), (s == BACKWARD), (s == SEPARATED)
        cand[:, SEPARATED] = np.where(~isO & allowed[:, SEPARATED], -p / ft, -np.inf)
        cand[:, FORWARD] = np.where(isS & allowed[:, FORWARD], -sp / ft, -np.inf)
        cand[:, BACKWARD] = np.where(isS & allowed[:, BACKWARD], -sm / ft, -np.inf)
        back = np.where(isF, -dv / dvt, np.where(isB, dv / dvt, np.where(isO, -w / dwt, -np.inf)))
        cand[:, STICK] = np.where(allowed[:, STICK], back, -np.inf)
        cand[forced] = -np.inf
        target = np.argmax(cand, axis=1).astype(np.int8)
        mag = cand[np.arange(n), target]
        return mag, target

    def _violations_step(self, s, z, q, p, ft, dtol):
        """:meth:`_violations` of the step problem (every state allowed, no node held), with
        one (4, N) array and no per-state masks: ``None`` when no sign is violated."""
        cand = self._step_candidates(s, z, q, p, ft, dtol)
        if cand.max() <= 1.0:
            return None
        target = np.argmax(cand, axis=0).astype(np.int8)
        return cand[target, self._node_range], target

    def _sign_layout(self, s):
        """Per-assignment data of :meth:`_step_candidates` (cached by assignment): the sign of
        the slip in the stick row (N,), the separated nodes (N,) and the (4, N) mask of the
        checks that do not apply."""
        key = s.tobytes()
        lay = self._sign_layouts.get(key)
        if lay is None:
            isS, isO = s == STICK, s == SEPARATED
            sgn = np.where(s == FORWARD, -1.0, 1.0)
            off = np.zeros((4, self.n), bool)
            off[STICK] = isS
            off[FORWARD:SEPARATED] = ~isS
            off[SEPARATED] |= isO
            if len(self._sign_layouts) >= 65536:
                self._sign_layouts.clear()
            lay = self._sign_layouts[key] = (sgn, isO, off)
        return lay

    def _step_candidates(self, s, z, q, p, ft, dtol):
        """The (4, N) normalised violations of the step problem's signs (> 1: violated; < -1:
        held by more than the tolerance; ``-inf`` where a check does not apply).

        Rows: stick ``-dv/dtol`` (forward), ``dv/dtol`` (backward), ``-w/dtol`` (separated);
        forward ``-(f p + q)/ft``, backward ``(q - f p)/ft`` (from stick); separated ``-p/ft``
        (from a contact state).  Computed as ``[f p + q, f p - q, p] / (-ft)`` in one division
        (the same floating-point values, IEEE negation being exact), the per-assignment masks
        cached by :meth:`_sign_layout` (a few numpy calls per step at N = 100, issue 25)."""
        n = self.n
        sgn, isO, off = self._sign_layout(s)
        fp = self.f * p
        cand = np.empty((4, n))
        np.add(fp, q, out=cand[FORWARD])
        np.subtract(fp, q, out=cand[BACKWARD])
        cand[SEPARATED] = p
        np.divide(cand[FORWARD:], -ft, out=cand[FORWARD:])
        zd = z / dtol
        np.multiply(sgn, zd[:n], out=cand[STICK])
        np.negative(zd[n:], out=cand[STICK], where=isO)
        np.putmask(cand, off, -np.inf)
        return cand

    def _probe(self, g, q0, p0, scale, ft, dtol):
        """The prediction ``g`` (the same step's assignment in the previous period) as the
        step's answer: a :class:`MixedSolution` when its factor is cached (or ``g`` is all
        stick) and every node holds its checks by more than the tolerance, else ``None``.

        Strictly inside the checks (no node at a state boundary, where another assignment
        gives the same answer to the tolerance) the answer's states determine the assignment,
        so with a unique step answer it is the one the iteration from the guess ends with (the
        kernel's probe, :func:`.kernel._probe`).  No factor is computed for a prediction."""
        key = g.tobytes()
        if g.any():  # (STICK = 0)
            F = self._cache.get(key)
            if F is None:
                return None
            self._keep_rows(F)  # its reactions by one product with the kept rows of K
            z = self._lu_solve(F, q0, p0)
            q, p = self._reactions(z, q0, p0, self._last_factor)
        else:
            F = None
            self._last_factor = None
            z = np.zeros(2 * self.n)
            q, p = q0.copy(), p0.copy()
        if not self._step_candidates(g, z, q, p, ft, dtol).max() < -1.0:
            return None
        hits = 0 if F is None else 1
        if F is not None:
            self._cache.move_to_end(key)
            self._base = F
        self.totals["cache_hits"] += hits
        self.totals["iterations"] += 1
        return MixedSolution(g.copy(), z, q, p, True, "active_set", 1, 0,
                             dict(factorizations=0, updates=0, cache_hits=hits))

    def residuals(self, z, q, p, allowed, forced, scale):
        """Natural complementarity residual of an answer (dimensionless; see StepResult).

        ``allowed=None`` / ``forced=None``: the step problem (every state allowed).
        """
        n = self.n
        dv, w = z[:n], z[n:]
        f = self.f
        if allowed is None:  # the step problem: x / ds = x K_jj / scale, min commutes
            # the three pairs (w, p), (dv+, f p + q), (dv-, f p - q) as rows of (3, N) arrays
            x = np.empty((3, n))
            y = np.empty((3, n))
            d = self.diag
            np.multiply(w, d[n:], out=x[0])
            np.multiply(dv, d[:n], out=x[1])
            np.negative(x[1], out=x[2])
            np.maximum(x[1:], 0.0, out=x[1:])
            y[0] = p
            np.multiply(f, p, out=y[1])
            np.subtract(y[1], q, out=y[2])
            y[1] += q
            np.minimum(x, y, out=x)
            r = np.abs(x, out=x).max(initial=0.0)
            return float(r / scale)
        ds = scale / self.diag
        xs = (w / ds[n:], np.maximum(dv, 0) / ds[:n], np.maximum(-dv, 0) / ds[:n])
        fp = f * p
        ys = (p / scale, (fp + q) / scale, (fp - q) / scale)
        res = 0.0
        free_nodes = ~forced
        for k, (x, y) in enumerate(zip(xs, ys, strict=True)):
            state = (SEPARATED, FORWARD, BACKWARD)[k]
            m = free_nodes & allowed[:, state]
            if np.any(m):
                res = max(res, float(np.abs(np.minimum(x[m], y[m])).max()))
            m2 = free_nodes & ~allowed[:, state]  # variable absent: must be zero
            if np.any(m2):
                res = max(res, float(np.abs(x[m2]).max()))
        fo = forced & allowed[:, SEPARATED]
        if np.any(fo):
            res = max(res, float(np.abs(np.concatenate([q[fo], p[fo]])).max() / scale))
        return res

    # ------------------------------------------------------------------ the mixed problem
    def solve_mixed(self, q0, p0, allowed=None, guess=None, scale=None,
                    prediction=None) -> MixedSolution:
        """Solve the step (or rate) problem with base reactions ``(q0, p0)`` at ``z = 0``.

        ``allowed`` (N, 4) bool: the states each node may take (rows with a single ``True`` are
        held in that state with no sign check: the interior nodes of a rate problem).
        ``prediction`` (step problem only): an assignment tried first by :meth:`_probe`.
        """
        n = self.n
        step = allowed is None
        allowed = self._all_allowed if step else np.asarray(allowed, bool)
        forced = self._none_forced if step else allowed.sum(axis=1) == 1
        if scale is None:
            scale = float(max(np.abs(q0).max(initial=0), np.abs(p0).max(initial=0)))
        scale = scale if scale > 0 else 1.0
        ft = self.feas_tol * scale
        dtol = ft / self.diag
        s = np.zeros(n, np.int8) if guess is None else np.array(guess, np.int8)
        if not step:
            bad = ~allowed[np.arange(n), s]
            s[bad] = np.argmax(allowed[bad], axis=1)
        self._counters = dict(factorizations=0, updates=0, cache_hits=0)
        if step and prediction is not None:
            prediction = np.asarray(prediction, np.int8)
        if step and prediction is not None and prediction.tobytes() != s.tobytes():
            sol = self._probe(prediction, q0, p0, scale, ft, dtol)
            if sol is not None:
                return sol
        visited = set()
        single = False
        it = 0
        while it < self.max_iter:
            it += 1
            key = s.tobytes()
            if key in visited:
                if single:
                    break
                single, visited = True, set()
            visited.add(key)
            z = self._solve_set(s, q0, p0, scale)
            if z is None:
                break
            q, p = self._reactions(z, q0, p0, self._last_factor)
            if step:
                viol = self._violations_step(s, z, q, p, ft, dtol)
            else:
                viol = self._violations(s, z, q, p, allowed, forced, ft, dtol)
                if viol[0].max(initial=-np.inf) <= 1.0:
                    viol = None
            if viol is None:
                self._remember(s, key)
                self.totals["iterations"] += it
                return MixedSolution(s, z, q, p, True, "active_set", it, 0, self._counters)
            mag, target = viol
            idx = np.flatnonzero(mag > 1.0) if not single else [int(np.argmax(mag))]
            s = s.copy()
            s[idx] = target[idx]
        self.totals["iterations"] += it
        if not np.any(forced) and np.all(allowed):
            sol = self._lemke_flexibility(q0, p0, scale)
        else:
            free = np.flatnonzero(~forced)
            n_assign = float(np.prod(allowed[free].sum(axis=1).astype(float)))
            sol = (self._enumerate_mixed(q0, p0, allowed, forced, scale) if n_assign <= 4096
                   else self._lemke(q0, p0, allowed, forced, scale))
        sol.iterations = it
        return sol
