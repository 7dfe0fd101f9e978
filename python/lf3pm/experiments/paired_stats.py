"""Paired comparisons of localization error: guided plans against unguided ones.

For each start/goal pair i there is one error per plan, a_i (guided) and b_i
(unguided), each the median over replay seeds. The comparison reports

- the median of the ratios r_i = a_i / b_i, with a percentile bootstrap
  confidence interval over pairs (seeded);
- the two-sided Wilcoxon signed-rank p of log a_i - log b_i (scipy; pairs with
  equal errors are dropped, as the test's ``wilcox`` zero method does);
- the share of pairs where guidance is worse (r_i > 1), and where it is worse beyond
  the replays' own noise: given each plan's errors over seeds, the guided mean
  exceeds the unguided by more than twice the standard error of their difference
  (NaN with one seed);
- failure rates: the share of pairs whose error exceeds ``failure_ape_m`` (1 m);
- the median overheads of path length and duration, a_len / b_len - 1.

How it judges (the bootstrap's resamples, seed and level, the failure line, the margin
of "meaningfully worse") is a :class:`PairedSettings`, its defaults written once here;
a study passes its own (the benefit study: its protocol's ``statistics`` section).
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np

from lf3pm.errors import Lf3pmError


@dataclass(frozen=True)
class PairedSettings:
    """How :func:`compare` judges, with the defaults written once here:
    ``bootstrap_draws`` resamples of the pairs for the median ratio's percentile
    interval, drawn from ``bootstrap_seed``, at confidence ``ci_level``; an error above
    ``failure_ape_m`` (m) counts as a localization failure; a guided plan counts as
    meaningfully worse when its mean error exceeds the unguided one's beyond seed noise
    and by more than ``worse_margin_m`` (m): a centimetre, below which a localization
    error does not matter to a ground robot's planning."""

    bootstrap_draws: int = 2000
    bootstrap_seed: int = 0
    ci_level: float = 0.95
    failure_ape_m: float = 1.0
    worse_margin_m: float = 0.01


#: The default settings (:class:`PairedSettings`' defaults).
PAIRED = PairedSettings()


@dataclass(frozen=True)
class Comparison:
    """Guided plans against their unguided twins over some pairs (:func:`compare`;
    ``pairs`` 0: nothing to compare, every other field NaN; the overheads NaN where no
    lengths or durations were given)."""

    pairs: int
    median_ratio: float = math.nan
    median_ratio_ci95: tuple[float, float] = (math.nan, math.nan)
    wilcoxon_p: float = math.nan
    share_worse: float = math.nan
    share_worse_beyond_noise: float = math.nan
    share_worse_beyond_noise_and_margin: float = math.nan
    failure_rate_guided: float = math.nan
    failure_rate_unguided: float = math.nan
    median_error_guided: float = math.nan
    median_error_unguided: float = math.nan
    median_length_overhead: float = math.nan
    median_duration_overhead: float = math.nan

    def to_json(self) -> dict:
        return asdict(self) if self.pairs else {"pairs": 0}

    @classmethod
    def from_json(cls, d: dict) -> Comparison:
        d = dict(d)
        if "median_ratio_ci95" in d:
            d["median_ratio_ci95"] = tuple(d["median_ratio_ci95"])
        return cls(**d)


def median_ratio_ci(
    ratios,
    *,
    draws: int = PAIRED.bootstrap_draws,
    level: float = PAIRED.ci_level,
    seed: int = PAIRED.bootstrap_seed,
) -> tuple[float, float]:
    """Percentile bootstrap interval of the median of ``ratios`` (resampling pairs)."""
    r = np.asarray(ratios, dtype=np.float64)
    if r.size == 0:
        return (math.nan, math.nan)
    rng = np.random.default_rng(np.random.SeedSequence([int(seed), 0xB007]))
    medians = np.median(r[rng.integers(0, r.size, size=(draws, r.size))], axis=1)
    lo, hi = np.percentile(medians, [50 * (1 - level), 50 * (1 + level)])
    return float(lo), float(hi)


def wilcoxon_p(guided, unguided) -> float:
    """Two-sided Wilcoxon signed-rank p of the paired log errors (NaN with fewer than
    two pairs that differ)."""
    from scipy.stats import wilcoxon

    d = np.log(np.asarray(guided, float)) - np.log(np.asarray(unguided, float))
    d = d[d != 0]
    if d.size < 2:
        return math.nan
    return float(wilcoxon(d).pvalue)


def worse_beyond_noise(guided_seeds, unguided_seeds, margin: float = 0.0) -> float:
    """Share of pairs whose guided mean error exceeds the unguided one by more than
    twice the standard error of the difference and by more than ``margin`` (m)
    (lists of per-seed errors per pair), among the pairs with at least two seeds on
    each side (NaN if none has: no spread to compare with)."""
    flags = []
    for a, b in zip(guided_seeds, unguided_seeds):
        a, b = np.asarray(a, float), np.asarray(b, float)
        if min(a.size, b.size) < 2:
            continue
        se = math.sqrt(a.var(ddof=1) / a.size + b.var(ddof=1) / b.size)
        flags.append(a.mean() - b.mean() > max(2.0 * se, margin))
    return float(np.mean(flags)) if flags else math.nan


def compare(
    guided,
    unguided,
    *,
    guided_length=None,
    unguided_length=None,
    guided_duration=None,
    unguided_duration=None,
    guided_seeds=None,
    unguided_seeds=None,
    settings: PairedSettings = PAIRED,
) -> Comparison:
    """The paired comparison of the module docstring, judged by ``settings`` (the
    bootstrap, the failure line, the worse margin). Errors must be positive and finite;
    ``*_seeds``: each pair's per-seed errors (for the share worse beyond noise). The
    interval's level is ``settings.ci_level`` (the field ``median_ratio_ci95`` keeps its
    name: 0.95 by default)."""
    s = settings
    a, b = np.asarray(guided, float), np.asarray(unguided, float)
    if a.shape != b.shape or a.ndim != 1:
        raise Lf3pmError(f"paired errors need two equal-length lists, got {a.shape} and {b.shape}")
    if not (np.all(np.isfinite(a)) and np.all(np.isfinite(b)) and np.all(a > 0) and np.all(b > 0)):
        raise Lf3pmError("paired errors must be positive and finite")
    ratios = a / b
    out = dict(
        pairs=int(a.size),
        median_ratio=float(np.median(ratios)) if a.size else math.nan,
        median_ratio_ci95=median_ratio_ci(ratios, draws=s.bootstrap_draws, level=s.ci_level, seed=s.bootstrap_seed),
        wilcoxon_p=wilcoxon_p(a, b),
        share_worse=float(np.mean(ratios > 1.0)) if a.size else math.nan,
        share_worse_beyond_noise=(
            worse_beyond_noise(guided_seeds, unguided_seeds) if guided_seeds is not None else math.nan
        ),
        share_worse_beyond_noise_and_margin=(
            worse_beyond_noise(guided_seeds, unguided_seeds, s.worse_margin_m) if guided_seeds is not None else math.nan
        ),
        failure_rate_guided=float(np.mean(a > s.failure_ape_m)) if a.size else math.nan,
        failure_rate_unguided=float(np.mean(b > s.failure_ape_m)) if a.size else math.nan,
        median_error_guided=float(np.median(a)) if a.size else math.nan,
        median_error_unguided=float(np.median(b)) if a.size else math.nan,
    )
    for name, x, y in (("length", guided_length, unguided_length), ("duration", guided_duration, unguided_duration)):
        if x is not None:
            out[f"median_{name}_overhead"] = float(np.median(np.asarray(x, float) / np.asarray(y, float) - 1.0))
    return Comparison(**out)


# --- effects over groups (maps), paired failures, equivalence ---------------------------


def geometric_mean(ratios) -> float:
    """exp(mean log ratio) (NaN where empty)."""
    r = np.asarray(ratios, float)
    return float(np.exp(np.mean(np.log(r)))) if r.size else math.nan


def group_bootstrap(groups, *, draws: int, seed: int, level: float) -> tuple[float, tuple[float, float]]:
    """The geometric mean over groups of each group's geometric-mean ratio (each group,
    a map, weighs the same however many pairs it has), with a percentile interval from
    a two-stage bootstrap: resample the groups with replacement, then the pairs within
    each group drawn (seeded: ``seed``; ``draws`` resamples; ``level`` e.g. 0.95). With
    one group the first stage is moot and the interval is that of its pairs."""
    logs = [np.log(np.asarray(g, float)) for g in groups if len(g)]
    if not logs:
        return math.nan, (math.nan, math.nan)
    estimate = float(np.exp(np.mean([g.mean() for g in logs])))
    rng = np.random.default_rng(np.random.SeedSequence([int(seed), 0x6A95]))
    chosen = rng.integers(0, len(logs), size=(draws, len(logs)))
    means = np.empty(chosen.shape)
    for i, g in enumerate(logs):  # each time a group is drawn, its pairs drawn afresh
        where = chosen == i
        means[where] = g[rng.integers(0, g.size, size=(int(where.sum()), g.size))].mean(axis=1)
    stats = means.mean(axis=1)
    lo, hi = np.exp(np.percentile(stats, [50 * (1 - level), 50 * (1 + level)]))
    return estimate, (float(lo), float(hi))


def sign_test_p(values) -> float:
    """Two-sided exact sign test that ``values`` (e.g. maps' log ratios) centre on 0
    (zeros dropped; NaN where none is left)."""
    from scipy.stats import binomtest

    v = np.asarray(values, float)
    v = v[v != 0]
    if v.size == 0:
        return math.nan
    return float(binomtest(int(np.sum(v > 0)), int(v.size), 0.5).pvalue)


def wilcoxon_exact_p(values) -> float:
    """Two-sided exact Wilcoxon signed-rank p that ``values`` centre on 0 (zeros
    dropped; NaN with fewer than two left)."""
    from scipy.stats import wilcoxon

    v = np.asarray(values, float)
    v = v[v != 0]
    if v.size < 2:
        return math.nan
    return float(wilcoxon(v, method="exact").pvalue)


def minimum_p(n: int) -> float:
    """The smallest two-sided p an exact sign or signed-rank test can give on ``n``
    units (all of one sign): 2 / 2^n (NaN for none)."""
    return 2.0 ** (1 - n) if n > 0 else math.nan


def mcnemar_exact_p(guided_only: int, unguided_only: int) -> float:
    """McNemar's exact test of a paired binary outcome: the two-sided binomial p of the
    discordant pairs (one plan fails, its twin does not) splitting evenly (1 where there
    is none)."""
    from scipy.stats import binomtest

    n = guided_only + unguided_only
    return 1.0 if n == 0 else float(binomtest(guided_only, n, 0.5).pvalue)


def binomial_upper(successes: int, n: int, level: float) -> float:
    """One-sided ``level`` Clopper-Pearson upper bound of a share (NaN for n = 0)."""
    from scipy.stats import beta

    if n == 0:
        return math.nan
    return 1.0 if successes >= n else float(beta.ppf(level, successes + 1, n - successes))


def tost_t_p(values, low: float, high: float) -> float:
    """Two one-sided t tests that the mean of ``values`` (log ratios) lies inside
    (log low, log high): the larger of the two p (NaN with fewer than two values)."""
    from scipy.stats import t

    v = np.asarray(values, float)
    if v.size < 2:
        return math.nan
    se = v.std(ddof=1) / math.sqrt(v.size)
    if se == 0:
        return 0.0 if math.log(low) < v.mean() < math.log(high) else 1.0
    p_low = t.sf((v.mean() - math.log(low)) / se, v.size - 1)
    p_high = t.cdf((v.mean() - math.log(high)) / se, v.size - 1)
    return float(max(p_low, p_high))
