"""The benefit study: do SOLM-guided plans localize better than the shortest ones?

    lf3pm experiment benefit -o DIR [--cases FILE.yaml] [--quick] [--seeds 3] [--workers 2]

On several maps (procedural scenes built for the question and real maps; ``cases``, read
from cases.yaml beside this package's modules, or a user's own cases file: ``case_file``),
seeded start/goal pairs are drawn from each map's start and goal zones. Each pair is
planned for one robot (omni or diff, alternating) with no metric (``none``) and with
each guidance of :data:`~lf3pm.experiments.guidance.GUIDANCE` (the SOLM channels q_n,
q_min and step_norm as they are, and the shipped default: channel, power and weight
of lf3pm.planner.cost_map). Every plan is replayed with the ``localization`` method
(registration to the prior map from drifting wheel odometry, docs/replay.md) on
``seeds`` seeds, and with ``lio`` too (every plan, or with ``lio="default"`` the
default and unguided ones only). Per pair, a plan's error is its APE rmse
(translation, no alignment), the median over seeds; paired_stats.py compares each
guidance with ``none`` (``analysis``).

Outputs: DIR/summary.json (every pair, plan and replay, the comparisons, the analysis
at the level of the map and the parameters: ``records.Summary``), the records
DIR/pairs.jsonl and DIR/replays.jsonl (one pair, one replay a line), DIR/benefit.md (the
tables: ``report``), DIR/scatter.png (errors of guided against unguided plans),
DIR/ratios.png (ratios per map), DIR/maps.png (each map's effect with its interval),
DIR/examples/*.png (one pair per map over its SOLM: ``figures``). ``lf3pm experiment
benefit-report DIR`` makes the report, figures and summary again from the records alone
(``regenerate``). Intermediate
results (SOLMs, trajectories, one JSON per replay) stay in DIR, so an interrupted
study resumes where it stopped. Replays run in ``workers`` processes (spawn:
small_gicp and the simulator use threads).

Modules: ``records`` (the data model and the folder's layout), ``cases`` (the maps),
``case_file`` (reading cases files), ``study`` (running it: pairs, plans, replays),
``analysis`` (statistics), ``report``
and ``figures`` (which read the records only). The names below are loaded on first
use, so that importing the records does not import the study.
"""


def __getattr__(name: str):
    if name == "run":
        from lf3pm.experiments.benefit.study import run

        return run
    if name in ("CASES", "QUICK"):
        from lf3pm.experiments.benefit import cases

        return getattr(cases, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
