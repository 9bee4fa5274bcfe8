"""A fair tuning protocol: search each method's parameters on *training* meshes, then evaluate the
chosen parameters on the run's own (*test*) meshes, beside the defaults.

Config::

    tune:
      metric: dist_mean          # a metric of the methods' task (its declared direction decides)
      train: [spot, armadillo]   # mesh list, same syntax as meshes:, none of them a test mesh
      budget: 12                 # settings tried per method: the whole grid if it is smaller, else
      seed: 0                    #   a seeded random sample of it (the defaults are always tried)
      params:
        scratch.implicit: {step: [0.01, 0.1, 1], iterations: [1, 3]}

Selection: for each method, every candidate setting runs on every training (mesh, noise, level,
seed) of the run's noise models; its score is the mean metric over those cases, and a candidate
with a failed or invalid case (diverged, ended worse than its noisy input, non-manifold or
topology-changing output) scores infinitely bad. The best score wins (ties: the earlier
candidate, the defaults first), but it replaces the setting as configured only when better than
it beyond the metric's compare tolerance (``max(rel * |default|, abs)``, and for a sampled metric
at least ``SE_Z`` times the two means' combined standard error, `mean_se`; for a certified
bound, ``hausdorff``, measured from the upper end of the candidate's bracket: brackets that
overlap are a tie): a difference the rankings call a tie chooses nothing. The tuned setting
then runs on the test meshes as extra cases; ``run.json`` records per method the chosen
parameters, the training scores of the defaults and of the chosen setting, the number of
candidates and the tuned case ids, and the report shows default vs tuned side by side. Training rows are kept in ``tune/`` inside the run folder.
"""
from __future__ import annotations

import difflib
import itertools
import json
import math
from collections import Counter
from dataclasses import dataclass, field

import numpy as np

from .tasks.base import SE_Z
from .yaml_input import short

TUNE_KEYS = {"metric", "train", "budget", "seed", "params"}


@dataclass
class TuneSpec:
    metric: str
    train: list
    budget: int
    seed: int
    params: dict                     # method -> {param: [values]}
    configured: dict                 # method -> (task, [param dicts of the run's own grid])
    cases: list = field(default_factory=list)
    common: tuple = ()
    noises: list | dict = field(default_factory=list)   # one list, or task -> list (harness.config)

    def candidates(self, method: str) -> list[dict]:
        """Parameter overrides tried for ``method``: {} (the defaults) first, then the grid or a sample."""
        import methods
        meth = methods.get(method)
        base = self.configured[method][1][0] if self.configured[method][1] else {}
        ranges = self.params[method]
        keys = sorted(ranges)
        total = math.prod(len(ranges[k]) for k in keys)
        pick = range(total)
        want = max(self.budget - 1, 0)
        if total > want:                     # a seeded sample of the product's positions, never the whole product
            # positions whose setting is the defaults (tried first anyway) are not drawn: the budget buys others
            default = meth.with_defaults(base)
            same = [[i for i, v in enumerate(ranges[k]) if _key(meth.with_defaults({**base, k: v})[k]) == _key(default[k])]
                    for k in keys]
            excl = {_position(ranges, keys, c) for c in itertools.product(*same)} if all(same) else set()
            rng = np.random.default_rng(self.seed)
            drawn = rng.choice(total, size=min(total, want + len(excl)), replace=False).tolist()
            pick = sorted([i for i in drawn if i not in excl][:want])
        grid = [_nth_combination(ranges, keys, i) for i in pick]
        seen, out = set(), []
        for g in [{}] + grid:                      # settings equal to the defaults are the defaults
            key = _key(meth.with_defaults({**base, **g}))
            if key not in seen:
                seen.add(key)
                out.append(g)
        return out

    def n_training_settings(self) -> dict:
        """``{task: [(method, range(n))]}``: how many training settings each method gets (what
        `grid_tasks` would list), without building them, for the case count."""
        out: dict = {}
        for m in self.params:
            task, base = self.configured[m]
            out.setdefault(task, []).append((m, range(len(self.candidates(m)) * len(base))))
        return out

    def grid_tasks(self) -> dict:
        """``{task: [(method, [params, ...])]}`` of the training cases (candidates x configured grid)."""
        import methods
        out: dict = {}
        for m in self.params:
            task, base = self.configured[m]
            meth = methods.get(m)
            grid = [meth.with_defaults({**b, **c}) for c in self.candidates(m) for b in base]
            out.setdefault(task, []).append((m, grid))
        return out


def _nth_combination(ranges: dict, keys: list, i: int) -> dict:
    """The ``i``-th element of ``itertools.product(*(ranges[k] for k in keys))`` (the last key
    varies fastest), as a dict."""
    out = {}
    for k in reversed(keys):
        i, j = divmod(i, len(ranges[k]))
        out[k] = ranges[k][j]
    return {k: out[k] for k in keys}


def _position(ranges: dict, keys: list, idx: tuple) -> int:
    """The position in the product (`_nth_combination`'s ``i``) of the value indices ``idx``."""
    i = 0
    for k, j in zip(keys, idx):
        i = i * len(ranges[k]) + j
    return i


def _key(v) -> str:
    return json.dumps(v, sort_keys=True, default=str)


MAX_SETTINGS = 10 ** 15      # a tune.params product above this is refused (sampled positions fit int64)


def check_tune(raw, base_dir, P: list, tasks: dict, check_meshes) -> TuneSpec | None:
    """Validate the ``tune:`` section (problems appended to ``P`` with their key paths); None
    when it has problems of its own (others already in ``P`` do not count)."""
    import methods
    from . import tasks as _tasks
    n0 = len(P)
    if not isinstance(raw, dict):
        P.append(f"tune: expected a mapping with {sorted(TUNE_KEYS)}, got {type(raw).__name__}")
        return None
    for k in raw:
        if k not in TUNE_KEYS:
            P.append(f"tune.{k}: unknown key; expected one of {sorted(TUNE_KEYS)}")
    budget, seed = raw.get("budget", 20), raw.get("seed", 0)
    if not isinstance(budget, int) or isinstance(budget, bool) or not 1 <= budget <= 1000:
        P.append(f"tune.budget: expected an integer in [1, 1000], got {short(budget)}")
        budget = 20
    if not isinstance(seed, int) or isinstance(seed, bool) or seed < 0:
        P.append(f"tune.seed: expected an integer >= 0, got {short(seed)}")
        seed = 0
    train = check_meshes(raw.get("train"))
    configured = {m: (t, [g for g in grid]) for t, entries in tasks.items() for m, grid in entries}
    n_listed = Counter(m for entries in tasks.values() for m, _ in entries)
    params = raw.get("params")
    out_params: dict = {}
    if not isinstance(params, dict) or not params:
        P.append("tune.params: expected a mapping method -> {parameter: [values]}")
        params = {}
    metric = raw.get("metric")
    for m, ranges in params.items():
        at = f"tune.params.{m}"
        if m not in configured:
            close = difflib.get_close_matches(str(m), list(configured), n=3, cutoff=0.5)
            P.append(f"{at}: {short(m)} is not one of the run's methods (list it under tasks: too)"
                     + (f"; did you mean {', '.join(close)}?" if close else ""))
            continue
        if not isinstance(ranges, dict) or not ranges:
            P.append(f"{at}: expected a mapping parameter -> list of values")
            continue
        if n_listed[m] > 1:                 # "as configured" would be the last entry in training, all on the test
            P.append(f"{at}: {m} is listed {n_listed[m]} times under tasks:; tuning compares one configured setting "
                     "with the chosen one: list it once (its values as lists in one entry)")
            continue
        meth = methods.get(m)
        axis = _tasks.get(configured[m][0]).axis_params
        ok = {}
        ranges, both = meth.canonical(ranges)     # a library's own spelling under the shared name
        P.extend(f"{at}: {b}" for b in both)
        for k, vals in ranges.items():
            if k in axis:                   # it defines the cell (the target, k, the sources): not a setting
                P.append(f"{at}.{k}: {k} is an axis of the {configured[m][0]} task (rows with other values are "
                         "other cells, not competitors): it cannot be tuned; list its values under the task's params")
                continue
            listed = {_key(g.get(k)) for g in configured[m][1]}
            if len(listed) > 1:             # "as configured" would be one value in training, all on the test
                P.append(f"{at}.{k}: the run lists several values of {k} for {m} under tasks:; tuning compares "
                         "one configured setting with the chosen one: list one value there, or tune another parameter")
                continue
            vals = vals if isinstance(vals, list) else [vals]
            bad = list(dict.fromkeys(p for v in vals for p in meth.param_problems({k: v})))   # once each
            if not vals or bad:
                P.extend(f"{at}.{k}: {b}" for b in (bad or ["empty list of values"]))
                continue
            ok[k] = vals
        size = math.prod(len(v) for v in ok.values())
        if size > MAX_SETTINGS:
            P.append(f"{at}: its value lists expand to {size:.3g} settings, more than {MAX_SETTINGS:.0e}")
            continue
        out_params[m] = ok
        if meth.setting_check is not None and size <= 100_000:     # candidates the method refuses as a whole
            base = configured[m][1][0] if configured[m][1] else {}
            for combo in itertools.product(*ok.values()):
                why = meth.setting_problem({**base, **dict(zip(ok, combo))})
                if why:
                    P.append(f"{at}: a candidate setting {json.dumps(dict(zip(ok, combo)), default=str)} cannot "
                             f"run: {why}")
                    break
    def ranks(t) -> bool:
        mt = _tasks.get(t).metric(metric) if isinstance(metric, str) else None
        return mt is not None and mt.better in ("lower", "higher")
    named = sorted({configured[m][0] for m in params if m in configured})
    if not named:                         # no method named well: a metric of any task of the run will do
        named = sorted({t for t, _ in configured.values()})
        named = [] if any(ranks(t) for t in named) else named[:1]
    for t in named:                       # the tasks it would rank: every one of them must declare it
        if not ranks(t):
            spec = _tasks.get(t)
            names = [x.name for x in spec.metrics if x.better in ("lower", "higher")]
            P.append(f"tune.metric: expected a metric of {spec.name} with a direction ({', '.join(names)}), "
                     f"got {short(metric)}")
    if len(P) > n0:
        return None
    return TuneSpec(metric=metric, train=train, budget=budget, seed=seed, params=out_params, configured=configured)


def mean_se(rows, se: str) -> float:
    """The standard error of the mean of a sampled metric over ``rows`` from each row's own
    (column ``se``): ``sqrt(sum se_i^2) / n``, the rows' draws being independent; 0 for a metric
    that is not sampled or rows that state none, infinite when one row's is (the default then stays)."""
    if not se or se not in rows or rows.empty:
        return 0.0
    e = np.nan_to_num(rows[se].astype(float).to_numpy(), nan=0.0, posinf=np.inf)   # unknown: no choice
    return float(math.sqrt(float(np.sum(e * e))) / len(e))


def choose(tune: TuneSpec, frames: dict) -> dict:
    """Per method: the chosen overrides and the training scores (see the module docstring)."""
    from . import tasks
    from .leaderboard import row_tops, validity
    out = {}
    for m in tune.params:
        task = tune.configured[m][0]
        df = frames.get(task)
        mt = tasks.get(task).metric(tune.metric)
        better = mt.better
        sign = -1.0 if better == "higher" else 1.0
        bracket = better == "lower" and mt.upper and df is not None and mt.upper in df   # a certified bound
        scores, errs, tops = [], [], []
        for cand in tune.candidates(m):
            if df is None:
                scores.append(math.inf)
                errs.append(0.0)
                tops.append(math.inf)
                continue
            rows = df[df["method"] == m]
            ps = [json.loads(p) for p in rows["params"]]
            want = {k: v for b in tune.configured[m][1][:1] for k, v in b.items() if k in tune.params[m]}
            want.update(cand)
            sel = rows[[all(p.get(k) == v for k, v in want.items()) for p in ps]]
            bad = (validity(tasks.get(task).spec(), sel) != "").any() or sel.empty
            val = sel[tune.metric].astype(float).mean() if not sel.empty else math.nan
            scores.append(math.inf if bad or not math.isfinite(val) else sign * val)
            errs.append(mean_se(sel, "" if mt.se_shared else mt.se))    # a shared sample: paired, no tie by it
            tops.append(float(row_tops(sel, tune.metric, mt.upper).mean()) if bracket and not sel.empty else scores[-1])
        best = int(np.argmin(scores)) if scores else 0
        if best and math.isfinite(scores[0]):     # as configured stays unless beaten beyond the tolerance
            def beats(c: int) -> bool:            # a certified bound: by its bracket's upper end
                tol = max(mt.rel * abs(scores[0]), mt.abs, SE_Z * math.hypot(errs[0], errs[c]))
                reach = max(scores[c], tops[c]) if math.isfinite(tops[c]) else scores[c]
                return math.isfinite(scores[c]) and scores[0] - reach > tol
            beating = [c for c in range(1, len(scores)) if beats(c)]
            best = min(beating, key=lambda c: scores[c]) if beating else 0
        cands = tune.candidates(m)
        out[m] = {"task": task, "chosen": cands[best], "candidates": len(cands),
                  "train_score": None if math.isinf(scores[best]) else sign * scores[best],
                  "default_train_score": None if math.isinf(scores[0]) else sign * scores[0],
                  "metric": tune.metric, "better": better}
    return out


def tuned_cases(cfg, tune: TuneSpec, choice: dict, expand_cases) -> list:
    """The test meshes' cases of every tuned method with its chosen setting (those whose setting
    differs from the defaults); ``expand_cases`` is `harness.config.expand_cases`."""
    import methods
    raw_meshes = [c.mesh for c in cfg.cases]
    meshes = list({json.dumps(m, sort_keys=True): m for m in raw_meshes}.values())
    tasks_: dict = {}
    for m, ch in choice.items():
        if not ch["chosen"]:
            continue
        task, base = tune.configured[m]
        meth = methods.get(m)
        tasks_.setdefault(task, []).append((m, [meth.with_defaults({**b, **ch["chosen"]}) for b in base]))
    return expand_cases(meshes, tune.noises, tasks_, *tune.common) if tasks_ else []
