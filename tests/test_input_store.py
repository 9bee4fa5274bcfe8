"""Per-input facts shared across the cases of one input (`harness.input_store`): computed once,
equal to a fresh computation, private to the session and gone after it."""
import os
from pathlib import Path

import numpy as np

import harness
from harness import input_store
from harness.config import load_config
from harness.runner import prepare_input


CFG = {"name": "store", "repeats": 1, "time_budget": 0, "meshes": ["bunny"],
       "noise": [{"model": "gaussian_normal", "levels": [0.3, 0.5]}],
       "tasks": {"smoothing": {"methods": ["scratch.explicit", "scratch.taubin"]}}}


def test_facts_are_computed_once_per_input_and_equal_a_fresh_computation(tmp_path, monkeypatch):
    from harness.tasks import smoothing
    calls = []
    real = smoothing.bounds_volume                    # only the "closed" fact calls it
    monkeypatch.setattr(smoothing, "bounds_volume", lambda F, n: calls.append(len(F)) or real(F, n))
    frames = harness.run(CFG, out=tmp_path / "r", executor="serial", quiet=True)
    rows = frames["smoothing"]
    assert (rows["status"] == "ok").all() and len(rows) == 4
    assert len(calls) == 2          # two inputs (noise levels) of two cases each: once per input, not 4
    for case in load_config(CFG).cases:             # the shared input metrics equal a fresh computation
        inp, _ = prepare_input(case)
        fresh = smoothing._input_metrics(inp)
        row = rows[rows["case_id"] == case.case_id].iloc[0]
        for k, v in fresh.items():
            assert row[k] == v, (case.case_id, k)
    # two levels are two inputs: their input metrics differ
    assert rows.groupby("noise_level")["input_ev_mean"].nunique().eq(1).all()
    assert rows["input_ev_mean"].nunique() == 2


def test_the_store_is_private_to_a_session_and_removed_after_it(tmp_path, monkeypatch):
    import dataclasses
    case = load_config(CFG).cases[0]
    monkeypatch.setenv("SHOOTOUT_INPUT_STORE", str(tmp_path))     # the environment is never trusted
    assert input_store.load(case, ("x",)) == {}          # outside a session: nothing kept
    input_store.save(case, {"x": 1}, ("x",))
    assert not any(tmp_path.iterdir())
    with input_store.session():
        d = Path(input_store._DIR)
        assert d.is_dir() and (d / input_store.LOCK_NAME).is_file()   # made and locked at the start
        input_store.save(case, {"x": np.arange(3), ("y", 2): "t", "z": "not declared"}, ("x", "y"))
        assert (d.stat().st_mode & 0o777) == 0o700 and d.parent != tmp_path
        got = input_store.load(case, ("x", "y", "z"))
        assert set(got) == {"x", ("y", 2)} and np.array_equal(got["x"], np.arange(3))
        other = next(c for c in load_config(CFG).cases if c.noise_level != case.noise_level)
        assert input_store.load(other, ("x",)) == {}     # another noise level: another input
        # the same spec under another label gets other noise (seeded by the label), another task
        # another namespace: neither sees these facts
        assert input_store.load(dataclasses.replace(case, mesh_key="other"), ("x",)) == {}
        assert input_store.load(dataclasses.replace(case, task="simplification"), ("x",)) == {}
        for f in d.glob("*.pkl"):                        # a torn file is a miss, not an error
            f.write_bytes(b"\x80garbage")
        assert input_store.load(case, ("x",)) == {}
        with input_store.session():                      # nested: the same store
            assert input_store._DIR == str(d)
    assert input_store._DIR is None and not d.exists()


def test_the_store_keeps_within_its_size_cap(monkeypatch):
    """Past `MAX_BYTES` a fact is recomputed instead of kept; a stored surface comes back with
    its hierarchy (and without libigl's tree, rebuilt on demand) and answers the same queries."""
    from harness import datasets
    from harness.metrics.surface_distance import Surface
    case = load_config(CFG).cases[0]
    m = datasets.load("bunny").clean
    S = Surface(m.V, m.F)
    S.bvh()
    S.query(m.V[:5])                                     # libigl's tree built: not pickled
    import dataclasses
    other = dataclasses.replace(case, seed=case.seed + 100)
    with input_store.session():
        monkeypatch.setattr(input_store, "MAX_BYTES", 1000)
        input_store.save(case, {"clean_surface": S, "closed": True}, ("clean_surface", "closed"))
        # the large fact is refused (and marked, so no later case serialises it again); the
        # small one is kept
        assert input_store.load(case, ("clean_surface", "closed")) == {"closed": True}
        monkeypatch.setattr(input_store, "MAX_BYTES", 2 * 1024**3)
        input_store.save(case, {"clean_surface": S}, ("clean_surface",))
        assert input_store.load(case, ("clean_surface",)) == {}
        input_store.save(other, {"clean_surface": S}, ("clean_surface",))
        back = input_store.load(other, ("clean_surface",))["clean_surface"]
    assert back.tree is None and back._bvh is not None
    P = m.V + 0.01
    assert np.array_equal(back.corresponding_distances(P), S.corresponding_distances(P))
    assert np.allclose(back.query(P)[0], S.query(P)[0], rtol=0, atol=1e-15)


def test_fact_files_hold_arrays_out_of_band_aligned_and_a_torn_file_is_a_miss():
    """Arrays are written from their own memory and come back equal, writeable and aligned (a
    compiled kernel takes them as fresh arrays); non-contiguous arrays and plain objects ride in
    the pickle; a truncated or extended file is a miss."""
    case = load_config(CFG).cases[0]
    a = np.arange(12.0).reshape(3, 4)
    fact = {"c": a, "f": np.asfortranarray(a), "strided": a[:, ::2], "i": np.arange(5, dtype=np.int64),
            "empty": np.zeros((0, 3)), "text": "x" * 7}
    with input_store.session():
        input_store.save(case, {"x": fact}, ("x",))
        got = input_store.load(case, ("x",))["x"]
        for k, v in fact.items():
            if isinstance(v, np.ndarray):
                g = got[k]
                assert g.dtype == v.dtype and np.array_equal(g, v) and g.flags.writeable and g.flags.aligned, k
                assert g.ctypes.data % 8 == 0
            else:
                assert got[k] == v
        assert got["f"].flags.f_contiguous and got["c"].flags.c_contiguous
        (path,) = [f for f in Path(input_store._DIR).iterdir() if f.suffix == ".pkl"]
        whole = path.read_bytes()
        import struct
        huge = len(whole) // 8 - 3                   # a corrupt count that still fits the file
        for bad in (whole[:-3], whole + b"\0", whole[:16] + struct.pack("<Q", huge) + whole[24:]):
            path.write_bytes(bad)
            assert input_store.load(case, ("x",)) == {}


_HOLDER = """
import sys, time
sys.path.insert(0, sys.argv[1])
from harness import input_store
with input_store.session():
    print(input_store.private_dir(), flush=True)
    time.sleep(60)
"""


def test_a_killed_sessions_private_directory_is_swept_and_a_live_one_is_not(tmp_path, monkeypatch):
    """A driver killed with SIGKILL cannot remove its private directory (input store, stderr
    files); the next session removes it, because nobody holds its lock any more. A running
    session's directory, held by its lock, is never touched."""
    import signal
    import subprocess
    import sys
    import tempfile
    root = str(Path(__file__).resolve().parents[1])
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path))      # this test's own temporary directory
    env = {**os.environ, "TMPDIR": str(tmp_path)}
    procs = [subprocess.Popen([sys.executable, "-c", _HOLDER, root], stdout=subprocess.PIPE, text=True, env=env)
             for _ in range(2)]
    try:
        killed, live = (Path(p.stdout.readline().strip()) for p in procs)
        assert killed.parent == live.parent == tmp_path and killed != live
        (killed / "facts.pkl").write_bytes(b"x" * 1000)
        procs[0].send_signal(signal.SIGKILL)
        procs[0].wait()
        assert killed.is_dir()                            # left behind by the killed driver
        foreign = tmp_path / (input_store.PREFIX + "made-elsewhere")   # another machine's: its lock
        foreign.mkdir()                                                # is not ours to test
        (foreign / input_store.LOCK_NAME).write_bytes(b"otherhost\n0000\n")
        with input_store.session():                       # a new session sweeps first
            mine = Path(input_store.private_dir())
            assert not killed.exists() and live.is_dir() and foreign.is_dir()
            assert input_store.sweep() == 0 and mine.is_dir()   # its own lock holds too
        assert not mine.exists()
    finally:
        for p in procs:
            p.kill()
            p.wait()
        input_store.sweep(str(tmp_path))                  # this test leaves nothing behind


def test_case_stderr_files_live_in_the_private_directory():
    """A case process's stderr file is made in the session's private directory, so a killed
    driver's are swept with it."""
    from harness.executors.isolation import _Job
    case = load_config(CFG).cases[0]
    with input_store.session():
        job = _Job(case, False)
        assert Path(job.stderr_path).parent == Path(input_store.private_dir())
        row, _ = job.collect()
        assert row["status"] == "ok" and not Path(job.stderr_path).exists()
