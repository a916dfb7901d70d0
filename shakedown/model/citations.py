"""What to cite: a registry of the methods a run used (after PyBaMM's ``pybamm.citations``).

Every public entry point of a method calls :func:`register` with the key of its reference
when it runs (``citations.register("kachanov1987")`` at the top of
:func:`crack_networks.kachanov_model`, and so on), so after a run :func:`used` holds exactly the
methods that ran, in the order they first ran.  The ``shakedown`` command resets the registry
before a scene, writes :func:`bibtex` of the used keys to ``CITATIONS.bib`` in the output
folder and prints :func:`summary` ("please cite ...").  From Python::

    from shakedown.model import citations
    citations.reset()
    ...                                  # build systems, run analyses
    print(citations.summary())
    open("refs.bib", "w").write(citations.bibtex())

Work done in worker processes is counted too: the sweep's task runner sends each worker's
:func:`used` keys back with its rows (:func:`shakedown.studies.store.run_tasks`).

The references are in :data:`REFERENCES`; a new method adds its entry with :func:`define`
(a key that is not defined is refused by :func:`register`, so a typo cannot pass silently).
Bibliographic data: the seeds' reference lists (``shared/seeds/``: Hassani et al. 2007, Agwa &
Pinto da Costa 2007, Barber 2011 and the works they cite) and the publishers' records.
"""

from __future__ import annotations

import re

from .errors import InputError
from .version import __version__

#: The package itself: always cited (see ``CITATION.cff``).
PACKAGE_KEY = "shakedown"

#: ``key -> BibTeX entry``.  Keys are ``firstauthorYEAR`` in lower case.
REFERENCES: dict[str, str] = {
    PACKAGE_KEY: """@software{shakedown,
  title = {shakedown: shakedown, cyclic dissipation and stability of discrete elastic systems
           with Coulomb friction},
  author = {{The shakedown developers}},
  year = {2026},
  version = {""" + __version__ + """},
  note = {Python package; see CITATION.cff}
}""",
    "melan1936": """@article{melan1936,
  author = {Melan, Ernst},
  title = {Theorie statisch unbestimmter {S}ysteme aus ideal-plastischem {B}austoff},
  journal = {Sitzungsberichte der Akademie der Wissenschaften in Wien, Abteilung IIa},
  volume = {145},
  pages = {195--218},
  year = {1936}
}""",
    "klarbring2007": """@article{klarbring2007,
  author = {Klarbring, Anders and Ciavarella, Michele and Barber, James R.},
  title = {Shakedown in elastic contact problems with {C}oulomb friction},
  journal = {International Journal of Solids and Structures},
  volume = {44},
  number = {25--26},
  pages = {8355--8365},
  year = {2007},
  doi = {10.1016/j.ijsolstr.2007.06.013}
}""",
    "ahn2008": """@article{ahn2008,
  author = {Ahn, Young Ju and Bertocchi, Enrico and Barber, James R.},
  title = {Shakedown of coupled two-dimensional discrete frictional systems},
  journal = {Journal of the Mechanics and Physics of Solids},
  volume = {56},
  number = {12},
  pages = {3433--3440},
  year = {2008},
  doi = {10.1016/j.jmps.2008.09.003}
}""",
    "barber2011": """@article{barber2011,
  author = {Barber, James R.},
  title = {Frictional systems subjected to oscillating loads},
  journal = {Annals of Solid and Structural Mechanics},
  volume = {2},
  pages = {45--55},
  year = {2011},
  doi = {10.1007/s12356-011-0017-7}
}""",
    "klarbring1990": """@article{klarbring1990,
  author = {Klarbring, Anders},
  title = {Examples of non-uniqueness and non-existence of solutions to quasistatic contact
           problems with friction},
  journal = {Ingenieur-Archiv},
  volume = {60},
  number = {8},
  pages = {529--541},
  year = {1990},
  doi = {10.1007/BF00541909}
}""",
    "kachanov1987": """@article{kachanov1987,
  author = {Kachanov, Mark},
  title = {Elastic solids with many cracks: a simple method of analysis},
  journal = {International Journal of Solids and Structures},
  volume = {23},
  number = {1},
  pages = {23--43},
  year = {1987},
  doi = {10.1016/0020-7683(87)90030-8}
}""",
    "hassani2007": """@article{hassani2007,
  author = {Hassani, Riad and Ionescu, Ioan R. and Sakki, Nour-Dine},
  title = {Unstable perturbation of the equilibrium under {C}oulomb friction: nonlinear
           eigenvalue analysis},
  journal = {Computer Methods in Applied Mechanics and Engineering},
  volume = {196},
  number = {23--24},
  pages = {2377--2389},
  year = {2007},
  doi = {10.1016/j.cma.2006.11.020}
}""",
    "agwa2007": """@inproceedings{agwa2007,
  author = {Agwa, Mohamed A. and Pinto da Costa, Ant{\\'o}nio},
  title = {Frictional instabilities in contact problems: numerical and analytical computation
           of instability modes},
  booktitle = {Congresso de M{\\'e}todos Num{\\'e}ricos em Engenharia / CILAMCE 2007},
  address = {Porto, Portugal},
  publisher = {APMTAC},
  year = {2007}
}""",
    "martins1999": """@article{martins1999,
  author = {Martins, Jo{\\~a}o A. C. and Barbarin, St{\\'e}phane and Raous, Michel and
            Pinto da Costa, Ant{\\'o}nio},
  title = {Dynamic stability of finite dimensional linearly elastic systems with unilateral
           contact and {C}oulomb friction},
  journal = {Computer Methods in Applied Mechanics and Engineering},
  volume = {177},
  pages = {289--328},
  year = {1999}
}""",
    "huangfu2018": """@article{huangfu2018,
  author = {Huangfu, Qi and Hall, J. A. Julian},
  title = {Parallelizing the dual revised simplex method},
  journal = {Mathematical Programming Computation},
  volume = {10},
  number = {1},
  pages = {119--142},
  year = {2018},
  doi = {10.1007/s12532-017-0130-5}
}""",
    "goulart2024": """@misc{goulart2024,
  author = {Goulart, Paul J. and Chen, Yuwen},
  title = {Clarabel: An interior-point solver for conic programs with quadratic objectives},
  year = {2024},
  eprint = {2405.12762},
  archiveprefix = {arXiv}
}""",
    "gustafsson2020": """@article{gustafsson2020,
  author = {Gustafsson, Tom and McBain, G. D.},
  title = {scikit-fem: A {P}ython package for finite element assembly},
  journal = {Journal of Open Source Software},
  volume = {5},
  number = {52},
  pages = {2369},
  year = {2020},
  doi = {10.21105/joss.02369}
}""",
    "lemke1965": """@article{lemke1965,
  author = {Lemke, Carlton E.},
  title = {Bimatrix equilibrium points and mathematical programming},
  journal = {Management Science},
  volume = {11},
  number = {7},
  pages = {681--689},
  year = {1965},
  doi = {10.1287/mnsc.11.7.681}
}""",
    "cattaneo1938": """@article{cattaneo1938,
  author = {Cattaneo, Carlo},
  title = {Sul contatto di due corpi elastici: distribuzione locale degli sforzi},
  journal = {Rendiconti dell'Accademia Nazionale dei Lincei},
  volume = {27},
  pages = {342--348, 434--436, 474--478},
  year = {1938}
}""",
    "mindlin1949": """@article{mindlin1949,
  author = {Mindlin, Raymond D.},
  title = {Compliance of elastic bodies in contact},
  journal = {Journal of Applied Mechanics},
  volume = {16},
  number = {3},
  pages = {259--268},
  year = {1949},
  doi = {10.1115/1.4009973}
}""",
    "ciavarella1998": """@article{ciavarella1998,
  author = {Ciavarella, Michele},
  title = {The generalized {C}attaneo partial slip plane contact problem. {I}--{T}heory},
  journal = {International Journal of Solids and Structures},
  volume = {35},
  number = {18},
  pages = {2349--2362},
  year = {1998},
  doi = {10.1016/S0020-7683(97)00154-6}
}""",
    "jager1998": """@article{jager1998,
  author = {J{\\"a}ger, J.},
  title = {A new principle in contact mechanics},
  journal = {Journal of Tribology},
  volume = {120},
  number = {4},
  pages = {677--684},
  year = {1998},
  doi = {10.1115/1.2833765}
}""",
}

#: What each key stands for, in one line (the summary printed after a run).
METHODS: dict[str, str] = {
    PACKAGE_KEY: "the shakedown package",
    "melan1936": "Melan's static shakedown theorem",
    "klarbring2007": "frictional Melan theorem, lower shakedown bound lam1",
    "ahn2008": "shakedown bounds of coupled frictional systems (Ahn's algorithm, lam2)",
    "barber2011": "uniqueness of the steady state of uncoupled systems (memory argument)",
    "klarbring1990": "critical friction coefficient of discrete systems",
    "kachanov1987": "Kachanov's crack-interaction approximation",
    "hassani2007": "power iteration for the nonlinear complementarity eigenproblem",
    "agwa2007": "complementarity eigenproblem and the layer instability modes",
    "martins1999": "dynamic stability of frictional systems (flutter / divergence)",
    "huangfu2018": "HiGHS linear-programming solver",
    "gustafsson2020": "scikit-fem finite element assembly",
    "goulart2024": "Clarabel conic (second-order cone) solver",
    "lemke1965": "Lemke's complementary pivoting",
    "cattaneo1938": "Cattaneo partial slip",
    "mindlin1949": "Mindlin partial slip",
    "ciavarella1998": "Ciavarella's generalised Cattaneo superposition",
    "jager1998": "Jager's superposition principle",
}

_KEY = re.compile(r"^[a-z][a-z0-9_-]*$")
_used: dict[str, None] = {PACKAGE_KEY: None}


def define(key: str, entry: str, method: str) -> None:
    """Add a reference (a new method's) to the registry.

    Parameters
    ----------
    key : str
        Lower-case key, the one in ``entry`` (``@article{key, ...``).
    entry : str
        The BibTeX entry.
    method : str
        One line saying what is cited, for :func:`summary`.
    """
    if not isinstance(key, str) or not _KEY.match(key):
        raise InputError(f"citation key {key!r} must be lower-case letters, digits, '_' or '-'")
    head = re.match(r"\s*@\w+\{([^,]+),", entry or "")
    if head is None or head.group(1).strip() != key:
        raise InputError(f"citation {key!r}: entry must start '@type{{{key},'; got {entry[:40]!r}")
    REFERENCES[key] = entry.strip()
    METHODS[key] = str(method)


def register(*keys: str) -> None:
    """Record that the methods of ``keys`` ran (idempotent, cheap: call it on every run)."""
    for key in keys:
        if key not in REFERENCES:
            raise InputError(
                f"citation key {key!r} is not defined; defined: {', '.join(sorted(REFERENCES))} "
                "(add it with shakedown.model.citations.define)")
        _used.setdefault(key, None)


def used() -> tuple[str, ...]:
    """Keys registered since the last :func:`reset`, the package first, in order of first use."""
    return tuple(_used)


def reset() -> None:
    """Forget the registered methods (the package itself stays)."""
    _used.clear()
    _used[PACKAGE_KEY] = None


def bibtex(keys=None) -> str:
    """BibTeX of ``keys`` (default: :func:`used`), one entry after another."""
    keys = used() if keys is None else tuple(keys)
    missing = [k for k in keys if k not in REFERENCES]
    if missing:
        raise InputError(f"citation keys {missing} are not defined")
    return "\n\n".join(REFERENCES[k] for k in keys) + "\n"


def summary(keys=None) -> str:
    """One line naming what to cite: ``"cite: key (method); ..."``."""
    keys = used() if keys is None else tuple(keys)
    return "please cite: " + "; ".join(f"{k} ({METHODS.get(k, '')})" for k in keys)
