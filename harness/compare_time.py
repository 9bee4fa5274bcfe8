"""The verdict on a case's time: B's timed samples against A's.

A regression needs statistical significance (one-sided Mann-Whitney p < ``ALPHA``) and a
minimum effect (the 95% bootstrap interval of the median ratio B/A, and the ratio of the
fastest samples, above the time factor; the medians more than ``TIME_FLOOR_S`` apart), judged
relative to the whole run's drift (`run_drift`) and on the raw times alike; other processes'
load (``others_cpu``, ``threads_busy``, the CPU times) can make it inconclusive
(`_load_explains`). A drift of the time factor or more is one change of the whole run
(`whole_run_change`). The rules in full are `harness.compare`'s docstring ("the module
docstring" below).
"""
from __future__ import annotations

import functools
import json
import math

from .schema import fmt
from .schema import number as _num

TIME_FACTOR = 1.5
TIME_FLOOR_S = 1e-3
BUSY_CORES = 0.5
OVERSUBSCRIBED = 1.25   # the load stretched the slower run's samples this much more than the faster's
CONTENDED_CPU = 2.0     # CPU time of the same work on an oversubscribed machine grows up to this (shared caches, hyperthreads)


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


def _fmt(v) -> str:
    return fmt(v, 4)
