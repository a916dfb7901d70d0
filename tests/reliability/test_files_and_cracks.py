"""Touching cracks, close-pair warnings, and file readers that quote no content (items 5, 10).

Before: a T-junction ``CrackSet([[0, 0], [0, 1]], [1, 1], [0, pi/2])`` passed (rounding left a
distance of 5e-17), and ``load_csv`` / the mesh and .npz readers put the first bad token of any
file they were pointed at into the error message.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

import crack_networks as cn
import shakedown as sd
from shakedown.scenes.files import build, scene_from_string

SECRET = "hunter2-secret-token"


@pytest.mark.parametrize("scale, shift", [(1.0, 0.0), (1e-3, 1e6), (37.0, -5e3), (1e6, 0.0)])
def test_t_junction_is_touching_at_any_scale_and_offset(scale, shift):
    # a vertical crack whose lower tip lies on a horizontal one (exact data, rounded centres)
    centres = scale * np.array([[0.0, 0.0], [0.0, 1.0]]) + shift
    with pytest.raises(sd.InputError, match="must not intersect or touch; cracks 1 .* and 2"):
        cn.CrackSet(centres, [scale, scale], [0.0, np.pi / 2])
    # the same pair 1e-3 a apart is a valid (if ill-advised) crack set; its distance is known
    # to the rounding of the coordinates, eps * (|shift| + scale) = 2e-10 at the worst case
    # (1e-6 absolute gap there): rel 1e-3 covers it
    cs = cn.CrackSet(centres + [[0.0, 0.0], [0.0, 1e-3 * scale]], [scale, scale],
                     [0.0, np.pi / 2])
    assert cs.min_distance() == pytest.approx(1e-3 * scale, rel=1e-3)


def test_close_pairs_warn_with_the_benchmark_threshold():
    # gap 0.05 a: Kachanov's opening error 3.7 % (RESULTS_kachanov.md s.2) -> warning
    close = cn.CrackSet([[0.0, 0.0], [2.05, 0.0]], [1.0, 1.0], [0.0, 0.0])
    with pytest.warns(cn.KachanovAccuracyWarning, match="cracks 1 and 2, distance 0.05"):
        cn.kachanov_model(close, friction=0.6)
    # gap 0.5 a (0.7 % error): silent
    far = cn.CrackSet([[0.0, 0.0], [2.5, 0.0]], [1.0, 1.0], [0.0, 0.0])
    with warnings.catch_warnings():
        warnings.simplefilter("error", cn.KachanovAccuracyWarning)
        cn.kachanov_model(far, friction=0.6)
    # the threshold is relative: the same geometry in micrometres warns the same way
    with pytest.warns(cn.KachanovAccuracyWarning):
        cn.kachanov_model(close.scaled(1e-6), shear_modulus=3e10, friction=0.6)


def test_crack_csv_quotes_no_content(tmp_path):
    p = tmp_path / "c.csv"
    p.write_text(f"x,y,half_length,angle\n0,0,1,0\n{SECRET},1,1,0\n")
    with pytest.raises(sd.InputError, match=r"line 3, column 1 \('x'\) is non-numeric") as info:
        cn.load_csv(p)
    assert SECRET not in str(info.value)
    p.write_text(f"{SECRET}:x:0:0\n")
    with pytest.raises(sd.InputError, match="must have a header") as info:
        cn.load_csv(p)
    assert SECRET not in str(info.value)
    p.write_bytes(b"\xff\xfe" + SECRET.encode())
    with pytest.raises(sd.InputError, match="not a readable UTF-8") as info:
        cn.load_csv(p)
    assert SECRET not in str(info.value)


@pytest.mark.parametrize("kind, body, load", [
    ("matrices", 'file = "{f}"\nfriction = 0.3', "q0 = [0.0]\np0 = [1.0]"),
    ("crack_network", 'file = "{f}"\nfriction = 0.3',
     "static = [-1.0, 0.0, -1.0]\ncyclic = [0.0, 1.0, 0.0]"),
])
def test_scene_file_keys_quote_no_content(tmp_path, kind, body, load):
    (tmp_path / "leak.npz").write_text(SECRET)
    (tmp_path / "leak.csv").write_text(f"x,y,half_length,angle\n{SECRET},0,1,0\n")
    f = "leak.npz" if kind == "matrices" else "leak.csv"
    text = f'[model]\nkind = "{kind}"\n' + body.format(f=f) + "\n[load]\n" + load + "\n"
    with pytest.raises(sd.InputError) as info:
        build(scene_from_string(text, directory=tmp_path))
    assert SECRET not in str(info.value) and f in str(info.value)


def test_mesh_reader_quotes_no_content(tmp_path):
    p = tmp_path / "m.msh"
    p.write_text(f"$MeshFormat\n{SECRET}\n$EndMeshFormat\n")
    with pytest.raises(sd.InputError, match="could not read mesh file") as info:
        sd.fe.from_file(p)
    assert SECRET not in str(info.value)
