"""Periodic welded reactions ``r_w(t) = r_0 + lam r_1(t)``, ``r = (q, p)`` (MODEL.md s.2).

Time is measured in cycles: ``t`` in ``[0, 1)`` is one period.  The periodic part ``r_1`` is
either a trigonometric polynomial (harmonics, exact extremes) or piecewise linear between
``n_samples`` equally spaced samples (extremes at the samples, exactly).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .errors import InputError, ShapeError
from .validation import check_count, real_array


def _vector(name: str, value, n: int | None, *, tangential: bool = False) -> np.ndarray:
    """One entry per node: shape (N,); a tangential ``q0`` may also be (N, 2) (3-D)."""
    arr = real_array(name, value)
    if arr.ndim in (1, 2) and arr.shape[0] == 0:
        raise ShapeError(f"{name} is empty: a load needs at least one node (N >= 1)")
    three_d = tangential and arr.ndim == 2 and arr.shape[1:] == (2,)
    if (arr.ndim != 1 and not three_d) or (n is not None and arr.shape[0] != n):
        want = f"({n},)" if n is not None else "(N,)"
        if tangential:
            want += f" (2-D) or {want[:-2]}, 2) (3-D: q_x, q_y per node)"
        raise ShapeError(f"{name} must have shape {want}; got shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise InputError(f"{name} must be finite; got {arr[~np.isfinite(arr)][0]}")
    return arr


def _static_pair(q0, p0) -> tuple[np.ndarray, np.ndarray]:
    """``q0`` and ``p0``, one entry per node each; a length mismatch names both (issue 9)."""
    q0, p0 = _vector("q0", q0, None, tangential=True), _vector("p0", p0, None)
    if q0.shape[0] != p0.shape[0]:
        raise ShapeError(
            f"q0 has {q0.shape[0]} entries but p0 has {p0.shape[0]}: both need one entry per node; "
            "fix the one whose length is not the number of nodes"
        )
    return q0, p0


def _table(name: str, value, n: int, *, allow_1d: bool, comp: tuple = ()) -> np.ndarray:
    """Rows of per-node values, shape (rows, N) + comp; ``comp = (2,)`` for 3-D tangential
    arrays.  With ``allow_1d`` a single row (N,) + comp is accepted."""
    arr = real_array(name, value)
    if arr.ndim == 1 + len(comp) and allow_1d:
        arr = arr[None]
    if arr.ndim != 2 + len(comp) or arr.shape[1:] != (n,) + comp:
        row = ", ".join([str(n)] + [str(c) for c in comp])
        shapes = (f"({row}{',' if not comp else ''}) or (n_harmonics, {row})" if allow_1d
                  else f"(n_samples, {row})")
        dim = " (dim = 3: q arrays carry (q_x, q_y) per node, p arrays one value)" if comp else ""
        raise ShapeError(f"{name} must have shape {shapes} (N = {n} nodes, the length of q0)"
                         f"{dim}; got shape {np.shape(value)}")
    if not np.all(np.isfinite(arr)):
        raise InputError(f"{name} must be finite; got {arr[~np.isfinite(arr)][0]}")
    return arr


def _frozen(*arrays):
    for a in arrays:
        a.setflags(write=False)


@dataclass(frozen=True, eq=False)
class LoadCycle:
    """Periodic welded reactions of ``N`` nodes, ``r_w(t) = r_0 + lam r_1(t)``.

    Build with :meth:`from_harmonics` or :meth:`from_samples`.  Forces are in the same units as
    ``K @ displacement`` (force per unit thickness for 2-D models).

    Three dimensions (MODEL.md s.8.1): the tangential arrays carry ``(q_x, q_y)`` per node in a
    trailing axis of length 2 (``q0`` of shape (N, 2), ``q_cos`` (H, N, 2), ``q1`` (S, N, 2));
    the normal arrays keep their 2-D shapes.  The dimension follows from ``q0``:
    :attr:`dim` is 3 when ``q0`` has shape (N, 2).

    Attributes
    ----------
    q0, p0 : ndarray, shape (N,) (``q0``: (N, 2) in 3-D)
        Static welded tangential and normal reactions (compression positive).
    kind : {"harmonic", "samples"}
    q_cos, q_sin, p_cos, p_sin : ndarray, shape (H, N) (``q_*``: (H, N, 2) in 3-D)
        Harmonic coefficients (``kind == "harmonic"``); harmonic ``k`` has frequency ``k + 1``.
    q1, p1 : ndarray, shape (S, N) (``q1``: (S, N, 2) in 3-D)
        Samples of the periodic part at ``t = k / S`` (``kind == "samples"``).
    """

    q0: np.ndarray
    p0: np.ndarray
    kind: str
    q_cos: np.ndarray | None = None
    q_sin: np.ndarray | None = None
    p_cos: np.ndarray | None = None
    p_sin: np.ndarray | None = None
    q1: np.ndarray | None = None
    p1: np.ndarray | None = None

    # ------------------------------------------------------------------ constructors
    @classmethod
    def from_harmonics(cls, q0, p0, *, q_cos=None, q_sin=None, p_cos=None, p_sin=None):
        """Periodic part as a Fourier series over one period (``t`` in cycles).

        ``q_w(t) = q0 + lam * sum_k (q_cos[k] cos(2 pi (k+1) t) + q_sin[k] sin(2 pi (k+1) t))``
        and the same for ``p``.  Each coefficient array has shape ``(N,)`` (one harmonic) or
        ``(n_harmonics, N)``; omitted arrays are zero.  Arrays with fewer harmonics are
        zero-padded.  In 3-D (``q0`` of shape (N, 2)) ``q_cos`` and ``q_sin`` have shape
        ``(N, 2)`` or ``(n_harmonics, N, 2)``; ``p_cos``, ``p_sin`` keep ``(N,)`` or
        ``(n_harmonics, N)``.
        """
        q0, p0 = _static_pair(q0, p0)
        n = q0.shape[0]
        qc = q0.shape[1:]  # () in 2-D, (2,) in 3-D
        given = {"q_cos": q_cos, "q_sin": q_sin, "p_cos": p_cos, "p_sin": p_sin}
        tables = {
            k: _table(k, v, n, allow_1d=True, comp=qc if k[0] == "q" else ())
            for k, v in given.items() if v is not None
        }
        h = max([t.shape[0] for t in tables.values()], default=1)
        full = {}
        for k in given:
            t = np.zeros((h, n) + (qc if k[0] == "q" else ()))
            if k in tables:
                t[: tables[k].shape[0]] = tables[k]
            full[k] = t
        _frozen(q0, p0, *full.values())
        return cls(q0=q0, p0=p0, kind="harmonic", **full)

    @classmethod
    def from_samples(cls, q0, p0, q1, p1):
        """Periodic part from samples ``q1[k], p1[k]`` at ``t = k / n_samples``, shape (S, N)
        (``q1``: (S, N, 2) in 3-D).

        Between samples the load is linear; the cycle closes from the last sample back to the
        first.  At least two samples are needed.
        """
        q0, p0 = _static_pair(q0, p0)
        n = q0.shape[0]
        q1 = _table("q1", q1, n, allow_1d=False, comp=q0.shape[1:])
        p1 = _table("p1", p1, n, allow_1d=False)
        if q1.shape[:2] != p1.shape:
            raise ShapeError(f"q1 and p1 must have the same shape; got {q1.shape} and {p1.shape}")
        if q1.shape[0] < 2:
            raise InputError(f"from_samples needs at least 2 samples per period; got {q1.shape[0]}")
        _frozen(q0, p0, q1, p1)
        return cls(q0=q0, p0=p0, kind="samples", q1=q1, p1=p1)

    @classmethod
    def static(cls, q0, p0):
        """A load with no periodic part."""
        q0 = _vector("q0", q0, None, tangential=True)
        return cls.from_harmonics(q0, p0)

    # ------------------------------------------------------------------ basic queries
    @property
    def n_nodes(self) -> int:
        return self.q0.shape[0]

    @property
    def dim(self) -> int:
        """2 (one tangential component per node) or 3 (``q0`` of shape (N, 2))."""
        return 3 if self.q0.ndim == 2 else 2

    @property
    def n_harmonics(self) -> int:
        return self.q_cos.shape[0] if self.kind == "harmonic" else 0

    @property
    def n_samples(self) -> int:
        return self.q1.shape[0] if self.kind == "samples" else 0

    @property
    def has_periodic_part(self) -> bool:
        if self.kind == "harmonic":
            return bool(
                np.any(self.q_cos) or np.any(self.q_sin) or np.any(self.p_cos) or np.any(self.p_sin)
            )
        return bool(np.any(self.q1) or np.any(self.p1))

    @property
    def breakpoints(self) -> np.ndarray:
        """Times (cycles) where the load's slope may change: the samples, or none for harmonics."""
        if self.kind == "samples":
            return np.arange(self.n_samples) / self.n_samples
        return np.zeros(0)

    def periodic(self, t):
        """Periodic part ``(q1(t), p1(t))``, each of shape ``np.shape(t) + (N,)`` (``q1``:
        ``np.shape(t) + (N, 2)`` in 3-D)."""
        t = np.asarray(t, dtype=float)
        if self.kind == "harmonic":
            k = np.arange(1, self.n_harmonics + 1)
            ang = 2 * np.pi * t[..., None] * k  # (..., H)
            c, s = np.cos(ang), np.sin(ang)
            if self.dim == 3:  # per direction as in 2-D: the same products, the same bits
                q = np.stack([c @ np.ascontiguousarray(self.q_cos[..., d])
                              + s @ np.ascontiguousarray(self.q_sin[..., d]) for d in (0, 1)],
                             axis=-1)
            else:
                q = c @ self.q_cos + s @ self.q_sin
            p = c @ self.p_cos + s @ self.p_sin
            return q, p
        S = self.n_samples
        x = np.mod(t, 1.0) * S
        i0 = np.floor(x).astype(int) % S
        frac = (x - np.floor(x))[..., None]
        i1 = (i0 + 1) % S
        fq = frac[..., None] if self.dim == 3 else frac
        q = (1 - fq) * self.q1[i0] + fq * self.q1[i1]
        p = (1 - frac) * self.p1[i0] + frac * self.p1[i1]
        return q, p

    def evaluate(self, t, lam: float):
        """Welded reactions ``(q_w(t), p_w(t))`` at load factor ``lam``; shapes ``t.shape + (N,)``."""
        q1, p1 = self.periodic(t)
        return self.q0 + lam * q1, self.p0 + lam * p1

    def q_w(self, t, lam: float) -> np.ndarray:
        """Welded tangential reaction ``q_w(t)``, shape ``np.shape(t) + (N,)``."""
        return self.evaluate(t, lam)[0]

    def p_w(self, t, lam: float) -> np.ndarray:
        """Welded normal reaction ``p_w(t)`` (compression positive), shape ``np.shape(t) + (N,)``."""
        return self.evaluate(t, lam)[1]

    # ------------------------------------------------------------------ extremes
    def periodic_min(self, cq, cp) -> tuple[np.ndarray, np.ndarray]:
        """Per node, the minimum over the cycle of ``cq_j q1_j(t) + cp_j p1_j(t)``.

        Parameters
        ----------
        cq, cp : array_like, shape (N,) or scalars
            Per-node weights of the tangential and normal periodic parts.  In 3-D ``cq`` has
            shape (N, 2) (or (2,)): a direction per node, the value is ``cq_j . q1_j(t)``.

        Returns
        -------
        minimum : ndarray, shape (N,)
            Exact minimum (closed form for one harmonic, roots of the derivative's
            trigonometric polynomial for several, the samples for sampled loads).
        t_min : ndarray, shape (N,)
            A time (cycles, in ``[0, 1)``) where the minimum is reached.
        """
        n = self.n_nodes
        cq = np.broadcast_to(np.asarray(cq, float), self.q0.shape)
        cp = np.broadcast_to(np.asarray(cp, float), (n,))
        if self.dim == 3:  # project the tangential arrays on the directions cq: a 2-D problem
            def dot(a):
                return (cq * a).sum(axis=-1)
        else:
            def dot(a):
                return cq * a
        if self.kind == "samples":
            g = dot(self.q1) + cp * self.p1  # (S, N)
            i = np.argmin(g, axis=0)
            return g[i, np.arange(n)], i / self.n_samples
        a = dot(self.q_cos) + cp * self.p_cos  # (H, N) cosine coefficients
        b = dot(self.q_sin) + cp * self.p_sin
        return _trig_min(a, b)

    def periodic_max(self, cq, cp):
        """Per node, the maximum over the cycle of ``cq q1 + cp p1`` and where it is reached."""
        m, t = self.periodic_min(-np.asarray(cq, float), -np.asarray(cp, float))
        return -m, t

    # ------------------------------------------------------------------ sampling error
    def sampling_error(self, n_samples: int) -> tuple[np.ndarray, np.ndarray]:
        """Largest error of the periodic part when it is sampled at ``n_samples`` equal steps.

        Per node, ``max_t |r1(t) - r1_S(t)|`` for ``r1 = q1, p1`` and ``r1_S`` the piecewise-linear
        interpolant through ``t = k / n_samples`` (what :meth:`to_samples` and implicit steps
        see).  Multiply by ``lam`` for the welded reactions [force].

        Harmonics (closed form): a harmonic ``k`` of amplitude ``a_k`` sampled every
        ``1 / S`` loses at most ``a_k (1 - cos(pi k / S))`` (reached when a peak falls midway
        between samples: the chord lies ``a_k (1 - cos(pi k / S))`` below it); the sum over
        harmonics bounds the error of several (exact for one).  Samples: exact, from the
        breakpoints of both piecewise-linear functions (0 when the sample times are a subset
        of the new ones).

        3-D: ``err_q`` bounds the Euclidean norm of the tangential error, by the root sum of
        squares of the two components' bounds (for harmonics; exact for samples, where the
        norm of the piecewise-linear difference is largest at a breakpoint).

        Returns
        -------
        err_q, err_p : ndarray, shape (N,)
            [force per unit load factor].
        """
        S = check_count("n_samples", n_samples, 2)
        if self.kind == "harmonic":
            loss = 1.0 - np.cos(np.pi * np.arange(1, self.n_harmonics + 1) / S)  # (H,)
            if self.dim == 3:
                amp = np.hypot(self.q_cos, self.q_sin)  # per direction as in 2-D (same bits)
                err_q = np.hypot(*(loss @ np.ascontiguousarray(amp[..., d]) for d in (0, 1)))
            else:
                err_q = loss @ np.hypot(self.q_cos, self.q_sin)
            return err_q, loss @ np.hypot(self.p_cos, self.p_sin)
        if S % self.n_samples == 0:
            return np.zeros(self.n_nodes), np.zeros(self.n_nodes)
        t = np.union1d(np.arange(S) / S, self.breakpoints)
        exact = self.periodic(t)
        coarse = self.to_samples(S).periodic(t)
        dq = np.abs(exact[0] - coarse[0])
        if self.dim == 3:
            dq = np.linalg.norm(exact[0] - coarse[0], axis=-1)
        return dq.max(axis=0), np.abs(exact[1] - coarse[1]).max(axis=0)

    # ------------------------------------------------------------------ transformations
    def to_samples(self, n_samples: int) -> LoadCycle:
        """Piecewise-linear interpolant of this load through ``n_samples`` equally spaced samples."""
        n_samples = check_count("n_samples", n_samples, 2)
        t = np.arange(n_samples) / n_samples
        q1, p1 = self.periodic(t)
        return LoadCycle.from_samples(self.q0, self.p0, q1, p1)

    def permuted(self, order) -> LoadCycle:
        """The same load with nodes reordered (``new[i] = old[order[i]]``)."""
        try:
            o = np.asarray(order)
            ok = o.shape == (self.n_nodes,) and o.dtype.kind in "iu"
        except (TypeError, ValueError):
            ok = False
        if not ok or not np.array_equal(np.sort(o), np.arange(self.n_nodes)):
            raise InputError(
                f"order must be a permutation of 0..{self.n_nodes - 1} (each node exactly "
                f"once, integers); got {order!r}"
            )
        if self.kind == "samples":
            return LoadCycle.from_samples(self.q0[o], self.p0[o], self.q1[:, o], self.p1[:, o])
        return LoadCycle.from_harmonics(
            self.q0[o], self.p0[o], q_cos=self.q_cos[:, o], q_sin=self.q_sin[:, o],
            p_cos=self.p_cos[:, o], p_sin=self.p_sin[:, o],
        )

    def scaled(self, factor: float) -> LoadCycle:
        """All reactions multiplied by ``factor``."""
        if self.kind == "samples":
            return LoadCycle.from_samples(
                factor * self.q0, factor * self.p0, factor * self.q1, factor * self.p1
            )
        return LoadCycle.from_harmonics(
            factor * self.q0, factor * self.p0, q_cos=factor * self.q_cos,
            q_sin=factor * self.q_sin, p_cos=factor * self.p_cos, p_sin=factor * self.p_sin,
        )

    def __repr__(self) -> str:
        extra = (
            f"n_harmonics={self.n_harmonics}" if self.kind == "harmonic"
            else f"n_samples={self.n_samples}"
        )
        dim = ", dim=3" if self.dim == 3 else ""
        return f"LoadCycle(n_nodes={self.n_nodes}{dim}, kind={self.kind!r}, {extra})"


def _trig_min(a: np.ndarray, b: np.ndarray):
    """Exact minimum over t in [0,1) of g_j(t) = sum_k a[k,j] cos(2 pi (k+1) t) + b[k,j] sin(...).

    One harmonic: ``-sqrt(a^2 + b^2)``.  Several: the critical points are the roots on the unit
    circle of ``z^H g'(z)``, a polynomial of degree 2H in ``z = exp(2 pi i t)``; every real
    critical point is evaluated and refined by two Newton steps.
    """
    H, n = a.shape
    if H == 1:
        amp = np.hypot(a[0], b[0])
        t = np.mod((np.arctan2(b[0], a[0]) + np.pi) / (2 * np.pi), 1.0)
        return -amp, t
    k = np.arange(1, H + 1)

    def g(t, j):
        ang = 2 * np.pi * np.outer(np.atleast_1d(t), k)
        return np.cos(ang) @ a[:, j] + np.sin(ang) @ b[:, j]

    mins = np.empty(n)
    tmin = np.empty(n)
    grid = np.arange(8 * H + 1) / (8 * H)
    for j in range(n):
        if not (np.any(a[:, j]) or np.any(b[:, j])):
            mins[j], tmin[j] = 0.0, 0.0
            continue
        # g'(theta) = sum_k k (b_k cos k theta - a_k sin k theta); with z = e^{i theta}:
        # cos = (z^k + z^-k)/2, sin = (z^k - z^-k)/(2i).  Coefficient of z^k: k (b_k + i a_k)/2,
        # of z^-k: k (b_k - i a_k)/2.  Multiply by z^H: degree-2H polynomial.
        coef = np.zeros(2 * H + 1, dtype=complex)  # index = power of z
        coef[H + k] = k * (b[:, j] + 1j * a[:, j]) / 2
        coef[H - k] = k * (b[:, j] - 1j * a[:, j]) / 2
        roots = np.roots(coef[::-1])
        roots = roots[np.abs(np.abs(roots) - 1.0) < 1e-6]
        raw = np.concatenate([np.mod(np.angle(roots) / (2 * np.pi), 1.0), grid])
        cand = raw.copy()
        for _ in range(2):  # Newton polish on g'(t) = 0
            ang = 2 * np.pi * np.outer(cand, k)
            d1 = (-np.sin(ang) * k) @ a[:, j] + (np.cos(ang) * k) @ b[:, j]
            d2 = (-np.cos(ang) * k**2) @ a[:, j] + (-np.sin(ang) * k**2) @ b[:, j]
            step = np.where(np.abs(d2) > 1e-300, d1 / np.where(d2 == 0, 1, d2), 0.0)
            cand = np.mod(cand - step / (2 * np.pi), 1.0)
        cand = np.concatenate([raw, cand])
        vals = g(cand, j)
        i = int(np.argmin(vals))
        mins[j], tmin[j] = vals[i], cand[i]
    return mins, tmin
