"""`lf3pm experiment ...`: the reproducible studies (tables, figures, summary.json)."""

from __future__ import annotations

from pathlib import Path

import typer
from rich.table import Table

from lf3pm.cli._common import app, check_output, configure, console, option, progress_bar, section_paths, user_errors

experiment_app = typer.Typer(help="Reproducible experiments (tables, figures, summary.json).", no_args_is_help=True)
app.add_typer(experiment_app, name="experiment")


@experiment_app.command("table1")
def experiment_table1(
    out: Path = typer.Option(..., "-o", "--out", help="Output folder."),
    poses: int | None = option("table1.poses"),
    trials: int | None = option("table1.trials"),
    seed: int | None = option("table1.seed"),
):
    """The paper's Table I: q_min, q_n, q_max and MDE on houses, house_meadow, meadow, wall."""
    with user_errors():
        check_output(out, folder=True, parents=True)
        from lf3pm.experiments import table1

        cfg = configure(None, locals(), section_paths("table1", "poses", "trials", "seed"))
        with progress_bar() as step:
            table1.run(out, cfg.table1, disturbance=cfg.mde, progress=step)
        console.print((out / "table1.md").read_text())
        console.print(f"wrote {out / 'summary.json'}, {out / 'table1.md'}, {out / 'table1.png'}")


@experiment_app.command("correlation")
def experiment_correlation(
    out: Path = typer.Option(..., "-o", "--out", help="Output folder."),
    poses_per_map: int | None = option("correlation.poses_per_map"),
    trials: int | None = option("correlation.trials"),
    sensor: str | None = option("sensor"),
    bootstrap: int | None = option("correlation.bootstrap"),
    seed: int | None = option("correlation.seed"),
):
    """Spearman correlation of each predictor with MDE, pooled and within maps."""
    with user_errors():
        check_output(out, folder=True, parents=True)
        from lf3pm.experiments import correlation

        cfg = configure(
            None,
            locals(),
            {"sensor": "sensor", **section_paths("correlation", "poses_per_map", "trials", "bootstrap", "seed")},
        )
        with progress_bar() as step:
            summary = correlation.run(out, cfg.correlation, sensor=cfg.sensor, progress=step)
        table = Table(title=f"Spearman rho with MDE ({summary['params']['poses']} poses)")
        for col in ("predictor", "pooled rho", "95% CI", "mean within-map rho", "95% CI"):
            table.add_column(col)
        for name, p in summary["predictors"].items():
            table.add_row(
                name,
                f"{p['rho']:.2f}",
                f"[{p['ci'][0]:.2f}, {p['ci'][1]:.2f}]",
                f"{p['within_mean_rho']:.2f}",
                f"[{p['within_mean_ci'][0]:.2f}, {p['within_mean_ci'][1]:.2f}]",
            )
        console.print(table)
        console.print(
            f"best within maps: {summary['best_within_map']}; best pooled: "
            f"{summary['best_pooled']}; wrote {out}/summary.json, poses.csv, scatter.png"
        )


@experiment_app.command("gobi")
def experiment_gobi(
    out: Path = typer.Option(..., "-o", "--out", help="Output folder (its SOLM and replays resume on a rerun)."),
    reduced: bool = typer.Option(False, help="A smaller desert (115 x 90 m; the demo's)."),
    seeds: int | None = option("gobi.seeds"),
    seed: int | None = option("gobi.seed"),
):
    """Town -> warehouse guided by q_n, q_min, |dx*|, the default and none; S, localization and LIO."""
    with user_errors():
        check_output(out, folder=True, parents=True)
        from dataclasses import replace

        study = configure(None, locals(), section_paths("gobi", "seeds", "seed")).gobi
        from lf3pm.experiments import gobi

        setup = replace(gobi.REDUCED if reduced else gobi.FULL, seed=study.seed)
        if study.seeds is not None:
            setup = replace(setup, replay_seeds=study.seeds)
        with progress_bar() as step:
            gobi.run(out, setup, progress=step)
        console.print((out / "gobi.md").read_text())
        console.print(f"wrote {out}/summary.json, gobi.md, trajectories.png, along.png, trajectories/")


@experiment_app.command("benefit")
def experiment_benefit(
    out: Path | None = typer.Option(None, "-o", "--out", help="Output folder (an interrupted study resumes there)."),
    quick: bool = typer.Option(
        False,
        help="One seed, on two small maps with one pair each (the package's quick_cases.yaml) or on --cases' maps.",
    ),
    cases: Path | None = typer.Option(
        None,
        "--cases",
        metavar="FILE.yaml",
        help='The maps, sensors, zones and pairs to study (docs/benefit.md, "Your own maps"; '
        "default: the study package's cases.yaml).",
    ),
    seeds: int | None = option("benefit.seeds"),
    workers: int | None = option("benefit.workers"),
    pair_seed: int | None = option("benefit.pair_seed"),
    guidance: list[str] | None = typer.Option(
        None,
        metavar="NAME=CHANNEL:POWER:WEIGHT",
        help="Compare these instead of q_n, q_min, step_norm and the default (repeat; a tuning run).",
    ),
    lio: str | None = option("benefit.lio"),
    odometry: str | None = option("benefit.odometry"),
    config: Path | None = typer.Option(
        None,
        "--config",
        metavar="FILE.yaml",
        help="Parameters from a YAML file: its benefit section, and its replay section's odometry "
        "settings and rest limits for the LIO replays (flags given override it).",
    ),
    frozen: Path | None = typer.Option(
        None,
        metavar="PROTOCOL.yaml",
        help="Run only this protocol: its seeds, pair seed and LIO settings are the defaults (docs/benefit.md).",
    ),
    write_protocol: Path | None = typer.Option(None, metavar="FILE.yaml", help="Write this run's protocol only."),
    reuse: Path | None = typer.Option(
        None,
        metavar="DIR",
        help="Take the SOLMs, plans and replays this run would make alike from DIR (a variant's run).",
    ),
    rules: Path | None = typer.Option(
        None, metavar="PROTOCOL.yaml", help="Its risk rule, fit, statistics, analysis and goals (a variant)."
    ),
):
    """Guided against unguided plans on several maps, judged by localization and LIO replays."""
    with user_errors():
        check_output(out or write_protocol, folder=out is not None, parents=True)
        from lf3pm.experiments import benefit
        from lf3pm.experiments.benefit import protocol as protocols
        from lf3pm.replays import registry

        cfg = configure(config, locals(), section_paths("benefit", "seeds", "workers", "pair_seed", "lio", "odometry"))
        study = cfg.benefit
        if frozen is not None:
            flags = {"seeds": seeds, "pair_seed": pair_seed, "lio": lio, "odometry": odometry}
            given = {k for k, v in flags.items() if v is not None}
            study = protocols.read_protocol(frozen).settle(study, given)
        registry.check_name(study.odometry, "--odometry" if odometry is not None else "benefit.odometry")
        registry.with_settings(cfg, config)  # the odometries' settings, checked by their sections
        from lf3pm.experiments.guidance import parse_guidance

        candidates = [parse_guidance(g) for g in guidance] if guidance else None
        from lf3pm.experiments.benefit.case_file import CASES_FILE, QUICK_FILE, load_cases

        # The repository's cases are read here too, so that a map file missing stops a run at once.
        chosen = load_cases(cases or (QUICK_FILE if quick else CASES_FILE), check_files=write_protocol is None)
        from lf3pm.experiments.benefit.study import StudySettings, freeze

        settings = StudySettings(
            study,
            cfg.replay,
            quick=quick,
            cases=chosen,
            guidance=candidates,
            rules=protocols.DEFAULT_PROTOCOL if rules is None else protocols.read_protocol(rules),
        )
        if write_protocol is not None or out is None:
            digest = freeze(write_protocol, settings, frozen).digest()
            return console.print(f"wrote {write_protocol} (protocol sha256 {digest})", soft_wrap=True)
        with progress_bar() as step:
            benefit.run(out, settings, frozen=frozen, reuse=reuse, progress=step)
        console.print((out / "benefit.md").read_text())
        console.print(f"wrote {out}/summary.json, protocol.yaml, benefit.md, scatter.png, ratios.png, examples/")


@experiment_app.command("benefit-report")
def experiment_benefit_report(
    records: Path = typer.Argument(..., help="A benefit study's folder: its summary.json and pairs.jsonl."),
    out: Path | None = typer.Option(None, "-o", "--out", help="Where to write (default: the records' folder)."),
):
    """The benefit study's report, figures and summary.json again, from its records alone (no map, no replay)."""
    with user_errors():
        from lf3pm.errors import Lf3pmError

        for name in ("summary.json", "pairs.jsonl"):
            if not (records / name).is_file():
                raise Lf3pmError(f"{records}: no {name} (a benefit study's records: lf3pm experiment benefit -o DIR)")
        if out is not None:
            check_output(out, folder=True, parents=True)
        from lf3pm.experiments.benefit.regenerate import regenerate

        regenerate(records, out)
        where = out if out is not None else records
        console.print((where / "benefit.md").read_text())
        console.print(f"wrote {where}/summary.json, benefit.md, scatter.png, ratios.png, maps.png")


def _listed(values: list[str] | None) -> list[str] | None:
    """The values of a repeated option, each also split at commas (None: not given)."""
    return None if not values else [part for value in values for part in value.split(",") if part]


@experiment_app.command("odometries")
def experiment_odometries(
    out: Path = typer.Option(..., "-o", "--out", help="Output folder."),
    scenes: list[str] | None = option("odometries.scenes", metavar="NAME,..."),
    sensors: list[str] | None = option("odometries.sensors", metavar="NAME,..."),
    odometries: list[str] | None = option("odometries.odometries", metavar="NAME,..."),
    seeds: int | None = option("odometries.seeds"),
    seconds: float | None = option("odometries.seconds"),
    settings: str | None = option("odometries.settings", metavar="JSON"),
):
    """The LIO replay's odometries side by side on the same drives: APE, time shift, tilt, ms/scan, rest drift."""
    with user_errors():
        check_output(out, folder=True, parents=True)
        import json

        from lf3pm.config import ConfigError

        try:
            parsed = None if settings is None else json.loads(settings)
        except json.JSONDecodeError as err:
            raise ConfigError(f"--settings is not JSON: {err}") from None
        given = {"scenes": _listed(scenes), "sensors": _listed(sensors), "odometries": _listed(odometries)}
        given.update(seeds=seeds, seconds=seconds, settings=parsed)
        paths = section_paths("odometries", "scenes", "sensors", "odometries", "seeds", "seconds", "settings")
        study = configure(None, given, paths).odometries
        from lf3pm.experiments import odometries as experiment

        experiment.chosen_odometries(study)
        with progress_bar() as step:
            experiment.run(out, study, progress=step)
        console.print((out / "odometries.md").read_text())
        console.print(f"wrote {out}/odometries.md, odometries.json")
