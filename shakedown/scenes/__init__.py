"""Scene files (TOML) -> typed options, model builders (:mod:`.builders`), analyses
(:mod:`.analyses`), the output folder (:mod:`.output`) and the ``shakedown`` command
(:mod:`.cli`).

The top of the pipeline: may import every other package of :mod:`shakedown`, and
:mod:`crack_networks` by name (lazily, when a scene asks for it).
"""

from .files import (
    ANALYSES,
    DEFAULT_SCENE,
    MODEL_KINDS,
    AnalysisContext,
    Scene,
    analysis_module,
    build,
    builder_module,
    builtin_scenes,
    check_type,
    load_scene,
    resolve_scene_path,
    run_scene,
    scene_from_dict,
    scene_from_string,
    tomllib,
    validate_options,
)

__all__ = [
    "ANALYSES",
    "DEFAULT_SCENE",
    "MODEL_KINDS",
    "AnalysisContext",
    "Scene",
    "analysis_module",
    "build",
    "builder_module",
    "builtin_scenes",
    "check_type",
    "load_scene",
    "resolve_scene_path",
    "run_scene",
    "scene_from_dict",
    "scene_from_string",
    "tomllib",
    "validate_options",
]
