"""Procedural test scenes: point-cloud maps with a known free sensor pose.

The scenes of the LF-3PM paper and of our validation study, each a sum of
simple surface samplers (:mod:`lf3pm.scenes.geometry`) and deterministic per
seed::

    from lf3pm.scenes import build_scene, describe_scenes
    scene = build_scene("houses", seed=0)          # params override the defaults
    scene.points, scene.reference_pose, scene.free_radius

``SCENES`` maps each name to its builder ``build(seed=0, **params) -> Scene``;
see docs/scenes.md for what each scene holds and its parameters.
"""

from __future__ import annotations

from lf3pm.errors import Lf3pmError
from lf3pm.scenes import boxes, gobi, house_meadow, houses, meadow, wall
from lf3pm.scenes.scene import Scene

_MODULES = (houses, house_meadow, meadow, wall, gobi, boxes)

#: Scene name -> builder ``build(seed=0, **params) -> Scene``.
SCENES = {module.NAME: module.build for module in _MODULES}

__all__ = ["SCENES", "Scene", "build_scene", "describe_scenes", "scene_defaults", "scene_names"]


def scene_names() -> list[str]:
    """The scene names, in a fixed order."""
    return list(SCENES)


def describe_scenes() -> list[tuple[str, str]]:
    """(name, one-line description) of every scene."""
    return [(module.NAME, module.DESCRIPTION) for module in _MODULES]


def scene_defaults(name: str) -> dict:
    """The default parameters of scene ``name``."""
    return dict(_module(name).DEFAULTS)


def build_scene(name: str, seed: int = 0, **params) -> Scene:
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
