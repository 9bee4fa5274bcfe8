"""The shape of the code: no import cycle in harness/ or methods/ (module- and function-level
imports), the run-folder readers (report, compare, benchmark export) import none of config,
runner, executors or methods, and the judge (harness) imports nothing from a contestant."""
from __future__ import annotations

import ast
import json
import shutil
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("harness", "methods")


def _modules() -> dict[str, Path]:
    out = {}
    for pkg in PACKAGES:
        for p in (ROOT / pkg).rglob("*.py"):
            parts = list(p.relative_to(ROOT).with_suffix("").parts)
            if parts[-1] == "__init__":
                parts = parts[:-1]
            out[".".join(parts)] = p
    return out


def import_graph() -> dict[str, set[str]]:
    """Module -> modules of harness/methods it imports anywhere in its body (not its parents)."""
    mods = _modules()
    graph: dict[str, set[str]] = {m: set() for m in mods}
    for mod, path in mods.items():
        is_pkg = path.name == "__init__.py"
        base = mod.split(".") if is_pkg else mod.split(".")[:-1]
        for node in ast.walk(ast.parse(path.read_text())):
            targets = []
            if isinstance(node, ast.Import):
                targets = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom):
                if node.level:
                    anchor = base[:len(base) - node.level + 1]
                    src = ".".join(anchor + ([node.module] if node.module else []))
                else:
                    src = node.module or ""
                for a in node.names:
                    sub = f"{src}.{a.name}"
                    targets.append(sub if sub in mods else src)
            for t in targets:
                while t and t not in mods:          # `import harness.core.geometry` -> that module
                    t = t.rpartition(".")[0]
                if t and t != mod and not mod.startswith(t + "."):   # a module's own parents are implicit
                    graph[mod].add(t)
    return graph


def find_cycle(graph) -> list[str] | None:
    state: dict[str, int] = {}
    stack: list[str] = []

    def visit(n):
        state[n] = 1
        stack.append(n)
        for m in sorted(graph.get(n, ())):
            if state.get(m) == 1:
                return stack[stack.index(m):] + [m]
            if m not in state:
                c = visit(m)
                if c:
                    return c
        stack.pop()
        state[n] = 2
        return None

    for n in sorted(graph):
        if n not in state:
            c = visit(n)
            if c:
                return c
    return None


def reachable(graph, start) -> set[str]:
    seen, todo = set(), [start]
    while todo:
        n = todo.pop()
        for m in graph.get(n, ()):
            if m not in seen:
                seen.add(m)
                todo.append(m)
    return seen


def test_the_cycle_finder_finds_cycles():
    assert find_cycle({"a": {"b"}, "b": {"c"}, "c": {"a"}}) == ["a", "b", "c", "a"]
    assert find_cycle({"a": {"b"}, "b": set()}) is None


def test_no_import_cycle_in_harness_or_methods():
    g = import_graph()
    assert len(g) > 40 and "harness.runner" in g["harness.executors.isolation"]   # the graph sees imports
    assert find_cycle(g) is None, " -> ".join(find_cycle(g))


@pytest.mark.parametrize("reader", ["harness.report.html", "harness.compare", "harness.benchmark_json"])
def test_run_folder_readers_import_no_runner_config_executor_or_method(reader):
    bad = {m for m in reachable(import_graph(), reader)
           if m in ("harness.config", "harness.runner", "harness.session") or m.startswith("harness.executors")
           or m == "methods" or m.startswith("methods.")}
    assert not bad, f"{reader} reaches {sorted(bad)}"


def test_the_judge_imports_no_contestant():
    g = import_graph()
    for mod, deps in g.items():
        if mod.startswith("harness."):
            assert not any(d.startswith("methods.scratch") for d in deps), (mod, deps)
        if mod.startswith("harness.core") or mod.startswith("harness.metrics") or mod.startswith("harness.tasks"):
            assert not any(d == "methods" or d.startswith("methods.") for d in deps), (mod, deps)


def test_no_adapter_imports_another_backends_private_names():
    for mod, path in _modules().items():
        if not mod.startswith("methods."):
            continue
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom) and node.module and node.module.startswith("methods."):
                own = mod.split(".")[1]
                other = node.module.split(".")[1]
                if other != own:
                    assert not any(a.name.startswith("_") for a in node.names), (mod, node.module)


PLUGIN = '''
from methods import register, SmoothingResult


@register("ghostlab.shrink", task="smoothing", library="ghostlab", params={"amount": 0.5})
def shrink(V, F, *, amount=0.5):
    """Move every vertex halfway to the centroid (a test plugin)."""
    c = V.mean(axis=0)
    return SmoothingResult(V=c + (1 - amount) * (V - c))
'''


def test_a_run_with_a_plugin_is_reported_after_the_plugin_is_gone(tmp_path):
    """Views included, and the plugin module is never imported by `shootout report`."""
    plug = tmp_path / "plug"
    plug.mkdir()
    (plug / "ghostlab_plugin.py").write_text(PLUGIN)
    cfg = {"name": "ghost", "hausdorff_samples": 300, "time_budget": 0, "save_meshes": False, "plugins": ["ghostlab_plugin"],
           "meshes": ["knight"], "noise": [{"model": "gaussian_normal", "levels": [0.2]}],
           "tasks": {"smoothing": {"methods": ["ghostlab.shrink", "scratch.explicit"]}}}
    (plug / "ghost.yaml").write_text(json.dumps(cfg))
    out = tmp_path / "run"
    env_py = sys.executable
    r = subprocess.run([env_py, "-m", "harness.cli", "run", str(plug / "ghost.yaml"), "--out", str(out), "--quiet"],
                       cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    shutil.rmtree(plug)                                          # the plugin is uninstalled
    (out / "report.html").unlink()
    probe = textwrap.dedent(f"""
        import sys
        from harness.cli import main
        code = main(["report", {str(out)!r}])
        bad = sorted(m for m in sys.modules if m.startswith("ghostlab") or m in ("harness.runner", "harness.config")
                     or m.startswith("harness.executors") or m == "methods" or m.startswith("methods."))
        print("IMPORTED", bad)
        sys.exit(code)
    """)
    r = subprocess.run([env_py, "-c", probe], cwd=tmp_path, capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    assert "IMPORTED []" in r.stdout
    html = (out / "report.html").read_text()
    data = json.loads(html.split("id='report-data'>", 1)[1].split("</script>", 1)[0].replace("<\\/", "</"))
    views = data["views"]
    assert views and all("error" not in v for v in views)
    assert any(v["title"].startswith("ghostlab.shrink") for v in views)


def test_a_users_methods_module_shadowing_ours_is_explained(tmp_path):
    """A methods.py next to a notebook comes first on sys.path: say so instead of an ImportError."""
    (tmp_path / "methods.py").write_text("from methods import register\n")
    (tmp_path / "c.yaml").write_text("meshes: [knight]\ntasks: {smoothing: {methods: [scratch.explicit]}}\n")
    r = subprocess.run([sys.executable, "-c", "import sys; sys.path.insert(0, ''); from harness.cli import main; "
                        "sys.exit(main(['run', 'c.yaml', '--out', 'o']))"],
                       cwd=tmp_path, capture_output=True, text=True, timeout=120)
    assert r.returncode == 2, r.stderr
    assert "shadows it" in r.stderr and str(tmp_path / "methods.py") in r.stderr and "Traceback" not in r.stderr
    assert not (tmp_path / "o").exists()


def test_a_plugin_imported_before_the_builtins_cannot_take_a_builtins_name(tmp_path):
    """From Python, a plugin imported before anything loaded the built-ins registered
    'scratch.taubin' as its own; the built-in module then failed to import (its name was taken),
    silently costing its other methods, and the plugin's rows carried the built-in's name."""
    (tmp_path / "hijack.py").write_text(textwrap.dedent('''
        from methods import register, SmoothingResult

        @register("scratch.taubin", task="smoothing", library="mylab", params={})
        def taubin(V, F):
            return SmoothingResult(V=V + 1.0)
    '''))
    r = subprocess.run([sys.executable, "-c", "import hijack"], cwd=tmp_path, capture_output=True, text=True,
                       timeout=120, env={**__import__("os").environ, "PYTHONPATH": f"{ROOT}:{tmp_path}"})
    assert r.returncode == 1 and "'scratch.taubin' is already registered (by methods.scratch.smoothing)" in r.stderr


def test_register_refuses_parameters_the_function_cannot_take_or_defaults_out_of_bounds():
    """A function declaring Param('amount') but taking amt=, or a default of 5.0 beyond high=1.0,
    registered fine and every case was then an error row."""
    from methods import Param, SmoothingResult, register
    with pytest.raises(ValueError, match="does not take parameter 'amount'"):
        @register("archtest.misnamed", task="smoothing", library="archtest", params={"amount": Param("amount", 0.1)})
        def misnamed(V, F, *, amt=0.1):
            return SmoothingResult(V=V)
    with pytest.raises(ValueError, match="default of 'amount' is refused"):
        @register("archtest.outofbounds", task="smoothing", library="archtest",
                  params={"amount": Param("amount", 5.0, high=1.0)})
        def outofbounds(V, F, *, amount=5.0):
            return SmoothingResult(V=V)

    @register("archtest.kwargs", task="smoothing", library="archtest", params={"amount": 0.1})
    def kwargs(V, F, **kw):                        # **kwargs takes every keyword
        return SmoothingResult(V=V)
    def refuse_big(p):
        return "amount above 0.5 needs mode 'b'" if p["amount"] > 0.5 and p["mode"] != "b" else None

    @register("archtest.combo", task="smoothing", library="archtest", setting_check=refuse_big,
              params={"amount": Param("amount", 0.1, high=1.0), "mode": Param("mode", "a", choices=("a", "b"))})
    def combo(V, F, *, amount=0.1, mode="a"):
        return SmoothingResult(V=V)

    @register("archtest.raising", task="smoothing", library="archtest", setting_check=lambda p: p["nope"],
              params={"amount": 0.1})
    def raising(V, F, *, amount=0.1):
        return SmoothingResult(V=V)
    import numpy as np

    from harness.config import load_config
    from harness.errors import ConfigError
    V, F = np.eye(3), np.array([[0, 1, 2]])
    with pytest.raises(ValueError, match="needs mode 'b'"):
        combo(V, F, amount=0.9)                    # the decorated function, called directly
    base = {"meshes": ["knight"], "tasks": {"smoothing": {"methods": [
        {"name": "archtest.combo", "params": {"amount": [0.1, 0.9]}}, {"name": "archtest.raising"}]}}}
    with pytest.raises(ConfigError) as e:
        load_config(base)
    assert "1 of its 2 setting(s) cannot run" in str(e.value) and "setting_check failed" in str(e.value), str(e.value)
    tuned = {"meshes": ["knight"], "tasks": {"smoothing": {"methods": ["archtest.combo"]}},
             "tune": {"metric": "dist_mean", "train": ["spot"], "params": {"archtest.combo": {"amount": [0.2, 0.9]}}}}
    with pytest.raises(ConfigError, match="a candidate setting .* cannot run: amount above 0.5"):
        load_config(tuned)
    import methods
    from methods.registry import _REGISTRY
    try:
        assert "archtest.kwargs" in [m.name for m in methods.all_methods("smoothing")]
        assert not {"archtest.misnamed", "archtest.outofbounds"} & {m.name for m in methods.all_methods()}
    finally:
        for n in ("archtest.kwargs", "archtest.combo", "archtest.raising"):
            _REGISTRY.pop(n, None)                         # other tests list every method
