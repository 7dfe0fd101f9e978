"""The map of a run from its own scans (`lf3pm audit --map self`, issue 42 item 3): every
scan in the world at its reference pose, and for each audited scan the map without the
scans recorded within a window of it, so that no scan registers against itself (docs/real.md,
"A map from the run itself": what registering against a map that holds the scan costs)."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from lf3pm.config import DEFAULTS, Config
from lf3pm.errors import RunError
from lf3pm.io.run_folder import RUN_MAP_VOXEL
from lf3pm.io.voxel import voxel_downsample
from lf3pm.map import Map, load_map
from lf3pm.runs import Run

#: What ``--map`` names to build the map from the run itself.
SELF = "self"


@dataclass(frozen=True)
class SelfMap:
    """A run's scans in the world at their reference poses, each reduced to one point per
    ``voxel`` (the voxel a run folder read as a map has), with their ``stamps``. Memory:
    the run's scans so reduced (the map, times how often a surface was seen).
    :meth:`around` is the map an audited scan is measured against."""

    run: str
    stamps: np.ndarray
    clouds: tuple[np.ndarray, ...]
    window: float
    voxel: float
    config: Config

    @classmethod
    def of_run(
        cls,
        run,
        config: Config | None = None,
        *,
        progress: Callable[[int, int | None], None] | None = None,
    ) -> SelfMap:
        """Reads ``run`` once (``config``'s run section, bad scans skipped) and keeps its
        scans in the world; the run section's ``exclude_window`` (s): scans within it of an
        audited scan stay out of that scan's map (0: the scan itself alone). The map section's voxel, where
        set, replaces :data:`RUN_MAP_VOXEL`. ``progress(read, total)`` after each scan
        (bad scans counted as read; total None where the run cannot say). RunError where
        the window leaves some scan no map."""
        config = DEFAULTS if config is None else config
        window = config.run.exclude_window
        voxel = config.map.voxel or RUN_MAP_VOXEL
        stamps, clouds = [], []
        with Run(run, config.run, skip_bad=True) as opened:
            if opened.reference is None:
                raise RunError(f"{opened.path}: the run has no reference poses to build its map at")
            total = opened.scan_count()
            for scan in opened.scans():
                rotation, origin = scan.pose[:3, :3], scan.pose[:3, 3]
                clouds.append(voxel_downsample(scan.points @ rotation.T + origin, voxel))
                stamps.append(scan.stamp)
                if progress is not None:
                    progress(scan.index + 1, total)
        if not clouds:
            raise RunError(f"{run}: no scan to build the map from")
        built = cls(str(run), np.asarray(stamps), tuple(clouds), float(window), voxel, config)
        for stamp in built.stamps:  # before any scan is audited: each must have a map
            if built.left_out(stamp).all():
                raise RunError(
                    f"{run}: every scan lies within {window:g} s of the scan at {stamp:.6f} s: "
                    "no map is left for it (a shorter --exclude-window)"
                )
        return built

    def left_out(self, stamp: float) -> np.ndarray:
        """Which scans the map around ``stamp`` leaves out (boolean, one per scan): those
        recorded within the window of it, the scan at ``stamp`` itself included."""
        return np.abs(self.stamps - stamp) <= self.window

    def around(self, stamp: float) -> Map:
        """The map for the scan recorded at ``stamp``: every other scan outside the window,
        one point per voxel, indexed with the map section's association settings."""
        keep = ~self.left_out(stamp)
        points = voxel_downsample(np.concatenate([c for c, k in zip(self.clouds, keep, strict=True) if k]), self.voxel)
        return load_map(points, self.config.map.model_copy(update={"voxel": None}), threads=self.config.scan.threads)

    def whole(self) -> np.ndarray:
        """Every scan's points, one per voxel: the map the figures draw."""
        return voxel_downsample(np.concatenate(self.clouds), self.voxel)

    def describe(self) -> dict:
        """What the audit's JSON and report say of the map."""
        return {
            "source": SELF,
            "run": self.run,
            "scans": len(self.clouds),
            "exclude_window_s": self.window,
            "voxel": self.voxel,
        }
