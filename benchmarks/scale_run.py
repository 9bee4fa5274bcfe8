"""Scale run (issue 7): a 1.3M-face procedural sphere through the runner.

Runs ``shootout run configs/scale.yaml --workers 1`` as a subprocess (the real CLI path:
isolated case processes, CSV rows appended as cases finish), watches the run folder to time
each case end to end (method + metrics), samples the resident memory of the whole process
tree, and prints per case: status, the method's time (``time_s``), the case's wall time,
``peak_rss_mb`` (getrusage of the case process, from the CSV) and a few metrics.

Methods of the config that are not registered/available here are dropped (printed).
Usage: python benchmarks/scale_run.py [--config configs/scale.yaml] [--out results/scale]
       [--subdivisions 8]
"""
from __future__ import annotations

import argparse
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import psutil
import yaml

ROOT = Path(__file__).resolve().parents[1]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--config", default=str(ROOT / "configs" / "scale.yaml"))
    ap.add_argument("--out", default=str(ROOT / "results" / "scale"))
    ap.add_argument("--subdivisions", type=int, help="override the sphere's subdivisions (8 = 1.3M faces)")
    a = ap.parse_args(argv)

    import methods
    cfg = yaml.safe_load(Path(a.config).read_text())
    for task, body in cfg["tasks"].items():
        keep = [m for m in body["methods"] if (m if isinstance(m, str) else m["name"]) in methods.available(task)]
        dropped = [m for m in body["methods"] if m not in keep]
        if dropped:
            print(f"not available here, dropped: {dropped}")
        body["methods"] = keep
    cfg["tasks"] = {t: b for t, b in cfg["tasks"].items() if b["methods"]}
    if a.subdivisions is not None:
        cfg["meshes"] = [{"procedural": "sphere", "subdivisions": a.subdivisions}]
    tmp = Path(tempfile.mkdtemp(prefix="scale-")) / "scale.yaml"
    tmp.write_text(yaml.safe_dump(cfg))

    out = Path(a.out)
    cmd = [str(Path(sys.executable).with_name("shootout")), "run", str(tmp), "--out", str(out),
           "--workers", "1", "--quiet"]
    print("$", " ".join(cmd), flush=True)
    t0 = time.perf_counter()
    proc = subprocess.Popen(cmd)
    driver = psutil.Process(proc.pid)
    from harness import tasks
    from harness.schema import task_file

    def task_csvs():                              # the per-task result files (not the leaderboard or winners)
        return [out / task_file(t) for t in tasks.names() if (out / task_file(t)).is_file()]

    arrivals: list[tuple[str, float]] = []        # (case_id, seconds since start) in CSV order
    seen: dict[str, int] = {}
    tree_peak = 0.0
    while True:
        done = proc.poll() is not None
        try:
            procs = [driver] + driver.children(recursive=True)
            rss = 0
            for p in procs:
                try:
                    rss += p.memory_info().rss
                except psutil.Error:
                    pass
            tree_peak = max(tree_peak, rss / 2**20)
        except psutil.Error:
            pass
        for csv in task_csvs():
            lines = csv.read_text().splitlines()[1:]
            for line in lines[seen.get(csv.name, 0):]:
                arrivals.append((line.split(",", 1)[0], time.perf_counter() - t0))
            seen[csv.name] = len(lines)
        if done:
            break
        time.sleep(0.5)
    total = time.perf_counter() - t0
    if proc.returncode != 0:
        print(f"shootout exited with {proc.returncode}")
        return proc.returncode

    from harness.results import load_csv
    prev = 0.0
    wall = {}
    for cid, t in sorted(arrivals, key=lambda x: x[1]):
        wall[cid] = t - prev
        prev = t
    print(f"\n{'task':13s} {'method':18s} {'mesh':26s} {'V':>8s} {'F':>9s} {'status':8s} "
          f"{'time_s':>8s} {'case_wall_s':>11s} {'peak_rss_mb':>11s}  metrics")
    for csv in task_csvs():
        df = load_csv(csv)
        for _, r in df.iterrows():
            if r["task"] == "laplacian":
                extra = (f"nnz={r['nnz']:.0f} sym_error={r['sym_error']:.2e} neg_weights={r['neg_weights']:.4f} "
                         f"min_eig={r['min_eig']!s} psd={r['psd']!s}")
            elif r["task"] == "smoothing":
                extra = (f"diverged={r['diverged']} ev_mean={r['ev_mean']:.3e} (input {r['input_ev_mean']:.3e}) "
                         f"normal_error_deg={r['normal_error_deg']:.2f} (input {r['input_normal_error_deg']:.2f})")
            else:
                extra = ""
            if r["status"] != "ok":
                extra = r["error"]
            print(f"{r['task']:13s} {r['method']:18s} {r['mesh']:26s} {r['n_vertices']:8.0f} {r['n_faces']:9.0f} "
                  f"{r['status']:8s} {r['time_s']:8.2f} {wall.get(r['case_id'], float('nan')):11.1f} "
                  f"{r['peak_rss_mb']:11.1f}  {extra}")
    print(f"\ntotal wall {total:.1f} s; peak RSS of the process tree (sampled every 0.5 s) "
          f"{tree_peak:.0f} MiB; machine memory {psutil.virtual_memory().total / 2**30:.1f} GiB; "
          f"load average {psutil.getloadavg()[0]:.1f} on {psutil.cpu_count()} cores")
    return 0


if __name__ == "__main__":
    sys.exit(main())
