"""Tables and verdict of a sweep (the crack-network study or a given system): per
(realisation, load factor), per band of load factors, over realisations, and the one-paragraph
answer."""

from __future__ import annotations

import numpy as np
import pandas as pd

from ..model.numbers import sig

__all__ = ["summarise", "bands", "regions", "verdict", "lam_u", "shown_differ", "SAME_RTOL"]

#: ``W*`` min and max count as "the same" when they differ by at most this fraction of max:
#: runs that reach the same orbit agree to the steady-state tolerance (``tol = 1e-10`` relative
#: change per cycle) times the few hundred steps of the approach; measured spreads of runs on
#: one orbit are below 1e-8 (default study), so 1e-6 separates "same" from "different" orbits,
#: whose spreads are 1e-4 or more.
SAME_RTOL = 1e-6
_REGIONS = ("below lam_adj", "lam_adj to lam1", "lam1 to lam2", "lam2 to lam_u", "above lam_u")


def summarise(runs: pd.DataFrame, realisations: pd.DataFrame) -> pd.DataFrame:
    """One row per (realisation, point): min / max over the initial states."""
    runs = runs.assign(cyclic_slip=(runs["period"] > 0) & ~runs["shook_down"].astype(bool))
    g = runs.groupby(["realisation", "point"], sort=False)
    s = g.agg(
        lam=("lam", "first"), x=("x", "first"),
        W_star_min=("W_star", "min"), W_star_max=("W_star", "max"),
        n_states=("state", "size"), n_steady=("W_star", "count"),
        n_shook_down=("shook_down", "sum"), n_cyclic_slip=("cyclic_slip", "sum"),
        frac_slip_min=("frac_slip", "min"), frac_slip_max=("frac_slip", "max"),
        frac_open_min=("frac_open", "min"), frac_open_max=("frac_open", "max"),
    ).reset_index()
    s["all_slip"] = s["frac_slip_min"].to_numpy(float) >= 1.0
    idx = runs.loc[runs["W_star"].notna()].groupby(["realisation", "point"])["W_star"].idxmax()
    arg = runs.loc[idx, ["realisation", "point", "state_kind"]].rename(
        columns={"state_kind": "max_from"})
    s = s.merge(arg, on=["realisation", "point"], how="left")
    s = s.merge(realisations[["realisation", "lam1", "lam2", "lam_adj"]], on="realisation")
    for c in ("n_shook_down", "n_cyclic_slip"):
        s[c] = s[c].astype(int)
    s = s.sort_values(["realisation", "lam", "point"], kind="stable").reset_index(drop=True)
    s.insert(2, "lam_index", s.groupby("realisation").cumcount())
    return s


def lam_u(summary: pd.DataFrame) -> pd.DataFrame:
    """Per realisation: ``lam_u`` (smallest load factor of the study from which on every
    state's steady cycle has every crack slipping), the bracket's lower end ``lam_u_low`` (the
    largest load factor below it where some crack does not slip; nan if none) and ``lam_same``
    (smallest load factor from which on min and max ``W*`` agree to :data:`SAME_RTOL`)."""
    out = []
    for r, g in summary.groupby("realisation", sort=True):
        g = g.sort_values("lam", kind="stable")
        lam = g["lam"].to_numpy(float)
        ok = g["all_slip"].to_numpy(bool)
        tail = np.flip(np.logical_and.accumulate(np.flip(ok)))
        i = int(np.argmax(tail)) if tail.any() else len(lam)
        wmax = g["W_star_max"].to_numpy(float)
        same = np.abs(wmax - g["W_star_min"].to_numpy(float)) <= SAME_RTOL * np.abs(wmax)
        same &= wmax > 0
        st = np.flip(np.logical_and.accumulate(np.flip(same)))
        k = int(np.argmax(st)) if st.any() else len(lam)
        out.append(dict(realisation=int(r), lam_u=lam[i] if i < len(lam) else np.nan,
                        lam_u_low=lam[i - 1] if 0 < i <= len(lam) else np.nan,
                        lam_same=lam[k] if k < len(lam) else np.nan))
    return pd.DataFrame(out)


def regions(summary: pd.DataFrame, lamu: pd.DataFrame) -> pd.DataFrame:
    """Per realisation and band of load factors (below ``lam_adj``, ``lam_adj`` to ``lam1``,
    ``lam1`` to ``lam2``, ``lam2`` to ``lam_u``, above): points, runs, runs that ended in cyclic
    slip (a steady cycle in which some crack slips), min and max ``W*``."""
    s = summary.merge(lamu, on="realisation")
    lam, l1, l2 = s["lam"], s["lam1"], s["lam2"]
    adj = np.minimum(s["lam_adj"], l1)
    lu = s["lam_u"].fillna(np.inf)
    which = np.select([lam < adj, lam < l1, lam <= l2, lam < lu], list(_REGIONS[:4]),
                      default=_REGIONS[4])
    s = s.assign(region=which)
    g = s.groupby(["realisation", "region"], sort=False)
    t = g.agg(lam_low=("lam", "min"), lam_high=("lam", "max"), n_points=("lam", "size"),
              n_runs=("n_states", "sum"), n_cyclic_slip=("n_cyclic_slip", "sum"),
              W_star_min=("W_star_min", "min"), W_star_max=("W_star_max", "max")).reset_index()
    t["order"] = t["region"].map({r: i for i, r in enumerate(_REGIONS)})
    return t.sort_values(["realisation", "order"]).drop(columns="order").reset_index(drop=True)


def bands(summary: pd.DataFrame, confidence: float = 0.95) -> pd.DataFrame:
    """Per point (the same name in every realisation): mean, standard deviation and the
    Student-t ``confidence`` interval of the mean over realisations of min and max ``W*`` and of
    the slipping fractions; nan intervals with one realisation.  The lower end of a ``W*``
    interval is clipped at 0 (``W* >= 0``)."""
    from scipy.special import stdtrit  # the t quantile; scipy.stats is not needed for this

    out = []
    for point, g in summary.groupby("point", sort=False):
        row = dict(point=point, lam=float(g["lam"].mean()), x=float(g["x"].mean()),
                   n_realisations=len(g))
        for col in ("W_star_min", "W_star_max", "frac_slip_min", "frac_slip_max",
                    "frac_open_min", "frac_open_max"):
            x = g[col].to_numpy(float)
            x = x[np.isfinite(x)]
            m = x.mean() if x.size else np.nan
            sd = x.std(ddof=1) if x.size > 1 else np.nan
            half = stdtrit(x.size - 1, 0.5 + confidence / 2) * sd / np.sqrt(x.size) \
                if x.size > 1 else np.nan
            lo = m - half
            row.update({f"{col}_mean": m, f"{col}_std": sd,
                        f"{col}_lo": max(lo, 0.0) if col.startswith("W") else lo,
                        f"{col}_hi": m + half})
        out.append(row)
    return pd.DataFrame(out).sort_values("x", kind="stable").reset_index(drop=True)


def shown_differ(wmin, wmax, digits: int = 4) -> np.ndarray:
    """Min and max differ *as the tables print them* (``digits`` significant digits, the
    tolerance of the summary table and of the verdict that summarises it)."""
    return np.array([sig(a, digits) != sig(b, digits) for a, b in
                     zip(np.atleast_1d(wmin), np.atleast_1d(wmax), strict=True)], bool)


def _plural(k: int, word: str) -> str:
    return f"{k} {word}{'s' * (k != 1)}"


def verdict(spec, realisations: pd.DataFrame, summary: pd.DataFrame, lamu: pd.DataFrame,
            regs: pd.DataFrame) -> str:
    """The study's answer in one paragraph: the band where the initial state matters, the load
    factor above which the dissipation is the same from every initial state, and, per band,
    whether any initial state ended in cyclic slip.

    Numbers have 4 significant digits (:func:`~shakedown.model.numbers.sig`); "min and max
    differ" uses the same digits as the summary table, "the same from every initial state" the
    stricter :data:`SAME_RTOL`.
    """
    l1, l2 = realisations["lam1"].to_numpy(float), realisations["lam2"].to_numpy(float)
    la = realisations["lam_adj"].to_numpy(float)
    D = spec.dissipation_name
    unit = f" {spec.source.energy_unit}" if spec.source is not None else ""
    word = spec.node_word

    def stat(x, digits=4):
        x = x[np.isfinite(x)]
        if not x.size:
            return "nan"
        if x.size == 1:
            return sig(x[0], digits)
        return f"{sig(x.mean(), digits)} (range {sig(x.min(), digits)}-{sig(x.max(), digits)})"

    n_lams = int(summary["lam"].nunique()) if len(summary) else 0
    n_states = int(summary["n_states"].max()) if len(summary) else 0
    parts = [f"{spec.describe()[0].upper()}{spec.describe()[1:]}: "
             f"{_plural(n_lams, 'load factor')} x {_plural(n_states, 'initial state')}."]
    bounded = bool(np.isfinite(l1).any() and np.isfinite(l2).any())
    if bounded:
        band = summary[(summary["lam"] > summary["lam1"]) & (summary["lam"] <= summary["lam2"])]
        wb_min = band["W_star_min"].max() if len(band) else float("nan")
        wb_max = band["W_star_max"].max() if len(band) else float("nan")
        parts.append(
            f"By the bounds (computed, LP certificates), the initial state decides whether the "
            f"system shakes down for lam1 = {stat(l1)} < lam < lam2 = {stat(l2)} (lam1/lam2 = "
            f"{stat(l1 / l2, 3)}): there min {D} = {sig(wb_min)}{unit} and max {D} up to "
            f"{sig(wb_max)}{unit} ({_plural(len(band), 'load factor')} of this study).")
    else:
        status = ", ".join(sorted(set(realisations["bounds_status"].astype(str))))
        parts.append(f"The bounds are undefined for this model (status {status}; shakedown "
                     "bounds explains why), so no band of load factors comes from them.")

    def where(x, lam2):  # a load factor, and its ratio to lam2 when that is defined
        x = np.asarray(x, float)
        ratio = x / lam2
        return stat(x) + (f" (lam/lam2 = {stat(ratio, 3)})" if np.isfinite(ratio).any() else "")

    first, last = [], []
    for _, g in summary.groupby("realisation", sort=True):
        wmax, wmin = g["W_star_max"].to_numpy(float), g["W_star_min"].to_numpy(float)
        differ = shown_differ(wmin, wmax) & (wmax > 0)
        lam = g["lam"].to_numpy(float)
        if differ.any():
            first.append((lam[differ].min(), g["lam2"].iloc[0]))
            last.append((lam[differ].max(), g["lam2"].iloc[0]))
    if first:
        f, lf = np.array(first).T
        la_, ll = np.array(last).T
        parts.append(f"In this study min and max {D} differ in the table (4 significant digits: "
                     f"the initial state matters) from lam = {where(f, lf)} to "
                     f"{where(la_, ll)}.")
    sub = summary[summary["lam"] < summary["lam1"]]
    nslip, nruns = int(sub["n_cyclic_slip"].sum()), int(sub["n_states"].sum())
    below = regs[regs["region"] == "lam_adj to lam1"]
    seed = " (the seed: none)" if spec.source is None else ""
    if nruns:
        parts.append(f"Below lam1, {nslip} of {nruns} runs ended in cyclic slip{seed}"
                     + (f"; between lam_adj = {stat(la)} and lam1: "
                        f"{int(below['n_cyclic_slip'].sum())} of {int(below['n_runs'].sum())}"
                        if len(below) else "") + ".")
    lu, ls = lamu["lam_u"].to_numpy(float), lamu["lam_same"].to_numpy(float)
    if np.isfinite(lu).any():
        parts.append(f"Every {word} slips in every steady cycle from lam_u = {where(lu, l2)} on.")
    else:
        fix = ("raise lam_span" if spec.lams == "auto"
               else f"add load factors above {sig(max(spec.lams))} to lams")
        parts.append(f"No load factor of the study made every {word} slip in every steady "
                     f"cycle (lam_u not reached: {fix}).")
    if np.isfinite(ls).any():
        parts.append(f"The dissipation is the same from every initial state (to {SAME_RTOL:g} "
                     f"relative) for lam >= {where(ls, l2)}.")
    else:
        top = summary.sort_values("lam", kind="stable").groupby("realisation").tail(1)
        wmin, wmax = top["W_star_min"].to_numpy(float), top["W_star_max"].to_numpy(float)
        if len(top) and np.all(wmax == 0):
            parts.append("At the largest load factor of the study every initial state shook "
                         f"down ({D} = 0).")
        elif len(top) and not shown_differ(wmin, wmax).any():
            parts.append(f"At the largest load factor of the study min and max {D} agree to 4 "
                         f"significant digits but not to {SAME_RTOL:g} relative.")
        else:
            parts.append(f"Min and max {D} still differ at the largest load factor of the "
                         "study.")
    return " ".join(parts)
