"""Every shipped benchmark runs to the end on a small input and finds its outputs equal to the
reference's (each benchmark cross-checks before it times). The ratios themselves are not tested
here: timing belongs to the benchmarks, not to the suite."""
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

SMALL = {
    "bench_adapters.py": ["--quick", "--pairs", "1", "--mesh", "bunny"],
    "bench_fixed_floor.py": ["--repeats", "1"],
    "bench_geodesics.py": ["--subdivisions", "3", "--pairs", "1", "--sources", "1"],
    "bench_hausdorff.py": ["--meshes", "bunny", "--pairs", "1"],
    "bench_implicit.py": ["--subdivisions", "3"],
    "bench_implicit_vs_user.py": ["--subdivisions", "3", "--pairs", "1"],
    "bench_laplacian.py": ["--subdivisions", "4", "--repeats", "1"],
    "bench_measure.py": ["--mesh", "bunny", "--repeats", "1"],
    "bench_qem.py": ["--sizes", "200k", "--repeats", "1"],
    "bench_spectrum.py": ["--k", "10", "--pairs", "1"],
    "bench_uniform.py": ["--pairs", "1", "--subdivisions", "4"],
    "scale_run.py": ["--subdivisions", "3"],
}

TINY = """name: floor_smoke
meshes: [bunny]
noise:
  - {model: gaussian_normal, levels: [0.3]}
tasks:
  laplacian: {methods: [scratch.cotan]}
  smoothing: {methods: [scratch.taubin]}
  simplification: {methods: [fast_simplification.qem], params: {target_ratio: [0.1]}}
"""


def test_every_benchmark_is_listed():
    """Every benchmark the repository ships (tracked by git; every ``.py`` file outside a git
    checkout, a helper module named ``_*.py`` aside) has a small run here."""
    try:
        listed = subprocess.run(["git", "ls-files", "benchmarks/*.py"], cwd=ROOT, capture_output=True,
                                text=True, check=True).stdout.split()
        shipped = sorted(Path(p).name for p in listed)
    except (OSError, subprocess.CalledProcessError):
        shipped = []
    shipped = shipped or sorted(p.name for p in (ROOT / "benchmarks").glob("*.py"))
    assert sorted(SMALL) == [name for name in shipped if not name.startswith("_")]


def _command(script: str, tmp: Path) -> list[str]:
    args = SMALL[script] + (["--out", str(tmp / "scale")] if script == "scale_run.py" else [])
    if script == "bench_fixed_floor.py":
        (tmp / "tiny.yaml").write_text(TINY)
        args += ["--config", str(tmp / "tiny.yaml")]
    return [sys.executable, str(ROOT / "benchmarks" / script), *args]


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    """Every benchmark's small run, two at a time (the suite itself runs one test at a time on
    two cores): ``{script: (exit status or None, output)}``. A run past 300 s is killed with its
    whole process group (a benchmark's own ``shootout run`` included)."""
    import os
    import signal
    import traceback
    from concurrent.futures import ThreadPoolExecutor
    tmp_path_factory.getbasetemp()                 # made once, before the threads ask for it

    def one(script):
        try:
            tmp = tmp_path_factory.mktemp(script.replace(".py", ""))
            proc = subprocess.Popen(_command(script, tmp), cwd=tmp, stdout=subprocess.PIPE,
                                    stderr=subprocess.STDOUT, text=True, start_new_session=True)
            try:
                out, _ = proc.communicate(timeout=300)
            except subprocess.TimeoutExpired:
                os.killpg(proc.pid, signal.SIGKILL)
                out, _ = proc.communicate()
                return None, f"timed out after 300 s\n{out}"
            return proc.returncode, out
        except Exception:  # noqa: BLE001 - this script's test reports it; the others still run
            return None, traceback.format_exc()
    with ThreadPoolExecutor(2) as pool:
        return dict(zip(sorted(SMALL), pool.map(one, sorted(SMALL))))


@pytest.mark.parametrize("script", sorted(SMALL))
def test_benchmark_runs_on_a_small_input(script, runs):
    code, out = runs[script]
    assert code == 0, out[-3000:]
    assert "MISMATCH" not in out, out[-3000:]
    if script == "bench_adapters.py":
        assert "outputs not matching: none" in out, out[-3000:]
    if script == "bench_fixed_floor.py":
        assert "share of the method time: outside measuring + required" in out, out[-3000:]
