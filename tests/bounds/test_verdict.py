"""The bounds verdict (issue 9): the answer first, in words, numbers rounded for reading.

References: a single node with ``B = 0`` has ``lam1 = lam2 = f p0 / |q1|`` (frictional
Melan theorem; the example of ``shakedown_bounds``'s docstring gives 1); the coupled two-node
system of seed 002 Fig. 4 (README); the 3-node system of the gallery with ``lam_adj < lam1``.
"""

import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

import shakedown as sd
from shakedown.bounds.verdict import bounds_verdict, constraint_name, fmt

COUPLED = dict(A=[[1.0, -0.3], [-0.3, 1.0]], B=[[-0.3, 0.9], [0.4, -0.1]],
               C=[[1.5, 0.2], [0.2, 1.5]])
LOAD = dict(q0=[0.1, -0.1], p0=[1.0, 1.0], q_cos=[0.5, 0.0], q_sin=[0.0, 0.5], p_cos=[0.0, 0.3])


def coupled(friction=0.7, **load):
    return (sd.DiscreteSystem(**COUPLED, friction=friction),
            sd.LoadCycle.from_harmonics(**{**LOAD, **load}))


def test_fmt_rounds_for_reading():
    assert fmt(0.47509366570983763) == "0.4751"
    assert fmt(1.2912701712398393) == "1.291"
    assert fmt(2.6498) == "2.650" and fmt(1.0) == "1.000"  # trailing zeros kept (issue 25)
    assert (fmt(np.inf), fmt(np.nan), fmt(-np.inf)) == ("inf", "nan", "-inf")
    assert constraint_name(0, 2) == "I_1" and constraint_name(3, 2) == "II_2"


@pytest.mark.parametrize("f, p0, q0, amp", [(0.5, 2.0, 0.0, 1.0), (0.3, 5.0, 0.4, 2.0)])
def test_single_node_melan_reference(f, p0, q0, amp):
    s = sd.DiscreteSystem([[1.0]], [[0.0]], [[1.0]], friction=f)
    b = sd.shakedown_bounds(s, sd.LoadCycle.from_harmonics([q0], [p0], q_cos=[amp]))
    # closed form for B = 0: a residual slip absorbs q0, so the safe range is the whole cone
    # width 2 f p0 against the cyclic swing 2 lam |q1|
    lam = f * p0 / amp
    v = bounds_verdict(b, adjacency=True)
    assert v.startswith(f"Shakes down from every initial state for lam < lam1 = lam2 = {fmt(lam)} "
                        "(proved for one or two nodes);")
    assert "never above" in v and "initial state never decides" in v


def test_coupled_two_nodes_states_the_band_where_the_initial_state_decides():
    b = sd.shakedown_bounds(*coupled(), adjacency=True)
    v = b.verdict()
    first = f"Shakes down from every initial state for lam < lam1 = {fmt(b.lam1)}"
    band = f"from some initial states only for {fmt(b.lam1)} < lam < lam2 = {fmt(b.lam2)}"
    assert v.startswith(first) and band in v and "never above lam2" in v
    assert repr(b.lam1) not in v  # 4 significant digits, not 17
    # lam_adj agrees with lam1 to the LP tolerance here: said in words, not as a second number
    assert abs(b.lam_adj - b.lam1) <= 1e-7 * b.lam1
    assert f"lam_adj = lam1 (node {b.adjacency_node + 1})" in v


def test_lam_adj_below_lam1_weakens_the_claim():
    p = sd.gallery.get("three_node_below_lam1")
    b = sd.shakedown_bounds(p.system, p.load, adjacency=True)
    assert b.lam_adj < b.lam1
    v = bounds_verdict(b, adjacency=True)
    # no longer claims "every initial state" up to lam1
    assert not v.startswith("Shakes down from every initial state for lam < lam1")
    node = b.adjacency_node + 1
    assert f"I_{node}, II_{node}" in v and "slip cyclically" in v


def test_tensile_static_load_is_named_and_explained():
    b = sd.shakedown_bounds(*coupled(friction=0.5, p0=[-1.0, 1.0]))
    assert b.status == "infeasible" and np.isnan(b.lam1)
    v = b.verdict()
    assert "undefined (nan)" in v and "tensile" in v and "node 1" in v and "separate" in v


def test_static_load_says_why_lam2_is_infinite():
    s, _ = coupled()
    b = sd.shakedown_bounds(s, sd.LoadCycle.static([0.1, -0.1], [1.0, 1.0]))
    assert "no periodic part" in b.verdict() and "lam2 = inf" in b.verdict()


def test_lam_adj_inf_is_explained_only_when_it_was_computed():
    b = sd.shakedown_bounds(*coupled(), adjacency=False)
    assert np.isnan(b.lam_adj)  # not computed
    assert "lam_adj" not in bounds_verdict(b, adjacency=False)  # two nodes: nothing to add


def test_uncomputed_lam_adj_is_a_caution_for_three_coupled_nodes():
    # the 3-node system of README 'Findings' (cyclic slip between lam_adj and lam1): without
    # lam_adj the verdict must not claim more than is proven
    p = sd.gallery.get("three_node_below_lam1")
    v = sd.shakedown_bounds(p.system, p.load).verdict()
    assert "lam_adj was not computed" in v and "certain only below lam_adj" in v


@settings(max_examples=20, deadline=None)
@given(exponent=st.floats(-6.0, 12.0),
       case=st.sampled_from(["coupled", "tensile", "slightly_tensile", "three"]))
@example(exponent=-6.0, case="slightly_tensile").via("the smallest units: tension of 1e-13")
@example(exponent=12.0, case="three").via("the largest units")
def test_verdict_does_not_depend_on_units(exponent, case):
    """Forces and stiffness in other units (the same factor on both: slips unchanged)."""
    if case == "three":
        p = sd.gallery.get("three_node_below_lam1")
        s, load = p.system, p.load
    else:
        # "slightly": p0 = -1e-7 of the load is still tension, in any units
        p0 = {"tensile": [-1.0, 1.0], "slightly_tensile": [-1e-7, 1.0]}.get(case, [1.0, 1.0])
        s, load = coupled(friction=0.5, p0=p0)
    k = 1.37 * 10.0 ** exponent
    scaled = sd.DiscreteSystem(k * s.A, k * s.B, k * s.C, s.friction)
    ref = bounds_verdict(sd.shakedown_bounds(s, load), adjacency=True)
    assert ("tensile" in ref) == (case in ("tensile", "slightly_tensile"))
    assert bounds_verdict(sd.shakedown_bounds(scaled, load.scaled(k)), adjacency=True) == ref
