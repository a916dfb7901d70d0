"""Half-space contact (issue 23): Cattaneo-Mindlin, Mindlin-Deresiewicz, rotating loads, uniqueness.

Run:  OPENBLAS_NUM_THREADS=1 PYTHONPATH=. python benchmarks/bench_half_space_mindlin.py PART
      PART in {cm, md, cubic, rotating, uniqueness}; prints markdown tables (copied into
      benchmarks/RESULTS_half_space.md) and writes benchmarks/half_space_PART.json.

Problem: sphere R = 1 on a flat, E1 = E2 = 1, P = 1e-3, f = 0.5, window 2.4 a (the contact
diameter spans 2n/2.4 cells); nu = 0 (Mindlin exact) unless stated.  3-D steps by the cone
engine (``ConeStepSolver``, ``solve_cycles`` for dim = 3) on the dense condensed stiffness.
"""

from __future__ import annotations

import argparse
import json
import os
import time
from pathlib import Path

import numpy as np

import shakedown as sd
from shakedown.models.half_space import continuum as cont
from shakedown.studies import half_space as hs

E, R, P, F = 1.0, 1.0, 1e-3, 0.5
HERE = Path(__file__).resolve().parent


def setup(n, nu=0.0, mats=None):
    mats = mats or ((E, nu), (E, nu))
    m = sd.half_space_model(radius=R, n_cells=n, width=2.4 * _a(m_star(mats)), friction=F,
                            materials=mats)
    return m, _a(m.e_star), cont.tangential_compliance_constant(mats)


def m_star(mats):
    from shakedown.models.half_space.influence import material_constants
    return material_constants(mats)[0]


def _a(e_star):
    return float(cont.hertz_radius(P, R, e_star))


def part_cm(ns, nus=(0.0, 0.3)):
    rows = []
    print("| nu | n | 2a/h | Q/fP | c_moment/c - 1 | c_area/c - 1 | delta/Mindlin - 1 "
          "| max abs(q_y)/(f p0 h^2) | time [s] |")
    print("|---|---|---|---|---|---|---|---|---|")
    for nu in nus:
        for n in ns:
            m, a, ct = setup(n, nu)
            p0 = float(cont.hertz_peak_pressure(P, R, m.e_star))
            for X in (0.3, 0.6, 0.9):
                t0 = time.perf_counter()
                res, qf, pf = hs.static_path(m, [(0, 0, P), (X * F * P, 0, P)], substeps=4)[-1]
                dt = time.perf_counter() - t0
                c = float(cont.cattaneo_mindlin_radius(X * F * P, P, F, a))
                row = dict(nu=nu, n=n, X=X, c_mom=float(hs.stick_radius(m, qf, pf, X * F * P, P) / c - 1),
                           c_area=float(hs.stuck_area_radius(m, res) / c - 1),
                           delta=float(hs.tangential_displacement(m, qf, pf)[0]
                                       / cont.mindlin_displacement(X * F * P, P, F, a, ct) - 1),
                           qy=float(np.abs(qf[:, 1]).max() / (F * p0 * m.h**2)), time=dt)
                rows.append(row)
                print(f"| {nu} | {n} | {2 * a / m.h:.1f} | {X} | {row['c_mom']:+.2e} | {row['c_area']:+.2e} "
                      f"| {row['delta']:+.2e} | {row['qy']:.2e} | {dt:.1f} |")
    return rows


def part_md(ns, X=0.5, steps=40):
    rows = []
    print("| n | 2a/h | W/W_MD - 1 | W_loop/W_MD - 1 | cycles to steady | time [s] |")
    print("|---|---|---|---|---|---|")
    for n in ns:
        m, a, ct = setup(n)
        t0 = time.perf_counter()
        run, loop = hs.fretting_run(m, P, X * F * P, steps_per_cycle=steps, max_cycles=6)
        dt = time.perf_counter() - t0
        W = float(cont.mindlin_deresiewicz_dissipation(X * F * P, P, F, a, ct))
        rows.append(dict(n=n, W=run.steady_dissipation / W - 1, W_loop=loop["W_loop"] / W - 1,
                         cycles=run.cycles_to_steady, time=dt))
        print(f"| {n} | {2 * a / m.h:.1f} | {rows[-1]['W']:+.2e} | {rows[-1]['W_loop']:+.2e} | "
              f"{run.cycles_to_steady} | {dt:.1f} |")
    return rows


def part_cubic(n, Xs=(0.025, 0.05, 0.1, 0.2, 0.4, 0.8), steps=40):
    m, a, ct = setup(n)
    rows = []
    print("| Q*/fP | W | W_MD | W/W_MD - 1 | cubic law W_3 | W/W_3 |")
    print("|---|---|---|---|---|---|")
    for X in Xs:
        run, loop = hs.fretting_run(m, P, X * F * P, steps_per_cycle=steps, max_cycles=6)
        W = run.steady_dissipation
        Wmd = float(cont.mindlin_deresiewicz_dissipation(X * F * P, P, F, a, ct))
        W3 = float(cont.mindlin_cubic_dissipation(X * F * P, P, F, a, ct))
        rows.append(dict(X=X, W=W, W_md=Wmd, W3=W3))
        print(f"| {X} | {W:.4e} | {Wmd:.4e} | {W / Wmd - 1:+.2e} | {W3:.4e} | {W / W3:.3f} |")
    x = np.log([r["X"] for r in rows[:3]])
    print(f"log-log slope of W over the three smallest amplitudes: "
          f"{np.polyfit(x, np.log([r['W'] for r in rows[:3]]), 1)[0]:.3f}")
    return rows


def part_rotating(n, X=0.5, steps=80, nu=0.0):
    m, a, ct = setup(n, nu)
    rows = []
    print("| load | Qx/fP | Qy/fP | W | W / W_unidirectional | cycles to steady | state change per cycle |")
    print("|---|---|---|---|---|---|---|")
    ref = None
    for name, qx, qy in (("oscillating", X, 0.0), ("elliptical 2:1", X, X / 2), ("rotating", X, X)):
        run, loop = hs.fretting_run(m, P, qx * F * P, qy * F * P, steps_per_cycle=steps,
                                    max_cycles=8)
        W = run.steady_dissipation
        ref = W if ref is None else ref
        rows.append(dict(load=name, W=W, ratio=W / ref, cycles=run.cycles_to_steady,
                         change=[float(c) for c in run.state_change], W_cycles=run.dissipation.tolist()))
        print(f"| {name} | {qx} | {qy} | {W:.4e} | {W / ref:.4f} | {run.cycles_to_steady} | "
              f"{', '.join(f'{c:.1e}' for c in run.state_change)} |")
    return rows


def _paths(X, P0, rng, k):
    """Initial loading paths OA ending at (Q_x, Q_y, P) = (X f P0, 0, P0)."""
    out = [[(0.0, 0.0, P0), (X * F * P0, 0.0, P0)]]  # Mindlin: P first, then Q
    out.append([(X * F * P0, 0.0, P0)])  # P and Q proportionally
    for _ in range(k - 2):
        Ps = rng.uniform(0.3, 1.6, 2) * P0
        ang = rng.uniform(0, 2 * np.pi, 2)
        amp = rng.uniform(0, 0.9, 2) * F * Ps
        pts = [(amp[j] * np.cos(ang[j]), amp[j] * np.sin(ang[j]), Ps[j]) for j in range(2)]
        out.append(pts + [(X * F * P0, 0.0, P0)])
    return out


def part_uniqueness(n, X=0.5, k=6, seed=0, steps=40):
    """Cycles from k initial loading paths; W of the last cycle, tractions of the last orbit."""
    rng = np.random.default_rng(seed)
    rows = []
    print("| materials | beta | load | paths | all steady | W spread / W | spread of q - mean_t q "
          "/ (f p0 h^2) | spread of q / (f p0 h^2) | stuck sets equal (sizes) |")
    print("|---|---|---|---|---|---|---|---|---|")
    for label, mats in (("similar", ((E, 0.3), (E, 0.3))),
                        ("rigid on nu=0.3", ((E, 0.3), (np.inf, 0.0)))):
        m = sd.half_space_model(radius=R, n_cells=n, width=2.4 * _a(m_star(mats)), friction=F,
                                materials=mats)
        p0 = float(cont.hertz_peak_pressure(P, R, m.e_star))
        for lname, qy in (("oscillating", 0.0), ("rotating", X)):
            Ws, qs, stuck, steady = [], [], [], []
            for path in _paths(X, P, rng, k):
                res = hs.static_path(m, path, substeps=4)[-1][0]
                run, loop = hs.fretting_run(m, P, X * F * P, qy * F * P, steps_per_cycle=steps,
                                            max_cycles=25, initial_slip=res.slip,
                                            initial_gap=res.gap, tol=1e-7)
                Ws.append(run.dissipation[-1])
                qs.append(loop["q_full"])
                stuck.append(tuple(sorted(run.stuck_nodes.tolist())))
                steady.append(run.status == "periodic")
            Ws = np.array(Ws)
            qa = np.array(qs)
            spread = float(np.ptp(Ws) / np.mean(Ws))
            qsp = float(np.max(np.ptp(qa, axis=0)) / (F * p0 * m.h**2))
            qvar = qa - qa.mean(axis=1, keepdims=True)
            qvsp = float(np.max(np.ptp(qvar, axis=0)) / (F * p0 * m.h**2))
            same = all(s == stuck[0] for s in stuck)
            rows.append(dict(materials=label, beta=m.beta, load=lname, W=Ws.tolist(), W_spread=spread,
                             q_spread=qsp, q_var_spread=qvsp, stuck_equal=same, steady=steady,
                             n_stuck=[len(s) for s in stuck]))
            print(f"| {label} | {m.beta:.3f} | {lname} | {k} | {all(steady)} | {spread:.1e} | {qvsp:.1e} "
                  f"| {qsp:.1e} | {same} ({', '.join(str(len(s)) for s in stuck)}) |")
    return rows


def part_pq(n, steps=40):
    """P and Q varying together: P = P0 + 0.3 P0 cos(2 pi t + 0.6), Q_x = 0.3 f P0 cos 2 pi t."""
    rows = []
    print("| materials | beta | status | cycles to steady | W of the last 3 cycles | reference cell margin |")
    print("|---|---|---|---|---|---|")
    for label, mats in (("similar", ((E, 0.3), (E, 0.3))),
                        ("rigid on nu=0.3", ((E, 0.3), (np.inf, 0.0)))):
        a = _a(m_star(((E, 0.3), (E, 0.3))))
        m = sd.half_space_model(radius=R, n_cells=n, width=2.4 * 1.3 ** (1 / 3) * a, friction=F,
                                materials=mats)
        load = m.load_cycle(P0=P, P1=0.3 * P, Qx=0.3 * F * P, phase=0.6)
        run = sd.solve_cycles(m.system, load, 1.0, steps_per_cycle=steps, max_cycles=30, tol=1e-8)
        Pt = lambda t: P + 0.3 * P * np.cos(2 * np.pi * t + 0.6)  # noqa: E731
        t, qf, pf, _, Q = hs.run_arrays(m, run, Pt, lambda t: 0.3 * F * P * np.cos(2 * np.pi * t),
                                        lambda t: 0 * t)
        ok, worst = m.check_reference(qf[:, m.keep], pf[:, m.keep], Q[:, 0], Q[:, 1], Pt(t))
        rows.append(dict(materials=label, beta=m.beta, status=run.status, cycles=run.cycles_to_steady,
                         W=run.dissipation.tolist(), reference_ok=ok, margin=worst))
        print(f"| {label} | {m.beta:.3f} | {run.status} | {run.cycles_to_steady} | "
              f"{', '.join(f'{w:.6e}' for w in run.dissipation[-3:])} | "
              f"{worst:.1e} ({'ok' if ok else 'FAILS'}) |")
    return rows


#: Named initial loading paths OA (points (Q_x, Q_y, P) in units of (f P0, f P0, P0)), each
#: ending where the cycle starts, (X, 0, 1): :func:`named_paths`.
def named_paths(X, P0):
    """Initial loading paths OA, by name, ending at ``(Q_x, Q_y, P) = (X f P0, 0, P0)``."""
    fP = F * P0
    end = (X * fP, 0.0, P0)
    return {
        "P then Qx (Mindlin)": [(0.0, 0.0, P0), end],
        "P then Qy, then Qx": [(0.0, 0.0, P0), (0.0, X * fP, P0), end],
        "P and Q together": [end],
        "Qx overshoot 0.9 and back": [(0.0, 0.0, P0), (0.9 * fP, 0.0, P0), end],
        "Qx to -0.9, then back": [(0.0, 0.0, P0), (-0.9 * fP, 0.0, P0), end],
        "Qy to -0.9, then back": [(0.0, 0.0, P0), (0.0, -0.9 * fP, P0), end],
        "P to 1.6 with Q, then down": [(0.0, 0.0, 1.6 * P0), (0.5 * fP, 0.5 * fP, 1.6 * P0), end],
        "P to 0.4, Q around, then up": [(0.0, 0.0, 0.4 * P0), (0.0, 0.3 * fP, 0.4 * P0),
                                        (-0.3 * fP, 0.0, 0.4 * P0), end],
    }


MATERIALS = {
    "similar (nu = 0.3)": ((E, 0.3), (E, 0.3)),
    "steel on aluminium": ((210e3, 0.3), (70e3, 0.33)),
    "rigid on nu = 0.3": ((E, 0.3), (np.inf, 0.0)),
}


def part_paths(n, X=0.5, steps=40, max_cycles=400, tol=1e-8, mats=None, out_png=None):
    """Cycles from the named initial loading paths; steady W, tractions, permanently stuck cells.

    ``P = P0`` constant, ``Q = X f P0 (cos 2 pi t, k sin 2 pi t)``, ``k = 0`` (oscillating) or 1
    (rotating).  Per case: the relative spread of the steady ``W``, the spread of the tractions
    at the same instants (whole, time-varying part, pressure; per cell, over ``f p0 h^2``), the
    permanently stuck cells shared by every path and those that differ.
    """
    rows, zones = [], []
    print("| materials | beta | load | paths steady | cycles (max) | last state change (max) | W (mean) "
          "| W spread / W | q - mean_t q spread | q spread | p spread | stuck cells: common / differing |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    for label in mats or MATERIALS:
        mt = MATERIALS[label]
        P0 = P * mt[0][0] / E  # P scaled with body 1's modulus: the same a / R for every pair
        a = float(cont.hertz_radius(P0, R, m_star(mt)))
        m = sd.half_space_model(radius=R, n_cells=n, width=2.4 * a, friction=F, materials=mt)
        p0 = float(cont.hertz_peak_pressure(P0, R, m.e_star))
        scale = F * p0 * m.h**2
        for lname, qy in (("oscillating", 0.0), ("rotating", X)):
            runs = []
            for pname, path in named_paths(X, P0).items():
                t0 = time.process_time()
                res = hs.static_path(m, path, substeps=4)[-1][0]
                run, loop = hs.fretting_run(m, P0, X * F * P0, qy * F * P0, steps_per_cycle=steps,
                                            max_cycles=max_cycles, initial_slip=res.slip,
                                            initial_gap=res.gap, tol=tol)
                cells = np.r_[m.keep[np.asarray(run.stuck_nodes, int)], m.reference]
                runs.append(dict(path=pname, W=float(run.dissipation[-1]), status=run.status,
                                 cycles=int(len(run.dissipation)),
                                 last_change=float(run.state_change[-1]),
                                 stuck=sorted(int(c) for c in cells), q=loop["q_full"],
                                 p=loop["p_full"], cpu=time.process_time() - t0))
            Ws = np.array([r["W"] for r in runs])
            qa = np.array([r["q"] for r in runs])
            pa = np.array([r["p"] for r in runs])
            qvar = qa - qa.mean(axis=1, keepdims=True)
            sets = [set(r["stuck"]) for r in runs]
            common = set.intersection(*sets)
            differ = set.union(*sets) - common
            row = dict(materials=label, beta=float(m.beta), load=lname, n=n, P0=P0, a=a, h=m.h,
                       W=Ws.tolist(), W_spread=float(np.ptp(Ws) / np.mean(Ws)),
                       q_spread=float(np.max(np.ptp(qa, axis=0)) / scale),
                       q_var_spread=float(np.max(np.ptp(qvar, axis=0)) / scale),
                       p_spread=float(np.max(np.ptp(pa, axis=0)) / (p0 * m.h**2)),
                       n_common=len(common), differing=sorted(differ),
                       n_stuck=[len(s) for s in sets],
                       paths=[{k: v for k, v in r.items() if k not in ("q", "p")} for r in runs])
            rows.append(row)
            zones.append((m, a, label, lname, runs))
            nst = sum(r["status"] == "periodic" for r in runs)
            print(f"| {label} | {m.beta:.3f} | {lname} | {nst}/{len(runs)} | "
                  f"{max(r['cycles'] for r in runs)} | {max(r['last_change'] for r in runs):.1e} | "
                  f"{np.mean(Ws):.4e} | {row['W_spread']:.1e} | {row['q_var_spread']:.1e} | "
                  f"{row['q_spread']:.1e} | {row['p_spread']:.1e} | {len(common)} / {len(differ)} |",
                  flush=True)
    if out_png:
        _zones_figure(zones, out_png)
    return rows


def _zones_figure(zones, out_png):
    """One row per (materials, load), one panel per path: the permanently stuck cells; "not
    common" counts the cells that differ from those stuck in every steady run."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from shakedown.plotting import half_space as ph

    k = len(zones[0][4])
    fig, axs = plt.subplots(len(zones), k, figsize=(2.3 * k, 2.5 * len(zones)), squeeze=False)
    for i, (m, a, label, lname, runs) in enumerate(zones):
        steady = [set(r["stuck"]) for r in runs if r["status"] == "periodic"]
        common = set.intersection(*steady) if steady else set()
        for j, r in enumerate(runs):
            ax = axs[i, j]
            if r["status"] == "periodic":
                note = f"{len(r['stuck'])} cells, {len(set(r['stuck']) ^ common)} not common"
            else:
                note = f"NOT STEADY after {r['cycles']} cycles (change {r['last_change']:.0e})"
            ph.plot_stuck_zone(m, r["stuck"], a=a, zoom=1.1 * a, ax=ax,
                               title=f"{r['path']}\n{note}")
            ax.title.set_fontsize(6.5)
            ax.legend().remove()
            ax.set_xlabel("x [length]" if i == len(zones) - 1 else "", fontsize=7)
            ax.set_ylabel(f"{label}, {lname}\ny [length]" if j == 0 else "", fontsize=7)
            ax.tick_params(labelsize=5, labelbottom=i == len(zones) - 1, labelleft=j == 0)
    fig.suptitle("permanently stuck cells (blue) of the steady cycle after each initial loading "
                 "path (dashed: Hertz a); rows: materials (beta), oscillating / rotating Q",
                 fontsize=9)
    fig.tight_layout()
    fig.savefig(out_png, dpi=110)


def replot(json_path, out_png, n=16):
    """The stick-zone figure again from a ``paths`` JSON (models rebuilt, no runs)."""
    rows = json.loads(Path(json_path).read_text())
    zones = []
    for r in rows:
        mt = MATERIALS[r["materials"]]
        a = float(cont.hertz_radius(r["P0"], R, m_star(mt)))
        m = sd.half_space_model(radius=R, n_cells=r.get("n", n), width=2.4 * a, friction=F,
                                materials=mt)
        zones.append((m, a, f"{r['materials']} (beta {r['beta']:.2f})", r["load"], r["paths"]))
    _zones_figure(zones, out_png)

if __name__ == "__main__":
    ap = argparse.ArgumentParser()
    ap.add_argument("part", choices=["cm", "md", "cubic", "rotating", "uniqueness", "pq", "paths"])
    ap.add_argument("--mats", nargs="*", default=None, choices=list(MATERIALS))
    ap.add_argument("--max-cycles", type=int, default=400)
    ap.add_argument("--replot", action="store_true", help="paths: redraw the figure from the JSON")
    ap.add_argument("--ns", type=int, nargs="*", default=[11, 15, 21, 31])
    ap.add_argument("--n", type=int, default=21)
    a = ap.parse_args()
    print(f"# OPENBLAS_NUM_THREADS={os.environ.get('OPENBLAS_NUM_THREADS')}; load {os.getloadavg()}")
    t0 = time.perf_counter()
    if a.replot:
        replot(HERE / "half_space_paths.json", HERE / "half_space_uniqueness_zones.png", a.n)
        raise SystemExit(0)
    out = {"cm": lambda: part_cm(a.ns), "md": lambda: part_md(a.ns), "cubic": lambda: part_cubic(a.n),
           "rotating": lambda: part_rotating(a.n), "uniqueness": lambda: part_uniqueness(a.n),
           "pq": lambda: part_pq(a.n),
           "paths": lambda: part_paths(a.n, max_cycles=a.max_cycles, mats=a.mats,
                                       out_png=HERE / "half_space_uniqueness_zones.png")}[a.part]()
    print(f"# total {time.perf_counter() - t0:.0f} s")
    (HERE / f"half_space_{a.part}.json").write_text(json.dumps(out, indent=1, default=float))
