"""``mode.csv`` of the stability analysis names its columns by what they are (issue 25: they
were ``x, y``): the slip mode ``chi v'`` and the cone unloading ``chi q' + mu* p'`` of each node,
complementary (conventions, section 5)."""

import pandas as pd

from shakedown.scenes.cli import main


def test_mode_csv_columns_say_what_they_hold(tmp_path):
    out = tmp_path / "stab"
    assert main(["stability", "two_node_coupled", "-q", "-o", str(out), "--set", "plots=false"]) == 0
    mode = pd.read_csv(out / "mode.csv")
    assert list(mode.columns) == ["node", "chi", "slip_mode", "cone_unloading"]
    assert mode["node"].min() == 1  # numbered from 1
    x, y = mode["slip_mode"].to_numpy(), mode["cone_unloading"].to_numpy()
    scale = max(abs(x).max(), 1e-300) * max(abs(y).max(), 1e-300)
    assert (x >= -1e-12 * abs(x).max()).all() and (y >= -1e-9 * max(abs(y).max(), 1e-300)).all()
    assert (abs(x * y) <= 1e-9 * scale).all()  # x y = 0 node by node
