"""A third-party odometry through the entry-point group ``lf3pm.odometries``, as a package
installs it: a folder on PYTHONPATH holding the plugin's module and its dist-info (the
entry point) runs under ``lf3pm replay --method lio --odometry NAME``, ``lf3pm config``
and replay_seeds with no change to lf3pm; a plugin that does not import or is not an
Odometry adapter, or whose odometry is not installed, is one line and exit status 2."""

import json
import os
import re
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest
import yaml
from scipy.interpolate import CubicSpline

from lf3pm.scenes import build_scene
from lf3pm.trajectory.trajectory import Trajectory

#: The plugin: docs/api.md's example, one file (an odometry whose estimate drifts along x).
API_DOC = Path(__file__).resolve().parents[1] / "docs" / "api.md"
PLUGIN = re.search(r"```python\n# toy_odometry.py\n(.*?)```", API_DOC.read_text(), re.S).group(1)


def install(folder, name, module, source, entry):
    """A package ``name`` in ``folder`` as pip leaves one: its module and a dist-info
    whose entry_points.txt registers ``entry`` (``key = module:Attr``) as an odometry."""
    folder.mkdir(exist_ok=True)
    (folder / f"{module}.py").write_text(textwrap.dedent(source))
    info = folder / f"{name.replace('-', '_')}-0.1.dist-info"
    info.mkdir()
    (info / "METADATA").write_text(f"Metadata-Version: 2.1\nName: {name}\nVersion: 0.1\n")
    (info / "entry_points.txt").write_text(f"[lf3pm.odometries]\n{entry}\n")
    return folder


def run(folder, *args):
    """``python *args`` with the plugin folder on PYTHONPATH, as an installed package is found."""
    env = dict(os.environ, PYTHONPATH=os.pathsep.join([str(folder), os.environ.get("PYTHONPATH", "")]))
    return subprocess.run([sys.executable, *args], capture_output=True, text=True, env=env, timeout=600)


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    """The boxes scene as a map file and a 2 s trajectory across it (CSV)."""
    folder = tmp_path_factory.mktemp("replay")
    np.save(folder / "boxes.npy", build_scene("boxes").points)
    spline = CubicSpline([0.0, 1.0, 2.0], [[-2.0, 0.0, 0.0], [-1.2, 0.3, 0.3], [-0.4, 0.4, 0.0]], bc_type="clamped")
    Trajectory(coefficients=np.transpose(spline.c[::-1], (1, 0, 2)).copy(), durations=np.diff(spline.x)).to_csv(
        folder / "traj.csv"
    )
    return folder


@pytest.fixture(scope="module")
def toy(tmp_path_factory):
    return install(
        tmp_path_factory.mktemp("site") / "site", "toy-odometry", "toy_odometry", PLUGIN, "toy = toy_odometry:Toy"
    )


@pytest.mark.slow
def test_a_plugin_odometry_runs_under_lf3pm_replay(files, toy):
    done = run(
        toy,
        "-m",
        "lf3pm",
        "replay",
        files / "traj.csv",
        "--map",
        files / "boxes.npy",
        "--method",
        "lio",
        "--odometry",
        "toy",
        "--json",
    )
    assert done.returncode == 0, done.stderr
    out = json.loads(done.stdout.strip().splitlines()[-1])
    first = out["runs"][0]
    assert out["odometry"] == "toy" and first["report"]["odometry"] == "Toy odometry"
    assert first["versions"]["toy-odometry"] == "0.1" and first["params"]["lio"]["options"] == {"odometry": "toy"}
    assert first["report"]["params"]["settings"] == {"drift": 0.0} and first["scans"] == 21
    # Without drift it holds the first pose: its error is the distance from there.
    truth, estimate = np.array(first["truth_xyz"]), np.array(first["estimate_xyz"])
    np.testing.assert_allclose(estimate, np.repeat(truth[:1], len(truth), axis=0), atol=1e-9)
    # lf3pm config takes its name too, and shows its settings with the built-in odometries'.
    config = files / "toy.yaml"
    config.write_text("replay: {method: lio, odometry: toy}\n")
    done = run(toy, "-m", "lf3pm", "config", "--config", config)
    assert done.returncode == 0 and "odometry: toy" in done.stdout, done.stderr
    shown = yaml.safe_load(done.stdout)["replay"]["odometries"]
    assert shown["toy"] == {"drift": 0.0} and {"genz", "dlio", "liosam"} <= set(shown)


@pytest.mark.slow
def test_a_plugin_odometry_s_settings_come_from_the_yaml(files, toy):
    """replay.odometries.toy in a --config file: lf3pm config shows it, lf3pm replay runs
    and records it (as the Python API's settings by name), a bad value is one line naming
    the field, exit 2."""
    config = files / "toy_drift.yaml"
    config.write_text("replay:\n  method: lio\n  odometry: toy\n  odometries:\n    toy: {drift: 0.01}\n")
    done = run(toy, "-m", "lf3pm", "config", "--config", config)
    assert done.returncode == 0, done.stderr
    assert yaml.safe_load(done.stdout)["replay"]["odometries"]["toy"] == {"drift": 0.01}
    done = run(
        toy, "-m", "lf3pm", "replay", files / "traj.csv", "--map", files / "boxes.npy", "--config", config, "--json"
    )
    assert done.returncode == 0, done.stderr
    first = json.loads(done.stdout.strip().splitlines()[-1])["runs"][0]
    assert first["report"]["params"]["settings"] == {"drift": 0.01}
    assert first["params"]["lio"]["options"] == {"odometry": "toy", "drift": 0.01}
    assert first["rest"]["drift_m"] == pytest.approx(0.2)  # 20 rest scans at 0.01 m
    bad = files / "toy_bad.yaml"
    bad.write_text("replay: {odometries: {toy: {drift: -1}}}\n")
    for command in (["config"], ["replay", files / "traj.csv", "--map", files / "boxes.npy"]):
        done = run(toy, "-m", "lf3pm", *command, "--config", bad)
        assert done.returncode == 2 and done.stderr.strip() == (
            f"lf3pm: error: {bad}: replay.odometries.toy.drift must be greater than or equal to 0, got -1"
        )


@pytest.mark.slow
def test_a_plugin_odometry_runs_in_replay_seeds_with_its_settings(files, toy):
    """What the studies call: replay_seeds over two seeds, the plugin's settings passed
    as the built-in odometries' are (its section validates them)."""
    script = f"""
import json, lf3pm
series = lf3pm.replay_seeds({str(files / "boxes.npy")!r}, {str(files / "traj.csv")!r}, "vlp16", "lio", seeds=2,
                            odometry="toy", drift=0.01)
runs = [[r.seed, r.report["odometry"], r.report["params"]["settings"], r.rest["drift_m"]] for r in series.results]
print(json.dumps(runs))
try:
    lf3pm.replay({str(files / "boxes.npy")!r}, {str(files / "traj.csv")!r}, "vlp16", "lio", odometry="toy", drift=-1.0)
except lf3pm.Lf3pmError as err:
    print(err)
"""
    done = run(toy, "-c", script)
    assert done.returncode == 0, done.stderr
    lines = done.stdout.strip().splitlines()
    runs = json.loads(lines[-2])
    # The 2 s rest is 20 scans: 0.2 m of drift at 0.01 m per scan.
    assert [r[:3] for r in runs] == [[0, "Toy odometry", {"drift": 0.01}], [1, "Toy odometry", {"drift": 0.01}]]
    assert runs[0][3] == pytest.approx(0.2)
    assert lines[-1] == "toy.drift must be greater than or equal to 0, got -1.0"


@pytest.mark.slow
def test_a_plugin_odometry_runs_in_a_study_s_replay_workers(files, toy, tmp_path):
    """The studies' machinery (experiments.replay_tasks): replays in spawned worker
    processes, each record saved as it ends, find the plugin as the parent does."""
    script = f"""
import json
from pathlib import Path
from lf3pm.experiments.map_cases import MapCase
from lf3pm.experiments.replay_tasks import ReplayTask, load_replay, run_replays

case = MapCase(name="boxes", source="scene:boxes", sensor="vlp16", space="r2", res=0.5)
out = Path({str(tmp_path)!r})
tasks = [ReplayTask(case, {str(files / "traj.csv")!r}, "lio", s, out / f"lio-toy_{{s}}.json", {{"odometry": "toy"}})
         for s in (0, 1)]
run_replays(tasks, 2, lambda *args, **kwargs: None)
print(json.dumps([load_replay(t.path)["rest"]["drift_m"] for t in tasks]))
"""
    done = run(toy, "-c", script)
    assert done.returncode == 0, done.stderr
    assert json.loads(done.stdout.strip().splitlines()[-1]) == [0.0, 0.0]  # it holds the first pose


BROKEN = """
raise ImportError("a dependency of the plugin is missing")
"""
NOT_AN_ADAPTER = '''
class Wrong:
    """Not an lf3pm Odometry."""
'''
MISSING_PACKAGE = PLUGIN.replace('worker = "toy_odometry:ToyWorker"', 'worker = "toy_odometry_backend:Worker"')


@pytest.mark.slow
@pytest.mark.parametrize(
    "source, attribute, message",
    [
        (
            BROKEN,
            "Bad",
            "odometry plugin bad (bad_odometry:Bad) does not import: "
            "ImportError: a dependency of the plugin is missing",
        ),
        (
            NOT_AN_ADAPTER,
            "Wrong",
            "odometry plugin bad (bad_odometry:Wrong): <class 'bad_odometry.Wrong'> "
            "is not a subclass of lf3pm.replays.adapters.Odometry",
        ),
    ],
    ids=["import-error", "wrong-interface"],
)
def test_a_bad_plugin_is_one_line_naming_it(files, tmp_path, source, attribute, message):
    bad = install(tmp_path / "site", "bad-odometry", "bad_odometry", source, f"bad = bad_odometry:{attribute}")
    done = run(bad, "-m", "lf3pm", "replay", files / "traj.csv", "--map", files / "boxes.npy", "--method", "lio")
    assert done.returncode == 2 and done.stderr.strip() == f"lf3pm: error: {message}"


@pytest.mark.slow
def test_a_plugin_whose_odometry_is_not_installed_is_one_line(files, tmp_path):
    """The worker process imports the odometry's worker class; a missing package is one
    line naming the odometry (as for GenZ-LIO or evalio without lf3pm[lio])."""
    missing = install(tmp_path / "site", "toy-odometry", "toy_odometry", MISSING_PACKAGE, "toy = toy_odometry:Toy")
    done = run(
        missing,
        "-m",
        "lf3pm",
        "replay",
        files / "traj.csv",
        "--map",
        files / "boxes.npy",
        "--method",
        "lio",
        "--odometry",
        "toy",
    )
    assert done.returncode == 2, done.stderr
    assert done.stderr.strip().splitlines() == [
        "lf3pm: error: the toy odometry is not installed (No module named 'toy_odometry_backend'): "
        "pip install toy-odometry"
    ]


@pytest.mark.slow
def test_lf3pm_s_own_entry_points_and_a_name_taken(tmp_path):
    """lf3pm's odometries declared as entry points (pyproject.toml) are the registry's own,
    not a clash; another package's odometry under one of their names is refused."""
    own = install(tmp_path / "own", "lf3pm-own", "unused_module", "", "genz = lf3pm.replays.genz:GenZ")
    assert run(own, "-m", "lf3pm", "config").returncode == 0
    clash = PLUGIN.replace('key = "toy"', 'key = "genz"')
    taken = install(tmp_path / "taken", "toy-odometry", "toy_odometry", clash, "genz = toy_odometry:Toy")
    done = run(taken, "-m", "lf3pm", "config")
    assert done.returncode == 2 and done.stderr.strip() == (
        "lf3pm: error: odometry plugin genz (toy_odometry:Toy): the name 'genz' is taken by lf3pm.replays.genz"
    )


def test_register_checks_an_adapter_in_process():
    from lf3pm.replays import registry
    from lf3pm.replays.adapters import Odometry
    from lf3pm.replays.genz import GenZ

    class Unfinished(Odometry):
        key = "unfinished"

    with pytest.raises(registry.PluginError, match=r"Unfinished does not set name, package, version, licence, worker"):
        registry.register(Unfinished)
    with pytest.raises(registry.PluginError, match="is not a subclass of lf3pm.replays.adapters.Odometry"):
        registry.register(object)
    assert registry.register(GenZ) is GenZ and "unfinished" not in registry.odometries()


def test_the_benefit_study_takes_a_plugin_odometry_and_its_settings(tmp_path, monkeypatch):
    """benefit.odometry is checked by the registry (a plugin's name is taken, as
    replay.odometry's), and the replay section's settings for it label the study's LIO
    replays apart from the defaults' (registered in this process as its entry point
    would; the registry restored afterwards)."""
    from lf3pm.config import DEFAULTS, ConfigError
    from lf3pm.experiments.benefit import study
    from lf3pm.experiments.benefit.cases import QUICK
    from lf3pm.experiments.benefit.records import LioRun
    from lf3pm.replays import registry

    (tmp_path / "toy_odometry.py").write_text(textwrap.dedent(PLUGIN))
    monkeypatch.syspath_prepend(str(tmp_path))
    import toy_odometry

    monkeypatch.setattr(registry, "_loaded", dict(registry.odometries()))
    registry.register(toy_odometry.Toy)
    case = QUICK[0]
    assert study.lio_run(case, "toy") == LioRun("toy", "lio-toy")
    drifting = DEFAULTS.replay.model_copy(update={"odometries": {"toy": {"drift": 0.01}}})
    assert study.lio_options("toy", drifting) == {"drift": 0.01}
    labelled = study.lio_run(case, "toy", drifting)
    assert labelled.odometry == "toy" and labelled.label.startswith("lio-toy.") and labelled.label != "lio-toy"
    stated = DEFAULTS.replay.model_copy(update={"odometries": {"toy": {"drift": 0.0}}})
    assert study.lio_run(case, "toy", stated) == LioRun("toy", "lio-toy")  # the defaults, stated
    with pytest.raises(ConfigError, match="benefit.odometry must be 'auto', .*'toy', got 'nothing'"):
        study.run(tmp_path / "out", study.StudySettings.of(odometry="nothing"))
    assert not (tmp_path / "out").exists()
