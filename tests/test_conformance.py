"""Conformance suite: every registered method through the published checks (`methods.checks`,
the scikit-learn ``parametrize_with_checks`` pattern), plus registry-level facts."""
import subprocess
import sys
import textwrap

import pytest

import methods
from methods.checks import check_method, parametrize_with_checks
from methods.registry import BROKEN

ALL = methods.all_methods()
IDS = [m.name for m in ALL]
BUILTIN = [m for m in ALL if m.func.__module__.startswith("methods.") and not m.extra]
OPTIONAL = [m for m in ALL if m.func.__module__.startswith("methods.") and m.extra]


def test_every_builtin_module_imports():
    methods.all_methods()
    assert BROKEN == {}, BROKEN


def test_registry_has_the_promised_methods():
    names = set(IDS)
    for n in ["scratch.uniform", "scratch.cotan", "libigl.cotan", "scratch.explicit", "fast_simplification.qem"]:
        assert n in names


def test_every_parameter_is_named_by_its_key():
    """`shootout methods`, errors and rows name a parameter by what the user passes: a shared
    Param declared under another key (``linear_solver: solver_param()``) takes that key."""
    wrong = {(m.name, k, p.name) for m in ALL for k, p in m.params.items() if p.name != k}
    assert not wrong, wrong
    m = methods.get("scratch.spectrum")
    with pytest.raises(Exception, match="linear_solver"):
        m.resolve_params({"linear_solver": "no-such-solver"})


@pytest.mark.parametrize("m", BUILTIN, ids=[m.name for m in BUILTIN])
def test_builtin_is_available(m):
    # make test installs every backend, so no built-in may be unavailable here
    assert m.unavailable_reason() is None


@pytest.mark.parametrize("m", OPTIONAL, ids=[m.name for m in OPTIONAL])
def test_optional_backend_is_available_or_says_how_to_install_it(m):
    why = m.unavailable_reason()
    assert why is None or f"pip install -e '.[{m.extra}]'" in why      # as the README says


def test_the_optional_extras_are_declared():
    import tomllib
    from pathlib import Path
    extras = tomllib.loads((Path(__file__).parents[1] / "pyproject.toml").read_text())["project"]["optional-dependencies"]
    assert OPTIONAL and all(m.extra in extras for m in OPTIONAL)


@parametrize_with_checks(ALL)
def test_conformance(method, check):
    check()


def test_a_broken_method_fails_the_checks():
    """The checks can fail: a method returning the wrong dtype, or ignoring bad parameters."""
    from methods import Method, SmoothingResult

    def lists(V, F, *, amount=0.1):
        """Returns Python lists instead of a float64 array."""
        return SmoothingResult(V=V.tolist())

    m = Method(name="broken.lists", task="smoothing", library="broken", func=lists,
               params={"amount": methods.Param("amount", 0.1, low=0.0)}, doc="broken")
    checks = dict(check_method(m))
    with pytest.raises(methods.MethodFailed, match="list"):
        checks["output_and_determinism"]()
    checks["bad_parameters"]()          # parameter validation is the interface's, so it still holds


def test_writing_into_the_input_and_a_flipped_laplacian_fail_the_checks():
    """Before: a method that flattened its input in place passed every check and left the checks'
    shared mesh (and `datasets.load`'s, the cache of every later run in the process) flat; a Laplacian of the wrong sign passed them all."""
    import numpy as np
    import scipy.sparse as sp

    from harness import datasets
    from methods import LaplacianResult, Method, SmoothingResult

    def squash(V, F):
        """Flattens its input in place."""
        V[:, 2] = 0.0
        return SmoothingResult(V=V.copy())

    m = Method(name="broken.squash", task="smoothing", library="broken", func=squash, params={}, doc="broken")
    with pytest.raises(AssertionError, match="wrote into its input"):
        dict(check_method(m))["output_and_determinism"]()
    squash(datasets.load("knight").clean.V, None)           # a direct call on a loaded mesh
    assert np.ptp(datasets.load("knight").clean.V[:, 2]) > 0 and np.ptp(datasets.cached("knight").clean.V[:, 2]) > 0

    def flipped(V, F, *, mass=1.0):
        """-cotmatrix, a mass matrix of ``mass``."""
        import igl
        return LaplacianResult(W=-igl.cotmatrix(V, F), M=mass * sp.identity(len(V), format="csr"))

    lap = Method(name="broken.flipped", task="laplacian", library="broken", func=flipped,
                 params={"mass": methods.Param("mass", 1.0)}, doc="broken")
    checks = dict(check_method(lap))
    checks["rows_sum_to_zero"]()
    with pytest.raises(AssertionError, match="libigl's sign"):
        checks["sign_convention"]()
    with pytest.raises(methods.MethodFailed, match="negative diagonal entries"):
        lap(np.eye(3), np.array([[0, 1, 2]]), mass=-1.0)


def test_a_plugin_authors_test_file_runs_the_published_checks(tmp_path):
    """The README's example plugin and its few-line test file, run by pytest as a plugin author would."""
    (tmp_path / "my_lab").mkdir()
    (tmp_path / "my_lab" / "__init__.py").write_text("")
    (tmp_path / "my_lab" / "methods.py").write_text(textwrap.dedent('''
        from methods import register, Param, SmoothingResult

        @register("mylab.wiggle", task="smoothing", library="mylab",
                  params={"amount": Param("amount", 0.1, low=0.0, high=1.0, doc="fraction of an edge")},
                  expected_failures={"open_mesh": "demonstrates a declared expected failure"})
        def wiggle(V, F, *, amount=0.1):
            """Move every vertex by `amount` (input units). V (n, 3) float64, F (m, 3) int64."""
            if V[:, 2].min() == V[:, 2].max():
                raise RuntimeError("refuses flat meshes (the open test mesh is flat): a declared failure")
            return SmoothingResult(V=V + amount)
    '''))
    (tmp_path / "test_my_lab.py").write_text(textwrap.dedent('''
        import my_lab.methods  # noqa: F401  (registers the method)
        from methods.checks import parametrize_with_checks

        @parametrize_with_checks(["mylab.wiggle"])
        def test_conformance(method, check):
            check()
    '''))
    r = subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "-o", "addopts=",
                        str(tmp_path / "test_my_lab.py")], cwd=tmp_path, capture_output=True, text=True, timeout=300)
    out = r.stdout + r.stderr
    assert r.returncode == 0, out
    assert "4 passed, 1 xfailed" in out, out
