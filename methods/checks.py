"""Conformance checks for methods, runnable in anyone's test suite.

``check_method(method)`` yields ``(name, check)`` pairs; each ``check()`` raises (an
AssertionError or the method's own exception) when the method breaks the contract. The checks:
declared defaults valid and a docstring present; output of the task's result type, of the right
shapes and dtypes, finite, its input arrays left as they were, and the same on a second call
(closed mesh), also on an open mesh
(not for simplification); unknown or out-of-range parameters and malformed arrays raise
ValueError naming the problem; and the task's own checks (`harness.tasks`: e.g. W rows summing
to zero in libigl's sign with a positive diagonal M, the face target reached).

In a plugin's tests (pytest)::

    from methods.checks import parametrize_with_checks

    @parametrize_with_checks(["mylab.wiggle"])
    def test_conformance(method, check):
        check()

A method declares a check it is known to fail with ``register(..., expected_failures={"name":
"why"})``; `parametrize_with_checks` marks it ``xfail(strict=True)`` with that reason.
"""
from __future__ import annotations

import functools
from typing import Callable, Iterator

import numpy as np

from harness import tasks

from . import registry
from .base import Method


@functools.lru_cache(maxsize=None)
def _mesh(name: str):
    from harness import datasets
    m = datasets.load(name).clean
    return m.V, m.F


def closed_mesh():
    """A small closed test mesh (decimated knight, 1k faces): fresh copies, so a method that
    writes into its input spoils no later check."""
    V, F = _mesh("knight")
    return V.copy(), F.copy()


def open_mesh():
    """A small mesh with boundary (woody), as fresh copies."""
    V, F = _mesh("woody")
    return V.copy(), F.copy()


def _declaration(m: Method):
    for p in m.params.values():
        assert p.problem(p.default) is None, f"default of {p.name!r} is invalid: {p.problem(p.default)}"
    assert m.doc, f"{m.name} has no docstring"


def _output_and_determinism(m: Method):
    V, F = closed_mesh()
    run, finish = m.bind(V, F)        # as m(V, F), which validates type, shapes, dtypes, but on the
    a = finish(run())                 # arrays themselves (m(V, F) hands the method copies)
    V0, F0 = closed_mesh()
    assert np.array_equal(V, V0) and np.array_equal(F, F0), \
        "the method wrote into its input arrays (a caller's mesh, e.g. a cached dataset, changes under it)"
    b = m(V, F)
    for x, y in zip(_arrays(a), _arrays(b)):
        assert x.shape == y.shape, "a second call returned a different shape"
        np.testing.assert_allclose(x, y, rtol=0, atol=1e-12, err_msg="a second call returned different values")


def _arrays(res) -> list[np.ndarray]:
    """The numeric fields of a result, except measured times (fields named ``*_s``)."""
    out = []
    for k, v in vars(res).items():
        if v is None or k.endswith("_s"):
            continue
        if hasattr(v, "toarray"):
            v = v.toarray() if v.shape[0] < 3000 else v.data
        a = np.asarray(v)
        if a.dtype.kind in "fiu":
            assert np.isfinite(a).all(), "non-finite values in the output"
            out.append(a)
    return out


def _open_mesh(m: Method):
    V, F = open_mesh()
    _arrays(m(V, F))


def _bad_parameters(m: Method):
    import pytest
    V, F = closed_mesh()
    with pytest.raises(ValueError, match="unknown parameter"):
        m(V, F, no_such_parameter_xyz=1)
    for name, p in m.params.items():
        bad = "not-a-number" if p.kind in ("int", "float", "bool") else 12345
        with pytest.raises(ValueError, match=name):
            m(V, F, **{name: bad})
        if p.low is not None:
            with pytest.raises(ValueError, match=name):
                m(V, F, **{name: p.low - 1})


def _bad_arrays(m: Method):
    import pytest
    V, F = closed_mesh()
    Vn = V.copy()
    Vn[3] = np.nan
    for args, needle in [((Vn, F), "NaN"), ((V, F + len(V)), "out of range"), ((V[:, :2], F), "shape"),
                         ((V, F[:, :2]), "shape"), ((V[:0], F[:0]), "empty")]:
        with pytest.raises(ValueError, match=needle):
            m(*args)


def check_method(method: Method | str) -> Iterator[tuple[str, Callable[[], None]]]:
    """``(name, check)`` for every conformance check of ``method`` (a `Method` or its name)."""
    m = registry.get(method) if isinstance(method, str) else method
    yield "declaration", functools.partial(_declaration, m)
    yield "bad_parameters", functools.partial(_bad_parameters, m)
    yield "bad_arrays", functools.partial(_bad_arrays, m)
    yield "output_and_determinism", functools.partial(_output_and_determinism, m)
    if m.task != "simplification":
        yield "open_mesh", functools.partial(_open_mesh, m)
    for name, fn in tasks.get(m.task).checks:
        yield name, functools.partial(fn, m, *closed_mesh())


def parametrize_with_checks(methods_):
    """A pytest ``parametrize`` mark over ``(method, check)`` for every check of every method.

    ``methods_``: `Method` objects or names. A method that is unavailable here (its library does
    not import) gets its checks skipped with the reason; a check the method declares in
    ``expected_failures`` is marked ``xfail(strict=True)`` with the declared reason.
    """
    import pytest
    params = []
    for item in methods_:
        m = registry.get(item) if isinstance(item, str) else item
        why = m.unavailable_reason()
        for name, check in check_method(m):
            marks = []
            if why:
                marks.append(pytest.mark.skip(reason=why))
            elif name in m.expected_failures:
                marks.append(pytest.mark.xfail(reason=m.expected_failures[name], strict=True))
            params.append(pytest.param(m, check, id=f"{m.name}-{name}", marks=marks))
    return pytest.mark.parametrize("method, check", params)
