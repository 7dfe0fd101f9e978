"""Running the benefit study: SOLMs, pairs and their plans, the replays, then the
analysis, report and figures (lf3pm.experiments.benefit)."""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from lf3pm.config import DEFAULTS, BenefitConfig, Config, ReplayConfig, configured
from lf3pm.errors import Lf3pmError
from lf3pm.experiments.benefit import analysis
from lf3pm.experiments.benefit.cases import CASES, QUICK
from lf3pm.experiments.benefit.localization_error import localization_error_fit
from lf3pm.experiments.benefit.protocol import (
    DEFAULT_PROTOCOL,
    RISK,
    STATISTICS,
    Goals,
    Protocol,
    ProtocolError,
    RiskRule,
    build,
    check_folder,
    check_frozen,
    read_protocol,
    write_protocol,
)
from lf3pm.experiments.benefit.records import (
    DEFAULT,
    LIO,
    LOCALIZATION,
    NONE,
    AnalysisSettings,
    Comparisons,
    ErrorFit,
    LioRun,
    Pair,
    Parameters,
    Plan,
    Redraw,
    SeedReplays,
    StudyFolder,
    Summary,
    plan_prefix,
    read_replay,
    replay_label,
    write_summary,
)
from lf3pm.experiments.guidance import GUIDANCE, UNGUIDED
from lf3pm.experiments.map_cases import MapCase, build_case_solm, in_polygon, is_polygon, load_case_map, zone_box
from lf3pm.experiments.replay_tasks import ReplayTask, run_replays, write_plan
from lf3pm.experiments.risk import at_risk, risk_share


@dataclass(frozen=True)
class StudySettings:
    """What a run of the study is run with (:func:`run`, :func:`study_protocol`): the
    configuration's ``benefit`` section (replay seeds, workers, pair seed, which plans
    the LIO replays, its odometry) and ``replay`` section (whose ``odometries`` settings
    the LIO runs with and whose rest limits judge its rests: :func:`lio_options`), both
    whole; ``quick``: one seed, on the quick cases unless ``cases`` are given; ``cases``
    (MapCases; None: the study's) and ``guidance`` (None:
    :data:`~lf3pm.experiments.guidance.GUIDANCE`; others: candidates to compare, e.g.
    when choosing the default); ``rules``: the protocol whose at-risk rule,
    localization-error fit, statistics, analysis, goals and name the run takes (a
    variant's). :meth:`of` makes one from a Config and fields by name."""

    benefit: BenefitConfig = DEFAULTS.benefit
    replay: ReplayConfig = DEFAULTS.replay
    quick: bool = False
    cases: tuple | None = None
    guidance: tuple | None = None
    rules: Protocol = DEFAULT_PROTOCOL

    @classmethod
    def of(cls, config: Config | None = None, **given) -> StudySettings:
        """``config``'s benefit and replay sections (None: lf3pm's defaults) with
        ``given``: this class's other fields, and the benefit section's by name
        (``pair_seed=3``; validated there: ConfigError naming ``benefit.<name>``)."""
        own = {k: given.pop(k) for k in ("quick", "cases", "guidance", "rules") if k in given}
        config = configured(config, ("benefit",), "the benefit study", **given)
        return cls(config.benefit, config.replay, **own)


#: A run of the study with lf3pm's defaults.
STUDY = StudySettings()


def run(
    out: Path, settings: StudySettings = STUDY, *, frozen: Path | None = None, reuse: Path | None = None, progress=None
) -> Summary:
    """Runs (or resumes) the study with ``settings`` (:class:`StudySettings`) into
    ``out`` and returns its summary. The replays of each LIO odometry (the benefit
    section's ``odometry``: :func:`lio_run`) keep their own JSONs, so that a second
    odometry's run in the same folder reuses the SOLMs, plans and localization
    replays. ``frozen``: a protocol file the run's protocol (:func:`study_protocol`)
    must equal (ProtocolError naming the first field that differs, before any work).
    The run judges by its protocol's statistics, analysis and goals, writes its
    protocol to DIR/protocol.yaml, and refuses a folder made under another.
    ``reuse``: a study folder made under another protocol (a sensitivity analysis
    beside a frozen run) whose SOLMs, plans and replays this run takes where its
    protocol makes them the same way (lf3pm.experiments.benefit.reuse)."""
    folder = StudyFolder(Path(out))
    protocol = study_protocol(settings)
    if frozen is not None:
        fixed = read_protocol(frozen)
        check_frozen(fixed, protocol, frozen)
        protocol = protocol.model_copy(update={"name": fixed.name, "date": fixed.date})
    if protocol.statistics.ape_floor_m != STATISTICS.ape_floor_m:
        raise ProtocolError(
            f"protocol.statistics.ape_floor_m: this lf3pm floors errors at {STATISTICS.ape_floor_m:g} m only "
            f"(records.APE_FLOOR: its analysis and figures), not {protocol.statistics.ape_floor_m:g}"
        )
    check_folder(folder.root / "protocol.yaml", protocol)
    study, replay = settings.benefit, settings.replay
    cases, guidance, seeds = _resolved(settings)
    pair_seed, statistics = study.pair_seed, protocol.statistics
    names = [g.name for g in guidance]
    lio_names = [NONE] + (names if study.lio == "all" else [n for n in names if n == DEFAULT])
    step = progress or (lambda label, total, advance=1, restart=False: None)
    started = time.perf_counter()
    folder.root.mkdir(parents=True, exist_ok=True)
    write_protocol(folder.root / "protocol.yaml", protocol)
    pairs, tasks, redrawn = [], [], []
    lio_runs = {case.name: lio_run(case, study.odometry, replay) for case in cases}
    options = {case: lio_options(run.odometry, replay) for case, run in lio_runs.items()}
    if reuse is not None:
        from lf3pm.experiments.benefit.reuse import link_reusable

        taken = link_reusable(reuse, protocol, folder, {name: r.label for name, r in lio_runs.items()})
        step(f"reused from {reuse}: {', '.join(f'{c} ({len(p)})' for c, p in taken.items()) or 'nothing'}", 1, 0)
    for number, case in enumerate(cases):
        step(f"{case.name}: map and SOLM", len(cases), 0, restart=number == 0)
        solm_path = build_case_solm(case, folder.solm(case.name))
        drawn = plan_pairs(
            case, solm_path, folder, np.random.SeedSequence([pair_seed, number]), guidance, protocol.risk, redrawn
        )
        for pair in drawn:
            pairs.append(pair)
            for name, plan in pair.plans.items():
                for method in (LOCALIZATION, LIO) if name in lio_names else (LOCALIZATION,):
                    given = {"odometry": lio_runs[case.name].odometry, **options[case.name]} if method == LIO else {}
                    label = replay_label(method, lio_runs[case.name])
                    for seed in range(seeds):
                        path = folder.replay(case.name, pair.number, name, label, seed)
                        tasks.append(ReplayTask(case, str(folder.root / plan.csv), method, seed, path, given))
        step(f"{case.name}: {len(drawn)} pairs planned", len(cases))
    run_replays(tasks, study.workers, step)
    seconds = time.perf_counter() - started  # the runtime the report states: to the replays' end
    pairs, replay_seconds = with_replays(folder, pairs, lio_runs, lio_names, seeds)
    comparisons = analysis.comparisons(pairs, [c.name for c in cases], names, lio_names[1:], statistics)
    fit, predictors = localization_error_fit(
        folder.root, cases, pairs, seeds=seeds, pair_seed=pair_seed, step=step, fit=protocol.localization_fit
    )
    map_analysis = analysis.analyse(pairs, [c.name for c in cases], AnalysisSettings(**protocol.analysis))
    pairs = [
        replace(
            pair,
            plans={
                name: replace(plan, q_n_exact=predictors.get((pair.case, pair.number, name)))
                for name, plan in pair.plans.items()
            },
        )
        for pair in pairs
    ]
    summary = Summary(
        protocol_sha256=protocol.digest(),
        seeds=seeds,
        pair_seed=pair_seed,
        runtime_s=seconds,
        lio_guidance=tuple(lio_names),
        lio_runs=lio_runs,
        odometry_names=odometry_names(lio_runs),
        replay_cpu_s=replay_seconds,
        parameters=Parameters(
            statistics.failure_ape_m,
            statistics.worse_margin_m,
            protocol.risk.share,
            protocol.risk.factor,
            replay.rest_speed_limit,
        ),
        cases=tuple(cases),
        guidance=(UNGUIDED,) + guidance,
        pairs=tuple(pairs),
        comparisons=comparisons,
        lio_rest=analysis.rest_counts(pairs),
        calibration=analysis.calibration(pairs),
        lio_beyond_bound=analysis.lio_beyond_bound(pairs, statistics.lio_bound_m),
        goal=analysis.goal(comparisons, map_analysis, protocol.goals),
        localization_error=ErrorFit(fit),
        map_analysis=map_analysis,
        redrawn=tuple(redrawn),
    )
    write_outputs(folder, summary, protocol.goals)
    return summary


def _resolved(settings: StudySettings) -> tuple[tuple, tuple, int]:
    """(cases, guidance, replay seeds) a run with ``settings`` uses: the given ones or
    the study's (the quick mode's cases and one seed)."""
    quick, cases, guidance = settings.quick, settings.cases, settings.guidance
    cases = tuple(cases) if cases is not None else (QUICK if quick else CASES)
    guidance = tuple(guidance) if guidance is not None else GUIDANCE
    return cases, guidance, 1 if quick else settings.benefit.seeds


def study_protocol(settings: StudySettings = STUDY, *, date: str = "") -> Protocol:
    """The protocol a :func:`run` with ``settings`` runs under (its settings checked
    first: ConfigError or Lf3pmError in one line): the cases, guidance, seeds and LIO
    of ``settings``, and its ``rules``' risk rule, fit, statistics, analysis, goals
    and name."""
    from dataclasses import asdict

    from lf3pm.config import validated
    from lf3pm.experiments.benefit.records import AnalysisSettings
    from lf3pm.replays import registry

    study, replay, rules = settings.benefit, settings.replay, settings.rules
    validated(BenefitConfig, "benefit", **study.model_dump())
    registry.check_name(study.odometry, "benefit.odometry")
    cases, guidance, seeds = _resolved(settings)
    names = [g.name for g in guidance]
    reserved = (NONE, *Comparisons.GROUPS)
    if len(set(names)) != len(names) or any(n in reserved for n in names):
        raise Lf3pmError(f"guidance names must be distinct and none of {', '.join(reserved)}, got {', '.join(names)}")
    try:
        analysed = asdict(AnalysisSettings(**rules.analysis))
    except TypeError as err:
        raise ProtocolError(f"protocol.analysis: {err}") from None
    return build(
        cases=cases,
        guidance=guidance,
        pair_seed=study.pair_seed,
        seeds=seeds,
        lio=study.lio,
        odometry=study.odometry,
        chosen={case.name: lio_run(case, study.odometry, replay).odometry for case in cases},
        replay=replay,
        risk=rules.risk,
        statistics=rules.statistics,
        localization_fit=rules.localization_fit,
        analysis=analysed,
        goals=rules.goals,
        name=rules.name,
        date=date,
    )


def freeze(path: Path | None, settings: StudySettings = STUDY, frozen: Path | None = None) -> Protocol:
    """Writes the protocol a :func:`run` with ``settings`` would use, dated today, to
    ``path`` (checked against the protocol file ``frozen`` first, when given); ``path``
    None: ConfigError (the study's -o/--out or --write-protocol is needed)."""
    import datetime

    from lf3pm.config import ConfigError

    if path is None:
        raise ConfigError("-o/--out is required (or --write-protocol FILE)")
    protocol = study_protocol(settings, date=datetime.datetime.now(datetime.UTC).date().isoformat())
    if frozen is not None:
        check_frozen(read_protocol(frozen), protocol, frozen)
    write_protocol(path, protocol)
    return protocol


def write_outputs(folder: StudyFolder, summary: Summary, goals: Goals) -> None:
    """summary.json, the report (its goals described by ``goals``, the protocol's) and
    the figures of ``summary`` into ``folder``."""
    from lf3pm.atomic import atomic_write
    from lf3pm.experiments.benefit.figures import example_figures, forest_figure, ratio_figure, scatter_figure
    from lf3pm.experiments.benefit.records import write_records
    from lf3pm.experiments.benefit.report import report

    write_summary(folder.summary, summary)
    write_records(folder, summary)
    with atomic_write(folder.report) as fp:
        fp.write(report(summary, goals).encode())
    scatter_figure(summary, folder.root / "scatter.png")
    ratio_figure(summary, folder.root / "ratios.png")
    forest_figure(summary, folder.forest)
    example_figures(summary, folder)


# --- pairs and plans ------------------------------------------------------------------


def plan_pairs(
    case: MapCase,
    solm_path: Path,
    folder: StudyFolder,
    seed: np.random.SeedSequence,
    guidance: tuple,
    rule: RiskRule = RISK,
    redrawn: list | None = None,
) -> list[Pair]:
    """``case.pairs`` seeded pairs, each planned with every guidance (a draw that some
    guidance cannot plan is replaced), trajectories written as CSV; at risk or not by
    ``rule`` (the protocol's). Each draw replaced is appended to ``redrawn`` (records.Redraw)."""
    from lf3pm.planner.plan import Planner
    from lf3pm.solm import Solm
    from lf3pm.trajectory.robots import Robot

    _, zones = load_case_map(case)
    planner = Planner(Solm.open(solm_path))
    _check_zones(case, zones, planner.esdf.grid)
    rng = np.random.default_rng(seed)
    trajectories = folder.trajectories(case.name)
    trajectories.mkdir(parents=True, exist_ok=True)
    pairs, attempts = [], 0
    while len(pairs) < case.pairs:
        attempts += 1
        if attempts > 50 * case.pairs:
            raise Lf3pmError(
                f"map case {case.name}: found only {len(pairs)} of {case.pairs} plannable pairs in {attempts - 1} draws"
            )
        number = len(pairs)
        robot = Robot(case.robots[number % len(case.robots)], r_safe=case.r_safe)
        ends = ("goal", "start") if case.both_ways and number % 2 else ("start", "goal")
        a, b = (_draw(planner, zones[end], robot, rng) for end in ends)
        if a is None or b is None or math.hypot(b[0] - a[0], b[1] - a[1]) < case.min_distance:
            if redrawn is not None:
                why = (
                    "no free cell in a zone" if a is None or b is None else f"ends closer than {case.min_distance:g} m"
                )
                redrawn.append(Redraw(case.name, attempts - 1, why))
            continue
        heading = math.atan2(b[1] - a[1], b[0] - a[0])
        yaw_a, yaw_b = (_yaw(case, end, heading, rng) for end in ends)
        start, goal = (a[0], a[1], yaw_a), (b[0], b[1], yaw_b)
        plans, risk = {}, None
        try:
            for g in (UNGUIDED,) + guidance:
                plan = planner.plan(start, goal, robot=robot, metric=g.channel, weight=g.weight, power=g.power)
                if g is UNGUIDED:
                    risk = risk_share(planner.solm, plan.trajectory, rule=rule)
                csv = trajectories / f"{number:02d}_{robot.kind}_{g.name}.csv"
                write_plan(plan.trajectory, csv, folder.replays(case.name), plan_prefix(number, g.name))
                summary = plan.summary()
                plans[g.name] = Plan(
                    guidance=g.name,
                    csv=str(csv.relative_to(folder.root)),
                    length_m=summary["trajectory_length_m"],
                    duration_s=summary["duration_s"],
                    violations=summary["violations"],
                    solm_mean=_solm_means(planner, plan),
                )
        except Lf3pmError as err:
            if redrawn is not None:
                redrawn.append(
                    Redraw(case.name, attempts - 1, f"{g.name} could not plan it: {str(err).splitlines()[0]}")
                )
            continue
        pairs.append(Pair(case.name, number, robot.kind, start, goal, risk, at_risk(risk, rule), plans))
    return pairs


def _solm_means(planner, plan) -> dict:
    """Each channel's time mean along the trajectory (at 10 Hz, interpolated, at the
    trajectory's yaw), in the channel's own units (degenerate cells at its cap)."""
    from lf3pm.grid_field import GridField

    s = plan.trajectory.sample(10.0)
    out = {}
    for channel in analysis.CHANNELS:
        layer = planner.cost_layer(channel, 1.0)
        g = planner.esdf
        field = GridField(layer.filled, g.x0, g.y0, g.res)
        out[channel] = float(np.mean(field.sample(s["x"], s["y"], s["yaw"])[0]) * layer.scale)
    return out


def _draw(planner, zone, robot, rng, tries: int = 200):
    """A random traversable cell centre inside ``zone`` (None if none found): a point
    uniform in the zone's box (a polygon's: points outside the polygon count as tries)."""
    free, grid = planner.esdf.traversable(robot.r_safe), planner.esdf.grid
    polygon = zone if is_polygon(zone) else None
    xmin, ymin, xmax, ymax = zone_box(zone)
    for _ in range(tries):
        x, y = rng.uniform(xmin, xmax), rng.uniform(ymin, ymax)
        if polygon is not None and not in_polygon(polygon, x, y):
            continue
        cell = grid.cell_of(x, y)
        if cell is not None and free[cell[1], cell[0]]:
            return grid.centre(*cell)
    return None


def _yaw(case: MapCase, end: str, heading: float, rng) -> float:
    """The yaw of a pose drawn in zone ``end``: uniform in the case's yaw range for it,
    else ``heading`` (no draw: the pairs of cases without yaw ranges stay as they were)."""
    lo_hi = (case.yaw_ranges or {}).get(end)
    return heading if lo_hi is None else float(rng.uniform(*lo_hi))


def _check_zones(case: MapCase, zones: dict, grid) -> None:
    """Lf3pmError naming the case and zone when a zone lies wholly off the SOLM's grid
    (no pair could ever be drawn there)."""
    gx0, gy0 = grid.x0, grid.y0
    gx1, gy1 = gx0 + grid.nx * grid.res, gy0 + grid.ny * grid.res
    for end in ("start", "goal"):
        xmin, ymin, xmax, ymax = zone_box(zones[end])
        if xmax < gx0 or xmin > gx1 or ymax < gy0 or ymin > gy1:
            raise Lf3pmError(
                f"map case {case.name}: its {end} zone ({xmin:g}, {ymin:g}, {xmax:g}, {ymax:g}) lies outside "
                f"the map's grid ({gx0:g}, {gy0:g}, {gx1:g}, {gy1:g})"
            )


# --- replays --------------------------------------------------------------------------


def lio_run(case: MapCase, odometry: str, replay: ReplayConfig = DEFAULTS.replay) -> LioRun:
    """The odometry the LIO replays of ``case`` run for the study's ``odometry`` (one the
    sensor cannot feed, LIO-SAM without rings: auto's choice), and their label (with
    the replay section ``replay``'s settings for it: :func:`lio_options`)."""
    from lf3pm.replays import registry
    from lf3pm.sensors import get_sensor

    sensor = get_sensor(case.sensor)
    if odometry != registry.AUTO and not registry.odometry(odometry).runs_on(sensor):
        odometry = registry.AUTO
    chosen = registry.choose_odometry(odometry, sensor).key
    auto = registry.choose_odometry(registry.AUTO, sensor).key
    return LioRun.of(chosen, auto, lio_options(chosen, replay))


def lio_options(odometry: str, replay: ReplayConfig) -> dict:
    """What the LIO replays of ``odometry`` are given beyond its name: the replay
    section's settings for it and its rest limits, those that differ from lf3pm's
    defaults (none: the replays of the defaults, named as before)."""
    from lf3pm.replays import registry

    options = registry.changed_settings(odometry, replay.odometries.get(odometry, {}))
    for name in ("rest_window", "rest_speed_limit"):
        if getattr(replay, name) != getattr(DEFAULTS.replay, name):
            options[name] = getattr(replay, name)
    return options


def odometry_names(lio_runs: dict[str, LioRun]) -> dict[str, str]:
    """The display name of each odometry the study ran (the registry's)."""
    from lf3pm.replays import registry

    return {run.odometry: registry.odometry(run.odometry).name for run in lio_runs.values()}


def with_replays(
    folder: StudyFolder, pairs: list[Pair], lio_runs: dict[str, LioRun], lio_names: list[str], seeds: int
) -> tuple[list[Pair], float]:
    """``pairs`` with each plan's replays read from the folder (the seeds found), and
    the replays' CPU seconds in all."""
    seconds, out = 0.0, []
    for pair in pairs:
        plans = {}
        for name, plan in pair.plans.items():
            replays = {}
            for method in (LOCALIZATION, LIO) if name in lio_names else (LOCALIZATION,):
                label = replay_label(method, lio_runs[pair.case])
                paths = (folder.replay(pair.case, pair.number, name, label, s) for s in range(seeds))
                runs = [read_replay(p) for p in paths if p.exists()]
                seconds += sum(r.seconds for r in runs)
                if runs:
                    replays[method] = SeedReplays.of(runs)
            plans[name] = replace(plan, replays=replays)
        out.append(replace(pair, plans=plans))
    return out, seconds
