"""The ``tune:`` step of a run: its training cases run into ``tune/``, each method's setting
chosen (`harness.tune`) and the tuned test cases returned, a choice that changed on
``--resume`` said and recorded; how many training cases a resume still runs; the tuned test
cases an earlier session's record made, and those run.json records as chosen (to rebuild the
views without tuning again)."""
from __future__ import annotations

import dataclasses
import sys
from pathlib import Path

from .config import Config
from .results import RunFolder


def _earlier_tuned_ids(record) -> set:
    """The tuned test cases an earlier session's choice (run.json ``tune``) made; none of a
    record that does not hold them as written."""
    methods = record.get("methods") if isinstance(record, dict) else None
    if not isinstance(methods, dict):
        return set()
    return {str(c) for ch in methods.values() if isinstance(ch, dict) and isinstance(ch.get("test_case_ids"), list)
            for c in ch["test_case_ids"]}


def _training_left(cfg: Config, out_dir: Path, resume: bool) -> int:
    """How many training cases of ``tune:`` will run: all, or on ``--resume`` those without an
    ok row in ``tune/`` (what `_tune` keeps); 0 without ``tune:``."""
    if cfg.tune is None:
        return 0
    ids = {c.case_id for c in cfg.tune.cases}
    kept: set = set()
    if resume:
        tf = RunFolder(out_dir / "tune")
        for t in {c.task for c in cfg.tune.cases}:
            try:
                kept |= {r["case_id"] for r in tf.read_rows(t) if r.get("status") == "ok"} & ids
            except Exception:  # noqa: BLE001 - a damaged training CSV: the tuning step says so
                pass
    return len(ids - kept)


def _tune(cfg: Config, ex, out_dir: Path, meta: dict, threads: int, resume: bool, quiet: bool,
          previous: dict | None = None) -> list:
    """Run the training cases of ``tune:`` into ``tune/``, choose each method's setting, and return
    the tuned test cases (see `harness.tune`). On ``--resume``, ``previous`` (run.json's ``tune``)
    is the earlier session's choice: a choice that changed (training cases that failed, e.g. timed
    out, ran again) is said on stderr and kept in ``changed_on_resume``."""
    from .tune import choose, tuned_cases
    tfolder = RunFolder(out_dir / "tune")
    done = tfolder.keep_ok_rows(known={c.case_id for c in cfg.tune.cases}) if resume else set()
    if not resume:
        tfolder.reset()
    todo = [dataclasses.replace(c, threads=threads) for c in cfg.tune.cases if c.case_id not in done]
    if not quiet:
        print(f"shootout: tuning: {len(todo)} of {len(cfg.tune.cases)} training case(s) to run on "
              f"{len(cfg.tune.train)} mesh(es)", file=sys.stderr, flush=True)
    for case, row, _ in ex.run(todo):
        tfolder.append(case.task, row)
    choice = choose(cfg.tune, tfolder.frames())
    for m, ch in choice.items():
        if ch["train_score"] is None:     # no candidate scored: nothing was chosen from
            print(f"shootout: warning: tuning: {m}: no training setting has a valid score (its training cases "
                  f"failed, timed out or are invalid: see {out_dir / 'tune'}); it runs as configured",
                  file=sys.stderr, flush=True)
    from .config import expand_cases
    tuned = [dataclasses.replace(c, threads=threads) for c in tuned_cases(cfg, cfg.tune, choice, expand_cases)]
    for m, ch in choice.items():
        ch["test_case_ids"] = sorted(c.case_id for c in tuned if c.method == m)
    from .datasets import spec_key
    meta["tune"] = {"metric": cfg.tune.metric, "train_meshes": [spec_key(t) for t in cfg.tune.train],
                    "budget": cfg.tune.budget, "seed": cfg.tune.seed, "methods": choice}
    prev = previous if isinstance(previous, dict) else {}
    earlier = prev.get("changed_on_resume")
    changed = [c for c in earlier if isinstance(c, dict)] if isinstance(earlier, list) else []
    chosen_before = prev.get("methods") if isinstance(prev.get("methods"), dict) else {}
    for m, ch in choice.items():
        entry = chosen_before.get(m)
        before = entry.get("chosen") if isinstance(entry, dict) and isinstance(entry.get("chosen"), dict) else None
        if before is not None and before != ch["chosen"]:
            changed.append({"method": m, "before": before, "after": ch["chosen"], "session": meta.get("session_id")})
            print(f"shootout: tuning: {m}: the choice changed on resume, {before or 'as configured'} -> "
                  f"{ch['chosen'] or 'as configured'} (training cases that had failed ran again); the earlier "
                  "choice's test rows are dropped", file=sys.stderr, flush=True)
    if changed:
        meta["tune"]["changed_on_resume"] = changed
    return tuned


def _recorded_tuned_cases(cfg: Config, meta: dict) -> list:
    """The tuned test cases of a run (its config's ``tune:`` and the settings run.json records as
    chosen): the tuning is not run again. [] when there are none or the record is unusable."""
    from .config import expand_cases
    from .tune import tuned_cases
    methods = ((meta.get("tune") or {}).get("methods") if isinstance(meta.get("tune"), dict) else None) or {}
    if cfg.tune is None or not isinstance(methods, dict):
        return []
    choice = {m: {"chosen": ch["chosen"]} for m, ch in methods.items()
              if m in cfg.tune.configured and isinstance(ch, dict) and isinstance(ch.get("chosen"), dict)}
    try:
        return tuned_cases(cfg, cfg.tune, choice, expand_cases)
    except Exception:  # noqa: BLE001 - a damaged record: those views say their case is not among the run's
        return []
