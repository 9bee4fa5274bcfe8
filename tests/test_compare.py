"""`shootout compare` on real run folders (identical, injected regressions, tolerances) and the
pytest-benchmark JSON export read back by pytest-benchmark's own `compare` command."""
from __future__ import annotations

import csv
import io
import json
import os

import numpy as np
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

import harness
from harness.cli import main as cli
from harness.compare import compare_runs, judge, judge_time, time_effect

SMALL = {
    "name": "tiny-compare",
    "repeats": 3,
    "seed": 0,
    "hausdorff_samples": 2000,
    "meshes": ["knight"],
    "noise": [{"model": "gaussian_normal", "levels": [0.3]}],
    "tasks": {
        "laplacian": {"methods": ["scratch.uniform", "scratch.cotan"]},
        "smoothing": {"methods": [{"name": "scratch.explicit", "params": {"iterations": [3, 8]}}]},
        "simplification": {"methods": ["fast_simplification.qem"], "params": {"target_ratio": [0.5]}},
    },
}


@pytest.fixture(scope="module")
def run_a(tmp_path_factory):
    out = tmp_path_factory.mktemp("cmp") / "a"
    harness.run(SMALL, out=out, quiet=True, workers=1,
                export_benchmark_json=out.parent / "bench.json")
    return out


def copy(run_a, tmp_path, name="b") -> Path:
    dst = tmp_path / name
    shutil.copytree(run_a, dst)
    return dst


def edit(path: Path, fn):
    rows = list(csv.DictReader(path.open()))
    fields = list(rows[0])
    fn(rows)
    with path.open("w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=fields, lineterminator="\n")
        w.writeheader()
        w.writerows(rows)


def run_compare(a, b, **kw):
    buf = io.StringIO()
    code = compare_runs(a, b, out=buf, **kw)
    return code, buf.getvalue()


def test_identical_runs_exit_0(run_a, tmp_path, capsys):
    b = copy(run_a, tmp_path)
    assert cli(["compare", str(run_a), str(b)]) == 0
    out = capsys.readouterr().out
    assert "0 regression(s)" in out and "5 cases in both" in out


def test_runs_of_different_code_are_said_to_be(run_a, tmp_path):
    """An outside audit: two runs whose code differed (another commit landed during the second)
    compared with no word of it; run.json records each run's code hash and commit."""
    b = copy(run_a, tmp_path)
    code, out = run_compare(run_a, b, time_factor=None)
    assert "different code" not in out
    meta = json.loads((b / "run.json").read_text())
    meta.update(code_sha256="0" * 64, git_commit="abcdef0123456789", git_dirty=True)
    (b / "run.json").write_text(json.dumps(meta))
    code, out = run_compare(run_a, b, time_factor=None)
    assert code == 0 and "note: the runs ran different code (A " in out and "B abcdef0123 with uncommitted changes" in out, out


def test_injected_metric_regression_exits_1_and_html(run_a, tmp_path):
    b = copy(run_a, tmp_path)
    edit(b / "smoothing.csv", lambda rows: rows[0].update(dist_mean=str(float(rows[0]["dist_mean"]) * 1.05)))
    html = tmp_path / "diff.html"
    code, out = run_compare(run_a, b, html_out=html)
    assert code == 1
    line = next(ln for ln in out.splitlines() if ln.startswith("REGRESSION"))
    assert "dist_mean" in line and "+5.0%" in line
    assert "1 regression(s) in 1 case(s)" in out
    page = html.read_text()
    assert "<b>1 regression(s)</b>" in page and "dist_mean" in page
    assert cli(["compare", str(run_a), str(b)]) == 1           # the CLI returns the same exit code


def test_a_regression_is_exit_1_even_when_no_one_reads_the_lines(run_a, tmp_path):
    """Before: with stdout closed early (`| head -1`, `| true`) compare returned 0 on a regression
    and skipped --html; a closed stderr (`2>&-`) crashed a run before its first row."""
    b = copy(run_a, tmp_path)
    edit(b / "smoothing.csv", lambda rows: rows[0].update(dist_mean=str(float(rows[0]["dist_mean"]) * 1.5)))
    html = tmp_path / "d.html"
    cmd = [sys.executable, "-m", "harness.cli", "compare", str(run_a), str(b), "--no-time", "--html", str(html)]
    env = {k: v for k, v in os.environ.items() if k != "PYTHONUNBUFFERED"}   # a pipe is block-buffered then
    p = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, cwd=Path(harness.__file__).parents[1],
                         env=env)
    p.stdout.close()                                  # the reader is gone before the first line
    _, err = p.communicate(timeout=120)
    assert p.returncode == 1, err
    assert "<b>1 regression(s)</b>" in html.read_text()
    r = subprocess.run([sys.executable, "-m", "harness.cli", "compare", str(run_a), str(b), "--no-time"],
                       stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True, timeout=120, env=env)
    assert r.returncode == 1 and "REGRESSION" in r.stdout
    r = subprocess.run(f"{sys.executable} -m harness.cli datasets | true", shell=True, capture_output=True, text=True,
                       timeout=120, env=env, executable="/bin/bash")
    assert r.returncode == 0 and "BrokenPipe" not in r.stderr, r.stderr
    from harness.cli import _PipeSafe                 # a character the terminal lacks is escaped, not the rest lost
    raw = io.BytesIO()
    out = _PipeSafe(io.TextIOWrapper(raw, encoding="ascii"))
    out.write("case \u2026 done\n")
    out.write("next\n")
    out.flush()
    assert raw.getvalue() == b"case \\u2026 done\nnext\n" and not out.broken
    cfg = tmp_path / "c.json"
    cfg.write_text(json.dumps({**SMALL, "tasks": {"smoothing": SMALL["tasks"]["smoothing"]}}))
    r = subprocess.run(f"{sys.executable} -m harness.cli run {cfg} --out {tmp_path / 'o'} 2>&-", shell=True,
                       capture_output=True, text=True, timeout=300, cwd=Path(harness.__file__).parents[1])
    assert r.returncode == 0 and "2 ok" in r.stdout, r.stdout


def test_a_column_only_one_run_has_is_a_note_not_a_regression(run_a, tmp_path):
    """Before: a metric column missing from B's CSV (another version) was a REGRESSION to '—' in
    every row; missing from A it was silently not compared."""
    b = copy(run_a, tmp_path)
    rows = list(csv.DictReader((b / "smoothing.csv").open()))
    with (b / "smoothing.csv").open("w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=[c for c in rows[0] if c != "ev_mean"], extrasaction="ignore",
                           lineterminator="\n")
        w.writeheader()
        w.writerows(rows)
    # a review: a column B's own run declares but its CSV lacks is a damaged file (exit 2), not a note
    with pytest.raises(harness.errors.ShootoutError, match="smoothing.csv: damaged CSV: no column.s. ev_mean, "
                                                           "which its run .run.json. declares"):
        run_compare(run_a, b, time_factor=None)
    meta = json.loads((b / "run.json").read_text())          # another version: it declares no ev_mean
    spec = meta["tasks"]["smoothing"]
    spec["metrics"] = [m for m in spec["metrics"] if m["name"] != "ev_mean"]
    (b / "run.json").write_text(json.dumps(meta))
    for x, y, where in ((run_a, b, "only in A"), (b, run_a, "only in B")):
        code, out = run_compare(x, y, time_factor=None)
        assert code == 0 and "REGRESSION" not in out, out
        assert f"smoothing.ev_mean ({where})" in out, out


def test_changes_within_tolerance_and_improvements_exit_0(run_a, tmp_path):
    b = copy(run_a, tmp_path)

    def fn(rows):
        rows[0]["dist_mean"] = str(float(rows[0]["dist_mean"]) * 1.005)   # 0.5 % worse: within the 1 % tolerance
        rows[1]["hausdorff"] = str(float(rows[1]["hausdorff"]) * 0.5)      # better: the whole bracket
        rows[1]["hausdorff_upper"] = str(float(rows[1]["hausdorff_upper"]) * 0.5)
    edit(b / "smoothing.csv", fn)
    code, out = run_compare(run_a, b)
    assert code == 0, out
    assert "1 improvement(s)" in out and "1 change(s) within tolerance" in out


@pytest.mark.parametrize("task, change, metric", [
    ("laplacian", {"SYM": "false"}, "SYM"),                                # a property is lost
    ("laplacian", {"loc_violations": "4", "LOC": "false"}, "loc_violations"),
    ("simplification", {"out_faces": "400"}, "out_faces"),                # misses its 500-face target
    ("smoothing", {"diverged": "true", "ev_mean": ""}, "diverged"),        # a blow-up, metrics gone
    ("smoothing", {"volume_ratio": "0.5"}, "volume_ratio"),
    ("simplification", {"status": "error", "error": "RuntimeError: boom"}, "status"),
])
def test_each_kind_of_regression(run_a, tmp_path, task, change, metric):
    b = copy(run_a, tmp_path)
    edit(b / f"{task}.csv", lambda rows: rows[0].update(change))
    code, out = run_compare(run_a, b)
    assert code == 1, out
    assert any(ln.startswith("REGRESSION") and f" {metric} " in ln for ln in out.splitlines()), out


def test_missing_case_is_a_regression_new_case_is_not(run_a, tmp_path):
    b = copy(run_a, tmp_path)
    edit(b / "laplacian.csv", lambda rows: rows.pop())
    code, out = run_compare(run_a, b)
    assert code == 1 and "missing in RUN_B" in out
    code, out = run_compare(b, run_a)          # the extra case in the candidate is only listed
    assert code == 0 and "new in B: 1 case(s)" in out
    assert "share no case" not in out and "says running" not in out
    meta = json.loads((b / "run.json").read_text())      # a run still going: its missing cases are said to be so
    (b / "run.json").write_text(json.dumps({**meta, "status": "running"}))
    code, out = run_compare(run_a, b)
    assert code == 1 and "B's run.json says running" in out
    for k, name in enumerate(("laplacian.csv", "smoothing.csv", "simplification.csv")):     # nothing in common
        edit(b / name, lambda rows, k=k: [r.update(case_id=f"e{k}{i:010d}") for i, r in enumerate(rows)])
    code, out = run_compare(run_a, b)
    assert code == 1 and "the runs share no case" in out


def test_time_needs_factor_and_spread(run_a, tmp_path):
    ra = {"time_s": 0.010, "time_min_s": 0.009, "time_max_s": 0.012}
    assert judge_time(ra, {"time_s": 0.030, "time_min_s": 0.028, "time_max_s": 0.035}) == "regression"
    # 3x slower median but the repeats overlap the baseline's spread: noise, not a regression
    assert judge_time(ra, {"time_s": 0.030, "time_min_s": 0.011, "time_max_s": 0.040}) == "same"
    # beyond the spread but only 1.4x
    assert judge_time(ra, {"time_s": 0.014, "time_min_s": 0.0135, "time_max_s": 0.015}) == "same"
    # sub-millisecond differences are never regressions
    assert judge_time({"time_s": 1e-4, "time_min_s": 1e-4, "time_max_s": 1e-4},
                      {"time_s": 5e-4, "time_min_s": 5e-4, "time_max_s": 5e-4}) == "same"
    assert judge_time(ra, {"time_s": 0.004, "time_min_s": 0.003, "time_max_s": 0.005}) == "improvement"
    b = copy(run_a, tmp_path)

    def slow(rows):
        r = rows[0]
        t = [x * 10 + 0.01 for x in json.loads(r["times"])]
        c = [x * 10 + 0.01 for x in json.loads(r["cpu_times"])]      # more work: CPU time grows too
        r.update(times=json.dumps(t), time_s=str(sorted(t)[len(t) // 2]), time_min_s=str(min(t)), time_max_s=str(max(t)),
                 cpu_times=json.dumps(c))
    edit(b / "smoothing.csv", slow)
    code, out = run_compare(run_a, b)
    line = next(ln for ln in out.splitlines() if ln.startswith("REGRESSION") and "time_s" in ln)
    assert code == 1 and "Mann-Whitney" in line and "95% CI" in line


def _row(times):
    return {"times": json.dumps(times), "time_s": sorted(times)[len(times) // 2],
            "time_min_s": min(times), "time_max_s": max(times)}


def test_time_is_decided_on_the_samples():
    rng = np.random.default_rng(1)
    base = list(0.010 * (1 + 0.3 * rng.random(20)))
    noisy_same = list(0.010 * (1 + 0.3 * rng.random(20)))
    assert judge_time(_row(base), _row(noisy_same)) == "same"
    assert judge_time(_row(base), _row([2 * t for t in noisy_same])) == "regression"
    assert judge_time(_row(base), _row([0.5 * t for t in noisy_same])) == "improvement"
    # significant but small: a 1.2x slowdown is below the minimum effect
    assert judge_time(_row(base), _row([1.2 * t for t in noisy_same])) == "same"
    # one slow outlier sample does not make a regression (the median and the rank test decide)
    assert judge_time(_row(base), _row(noisy_same[:-1] + [1.0])) == "same"
    # 2x slower but only 3 samples a side: too few to reach p < 0.01, so inconclusive, never a regression
    assert judge_time(_row(base[:3]), _row([2 * t for t in base[:3]])) == "inconclusive"
    eff = time_effect(_row(base), _row([2 * t for t in noisy_same]))
    assert 1.6 < eff["ci"][0] < eff["ratio"] < eff["ci"][1] < 2.5 and eff["p_slower"] < 1e-6


def test_wall_time_on_a_busier_machine_without_cpu_time_is_inconclusive():
    """Load from other processes during a whole sample window stretches every sample's wall time,
    the fastest included (a 4.6x 'regression' with p = 1e-10 between two runs of the same code).
    When other processes kept B's machine busier (others_cpu) and the CPU time did not move, time
    is inconclusive; on an equally quiet machine a wall-time change counts even without a CPU
    change (a sleep, I/O, lost parallelism); more work moves the CPU time and counts anyway."""
    rng = np.random.default_rng(1)
    base = list(0.010 * (1 + 0.3 * rng.random(20)))
    same = list(0.010 * (1 + 0.3 * rng.random(20)))
    slow = [4 * t for t in same]

    def row(wall, cpu, others):
        return {**_row(wall), "cpu_times": json.dumps(cpu), "others_cpu": others}
    assert judge_time(row(base, base, 0.1), row(slow, same, 1.5)) == "inconclusive"
    assert judge_time(row(base, base, 0.1), row(slow, same, 0.2)) == "regression"      # quiet: a sleep counts
    assert judge_time(row(base, base, 0.1), row(slow, slow, 1.5)) == "regression"      # more work
    assert judge_time(row([4 * t for t in base], base, 1.5), row(same, same, 0.1)) == "inconclusive"
    assert judge_time(row([4 * t for t in base], base, 0.1), row(same, same, 0.1)) == "improvement"
    assert judge_time(row(base, base, 0.1), row(same, same, 1.5)) == "same"
    no_load = {**_row(base), "cpu_times": json.dumps(base)}                 # A's window too short to measure it
    assert judge_time(no_load, row(slow, same, 1.5)) == "inconclusive"        # A's load unknown, B's busy
    assert judge_time(no_load, row(slow, slow, 1.5)) == "regression"          # ... but 4x the CPU time
    assert judge_time(no_load, row(slow, same, 0.2)) == "regression"          # ... or B quiet
    assert judge_time(row(base, base, 0.1), row(slow, same, 1.5), load_rule=False) == "regression"
    # less than half a core busier, but the slower run's machine had fewer free cores than the
    # case used: its samples waited for a core (measured: 17x the wall time of a 0.6 ms method,
    # with 1.95x its CPU time, at 1.9 of 2 cores busy)
    twice = [2.3 * t for t in same]
    assert judge_time(row(base, base, 0.98), row(twice, same, 1.465)) == "regression"       # core count unknown
    assert judge_time(row(base, base, 0.98), row(twice, same, 1.465), cores=2) == "inconclusive"
    assert judge_time(row(base, base, 0.98), row(twice, same, 1.465), cores=8) == "regression"  # cores to spare
    assert judge_time(row(base, base, 1.6), row([17 * t for t in same], [1.95 * t for t in same], 1.9),
                      cores=2) == "inconclusive"
    assert judge_time(row(base, base, 0.98), row(slow, slow, 1.465), cores=2) == "regression"   # 4x the CPU time
    # under equal load nothing is excused: 2.5x the wall and CPU time, two workers with a quarter
    # core of outside load in both runs, or one worker whose case uses 1.7 cores, 0.2 busy in both;
    # but a case keeping 2 threads busy beside 0.7 busy cores oversubscribes 2 cores, where
    # waiting threads make any time (84x between two loaded reruns): inconclusive even then
    more = [2.5 * t for t in same]
    assert judge_time(row(base, base, 1.25), row(more, more, 1.25), cores=2) == "regression"
    assert judge_time(row(base, [1.7 * t for t in base], 0.2), row(more, [1.7 * t for t in more], 0.2),
                      cores=2) == "regression"
    assert judge_time(row(base, [1.7 * t for t in base], 0.7), row(more, [1.7 * t for t in more], 0.7),
                      cores=2) == "inconclusive"
    assert judge_time(row(more, more, 1.25), row(base, base, 1.25), cores=2) == "improvement"
    assert judge_time(row(base, base, 1.4), row(more, more, 1.25), cores=2) == "regression"   # B less loaded
    # beside one busy sibling on two cores about one core is free: not oversubscribed, so 2x the
    # CPU time with 4x the wall time is a regression
    assert judge_time(row(base, base, 1.0), row(slow, [2 * t for t in same], 1.05), cores=2) == "regression"
    assert judge_time(row(twice, same, 1.465), row(base, base, 0.98), cores=2) == "inconclusive"  # improvement


def test_load_that_oversubscribes_the_cases_threads_excuses_even_a_cpu_time_change():
    """An outside review: one worker (2 threads per case on 2 cores), B rerun beside a busy loop:
    libigl.eigsh took 12.7x, with 7.1x the CPU time (BLAS threads spin while they wait for a
    core), and was called a regression (exit 1). With the case's threads plus the load above the
    cores, neither time can tell: inconclusive. Nothing changes when the threads fit."""
    rng = np.random.default_rng(2)
    base = list(0.0148 * (1 + 0.2 * rng.random(12)))

    def row(k_wall, k_cpu, others, busy=None):         # busy None: a row of a version without the column
        return {**_row([k_wall * t for t in base]), "cpu_times": json.dumps([k_cpu * t for t in base]),
                "others_cpu": others, **({} if busy is None else {"threads_busy": busy})}
    a, b = row(1, 1.9, 0.0), row(12.7, 7.1 * 1.9, 1.05)                     # u = 1.9: two threads (older rows)
    assert judge_time(a, b, cores=2) == "inconclusive"                       # u = 1.9 says two threads
    assert judge_time(a, b, cores=2, threads=(2, 2)) == "inconclusive"
    assert judge_time(a, b, cores=8, threads=(2, 2)) == "regression"          # cores to spare
    assert judge_time(a, row(12.7, 7.1 * 1.9, 0.3), cores=2, threads=(2, 2)) == "regression"   # equally quiet
    assert judge_time(b, a, cores=2, threads=(2, 2)) == "inconclusive"        # the same, read as an improvement
    # both machines about as busy, but beyond the case's 2 threads on 2 cores: 84x with 83x the CPU
    # time in one rerun (a busy loop beside B, bursty load during A); nothing can tell
    assert judge_time(row(1, 1.9, 0.88), row(84, 83 * 1.9, 1.0), cores=2, threads=(2, 2)) == "inconclusive"
    assert judge_time({**a, "others_cpu": None}, row(8, 2.8 * 1.9, 1.4), cores=2, threads=(2, 2)) == "inconclusive"
    # samples that used one core, but two threads busy (a BLAS pool spinning for a core): excused;
    # one busy thread, 10x the wall and CPU time on a machine 0.6 core busier: a regression
    # (another review: the run's 2 threads per case alone excused every such case)
    assert judge_time(row(1, 1, 0.88, 2), row(84, 83, 1.0, 2), cores=2, threads=(2, 2)) == "inconclusive"
    assert judge_time(row(1, 1, 0.0, 1), row(10, 10, 0.6, 1), cores=2, threads=(2, 2)) == "regression"
    assert judge_time(row(1, 1, 0.0), row(10, 10, 0.6), cores=2, threads=(2, 2)) == "regression"      # u = 1


def test_a_verdict_must_hold_on_the_raw_times_and_a_common_slowdown_is_the_whole_runs():
    """An outside review: six cases made 2x slower and three unchanged gave a drift of 2, so the
    three unchanged cases were called improvements ('B/A 0.502x') and the six slowed ones passed
    (exit 0). Now a verdict must also hold on the raw times, and a drift of 1.5x or more while
    the machines were as busy is a regression of the whole run."""
    from harness.compare import compare_rows
    rng = np.random.default_rng(4)

    def row(k, others=0.1):
        t = list(0.01 * k * (1 + 0.05 * rng.random(12)))
        return {**_row(t), "cpu_times": json.dumps(t), "others_cpu": others, "status": "ok", "task": "smoothing",
                "method": "m", "mesh": "x", "params": "{}"}
    ids = [f"c{i}" for i in range(9)]
    A = {c: {**row(1), "case_id": c} for c in ids}
    B = {c: {**row(2 if i < 6 else 1), "case_id": c} for i, c in enumerate(ids)}
    res = compare_rows(A, B)
    verdicts = {c["case_id"]: c["verdict"] for c in res["changes"] if c["metric"] == "time_s"}
    assert res["drift"] == pytest.approx(2, rel=0.1)
    assert all(verdicts[c] in ("within tolerance", "inconclusive") for c in ids[6:]), verdicts    # no false improvement
    assert verdicts["(all cases)"] == "regression"
    sparse = {c: {**r, "others_cpu": None if i > 1 else 0.1} for i, (c, r) in enumerate(A.items())}
    assert "(all cases)" in {c["case_id"] for c in compare_rows(sparse, B)["changes"]}   # each run's own median
    blank = {c: {**r, "others_cpu": None} for c, r in B.items()}              # load not measured: the CPU
    assert "(all cases)" in {c["case_id"] for c in compare_rows(A, blank)["changes"]}   # time doubled too
    sleeps = {c: {**r, "cpu_times": A[c]["cpu_times"]} for c, r in blank.items()}
    assert "(all cases)" not in {c["case_id"] for c in compare_rows(A, sleeps)["changes"]}
    busy = {c: {**r, "others_cpu": 1.2, "cpu_times": A[c]["cpu_times"]} for c, r in B.items()}   # busier, same CPU:
    assert "(all cases)" not in {c["case_id"] for c in compare_rows(A, busy)["changes"]}     # the load's
    worked = {c: {**r, "others_cpu": 1.2} for c, r in B.items()}                # busier, but 2x the CPU time
    assert "(all cases)" in {c["case_id"] for c in compare_rows(A, worked)["changes"]}      # with one thread
    assert "(all cases)" not in {c["case_id"] for c in compare_rows(A, B, absolute_time=True)["changes"]}
    same = compare_rows(A, {c: {**row(1), "case_id": c} for c in ids})
    assert not [c for c in same["changes"] if c["verdict"] in ("regression", "improvement")]


def test_two_worker_runs_excuse_a_wall_time_change_that_load_explains(run_a, tmp_path):
    """Between two runs with two workers (siblings count as other processes), a case whose wall
    time doubled while its CPU time did not, on a machine with fewer free cores than the case
    used, is inconclusive, not a regression (a rerun of the same code under an outside load);
    with 4x the CPU time it is a regression."""
    a, b = copy(run_a, tmp_path, "a2"), copy(run_a, tmp_path, "b2")
    for d in (a, b):
        meta = json.loads((d / "run.json").read_text())
        meta["workers"] = 2
        meta.setdefault("timing", {})["threads_per_case"] = 1
        meta.setdefault("machine", {})["cpu_count"] = 2
        (d / "run.json").write_text(json.dumps(meta))

    def busy(others, wall=1.0, cpu=1.0):
        def fn(rows):
            r = rows[0]
            n = len(json.loads(r["times"]))
            t = [0.02 * wall * (1 + 0.01 * i) for i in range(max(n, 12))]
            c = [0.02 * cpu * (1 + 0.01 * i) for i in range(len(t))]
            r.update(times=json.dumps(t), time_s=str(sorted(t)[len(t) // 2]), time_min_s=str(min(t)),
                     time_max_s=str(max(t)), cpu_times=json.dumps(c), others_cpu=str(others))
        return fn
    # measured between two runs of the same code: B's machine had 0.49 core more load, which left
    # the single-threaded case 0.535 of a core (2 - 1.465): 1.87x slower from the load alone
    edit(a / "laplacian.csv", busy(0.978))
    edit(b / "laplacian.csv", busy(1.465, wall=2.3, cpu=1.1))
    code, out = run_compare(a, b)
    assert code == 0 and "inconclusive" in out, out
    edit(b / "laplacian.csv", busy(1.465, wall=4.0, cpu=4.0))
    code, out = run_compare(a, b)
    assert code == 1 and any(ln.startswith("REGRESSION") and "time_s" in ln for ln in out.splitlines()), out


def test_rules():
    assert judge("hausdorff", 0.010, 0.0102) == "regression"          # +2 %
    assert judge("hausdorff", 0.010, 0.01005) == "same"               # +0.5 %
    assert judge("hausdorff", 1e-9, 5e-7) == "same"                   # tiny in absolute terms
    assert judge("min_angle", 20.0, 19.0) == "regression"             # higher is better
    assert judge("min_eig", -1e-17, -1e-3) == "regression"
    assert judge("volume_ratio", 0.98, 1.01) == "improvement"         # closer to 1
    assert judge("volume_ratio", 0.99, 1.03) == "regression"
    assert judge("out_faces", 500, 502, None, {"target_faces": 500}) == "same"
    assert judge("out_faces", 500, 480, None, {"target_faces": 500}) == "regression"
    assert judge("psd", True, False) == "regression" and judge("topology_changed", True, False) == "improvement"
    assert judge("peak_rss_mb", 100.0, 900.0) == "changed"             # informational only


def test_not_a_run_folder_is_a_usage_error(run_a, tmp_path):
    assert cli(["compare", str(run_a), str(tmp_path / "nope")]) == 2


def test_benchmark_json_layout(run_a):
    path = run_a.parent / "bench.json"            # written by harness.run(..., export_benchmark_json=...)
    doc = json.loads(path.read_text())
    assert {"machine_info", "commit_info", "benchmarks", "datetime", "version"} <= doc.keys()
    assert {"node", "processor", "machine", "python_version", "system", "cpu"} <= doc["machine_info"].keys()
    assert {"id", "time", "dirty", "project", "branch"} <= doc["commit_info"].keys()
    rows = {}
    for task in ("laplacian", "smoothing", "simplification"):
        for r in csv.DictReader((run_a / f"{task}.csv").open()):
            rows[r["case_id"]] = r
    assert len(doc["benchmarks"]) == len(rows) == 5
    for b in doc["benchmarks"]:
        assert {"group", "name", "fullname", "params", "param", "extra_info", "options", "stats"} <= b.keys()
        s = b["stats"]
        assert {"min", "max", "mean", "stddev", "rounds", "median", "iqr", "q1", "q3", "outliers", "ops",
                "total", "iterations", "ld15iqr", "hd15iqr", "iqr_outliers", "stddev_outliers"} <= s.keys()
        r = rows[b["extra_info"]["case_id"]]
        assert s["median"] == float(r["time_s"]) and s["min"] == float(r["time_min_s"])
        times = json.loads(r["times"])
        assert s["max"] == float(r["time_max_s"]) and s["rounds"] == int(r["repeats"]) == len(times) >= 3
        assert abs(s["mean"] - sum(times) / len(times)) <= 1e-12 * s["mean"] and "stats_note" not in b["extra_info"]
        assert s["min"] <= s["q1"] <= s["median"] <= s["q3"] <= s["max"] and s["min"] <= s["mean"] <= s["max"]


def test_pytest_benchmark_reads_the_export(run_a):
    """pytest-benchmark's own `compare` command loads and tabulates the file."""
    path = run_a.parent / "bench.json"
    r = subprocess.run([sys.executable, "-m", "pytest_benchmark", "compare", str(path), "--columns=min,median,max,rounds"],
                       capture_output=True, text=True, timeout=60, cwd=run_a.parent)
    assert r.returncode == 0, r.stderr
    assert "Failed to load" not in r.stderr + r.stdout
    assert "scratch.cotan[mass=voronoi]" in r.stdout and "laplacian/knight/gaussian_normal-0.3" in r.stdout


def test_time_can_be_left_out(run_a, tmp_path):
    b = copy(run_a, tmp_path)

    def slow(rows):
        r = rows[0]
        t = [x * 10 + 0.01 for x in json.loads(r["times"])]
        c = [x * 10 + 0.01 for x in json.loads(r["cpu_times"])]      # more work: CPU time grows too
        r.update(times=json.dumps(t), time_s=str(sorted(t)[len(t) // 2]), time_min_s=str(min(t)), time_max_s=str(max(t)),
                 cpu_times=json.dumps(c))
    edit(b / "laplacian.csv", slow)
    assert run_compare(run_a, b)[0] == 1
    code, out = run_compare(run_a, b, time_factor=None)
    assert code == 0 and "time not compared" in out


def test_output_files_are_checked_before_any_work(run_a, tmp_path, capsys):
    """--html on a folder and --time-factor nan are exit 2 (a traceback was exit 1, which CI reads
    as a regression; nan silently turned the time gate off); --export-benchmark-json naming a
    folder or the config being run is refused before the run."""
    assert cli(["compare", str(run_a), str(run_a), "--html", str(tmp_path)]) == 2
    before = (run_a / "smoothing.csv").read_bytes()
    assert cli(["compare", str(run_a), str(run_a), "--html", str(run_a / "smoothing.csv")]) == 2
    assert (run_a / "smoothing.csv").read_bytes() == before
    assert cli(["compare", str(run_a), str(run_a), "--time-factor", "nan"]) == 2
    capsys.readouterr()
    assert cli(["compare", str(run_a), str(tmp_path / "nope"), "--time-factor", "0.5", "--no-time",
                "--html", str(tmp_path)]) == 2
    err = capsys.readouterr().err                   # every problem in one message
    assert "4 problems" in err and "not a run folder" in err and "--time-factor: expected" in err
    assert "--no-time compares no times" in err and "is a folder" in err and "got 0.5" in err
    assert cli(["compare", str(run_a), str(run_a), "--html", str(tmp_path / "new" / "d.html")]) == 0
    assert (tmp_path / "new" / "d.html").is_file()
    cfg = tmp_path / "c.json"
    cfg.write_text(json.dumps(SMALL))
    before = cfg.read_bytes()
    for target in (tmp_path, cfg, "/proc/nope/x.json"):     # /proc: access() says writable to root
        assert cli(["run", str(cfg), "--out", str(tmp_path / "o"), "--export-benchmark-json", str(target)]) == 2
    assert cfg.read_bytes() == before and not (tmp_path / "o").exists()
    assert cli(["compare", str(run_a), str(run_a), "--html", "/proc/x.html"]) == 2
    # inside a run folder (its views/ etc.) or the run folder itself, not yet made: a finished run
    # crashed on it, or the views' index was replaced by the export
    o = tmp_path / "o"
    for target in (o, o / "views" / "index.json", o / "views"):
        assert cli(["run", str(cfg), "--out", str(o), "--export-benchmark-json", str(target)]) == 2
    assert not o.exists()
    index = (run_a / "views" / "index.json").read_bytes()
    assert cli(["compare", str(run_a), str(run_a), "--html", str(run_a / "views" / "index.json")]) == 2
    assert (run_a / "views" / "index.json").read_bytes() == index
    with pytest.raises(harness.errors.ShootoutError, match="is the run folder itself"):   # from Python too
        harness.run(SMALL, out=o, export_benchmark_json=o)
    assert not o.exists()
    exports = run_a / "exports" / "d.html"            # another folder of the user's inside it: allowed
    assert cli(["compare", str(run_a), str(run_a), "--html", str(exports)]) == 0 and exports.is_file()
    shutil.rmtree(run_a / "exports")
    # an existing file of another kind (a config's mesh, notes) is never overwritten by an export
    mesh = tmp_path / "myscan.obj"
    mesh.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    with pytest.raises(harness.errors.ShootoutError, match="is not a benchmark export"):
        harness.run(SMALL, out=tmp_path / "o2", export_benchmark_json=mesh)
    assert cli(["compare", str(run_a), str(run_a), "--html", str(mesh)]) == 2
    assert mesh.read_text().startswith("v 0 0 0") and not (tmp_path / "o2").exists()
    from harness.results import OUTPUT_KINDS
    assert OUTPUT_KINDS["json"][1](run_a.parent / "bench.json")                    # an export is replaced
    assert cli(["compare", str(run_a), str(run_a), "--html", str(tmp_path / "new" / "d.html")]) == 0   # its own: again
    loop = tmp_path / "loop"
    loop.symlink_to(loop)
    assert cli(["run", str(cfg), "--out", str(loop)]) == 2
    assert cli(["compare", str(run_a), str(run_a), "--html", str(loop / "x.html")]) == 2


def test_the_terminal_names_each_changed_case_by_id_and_no_time_prints_no_timing_note(run_a, tmp_path):
    """Two cases whose labels differ only past the column width stay distinguishable: every
    change line carries its case id; ``time_factor=None`` (``--no-time``) prints no timing note."""
    b = copy(run_a, tmp_path)
    rows = list(csv.DictReader((b / "smoothing.csv").open()))
    edit(b / "smoothing.csv", lambda rows: [r.update(dist_mean=str(float(r["dist_mean"]) * 1.05)) for r in rows])
    code, out = run_compare(run_a, b)
    assert code == 1
    for r in rows:
        assert any(line.startswith("REGRESSION") and r["case_id"] in line and "dist_mean" in line
                   for line in out.splitlines()), (r["case_id"], out)
    code, out = run_compare(run_a, b, time_factor=None)
    assert code == 1 and not any(line.startswith("note:") for line in out.splitlines()), out


def test_a_run_of_an_unknown_task_kind_is_named_as_such(run_a, tmp_path):
    """A run made by an installation with another task kind (a fork's `area`) is not called
    'not a run folder': the message names the unknown kind."""
    b = copy(run_a, tmp_path)
    for f in b.glob("*.csv"):
        f.unlink()
    (b / "area.csv").write_text("case_id,task\nx,area\n")
    meta = json.loads((b / "run.json").read_text())
    meta["tasks"] = {"area": {"name": "area"}}
    (b / "run.json").write_text(json.dumps(meta))
    with pytest.raises(harness.errors.ShootoutError, match="task kind\\(s\\) area are not known to this installation"):
        run_compare(b, run_a)
    # beside a known kind's rows too (a review: compare left the area rows out, exit 0 on their regression)
    c = copy(run_a, tmp_path, "c")
    (c / "area.csv").write_text("case_id,task\nx,area\n")
    meta = json.loads((c / "run.json").read_text())
    meta["tasks"] = {**meta["tasks"], "area": {"name": "area"}}
    (c / "run.json").write_text(json.dumps(meta))
    for a, z in ((c, run_a), (run_a, c)):
        with pytest.raises(harness.errors.ShootoutError, match="area are not known to this installation.*could not be compared"):
            run_compare(a, z)


def test_report_load_run_and_a_fresh_run_with_a_task_kind_not_installed(run_a, tmp_path, capsys):
    """Before: `shootout report` replaced a good report with 'No rows' and `load_run` returned an
    empty frame for a run of a kind not installed here; a fresh run into that folder left the old
    `area.csv` beside the new rows (load_run, the report and compare then showed it); and
    `shootout report` on a folder of the user's (any CSV) replaced their report.html."""
    b = copy(run_a, tmp_path)
    (b / "area.csv").write_text("case_id,task\nx,area\n")
    meta = json.loads((b / "run.json").read_text())
    meta["tasks"]["area"] = {"name": "area"}
    (b / "run.json").write_text(json.dumps(meta))
    before = (b / "report.html").read_bytes()
    assert cli(["report", str(b)]) == 2
    assert "task kind(s) ['area'] whose module is not installed" in capsys.readouterr().err
    assert (b / "report.html").read_bytes() == before
    with pytest.raises(harness.errors.ShootoutError, match="area"):
        harness.load_run(b)
    cfg = {**SMALL, "tasks": {"smoothing": SMALL["tasks"]["smoothing"]}}
    harness.run(cfg, out=b, quiet=True, workers=1)
    assert not (b / "area.csv").exists() and not (b / "laplacian.csv").exists()
    assert set(harness.load_run(b)["task"]) == {"smoothing"}
    mine = tmp_path / "mine"
    mine.mkdir()
    (mine / "data.csv").write_text("a,b\n1,2\n")
    (mine / "report.html").write_text("<html>mine</html>")
    assert cli(["report", str(mine)]) == 2
    assert (mine / "report.html").read_text() == "<html>mine</html>"
    assert "not a run folder of mesh-shootout" in capsys.readouterr().err


def test_compare_matches_eval_rows_by_file_not_by_position(tmp_path):
    """Two evals of the same two files given in the opposite order compare equal (eval's case
    ids were eval0000, eval0001: the files were compared crosswise, 12 false regressions), and a
    case id whose rows describe different cases is listed, not judged."""
    import pandas as pd

    from harness.datasets import load
    from harness.mesh import write_obj
    src = load("knight").clean
    files = []
    for k, s in enumerate((0.001, 0.01)):
        p = tmp_path / f"r{k}.obj"
        write_obj(p, src.V + s * np.sin(np.arange(src.V.size)).reshape(-1, 3), src.F)
        files.append(p)
    clean = tmp_path / "clean.obj"
    write_obj(clean, src.V, src.F)
    for name, order in (("E1", files), ("E2", files[::-1])):
        labels = sum((["--label", p.stem] for p in order), [])
        assert cli(["eval", *map(str, order), "--clean", str(clean), *labels, "--out", str(tmp_path / name)]) == 0
    out = io.StringIO()
    assert compare_runs(tmp_path / "E1", tmp_path / "E2", time_factor=None, out=out) == 0
    assert "0 regression(s)" in out.getvalue() and "2 cases in both" in out.getvalue(), out.getvalue()
    # a new version of one output under its label, given by another path: compared with the old one
    v2 = tmp_path / "v2"
    v2.mkdir()
    write_obj(v2 / "r0.obj", src.V + 0.02 * np.sin(np.arange(src.V.size)).reshape(-1, 3), src.F)
    assert cli(["eval", str(v2 / "r0.obj"), str(files[1]), "--clean", str(clean), "--out", str(tmp_path / "E4")]) == 0
    out = io.StringIO()
    assert compare_runs(tmp_path / "E1", tmp_path / "E4", time_factor=None, out=out) == 1
    assert "2 cases in both" in out.getvalue() and "not compared: the rows" not in out.getvalue(), out.getvalue()
    assert "REGRESSION" in out.getvalue() and "dist_mean" in out.getvalue()
    # the same ids on rows of other cases (a run folder edited by hand): listed as not compared
    shutil.copytree(tmp_path / "E1", tmp_path / "E3")
    csv_path = tmp_path / "E3" / "smoothing.csv"
    df = pd.read_csv(csv_path)
    df["method"] = df["method"][::-1].values
    df.to_csv(csv_path, index=False)
    out = io.StringIO()
    assert compare_runs(tmp_path / "E1", tmp_path / "E3", time_factor=None, out=out) == 0
    assert out.getvalue().count("not compared: the rows describe different cases (method differ)") == 2, out.getvalue()


def test_compare_judges_with_the_baselines_rules_and_says_when_they_differ(run_a, tmp_path):
    """B's run.json declaring a looser tolerance (or the other direction) for a metric does not
    excuse B's regression: the baseline's rule decides, and a note names the metric."""
    a = run_a
    b = copy(run_a, tmp_path)
    edit(b / "smoothing.csv", lambda rows: rows[0].update(dist_mean=repr(float(rows[0]["dist_mean"]) * 1.3)))
    meta = json.loads((b / "run.json").read_text())
    for m in meta["tasks"]["smoothing"]["metrics"]:
        if m["name"] == "dist_mean":
            m["rel"], m["better"] = 0.5, "higher"
    (b / "run.json").write_text(json.dumps(meta))
    out = io.StringIO()
    assert compare_runs(a, b, time_factor=None, out=out) == 1
    text = out.getvalue()
    assert "smoothing.dist_mean" in text and "A's (the baseline's) are used" in text, text
    assert "REGRESSION" in text and "dist_mean" in text


def test_benchmark_export_names_each_seed(tmp_path):
    """With two seeds of one noise level, the export's rows of one group had the same name (the
    seed only in fullname), so pytest-benchmark compare showed two identical-looking rows."""
    from harness.benchmark_json import build
    harness.run({**SMALL, "noise": [{"model": "gaussian_normal", "levels": [0.3], "seeds": 2}],
                 "tasks": {"smoothing": {"methods": ["scratch.taubin"]}}}, out=tmp_path / "o", quiet=True, workers=1)
    doc = build(tmp_path / "o")
    names = [(b["group"], b["name"]) for b in doc["benchmarks"]]
    assert len(names) == 2 and len(set(names)) == 2, names
    assert all("[seed=" in n for _, n in names)


def test_compare_and_the_export_write_settings_as_a_config_does(run_a, tmp_path):
    """compare's case names and the benchmark JSON's names wrote Python's ``True`` and left text
    unquoted, so ``tag: "true"`` and ``tag: true`` had one name; they now write each value as the
    report's labels do (`label_value`)."""
    from harness.benchmark_json import build
    from harness.compare import _label
    row = {"mesh": "m", "noise_model": "none", "noise_level": "", "method": "x",
           "params": json.dumps({"flag": True, "tag": "true", "none": None, "solver": "scipy"})}
    assert _label(row) == 'm none x[flag=true,solver=scipy,tag="true"]'
    b = copy(run_a, tmp_path)
    edit(b / "smoothing.csv", lambda rows: [r.update(params=json.dumps({**json.loads(r["params"]), "flag": True,
                                                                         "tag": "null"})) for r in rows])
    names = [x["name"] for x in build(b)["benchmarks"] if x["group"].startswith("smoothing/")]
    assert names and all('flag=true' in n and 'tag="null"' in n for n in names), names


def test_benchmark_json_stats_are_pytest_benchmarks_own():
    """An outside review: the export's quartiles (numpy's interpolation) differed from
    pytest-benchmark's in every benchmark, and so did some outlier counts and Tukey fences; the
    docstring said they were computed as pytest-benchmark computes them. Now they are, for
    sample counts 1 to 12 and samples with ties."""
    stats_mod = pytest.importorskip("pytest_benchmark.stats")
    from harness.benchmark_json import stats_from_row
    rng = np.random.default_rng(3)
    for n in range(1, 13):
        for _ in range(20):
            t = np.round(rng.lognormal(-7, 0.5, n), 6 if n % 3 else 4).tolist()     # ties on some
            mine = stats_from_row({"time_s": float(np.median(t)), "times": json.dumps(t)})
            ref = stats_mod.Stats()
            for x in t:
                ref.update(x)
            for k in ("q1", "q3", "iqr", "iqr_outliers", "stddev_outliers", "ld15iqr", "hd15iqr", "median",
                      "mean", "stddev", "min", "max", "rounds", "total"):
                assert mine[k] == pytest.approx(getattr(ref, k), rel=1e-12, abs=1e-18), (n, k, t)


def test_the_same_machine_is_not_called_another_for_a_key_one_version_records_alone():
    """An outside review: a baseline written before run.json recorded ``usable_cpus`` was said
    to come from a different machine."""
    from harness.compare import timing_notes
    m = {"node": "n", "cpu": "x", "cpu_count": 2}
    res = {"changes": [], "rows_a": {}, "rows_b": {}, "drift": 1.0}
    assert not any("different machines" in n for n in timing_notes({"machine": m}, {"machine": {**m, "usable_cpus": 2}}, res))
    assert any("different machines" in n for n in timing_notes({"machine": m}, {"machine": {**m, "cpu_count": 8}}, res))
    assert not any("others_cpu" in n for n in timing_notes({"machine": m}, {"machine": m}, res))   # nothing measured


def test_the_second_review_of_the_time_rules():
    """A review of the mends: (1) short cases (no load measured on either side) of a BLAS method
    beside a busy loop were a 38x regression with 38x the CPU time; (2) a whole run 10x slower
    with 2 workers (the sibling in others_cpu) was never reported; (3) a single-threaded case 10x
    slower in wall and CPU time beside a full busy loop was excused; (4) threads_busy inf
    crashed."""
    from harness.compare import compare_rows
    rng = np.random.default_rng(5)

    def row(k_wall, k_cpu, others=None, busy=None, n=12):
        t = list(0.01 * (1 + 0.05 * rng.random(n)))
        return {**_row([k_wall * x for x in t]), "cpu_times": json.dumps([k_cpu * x for x in t]),
                "others_cpu": others, "threads_busy": busy, "status": "ok", "task": "smoothing", "method": "m",
                "mesh": "x", "params": "{}"}
    # (1) neither window measured the load, two threads busy: inconclusive; one thread: judged
    assert judge_time(row(1, 1, busy=2), row(38, 38, busy=2), cores=2, threads=(2, 2)) == "inconclusive"
    assert judge_time(row(1, 1, busy=1), row(38, 38, busy=1), cores=2, threads=(2, 2)) == "regression"
    # (3) one thread, 10x the CPU time, beside a full busy loop: a regression; 1x the CPU: load
    assert judge_time(row(1, 1, 0.05, 1), row(10, 10, 1.05, 1), cores=2, threads=(2, 2)) == "regression"
    assert judge_time(row(1, 1, 0.05, 1), row(10, 1, 1.05, 1), cores=2, threads=(2, 2)) == "inconclusive"
    # (2) two workers, one thread each, the sibling as others_cpu 1.0 in both: the whole run's 10x is seen
    ids = [f"c{i}" for i in range(8)]
    A = {c: {**row(1, 1, 1.0, 1), "case_id": c} for c in ids}
    B = {c: {**row(10, 10, 1.0, 1), "case_id": c} for c in ids}
    assert "(all cases)" in {c["case_id"] for c in compare_rows(A, B, cores=2, threads=(1, 1))["changes"]}
    # ... and beside a busy loop (others 1.4), seen only because the CPU time grew 10x with one thread busy
    B2 = {c: {**r, "others_cpu": 1.4} for c, r in B.items()}
    assert "(all cases)" in {c["case_id"] for c in compare_rows(A, B2, cores=2, threads=(1, 1))["changes"]}
    B3 = {c: {**row(10, 1, 1.4, 1), "case_id": c} for c in ids}                 # wall only: the load's
    assert "(all cases)" not in {c["case_id"] for c in compare_rows(A, B3, cores=2, threads=(1, 1))["changes"]}
    # (1b) one run unmeasured, the other oversubscribed with two threads busy: not the code's
    A4 = {c: {**row(1, 1), "case_id": c} for c in ids}
    B4 = {c: {**row(20, 20, 0.7, 2), "case_id": c} for c in ids}
    assert "(all cases)" not in {c["case_id"] for c in compare_rows(A4, B4, cores=2, threads=(2, 2))["changes"]}
    # (4) a hand-edited inf
    assert judge_time(row(1, 1, 0.0, float("inf")), row(10, 10, 1.2, 1), cores=2, threads=(2, 2)) in (
        "regression", "inconclusive")


def test_the_third_review_of_the_time_rules():
    """A review of the second mends: (1) single-threaded ms cases with no load measured, 2x the
    wall time and the same CPU time beside load: a false regression; (2) a real 2x slowdown in
    wall and CPU time at a load stretch of 1.25 was excused; (3) every case 2x slower with 2
    workers beside 0.3 core more load: no whole-run line, every case 'within tolerance'."""
    from harness.compare import compare_rows
    rng = np.random.default_rng(6)

    def row(k_wall, k_cpu, others=None, busy=None, base=0.004):
        t = list(base * (1 + 0.05 * rng.random(25)))
        return {**_row([k_wall * x for x in t]), "cpu_times": json.dumps([k_cpu * x for x in t]),
                "others_cpu": others, "threads_busy": busy, "status": "ok", "task": "smoothing", "method": "m",
                "mesh": "x", "params": "{}"}
    assert judge_time(row(1, 1, busy=1), row(2, 1, busy=1), cores=2, threads=(2, 2)) == "inconclusive"   # (1)
    assert judge_time(row(1, 1, busy=1), row(2, 2, busy=1), cores=2, threads=(2, 2)) == "regression"
    for k in (2.0, 2.9):                                                                                 # (2)
        assert judge_time(row(1, 1, 1.0, 1, 0.05), row(k, k, 1.2, 1, 0.05), cores=2, threads=(1, 1)) == "regression"
    ids = [f"c{i}" for i in range(8)]                                                                    # (3)
    A = {c: {**row(1, 1, 1.0, 1), "case_id": c} for c in ids}
    B = {c: {**row(2, 2, 1.3, 1), "case_id": c} for c in ids}
    res = compare_rows(A, B, cores=2, threads=(1, 1))
    verdicts = {c["case_id"]: c["verdict"] for c in res["changes"] if c["metric"] == "time_s"}
    assert verdicts.pop("(all cases)") == "regression"
    assert set(verdicts.values()) <= {"regression", "inconclusive"}, verdicts      # never 'within tolerance'


def test_the_others_cpu_note_gives_the_true_median_as_the_report_does():
    """`compare`'s note on other processes' load took the upper median of an even count, where
    the report's header takes the true median."""
    from harness.compare import timing_notes
    m = {"node": "n", "cpu": "x", "cpu_count": 2}
    rows = {c: {"others_cpu": v} for c, v in zip("abcd", ("0.1", "0.2", "0.4", "0.9"))}
    res = {"changes": [], "rows_a": rows, "rows_b": rows, "drift": 1.0}
    note = next(n for n in timing_notes({"machine": m}, {"machine": m}, res) if "others_cpu" in n)
    assert "A 0.3 (max 0.9, 4 cases)" in note, note


def test_an_infinite_baseline_is_no_tolerance_for_any_value():
    """An outside review: a hand-edited baseline of inf made the tolerance infinite, so any finite
    value of B was 'within tolerance' (this version writes no inf; older ones did). Listings show
    it as inf, not as a missing value."""
    from harness.compare import Rule, judge
    lower, higher = Rule("lower", 0.01, 0.0), Rule("higher", 0.01, 0.0)
    inf = float("inf")
    assert judge("m", inf, 1.0, rule=lower) == "improvement" and judge("m", 1.0, inf, rule=lower) == "regression"
    assert judge("m", -inf, 1.0, rule=higher) == "improvement" and judge("m", inf, inf, rule=lower) == "same"
    from harness.schema import fmt
    assert (fmt(inf), fmt(-inf), fmt("inf"), fmt(float("nan"))) == ("inf", "-inf", "inf", "—")


def test_a_case_label_names_its_seed():
    """An outside review: two regression lines of one method on two seeds read the same."""
    from harness.compare import _label
    r = {"mesh": "woody", "noise_model": "gaussian_normal", "noise_level": 0.3, "method": "meshlab.hc",
         "params": '{"iterations": 1}'}
    assert _label({**r, "seed": 1}) == "woody gaussian_normal 0.3 seed 1 meshlab.hc[iterations=1]"
    assert _label({**r, "seed": 2}) != _label({**r, "seed": 1}) and "seed" not in _label({**r, "seed": ""})


def test_other_measurement_settings_are_noted(tmp_path, capsys):
    """A review: a rerun with hausdorff_samples 20001 compared case by case with no word that
    the sampled metrics were sampled otherwise; run.json records the settings, compare notes them."""
    import harness
    from harness.compare import compare_runs
    cfg = {"name": "ms", "repeats": 1, "time_budget": 0, "meshes": ["knight"], "noise": [{"model": "none"}],
           "tasks": {"simplification": {"methods": ["fast_simplification.qem"], "params": {"target_ratio": [0.5]}}}}
    harness.run({**cfg, "hausdorff_samples": 500}, out=tmp_path / "a", quiet=True, workers=1)
    harness.run({**cfg, "hausdorff_samples": 501}, out=tmp_path / "b", quiet=True, workers=1)
    meta = json.loads((tmp_path / "a" / "run.json").read_text())
    assert meta["measurement"] == {"hausdorff_samples": 500, "hausdorff_eps": 0.001, "sample_seed": 0}
    compare_runs(tmp_path / "a", tmp_path / "b", time_factor=None)
    out = capsys.readouterr().out
    assert "note: the runs measured with other settings (hausdorff_samples A 500, B 501)" in out, out
    compare_runs(tmp_path / "a", tmp_path / "a", time_factor=None)
    assert "other settings" not in capsys.readouterr().out


def test_an_older_baseline_without_standard_errors_still_reads_them(tmp_path, capsys):
    """A review: with A from a version whose run.json declares no standard-error column, A's
    rules won and a change within sampling noise was a regression, with a note of other rules."""
    import harness
    from harness.compare import compare_runs
    cfg = {"name": "se", "repeats": 1, "time_budget": 0, "meshes": ["knight"], "noise": [{"model": "none"}],
           "tasks": {"simplification": {"methods": ["fast_simplification.qem"], "params": {"target_ratio": [0.5]}}}}
    for d in ("a", "b"):
        harness.run(cfg, out=tmp_path / d, quiet=True, workers=1)
    meta = json.loads((tmp_path / "a" / "run.json").read_text())
    for m in meta["tasks"]["simplification"]["metrics"]:
        m.pop("se", None), m.pop("se_z", None)
    (tmp_path / "a" / "run.json").write_text(json.dumps(meta))
    import pandas as pd
    p = tmp_path / "b" / "simplification.csv"
    df = pd.read_csv(p)
    df["surface_dist_mean"] *= 1.015                 # 1.5%: beyond the 1% tolerance, within 3 standard errors
    df["surface_dist_mean_se"] = df["surface_dist_mean"] * 0.005
    df.to_csv(p, index=False)
    assert compare_runs(tmp_path / "a", tmp_path / "b", time_factor=None) == 0
    out = capsys.readouterr().out
    assert "REGRESSION" not in out and "other rules" not in out, out


def test_runs_measured_with_other_settings_are_not_false_regressions(run_a, tmp_path):
    """A review: a run with hausdorff_eps 0.3 (bracket [0.009477, 0.012224]) against one with the
    default (0.009646, inside it) was a REGRESSION of hausdorff, exit 1; with hausdorff_samples 0
    the blank surface_dist_mean was one too. Certified brackets now count only where they lie
    apart, and a value one run's settings did not measure is a change."""
    from harness.compare import RULES
    rule = RULES["hausdorff"]
    assert rule.upper == "hausdorff_upper"
    a = {"hausdorff": 0.009477, "hausdorff_upper": 0.012224}
    b = {"hausdorff": 0.009646, "hausdorff_upper": 0.009655}
    assert judge("hausdorff", a["hausdorff"], b["hausdorff"], a, b, rule=rule) == "same"
    assert judge("hausdorff", b["hausdorff"], a["hausdorff"], b, a, rule=rule) == "same"
    far = {"hausdorff": 0.0125, "hausdorff_upper": 0.0126}                 # above A's whole bracket
    assert judge("hausdorff", a["hausdorff"], far["hausdorff"], a, far, rule=rule) == "regression"
    assert judge("hausdorff", far["hausdorff"], b["hausdorff"], far, b, rule=rule) == "improvement"
    assert judge("hausdorff", 0.01, 0.0102, {}, {}, rule=rule) == "regression"     # no bracket stored: as before
    c = copy(run_a, tmp_path, "c")
    meta = json.loads((c / "run.json").read_text())
    meta["measurement"] = {**meta["measurement"], "hausdorff_samples": 0}
    (c / "run.json").write_text(json.dumps(meta))
    edit(c / "simplification.csv", lambda rows: [r.update(surface_dist_mean="", surface_dist_mean_se="")
                                                 for r in rows])
    code, out = run_compare(run_a, c, time_factor=None)
    assert code == 0 and "REGRESSION" not in out and "not measured by one run's settings" in out, out
    meta["measurement"] = json.loads((run_a / "run.json").read_text())["measurement"]
    (c / "run.json").write_text(json.dumps(meta))                          # the same settings: a lost value
    code, out = run_compare(run_a, c, time_factor=None)
    assert code == 1 and "surface_dist_mean" in out, out
    d = copy(run_a, tmp_path, "d")                  # another eps blanks nothing: a lost column still regresses
    meta = json.loads((d / "run.json").read_text())
    meta["measurement"] = {**meta["measurement"], "hausdorff_eps": 0.3}
    (d / "run.json").write_text(json.dumps(meta))
    edit(d / "smoothing.csv", lambda rows: [r.update(min_angle="") for r in rows])
    code, out = run_compare(run_a, d, time_factor=None)
    assert code == 1 and "REGRESSION" in out and "min_angle" in out, out


def test_a_baselines_recorded_rules_that_no_version_writes_are_not_used(run_a, tmp_path):
    """A review: a 10x worse dist_mean passed (exit 0) when A's run.json declared rel NaN, abs
    Infinity, better "bogus" (taken as higher is better: an "improvement") for it. Such a
    declaration is left out and the installed kind's rule applies."""
    b = copy(run_a, tmp_path)
    edit(b / "smoothing.csv", lambda rows: [r.update(dist_mean=str(float(r["dist_mean"]) * 10)) for r in rows])
    for i, bad in enumerate(({"rel": float("nan")}, {"abs": float("inf")}, {"better": "bogus"}, {"rel": -1})):
        a = copy(run_a, tmp_path, f"a{i}")
        meta = json.loads((a / "run.json").read_text())
        for m in meta["tasks"]["smoothing"]["metrics"]:
            if m["name"] == "dist_mean":
                m.update(bad)
        (a / "run.json").write_text(json.dumps(meta))
        code, out = run_compare(a, b, time_factor=None)
        assert code == 1 and "REGRESSION" in out and "dist_mean" in out, (bad, out)


def test_the_report_refuses_a_case_id_in_two_rows(run_a, tmp_path):
    """A review: a duplicated row weighted its seed 2/3 in the winners (dist_mean 16.7% off) and
    the status table counted 7 cases of 6. Every reader now refuses the folder (exit 2), as compare did."""
    b = copy(run_a, tmp_path)
    lines = (b / "smoothing.csv").read_text().splitlines(keepends=True)
    (b / "smoothing.csv").write_text("".join(lines + lines[1:2]))
    cid = lines[1].split(",")[0]
    r = subprocess.run([sys.executable, "-m", "harness.cli", "report", str(b)], capture_output=True, text=True,
                       cwd=Path(__file__).resolve().parents[1], timeout=300)
    assert r.returncode == 2 and f"case id {cid} appears in more than one row" in r.stderr, r.stderr
    with pytest.raises(harness.errors.ShootoutError, match="appears in more than one row"):
        harness.load_run(b)


def test_a_result_turned_invalid_regresses_though_its_metrics_stay_within_tolerance(run_a, tmp_path):
    """Both runs' rows are judged valid by the baseline's ``invalid_when`` rules: a smoothing result 0.4 % farther from the clean surface than before but now past its noisy
    input's distance (by more than the 1 % tolerance) is a regression, listed as ``validity``."""
    a, b = copy(run_a, tmp_path, "a"), copy(run_a, tmp_path, "b")
    for d, factor in ((a, 1.008), (b, 1.012)):
        edit(d / "smoothing.csv", lambda rows, f=factor: rows[0].update(
            dist_mean_sym=repr(float(rows[0]["input_dist_mean_sym"]) * f)))
    code, out = run_compare(a, b, time_factor=None)
    assert code == 1, out
    line = next(ln for ln in out.splitlines() if ln.startswith("REGRESSION"))
    assert " validity " in line and "valid" in line and "dist_mean_sym" not in line.split(" validity ")[0], out
    assert "1 regression(s)" in out and "1 change(s) within tolerance" in out, out
    code, out = run_compare(b, a, time_factor=None)       # back to valid: an improvement
    assert code == 0 and "1 improvement(s)" in out, out
    code, out = run_compare(b, b, time_factor=None)       # invalid in both: no change
    assert code == 0 and "validity" not in out, out


def test_validity_rules_that_changed_between_versions_are_no_regression(run_a, tmp_path):
    """A review: with each run judged by its own recorded rules, a baseline from a version before
    a new rule made every row the new rule catches a "regression" on upgrading. Both runs are
    judged by A's rules (as the metrics' tolerances), and a note says B declares others; a
    hand-edited rule no version writes gives way to the installed kind's."""
    b = copy(run_a, tmp_path)
    meta = json.loads((b / "run.json").read_text())
    rules = meta["tasks"]["smoothing"]["invalid_when"]
    meta["tasks"]["smoothing"]["invalid_when"] = rules + [{"column": "ev_mean", "op": ">", "value": 0.0,
                                                           "why": "a stricter rule of a later version"}]
    (b / "run.json").write_text(json.dumps(meta))
    for x, y in ((run_a, b), (b, run_a)):
        code, out = run_compare(x, y, time_factor=None)
        assert code == 0 and not [ln for ln in out.splitlines() if " validity " in ln and not ln.startswith("note")], out
        assert "B declares other validity rules (invalid_when) for smoothing" in out, out
    for bad in ([None], "x", [{"column": "ev_mean", "op": ">", "value": None}]):
        meta["tasks"]["smoothing"]["invalid_when"] = bad
        (b / "run.json").write_text(json.dumps(meta))
        code, out = run_compare(b, run_a, time_factor=None)
        assert code == 0 and not [ln for ln in out.splitlines() if " validity " in ln and not ln.startswith("note")], (bad, out)


@pytest.mark.parametrize("damage", ["missing", "torn"])
def test_a_run_json_that_cannot_be_read_is_named_not_taken_for_the_defaults(run_a, tmp_path, damage):
    """A review: with B's run.json gone or torn, compare printed 'the runs measured with other
    settings (hausdorff_samples A 2000, B 20000)', B's settings read as the defaults."""
    b = copy(run_a, tmp_path)
    if damage == "missing":
        (b / "run.json").unlink()
    else:
        (b / "run.json").write_text('{"name": "good", ')
    code, out = run_compare(run_a, b, time_factor=None)
    assert code == 0, out
    assert "other settings" not in out, out
    state = "missing" if damage == "missing" else "corrupt"
    assert f"note: B's run.json is {state}: its measurement settings, metric rules and validity rules are not known" \
        in out, out
    code, out = run_compare(b, run_a, time_factor=None)
    assert code == 0 and f"note: A's run.json is {state}" in out and "other settings" not in out, out


def test_a_row_recorded_before_a_rename_is_the_same_case():
    """A diff review of the shared parameter names: a run recorded with fast-simplification's agg /
    preserve_border (or before cotan_mean's signed existed) has the same case ids as one recorded
    after, and compare must compare those rows, not call them different cases because the params
    text differs."""
    from harness.compare import compare_rows
    base = {"task": "simplification", "mesh": "knight", "method": "fast_simplification.qem", "noise_model": "none",
            "noise_level": 0.0, "seed": 0, "status": "ok", "hausdorff": 0.01}
    a = {**base, "params": '{"agg": 7.0, "preserve_border": false, "target_ratio": 0.5}'}
    b = {**base, "params": '{"aggressiveness": 7.0, "preserve_boundary": false, "target_ratio": 0.5}', "hausdorff": 0.02}
    from harness.compare import param_ids
    from harness.session import task_specs
    from harness.config import load_config
    cfg = load_config({"name": "i", "meshes": ["knight"], "noise": [{"model": "none"}],
                       "tasks": {"simplification": {"methods": ["fast_simplification.qem"]}}})
    ids = param_ids({"tasks": task_specs(cfg)})        # as the newer run's run.json records them
    assert ids["fast_simplification.qem"]["aggressiveness"] == {"as": "agg"}
    out = compare_rows({"x": a}, {"x": b}, time_factor=None, ids=ids)
    assert [c["metric"] for c in out["changes"]] == ["hausdorff"], out["changes"]
    assert compare_rows({"x": a}, {"x": b}, time_factor=None)["changes"][0]["metric"] == "case"   # no record: differ
    c = {**base, "params": '{"aggressiveness": 3.0, "preserve_boundary": false, "target_ratio": 0.5}'}
    out = compare_rows({"x": a}, {"x": c}, time_factor=None, ids=ids)
    assert out["changes"][0]["metric"] == "case" and "params differ" in out["changes"][0]["note"]
