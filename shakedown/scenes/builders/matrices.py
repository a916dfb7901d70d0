"""Scene model kind ``"matrices"``: a system given by its blocks ``A``, ``B``, ``C``.

``[model]`` keys
    ``A``, ``B``, ``C`` : nested lists (N x N) [force / length], or
    ``file`` : an ``.npz`` beside the scene with arrays ``A``, ``B``, ``C`` (and optionally
    ``friction``); ``friction`` : number or list of N (overrides the file);
    ``symmetry_rtol`` : number.
``[load]`` keys
    ``q0``, ``p0`` : lists of N [force]; then either harmonics ``q_cos``, ``q_sin``, ``p_cos``,
    ``p_sin`` (lists of N or of lists of N) or samples ``q1``, ``p1`` (lists of lists of N);
    or ``file`` : an ``.npz`` with the same names.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from ...model.errors import InputError, SceneError
from ...model.loading import LoadCycle
from ...model.system import DiscreteSystem

MODEL_KEYS = ("A", "B", "C", "file", "friction", "symmetry_rtol")
HARMONIC_KEYS = ("q_cos", "q_sin", "p_cos", "p_sin")
SAMPLE_KEYS = ("q1", "p1")
LOAD_KEYS = ("q0", "p0", "file", *HARMONIC_KEYS, *SAMPLE_KEYS)


def _npz(path: Path, table: str) -> dict:
    if path.suffix != ".npz":
        raise SceneError(f"[{table}] key 'file' = {str(path)!r} must name an .npz file")
    if not path.is_file():
        raise SceneError(f"[{table}] key 'file' = {str(path)!r}: no such file")
    try:
        with np.load(path, allow_pickle=False) as data:
            return {k: np.array(data[k]) for k in data.files}
    except Exception as exc:  # zipfile / format errors; their text may quote the file
        raise SceneError(f"[{table}] key 'file' = {str(path)!r} is not a readable .npz of "
                         f"numeric arrays ({type(exc).__name__})") from None


def _array(table, key, value):
    bad = _not_a_number(value)
    if bad is not None:
        if isinstance(bad, str):
            what, fix = f"the text {bad!r}", f"write {bad} without quotes"
        else:
            what, fix = f"the boolean {str(bad).lower()}", "write a number such as 0.7"
        raise SceneError(
            f"[{table}] key {key!r} must be a number or a (nested) list of numbers; got "
            f"{what}, which is not a number ({fix})"
        )
    try:
        arr = np.array(value, dtype=float)
    except (TypeError, ValueError):
        raise SceneError(
            f"[{table}] key {key!r} = {value!r} must be a number or a (nested) list of numbers"
        ) from None
    return arr


def _not_a_number(value):
    """The first string or boolean inside ``value`` (TOML lists may nest), else None."""
    if isinstance(value, (str, bool)):
        return value
    if isinstance(value, (list, tuple)):
        for v in value:
            bad = _not_a_number(v)
            if bad is not None:
                return bad
    return None


def build(model: dict, load: dict, scene_dir: Path):
    for key in model:
        if key not in MODEL_KEYS:
            raise SceneError(
                f"[model] key {key!r} is not allowed for kind 'matrices'; "
                f"allowed: {', '.join(MODEL_KEYS)}"
            )
    data = {}
    if "file" in model:
        data.update(_npz(scene_dir / str(model["file"]), "model"))
    for key in ("A", "B", "C", "friction"):
        if key in model:
            data[key] = _array("model", key, model[key])
    for key in ("A", "C"):
        if key not in data:
            raise SceneError(f"[model] key {key!r} is missing (an N x N list, or give 'file')")
    if "B" not in data:
        data["B"] = np.zeros_like(data["A"])
    if "friction" not in data:
        raise SceneError("[model] key 'friction' is missing (a number >= 0 or a list of N)")
    kwargs = {}
    if "symmetry_rtol" in model:
        kwargs["symmetry_rtol"] = float(model["symmetry_rtol"])
    try:
        system = DiscreteSystem(data["A"], data["B"], data["C"], data["friction"], **kwargs)
    except InputError as exc:
        raise SceneError(f"[model] {exc}") from None
    return system, build_load(load, scene_dir, system.n_nodes), None


def build_load(load: dict, scene_dir: Path, n: int) -> LoadCycle:
    for key in load:
        if key not in LOAD_KEYS:
            raise SceneError(
                f"[load] key {key!r} is not allowed for kind 'matrices'; "
                f"allowed: {', '.join(LOAD_KEYS)}"
            )
    data = {}
    if "file" in load:
        data.update(_npz(scene_dir / str(load["file"]), "load"))
    for key in LOAD_KEYS[:1] + LOAD_KEYS[1:2] + HARMONIC_KEYS + SAMPLE_KEYS:
        if key in load:
            data[key] = _array("load", key, load[key])
    for key in ("q0", "p0"):
        if key not in data:
            raise SceneError(f"[load] key {key!r} is missing (a list of {n} numbers)")
        if data[key].shape != (n,):
            raise SceneError(
                f"[load] key {key!r} must list one value per node ({n} nodes); got "
                f"{data[key].tolist()!r} (shape {data[key].shape})"
            )
    harm = [k for k in HARMONIC_KEYS if k in data]
    samp = [k for k in SAMPLE_KEYS if k in data]
    try:
        if harm and samp:
            raise SceneError(
                f"[load] give either harmonics ({', '.join(HARMONIC_KEYS)}) or samples "
                f"(q1, p1), not both; got {harm + samp}"
            )
        if samp:
            if len(samp) != 2:
                raise SceneError("[load] samples need both 'q1' and 'p1' (n_samples x N lists)")
            cycle = LoadCycle.from_samples(data["q0"], data["p0"], data["q1"], data["p1"])
        else:
            cycle = LoadCycle.from_harmonics(
                data["q0"], data["p0"], **{k: data[k] for k in harm}
            )
    except SceneError:
        raise
    except InputError as exc:
        raise SceneError(f"[load] {exc}") from None
    if cycle.n_nodes != n:
        raise SceneError(f"[load] key 'q0' has {cycle.n_nodes} entries but the model has {n} nodes")
    return cycle
