"""The benefit study's maps: procedural scenes built for the question and two real maps,
each a :class:`~lf3pm.experiments.map_cases.MapCase`, read from the package's cases
files (one source: cases.yaml beside this package's modules, and quick_cases.yaml for
``--quick``; the schema: :mod:`lf3pm.experiments.benefit.case_file`)."""

from __future__ import annotations

from lf3pm.experiments.benefit.case_file import CASES_FILE, QUICK_FILE, load_cases

#: The study's nine maps. Their map files may be absent (no shared data folder): a run
#: then stops at the first such case, naming it.
CASES = load_cases(CASES_FILE, check_files=False)

#: `--quick`: two small maps, one pair each, one seed (the test suite's run).
QUICK = load_cases(QUICK_FILE, check_files=False)
