"""The citation registry: well-formed references, and each method registers when it runs."""

import re

import numpy as np
import pytest

import shakedown as sd
from shakedown.model import citations


@pytest.fixture(autouse=True)
def fresh_registry():
    citations.reset()
    yield
    citations.reset()


def test_every_reference_is_a_well_formed_bibtex_entry():
    assert set(citations.METHODS) == set(citations.REFERENCES)
    for key, entry in citations.REFERENCES.items():
        head = re.match(r"@(\w+)\{([^,]+),", entry)
        assert head and head.group(2) == key, key
        assert entry.count("{") == entry.count("}"), key
        for field in ("author", "title", "year"):
            assert re.search(rf"^\s*{field}\s*=", entry, re.M), (key, field)


def test_seed_references_carry_the_seeds_bibliographic_data():
    # seed 000's own header: CMAME 196 (2007) 2377-2389, doi:10.1016/j.cma.2006.11.020
    assert "10.1016/j.cma.2006.11.020" in citations.REFERENCES["hassani2007"]
    assert "2377--2389" in citations.REFERENCES["hassani2007"]
    # seed 001's header: CMNE/CILAMCE 2007, Porto
    assert "Porto" in citations.REFERENCES["agwa2007"]


def test_registry_records_what_ran_in_order_once():
    assert citations.used() == ("shakedown",)
    citations.register("kachanov1987", "melan1936")
    citations.register("kachanov1987")
    assert citations.used() == ("shakedown", "kachanov1987", "melan1936")
    keys = re.findall(r"^@\w+\{([^,]+),", citations.bibtex(), re.M)
    assert keys == list(citations.used())
    assert "kachanov1987 (Kachanov" in citations.summary()
    citations.reset()
    assert citations.used() == ("shakedown",)


def test_unknown_keys_and_bad_entries_are_refused():
    with pytest.raises(sd.InputError, match="citation key 'kachanov1978' is not defined"):
        citations.register("kachanov1978")
    with pytest.raises(sd.InputError, match="must start '@type"):
        citations.define("smith2020", "@article{jones2020, title={x}}", "x")
    with pytest.raises(sd.InputError, match="lower-case"):
        citations.define("Smith 2020", "@article{Smith 2020, title={x}}", "x")


def test_bounds_register_the_shakedown_theorems():
    s = sd.DiscreteSystem([[1.0]], [[0.0]], [[1.0]], friction=0.5)
    sd.shakedown_bounds(s, sd.LoadCycle.from_harmonics([0.0], [1.0], q_cos=[0.2]))
    assert {"melan1936", "klarbring2007", "ahn2008"} <= set(citations.used())
    assert "kachanov1987" not in citations.used()


def test_kachanov_registers_kachanov():
    import crack_networks as cn

    cracks = cn.sample_crack_set(3, density=0.05, half_length=1.0, rng=1)
    cn.kachanov_model(cracks, shear_modulus=1.0, poisson_ratio=0.25, friction=0.6)
    assert citations.used() == ("shakedown", "kachanov1987")


def test_stability_and_lemke_register_their_papers():
    from shakedown.evolution.lemke import lemke
    from shakedown.stability import NodePartition, mceip_mu, power_iteration, slip_pencil

    K = np.array([[2.0, 0.5], [0.5, 3.0]])
    mceip_mu(K, NodePartition.all_slip(1, chi=-1.0))
    assert "agwa2007" in citations.used() and "hassani2007" not in citations.used()
    power_iteration(slip_pencil(K, NodePartition.all_slip(1, chi=-1.0)))
    assert "hassani2007" in citations.used()
    lemke(np.eye(2), np.array([-1.0, 1.0]))
    assert "lemke1965" in citations.used()
    s = sd.DiscreteSystem([[2.0]], [[0.5]], [[3.0]], friction=1.0)
    s.critical_friction()
    assert citations.used()[-1] == "klarbring1990"


def test_fe_condensation_registers_scikit_fem():
    pytest.importorskip("skfem")
    fe = sd.fe
    fe.FEModel(fe.rectangle(1.0, 1.0, 2, 2), fe.isotropic(1.0, 0.3), dirichlet=["top"],
               contact=["bottom"]).condense()
    assert "gustafsson2020" in citations.used()


def test_half_plane_partial_slip_registers_its_papers():
    from shakedown.models.half_plane.continuum import cattaneo_mindlin_ratio, shell_history

    cattaneo_mindlin_ratio(0.5, 1.0, 1.0)
    assert {"cattaneo1938", "mindlin1949"} <= set(citations.used())
    shell_history(np.array([1.0, 1.0, 1.0]), np.array([0.0, 0.3, -0.2]), 0.5)
    assert {"ciavarella1998", "jager1998"} <= set(citations.used())
