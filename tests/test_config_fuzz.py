"""Property-based tests (hypothesis): malformed configs always give exit 2, a message on
stderr, no traceback, and nothing written (issue 7).

Each generated config starts from a valid one and receives one to three mutations, each of
which alone makes the config invalid (unknown keys, wrong types, out-of-range values, unknown
meshes, models, tasks, methods and parameters); or it is random YAML text or a random
YAML structure. `shootout run` is called in-process through `harness.cli.main` (plus one
subprocess check of the real console script).
"""
import contextlib
import io
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import pytest
import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from harness.cli import main
from harness.config import NOISE_KEYS, TASK_KEYS, TOP_KEYS, load_config
from harness.errors import ConfigError

SHOOTOUT = Path(sys.executable).with_name("shootout")
BASE = {"name": "fuzz", "meshes": ["knight"], "tasks": {"laplacian": {"methods": ["scratch.uniform"]}}}
SETTINGS = settings(max_examples=50, deadline=None, suppress_health_check=[HealthCheck.too_slow])

# ----------------------------------------------------------------------------- value strategies

finite = st.floats(allow_nan=False, allow_infinity=False, width=32)
scalars = st.one_of(st.none(), st.booleans(), st.integers(-10**6, 10**6), finite, st.text(max_size=8))
json_values = st.recursive(scalars, lambda inner: st.one_of(st.lists(inner, max_size=3),
                                                            st.dictionaries(st.text(max_size=6), inner, max_size=3)),
                           max_leaves=6)
not_int = st.one_of(st.none(), st.booleans(), finite.filter(lambda x: x != int(x)), st.text(max_size=6),
                    st.lists(scalars, max_size=2), st.dictionaries(st.text(max_size=4), scalars, max_size=2))
not_num = st.one_of(st.none(), st.booleans(), st.text(max_size=6), st.lists(scalars, max_size=2))
not_list = st.one_of(scalars, st.dictionaries(st.text(max_size=4), scalars, max_size=2))
not_dict = st.one_of(scalars, st.lists(scalars, max_size=2))
fresh = st.text(st.characters(whitelist_categories=("Ll", "Nd")), min_size=1, max_size=8)


def without(keys):
    return st.text(min_size=1, max_size=12).filter(lambda k: k not in keys)


# ----------------------------------------------------------------------------- mutations
# each returns (path, value): set config[path] = value; every one alone is a config error

top_key = st.tuples(without(TOP_KEYS).map(lambda k: (k,)), json_values)
bad_top_value = st.one_of(
    st.tuples(st.just(("repeats",)), st.one_of(not_int, st.integers(-5, 0))),
    st.tuples(st.just(("seed",)), st.one_of(not_int, st.integers(-10**6, -1))),
    st.tuples(st.just(("hausdorff_samples",)), st.one_of(not_int, st.integers(-10**6, -1))),
    st.tuples(st.just(("save_meshes",)), st.one_of(st.none(), st.integers(), st.text(max_size=5), finite)),
    st.tuples(st.just(("timeout",)), st.one_of(not_num.filter(lambda v: v is not None),   # null = no limit
                                               finite.filter(lambda x: x <= 0), st.integers(-100, 0))),
    st.tuples(st.just(("name",)), st.one_of(st.none(), st.integers(), st.just(""), st.lists(scalars, max_size=2),
                                            st.text(max_size=6).map(lambda s: s + "/x"))),
    st.tuples(st.just(("plugins",)), st.one_of(st.integers(), st.booleans(), st.text(max_size=5),
                                               st.lists(st.integers(), min_size=1, max_size=2),
                                               fresh.map(lambda s: ["no_such_plugin_" + s]))),
    st.tuples(st.just(("report",)), st.one_of(st.integers(), st.text(min_size=1, max_size=5),
                                              st.lists(scalars, min_size=1, max_size=2))),
)
bad_mesh_entry = st.one_of(
    fresh.map(lambda s: "nomesh_" + s),
    st.integers(), finite, st.none(), st.lists(scalars, max_size=2),
    st.fixed_dictionaries({"procedural": fresh.map(lambda s: "noshape_" + s)}),
    st.fixed_dictionaries({"procedural": st.just("sphere"), "subdivisions": st.one_of(st.integers(10, 99), st.integers(-9, -1),
                                                                                     st.text(max_size=3), finite)}),
    st.fixed_dictionaries({"procedural": st.just("torus"), "resolution": st.one_of(st.integers(-9, 2), st.integers(5000, 10**6))}),
    st.fixed_dictionaries({"procedural": st.just("sphere"), "unknown_arg": scalars}),
    st.fixed_dictionaries({"file": fresh.map(lambda s: f"missing_{s}.obj")}),
    st.fixed_dictionaries({"file": st.one_of(st.integers(), st.none(), st.lists(scalars, max_size=2))}),
    st.fixed_dictionaries({"file": st.just("x.obj"), "colour": scalars}),
    st.dictionaries(without({"procedural", "file"}), scalars, min_size=1, max_size=2),
)
bad_meshes = st.tuples(st.just(("meshes",)), st.one_of(
    not_list, st.just([]),
    st.lists(bad_mesh_entry, min_size=1, max_size=2).map(lambda xs: ["knight"] + xs)))
bad_noise_entry = st.one_of(
    not_dict,
    st.fixed_dictionaries({"model": fresh.map(lambda s: "nomodel_" + s), "levels": st.just([0.1])}),
    st.fixed_dictionaries({"model": st.just("gaussian_normal"),
                           "levels": st.one_of(not_list, st.just([]), st.lists(st.one_of(finite.filter(lambda x: x < 0 or x > 100),
                                                                                         st.text(max_size=3)), min_size=1, max_size=2))}),
    st.fixed_dictionaries({"model": st.just("gaussian_normal"), "levels": st.just([0.1]),
                           "seeds": st.one_of(st.integers(-5, 0), st.integers(1001, 10**6), st.text(max_size=3))}),
    st.fixed_dictionaries({"model": st.just("gaussian_random"), "levels": st.just([0.1]), "fraction": finite}),
    st.fixed_dictionaries({"model": st.just("impulsive"), "levels": st.just([0.1]),
                           "fraction": st.one_of(finite.filter(lambda x: x <= 0 or x > 1), st.text(max_size=3))}),
    st.fixed_dictionaries({"model": st.just("none"), "levels": st.lists(finite.filter(lambda x: x != 0), min_size=1, max_size=2)}),
    st.dictionaries(without(NOISE_KEYS), scalars, min_size=1, max_size=2).map(lambda d: {"model": "none", **d}),
)
bad_noise = st.tuples(st.just(("noise",)), st.one_of(not_list, st.just([]), st.lists(bad_noise_entry, min_size=1, max_size=2)))
bad_method = st.one_of(
    fresh.map(lambda s: "nosuch." + s), fresh,
    st.just("fast_simplification.qem"),                  # a simplification method under laplacian
    st.integers(), st.none(), st.lists(scalars, max_size=2),
    st.fixed_dictionaries({"name": st.just("scratch.uniform"), "params": st.dictionaries(fresh.map(lambda s: "np_" + s), scalars, min_size=1, max_size=2)}),
    st.fixed_dictionaries({"name": st.just("scratch.cotan"), "params": st.fixed_dictionaries({"mass": st.one_of(fresh.map(lambda s: "m_" + s), st.integers(), st.none())})}),
    st.fixed_dictionaries({"name": st.just("scratch.uniform"), "extra": scalars}),
    st.fixed_dictionaries({"name": st.one_of(st.integers(), st.none())}),
    st.fixed_dictionaries({"name": st.just("scratch.uniform"), "params": st.one_of(st.integers(), st.booleans(), st.text(max_size=3),
                                                                                    st.lists(scalars, min_size=1, max_size=2))}),
)
bad_tasks = st.one_of(
    st.tuples(st.just(("tasks",)), st.one_of(not_dict, st.just({}))),
    st.tuples(without(("laplacian", "smoothing", "simplification")).map(lambda t: ("tasks", t)),
              st.just({"methods": ["scratch.uniform"]})),
    st.tuples(st.just(("tasks", "laplacian")), st.one_of(not_dict, st.just({}), st.just({"methods": []}),
                                                         st.fixed_dictionaries({"methods": not_list}),
                                                         st.dictionaries(without(TASK_KEYS), scalars, min_size=1, max_size=2)
                                                         .map(lambda d: {"methods": ["scratch.uniform"], **d}))),
    st.tuples(st.just(("tasks", "laplacian", "methods")), st.lists(bad_method, min_size=1, max_size=2)),
    st.tuples(st.just(("tasks", "smoothing")),
              st.fixed_dictionaries({"methods": st.just([{"name": "scratch.explicit"}]),
                                     "params": st.fixed_dictionaries({"iterations": st.one_of(st.integers(-10, -1), st.text(min_size=1, max_size=3),
                                                                                              st.just([]))})})),
)
mutation = st.one_of(top_key, bad_top_value, bad_meshes, bad_noise, bad_tasks)


def apply(mutations) -> dict:
    cfg = yaml.safe_load(yaml.safe_dump(BASE))
    for path, value in mutations:
        node = cfg
        for k in path[:-1]:
            if not isinstance(node.get(k), dict):
                node[k] = {}
            node = node[k]
        node[path[-1]] = value
    return cfg


def run_cli(text_or_bytes) -> tuple[int, str, str, bool]:
    """(exit code, stdout, stderr, anything written) of `shootout run` on that config file."""
    with tempfile.TemporaryDirectory() as d:
        d = Path(d)
        p = d / "cfg.yaml"
        if isinstance(text_or_bytes, bytes):
            p.write_bytes(text_or_bytes)
        else:
            p.write_text(text_or_bytes, encoding="utf-8")
        out, err = io.StringIO(), io.StringIO()
        cwd = os.getcwd()
        os.chdir(d)                       # results/<name> would land here if --out were ignored
        try:
            with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
                try:
                    code = main(["run", str(p), "--out", str(d / "out"), "--quiet"])
                except SystemExit as exc:           # argparse-style exits
                    code = exc.code
        finally:
            os.chdir(cwd)
        written = sorted(x.name for x in d.iterdir() if x.name != "cfg.yaml")
        return code, out.getvalue(), err.getvalue(), bool(written)


def assert_rejected(code, out, err, written):
    assert code == 2, (code, out, err)
    assert err.startswith("shootout: ") and len(err.strip()) > len("shootout: ")
    assert "Traceback" not in err + out
    assert not written


@SETTINGS
@given(st.lists(mutation, min_size=1, max_size=3))
def test_mutated_configs_are_rejected(mutations):
    cfg = apply(mutations)
    assert_rejected(*run_cli(yaml.safe_dump(cfg)))


@SETTINGS
@given(st.text(max_size=200))
def test_random_yaml_text_is_rejected(text):
    assert_rejected(*run_cli(text))


@SETTINGS
@given(st.dictionaries(st.text(max_size=10), json_values, max_size=5)
       .filter(lambda d: "meshes" not in d or "tasks" not in d or set(d) - TOP_KEYS))
def test_random_yaml_structures_are_rejected(cfg):
    assert_rejected(*run_cli(yaml.safe_dump(cfg)))


def test_all_problems_reported_at_once():
    cfg = apply([(("repeats",), 0), (("meshes",), ["knight", "nomesh_zz"]),
                 (("tasks", "laplacian", "methods"), ["nosuch.method"])])
    code, out, err, written = run_cli(yaml.safe_dump(cfg))
    assert_rejected(code, out, err, written)
    assert "3 problem(s)" in err
    for key in ("repeats", "meshes[1]", "tasks.laplacian.methods[0]"):
        assert key in err, key


def test_the_console_script_rejects_a_bad_config(tmp_path):
    p = tmp_path / "bad.yaml"
    p.write_text("name: fuzz\nrepeats: many\nmeshes: [knight]\ntasks: {laplacian: {methods: [scratch.uniform]}}\n")
    r = subprocess.run([str(SHOOTOUT), "run", str(p), "--out", str(tmp_path / "out")],
                       capture_output=True, text=True, timeout=120, cwd=tmp_path)
    assert r.returncode == 2 and "repeats" in r.stderr and str(p) in r.stderr
    assert "Traceback" not in r.stderr + r.stdout
    assert sorted(x.name for x in tmp_path.iterdir()) == ["bad.yaml"]


# Found while writing these tests and fixed in harness/config.py by the lead: non-UTF-8
# file, non-finite timeouts, falsy plugins/params of the wrong type taken as the default.
def test_non_utf8_config_is_rejected():
    assert_rejected(*run_cli(b"\xff\xfe\x00name: x\n"))


FALSY_SLOTS = {"plugins": (("plugins",),),
               "method params": (("tasks", "laplacian", "methods"), "params"),
               "task params": (("tasks", "laplacian", "params"),)}


@pytest.mark.parametrize("slot", sorted(FALSY_SLOTS))
@pytest.mark.parametrize("value", [0, False, ""])
def test_falsy_values_of_the_wrong_type_are_rejected(slot, value):
    path = FALSY_SLOTS[slot]
    if slot == "method params":
        mut = [(path[0], [{"name": "scratch.uniform", "params": value}])]
    else:
        mut = [(path[0], value)]
    assert_rejected(*run_cli(yaml.safe_dump(apply(mut))))


@pytest.mark.parametrize("value", [float("nan"), float("inf"), float("-inf")])
def test_non_finite_timeout_in_config_is_rejected(value):
    assert_rejected(*run_cli(yaml.safe_dump({**BASE, "timeout": value})))


def test_duplicate_keys_compare_as_loaded():
    """A key given twice (as the loaded dict would see it) is an error listing each repeat with
    its line; keys that load differently (1 and "1") are two keys."""
    import yaml
    from harness import yaml_input
    with pytest.raises(yaml.YAMLError, match=r"duplicate key '0x1' at line 2 \(first at line 1\)"):
        yaml_input.load("1: x\n0x1: y\n")
    with pytest.raises(yaml.YAMLError, match=r"duplicate key '~' at line 2.*duplicate key 'b' at line 3"):
        yaml_input.load("null: 1\n~: 2\nc: {b: 1, b: 2}\n")
    assert yaml_input.load("1: x\n'1': y\n") == {1: "x", "1": "y"}
    assert yaml_input.load("=: 1\n") == {"=": 1}                  # as safe_load: the key check builds nothing
    with pytest.raises(yaml.YAMLError, match="could not determine a constructor for the tag '!foo'"):
        yaml_input.load("!foo extra: 1\n")
    found = []                                # merge keys and `=` are YAML's own, not refused tags
    assert yaml_input.load("b: &b {a: 1}\nx: {<<: *b, c: 2}\n=: 3\n", found) == {"b": {"a": 1}, "x": {"a": 1, "c": 2},
                                                                                 "=": 3}
    assert found == [], found
    found = []                                # an unknown tag too, its node read as plain data
    assert yaml_input.load("a: !!python/object:os.system x\nb: !foo [1]\n", found) == {"a": "x", "b": [1]}
    assert found == ["the tag '!!python/object:os.system' at line 1 is refused: configs take plain values only",
                     "the tag '!foo' at line 2 is refused: configs take plain values only"]
    found: list = []                          # a config lists them with its other problems
    assert yaml_input.load("a: 1\nb: 010\na: 2\n", found) == {"a": 2, "b": 8}
    assert found == ["duplicate key 'a' at line 3 (first at line 1): each key may appear once in a mapping",
                     "'010' at line 2 is octal in YAML 1.1 (it reads as 8); write the number you mean, or "
                     "quote it for text"]
    with pytest.raises(yaml.YAMLError, match="cannot be read as its tag says"):     # was a ValueError traceback
        yaml_input.load("time_budget: !!int abc\n")
    assert yaml_input.load("x: &a {k: 1}\ny: *a\n<<: {z: 1}\n") == {"x": {"k": 1}, "y": {"k": 1}, "z": 1}


def test_numbers_yaml_11_reads_otherwise_and_deep_nesting_are_refused(tmp_path):
    """Before: `iterations: [005, 010, 020]` ran 5, 8 and 16 iterations and `timeout: 1:30` was
    90 s, silently; `step: 1e-3` was refused as text; a config nested 400 levels deep (895 bytes) was a RecursionError traceback."""
    import yaml
    from harness import yaml_input
    with pytest.raises(yaml.YAMLError, match=r"'010' at line 1 is octal in YAML 1.1 \(it reads as 8\)"):
        yaml_input.load("iterations: [005, 010]\n")
    with pytest.raises(yaml.YAMLError, match=r"'1:30' at line 2 is base 60 in YAML 1.1 \(it reads as 90\)"):
        yaml_input.load("a: 1\ntimeout: 1:30\n")
    with pytest.raises(ConfigError) as exc:        # a review: listed alone, the config's other problems after a fix
        load_config("name: y\nrepeats: 010\ntimeout: 1:30\nmeshes: [bunyy]\n")
    assert len(exc.value.problems) >= 3 and "'010' at line 2 is octal" in exc.value.problems[0], exc.value.problems
    assert "'1:30' at line 3 is base 60" in exc.value.problems[1] and "bunyy" in str(exc.value)
    assert yaml_input.load("a: [0, 0.5, '010', 0x10, 1_000, 08, 1.5e3, 1e-3, -2E+2, '1e3', 1e3x]\n") == {
        "a": [0, 0.5, "010", 16, 1000, "08", 1500.0, 0.001, -200.0, "1e3", "1e3x"]}      # 1e-3 was text
    assert yaml_input.load("views: [123e45678901, 1e5]\n") == {"views": ["123e45678901", 100000.0]}   # a case id
    deep = tmp_path / "deep.yaml"
    deep.write_text("name: x\nmeshes: [knight]\ntasks: " + "[" * 400 + "]" * 400 + "\n")
    r = subprocess.run([str(SHOOTOUT), "run", str(deep), "--out", str(tmp_path / "o")],
                       capture_output=True, text=True, timeout=120)
    assert r.returncode == 2 and "nested too deeply" in r.stderr and "Traceback" not in r.stderr
    assert not (tmp_path / "o").exists()


def test_a_tasks_own_noise_list_replaces_the_top_level_one():
    """``tasks.<task>.noise`` gives that task its own noise list; other tasks keep the top-level
    one, the shared inputs keep their case ids, and its problems carry their key path."""
    from harness.config import load_config
    from harness.errors import ConfigError
    base = {"meshes": ["knight", "woody"], "noise": [{"model": "gaussian_normal", "levels": [0.3]}, {"model": "none"}],
            "tasks": {"laplacian": {"methods": ["scratch.cotan"]}, "smoothing": {"methods": ["scratch.taubin"]}}}
    every = load_config(base).cases
    own = load_config({**base, "tasks": {**base["tasks"], "smoothing": {
        "methods": ["scratch.taubin"], "noise": [{"model": "gaussian_normal", "levels": [0.3, 0.5], "seeds": 2}]}}}).cases
    got = {(c.task, c.mesh_key, c.noise_model, c.noise_level, c.seed) for c in own}
    assert {k for k in got if k[0] == "laplacian"} == {(c.task, c.mesh_key, c.noise_model, c.noise_level, c.seed)
                                                       for c in every if c.task == "laplacian"}
    assert {k[2:] for k in got if k[0] == "smoothing"} == {("gaussian_normal", lv, s) for lv in (0.3, 0.5) for s in (0, 1)}
    assert len(own) == 2 * 2 + 2 * 4
    shared = {c.case_id for c in every if c.task == "laplacian" or c.noise_model != "none"}
    assert shared <= {c.case_id for c in own}                   # same input, same case id
    with pytest.raises(ConfigError) as e:
        load_config({**base, "tasks": {"smoothing": {"methods": ["scratch.taubin"], "noise": [{"model": "gausian"}]},
                                       "laplacian": {"methods": ["scratch.cotan"], "noise": []}}})
    msg = str(e.value)
    assert "tasks.smoothing.noise[0].model" in msg and "tasks.laplacian.noise: expected a non-empty list" in msg


def test_bad_flags_config_and_out_folder_are_one_message(tmp_path, capsys):
    """`shootout run` lists every problem at once (flags, the config's problems with their key
    paths, a folder holding someone's files) and writes nothing; `shootout eval` names every
    missing file, not the first."""
    from harness.cli import main as cli
    out = tmp_path / "out"
    out.mkdir()
    (out / "smoothing.csv").write_text("mine\n")
    bad = tmp_path / "bad.yaml"
    bad.write_text("meshes: [knigt]\ntasks:\n  smoothing: {methods: [scratch.taubn]}\n")
    assert cli(["run", str(bad), "--out", str(out), "--timeout", "-3", "--workers", "0"]) == 2
    err = capsys.readouterr().err
    for what in ("--workers", "--timeout", "meshes[0]", "tasks.smoothing.methods[0]", "holds smoothing.csv"):
        assert what in err, (what, err)
    assert "5 problems" in err
    assert sorted(p.name for p in out.iterdir()) == ["smoothing.csv"] and (out / "smoothing.csv").read_text() == "mine\n"
    # a flag that is not a number at all joins the same message (argparse used to stop at it alone)
    assert cli(["run", str(bad), "--out", str(out), "--timeout", "1:30", "--workers", "two"]) == 2
    err = capsys.readouterr().err
    assert "5 problems" in err and "got 'two'" in err and "got '1:30'" in err and "meshes[0]" in err, err
    assert cli(["eval", "--clean", str(tmp_path / "nothere.obj"), str(tmp_path / "a.obj"), "--hausdorff-samples",
                "many", "--out", str(tmp_path / "e")]) == 2
    err = capsys.readouterr().err
    assert "3 problems" in err and "--hausdorff-samples" in err and "got 'many'" in err, err
    (tmp_path / "looks.obj").mkdir()                # a folder named like a mesh
    folder = tmp_path / "folder.yaml"
    folder.write_text(f"meshes: [{{file: {tmp_path / 'looks.obj'}}}]\ntasks:\n  smoothing: {{methods: [scratch.taubin]}}\n")
    assert cli(["run", str(folder), "--out", str(tmp_path / "f")]) == 2
    assert "meshes[0].file: " in (err := capsys.readouterr().err) and "is a folder; give a mesh file" in err, err
    assert cli(["eval", "--clean", str(tmp_path / "nothere.obj"), str(tmp_path / "a.obj"), str(tmp_path / "b.obj"),
                "--out", str(tmp_path / "e")]) == 2
    err = capsys.readouterr().err
    assert all(f"{n}: no such file" in err for n in ("nothere.obj", "a.obj", "b.obj")), err
    assert not (tmp_path / "e").exists()
