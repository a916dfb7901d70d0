"""The pictures of issue 23 read from their artists: maps of the contact surface (stick, slip,
open, traction arrows), the permanently stuck zone against the continuum prediction, the
``Q_x``-``Q_y`` path, the force-displacement loops (half-space and a 3-D patch), and the
dissipation against amplitude on log-log axes with the cubic law."""

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402
from figure_checks import check_legend_matches_drawn, check_units, legend_entries, visible  # noqa: E402
from matplotlib.colors import to_rgba  # noqa: E402

import shakedown as sd  # noqa: E402
from shakedown.models.half_space import continuum as cont  # noqa: E402
from shakedown.plotting import contact_patch as cp  # noqa: E402
from shakedown.plotting import half_space as ph  # noqa: E402
from shakedown.studies import half_space as hs  # noqa: E402

P, F, X = 1e-3, 0.5, 0.6
MATS = ((1.0, 0.0), (1.0, 0.0))


@pytest.fixture(autouse=True)
def _close():
    yield
    plt.close("all")


@pytest.fixture(scope="module")
def fretting():
    """A 9 x 9 sphere on a flat (nu = 0: Mindlin exact), steady cycle at Q* = 0.6 f P."""
    a = float(cont.hertz_radius(P, 1.0, 0.5))
    m = sd.half_space_model(radius=1.0, n_cells=9, width=2.4 * a, friction=F, materials=MATS)
    run, loop = hs.fretting_run(m, P, X * F * P, steps_per_cycle=16, max_cycles=3)
    return m, a, run, loop


def test_contact_map_legend_colours_arrows_and_circles(fretting):
    m, a, _, loop = fretting
    k = int(np.argmax([np.count_nonzero(np.asarray(st) == "slip") for st in loop["states"]]))
    assert "slip" in set(loop["states"][k]) and "stick" in set(loop["states"][k])
    c = float(cont.cattaneo_mindlin_radius(X * F * P, P, F, a))
    ax = ph.plot_contact_map(m, loop["q_full"][k], loop["p_full"][k], loop["states"][k], a=a, c=c)
    check_units(ax)
    # each state of the legend has its colour in the map; the circles are drawn and visible
    img = ax.images[0]
    colours = {tuple(np.round(img.cmap(img.norm(v)), 3)) for v in np.unique(img.get_array())}
    leg = ax.get_legend()
    for text, handle in zip(leg.get_texts(), leg.legend_handles, strict=True):
        lab = text.get_text()
        if lab in ("stick", "slip"):
            assert tuple(np.round(to_rgba(handle.get_facecolor()), 3)) in colours, lab
    lines = {ln.get_label(): ln for ln in ax.lines}
    assert set(lines) == {f"Hertz a = {a:.3g}", f"continuum c = {c:.3g}"}
    assert all(visible(ln, ax) for ln in lines.values())
    # one arrow per cell in contact (stick or slip), none on open cells
    arrows = ax.collections[0]
    st = np.asarray(loop["states"][k]).astype(str)
    assert len(arrows.get_offsets()) == int(np.count_nonzero(st != "separation")) > 0
    assert {"stick", "slip", "open"} <= set(legend_entries(ax))


def test_stuck_zone_against_the_continuum_prediction(fretting):
    m, a, run, _ = fretting
    cells = np.r_[m.keep[np.asarray(run.stuck_nodes, int)], m.reference]
    c = float(cont.cattaneo_mindlin_radius(X * F * P, P, F, a))
    ax = ph.plot_stuck_zone(m, cells, a=a, c_pred=c)
    check_legend_matches_drawn(ax)
    check_units(ax)
    assert int(np.count_nonzero(ax.images[0].get_array() == 1)) == len(cells)
    assert str(len(cells)) in ax.get_title()


def test_force_displacement_loop_and_load_path(fretting):
    m, a, run, loop = fretting
    fig, axs = plt.subplots(1, 2)
    ref = cont.mindlin_deresiewicz_loop(X * F * P, P, F, a, cont.tangential_compliance_constant(MATS))
    ph.plot_hysteresis(loop["Q"], loop["delta"], reference=ref, ax=axs[0])
    ph.plot_load_path(loop["Q"], friction_P=F * P, ax=axs[1])
    for ax in axs:
        check_legend_matches_drawn(ax)
        check_units(ax)
    # the drawn loop encloses the dissipation per cycle (closed integral Q d delta)
    x, y = axs[0].lines[0].get_xdata(), axs[0].lines[0].get_ydata()
    area = float(np.sum(0.5 * (y[1:] + y[:-1]) * np.diff(x)))
    assert area == pytest.approx(run.steady_dissipation, rel=0.05)


def test_dissipation_against_amplitude_is_log_log_with_the_cubic_law():
    a = float(cont.hertz_radius(P, 1.0, 0.5))
    ct = cont.tangential_compliance_constant(MATS)
    amps = np.array([0.05, 0.1, 0.2, 0.4])
    Ws = np.array([cont.mindlin_deresiewicz_dissipation(x * F * P, P, F, a, ct) for x in amps])
    Ws[0] = 0.0  # no cell slipped at the smallest amplitude: left out, not drawn at log(0)
    ax = ph.plot_dissipation_amplitude(
        amps, Ws, W_exact=lambda x: cont.mindlin_deresiewicz_dissipation(x * F * P, P, F, a, ct),
        W_cubic=lambda x: cont.mindlin_cubic_dissipation(x * F * P, P, F, a, ct))
    assert ax.get_xscale() == ax.get_yscale() == "log"
    check_legend_matches_drawn(ax)
    check_units(ax)
    assert len(ax.lines[0].get_xdata()) == 3
    cubic = next(ln for ln in ax.lines if "cubic" in ln.get_label())
    x, y = np.log(cubic.get_xdata()), np.log(cubic.get_ydata())
    assert np.polyfit(x, y, 1)[0] == pytest.approx(3.0, abs=1e-9)


def test_contact_patch_maps_of_a_3d_run(fretting):
    """The FE-patch plots take any 3-D model with node positions (here the half-space's)."""
    m, _, run, _ = fretting
    units = {"force": "N", "length": "mm", "energy": "N mm"}
    ax = cp.plot_patch_states(m, run, 0.25, units=units)
    check_legend_matches_drawn(ax)
    check_units(ax)
    fig, ax = plt.subplots()
    cp.plot_stuck_zone(m, run, ax, units=units)
    check_legend_matches_drawn(ax)
    check_units(ax)
    n_marked = sum(len(c.get_offsets()) for c in ax.collections if not c.get_label().startswith("_"))
    assert n_marked == m.system.n_nodes


def test_force_loop_area_and_opening():
    """The loop opening's title gives the area of the drawn force loop, ``closed integral F dx``;
    on an ellipse ``x = u cos, F = k x + b sin`` it is ``pi u b``, and the opening panel removes
    the line ``k x``."""
    import pandas as pd

    t = np.arange(64) / 64
    u, k, b = 0.002, 3e5, 20.0
    x = u * np.cos(2 * np.pi * t)
    Fx = k * x - b * np.sin(2 * np.pi * t)    # -sum q_x; two nodes share it
    rows = [{"t": tk, "node": i, "q_x": -f / 2, "q_y": 0.0, "p": 1.0, "state": "slip"}
            for tk, f in zip(t, Fx, strict=True) for i in range(2)]
    tab = pd.DataFrame(rows)
    xs, fs = np.r_[x, x[:1]], np.r_[Fx, Fx[:1]]
    assert cp.loop_area(xs, fs) == pytest.approx(np.pi * u * b, rel=2e-3)
    units = {"force": "N", "length": "mm", "energy": "N mm"}
    fig, axs = plt.subplots(1, 2)
    cp.plot_force_loop(tab, 1.0, axs[0], units=units, displacement=u)
    cp.plot_loop_opening(tab, 1.0, axs[1], units=units, displacement=u)
    check_legend_matches_drawn(axs[0])
    check_units(*axs)
    np.testing.assert_allclose(axs[0].lines[0].get_xdata(), xs)
    np.testing.assert_allclose(axs[0].lines[0].get_ydata(), fs)
    opening = axs[1].lines[0].get_ydata()
    assert np.abs(opening).max() == pytest.approx(b, rel=1e-2)
    assert f"{cp.loop_area(xs, fs):.4g}" in axs[1].get_title()
