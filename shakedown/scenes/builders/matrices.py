"""Scene model kind ``"matrices"``: a system given by its blocks, from the scene or from files.

``[model]`` keys (file names are relative to the scene's folder)
    ``A``, ``B``, ``C`` : nested lists (N x N) [force / length]; or
    ``file`` : an ``.npz`` or MATLAB ``.mat`` file holding ``A``, ``B``, ``C`` (or the reduced
    ``K`` of shape 2N x 2N) and optionally ``friction``; or
    ``K_file`` : the reduced stiffness ``K = [[A, B], [B^T, C]]`` (2N x 2N, order
    ``v_1..v_N, w_1..w_N``) in any of ``.mtx``, ``.mat``, ``.npz``, ``.csv``; or
    ``A_file``, ``B_file``, ``C_file`` : the blocks, each in any of those formats; or
    ``stiffness_file`` : a *full* stiffness (every DOF of an FE model, e.g. an Abaqus, ANSYS
    or Code_Aster export), condensed onto the contact nodes named by ``tangential_dofs`` and
    ``normal_dofs`` (one DOF per contact node each, counted from ``dof_base``, default 1),
    with ``fixed_dofs`` (supports, held at zero), ``tangential_sign`` and ``normal_sign``
    (+1 or -1, or a list: +1 when the DOF points along MODEL.md's slip direction ``t`` /
    the body's outward normal; see :mod:`shakedown.models.formats.stiffness`).
    ``variables`` : table renaming the arrays read from ``.mat`` / ``.npz`` files, e.g.
    ``{A = "Ktt", B = "Ktn", C = "Knn", K = "Kred", friction = "mu", stiffness = "KGLOB"}``.
    ``friction`` : number or list of N (overrides the file's); ``symmetry_rtol`` : number.
    ``sparse`` : true keeps ``K_file`` / ``A_file``, ``B_file``, ``C_file`` (and the arrays of
    ``file``) as ``scipy.sparse`` matrices: the system is then sparse and the cyclic runs and
    the bounds use it without densifying; with ``stiffness_file`` the stiffness is kept
    uncondensed (:func:`~shakedown.models.formats.uncondensed_stiffness`: the dense reduced
    stiffness is never formed, for thousands of contact nodes).
    ``dim`` : 2 (default) or 3: two tangential slips per node (MODEL.md s.8); ``A`` is then
    (2N x 2N) over ``v_1x, v_1y, v_2x, ...``, ``B`` (2N x N), ``C`` (N x N), a ``K`` (file or
    ``K_file``) is 3N x 3N in the order ``v_1x, v_1y, ..., w_1, ...``, ``friction`` a number,
    N numbers or N pairs ``[f_x, f_y]`` (elliptic cones); ``stiffness_file`` is 2-D only.
``[load]`` keys
    ``q0``, ``p0`` : lists of N [force] (``dim = 3``: ``q0`` and the tangential harmonics /
    samples are lists of N pairs ``[q_x, q_y]``); then either harmonics ``q_cos``, ``q_sin``, ``p_cos``,
    ``p_sin`` (lists of N or of lists of N) or samples ``q1``, ``p1`` (lists of lists of N);
    or ``file`` : an ``.npz`` / ``.mat`` with the same names; or
    ``record_file`` : a measured CSV record (columns ``t, q_1, p_1, ..., q_N, p_N``) with
    ``period`` (its time unit), ``n_samples`` (default 256), ``t_start`` (default: the first
    time), ``max_error`` (default 0.01: accepted resampling error relative to the largest
    reaction; see :mod:`shakedown.models.formats.records`);
    with ``stiffness_file``: ``static_force`` and ``cyclic_force`` (``cyclic_sin_force``),
    full-DOF force vectors (a list, or a file name: ``.mtx``, ``.csv``, or a ``.mat`` /
    ``.npz`` array named after the key), giving ``r_w(t) = r_static + lam (r_cos cos 2 pi t
    + r_sin sin 2 pi t)``.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import scipy.sparse as sp

from ...model.errors import InputError, SceneError
from ...model.loading import LoadCycle
from ...model.sparse import abs_max
from ...model.system import SYMMETRY_RTOL, DiscreteSystem
from ...models.formats import (
    UncondensedStiffness,
    condense_stiffness,
    read_load_record,
    read_matrix,
    read_vector,
    uncondensed_stiffness,
)
from ...models.formats.readers import container_names, read_array

STIFFNESS_KEYS = ("stiffness_file", "tangential_dofs", "normal_dofs", "fixed_dofs",
                  "tangential_sign", "normal_sign", "dof_base")
MODEL_KEYS = ("A", "B", "C", "file", "K_file", "A_file", "B_file", "C_file", *STIFFNESS_KEYS,
              "variables", "friction", "symmetry_rtol", "sparse", "dim")
HARMONIC_KEYS = ("q_cos", "q_sin", "p_cos", "p_sin")
SAMPLE_KEYS = ("q1", "p1")
RECORD_KEYS = ("record_file", "period", "n_samples", "t_start", "max_error")
FORCE_KEYS = ("static_force", "cyclic_force", "cyclic_sin_force")
LOAD_KEYS = ("q0", "p0", "file", *HARMONIC_KEYS, *SAMPLE_KEYS, *RECORD_KEYS, *FORCE_KEYS)
VARIABLE_NAMES = ("A", "B", "C", "K", "friction", "stiffness", *LOAD_KEYS[:2], *HARMONIC_KEYS,
                  *SAMPLE_KEYS, *FORCE_KEYS)


def _variables(model: dict) -> dict:
    names = model.get("variables", {})
    if not isinstance(names, dict) or not all(isinstance(v, str) for v in names.values()):
        raise SceneError('[model] key \'variables\' must be a table of names, e.g. '
                         '{A = "Ktt", B = "Ktn", C = "Knn"}')
    for key in names:
        if key not in VARIABLE_NAMES:
            raise SceneError(f"[model.variables] key {key!r} is not allowed; allowed: "
                             f"{', '.join(VARIABLE_NAMES)}")
    return names


def _container(path: Path, table: str, names: dict) -> dict:
    """Arrays of an ``.npz`` / ``.mat`` file (no pickles), renamed by ``names``."""
    if path.suffix.lower() not in (".npz", ".mat"):
        raise SceneError(f"[{table}] key 'file' = {path.name!r} must name an .npz or .mat file "
                         "(one matrix per .mtx/.csv file: use K_file or A_file, B_file, C_file)")
    present = container_names(path)
    out = {key: read_array(path, names.get(key, key)) for key in VARIABLE_NAMES
           if names.get(key, key) in present}
    for key in ("friction", "q0", "p0"):  # MATLAB stores every vector and scalar as 2-D
        if key in out and out[key].ndim == 2 and 1 in out[key].shape:
            out[key] = out[key].ravel()
            if key == "friction" and out[key].size == 1:
                out[key] = out[key][0]
    return out


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
    except OverflowError:  # an integer beyond 1.8e308
        raise SceneError(f"[{table}] key {key!r} holds an integer too large for a float (more "
                         "than 1.8e308): express it in larger units") from None
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


def _split(K, where: str, dim: int = 2) -> dict:
    if len(K.shape) != 2 or K.shape[0] != K.shape[1] or K.shape[0] % dim:
        size = "2N (order v_1..v_N, w_1..w_N)" if dim == 2 else (
            "3N (order v_1x, v_1y, ..., v_Nx, v_Ny, w_1, ..., w_N)")
        raise SceneError(f"{where}: the reduced stiffness K must be square of size {size}; "
                         f"got shape {K.shape}")
    n = K.shape[0] // dim * (dim - 1)  # the tangential unknowns: N (2-D) or 2N (3-D)
    # the DiscreteSystem's own symmetry tolerance (SYMMETRY_RTOL = 1e-8 of max|K|: room for
    # matrices written with 10 significant digits), checked here to name the file
    if sp.issparse(K):
        K = sp.csr_matrix(K)
        asym = abs_max(K[:n, n:] - K[n:, :n].T)
        if asym > SYMMETRY_RTOL * abs_max(K):
            raise SceneError(f"{where}: K is not symmetric (its B and B^T blocks differ)")
        return {"A": K[:n, :n], "B": K[:n, n:], "C": K[n:, n:]}
    if not np.allclose(K[:n, n:], K[n:, :n].T, rtol=0, atol=SYMMETRY_RTOL * np.abs(K).max()):
        raise SceneError(f"{where}: K is not symmetric (its B and B^T blocks differ)")
    return {"A": K[:n, :n], "B": K[:n, n:], "C": K[n:, n:]}


def _model_data(model: dict, scene_dir: Path, dim: int = 2):
    names = _variables(model)
    if dim == 3 and "stiffness_file" in model:
        raise SceneError("[model] 'stiffness_file' (condensation onto one tangential DOF per "
                         "node) is 2-D only; for dim = 3 give A, B, C or file / K_file")
    sources = [k for k in ("file", "K_file", "stiffness_file") if k in model]
    if any(k in model for k in ("A_file", "B_file", "C_file")):
        sources.append("A_file/B_file/C_file")
    if len(sources) > 1:
        raise SceneError(f"[model] give one source of the stiffness; got {', '.join(sources)}")
    if "stiffness_file" not in model and any(k in model for k in STIFFNESS_KEYS):
        raise SceneError("[model] keys " + ", ".join(k for k in STIFFNESS_KEYS if k in model)
                         + " need 'stiffness_file'")
    data, condensed = {}, None
    sparse = model.get("sparse", False)
    if not isinstance(sparse, bool):
        raise SceneError(f"[model] key 'sparse' = {sparse!r} must be true or false")
    if "file" in model:
        data.update(_container(scene_dir / str(model["file"]), "model", names))
        if "K" in data and "A" not in data:
            data.update(_split(data.pop("K"), f"[model] file {model['file']!r}", dim))
    if "K_file" in model:
        K = read_matrix(scene_dir / str(model["K_file"]), names.get("K"), sparse=sparse)
        data.update(_split(K, f"[model] K_file {model['K_file']!r}", dim))
    for key in ("A", "B", "C"):
        if f"{key}_file" in model:
            data[key] = read_matrix(scene_dir / str(model[f"{key}_file"]), names.get(key),
                                    sparse=sparse)
    if "stiffness_file" in model:
        for key in ("tangential_dofs", "normal_dofs"):
            if key not in model:
                raise SceneError(f"[model] key {key!r} is missing (one DOF per contact node, "
                                 "counted from dof_base = 1)")
        Kfull = read_matrix(scene_dir / str(model["stiffness_file"]), names.get("stiffness"),
                            sparse=True)
        make = uncondensed_stiffness if sparse else condense_stiffness
        condensed = make(
            Kfull, model["tangential_dofs"], model["normal_dofs"],
            fixed_dofs=model.get("fixed_dofs", []), tangential_sign=model.get("tangential_sign", 1),
            normal_sign=model.get("normal_sign", 1), dof_base=int(model.get("dof_base", 1)))
        if not sparse:
            data.update(dict(zip("ABC", condensed.blocks, strict=True)))
    return data, condensed


def build(model: dict, load: dict, scene_dir: Path):
    for key in model:
        if key not in MODEL_KEYS:
            raise SceneError(
                f"[model] key {key!r} is not allowed for kind 'matrices'; "
                f"allowed: {', '.join(MODEL_KEYS)}"
            )
    scene_dir = Path(scene_dir)
    dim = model.get("dim", 2)
    if isinstance(dim, bool) or dim not in (2, 3):
        raise SceneError(f"[model] key 'dim' = {dim!r} must be 2 or 3 (tangential slips per "
                         "node: one or two)")
    try:
        data, condensed = _model_data(model, scene_dir, dim)
    except SceneError:
        raise
    except InputError as exc:
        raise SceneError(f"[model] {exc}") from None
    for key in ("A", "B", "C", "friction"):
        if key in model:
            data[key] = _array("model", key, model[key])
    names = _variables(model)
    if isinstance(condensed, UncondensedStiffness):  # stiffness_file with sparse = true
        given = [k for k in ("A", "B", "C") if k in model]
        if given:
            raise SceneError(f"[model] keys {', '.join(given)} and 'stiffness_file' are two "
                             "sources of the stiffness; give one")
        if "friction" not in data:
            raise SceneError("[model] key 'friction' is missing (a number >= 0 or a list of N)")
        try:
            system = condensed.system(data["friction"])
        except InputError as exc:
            raise SceneError(f"[model] {exc}") from None
        return system, build_load(load, scene_dir, system.n_nodes, condensed, names), condensed
    if model.get("sparse") is True:  # every block sparse, whatever its source
        for key in ("A", "B", "C"):
            if key in data and not sp.issparse(data[key]):
                data[key] = sp.csr_matrix(np.asarray(data[key], float))
    for key in ("A", "C"):
        if key not in data:
            raise SceneError(f"[model] key {key!r} is missing (an N x N list, or give 'file', "
                             "'K_file', 'A_file'/'C_file' or 'stiffness_file')")
    if "B" not in data:
        data["B"] = (sp.csr_matrix(data["A"].shape) if sp.issparse(data["A"])
                     else np.zeros_like(data["A"]))
    if "friction" not in data:
        raise SceneError("[model] key 'friction' is missing (a number >= 0 or a list of N)")
    kwargs = {}
    if "symmetry_rtol" in model:
        tol = model["symmetry_rtol"]
        if isinstance(tol, bool) or not isinstance(tol, (int, float)) or not 0 <= tol < 1:
            raise SceneError(f"[model] key 'symmetry_rtol' = {tol!r} must be a number in [0, 1) "
                             "(relative asymmetry accepted, e.g. 1e-8)")
        kwargs["symmetry_rtol"] = float(tol)
    try:
        system = DiscreteSystem(data["A"], data["B"], data["C"], data["friction"], dim=dim,
                                **kwargs)
    except InputError as exc:
        raise SceneError(f"[model] {exc}") from None
    return system, build_load(load, scene_dir, system.n_nodes, condensed, names,
                              dim), condensed


def _force(load: dict, key: str, scene_dir: Path, names: dict):
    value = load[key]
    if isinstance(value, str):
        return read_vector(scene_dir / value, names.get(key, key)
                           if Path(value).suffix.lower() in (".npz", ".mat") else None)
    return _array("load", key, value)


def _full_load(load: dict, scene_dir: Path, condensed, names: dict) -> LoadCycle:
    other = [k for k in load if k not in FORCE_KEYS]
    if other:
        raise SceneError(f"[load] with 'stiffness_file' takes {', '.join(FORCE_KEYS)} (full-DOF "
                         f"force vectors); not {', '.join(other)}")
    welded = {}
    for key in FORCE_KEYS:
        if key in load:
            welded[key] = condensed.welded(_force(load, key, scene_dir, names))
    n = condensed.n_nodes
    q0, p0 = welded.get("static_force", (np.zeros(n), np.zeros(n)))
    kw = {}
    if "cyclic_force" in welded:
        kw.update(q_cos=welded["cyclic_force"][0], p_cos=welded["cyclic_force"][1])
    if "cyclic_sin_force" in welded:
        kw.update(q_sin=welded["cyclic_sin_force"][0], p_sin=welded["cyclic_sin_force"][1])
    return LoadCycle.from_harmonics(q0, p0, **kw)


def build_load(load: dict, scene_dir: Path, n: int, condensed=None, names=None,
               dim: int = 2) -> LoadCycle:
    for key in load:
        if key not in LOAD_KEYS:
            raise SceneError(
                f"[load] key {key!r} is not allowed for kind 'matrices'; "
                f"allowed: {', '.join(LOAD_KEYS)}"
            )
    names = names or {}
    try:
        if condensed is not None:
            cycle = _full_load(load, Path(scene_dir), condensed, names)
        elif any(k in load for k in FORCE_KEYS):
            raise SceneError(f"[load] keys {', '.join(FORCE_KEYS)} need [model] 'stiffness_file'")
        elif "record_file" in load:
            cycle = _record(load, Path(scene_dir))
        else:
            cycle = _reactions(load, Path(scene_dir), n, names, dim)
    except SceneError:
        raise
    except InputError as exc:
        raise SceneError(f"[load] {exc}") from None
    if cycle.n_nodes != n:
        raise SceneError(f"[load] gives {cycle.n_nodes} nodes but the model has {n} nodes")
    if getattr(cycle, "dim", 2) != dim:
        raise SceneError(f"[load] is {getattr(cycle, 'dim', 2)}-D but [model] has dim = {dim}: "
                         + ("give q0 and the tangential harmonics as N pairs [q_x, q_y]"
                            if dim == 3 else "give q0 as a list of N numbers"))
    return cycle


def _record(load: dict, scene_dir: Path) -> LoadCycle:
    other = [k for k in load if k not in RECORD_KEYS]
    if other:
        raise SceneError(f"[load] 'record_file' takes {', '.join(RECORD_KEYS)}; not "
                         f"{', '.join(other)}")
    if "period" not in load:
        raise SceneError("[load] key 'period' is missing (the loading period, in the record's "
                         "time unit)")
    kw = {k: load[k] for k in ("n_samples", "t_start", "max_error") if k in load}
    cycle, _ = read_load_record(scene_dir / str(load["record_file"]), load["period"], **kw)
    return cycle


def _reactions(load: dict, scene_dir: Path, n: int, names: dict, dim: int = 2) -> LoadCycle:
    if any(k in load for k in RECORD_KEYS):
        raise SceneError("[load] keys " + ", ".join(k for k in RECORD_KEYS if k in load)
                         + " need 'record_file'")
    data = {}
    if "file" in load:
        data.update(_container(scene_dir / str(load["file"]), "load", names))
    for key in ("q0", "p0", *HARMONIC_KEYS, *SAMPLE_KEYS):
        if key in load:
            data[key] = _array("load", key, load[key])
    for key in ("q0", "p0"):
        want = (n, 2) if (dim == 3 and key == "q0") else (n,)
        if key not in data:
            raise SceneError(f"[load] key {key!r} is missing (a list of {n} "
                             + ("pairs [q_x, q_y])" if len(want) == 2 else "numbers)"))
        if data[key].shape != want:
            raise SceneError(
                f"[load] key {key!r} must list one value per node ({n} nodes"
                + (", each a pair [q_x, q_y]" if len(want) == 2 else "") + "); got "
                f"{data[key].tolist()!r} (shape {data[key].shape})"
            )
    harm = [k for k in HARMONIC_KEYS if k in data]
    samp = [k for k in SAMPLE_KEYS if k in data]
    if harm and samp:
        raise SceneError(
            f"[load] give either harmonics ({', '.join(HARMONIC_KEYS)}) or samples "
            f"(q1, p1), not both; got {harm + samp}"
        )
    if samp:
        if len(samp) != 2:
            raise SceneError("[load] samples need both 'q1' and 'p1' (n_samples x N lists)")
        return LoadCycle.from_samples(data["q0"], data["p0"], data["q1"], data["p1"])
    return LoadCycle.from_harmonics(data["q0"], data["p0"], **{k: data[k] for k in harm})


def resolved(model: dict, load: dict) -> tuple[dict, dict]:
    """``[model]`` and ``[load]`` with the defaults :func:`build` applies filled in."""
    m, ld = dict(model), dict(load)
    if "stiffness_file" in m:
        m.setdefault("fixed_dofs", [])
        m.setdefault("tangential_sign", 1)
        m.setdefault("normal_sign", 1)
        m.setdefault("dof_base", 1)
    if "record_file" in ld:
        ld.setdefault("n_samples", 256)
        ld.setdefault("max_error", 1e-2)
    return m, ld


def provenance(model: dict, load: dict) -> dict:
    """What the manifest states about the inputs: the resampling error of a load record.

    ``model`` and ``load`` are the resolved tables (absolute file paths).
    """
    if "record_file" not in load or "period" not in load:
        return {}
    kw = {k: load[k] for k in ("n_samples", "t_start") if k in load}
    try:
        _, fit = read_load_record(load["record_file"], load["period"], max_error=float("inf"), **kw)
    except InputError:
        return {}  # the build reports it
    return {"load_record": fit.message(), "load_record_relative_error": fit.relative_error}
