"""What a variant's run takes from a frozen run's folder (experiments/benefit/reuse.py):
only what its protocol makes the same way; files linked, never changed."""

from dataclasses import replace

from lf3pm.config import DEFAULTS
from lf3pm.experiments.benefit.protocol import write_protocol
from lf3pm.experiments.benefit.records import LIO, LOCALIZATION, StudyFolder
from lf3pm.experiments.benefit.reuse import link_reusable, reusable
from lf3pm.experiments.benefit.study import StudySettings, study_protocol
from lf3pm.experiments.map_cases import MapCase

TUNNEL = MapCase("tunnel", "scene:tunnel", "vlp16", "r2", 0.5, 2, ray_stride=4, min_distance=20.0)
ORIENTATION = MapCase("orientation", "scene:orientation", "mid70", "se2", 2.0, 2, yaw_bins=12, yaw_reuse=True)
EVERYTHING = {"solm", "plans", LOCALIZATION, LIO, "predictors"}


def _protocol(cases=(TUNNEL, ORIENTATION), replay=DEFAULTS.replay, **benefit):
    return study_protocol(replace(StudySettings.of(**benefit), replay=replay, cases=tuple(cases)))


def test_the_same_protocol_takes_everything():
    p = _protocol()
    assert reusable(p, p) == {"tunnel": EVERYTHING, "orientation": EVERYTHING}


def test_the_rules_change_nothing_that_is_computed():
    p = _protocol()
    rules = p.model_copy(update={"risk": p.risk.model_copy(update={"median": "all_headings"})})
    assert reusable(p, rules) == {"tunnel": EVERYTHING, "orientation": EVERYTHING}


def test_another_pair_seed_keeps_the_solms_only():
    assert reusable(_protocol(), _protocol(pair_seed=3)) == {"tunnel": {"solm"}, "orientation": {"solm"}}


def test_an_odometrys_settings_keep_localization_and_the_other_maps_lio():
    genz = DEFAULTS.replay.model_copy(update={"odometries": {"genz": {"mapping": {"voxel_size": 0.5}}}})
    taken = reusable(_protocol(), _protocol(replay=genz))
    # the tunnel's VLP-16 runs DLIO, the orientation's Mid-70 GenZ-LIO
    assert taken == {"tunnel": EVERYTHING, "orientation": EVERYTHING - {LIO}}


def test_other_rest_limits_keep_localization_only():
    strict = DEFAULTS.replay.model_copy(update={"rest_speed_limit": 0.01})
    taken = reusable(_protocol(), _protocol(replay=strict))
    assert taken == {name: EVERYTHING - {LIO} for name in ("tunnel", "orientation")}


def test_other_replay_settings_keep_no_replay_other_localization_the_lio():
    p = _protocol()
    for section, field, value, kept in (
        ("replay", "imu_rate", 100.0, {"solm", "plans", "predictors"}),
        ("localization", "scan_voxel", 0.5, EVERYTHING - {LOCALIZATION}),
    ):
        changed = p.model_copy(update={section: {**getattr(p, section), field: value}})
        assert reusable(p, changed) == {"tunnel": kept, "orientation": kept}, section


def test_a_changed_or_moved_case_takes_nothing():
    other = replace(ORIENTATION, sensor="vlp16")
    assert reusable(_protocol(), _protocol(cases=(TUNNEL, other))) == {"tunnel": EVERYTHING}
    assert reusable(_protocol(), _protocol(cases=(ORIENTATION, TUNNEL))) == {}  # each case's pairs: its index


def test_links_leave_the_source_and_what_the_folder_holds(tmp_path):
    source, target = StudyFolder(tmp_path / "frozen"), StudyFolder(tmp_path / "variant")
    p = _protocol(cases=(TUNNEL,))
    write_protocol(source.root / "protocol.yaml", p)
    files = {
        source.solm("tunnel") / "q_n" / "c" / "0": b"solm",
        source.trajectories("tunnel") / "00_omni_none.csv": b"plan",
        source.replays("tunnel") / "00_none_localization_0.json": b"loc",
        source.replays("tunnel") / "00_none_lio_0.json": b"lio",
        source.replays("tunnel") / "00_none_lio-genz_0.json": b"another odometry's",
        source.root / "predictors" / "tunnel" / "00_none.json": b"predictor",
    }
    for path, data in files.items():
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_bytes(data)
    kept = target.replays("tunnel") / "00_none_localization_0.json"
    kept.parent.mkdir(parents=True)
    kept.write_bytes(b"ours")
    assert link_reusable(source.root, p, target, {"tunnel": "lio"}) == {"tunnel": EVERYTHING}
    assert kept.read_bytes() == b"ours"
    lio = target.replays("tunnel") / "00_none_lio_0.json"
    assert lio.stat().st_ino == (source.replays("tunnel") / "00_none_lio_0.json").stat().st_ino
    assert not (target.replays("tunnel") / "00_none_lio-genz_0.json").exists()
    solm = target.solm("tunnel") / "q_n" / "c" / "0"
    assert (
        solm.read_bytes() == b"solm" and solm.stat().st_ino != (source.solm("tunnel") / "q_n" / "c" / "0").stat().st_ino
    )
    assert (target.trajectories("tunnel") / "00_omni_none.csv").read_bytes() == b"plan"
    assert (target.root / "predictors" / "tunnel" / "00_none.json").read_bytes() == b"predictor"
    assert all(path.read_bytes() == data for path, data in files.items())
