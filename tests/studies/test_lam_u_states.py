"""The study's all-slip criterion behind ``lam_u`` takes the *smallest* fraction of slipping
cracks over the initial states (issue 24: a test gap; with the largest fraction, a load factor
at which one state slips everywhere and another does not would count as "all slip")."""

import numpy as np
import pandas as pd

from shakedown.studies.summary import lam_u, regions, summarise


def runs_with_states_that_differ():
    """Two realisations, three load factors, three initial states each; at the middle load
    factor the states reach steady cycles with different fractions of slipping cracks."""
    rows = []
    frac = {0: [[0.25, 0.5, 0.5], [1.0, 0.75, 1.0], [1.0, 1.0, 1.0]],
            1: [[0.5, 0.5, 0.5], [1.0, 1.0, 1.0], [1.0, 1.0, 1.0]]}
    for r in (0, 1):
        for point, lam in enumerate((1.0, 2.0, 3.0)):
            for state in range(3):
                f = frac[r][point][state]
                rows.append(dict(realisation=r, point=point, lam=lam, x=lam / 1.5, state=state,
                                 state_kind=["zero", "safe", "random"][state],
                                 W_star=lam * (1 + 0.1 * state), shook_down=False, period=1,
                                 frac_slip=f, frac_open=0.0))
    real = pd.DataFrame(dict(realisation=[0, 1], lam1=[0.8, 0.8], lam2=[1.5, 1.5],
                             lam_adj=[0.5, 0.5]))
    return pd.DataFrame(rows), real


def test_lam_u_needs_every_state_slipping_everywhere():
    runs, real = runs_with_states_that_differ()
    s = summarise(runs, real)
    # at lam = 2 realisation 0 has one state with 75 % of its cracks slipping: not all slip
    assert s.loc[(s.realisation == 0) & (s.lam == 2.0), "all_slip"].tolist() == [False]
    assert s.loc[(s.realisation == 1) & (s.lam == 2.0), "all_slip"].tolist() == [True]
    lu = lam_u(s).set_index("realisation")
    assert (lu.loc[0, "lam_u"], lu.loc[0, "lam_u_low"]) == (3.0, 2.0)
    assert lu.loc[1, "lam_u"] == 2.0 and lu.loc[1, "lam_u_low"] == 1.0
    # the bands follow: realisation 0's point at lam = 2 lies below lam_u
    reg = regions(s, lam_u(s))
    r0 = reg[(reg.realisation == 0) & (reg.region == "lam2 to lam_u")]
    assert int(r0["n_points"].sum()) == 1 and float(r0["lam_low"].min()) == 2.0
    assert np.isnan(lu.loc[0, "lam_same"]) or lu.loc[0, "lam_same"] >= 1.0
