"""Procedural test scenes: point-cloud maps with a known free sensor pose.

The scenes of the LF-3PM paper and of our validation study, each a sum of
simple surface samplers (:mod:`lf3pm.scenes.geometry`) and deterministic per
seed::

    from lf3pm.scenes import build_scene, describe_scenes
    scene = build_scene("houses", seed=0)          # params override the defaults
    scene.points, scene.reference_pose, scene.free_radius
    scene.zones                                     # {"start": Zone, "goal": Zone} for studies
    scene.volumes                                   # {"start": Volume, "goal": Volume} for flights

``SCENES`` maps each name to its builder ``build(seed=0, **params) -> Scene``;
see docs/scenes.md for what each scene holds and its parameters.
"""

from __future__ import annotations

from lf3pm.config import DEFAULTS as CONFIG
from lf3pm.errors import Lf3pmError
from lf3pm.scenes import (
    atrium,
    boxes,
    bridge,
    corridor,
    drift,
    field,
    forest,
    gobi,
    house_meadow,
    houses,
    meadow,
    open_field,
    orientation,
    tunnel,
    wall,
)
from lf3pm.scenes.scene import VOLUME_CLEARANCE, Scene, Volume, Zone, resolve_params

_MODULES = (
    houses,
    house_meadow,
    meadow,
    wall,
    gobi,
    boxes,
    tunnel,
    orientation,
    corridor,
    field,
    # For flights (docs/scenes.md, "Flight scenes"): start and goal volumes, no zones.
    drift,
    forest,
    bridge,
    atrium,
    open_field,
)

#: Scene name -> builder ``build(seed=0, **params) -> Scene``.
SCENES = {module.NAME: module.build for module in _MODULES}

__all__ = [
    "SCENES",
    "VOLUME_CLEARANCE",
    "Scene",
    "Volume",
    "Zone",
    "build_scene",
    "describe_scenes",
    "scene_defaults",
    "scene_names",
    "scene_volumes",
    "scene_zones",
]


def scene_names() -> list[str]:
    """The scene names, in a fixed order."""
    return list(SCENES)


def describe_scenes() -> list[tuple[str, str]]:
    """(name, one-line description) of every scene."""
    return [(module.NAME, module.DESCRIPTION) for module in _MODULES]


def scene_defaults(name: str) -> dict:
    """The default parameters of scene ``name``."""
    return dict(_module(name).DEFAULTS)


def scene_zones(name: str, **params) -> dict:
    """The planning-study zones of scene ``name`` with ``params`` (name -> :class:`Zone`;
    empty for scenes without any), without building the scene: the same rectangles as
    ``build_scene(name, **params).zones``. A drawn position can still fall on an
    obstacle (a box, a pillar): keep the SOLM's traversable cells."""
    module = _module(name)
    zones = getattr(module, "zones", None)
    return zones(resolve_params(module.NAME, module.DEFAULTS, params)) if zones else {}


def scene_volumes(name: str, **params) -> dict:
    """The flight volumes of scene ``name`` with ``params`` (name -> :class:`Volume`; empty
    for scenes without any), without building the scene: the same boxes as
    ``build_scene(name, **params).volumes``, which the builder checks are free (no map
    point within ``VOLUME_CLEARANCE`` of them)."""
    module = _module(name)
    volumes = getattr(module, "volumes", None)
    boxes = volumes(resolve_params(module.NAME, module.DEFAULTS, params)) if volumes else {}
    return {key: Volume(*map(float, box)) for key, box in boxes.items()}


def build_scene(name: str, seed: int = CONFIG.scene.seed, **params) -> Scene:
    """Builds scene ``name`` with ``seed``; ``params`` override its defaults.

    Raises Lf3pmError (one line) for an unknown name, an unknown parameter or
    a bad value.
    """
    return _module(name).build(seed, **params)


def _module(name):
    key = str(name).strip().lower().replace("-", "_")
    for module in _MODULES:
        if module.NAME == key:
            return module
    raise Lf3pmError(f"unknown scene {name!r}; known scenes: {', '.join(SCENES)}")
