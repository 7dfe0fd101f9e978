"""Audit a recorded run against its map (issue 42, item 2; docs/real.md): per scan at its
reference pose, the metric of the real points, the simulated scan's metric and predicted
localization error, and real registration from disturbed starts; their summary.

- :func:`audit_run` -- every N-th scan of a run (lf3pm.runs), :class:`RunAudit`;
- :func:`audit_scan` -- one scan, :class:`ScanAudit` (the per-scan record);
- :func:`summarize` -- :class:`AuditSummary`: rank correlations of each prediction with
  each real error, the share inside the predicted interval, the simulated/real ratio,
  the scans furthest off;
- :class:`SelfMap` -- the map from the run's own scans (``--map self``), each audited
  scan's without the scans near it in time;
- :func:`write_audit` -- the CSV, the JSON, the Markdown report and the figures (``lf3pm audit -o``);
- :mod:`lf3pm.audit.calibrate` -- the predicted localization error fitted on a run (``--calibrate``);
- :mod:`lf3pm.audit.sensor_fit` -- a sensor fitted from a run's scans (``lf3pm sensors fit``).
"""

from lf3pm.audit.record import ScanAudit
from lf3pm.audit.report import write_audit
from lf3pm.audit.run_audit import RunAudit, audit_run, check_run
from lf3pm.audit.scan_audit import audit_scan, spread
from lf3pm.audit.self_map import SELF, SelfMap
from lf3pm.audit.summary import AuditSummary, Correlation, OffScan, spearman, summarize

__all__ = [
    "SELF",
    "AuditSummary",
    "Correlation",
    "OffScan",
    "RunAudit",
    "ScanAudit",
    "SelfMap",
    "audit_run",
    "audit_scan",
    "check_run",
    "spearman",
    "spread",
    "summarize",
    "write_audit",
]
