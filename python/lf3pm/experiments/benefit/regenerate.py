"""The benefit study's report, figures and summary.json recomputed from a run's records
alone (``lf3pm experiment benefit-report DIR``): the analysis, then the report and the
figures, which themselves read only the records; judged by the run's protocol
(DIR/protocol.yaml: its statistics and goals), lf3pm's defaults where the folder has
none."""

from __future__ import annotations

import shutil
from dataclasses import replace
from pathlib import Path

from lf3pm.atomic import atomic_write
from lf3pm.experiments.benefit import analysis
from lf3pm.experiments.benefit.figures import example_figures, forest_figure, ratio_figure, scatter_figure
from lf3pm.experiments.benefit.protocol import DEFAULT_PROTOCOL, read_protocol
from lf3pm.experiments.benefit.records import StudyFolder, Summary, read_records, write_summary
from lf3pm.experiments.benefit.report import report


def regenerate(root, out=None, settings=None, protocol=None) -> Summary:
    """The report, figures and summary.json of the study whose records are in ``root``
    (summary.json's setup and pairs.jsonl; records.read_records), recomputed from those
    records alone, into ``out`` (default ``root``): no map is loaded, no replay run. The
    localization-error fit is the run's (it needs the maps); the example figures are
    drawn only where ``out`` holds the study's SOLMs. ``settings``: the analysis's
    (default: the records' own, else AnalysisSettings' defaults). ``protocol``: whose
    statistics and goals judge the comparisons and goals (default: ``root``'s
    protocol.yaml where there is one, else lf3pm's defaults)."""
    source = StudyFolder(Path(root))
    folder = StudyFolder(Path(out) if out is not None else source.root)
    records = read_records(source.root)
    if protocol is None:
        written = source.root / "protocol.yaml"
        protocol = read_protocol(written) if written.exists() else DEFAULT_PROTOCOL
    if settings is None and records.map_analysis is not None:
        settings = records.map_analysis.settings
    pairs, cases = list(records.pairs), [c.name for c in records.cases]
    guided, lio_guided = [g.name for g in records.guided], list(records.lio_guidance[1:])
    comparisons = analysis.comparisons(pairs, cases, guided, lio_guided, protocol.statistics)
    maps = analysis.analyse(pairs, cases, settings)
    summary = replace(
        records,
        comparisons=comparisons,
        lio_rest=analysis.rest_counts(pairs),
        calibration=analysis.calibration(pairs),
        lio_beyond_bound=analysis.lio_beyond_bound(pairs, protocol.statistics.lio_bound_m),
        goal=analysis.goal(comparisons, maps, protocol.goals),
        map_analysis=maps,
    )
    folder.root.mkdir(parents=True, exist_ok=True)
    if folder.root.resolve() != source.root.resolve():
        for name in (source.pair_records, source.replay_records):
            if name.exists():
                shutil.copyfile(name, folder.root / name.name)
    write_summary(folder.summary, summary)
    with atomic_write(folder.report) as fp:
        fp.write(report(summary, protocol.goals).encode())
    scatter_figure(summary, folder.root / "scatter.png")
    ratio_figure(summary, folder.root / "ratios.png")
    forest_figure(summary, folder.forest)
    if all(folder.solm(c).exists() for c in cases):
        example_figures(summary, folder)
    return summary
