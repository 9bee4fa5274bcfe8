"""``shootout compare RUN_A RUN_B``: match cases by ``case_id``, show what changed, flag regressions.

RUN_A is the baseline, RUN_B the candidate. For every case present in both runs and every
metric column, the two values are compared with the rule its task declares (`harness.tasks`:
each metric's ``better`` direction and ``rel``/``abs`` tolerance, recorded in run.json; the
baseline's rule where the two runs declare different ones, and a note names those metrics).
Two rows with one case id that describe different cases (task, mesh, method, params, noise or
seed differ) are listed as ``changed`` and not compared; a folder with a case id in two rows is
refused:

* error-like metrics (lower is better: ``ev_*``, ``dist_mean``, ``hausdorff``, normal errors,
  ``sym_error``, ``lin_error``, ``neg_weights``, ``obtuse_fraction``, ``max_angle``) regress when
  ``b > a + max(rel * |a|, abs)``: worse by more than ``rel`` (1 %) relative *and* more than a
  small absolute amount (lengths are fractions of the bounding-box diagonal, so ``1e-6`` is
  far below anything visible; angles ``0.01`` degrees); a sampled one (``Rule.se``:
  ``surface_dist_mean``) also only beyond ``se_z`` combined standard errors, and a certified
  bracket (``Rule.upper``: ``hausdorff`` to ``hausdorff_upper``) only when the two brackets lie
  apart by more than that;
* quality metrics (higher is better: ``min_angle``, ``radius_ratio_mean``, ``min_eig``) regress
  when ``b < a - max(rel * |a|, abs)``;
* ratios that should be 1 (``volume_ratio``, ``area_ratio``) regress when ``|b - 1|`` grows
  by more than ``max(1 % of |a - 1|, 1e-4)``;
* flags regress when a good value turns bad: ``SYM LOC LIN POS psd operator_symmetric manifold``
  true -> false, ``diverged topology_changed`` false -> true; ``loc_violations`` may not grow;
* a count with a target (``out_faces``, ``Metric.target``: ``target_faces``) regresses when its
  miss of the target grows by more than ``1 % of the target + 2`` (`harness.tasks.base.target_tolerance`,
  which also decides simplification's ``over_target``);
* a value that becomes blank (not measurable any more) regresses; one that appears improves;
  except a sampled metric's when the runs drew another number of points (``hausdorff_samples``,
  0 measuring none): changed;
* time is decided on the stored samples (``times``): it regresses when B is slower with
  statistical significance *and* by a minimum effect: the one-sided Mann-Whitney U test of
  B's samples against A's gives p < ``ALPHA`` (0.01), the lower end of the 95% bootstrap
  confidence interval of the median ratio B/A exceeds ``time_factor`` (1.5: B is, with
  confidence, at least that much slower), B's fastest sample is also more than ``time_factor``
  times A's fastest, and the medians differ by more than 1 ms. A method that does more work
  slows every sample, its fastest included; a burst of load elsewhere slows some samples but
  rarely the fastest, so it widens the interval or moves the median without raising an alarm.
  The ratio is printed with its interval. Cases whose sample counts cannot reach significance
  (the exact test's smallest p, ``1 / C(n_A + n_B, n_A)``, is not below ``ALPHA``: e.g. 3
  samples a side) are inconclusive, never regressions. B's samples are first divided by the
  run's drift (the median over all cases of the ratio of median times; ``--absolute-time``
  turns this off), and the verdict must hold on the raw times too, else it is inconclusive
  (load slows multi-threaded cases more than single-threaded ones, so one drift fits neither).
  A drift of ``time_factor`` or more is itself one regression line for the whole run
  (`whole_run_change`) where neither run oversubscribed its machine, or, on a busier or
  unmeasured machine, where one thread per case was busy and the CPU time changed with the
  wall time.

  Load from other processes slows every sample, the fastest included. ``others_cpu`` is how
  many cores other processes (with several workers, the case's siblings too) kept busy from
  the first sample to the last (from the cold call in runs before 2026-11-27), blank for
  windows under 0.2 s, so runs with ``time_budget: 0`` and millisecond cases often have no
  load check; ``threads_busy`` how many
  threads of the case ran (`threads_used`). A wall-time regression (improvement) of B (A) is
  inconclusive when (threads ``t``, the slower run's load ``o``, the CPU time ratio ``c``):
  - ``t`` > 1 and ``t + o`` exceeds the cores by ``BUSY_CORES`` (0.5) or more: threads waiting
    for a core, and BLAS pools spinning while they wait, grow the wall and CPU time alike;
  - neither run measured its load, and ``t`` > 1 or ``c`` did not grow by ``time_factor``;
  - only the slower run measured its load, ``BUSY_CORES`` or more, and ``c`` did not grow by
    ``time_factor``;
  - the slower run's machine was busier by ``BUSY_CORES`` or more, ``t + o`` exceeded the cores,
    and (for one thread) ``c`` did not grow by more than ``CONTENDED_CPU`` (2) x ``time_factor``;
  - the load stretched the slower samples ``OVERSUBSCRIBED`` (1.25) times or more beyond the
    other run's (`load_stretch`: ``max(1, u / free)``, ``u`` the cores the faster row used,
    ``free`` the cores the load left), ``c`` did not grow by more than ``CONTENDED_CPU`` x
    ``time_factor``, and, where ``c`` grew with the wall time (0.75 of it or more), the change
    divided by that stretch is not past ``time_factor``
    (a waiting process's CPU time itself grows under shared caches and hyperthreads, by 1.95x
    measured here once);
  - the slower run's machine was busier by ``BUSY_CORES`` or more and ``c`` did not grow by
    ``time_factor``.
  Under equal load nothing is excused: on equally quiet machines a wall-time change counts
  whatever its CPU time does (sleeps, I/O, lost parallelism). Rows without samples fall back
  to: median over ``time_factor`` x A's, fastest B repeat slower than slowest A repeat, > 1 ms;
* a case whose result was valid and is not any more (the task's ``invalid_when`` rules, e.g.
  ``diverged``, or a smoothing result farther from the clean surface than its noisy input; both
  runs judged by the rules A's run.json recorded, or the installed kind's, and a note when B
  declares others) regresses, whatever its metrics' own verdicts; one that turns valid improves;
  one invalid for another reason changed;
* a case whose status was ok and is not any more regresses; a case of RUN_A missing in RUN_B
  regresses too (an interrupted or shrunken run must not pass CI); cases new in RUN_B are listed.

Inputs (``input_*``, ``n_vertices``, ``n_faces``) are compared only to warn that the two runs
did not see the same data. ``nnz``, ``peak_rss_mb``, ``genus_change``, ``boundary_loops_change``
are informational. Exit code: 1 if anything regressed, else 0.
"""
from __future__ import annotations

import functools
import html
import json
import math
import statistics
import sys
from dataclasses import dataclass, replace
from pathlib import Path

from .core.params import id_form
from .errors import ShootoutError
from .leaderboard import params_text, validity
from .tasks.base import target_tolerance
from .results import RunFolder, recorded_specs
from .schema import fmt
from .schema import number as _num

TIME_FACTOR = 1.5
TIME_FLOOR_S = 1e-3
BUSY_CORES = 0.5
OVERSUBSCRIBED = 1.25   # the load stretched the slower run's samples this much more than the faster's
CONTENDED_CPU = 2.0     # CPU time of the same work on an oversubscribed machine grows up to this (shared caches, hyperthreads)


@dataclass(frozen=True)
class Rule:
    kind: str            # lower | higher | one | true | false | count | target | info | input
    rel: float = 0.01
    abs: float = 0.0
    se: str = ""         # a sampled metric's standard-error column (`harness.tasks.base.Metric`)
    se_z: float = 3.0
    target: str = ""     # kind target: the column of the count asked for (`Metric.target`)
    upper: str = ""      # a certified bracket's upper end (`Metric.upper`)


COMMON_RULES = {"n_vertices": Rule("input"), "n_faces": Rule("input"), "peak_rss_mb": Rule("info")}


def _rule(m: dict) -> Rule | None:
    """The compare rule a metric's declaration (run.json) gives, or None for one that is not a
    declaration this version could have written (an unknown direction, a tolerance that is not a
    finite number >= 0): the installed kind's rule is used instead."""
    from .tasks.base import BETTER
    try:
        r = Rule(m.get("better", "info"), float(m.get("rel", 0.01)), float(m.get("abs", 0.0)),
                 "" if m.get("se_shared") is True else str(m.get("se") or ""),   # a shared sample: paired, exact
                 float(m.get("se_z", 3.0)), str(m.get("target") or ""),
                 str(m.get("upper") or ""))
    except (AttributeError, TypeError, ValueError):
        return None
    ok = r.kind in BETTER and all(math.isfinite(x) and x >= 0 for x in (r.rel, r.abs, r.se_z))
    return r if ok else None


def rules_from_specs(specs: dict) -> dict[str, dict[str, Rule]]:
    """``{task: {metric: Rule}}`` from task declarations (run.json's ``tasks``); a declaration
    that is not one (`_rule`) is left out, and the installed kind's rule applies."""
    out = {}
    for task, spec in (specs or {}).items():
        metrics = spec.get("metrics") if isinstance(spec, dict) else None
        if not isinstance(metrics, list):
            continue
        rules = {m["name"]: _rule(m) for m in metrics if isinstance(m, dict) and isinstance(m.get("name"), str)}
        out[task] = {k: r for k, r in rules.items() if r is not None}
    return out


def _known_rules() -> dict[str, dict[str, Rule]]:
    from . import tasks
    return rules_from_specs({n: t.spec() for n, t in tasks.all_tasks().items()})


KNOWN = _known_rules()
# metric -> rule over every known task (used when a row's task is not given)
RULES: dict[str, Rule] = {**{m: r for t in KNOWN.values() for m, r in t.items()}, **COMMON_RULES}


def rule_for(metric: str, task: str | None = None, rules: dict | None = None) -> Rule:
    """The compare rule of ``metric`` in ``task`` (from ``rules``, else the known tasks)."""
    for source in (rules or {}, KNOWN):
        r = source.get(task, {}).get(metric) if task else None
        if r is not None:
            return r
    return RULES.get(metric, Rule("info"))


SKIP = {"case_id", "task", "mesh", "noise_model", "noise_level", "seed", "method", "library", "params",
        "status", "error", "time_s", "time_min_s", "time_max_s", "time_q1_s", "time_q3_s", "time_cold_s", "times",
        "time_cpu_s", "cpu_times", "others_cpu", "threads_busy",
        "method_mem_mb", "repeats", "min_angle_hist"}


def _blank(v) -> bool:
    return v is None or (isinstance(v, float) and math.isnan(v)) or v == ""


def judge(metric: str, a, b, row_a=None, row_b=None, rule: Rule | None = None) -> str:
    """'regression' | 'improvement' | 'changed' (beyond tolerance, no direction) | 'same' (within it).
    The tolerance is ``max(rel * |a|, abs)``, and for a sampled metric (``rule.se``) at least
    ``se_z`` times the two rows' combined standard error."""
    rule = rule or rule_for(metric, (row_b or row_a or {}).get("task"))
    if _blank(a) and _blank(b):
        return "same"
    if rule.kind in ("info", "input"):
        if _blank(a) != _blank(b):
            return "changed"
        x, y = _num(a), _num(b)
        if x is not None and y is not None:
            return "same" if abs(x - y) <= 1e-12 * max(abs(x), abs(y), 1.0) else "changed"
        return "same" if str(a) == str(b) else "changed"
    if _blank(b):
        return "regression"
    if _blank(a):
        return "improvement"
    if rule.kind in ("true", "false"):
        good = rule.kind == "true"
        va, vb = bool(a), bool(b)
        if va == vb:
            return "same"
        return "regression" if va == good else "improvement"
    x, y = _num(a), _num(b)
    if x is None or y is None:
        return "same" if str(a) == str(b) else "changed"
    if rule.kind == "count":
        return "same" if x == y else ("regression" if y > x else "improvement")
    if rule.kind == "target":
        t = _num((row_b or {}).get(rule.target)) if rule.target else None
        if t is None:
            return "same" if x == y else "changed"
        miss_a, miss_b = abs(x - t), abs(y - t)
        tol = target_tolerance(t)
        if miss_b > miss_a + tol:
            return "regression"
        return "improvement" if miss_b < miss_a - tol else "same"
    if rule.kind == "one":
        x, y = abs(x - 1.0), abs(y - 1.0)
    if not (math.isfinite(x) and math.isfinite(y)):   # an infinity: its order decides (no tolerance of it)
        if x == y:
            return "same"
        return "regression" if (y > x) == (rule.kind in ("lower", "one")) else "improvement"
    tol = max(rule.rel * abs(x), rule.abs)
    if rule.se:                  # a sampled metric: within SE_Z combined standard errors is the same
        sa, sb = _num((row_a or {}).get(rule.se)), _num((row_b or {}).get(rule.se))
        if sa is not None and sb is not None and math.isfinite(sa) and math.isfinite(sb):
            tol = max(tol, rule.se_z * math.hypot(sa, sb))
    if rule.upper and rule.kind == "lower":     # certified brackets [x, x_up], [y, y_up]: apart, or the same
        xu, yu = _upper(x, (row_a or {}).get(rule.upper)), _upper(y, (row_b or {}).get(rule.upper))
        if y - xu > tol:
            return "regression"
        return "improvement" if x - yu > tol else "same"
    worse = (y - x) if rule.kind in ("lower", "one") else (x - y)
    if worse > tol:
        return "regression"
    if worse < -tol:
        return "improvement"
    return "same"


def _upper(lo: float, up) -> float:
    """A bracket's upper end: the row's ``up`` where it is a finite number at or above ``lo``,
    else ``lo`` (no bracket)."""
    u = _num(up)
    return u if u is not None and math.isfinite(u) and u >= lo else lo


ALPHA = 0.01
BOOTSTRAP = 2000


def time_samples(row: dict, column: str = "times") -> list[float] | None:
    """The row's timed samples (seconds; ``cpu_times`` for their CPU times), or None when the run
    stored none."""
    try:
        t = json.loads(row.get(column) or "null")
    except (TypeError, ValueError):
        return None
    if isinstance(t, list) and t and all(isinstance(x, (int, float)) and not isinstance(x, bool)
                                         and math.isfinite(x) and x >= 0 for x in t):
        return [float(x) for x in t]
    return None


@functools.lru_cache(maxsize=1024)
def _bootstrap_medians(a: tuple, b: tuple):
    """The medians of ``BOOTSTRAP`` seeded resamples of each sample list (the same resamples
    every time: one computation serves the raw and the drift-relative verdicts and the note)."""
    import numpy as np
    A, B = np.asarray(a), np.asarray(b)
    rng = np.random.default_rng(0)
    ra_ = np.median(A[rng.integers(0, A.size, (BOOTSTRAP, A.size))], axis=1)
    rb_ = np.median(B[rng.integers(0, B.size, (BOOTSTRAP, B.size))], axis=1)
    return ra_, rb_


def time_effect(ra: dict, rb: dict, drift: float = 1.0) -> dict | None:
    """Median ratio B/A with a seeded 95% bootstrap interval and one-sided Mann-Whitney p-values
    (``p_slower``: B slower than A; ``p_faster``), or None without samples on both sides.
    B's samples are divided by ``drift`` first (the whole run's speed change, see `run_drift`)."""
    a, b = time_samples(ra), time_samples(rb)
    if a is None or b is None:
        return None
    import numpy as np
    from scipy.stats import mannwhitneyu
    A, B = np.asarray(a), np.asarray(b) / drift
    ma, mb = float(np.median(A)), float(np.median(B))
    ra_, rb_ = _bootstrap_medians(tuple(a), tuple(b))     # B's scale by the drift (a median is scale-equivariant)
    with np.errstate(divide="ignore", invalid="ignore"):
        ratios = (rb_ / drift) / ra_
    lo, hi = (float(x) for x in np.nanpercentile(ratios, [2.5, 97.5]))
    if A.size > 1 or B.size > 1:
        p_slower = float(mannwhitneyu(B, A, alternative="greater").pvalue)
        p_faster = float(mannwhitneyu(B, A, alternative="less").pvalue)
    else:
        p_slower = p_faster = 1.0
    # the smallest one-sided p any outcome can give with these sample sizes is 1 / C(n, k) (exact test)
    conclusive = math.comb(int(A.size + B.size), int(A.size)) > 1 / ALPHA
    min_ratio = float(B.min() / A.min()) if A.min() > 0 else math.inf
    return {"ratio": mb / ma if ma > 0 else math.inf, "ci": (lo, hi), "min_ratio": min_ratio, "p_slower": p_slower,
            "p_faster": p_faster, "n": (A.size, B.size), "conclusive": conclusive, "diff": mb - ma}


def run_drift(rows_a: dict, rows_b: dict) -> float:
    """How much slower B ran overall: the median over cases (ok in both, with samples) of the
    ratio of median times B/A; 1.0 with fewer than 5 such cases. A machine that is busier during
    one run slows every case alike; a changed method moves away from this common factor."""
    import numpy as np
    r = []
    for cid, ra in rows_a.items():
        rb = rows_b.get(cid)
        if rb is None or ra.get("status") != "ok" or rb.get("status") != "ok":
            continue
        a, b = time_samples(ra), time_samples(rb)
        if a and b and np.median(a) > 0:
            r.append(np.median(b) / np.median(a))
    return float(np.median(r)) if len(r) >= 5 else 1.0


def whole_run_change(rows_a: dict, rows_b: dict, drift: float, factor: float, cores: int | None = None,
                     threads: tuple | None = None) -> dict | None:
    """A change entry for the whole run when its drift (`run_drift`) is ``factor`` or more (a
    regression) or ``1 / factor`` or less (an improvement) while neither machine was
    oversubscribed: each run's median load from other processes (``others_cpu`` of its ok rows,
    at least 2; with several workers the siblings are in it) plus the threads one of its cases
    kept busy (median ``threads_busy``; else ``threads``, its threads per case) stayed within
    ``cores`` + 0.25 (without ``cores``: each median below ``BUSY_CORES``), so the machines
    were about as free; otherwise (a busier machine, or a load not measured) only when one
    case of each run kept one thread busy and the median CPU time ratio over the cases (at
    least 5) changed by ``factor`` and by at least 0.75 of the drift (one thread waiting for a
    core does not change its CPU time; waiting threads of a pool may spin). The common change
    is then the code's (or the machine's: the notes say when the runs come from different
    machines). None otherwise."""
    import numpy as np
    if 1.0 / factor < drift < factor:
        return None
    def median_of(rows, value):           # over the ok rows that have it (at least 2)
        v = [value(r) for r in rows.values() if r.get("status") == "ok"]
        v = [x for x in v if x is not None and math.isfinite(x)]
        return float(np.median(v)) if len(v) >= 2 else None
    load = [median_of(rows, lambda r: _num(r.get("others_cpu"))) for rows in (rows_a, rows_b)]
    busy = [median_of(rows, lambda r: _num(r.get("threads_busy"))) for rows in (rows_a, rows_b)]
    used = [median_of(rows, _u) for rows in (rows_a, rows_b)]
    # the cores one case of each run kept busy itself (its siblings are in others_cpu already): its
    # threads_busy, else the run's threads per case, else (older rows) its CPU time over wall time
    mine = [b if b is not None else (t if t else (max(1, round(u)) if u is not None else None))
            for b, t, u in zip(busy, threads or (None, None), used)]
    verdict = "regression" if drift >= factor else "improvement"
    c = [cpu_ratio(ra, rows_b[k]) for k, ra in rows_a.items() if k in rows_b and ra.get("status") == "ok"
         and rows_b[k].get("status") == "ok"]
    c = [x for x in c if x is not None]
    cpu = float(np.median(c)) if len(c) >= 5 else None

    def crowded(o, k):                    # the run's own case plus the others' load beyond the cores
        return o is None or (o + (k or 1) > cores + 0.25 if cores else o >= BUSY_CORES)
    single = all(k is not None and k <= 1 for k in mine)
    if not any(crowded(o, k) for o, k in zip(load, mine)):
        why = (f" on machines neither run oversubscribed (others_cpu median {load[0]:.2g} / {load[1]:.2g} "
               "cores, A / B)")
    elif (single and cpu is not None and (cpu >= factor and cpu >= 0.75 * drift if verdict == "regression"
                                          else cpu <= 1.0 / factor and cpu <= drift / 0.75)):
        # a busy or unmeasured machine: one thread waiting for a core does not change its CPU time, so
        # a CPU time that changed with the wall time is the code's
        why = (f", and {cpu:.3g}x its CPU time with one thread per case (median over {len(c)} cases; other "
               "processes' load " + ("not measured" if None in load else
                                     f"{load[0]:.2g} / {load[1]:.2g} cores, A / B") + ")")
    else:
        return None
    return {"case_id": "(all cases)", "task": "(run)", "case": "the whole run", "metric": "time_s", "a": 1.0,
            "b": round(drift, 4), "verdict": verdict,
            "note": (f"B took {drift:.3g}x A's time in the median case{why}: every case changed alike, which "
                     "each case's verdict, relative to this drift, does not count (--absolute-time judges each "
                     "case on its raw times)")}


def _u(row: dict) -> float | None:
    """Cores the row's samples kept busy: median CPU time over median wall time."""
    import numpy as np
    c, w = time_samples(row, "cpu_times"), time_samples(row)
    return float(np.median(c) / np.median(w)) if c and w and np.median(w) > 0 else None


def cpu_ratio(ra: dict, rb: dict) -> float | None:
    """Median process CPU time per sample, B over A (``cpu_times``), or None without them."""
    a, b = time_samples(ra, "cpu_times"), time_samples(rb, "cpu_times")
    if not a or not b:
        return None
    import numpy as np
    ma = float(np.median(a))
    return float(np.median(b)) / ma if ma > 0 else None


def threads_used(fast: dict, slow: dict, cap: int | None) -> int | None:
    """Threads the case kept busy: the larger ``threads_busy`` of the two rows (threads that ran
    for 5% of the timed window, a spinning BLAS pool included); where both are blank (windows
    under 0.05 s), ``cap``, the run's threads per case (a short multi-threaded sample's CPU time
    is too coarse to tell); for rows written before that column, the faster row's ``u = CPU /
    wall`` rounded (at least 1); else ``cap``."""
    tb = [x for x in (_num(fast.get("threads_busy")), _num(slow.get("threads_busy")))
          if x is not None and math.isfinite(x)]
    if tb:
        return int(max(tb))
    if "threads_busy" in fast or "threads_busy" in slow:   # this version, windows too short to count them
        return cap
    u = _u(fast)
    return max(1, int(round(u))) if u is not None else cap


def busier(ra: dict, rb: dict) -> float | None:
    """Cores other processes kept busy during B's samples minus during A's (``others_cpu``)."""
    a, b = _num(ra.get("others_cpu")), _num(rb.get("others_cpu"))
    return None if a is None or b is None else b - a


def load_stretch(fast: dict, slow: dict, cores: int | None) -> float | None:
    """How much more the other processes' load stretched the slower row's samples than the
    faster row's: a process using ``u = CPU / wall`` cores (the faster row's median sample) on a
    machine with ``free = cores - others_cpu`` cores free runs about ``max(1, u / free)`` times
    slower; the ratio of that for the slower row to that for the faster. 1 under equal load;
    None when the core count, the CPU times or ``others_cpu`` are missing."""
    if not cores:
        return None
    u, of, os_ = _u(fast), _num(fast.get("others_cpu")), _num(slow.get("others_cpu"))
    if u is None or of is None or os_ is None:
        return None
    return max(1.0, u / max(cores - os_, 1e-3)) / max(1.0, u / max(cores - of, 1e-3))


def _load_explains(ra: dict, rb: dict, verdict: str, factor: float, cores: int | None = None,
                   threads: tuple | None = None, ratio: float | None = None, min_ratio: float | None = None) -> bool:
    """Whether other processes' load explains a wall-time change (module docstring): the slower
    run's case kept several threads busy (`threads_used`; ``threads``: A's and B's threads per
    case, where the rows do not say) and its threads
    plus the other processes' load exceeded the ``cores`` by ``BUSY_CORES`` or more (threads
    waiting for a core, and BLAS threads spinning while they wait, grow the wall and the CPU
    time alike, by 80x in one rerun, so neither can tell), or neither run measured its load
    (windows under 0.2 s); or its machine was busier by ``BUSY_CORES`` or more and its case's
    threads plus that load exceeded the cores, for a single-threaded case only where the CPU
    time did not grow by more than ``CONTENDED_CPU`` x ``factor``; or the
    load stretched the slower run's samples ``OVERSUBSCRIBED`` (1.25) times or more beyond the
    faster run's (`load_stretch`) and the CPU time did not grow by more than ``CONTENDED_CPU`` x
    ``factor``; or the slower run's machine was busier by ``BUSY_CORES`` or more and the CPU time
    did not grow by ``factor``; or only the slower run measured its load (the other's sample
    window was too short), ``BUSY_CORES`` or more, and the CPU time did not grow by ``factor``."""
    c = cpu_ratio(ra, rb)
    slow, fast = (rb, ra) if verdict == "regression" else (ra, rb)
    grew = None if c is None else (c if verdict == "regression" else (1.0 / c if c > 0 else math.inf))
    o_slow, o_fast = _num(slow.get("others_cpu")), _num(fast.get("others_cpu"))
    t_slow = threads_used(fast, slow, (threads or (None, None))[1 if verdict == "regression" else 0])
    if (cores and t_slow and t_slow > 1 and o_slow is not None
            and t_slow + o_slow >= cores + BUSY_CORES):
        return True                       # a multi-threaded case on an oversubscribed machine: no time tells
    if o_slow is None and o_fast is None:  # neither window was long enough to measure the load:
        # threads that may have waited (and spun) for a core tell nothing; one thread, its CPU time
        return bool(t_slow and t_slow > 1) or (grew is not None and grew <= factor)
    if o_fast is None:                    # the faster run's load is unknown: it may have been as quiet or not
        return o_slow is not None and o_slow >= BUSY_CORES and not (grew is not None and grew > factor)
    d = busier(ra, rb)
    if d is None:
        return False
    if (cores and t_slow and (d if verdict == "regression" else -d) >= BUSY_CORES and t_slow + o_slow > cores
            and (t_slow > 1 or not (grew is not None and grew > CONTENDED_CPU * factor))):
        return True                       # (one thread waiting for a core does not multiply its CPU time)
    stretch = load_stretch(fast, slow, cores)
    if stretch is not None and stretch >= OVERSUBSCRIBED:
        slowest = min(ratio, min_ratio if min_ratio is not None else ratio) if ratio is not None else None
        if slowest is not None and grew is not None and grew >= 0.75 * ratio and slowest / stretch > factor:
            return False                  # the CPU time grew with the wall time, beyond what the load stretches
        return not (grew is not None and grew > CONTENDED_CPU * factor)
    if grew is not None and grew > factor:
        return False
    return (d if verdict == "regression" else -d) >= BUSY_CORES


def judge_time(ra: dict, rb: dict, factor: float = TIME_FACTOR, drift: float = 1.0, load_rule: bool = True,
               cores: int | None = None, threads: tuple | None = None) -> str:
    """'regression' | 'improvement' | 'inconclusive' | 'same' (see the module docstring);
    ``cores``: the machine's core count (`load_stretch`), when known; ``threads``: A's and B's
    threads per case. With a ``drift`` the raw times must agree: a change that only the drift
    correction makes (an unchanged single-threaded case beside multi-threaded ones that load
    slowed more), or that it hides, is inconclusive."""
    v = _judge_time(ra, rb, factor, drift, load_rule, cores, threads)
    if drift == 1.0 or v == "inconclusive":
        return v
    raw = _judge_time(ra, rb, factor, 1.0, load_rule, cores, threads)
    return v if raw == v else "inconclusive"


def _judge_time(ra: dict, rb: dict, factor: float, drift: float, load_rule: bool, cores: int | None,
                threads: tuple | None) -> str:
    eff = time_effect(ra, rb, drift)
    if eff is not None:
        if not eff["conclusive"]:
            return "inconclusive"
        lo, hi = eff["ci"]
        verdict = "same"
        if eff["p_slower"] < ALPHA and lo > factor and eff["min_ratio"] > factor and eff["diff"] > TIME_FLOOR_S:
            verdict = "regression"
        if eff["p_faster"] < ALPHA and hi < 1 / factor and eff["min_ratio"] < 1 / factor and -eff["diff"] > TIME_FLOOR_S:
            verdict = "improvement"
        slower = (eff["ratio"], eff["min_ratio"]) if verdict == "regression" else (
            1.0 / eff["ratio"] if eff["ratio"] > 0 else math.inf, 1.0 / eff["min_ratio"] if eff["min_ratio"] > 0 else math.inf)
        if verdict != "same" and load_rule and _load_explains(ra, rb, verdict, factor, cores, threads, *slower):
            return "inconclusive"
        return verdict
    a, b = _num(ra.get("time_s")), _num(rb.get("time_s"))
    if a is None or b is None:
        return "same"
    a_max = _num(ra.get("time_max_s")) or a
    b_min = _num(rb.get("time_min_s")) or b
    b_max = _num(rb.get("time_max_s")) or b
    a_min = _num(ra.get("time_min_s")) or a
    if b > factor * a and b_min > a_max and b - a > TIME_FLOOR_S:
        return "regression"
    if a > factor * b and a_min > b_max and a - b > TIME_FLOOR_S:
        return "improvement"
    return "same"


def _time_note(ra: dict, rb: dict, drift: float = 1.0) -> str:
    eff = time_effect(ra, rb, drift)
    if eff is None:
        return (f"A {_fmt(ra.get('time_min_s'))}..{_fmt(ra.get('time_max_s'))}, "
                f"B {_fmt(rb.get('time_min_s'))}..{_fmt(rb.get('time_max_s'))} (no samples stored)")
    lo, hi = eff["ci"]
    p = min(eff["p_slower"], eff["p_faster"])
    rel = f" relative to the run drift {drift:.3g}x" if drift != 1.0 else ""
    c, d = cpu_ratio(ra, rb), busier(ra, rb)
    load = "" if d is None else (f"other processes kept {_num(ra.get('others_cpu')):.2g} / "
                                 f"{_num(rb.get('others_cpu')):.2g} cores busy (A / B), ")
    return (f"B/A {eff['ratio']:.3g}x{rel} [95% CI over these samples {lo:.3g}, {hi:.3g}; two runs of "
            f"the same code differ more], fastest {eff['min_ratio']:.3g}x, "
            f"Mann-Whitney p={p:.2g}, " + ("" if c is None else f"CPU time B/A {c:.3g}x, ") + load +
            f"{eff['n'][0]} vs {eff['n'][1]} samples" + ("" if eff["conclusive"] else " (too few to decide)"))


def _rows(run, specs: dict | None = None, meta: dict | None = None) -> dict[str, dict]:
    """``{case_id: row}`` of a run folder, each row with ``task`` and ``_invalid`` (why it is not a
    valid result, by ``specs``' rules for its task where given, else by its own run's: ``meta``,
    its run.json, read here when not given)."""
    folder = RunFolder(run)
    if not Path(run).is_dir():
        raise ShootoutError(f"{run}: no such run folder")
    from . import tasks
    unknown = folder.missing_task_kinds()
    if unknown:               # a task kind this installation lacks (e.g. a fork's harness/tasks/area.py): its rows
        raise ShootoutError(f"{run}: its task kind(s) {', '.join(unknown)} are not known to this installation "
                            f"(known: {', '.join(tasks.names())}), so their rows could not be compared; compare it "
                            "with the version that made it")
    frames = folder.frames()
    if not frames:
        raise ShootoutError(f"{run}: not a run folder (no task CSV such as smoothing.csv)")
    meta = (folder.read_run_json() or {}) if meta is None else meta
    specs = {**recorded_specs(meta, frames), **(specs or {})}
    out, twice = {}, set()
    for task, df in frames.items():
        why = validity(specs.get(task) or {"name": task}, df, measured=True)
        for rec, bad in zip(df.to_dict("records"), why):
            rec = {k: (None if isinstance(v, float) and math.isnan(v) else v) for k, v in rec.items()}
            rec["task"], rec["_invalid"] = task, bad if rec.get("status") == "ok" else ""
            cid = str(rec["case_id"])
            if cid in out:
                twice.add(cid)
            out[cid] = rec
    if twice:
        raise ShootoutError(f"{run}: {len(twice)} case id(s) appear in more than one row (first: "
                            f"{sorted(twice)[0]}): a run folder holds one row per case; which one to compare is "
                            "not decidable")
    return out


IDENTITY = ("task", "mesh", "method", "params", "noise_model", "noise_level", "seed")


def _label(r: dict) -> str:
    try:
        p = json.loads(r.get("params") or "{}")
    except json.JSONDecodeError:
        p = {}
    ps = params_text(p if isinstance(p, dict) else {})
    lvl, seed = r.get("noise_level"), _num(r.get("seed"))
    noise = str(r.get("noise_model")) if _blank(lvl) else f"{r.get('noise_model')} {lvl:g}"
    noise += "" if seed is None or not math.isfinite(seed) else f" seed {seed:g}"    # two seeds: two cases
    return f"{r.get('mesh')} {noise} {r.get('method')}[{ps}]"


def _params_identity(r: dict, ids: dict | None = None) -> str:
    """A row's parameters as its case id records them (`harness.core.params.id_form` under
    ``ids``, ``{method: id_spec}`` from the runs' run.json: a renamed parameter under its old
    name, an added one left out at its default), so a run recorded before a rename or an
    addition describes the same case as one after it."""
    try:
        p = json.loads(str(r.get("params")))
    except (TypeError, ValueError):
        return str(r.get("params"))
    if not isinstance(p, dict):
        return str(r.get("params"))
    return json.dumps(id_form(p, (ids or {}).get(str(r.get("method")))), sort_keys=True, default=str)


def param_ids(*metas) -> dict:
    """``{method: id_spec}`` the runs' run.json record (`harness.session.task_specs`), merged."""
    out: dict = {}
    for meta in metas:
        for spec in ((meta or {}).get("tasks") or {}).values():
            ids = spec.get("param_ids") if isinstance(spec, dict) else None
            if isinstance(ids, dict):
                out.update({m: v for m, v in ids.items() if isinstance(v, dict)})
    return out


def compare_rows(rows_a: dict, rows_b: dict, time_factor: float | None = TIME_FACTOR, rules=None,
                 absolute_time: bool = False, load_rule: bool = True, cores: int | None = None,
                 threads: tuple | None = None, samples_differ: bool = False, ids: dict | None = None) -> dict:
    """Every change between two runs' rows: ``{"changes": [...], "only_a": [...], "only_b": [...], ...}``.

    ``rules``: ``{task: {metric: Rule}}`` from the runs' task declarations (default: the known tasks).
    Times are judged relative to the whole run's drift (`run_drift`) unless ``absolute_time``;
    ``load_rule``: the other processes' load may make a time change inconclusive (`judge_time`;
    ``cores``, the core count both runs' machines share, lets `load_stretch` do so; ``threads``,
    A's and B's threads per case). A drift of
    ``time_factor`` or more (or its inverse) on machines that were not oversubscribed
    (`whole_run_change`) is itself a change of the whole run: every case slowed alike, which no case's verdict relative to the
    drift can see. ``samples_differ``: the runs drew another number of points (`_measurement`'s
    ``hausdorff_samples``; 0 measures no sampled metric), so a sampled metric's value (``Rule.se``)
    one of them left blank was not measured there: changed, not a regression. ``ids``: how case
    ids record renamed and added parameters (`param_ids`), so rows recorded before and after one
    compare as the same case.
    """
    changes, input_changes = [], []
    unmatched: set = set()
    drift = run_drift(rows_a, rows_b)
    used_drift = 1.0 if absolute_time else drift
    common = [c for c in rows_a if c in rows_b]
    for cid in common:
        ra, rb = rows_a[cid], rows_b[cid]
        base = {"case_id": cid, "task": ra["task"], "case": _label(ra)}
        keys = IDENTITY if ra.get("library") != "external" else [k for k in IDENTITY if k != "params"]   # eval: the path
        differ = [k for k in keys if (_params_identity(ra, ids) != _params_identity(rb, ids) if k == "params"
                                      else str(ra.get(k)) != str(rb.get(k)))]
        if differ:                          # one id, two different cases (e.g. two evals' files in another order)
            changes.append({**base, "metric": "case", "a": _label(ra), "b": _label(rb), "verdict": "changed",
                            "note": f"not compared: the rows describe different cases ({', '.join(differ)} differ)"})
            continue
        sa, sb = ra.get("status"), rb.get("status")
        if sa != sb:
            verdict = "regression" if sa == "ok" else ("improvement" if sb == "ok" else "changed")
            changes.append({**base, "metric": "status", "a": sa, "b": sb, "verdict": verdict,
                            "note": str(rb.get("error") or "")[:200]})
        if sa == "ok" and sb == "ok" and time_factor:
            v = judge_time(ra, rb, time_factor, used_drift, load_rule, cores, threads)
            a, b = _num(ra.get("time_s")), _num(rb.get("time_s"))
            if a is not None and b is not None and a != b:
                changes.append({**base, "metric": "time_s", "a": a, "b": b,
                                "verdict": "within tolerance" if v == "same" else v,
                                "note": _time_note(ra, rb, used_drift)})
        if sa != "ok" or sb != "ok":
            continue
        wa, wb = ra.get("_invalid") or "", rb.get("_invalid") or ""
        if wa != wb:                 # a valid result turned invalid (e.g. diverged, worse than its input), or back
            why = "; ".join(f"{w} invalid: {x}" for w, x in (("A", wa), ("B", wb)) if x)
            changes.append({**base, "metric": "validity", "a": "invalid" if wa else "valid",
                            "b": "invalid" if wb else "valid",
                            "verdict": "regression" if not wa else ("improvement" if not wb else "changed"),
                            "note": f"{why} (the task's invalid_when rules, A's)"})
        for metric in {**ra, **rb}:
            if metric in SKIP or metric.startswith("_"):
                continue
            if metric not in ra or metric not in rb:     # a column one version writes and the other not
                unmatched.add((ra["task"], metric, "A" if metric in ra else "B"))
                continue
            a, b = ra.get(metric), rb.get(metric)
            rule = rule_for(metric, rb.get("task"), rules)
            verdict = judge(metric, a, b, ra, rb, rule=rule)
            if verdict == "same":
                if not (_blank(a) and _blank(b)) and a != b and not (_num(a) == _num(b) and _num(a) is not None):
                    changes.append({**base, "metric": metric, "a": a, "b": b, "verdict": "within tolerance"})
                continue
            if verdict == "changed" and rule.kind == "info":
                verdict = "info"              # e.g. peak_rss_mb: counted, not listed
            note = ""
            if samples_differ and rule.se and verdict in ("regression", "improvement") and _blank(a) != _blank(b):
                verdict, note = "changed", "not measured by one run's settings"
            entry = {**base, "metric": metric, "a": a, "b": b, "verdict": verdict, **({"note": note} if note else {})}
            (input_changes if rule.kind == "input" else changes).append(entry)
    whole = (whole_run_change(rows_a, rows_b, drift, time_factor, cores, threads) if time_factor and not absolute_time
             else None)
    if whole is not None:
        changes.append(whole)
    only_a = [c for c in rows_a if c not in rows_b]
    only_b = [c for c in rows_b if c not in rows_a]
    for cid in only_a:
        r = rows_a[cid]
        changes.append({"case_id": cid, "task": r["task"], "case": _label(r), "metric": "case", "a": r.get("status"),
                        "b": None, "verdict": "regression", "note": "missing in RUN_B"})
    return {"changes": changes, "input_changes": input_changes, "unmatched_columns": sorted(unmatched),
            "common": len(common), "only_a": only_a,
            "only_b": only_b, "rows_a": rows_a, "rows_b": rows_b, "drift": drift, "absolute_time": absolute_time}


def _fmt(v) -> str:
    return fmt(v, 4)


def _change(a, b) -> str:
    x, y = _num(a), _num(b)
    if x is None or y is None or isinstance(a, bool) or isinstance(b, bool):
        return ""
    if x == 0:
        return "" if y == 0 else f"{y - x:+.3g}"
    return f"{(y - x) / abs(x) * 100:+.1f}%"


ORDER = {"regression": 0, "improvement": 1, "changed": 2, "within tolerance": 3, "inconclusive": 4, "info": 5}


def _measurement(meta: dict) -> dict:
    """A run's measurement settings: run.json's ``measurement``, else its config's keys (an
    eval's under ``eval``), else the defaults; none when there is no run.json to read (``meta``
    empty: missing or damaged), as they are then not known."""
    if not meta:
        return {}
    got = meta.get("measurement") if isinstance(meta.get("measurement"), dict) else None
    if got is None:
        cfg = meta.get("config") if isinstance(meta.get("config"), dict) else {}
        cfg = cfg.get("eval") if isinstance(cfg.get("eval"), dict) else cfg
        got = {"hausdorff_samples": cfg.get("hausdorff_samples", 20000), "hausdorff_eps": cfg.get("hausdorff_eps", 1e-3)}
    return {k: got.get(k) for k in ("hausdorff_samples", "hausdorff_eps") if got.get(k) is not None}


def timing_notes(meta_a: dict, meta_b: dict, res: dict) -> list[str]:
    """Why time changes between these two runs may not mean what they seem."""
    notes = []
    ma, mb = meta_a.get("machine"), meta_b.get("machine")
    if ma and mb and any(ma[k] != mb[k] for k in ma.keys() & mb.keys()):     # keys one version records alone: not a difference
        notes.append("the runs come from different machines: time changes compare different hardware")
    wa, wb = meta_a.get("workers"), meta_b.get("workers")
    if wa and wb and wa != wb:
        notes.append(f"A ran {wa} worker(s) in parallel, B {wb}: time changes include a different contention")
    elif (wa or 1) > 1 and ma and (ma.get("cpu_count") or 0) <= (wa or 1):
        notes.append(f"{wa} workers on {ma.get('cpu_count')} cores: timings include contention "
                     "(run both with --workers 1 for timing-grade comparisons)")
    drift = res.get("drift", 1.0)
    if abs(drift - 1.0) > 0.1:
        how = ("judged without correcting for it (--absolute-time)" if res.get("absolute_time") else
               "each case's time is judged relative to this common factor (--absolute-time to judge raw times)")
        notes.append(f"B ran {drift:.2f}x A's time overall (median over cases): a busier or faster machine "
                     f"slows or speeds every case alike; {how}")
    la, lb = meta_a.get("load_average"), meta_b.get("load_average")
    if la or lb:
        notes.append(f"load average (1 min) at start/end: A {la}, B {lb}")
    busy = []
    for rows in (res["rows_a"], res["rows_b"]):
        v = sorted(x for x in (_num(r.get("others_cpu")) for r in rows.values()) if x is not None)
        busy.append(f"{statistics.median(v):.2g} (max {v[-1]:.2g}, {len(v)} cases)" if v else "not measured")
    if busy != ["not measured", "not measured"]:
        notes.append(f"cores other processes kept busy during the timed calls (others_cpu, median): A {busy[0]}, "
                     f"B {busy[1]}; what the load average says may differ (it counts waiting processes)")
    n_inc = sum(c["verdict"] == "inconclusive" for c in res["changes"])
    if n_inc:
        notes.append(f"{n_inc} case(s) are inconclusive on time (not counted as regressions): too few timed samples "
                     "on one side (raise repeats or time_budget), a wall-time change that other processes' load "
                     "explains, or a change the raw times and the times relative to the run's drift disagree on "
                     "(each case's note is in the --html page)")
    if any(time_samples(r) is None for r in list(res["rows_a"].values()) + list(res["rows_b"].values())
           if r.get("status") == "ok" and r.get("library") != "external"):        # eval rows have no time at all
        notes.append("some rows store no timed samples (older runs): their time is judged on median/min/max only")
    return notes


def _sorted(changes):
    return sorted(changes, key=lambda c: (ORDER.get(c["verdict"], 9), c["task"], c["case"], c["metric"]))


def compare_runs(run_a, run_b, html_out=None, time_factor: float | None = TIME_FACTOR, out=None,
                 max_lines: int = 200, absolute_time: bool = False) -> int:
    """Print the changes from RUN_A (baseline) to RUN_B; write an HTML diff if asked; 1 on a regression.

    ``time_factor=None`` (or 0) leaves timings out (metrics only), e.g. for runs from different machines.
    """
    out = out or sys.stdout
    meta_a = RunFolder(run_a).read_run_json() or {}
    meta_b = RunFolder(run_b).read_run_json() or {}
    ra = _rows(run_a, meta=meta_a)
    spec_a = recorded_specs(meta_a, {r["task"]: None for r in ra.values()})
    rb = _rows(run_b, spec_a, meta_b)                # validity by the baseline's rules, as its metrics' tolerances
    spec_b = recorded_specs(meta_b, {r["task"]: None for r in rb.values()})
    other_validity = sorted(t for t in spec_a.keys() & spec_b.keys()
                            if spec_a[t].get("invalid_when") != spec_b[t].get("invalid_when"))
    rules_a, rules_b = rules_from_specs(meta_a.get("tasks")), rules_from_specs(meta_b.get("tasks"))
    rules = {t: {**rules_b.get(t, {}), **rules_a.get(t, {})} for t in {*rules_a, *rules_b}}   # the baseline's rules
    for t in rules_a.keys() & rules_b.keys():   # a standard-error column either run names is read (older A: none)
        for m in rules_a[t].keys() & rules_b[t].keys():
            if not rules_a[t][m].se and rules_b[t][m].se:
                rules[t][m] = replace(rules_a[t][m], se=rules_b[t][m].se, se_z=rules_b[t][m].se_z)
    for t, rs in rules.items():       # a target or bracket column A does not name (older run.json): B's, or the kind's
        for m, r in rs.items():
            b, known = rules_b.get(t, {}).get(m) or r, rule_for(m, t)
            if r.kind == "target" and not r.target:
                rs[m] = r = replace(r, target=b.target or known.target)
            if r.kind == "lower" and not r.upper and (b.upper or known.upper) and known.kind == "lower":
                rs[m] = replace(r, upper=b.upper or known.upper)
    other_rules = sorted(f"{t}.{m}" for t in rules_a.keys() & rules_b.keys()
                         for m in rules_a[t].keys() & rules_b[t].keys()
                         if replace(rules_a[t][m], se="", se_z=3.0, target="", upper="")
                         != replace(rules_b[t][m], se="", se_z=3.0, target="", upper=""))
    ca, cb = ((m.get("machine") or {}).get("cpu_count") for m in (meta_a, meta_b))
    threads = tuple((m.get("timing") or {}).get("threads_per_case") if isinstance(m.get("timing"), dict) else None
                    for m in (meta_a, meta_b))
    threads = tuple(t if isinstance(t, int) and not isinstance(t, bool) and t > 0 else None for t in threads)
    ma_, mb_ = _measurement(meta_a), _measurement(meta_b)
    differ = [f"{k} A {ma_[k]}, B {mb_[k]}" for k in ma_ if k in mb_ and ma_[k] != mb_[k]]
    res = compare_rows(ra, rb, time_factor, rules, absolute_time, cores=ca if ca == cb else None, threads=threads,
                       samples_differ=not ma_ or not mb_ or ma_.get("hausdorff_samples") != mb_.get("hausdorff_samples"),
                       ids=param_ids(meta_a, meta_b))
    changes = _sorted(res["changes"])
    regress = [c for c in changes if c["verdict"] == "regression"]
    shown = [c for c in changes if c["verdict"] not in ("within tolerance", "info", "inconclusive")]
    quiet = sum(c["verdict"] == "within tolerance" for c in changes)
    n_info = sum(c["verdict"] == "info" for c in changes)
    print(f"compare A={run_a} (baseline) B={run_b}: {res['common']} cases in both, "
          f"{len(res['only_a'])} only in A, {len(res['only_b'])} only in B", file=out)
    for note in (timing_notes(meta_a, meta_b, res) if time_factor else []):     # --no-time: no timing notes
        print(f"note: {note}", file=out)
    for which, meta, run in (("A", meta_a, run_a), ("B", meta_b, run_b)):
        if not meta:
            print(f"note: {which}'s run.json is {RunFolder(run).run_json_state()}: its measurement settings, metric "
                  "rules and validity rules are not known; the installed version's rules are used, and a sampled "
                  "value only one run has is a change, not a regression", file=out)
        if meta.get("status") in ("running", "interrupted"):
            print(f"note: {which}'s run.json says {meta['status']}: the run is still going, was killed or was "
                  "interrupted, so a case missing from it may not have run yet (--resume finishes it)", file=out)
    if res["common"] == 0 and res["only_a"] and res["only_b"]:
        print("note: the runs share no case: they ran other configs (or meshes whose files changed), so every case "
              "of A counts as missing in B", file=out)
    if res["unmatched_columns"]:
        cols = ", ".join(f"{t}.{m} (only in {w})" for t, m, w in res["unmatched_columns"][:8])
        print(f"note: not compared, a column only one run's CSV has (another version wrote it?): {cols}"
              + (f" and {len(res['unmatched_columns']) - 8} more" if len(res["unmatched_columns"]) > 8 else ""),
              file=out)
    if differ:
        print(f"note: the runs measured with other settings ({'; '.join(differ)}): sampled metrics "
              "(surface_dist_mean) differ by their sampling too, within their standard errors; certified brackets "
              "(hausdorff to hausdorff_upper) count only where they lie apart; a sampled value one run did not "
              "measure (hausdorff_samples 0) is a change, not a regression", file=out)
    if other_rules:
        print(f"note: B declares other rules (direction or tolerance) for {len(other_rules)} metric(s), e.g. "
              f"{', '.join(other_rules[:5])}: A's (the baseline's) are used", file=out)
    if other_validity:
        print(f"note: B declares other validity rules (invalid_when) for {', '.join(other_validity)}: both runs' "
              "results are judged valid or not by A's (the baseline's)", file=out)
    if res["input_changes"]:
        n = len({c['case_id'] for c in res['input_changes']})
        print(f"warning: {n} case(s) saw different input data (mesh or noise changed): "
              + ", ".join(sorted({c['metric'] for c in res['input_changes']})), file=out)
    if shown:
        w = max(12, min(90, max(len(c["case"]) for c in shown)))
        head = (f"{'verdict':11s} {'task':14s} {'case id':12s} {'case':{w}s} {'metric':22s} {'A':>11s} {'B':>11s} "
                f"{'change':>9s}")
        print(head, file=out)
        print("-" * len(head), file=out)
        for c in shown[:max_lines]:
            flag = "REGRESSION" if c["verdict"] == "regression" else c["verdict"]
            case = c["case"] if len(c["case"]) <= w else c["case"][:w - 1] + "…"
            line = (f"{flag:11s} {c['task']:14s} {c['case_id']:12s} {case:{w}s} {c['metric']:22s} {_fmt(c['a']):>11s} "
                    f"{_fmt(c['b']):>11s} {_change(c['a'], c['b']):>9s}")
            if c.get("note"):
                line += f"  {c['note']}"
            print(line, file=out)
        if len(shown) > max_lines:
            print(f"... {len(shown) - max_lines} more changes (see --html)", file=out)
    n_imp = sum(c["verdict"] == "improvement" for c in changes)
    print(f"{len(regress)} regression(s) in {len({c['case_id'] for c in regress})} case(s), {n_imp} improvement(s), "
          f"{quiet} change(s) within tolerance, {n_info} informational (peak_rss_mb ...); tolerances: each metric's "
          f"declared rel/abs (errors: worse by >1% and a small absolute amount; " +
          (f"time: Mann-Whitney p<{ALPHA:g}, the 95% interval of the median ratio and the ratio of the fastest samples above {time_factor:g}x)"
           if time_factor else "time not compared)"), file=out)
    if res["only_b"]:
        print(f"new in B: {len(res['only_b'])} case(s), e.g. " + ", ".join(_label(rb[c]) for c in res["only_b"][:3]),
              file=out)
    if html_out:
        Path(html_out).parent.mkdir(parents=True, exist_ok=True)
        Path(html_out).write_text(_html(run_a, run_b, res, changes, time_factor), encoding="utf-8")
        print(f"HTML diff: {html_out}", file=out)
    return 1 if regress else 0


def _html(run_a, run_b, res, changes, time_factor) -> str:
    e = html.escape
    colors = {"regression": "#fdecec", "improvement": "#e8f5ec", "changed": "#fff8e1", "within tolerance": "#fff"}
    rows = "".join(
        f"<tr style='background:{colors.get(c['verdict'], '#fff')}'><td>{e(c['verdict'])}</td><td>{e(c['task'])}</td>"
        f"<td>{e(c['case'])}</td><td><code>{e(c['case_id'])}</code></td><td>{e(c['metric'])}</td>"
        f"<td class=n>{e(_fmt(c['a']))}</td><td class=n>{e(_fmt(c['b']))}</td><td class=n>{e(_change(c['a'], c['b']))}</td>"
        f"<td>{e(c.get('note', ''))}</td></tr>" for c in changes)
    n_reg = sum(c["verdict"] == "regression" for c in changes)
    summary = (f"{res['common']} cases in both runs, {len(res['only_a'])} only in A, {len(res['only_b'])} only in B; "
               f"<b>{n_reg} regression(s)</b>.")
    doc = e(__doc__ or "")
    return ("<!doctype html><html><head><meta charset='utf-8'><title>mesh-shootout compare</title><style>"
            "body{font:14px system-ui,sans-serif;margin:20px;color:#1d2330}table{border-collapse:collapse;font-size:12px}"
            "td,th{border:1px solid #d9dee7;padding:3px 6px;text-align:left}td.n{text-align:right;font-variant-numeric:tabular-nums}"
            "pre{background:#f5f7fa;padding:8px;white-space:pre-wrap;font-size:12px}</style></head><body>"
            f"<h1>mesh-shootout compare</h1><p>A (baseline): <code>{e(str(Path(run_a).resolve()))}</code><br>"
            f"B (candidate): <code>{e(str(Path(run_b).resolve()))}</code></p><p>{summary}</p>"
            f"<table><tr><th>verdict</th><th>task</th><th>case</th><th>id</th><th>metric</th><th>A</th><th>B</th>"
            f"<th>change</th><th>note</th></tr>{rows}</table>"
            f"<details><summary>Tolerances (time factor {time_factor or 'off'})</summary><pre>{doc}</pre></details>"
            "</body></html>")
