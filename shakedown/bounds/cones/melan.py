"""``lam2`` in 3-D by cutting planes on time, with a certified bracket (MODEL.md s.8.3).

``lam2 = sup {lam : H(lam) != {}}`` where ``H(lam)`` is the set of slip states ``v`` whose every
node stays inside its friction cone at every time of the cycle: a semi-infinite second-order
cone program.  Sampling the cycle at fixed times relaxes it (fewer constraints), so a sampled
SOCP *over*-estimates ``lam2``.  Here the times are refined until the exact worst times are
found (an exchange / cutting-plane method):

1. solve the SOCP on the current cuts (:func:`.socp.solve_cuts`): value ``lam_k``, state
   ``u_k``; its multipliers prove ``lam2 <= lam_hi`` (:func:`.socp.dual_bound`, weak duality:
   any subset of the constraints gives an upper bound; the multipliers' residuals enter the
   bound through an a-priori bound on the state, :mod:`.dual`, so it holds whatever their
   accuracy);
2. find every node's exact worst time for ``(u_k, lam_k)`` (:mod:`.separation`, roots of a
   trigonometric polynomial) and the largest violation ``eps >= 0``;
3. a state with a proven strict margin ``tau0 > 0`` at ``lam = 0`` (:func:`.socp.static_margin`)
   and convexity of ``H`` in ``(v, lam)`` give the exactly safe state
   ``theta (u_k, lam_k) + (1 - theta) (u0, 0)``, ``theta = tau0 / (tau0 + eps)``: ``lam_lo =
   theta lam_k`` (checked again by the exact separation);
4. stop when ``lam_hi - lam_lo <= rtol lam_hi``; else add the worst time of every violated node
   as a new cut.

Everything is nondimensional (:mod:`.data`); the bracket is scaled back by the load-factor scale.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .rounds import SocpLog, active_cuts, margin_state, resolve_solver, solve_round
from .separation import worst_times
from .socp import LAM_CAP, dual_bound, solve_cuts

#: Default relative width of the certified bracket ``[lam_lo, lam_hi]``.
BRACKET_RTOL = 1e-6
#: Below this ``rtol`` every dense round solves its late Newton systems in the split form
#: (:mod:`.ipm_split`): the normal equations stop at a gap of ``~ 1e-8 .. 1e-6``.  Not above
#: it: its LU of ``2N + 1 + k`` (``k`` split cones) is dear at large N (measured at N = 500,
#: rtol = 1e-6, seed 2 of the benchmark: 89 s of CPU with split re-solves and ``DUAL_TOL =
#: 1e-4``, against 27 s with neither).
SPLIT_RTOL = 1e-7
#: A node is cut again when its violation exceeds this (units of the force scale).
CUT_TOL = 1e-12
#: Largest dual residual (cone membership, stationarity; relative) of a dense answer accepted
#: without a Clarabel re-solve.  A quality screen only: the bound of any multipliers is valid
#: (:mod:`.dual`, which also polishes them), larger residuals just make it looser, and a bound
#: too loose to close the bracket is re-solved anyway (``_too_wide``).  It was ``1e-6`` when
#: the bound relied on the residuals being small, and is kept: a larger value lets rounds
#: through whose bound is then too loose, and their re-solve costs more than Clarabel's.
DUAL_TOL = 1e-6


@dataclass
class MelanOutcome:
    """Nondimensional answer of :func:`melan_lam2` (see :class:`~.result.ConeBounds`)."""

    status: str
    lam_lo: float
    lam_hi: float
    u_safe: np.ndarray
    margin: float
    u_last: np.ndarray
    lam_last: float
    cut_nodes: np.ndarray
    cut_times: np.ndarray
    z: np.ndarray
    residuals: dict = field(default_factory=dict)
    rounds: int = 0
    iterations: int = 0
    history: list = field(default_factory=list)
    messages: list = field(default_factory=list)
    u0: np.ndarray | None = None
    tau0: float = np.nan
    log: SocpLog = field(default_factory=SocpLog)


def initial_cuts(data, per_node=None):
    """Equally spaced times for every node: ``4 H`` per node for harmonic loads (``H`` the
    number of harmonics), at most 8 samples for sampled loads."""
    n = data.n_nodes
    if per_node is None:
        per_node = 4 * data.ac.shape[0] if data.kind == "harmonic" else min(8, data.b1s.shape[0])
    if data.kind == "samples":
        S = data.b1s.shape[0]
        t = np.unique(np.round(np.linspace(0, S, per_node, endpoint=False)).astype(int) % S) / S
    else:
        t = np.arange(per_node) / per_node
    return np.repeat(np.arange(n), t.size), np.tile(t, n)


def melan_lam2(data, *, rtol=BRACKET_RTOL, max_rounds=60, cuts=None, solver="auto",
               fail=None) -> MelanOutcome:
    """The certified bracket ``lam_lo <= lam2 <= lam_hi`` (module docstring), nondimensional.

    Parameters
    ----------
    data : ConeData
    rtol : float
        Stop when ``lam_hi - lam_lo <= rtol * lam_hi``.
    max_rounds : int
        SOCP solves at most; the bracket reached is returned with status ``"bracket"``.
    cuts : tuple of (nodes, times), optional
        Starting cuts (default :func:`initial_cuts`).
    solver : {"auto", "dense", "clarabel"}
        ``"dense"``: every SOCP of a coupled system by the dense interior point (checked;
        Clarabel where the check fails or where its bound is too loose to close the bracket),
        and each round re-solves only the cuts that carry the last relaxation plus the new
        worst times (:func:`.rounds.active_cuts`); ``"clarabel"``: every SOCP by Clarabel on
        the growing set of cuts; ``"auto"``: ``"dense"`` from
        :data:`.rounds.DENSE_MIN_NODES` nodes on.  Uncoupled systems always use Clarabel
        (their SOCP is sparse).
    fail : callable, optional
        Test hook passed to :func:`.rounds.solve_round`.
    """
    nodes, times = initial_cuts(data) if cuts is None else (np.asarray(cuts[0]),
                                                            np.asarray(cuts[1], float))
    log = SocpLog()
    solver = resolve_solver(solver, data)
    u0, tau0 = margin_state(data, solver=solver, log=log, fail=fail)
    out = MelanOutcome("bounded", 0.0, np.inf, u0, tau0, u0, 0.0, nodes, times, np.zeros((0, 3)),
                       u0=u0, tau0=tau0, log=log)
    dense = solver == "dense"
    split = rtol < SPLIT_RTOL
    start = (u0, 0.0)
    if not tau0 > 0:
        out.status = "infeasible"
        out.lam_lo = out.lam_hi = np.nan
        out.messages.append(
            "no state is strictly inside every friction cone under the static load (lam = 0): "
            "gross slip, or a node at the edge of its cone")
        return out
    worst = {"cone": 0.0, "stationarity": 0.0, "sign": 0.0}
    for rnd in range(max_rounds):
        ans, bound = solve_round(data, nodes, times, solver=solver, start=start,
                                 dual_tol=DUAL_TOL, log=log, fail=fail, split=split)
        out.rounds = rnd + 1
        out.iterations += ans.iterations
        if ans.status == "unbounded":
            out.status, out.lam_hi = "unbounded", np.inf
            out.messages.append("a safe state exists for every lam (the relaxation reached lam = "
                                f"{LAM_CAP:g} load-factor scales)")
            g, _ = worst_times(data, ans.u, ans.lam)
            if g.max() <= 0:
                out.lam_lo, out.u_safe = ans.lam, ans.u
            break
        if ans.status != "optimal":
            out.status = "failed"
            out.messages.append(f"the SOCP solver stopped with status {ans.status}")
            break
        hi, res = dual_bound(data, nodes, times, ans.z, ans.y_cap) if bound is None else bound
        cert = (hi, res, ans.z, nodes, times)
        g, tw = worst_times(data, ans.u, ans.lam)
        eps = max(float(g.max()), 0.0)
        theta = tau0 / (tau0 + eps + CUT_TOL * tau0)
        uc, lc = theta * ans.u + (1 - theta) * u0, theta * ans.lam
        if bound is not None and _too_wide(out, hi, lc, ans.lam, rtol):
            # the cuts are right but the dense answer's gap (~ cuts x mu) is too wide to close
            # the bracket: its active cuts alone (a relaxation too) by the dense path (split
            # Newton systems, .ipm_split, when rtol < SPLIT_RTOL), and if that is still too
            # wide, the whole round by Clarabel
            cert, ans2 = _tighten(data, nodes, times, ans, (0.9 * uc + 0.1 * u0, 0.9 * lc), log,
                                  fail, split)
            out.iterations += ans2.iterations if ans2 is not None else 0
            if _too_wide(out, cert[0], lc, ans.lam, rtol):
                log.record("clarabel", "dense interior point: gap too wide to close the bracket "
                           f"({(hi - ans.lam) / hi:.2g})")
                ans = solve_cuts(data, nodes, times)
                out.iterations += ans.iterations
                if ans.status != "optimal":
                    out.status = "failed"
                    out.messages.append(f"the SOCP solver stopped with status {ans.status}")
                    break
                hi, res = dual_bound(data, nodes, times, ans.z, ans.y_cap)
                cert = (hi, res, ans.z, nodes, times)
                g, tw = worst_times(data, ans.u, ans.lam)
                eps = max(float(g.max()), 0.0)
                theta = tau0 / (tau0 + eps + CUT_TOL * tau0)
                uc, lc = theta * ans.u + (1 - theta) * u0, theta * ans.lam
        res = cert[1]
        _adopt(out, worst, cert)
        gc, _ = worst_times(data, uc, lc)
        if gc.max() <= 0 and lc >= out.lam_lo:
            out.lam_lo, out.u_safe, out.margin = lc, uc, float(-gc.max())
        out.u_last, out.lam_last = ans.u, ans.lam
        out.history.append((len(nodes), ans.lam, out.lam_lo, out.lam_hi, eps))
        if out.lam_hi - out.lam_lo <= rtol * max(out.lam_hi, 1e-300):
            break
        viol = np.flatnonzero(g > CUT_TOL)
        if viol.size == 0 and not dense:
            # no violation but the bracket is open: the solver's multipliers (Clarabel's
            # stationarity ~1e-8) do not certify its value to rtol; the active cuts alone by
            # the dense path may (issue 22: seed 0 of tests/bounds/test_cone_dual.py bracketed
            # to 1.3e-9 against rtol = 1e-9 with OpenBLAS's AVX-512 kernels)
            cert, ans2 = _tighten(data, nodes, times, ans, (0.9 * uc + 0.1 * u0, 0.9 * lc),
                                  log, fail, split)
            out.iterations += ans2.iterations if ans2 is not None else 0
            _adopt(out, worst, cert)
            if out.lam_hi - out.lam_lo <= rtol * max(out.lam_hi, 1e-300):
                break
        if viol.size == 0:  # no violation but the bracket is open: dual not certified
            out.messages.append("the relaxation's multipliers did not certify its value "
                                f"(residuals {res})")
            break
        start = (0.9 * uc + 0.1 * u0, 0.9 * lc)  # strictly inside every cone
        if dense:
            nodes, times = _prune(nodes, times, ans.z, tw)
        nodes, times = _add_cuts(nodes, times, viol, tw[viol])
    else:
        out.status = "bracket"
    if out.status == "bounded" and not out.lam_hi - out.lam_lo <= rtol * max(out.lam_hi, 1e-300):
        out.status = "bracket"
    if out.status == "bracket":
        out.messages.append(f"lam2 bracketed in [{out.lam_lo:.10g}, {out.lam_hi:.10g}] "
                            f"(nondimensional) after {out.rounds} SOCPs, not to rtol = {rtol:g}")
    out.residuals = worst
    return out


def _adopt(out, worst, cert):
    """Take the bound of ``cert = (hi, residuals, z, nodes, times)`` where it is lower than the
    bracket's upper end (valid whatever the residuals, :mod:`.dual`: they only loosen it), and
    keep the worst residuals."""
    hi, res, z, nodes, times = cert
    for k, v in res.items():
        worst[k] = max(worst[k], v)
    if hi < out.lam_hi:
        out.lam_hi, out.z = hi, z
        out.cut_nodes, out.cut_times = nodes.copy(), times.copy()


def _too_wide(out, hi, lc, lam, rtol):
    """The state's side would close the bracket but the bound ``hi`` does not."""
    lo, up = max(lc, out.lam_lo), min(hi, out.lam_hi)
    return lo >= (1 - 0.5 * rtol) * lam and up - lo > rtol * up


def _tighten(data, nodes, times, ans, start, log, fail, split):
    """The bound of the relaxation on the active cuts of ``ans`` alone (fewer cones: a smaller
    gap at the interior point's accuracy); ``(cert, answer)`` with ``cert = (hi, residuals, z,
    nodes, times)``, the better (smaller, valid) of the two bounds."""
    hi, res = dual_bound(data, nodes, times, ans.z, ans.y_cap)
    cert = (hi, res, ans.z, nodes, times)
    sn, st = active_cuts(nodes, times, ans.z, np.zeros(0, int), np.zeros(0))
    if sn.size >= nodes.size:
        return cert, None
    a2, b2 = solve_round(data, sn, st, solver="dense", start=start, dual_tol=DUAL_TOL, log=log,
                         fail=fail, split=split)
    if a2.status != "optimal":
        return cert, a2
    h2, r2 = dual_bound(data, sn, st, a2.z, a2.y_cap) if b2 is None else b2
    if h2 < hi:
        cert = (h2, r2, a2.z, sn, st)
    return cert, a2


def _prune(nodes, times, z, tw):
    """The cuts that carry the relaxation (:func:`.rounds.active_cuts`), and the worst time of
    every node left without a cut."""
    nn, tt = active_cuts(nodes, times, z, np.zeros(0, int), np.zeros(0))
    free = np.setdiff1d(np.arange(tw.size), nn)
    return np.concatenate([nn, free]), np.concatenate([tt, tw[free]])


def _add_cuts(nodes, times, viol, tw):
    """Add the worst time of every violated node and two neighbours at a quarter of the
    distance to the node's nearest cut on either side: the interval around the maximiser of
    the violation shrinks about four-fold per round instead of two-fold."""
    order = np.lexsort((times, nodes))
    sn, st = nodes[order], times[order]
    new_n, new_t = [viol], [tw]
    first = np.searchsorted(sn, viol, side="left")
    last = np.searchsorted(sn, viol, side="right")
    for i, t, a, b in zip(viol, tw, first, last, strict=True):
        ts = st[a:b]
        if ts.size == 0:
            continue
        d = np.mod(ts - t, 1.0)  # distance forward
        fwd = d[d > 1e-12].min(initial=0.5)
        bwd = np.mod(t - ts, 1.0)
        bwd = bwd[bwd > 1e-12].min(initial=0.5)
        new_n.append(np.array([i, i]))
        new_t.append(np.mod(np.array([t + 0.25 * fwd, t - 0.25 * bwd]), 1.0))
    return np.concatenate([nodes, *new_n]), np.concatenate([times, *new_t])
