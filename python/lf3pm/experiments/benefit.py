"""The benefit study: do SOLM-guided plans localize better than the shortest ones?

    lf3pm experiment benefit -o DIR [--quick] [--seeds 3] [--workers 2]

On several maps (procedural scenes built for the question and real maps), seeded
start/goal pairs are drawn from each map's start and goal zones. Each pair is
planned for one robot (omni or diff, alternating) with no metric (``none``) and
with each guidance of :data:`GUIDANCE` (the SOLM channels q_n, q_min and
step_norm as they are, and the shipped default: channel, power and weight of
lf3pm.planner.cost_map). Every plan is replayed with the ``localization`` method
(registration to the prior map from drifting wheel odometry, docs/replay.md) on
``seeds`` seeds, and with ``lio`` too (every plan, or with ``lio="default"`` the
default and unguided ones only). Per pair,
a plan's error is its APE rmse (translation, no alignment), the median over
seeds; paired_stats.py compares each guidance with ``none``.

Outputs: DIR/summary.json (every pair, plan and replay, the comparisons and the
parameters), DIR/benefit.md (the tables), DIR/scatter.png (errors of guided
against unguided plans), DIR/ratios.png (ratios per map), DIR/examples/*.png
(one pair per map over its SOLM). Intermediate results (SOLMs, trajectories,
one JSON per replay) stay in DIR, so an interrupted study resumes where it
stopped. Replays run in ``workers`` processes (spawn: small_gicp and the
simulator use threads).
"""

from __future__ import annotations

import json
import math
import time
from dataclasses import asdict, replace
from pathlib import Path

import numpy as np

from lf3pm.atomic import atomic_write
from lf3pm.config import DEFAULTS, BenefitConfig, validated
from lf3pm.errors import Lf3pmError
from lf3pm.experiments.guidance import GUIDANCE, UNGUIDED
from lf3pm.experiments.localization_error import localization_error_fit
from lf3pm.experiments.map_cases import MapCase, build_case_solm, load_case_map
from lf3pm.experiments.paired_stats import FAILURE_APE, WORSE_MARGIN, compare
from lf3pm.experiments.replay_tasks import ReplayTask, load_replay, replay_json, replay_summary, run_replays, write_plan
from lf3pm.experiments.risk import AT_RISK_SHARE, RISK_FACTOR, at_risk, risk_share
from lf3pm.planner.poses import grid_cell
from lf3pm.replays.replay_result import REST_SPEED_LIMIT

#: The reduced Gobi scene of the demo (experiments/gobi.py): town and open desert.
_GOBI = {
    "length": 115.0,
    "width": 90.0,
    "west": 25.0,
    "town_radius": 25.0,
    "warehouse_distance": 60.0,
    "buildings": 4,
    "stones": 150,
}

#: Zones of the two real maps (single scans in their sensor frames), where their ground is
#: sampled densely enough to plan on (docs/benefit.md): the room scan's free floor spans
#: about 5 m, the street sweep's rings of ground need 1.5 m cells.
_ROOM_ZONES = {"start": (1.3, -0.6, 2.3, 0.6), "goal": (4.8, 0.6, 5.9, 1.9)}
_STREET_ZONES = {"start": (-25.0, -25.0, -15.0, -15.0), "goal": (0.0, -25.0, 15.0, -15.0)}

CASES = (
    MapCase(
        "tunnel",
        "scene:tunnel",
        "vlp16",
        "r2",
        0.5,
        8,
        ray_stride=4,
        scene_params={"length": 40.0},
        both_ways=True,
        min_distance=30.0,
    ),
    MapCase(
        "orientation", "scene:orientation", "mid70", "se2", 1.0, 8, yaw_reuse=True, ray_stride=4, min_distance=20.0
    ),
    MapCase(
        "gobi",
        "scene:gobi",
        "mid70",
        "se2",
        1.0,
        8,
        yaw_reuse=True,
        ray_stride=2,
        scene_params=_GOBI,
        bounds=(-15.0, -30.0, 55.0, 30.0),
        zones={"start": (-8.0, -8.0, 8.0, 8.0), "goal": (30.0, -20.0, 45.0, 20.0)},
        min_distance=25.0,
    ),
    MapCase("houses", "scene:houses", "vlp16", "r2", 0.5, 8, ray_stride=4, both_ways=True, min_distance=20.0),
    # The room's halves join through gaps that leave the body 0.28 m on each side.
    MapCase("boxes", "scene:boxes", "vlp16", "r2", 0.25, 6, ray_stride=4, both_ways=True, min_distance=8.0, r_safe=0.2),
    MapCase(
        "street",
        "outdoor_urban64_2021-10-26-16-21-29-468.pcd",
        "vlp16",
        "r2",
        1.5,
        6,
        ray_stride=4,
        bounds=(-30.0, -30.0, 30.0, 30.0),
        zones=_STREET_ZONES,
        both_ways=True,
        min_distance=15.0,
    ),
    # Its start and goal zones join only with 0.1-0.15 m to spare beyond the body.
    MapCase(
        "room",
        "indoor_pcl_room_scan1.pcd",
        "vlp16",
        "r2",
        0.25,
        4,
        ray_stride=4,
        bounds=(-3.0, -2.5, 8.5, 3.5),
        zones=_ROOM_ZONES,
        both_ways=True,
        min_distance=2.5,
        r_safe=0.1,
    ),
    # Appended, not inserted: a case's pairs are drawn from its index (pair seed, index).
    MapCase(
        "corridor",
        "scene:corridor",
        "mid70",
        "se2",
        0.5,
        8,
        yaw_reuse=True,
        ray_stride=4,
        both_ways=True,
        min_distance=30.0,
    ),
    MapCase("field", "scene:field", "mid70", "se2", 1.0, 8, yaw_reuse=True, ray_stride=4, min_distance=60.0),
)

#: `--quick`: two small maps, one pair each, one seed (the test suite's run).
QUICK = (
    replace(CASES[0], pairs=1, scene_params={"length": 20.0, "pillars": 8}, min_distance=20.0),
    replace(CASES[1], pairs=1, res=2.0, yaw_bins=12),
)


def run(
    out: Path,
    *,
    quick: bool = False,
    seeds: int = DEFAULTS.benefit.seeds,
    workers: int = DEFAULTS.benefit.workers,
    pair_seed: int = DEFAULTS.benefit.pair_seed,
    cases: tuple | None = None,
    guidance: tuple | None = None,
    lio: str = DEFAULTS.benefit.lio,
    odometry: str = DEFAULTS.benefit.odometry,
    progress=None,
) -> dict:
    """Runs (or resumes) the study into ``out`` and returns the summary. ``guidance``
    replaces :data:`GUIDANCE` (candidates to compare, e.g. when choosing the default).
    ``lio``: which plans the LIO replays too: ``all``, or ``default`` (the one named
    default and the unguided one: a shorter run). ``odometry``: the LIO's
    (:func:`lio_odometry`); the replays of each keep their own JSONs, so that a second
    odometry's run in the same folder reuses the SOLMs, plans and localization replays."""
    out = Path(out)
    validated(BenefitConfig, "benefit", seeds=seeds, workers=workers, pair_seed=pair_seed, lio=lio, odometry=odometry)
    cases = cases if cases is not None else (QUICK if quick else CASES)
    guidance = tuple(guidance) if guidance is not None else GUIDANCE
    names = [g.name for g in guidance]
    if len(set(names)) != len(names) or "none" in names:
        raise Lf3pmError(f"guidance names must be distinct and not 'none', got {', '.join(names)}")
    lio_names = ["none"] + (names if lio == "all" else [n for n in names if n == "default"])
    if quick:
        seeds = 1
    step = progress or (lambda label, total, advance=1, restart=False: None)
    started = time.perf_counter()
    out.mkdir(parents=True, exist_ok=True)
    records, tasks = [], []
    lio_runs = {case.name: lio_odometry(case, odometry) for case in cases}
    for number, case in enumerate(cases):
        step(f"{case.name}: map and SOLM", len(cases), 0, restart=number == 0)
        solm_path = build_case_solm(case, out / "solm" / f"{case.name}.zarr")
        pairs = _plan_pairs(case, solm_path, out, np.random.SeedSequence([pair_seed, number]), guidance)
        for pair in pairs:
            records.append(pair)
            for name, plan in pair["plans"].items():
                lio_run = lio_runs[case.name]
                for method in ("localization", "lio") if name in lio_names else ("localization",):
                    label, options = (
                        (lio_run["label"], {"odometry": lio_run["odometry"]}) if method == "lio" else (method, {})
                    )
                    for seed in range(seeds):
                        tasks.append(
                            ReplayTask(
                                case,
                                str(out / plan["csv"]),
                                method,
                                seed,
                                replay_path(out, case, pair["pair"], name, label, seed),
                                options,
                            )
                        )
        step(f"{case.name}: {len(pairs)} pairs planned", len(cases))
    run_replays(tasks, workers, step)
    summary = _summarise(
        out, cases, guidance, lio_names[1:], lio_runs, records, seeds, pair_seed, time.perf_counter() - started
    )
    summary["localization_error"] = localization_error_fit(
        out, cases, records, seeds=seeds, pair_seed=pair_seed, step=step
    )
    with atomic_write(out / "summary.json") as fp:
        fp.write(json.dumps(summary, indent=1).encode())
    with atomic_write(out / "benefit.md") as fp:
        fp.write(report(summary).encode())
    from lf3pm.experiments.benefit_figures import example_figures, ratio_figure, scatter_figure

    scatter_figure(summary, out / "scatter.png")
    ratio_figure(summary, out / "ratios.png")
    example_figures(cases, summary, out)
    return summary


# --- maps and SOLMs -------------------------------------------------------------------

# --- pairs and plans ------------------------------------------------------------------


def _plan_pairs(case: MapCase, solm_path: Path, out: Path, seed: np.random.SeedSequence, guidance: tuple) -> list[dict]:
    """``case.pairs`` seeded pairs, each planned with every guidance (a draw that some
    guidance cannot plan is replaced), trajectories written as CSV."""
    from lf3pm.planner.plan import Planner
    from lf3pm.solm import Solm
    from lf3pm.trajectory.robots import Robot

    _, zones = load_case_map(case)
    planner = Planner(Solm.open(solm_path))
    rng = np.random.default_rng(seed)
    folder = out / "trajectories" / case.name
    folder.mkdir(parents=True, exist_ok=True)
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
            continue
        heading = math.atan2(b[1] - a[1], b[0] - a[0])
        start, goal = (a[0], a[1], heading), (b[0], b[1], heading)
        plans, risk = {}, None
        try:
            for g in (UNGUIDED,) + guidance:
                plan = planner.plan(start, goal, robot=robot, metric=g.channel, weight=g.weight, power=g.power)
                if g is UNGUIDED:
                    risk = risk_share(planner.solm, plan.trajectory)
                csv = folder / f"{number:02d}_{robot.kind}_{g.name}.csv"
                write_plan(plan.trajectory, csv, out / "replays" / case.name, _plan_prefix(number, g.name))
                summary = plan.summary()
                plans[g.name] = {
                    "csv": str(csv.relative_to(out)),
                    "length_m": summary["trajectory_length_m"],
                    "duration_s": summary["duration_s"],
                    "violations": summary["violations"],
                    "solm_mean": _solm_means(planner, plan),
                }
        except Lf3pmError:
            continue
        pairs.append(
            {
                "case": case.name,
                "pair": number,
                "robot": robot.kind,
                "start": start,
                "goal": goal,
                "risk_share": risk,
                "at_risk": at_risk(risk),
                "plans": plans,
            }
        )
    return pairs


#: SOLM channels whose mean along each trajectory the summary records (calibration).
CHANNELS = ("q_n", "q_min", "q_max", "step_norm")


def _solm_means(planner, plan) -> dict:
    """Each channel's time mean along the trajectory (at 10 Hz, interpolated, at the
    trajectory's yaw), in the channel's own units (degenerate cells at its cap)."""
    from lf3pm.grid_field import GridField

    s = plan.trajectory.sample(10.0)
    out = {}
    for channel in CHANNELS:
        layer = planner.cost_layer(channel, 1.0)
        g = planner.esdf
        field = GridField(layer.filled, g.x0, g.y0, g.res)
        out[channel] = float(np.mean(field.sample(s["x"], s["y"], s["yaw"])[0]) * layer.scale)
    return out


def _draw(planner, zone, robot, rng, tries: int = 200):
    """A random traversable cell centre inside ``zone`` (None if none found)."""
    g = planner.esdf
    free = g.traversable(robot.r_safe)
    xmin, ymin, xmax, ymax = zone
    for _ in range(tries):
        x, y = rng.uniform(xmin, xmax), rng.uniform(ymin, ymax)
        cell = grid_cell(g, x, y)
        if cell is not None and free[cell[1], cell[0]]:
            return g.x0 + (cell[0] + 0.5) * g.res, g.y0 + (cell[1] + 0.5) * g.res
    return None


# --- replays --------------------------------------------------------------------------


def lio_odometry(case: MapCase, odometry: str) -> dict:
    """The odometry the LIO replays of ``case`` run for the study's ``odometry``
    (one the sensor cannot feed, LIO-SAM without rings: auto's choice) and the label of their JSONs:
    ``lio`` for auto's choice, else ``lio-<name>``."""
    from lf3pm.replays.lio import choose_odometry, runs_on
    from lf3pm.sensors import get_sensor

    sensor = get_sensor(case.sensor)
    if odometry != "auto" and not runs_on(odometry, sensor):
        odometry = "auto"
    chosen, default = choose_odometry(odometry, sensor), choose_odometry("auto", sensor)
    return {"odometry": chosen, "label": "lio" if chosen == default else f"lio-{chosen}"}


def replay_path(out: Path, case: MapCase, pair: int, guidance: str, method: str, seed: int) -> Path:
    """Where the study keeps one replay's JSON (replay_tasks.replay_task); ``method``: the
    replay method, or a LIO's label (:func:`lio_odometry`)."""
    return replay_json(out / "replays" / case.name, _plan_prefix(pair, guidance), method, seed)


def _plan_prefix(pair: int, guidance: str) -> str:
    """The name shared by a plan's replays (replay_tasks.replay_json)."""
    return f"{pair:02d}_{guidance}_"


# --- analysis -------------------------------------------------------------------------


def _summarise(
    out: Path,
    cases,
    guidance: tuple,
    lio_names: list,
    lio_runs: dict,
    records: list,
    seeds: int,
    pair_seed: int,
    seconds: float,
) -> dict:
    by_name = {case.name: case for case in cases}
    replay_seconds = 0.0
    for pair in records:
        case = by_name[pair["case"]]
        for name, plan in pair["plans"].items():
            for method in ("localization", "lio") if name in ["none"] + lio_names else ("localization",):
                label = lio_runs[case.name]["label"] if method == "lio" else method
                runs = [
                    load_replay(p)
                    for p in (replay_path(out, case, pair["pair"], name, label, s) for s in range(seeds))
                    if p.exists()
                ]
                replay_seconds += sum(r["seconds"] for r in runs)
                if runs:
                    plan[method] = {**replay_summary(runs), "scans": runs[0]["scans"]}
    comparisons = {}
    names = [g.name for g in guidance]
    risky, safe = [r for r in records if r["at_risk"]], [r for r in records if not r["at_risk"]]
    for method, compared in (("localization", names), ("lio", lio_names), (STEADY, lio_names)):
        comparisons[method] = {name: _compare(records, name, method) for name in compared}
        comparisons[method]["by_risk"] = {
            name: {"at_risk": _compare(risky, name, method), "no_risk": _compare(safe, name, method)}
            for name in compared
        }
        if "default" in names:
            comparisons[method]["default_by_map"] = {
                case.name: _compare([r for r in records if r["case"] == case.name], "default", method) for case in cases
            }
            comparisons[method]["default_by_robot"] = {
                kind: _compare([r for r in records if r["robot"] == kind], "default", method)
                for kind in sorted({r["robot"] for r in records})
            }
    return {
        "experiment": "benefit",
        "seeds": seeds,
        "pair_seed": pair_seed,
        "runtime_s": seconds,
        "lio_guidance": ["none"] + lio_names,
        "lio_odometry": {name: run["odometry"] for name, run in lio_runs.items()},
        "replay_cpu_s": replay_seconds,
        "failure_ape_m": FAILURE_APE,
        "cases": [asdict(c) for c in cases],
        "guidance": [asdict(g) for g in (UNGUIDED,) + guidance],
        "pairs": records,
        "comparisons": comparisons,
        "lio_rest": rest_counts(records),
        "calibration": _calibration(records),
        "lio_beyond_bound": lio_beyond_bound(records),
        "goal": _goal(comparisons),
    }


#: The bound the issue sets on the LIO's error along a guided plan (m): the report lists
#: every default-guided plan beyond it, beside its unguided plan, so that where and how
#: often the bound fails is read off the study, not looked for.
LIO_BOUND = 0.3


def lio_beyond_bound(records: list, bound: float = LIO_BOUND) -> dict:
    """The pairs whose default-guided plan's LIO APE (median over seeds) exceeds
    ``bound`` m, with the unguided plan's, among the pairs with both replayed."""
    both = [r for r in records if "lio" in r["plans"].get("default", {}) and "lio" in r["plans"]["none"]]
    beyond = [
        {
            "case": r["case"],
            "pair": r["pair"],
            "robot": r["robot"],
            "at_risk": r["at_risk"],
            "guided_m": r["plans"]["default"]["lio"]["ape"],
            "unguided_m": r["plans"]["none"]["lio"]["ape"],
        }
        for r in both
        if r["plans"]["default"]["lio"]["ape"] > bound
    ]
    return {"bound_m": bound, "pairs_replayed": len(both), "pairs": beyond}


def _calibration(records: list) -> dict:
    """How each channel's mean along a trajectory predicts the APE of each replay
    ({"localization": {channel: ...}, "lio": ...}), over every plan replayed so: Spearman
    rho pooled and within maps (mean), and the slope b of log APE = a + b log(mean
    channel) (pooled least squares): the power at which the channel's cost ratios track
    APE ratios."""
    from scipy.stats import spearmanr

    out = {}
    for method in ("localization", "lio"):
        for channel in CHANNELS:
            rows = [
                (pair["case"], plan["solm_mean"][channel], plan[method]["ape"])
                for pair in records
                for plan in pair["plans"].values()
                if method in plan and plan["solm_mean"].get(channel, 0) > 0
            ]
            if len(rows) < 3:
                continue
            case, q, ape = (np.array(c) for c in zip(*rows))
            ape = np.maximum(ape.astype(float), 1e-4)
            within = [
                spearmanr(q[case == c], ape[case == c])[0]
                for c in np.unique(case)
                if np.sum(case == c) >= 5 and np.ptp(ape[case == c]) > 0
            ]
            slope = np.polyfit(np.log(q.astype(float)), np.log(ape), 1)[0]
            out.setdefault(method, {})[channel] = {
                "plans": len(rows),
                "spearman_pooled": float(spearmanr(q, ape)[0]),
                "spearman_within_mean": float(np.nanmean(within)) if within else math.nan,
                "log_log_slope": float(slope),
            }
    return out


#: The LIO comparison restricted to steady starts: per pair, the seeds on which the
#: odometry held still during the rest before both plans (replay_result.rest_motion).
#: Where it did not, it entered the plan moving, and the APE measures that start, not
#: the plan (docs/lio.md, "A still sensor").
STEADY = "lio_steady"


def _compare(records: list, guidance: str, method: str) -> dict:
    if method == STEADY:
        rows = [p for p in (_steady_seeds(r["plans"], guidance) for r in records) if p is not None]
        method = "lio"
    else:
        rows = [r["plans"] for r in records if method in r["plans"][guidance] and method in r["plans"]["none"]]
    if not rows:
        return {"pairs": 0}
    floor = 1e-4  # 0.1 mm: an APE below it is rounding, and ratios need a positive error
    return compare(
        [max(p[guidance][method]["ape"], floor) for p in rows],
        [max(p["none"][method]["ape"], floor) for p in rows],
        guided_length=[p[guidance]["length_m"] for p in rows],
        unguided_length=[p["none"]["length_m"] for p in rows],
        guided_duration=[p[guidance]["duration_s"] for p in rows],
        unguided_duration=[p["none"]["duration_s"] for p in rows],
        guided_seeds=[p[guidance][method]["ape_per_seed"] for p in rows],
        unguided_seeds=[p["none"][method]["ape_per_seed"] for p in rows],
    )


def _steady_seeds(plans: dict, guidance: str):
    """The pair's two plans (none, ``guidance``) with their LIO replays kept on the seeds
    whose rest was steady before both (None: no such seed, or no rest recorded)."""
    a, b = plans[guidance].get("lio"), plans["none"].get("lio")
    if a is None or b is None or "rest_steady_per_seed" not in a or "rest_steady_per_seed" not in b:
        return None
    keep = [k for k, (x, y) in enumerate(zip(a["rest_steady_per_seed"], b["rest_steady_per_seed"])) if x and y]
    if not keep:
        return None

    def kept(run):
        return {
            "ape": float(np.median([run["ape_per_seed"][k] for k in keep])),  # noqa: E731
            "ape_per_seed": [run["ape_per_seed"][k] for k in keep],
        }

    return {"none": {**plans["none"], "lio": kept(b)}, guidance: {**plans[guidance], "lio": kept(a)}}


def rest_counts(records: list) -> dict:
    """Per map: LIO replays in all, and those whose rest was not steady (the odometry
    moved while the sensor stood still)."""
    out = {}
    for pair in records:
        row = out.setdefault(pair["case"], {"replays": 0, "unsteady": 0})
        for plan in pair["plans"].values():
            flags = plan.get("lio", {}).get("rest_steady_per_seed", [])
            row["replays"] += len(flags)
            row["unsteady"] += sum(not f for f in flags)
    return out


def _goal(comparisons: dict) -> dict:
    """The issue's goals for the default guidance, each True or False: on the at-risk
    pairs a median APE ratio of at most 0.3 with Wilcoxon p < 0.01; on the others a
    median ratio within [0.95, 1.05] whose 95 % interval ends at most at 1.10, and
    meaningfully worse (beyond seed noise and by more than paired_stats.WORSE_MARGIN)
    on at most 10 % of them; each under localization and the LIO; a median length
    overhead of at most 15 %. None where a goal cannot be judged: seed noise needs two
    seeds."""
    goal = {}
    for method in ("localization", "lio", STEADY):
        default = comparisons[method]["by_risk"].get("default", {})
        risky, safe = default.get("at_risk", {}), default.get("no_risk", {})
        if risky.get("pairs"):
            goal[f"{method}_at_risk_ratio_at_most_0.3"] = risky["median_ratio"] <= 0.3
            goal[f"{method}_at_risk_wilcoxon_p_below_0.01"] = bool(risky["wilcoxon_p"] < 0.01)
        if safe.get("pairs"):
            goal[f"{method}_no_risk_ratio_within_0.95_1.05"] = 0.95 <= safe["median_ratio"] <= 1.05
            goal[f"{method}_no_risk_ci_upper_at_most_1.10"] = safe["median_ratio_ci95"][1] <= 1.10
            worse = safe["share_worse_beyond_noise_and_margin"]
            goal[f"{method}_no_risk_worse_on_at_most_10pct"] = bool(worse <= 0.1) if math.isfinite(worse) else None
    overall = comparisons["localization"].get("default", {})
    if overall.get("pairs"):
        goal["length_overhead_at_most_15pct"] = overall["median_length_overhead"] <= 0.15
    return goal


def odometry_line(summary: dict) -> str:
    """Which odometry ran the LIO replays of which maps, e.g. "DLIO: tunnel, houses;
    GenZ-LIO: gobi"."""
    from lf3pm.replays.lio import ODOMETRIES

    maps: dict = {}
    for case, odometry in summary.get("lio_odometry", {}).items():
        maps.setdefault(ODOMETRIES[odometry].name, []).append(case)
    return "; ".join(f"{name}: {', '.join(cases)}" for name, cases in maps.items())


def report(summary: dict) -> str:
    """The Markdown tables of a summary."""

    def row(name, c):
        if not c.get("pairs"):
            return f"| {name} | 0 | | | | | | | |"
        lo, hi = c["median_ratio_ci95"]
        share = lambda v: "n/a" if v is None or not math.isfinite(v) else f"{100 * v:.0f} %"  # noqa: E731
        beyond = f"{share(c['share_worse_beyond_noise'])}, {share(c['share_worse_beyond_noise_and_margin'])}"
        return (
            f"| {name} | {c['pairs']} | {c['median_ratio']:.2f} [{lo:.2f}, {hi:.2f}] | {c['wilcoxon_p']:.2g} | "
            f"{100 * c['share_worse']:.0f} % ({beyond}) | {100 * c['failure_rate_guided']:.0f} % / "
            f"{100 * c['failure_rate_unguided']:.0f} % | {100 * c['median_length_overhead']:+.1f} % | "
            f"{100 * c['median_duration_overhead']:+.1f} % | {1000 * c['median_error_guided']:.0f} / "
            f"{1000 * c['median_error_unguided']:.0f} |"
        )

    header = (
        "| guidance | pairs | median APE ratio [95 % CI] | Wilcoxon p | worse (beyond seed noise, "
        f"and by > {100 * WORSE_MARGIN:g} cm) | "
        "failures guided / none "
        f"(APE > {summary['failure_ape_m']:g} m) | length overhead | duration overhead | median APE (mm) "
        "guided / none |\n|---|---|---|---|---|---|---|---|---|"
    )
    specs = "; ".join(
        f"{g['name']}: {g['channel']} to the power {g['power']:g}, weight {g['weight']:g}"
        for g in summary["guidance"]
        if g["name"] != "none"
    )
    lines = [
        "# Benefit study: localization along guided and unguided plans",
        "",
        f"{len(summary['pairs'])} pairs on {len(summary['cases'])} maps, {summary['seeds']} seed(s) per "
        f"replay, pair seed {summary['pair_seed']}. Guidance: {specs}. Runtime "
        f"{summary['runtime_s'] / 60:.0f} min (this invocation; a resumed study counts only its own "
        f"part), replays {summary['replay_cpu_s'] / 60:.0f} CPU-minutes in all.",
        "",
        "## Localization (registration to the prior map from wheel odometry)",
        "",
        header,
    ]
    comps = summary["comparisons"]
    lines += [row(g["name"], comps["localization"][g["name"]]) for g in summary["guidance"] if g["name"] != "none"]
    lio_rows = [row(g["name"], comps["lio"][g["name"]]) for g in summary["guidance"] if g["name"] in comps["lio"]]
    if lio_rows:
        lines += ["", f"## LIO ({odometry_line(summary)})", "", header] + lio_rows
    rest = summary.get("lio_rest", {})
    if any(v["replays"] for v in rest.values()):
        counts = ", ".join(f"{name} {v['unsteady']} of {v['replays']}" for name, v in rest.items() if v["replays"])
        lines += [
            "",
            f"## LIO from steady starts (rest speed at most {REST_SPEED_LIMIT:g} m/s before both plans)",
            "",
            "LIO replays whose odometry moved while the sensor stood still for its rest (faster than "
            f"{REST_SPEED_LIMIT:g} m/s at the rest's end), per map: {counts}. Below, each pair keeps the seeds "
            "on which both plans started steady; a pair with none is left out.",
            "",
            header,
        ]
        lines += [row(g["name"], comps[STEADY][g["name"]]) for g in summary["guidance"] if g["name"] in comps[STEADY]]
    titles = (("localization", "localization"), ("lio", "LIO"), (STEADY, "LIO, steady starts"))
    for method, title in titles:
        if "default_by_map" in comps[method]:
            lines += [
                "",
                f"## Default guidance against none, per map, per robot and at risk ({title})",
                "",
                header.replace("| guidance |", "| pairs of |"),
            ]
            lines += [row(name, c) for name, c in comps[method]["default_by_map"].items()]
            lines += [row(f"{kind} robot", c) for kind, c in comps[method]["default_by_robot"].items()]
            risk = (
                f"at risk (SOLM: >= {100 * AT_RISK_SHARE:.0f} % of the unguided plan's poses degenerate or "
                f"q_n >= {RISK_FACTOR:g} x the map's median)"
            )
            default = comps[method]["by_risk"]["default"]
            lines += [row(risk, default["at_risk"]), row("no risk", default["no_risk"])]
    for method, title in titles:
        by_risk = comps[method].get("by_risk", {})
        if by_risk:
            lines += [
                "",
                f"## Every guidance against none, at risk and no risk ({title})",
                "",
                header.replace("| guidance |", "| guidance, pairs |"),
            ]
            lines += [
                row(f"{name}, {label}", c[key])
                for name, c in by_risk.items()
                for key, label in (("at_risk", "at risk"), ("no_risk", "no risk"))
                if c[key]["pairs"]
            ]
    beyond = summary.get("lio_beyond_bound")
    if beyond and beyond["pairs_replayed"]:
        lines += [
            "",
            f"## Default-guided plans whose LIO error exceeds {beyond['bound_m']:g} m "
            f"({len(beyond['pairs'])} of {beyond['pairs_replayed']} pairs)",
            "",
        ]
        if beyond["pairs"]:
            lines += [
                "| map | pair | robot | at risk | LIO APE guided (m) | LIO APE none (m) |",
                "|---|---|---|---|---|---|",
            ]
            lines += [
                f"| {b['case']} | {b['pair']} | {b['robot']} | {'yes' if b['at_risk'] else 'no'} | "
                f"{b['guided_m']:.2f} | {b['unguided_m']:.2f} |"
                for b in beyond["pairs"]
            ]
    for method, title in (("localization", "localization error"), ("lio", "the LIO's error")):
        cal = summary.get("calibration", {}).get(method)
        if not cal:
            continue
        lines += [
            "",
            f"## Which channel predicts {title} (every plan's mean along its trajectory)",
            "",
            "| channel | plans | Spearman rho pooled | mean rho within maps | slope of log APE on log channel |",
            "|---|---|---|---|---|",
        ]
        lines += [
            f"| {ch} | {c['plans']} | {c['spearman_pooled']:.2f} | {c['spearman_within_mean']:.2f} | "
            f"{c['log_log_slope']:.2f} |"
            for ch, c in cal.items()
        ]
    fit = summary.get("localization_error")
    if fit and "a" in fit:
        lo, hi = (math.exp(fit[k]) for k in ("log_lo", "log_hi"))
        lines += [
            "",
            "## Predicted localization error (lf3pm evaluate's predicted_localization_error_m)",
            "",
            f"log APE = {fit['a']:.2f} + {fit['b']:.2f} log q_n over {fit['samples']} plans without a "
            f"degenerate pose (q_n exact, once per second); 10-90 % interval x{lo:.2f} to x{hi:.2f}. "
            "Each map left out of the fit in turn and predicted:",
            "",
            "| map left out | plans | inside the interval | Spearman within the map | median factor |",
            "|---|---|---|---|---|",
        ]
        for name, v in fit["validation"].items():
            rho = "n/a" if v["spearman_within_map"] is None else f"{v['spearman_within_map']:.2f}"
            lines += [
                f"| {name} | {v['plans']} | {100 * v['share_inside_interval']:.0f} % | {rho} | "
                f"{v['median_factor']:.2f} |"
            ]
    goal = summary["goal"]
    if goal:
        verdict = {True: "yes", False: "no", None: "n/a (one seed)"}
        lines += [
            "",
            "Goal (issue): " + "; ".join(f"{k.replace('_', ' ')}: {verdict[v]}" for k, v in goal.items()) + ".",
        ]
    return "\n".join(lines) + "\n"
