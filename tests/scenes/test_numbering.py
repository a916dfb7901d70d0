"""Everything the command line writes numbers nodes, realisations, initial states and load
factors from 1 (issue 25): the CSV/Parquet tables, the JSON files, the verdict texts and the
printed messages of small runs of every analysis that numbers them are scanned for a 0.

The Python API keeps 0-based arrays and tables (documented in the README); a table that is
also a file is numbered from 1 in the file.
"""

import json
import re

import pandas as pd
import pytest

from shakedown.scenes.cli import main

#: Columns that hold a number of a node, a realisation, an initial state or a load factor.
NUMBER_COLUMNS = re.compile(r"^(node|state|realisation|crack|lam_index|\w+_node)$")
#: Columns named by a node (``slip_3``, ``initial_slip_1_x``, ``q_2``).
NODE_NAMED = re.compile(r"^(?:initial_slip|steady_slip|slip|gap|q|p|v|w)_(\d+)(?:_[xyz])?$")
#: A list of numbers under one of these JSON keys.
NUMBER_KEYS = re.compile(r"^(node|nodes|state|realisation|lam_index|\w+_nodes?|stuck_nodes"
                         r"|unloading_nodes|borderline_nodes|closed_nodes)$")
#: Words followed by a number in a message.
ZERO_IN_TEXT = re.compile(r"\b(node|nodes|realisation|realisations|state|crack|real|I|II)[ _]0\b")

RUNS = {
    "bounds": ["bounds", "two_node_coupled", "--set", "plots=false"],
    "stability": ["stability", "two_node_coupled", "--set", "plots=false"],
    "uniqueness": ["cycles", "two_node_coupled", "--set", "n_initial_states=3", "--set",
                   "steps_per_cycle=32", "--set", "lam=1.2", "--set", "plots=false"],
    "sweep": ["sweep", "two_node_coupled", "--set", "lams=[0.5,1.5]", "--set", "n_states=2",
              "--set", "n_workers=1", "--set", "steps_per_cycle=32", "--set", "plots=false"],
}


def _numbers(value):
    if isinstance(value, bool):
        return []
    if isinstance(value, int):
        return [value]
    if isinstance(value, str):
        return [int(x) for x in value.split(",") if x.strip().lstrip("-").isdigit()]
    if isinstance(value, list):
        return [x for v in value for x in _numbers(v)]
    return []


def _scan_json(obj, where, bad):
    if isinstance(obj, dict):
        for k, v in obj.items():
            if NUMBER_KEYS.match(str(k)) and any(x < 1 for x in _numbers(v)):
                bad.append(f"{where}: {k} = {v!r}")
            _scan_json(v, f"{where}/{k}", bad)
    elif isinstance(obj, list):
        for i, v in enumerate(obj):
            _scan_json(v, f"{where}[{i + 1}]", bad)


def scan(folder, text):
    """Every 0 where a number counted from 1 belongs, as 'file: what' strings."""
    bad = []
    for path in sorted(folder.rglob("*")):
        if path.suffix in (".csv", ".parquet") and not any("store" in d for d in path.parts):
            # (a sweep's store holds the API's rows, 0-based, for resuming: not read by people)
            table = pd.read_csv(path) if path.suffix == ".csv" else pd.read_parquet(path)
            for col in table.columns:
                m = NODE_NAMED.match(str(col))
                if m and int(m[1]) < 1:
                    bad.append(f"{path.name}: column {col}")
                if NUMBER_COLUMNS.match(str(col)) and pd.api.types.is_integer_dtype(table[col]):
                    if (table[col] < 1).any():
                        bad.append(f"{path.name}: {col} = {table[col].min()}")
                if str(col) == "stuck":
                    zeros = [s for s in table[col].dropna().astype(str) if "0" in s.split(",")]
                    if zeros:
                        bad.append(f"{path.name}: stuck {zeros[0]!r}")
        elif path.suffix == ".json":
            _scan_json(json.loads(path.read_text()), path.name, bad)
        elif path.suffix == ".txt":
            for m in ZERO_IN_TEXT.finditer(path.read_text()):
                bad.append(f"{path.name}: {m[0]!r}")
    for m in ZERO_IN_TEXT.finditer(text):
        bad.append(f"stdout/stderr: {m[0]!r}")
    return bad


@pytest.mark.parametrize("name", sorted(RUNS))
def test_written_outputs_number_from_1(name, tmp_path, capsys):
    out = tmp_path / name
    assert main([*RUNS[name], "-o", str(out)]) == 0
    captured = capsys.readouterr()
    files = [p for p in out.rglob("*") if p.suffix in (".csv", ".json", ".txt", ".parquet")]
    assert files  # the scan reads something
    assert scan(out, captured.out + captured.err) == []


def test_the_scan_finds_a_0_based_table(tmp_path):
    # the scanner itself, on files written 0-based
    pd.DataFrame({"realisation": [0, 1], "state": [1, 2], "stuck": ["0,2", ""]}).to_csv(
        tmp_path / "runs.csv", index=False)
    (tmp_path / "r.json").write_text(json.dumps({"rows": [{"stuck_nodes": [0, 3]}]}))
    (tmp_path / "v.txt").write_text("breaks constraint I_0 at node 0")
    bad = scan(tmp_path, "real 0")
    assert len(bad) == 6 and any("stuck '0,2'" in b for b in bad)
