"""`harness.run`'s arguments: refused as ``shootout run`` refuses the same flags, in one
ShootoutError naming each, with nothing written."""
from __future__ import annotations

from pathlib import Path

import pytest

import harness
from harness.errors import ShootoutError

TETRA = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n"
RUN = {"name": "r9", "meshes": ["knight"], "time_budget": 0, "tasks": {"laplacian": {"methods": ["scratch.uniform"]}}}


@pytest.fixture()
def results_cfg(tmp_path):
    (tmp_path / "tet.obj").write_text(TETRA)
    return {"name": "rc", "hausdorff_samples": 100,
            "results": [{"file": str(tmp_path / "tet.obj"), "clean": str(tmp_path / "tet.obj")}]}


@pytest.mark.parametrize("kwargs, names", [
    ({"export_benchmark_json": "bench.json", "resume": True, "workers": 3},
     "resume, workers, export_benchmark_json"),
    ({"executor": "dask", "scheduler": "tcp://127.0.0.1:1"}, "executor, scheduler"),
    ({"timeout": 5}, "timeout"),
])
def test_a_results_config_refuses_the_arguments_the_cli_refuses(results_cfg, tmp_path, kwargs, names):
    """They were silently ignored (no JSON written) where ``shootout run`` exits 2."""
    kwargs = {k: str(tmp_path / v) if k == "export_benchmark_json" else v for k, v in kwargs.items()}
    with pytest.raises(ShootoutError) as exc:
        harness.run(results_cfg, out=tmp_path / "o", **kwargs)
    msg = str(exc.value)
    assert f"{names}: a results: config scores files made elsewhere and runs no case; drop these" in msg, msg
    assert not (tmp_path / "o").exists() and not (tmp_path / "bench.json").exists()
    frames = harness.run(results_cfg, out=tmp_path / "o", quiet=True)     # out and quiet are taken
    assert list(frames["smoothing"]["status"]) == ["ok"]


def test_a_results_config_lists_its_refused_arguments_with_the_other_bad_ones(results_cfg, tmp_path):
    with pytest.raises(ShootoutError) as exc:
        harness.run(results_cfg, out=tmp_path / "o", resume=True, workers=0)
    msg = str(exc.value)
    assert msg.startswith("2 problems:") and "expected an integer >= 1, got 0" in msg and "resume, workers:" in msg


def test_a_results_configs_own_problems_join_the_argument_problems(results_cfg, tmp_path, capsys):
    """Only the argument's problem was said (a review): the config's were left for the next try."""
    import yaml

    from harness.cli import main
    bad = dict(results_cfg, extra=1, hausdorff_samples=1.5)
    with pytest.raises(ShootoutError) as exc:
        harness.run(bad, out=tmp_path / "o", workers=2)
    msg = str(exc.value)
    assert msg.startswith("3 problems:") and "workers: a results: config" in msg, msg
    assert "extra: unknown key" in msg and "hausdorff_samples: expected an integer" in msg, msg
    cfg = tmp_path / "bad.yaml"
    cfg.write_text(yaml.safe_dump(bad))
    assert main(["run", str(cfg), "--workers", "2", "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert "--workers: " in err and "extra: unknown key" in err and "hausdorff_samples: expected" in err, err
    assert not (tmp_path / "o").exists()


def test_an_empty_out_is_refused(tmp_path, monkeypatch):
    """``out=""`` wrote results/<name> in the current folder where ``--out ''`` exits 2."""
    monkeypatch.chdir(tmp_path)
    for out in ("", "  "):
        with pytest.raises(ShootoutError, match="out: an empty path"):
            harness.run(RUN, out=out)
    with pytest.raises(ShootoutError, match="out: expected a folder path, got int 5"):
        harness.run(RUN, out=5)
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("given, needle", [
    (None, "config_or_path: expected a Config, a dict, YAML text or the path of a config file (.yaml, .yml, "
           ".json), got None"),
    (5, "config_or_path: expected a Config, a dict, YAML text or the path of a config file (.yaml, .yml, "
        ".json), got int 5"),
    ("FOLDER", "is a folder; expected a Config"),
    (Path("FOLDER"), "is a folder; expected a Config"),
    ("no/such/config", "'no/such/config' names no file and is not YAML text of a mapping"),
])
def test_a_config_argument_of_the_wrong_kind_says_what_was_given(tmp_path, monkeypatch, given, needle):
    """``run(None)`` and ``run("<a folder>")`` said 'expected a mapping, got str' (the text "None",
    the folder's path read as YAML)."""
    monkeypatch.chdir(tmp_path)
    if given in ("FOLDER", Path("FOLDER")):
        (tmp_path / "FOLDER").mkdir()
        given = type(given)(tmp_path / "FOLDER")
    with pytest.raises(ShootoutError) as exc:
        harness.run(given)
    assert needle in str(exc.value), str(exc.value)
    assert sorted(p.name for p in tmp_path.iterdir()) == (["FOLDER"] if (tmp_path / "FOLDER").exists() else [])


def test_one_line_config_text_longer_than_a_file_name_runs(tmp_path):
    """A review: a JSON config given as one line of text (YAML text, per the README) longer than
    255 characters raised OSError (File name too long) from the argument check; an empty string
    was called a folder."""
    import json
    cfg = {**RUN, "name": "jsontext", "noise": [{"model": "gaussian_normal", "levels": [0.2]}],
           "tasks": {"smoothing": {"methods": [{"name": "scratch.taubin", "params": {"iterations": 3}}]},
                     "laplacian": {"methods": ["scratch.uniform"]}}}
    text = json.dumps(cfg)
    assert len(text) > 255 and "\n" not in text
    out = harness.run(text, out=tmp_path / "o", quiet=True, workers=1)
    assert len(out["smoothing"]) == 1 and len(out["laplacian"]) == 1
    with pytest.raises(ShootoutError, match="config_or_path: an empty string"):
        harness.run("", out=tmp_path / "e")
    from harness.config import load_config
    from harness.errors import ConfigError
    with pytest.raises(ConfigError, match="config file not found"):      # a path too long to look up (OSError before)
        load_config("/tmp/" + "x" * 300 + ".yaml")
    with pytest.raises(ConfigError, match="config file not found"):
        load_config(Path("/tmp/" + "x" * 300 + ".yaml"))


def test_a_method_called_through_the_api_never_writes_into_or_returns_the_callers_arrays(monkeypatch):
    """`methods.get(name)(V, F)` handed a float64 C-contiguous V to the method as it was: one that
    wrote into its input changed the caller's mesh, and one that returned it gave a result that
    was the caller's array."""
    import dataclasses

    import numpy as np

    import methods
    from harness.tasks.smoothing import SmoothingResult
    from methods import registry

    def scribble(V, F, **kw):
        V += 1.0
        F[:] = F[::-1]
        return SmoothingResult(V=V)
    real = methods.get("scratch.explicit")                  # (loads the built-in methods)
    monkeypatch.setitem(registry._REGISTRY, "scratch.explicit", dataclasses.replace(real, func=scribble))
    V = np.array([[0.0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]])
    F = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    V0, F0 = V.copy(), F.copy()
    r = methods.get("scratch.explicit")(V, F)
    assert np.array_equal(V, V0) and np.array_equal(F, F0) and not np.shares_memory(r.V, V)
    assert np.array_equal(r.V, V0 + 1.0)
    # so do objects numpy reads in place (a review: a memoryview slipped past a check for ndarray)
    r = methods.get("scratch.explicit")(memoryview(V), memoryview(F))
    assert np.array_equal(V, V0) and np.array_equal(F, F0) and not np.shares_memory(r.V, V)


def test_numpy_numbers_in_a_config_dict_are_the_numbers_yaml_gives(tmp_path):
    """A review: ``np.int64(5)`` as a parameter passed validation, then the run cleared the earlier
    run's folder and crashed writing its plan (int64 is no JSON); its case id also differed from 5's."""
    import numpy as np

    def cfg(it, lam):
        return {"name": "np", "meshes": ["knight"], "time_budget": 0, "tasks": {"smoothing": {"methods": [
            {"name": "scratch.taubin", "params": {"iterations": it, "lambda": lam}}]}}}
    plain = harness.run(cfg(2, 0.5), out=tmp_path / "o", quiet=True, workers=1)
    from harness.config import load_config
    assert [c.case_id for c in load_config(cfg(np.int64(2), np.float32(0.5))).cases] == \
        [c.case_id for c in load_config(cfg(2, 0.5)).cases]
    again = harness.run(cfg(np.int64(2), np.float32(0.5)), out=tmp_path / "o", quiet=True, workers=1, resume=True)
    assert list(again["smoothing"]["case_id"]) == list(plain["smoothing"]["case_id"])
    fresh = harness.run(cfg(np.int64(3), 0.5), out=tmp_path / "o", quiet=True, workers=1)
    assert list(fresh["smoothing"]["status"]) == ["ok"]


def test_a_parameter_name_that_is_not_a_string_is_a_problem_not_a_crash():
    """``params: {1: 2}`` crashed the config check (difflib on an int) with a traceback."""
    import methods
    from harness.config import load_config
    from harness.errors import ConfigError
    m = methods.get("scratch.taubin")
    assert m.param_problems({1: 2})[0].startswith("unknown parameter 1;")
    with pytest.raises(ConfigError) as exc:
        load_config({"name": "k", "meshes": ["knight"], "tasks": {"smoothing": {
            "methods": [{"name": "scratch.taubin", "params": {1: 2, None: 4}}]}}})
    assert "unknown parameter 1" in str(exc.value) and "unknown parameter None" in str(exc.value)


def test_an_empty_config_says_so():
    from harness.config import load_config
    from harness.errors import ConfigError
    with pytest.raises(ConfigError) as exc:
        load_config("\n# nothing\n")
    assert "the config is empty" in str(exc.value)


def test_the_api_lists_the_configs_problems_with_the_arguments(tmp_path):
    """A review: harness.run(bad config, workers=0) named the argument alone, and a bad out
    (the file system root) hid nothing but came after the config's; the CLI lists them together."""
    bad = {"name": "b", "meshes": ["nosuchmesh"], "tasks": {"smoothing": {"methods": ["scratch.taubin"]}}}
    with pytest.raises(ShootoutError) as exc:
        harness.run(bad, out=tmp_path / "o", workers=0)
    msg = str(exc.value)
    assert "workers: expected an integer" in msg and "--workers" not in msg and "meshes[0]: unknown mesh" in msg, msg
    (tmp_path / "afile").write_text("mine")
    with pytest.raises(ShootoutError) as exc:
        harness.run(bad, out=tmp_path / "afile")
    msg = str(exc.value)
    assert "afile" in msg and "meshes[0]: unknown mesh" in msg, msg
    assert not (tmp_path / "o").exists() and (tmp_path / "afile").read_text() == "mine"


def test_a_yaml_error_names_the_config_file(tmp_path):
    """A review: a YAML syntax error read 'in "<unicode string>", line 2' for a config file."""
    from harness.config import load_config
    from harness.errors import ConfigError
    p = tmp_path / "bad.yaml"
    p.write_text("name: x\nmeshes: [knight\n")
    with pytest.raises(ConfigError) as exc:
        load_config(p)
    assert f'in "{p}", line 2' in str(exc.value) and "<unicode string>" not in str(exc.value), str(exc.value)


def test_results_and_tasks_in_one_config_are_named_as_such():
    """A review: 'results: unknown key (did you mean repeats?)', though results: is documented."""
    from harness.config import load_config
    from harness.errors import ConfigError
    with pytest.raises(ConfigError) as exc:
        load_config({"name": "x", "meshes": ["knight"], "results": [],
                     "tasks": {"smoothing": {"methods": ["scratch.taubin"]}}})
    assert "results: a config either runs tasks (tasks:) or scores files" in str(exc.value)
    assert "unknown key" not in str(exc.value), str(exc.value)


def test_an_empty_export_path_says_so(tmp_path, capsys):
    """A review: --export-benchmark-json "" read ': is a folder; give a file name'."""
    from harness.cli import main
    cfg = tmp_path / "c.json"
    cfg.write_text('{"name": "e", "meshes": ["knight"], "tasks": {"laplacian": {"methods": ["scratch.uniform"]}}}')
    assert main(["run", str(cfg), "--out", str(tmp_path / "o"), "--export-benchmark-json", ""]) == 2
    assert "--export-benchmark-json: an empty path; give a file name" in capsys.readouterr().err
    assert not (tmp_path / "o").exists()


def test_a_misspelt_method_is_named_beside_a_plugin_that_failed_and_its_matches_are_of_its_task(tmp_path,
                                                                                                 monkeypatch):
    """A review: with one plugin failing, a typo in a method of a plugin that imported (or a
    built-in's) went unreported; and 'scratch.taubn' was offered scratch.cotan, a Laplacian."""
    from harness.config import load_config
    from harness.errors import ConfigError
    (tmp_path / "mylab_ok.py").write_text(
        "from methods import register\nfrom harness.tasks.smoothing import SmoothingResult\n"
        "@register('mylab_ok.wiggle', task='smoothing', library='mylab')\n"
        "def w(V, F):\n    \"\"\"Returns its input.\"\"\"\n    return SmoothingResult(V=V.copy())\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    with pytest.raises(ConfigError) as exc:
        load_config({"name": "p", "plugins": ["mylab_ok", "no_such_plugin_qq"], "meshes": ["knight"],
                     "tasks": {"smoothing": {"methods": ["mylab_ok.wigle", "scratch.taubn", "qq.thing"]}}})
    msg = str(exc.value)
    assert "unknown method 'mylab_ok.wigle'; did you mean mylab_ok.wiggle" in msg, msg
    assert "unknown method 'scratch.taubn'; did you mean scratch.taubin" in msg and "scratch.cotan" not in msg, msg
    assert "qq.thing" not in msg                      # likely the failed plugin's: its failure explains it


def test_seeds_on_the_noise_free_model_are_refused_as_its_levels_are():
    """A review: seeds: 3 on {model: none} was ignored without a word."""
    from harness.config import load_config
    from harness.errors import ConfigError
    with pytest.raises(ConfigError, match=r"noise\[0\]\.seeds: model none adds no noise"):
        load_config({"name": "s", "meshes": ["knight"], "noise": [{"model": "none", "seeds": 3}],
                     "tasks": {"smoothing": {"methods": ["scratch.taubin"]}}})
    assert load_config({"name": "s", "meshes": ["knight"], "noise": [{"model": "none", "seeds": 1}],
                        "tasks": {"smoothing": {"methods": ["scratch.taubin"]}}}).cases
