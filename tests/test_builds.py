"""Results do not depend on the instruction set the core was built for, nor on the CPU's
vector extensions (README, Supported CPUs; docs/design.md, Reproducible builds).

The default build has the core twice, for x86-64-v3 and for the portable x86-64. The
reference workload (tests/reference_workload.py: scenes, poses evaluated with their
observation rows, an R2 and an SE(2) SOLM, plans for three robots, L-BFGS) runs once
with each, and once with NumPy's vector kernels above its baseline switched off, as on
an older CPU (on an AVX-512 machine that covers the AVX2 ones; NumPy's AVX-512 arctan2,
exp, log and powers differ in the last bit from the C library's); every array must be
equal to the last bit.
"""

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from lf3pm import _core
from lf3pm.errors import CoreLevelError

WORKLOAD = Path(__file__).with_name("reference_workload.py")


def run_workload(path: Path, **env) -> dict:
    subprocess.run([sys.executable, str(WORKLOAD), str(path)], env={**os.environ, **env}, check=True, timeout=600)
    with np.load(path) as data:
        return {key: data[key] for key in data.files}


def differences(a: dict, b: dict) -> list:
    """The arrays of a and b that are not the same bits, with their largest relative difference."""
    assert a.keys() == b.keys()
    out = []
    for key in sorted(a):
        x, y = a[key], b[key]
        if key == "arch" or (x.dtype == y.dtype and x.shape == y.shape and x.tobytes() == y.tobytes()):
            continue
        if x.shape != y.shape:
            out.append(f"{key}: shape {x.shape} against {y.shape}")
            continue
        rel = np.abs(x - y) / np.maximum(np.abs(x), np.finfo(float).tiny)
        out.append(f"{key}: {int(np.sum(x != y))} of {x.size} values differ, by up to {np.nanmax(rel):.2g} relative")
    return out


@pytest.fixture(scope="module")
def reference(tmp_path_factory) -> dict:
    """The workload on the level this machine loads by default."""
    return run_workload(tmp_path_factory.mktemp("workload") / "default.npz")


def numpy_dispatched_features() -> list:
    """NumPy's dispatch targets (vector kernels above its baseline) this CPU has."""
    try:
        from numpy._core import _multiarray_umath as umath
    except ImportError:  # NumPy 1.x
        from numpy.core import _multiarray_umath as umath
    found = umath.__cpu_features__
    return [target for target in umath.__cpu_dispatch__ if found.get(target)]


@pytest.mark.slow
def test_every_level_built_computes_the_same_bits(reference, tmp_path):
    others = [arch for arch in _core.cpu_check.levels if arch != _core.ARCH and _core.cpu_check.runs(arch)]
    if not others:
        pytest.skip(f"this build has one level this CPU runs ({', '.join(_core.cpu_check.levels)})")
    assert str(reference["arch"]) == _core.ARCH
    for arch in others:
        result = run_workload(tmp_path / f"{arch}.npz", LF3PM_CORE=arch)
        assert str(result["arch"]) == arch
        assert differences(reference, result) == [], f"{_core.ARCH} against {arch}"


@pytest.mark.slow
def test_numpy_without_its_vector_kernels_computes_the_same_bits(reference, tmp_path):
    features = numpy_dispatched_features()
    if not features:
        pytest.skip("NumPy runs its baseline kernels on this CPU: there is nothing to switch off")
    result = run_workload(tmp_path / "numpy_baseline.npz", NPY_DISABLE_CPU_FEATURES=" ".join(features))
    assert differences(reference, result) == []


@pytest.mark.slow
def test_a_level_not_built_or_not_run_here_is_one_line(tmp_path):
    for asked, says in (("x86-64-v9", "this build has the core for"), ("", None)):
        run = subprocess.run(
            [sys.executable, "-m", "lf3pm", "sensors"],
            capture_output=True,
            text=True,
            env={**os.environ, "LF3PM_CORE": asked},
            timeout=120,
        )
        if says is None:
            assert run.returncode == 0, run.stderr
            continue
        assert run.returncode == 2
        lines = run.stderr.strip().splitlines()
        assert len(lines) == 1 and "LF3PM_CORE=x86-64-v9" in lines[0] and says in lines[0], run.stderr
    assert issubclass(CoreLevelError, ImportError)
