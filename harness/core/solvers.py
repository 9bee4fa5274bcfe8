"""Sparse symmetric positive-definite solves for the implicit smoothing systems.

The implicit methods (backward Euler ``(M - h W) X' = M X``, screened Poisson
``(alpha^2 M - W) X = alpha^2 M X0``) solve one SPD system with three right-hand sides per
step. This module picks a direct solver among those that import here, factors each matrix
once (callers reuse the factor across iterations) and keeps the *symbolic* analysis (the
fill-reducing ordering, and where the backend allows it the elimination structure) in a small
cache keyed on the sparsity pattern, so reassembled systems of the same mesh within one call
skip the analysis but always redo the numeric factorization. The runner empties the cache
before every timed call (`harness.runner.forget_inputs`): a sample pays for the analysis as a
first call on its mesh does.

Backends (name: what it is; symbolic reuse):

``cholmod``
    scikit-sparse's CHOLMOD supernodal Cholesky (``sksparse.cholmod``); reuses the symbolic
    analysis (``analyze`` once, ``cholesky_inplace`` per matrix). Needs SuiteSparse headers to
    build, so it is not installable from PyPI alone (0.4.x builds against Debian's
    SuiteSparse 5; 0.5 needs SuiteSparse 7).
``pypardiso``
    Intel MKL PARDISO through pypardiso, matrix type 2 (real SPD), upper triangle; phase 11
    (analysis) once per pattern, phase 22 (numeric) per matrix, phase 33 (solve).
``scipy``
    ``scipy.sparse.linalg.splu`` (SuperLU) in symmetric mode (``SymmetricMode=True``,
    ``diag_pivot_thresh=0``: diagonal pivots, fine for SPD). The ordering is reverse
    Cuthill-McKee followed by ``permc_spec="MMD_AT_PLUS_A"``; it is cached per pattern and the
    matrix, permuted symmetrically, is factored with ``NATURAL``. Always present: the
    pure-scipy fallback.
``qdldl``
    OSQP's QDLDL (``qdldl.Solver``): AMD ordering + up-looking LDL^T, single-threaded;
    ``update`` reuses the symbolic factorization.
``cholespy``
    cholespy's ``CholeskySolverD`` (bundled CHOLMOD); analysis is redone for each matrix.

``auto`` picks by size, the first importable of ``AUTO_SMALL`` below ``AUTO_SMALL_MAX_N``
unknowns and of ``AUTO_LARGE`` above (fastest first, from the timings of
``benchmarks/bench_implicit.py``). The environment variable ``MESH_SHOOTOUT_SOLVER`` overrides
the automatic choice. :func:`solver_info` reports the policy, what is installed and the
backend last used, for ``run.json``.
"""
from __future__ import annotations

import hashlib
import importlib
import os
import sys

import numpy as np
import scipy.sparse as sp

from .solver_backends import _BACKENDS, _SYMBOLIC, Factor, _new_pardiso

SOLVERS = ("cholmod", "pypardiso", "scipy", "qdldl", "cholespy")
# Fastest first, from benchmarks/bench_implicit.py (2 cores). Small systems (up to
# AUTO_SMALL_MAX_N vertices): the single-threaded LDL^T of QDLDL has no start-up cost (PARDISO's
# first call loads MKL in every fresh process). Above, QDLDL's AMD fill decides and depends on
# the mesh (an icosphere fills far more than armadillo at the same size: benchmarks/bench_implicit.py
# times every backend),
# so PARDISO, whose time varies less, is chosen.
# Large systems: supernodal, multithreaded factorizations win; a scikit-sparse built on the
# OS SuiteSparse (Debian 5.12, its BLAS) measured 4x slower than PARDISO at 1.3M faces.
AUTO_SMALL = ("qdldl", "scipy")
AUTO_LARGE = ("pypardiso", "cholespy", "cholmod", "scipy")
AUTO_SMALL_MAX_N = 5_000
AUTO_ORDER = AUTO_LARGE
_MODULES = {"cholmod": "sksparse.cholmod", "pypardiso": "pypardiso", "scipy": "scipy",
            "qdldl": "qdldl", "cholespy": "cholespy"}
_DIST = {"cholmod": "scikit-sparse", "pypardiso": "pypardiso", "scipy": "scipy",
         "qdldl": "qdldl", "cholespy": "cholespy"}
SOLVER_CHOICES = ("auto",) + SOLVERS

_USED: dict = {}             # backend -> largest system `factorize` gave it since `forget_used`


_IMPORTABLE: dict = {}


def _importable(name: str) -> bool:
    if name in _IMPORTABLE:
        return _IMPORTABLE[name]
    ok = True
    try:
        if name == "pypardiso":  # importing it builds a solver, which looks up mkl_rt
            _new_pardiso()
        else:
            importlib.import_module(_MODULES[name])
    except Exception:  # ImportError, or a broken binary (e.g. mkl_rt not found)
        ok = False
    _IMPORTABLE[name] = ok
    return ok


def installed_solvers() -> list[str]:
    """Backends that import here, in ``SOLVERS`` order."""
    return [s for s in SOLVERS if _importable(s)]


def auto_solver(n: int | None = None) -> str:
    """The backend ``auto`` resolves to for an ``n``-by-``n`` system (``n`` None: large).

    ``MESH_SHOOTOUT_SOLVER`` (a backend name) overrides the choice.
    """
    env = os.environ.get("MESH_SHOOTOUT_SOLVER", "").strip()
    if env and env != "auto":
        if env not in SOLVERS:
            raise ValueError(f"MESH_SHOOTOUT_SOLVER={env!r}: expected one of {SOLVER_CHOICES}")
        return env
    order = AUTO_SMALL if (n is not None and n < AUTO_SMALL_MAX_N) else AUTO_LARGE
    for s in order:
        if _importable(s):
            return s
    return "scipy"


def solver_info() -> dict:
    """Provenance for ``run.json``: the automatic choice, installed backends and versions."""
    from importlib.metadata import PackageNotFoundError, version
    versions = {}
    for s in installed_solvers():
        try:
            versions[s] = version(_DIST[s])
        except PackageNotFoundError:
            versions[s] = None
    return {"auto": auto_solver(), "auto_small": auto_solver(1),
            "auto_small_max_n": AUTO_SMALL_MAX_N,
            "auto_order_small": list(AUTO_SMALL), "auto_order_large": list(AUTO_LARGE),
            "env_override": os.environ.get("MESH_SHOOTOUT_SOLVER") or None,
            "installed": installed_solvers(), "versions": versions}


def forget_used() -> None:
    """Start a new record of the backends `factorize` uses (`used`)."""
    _USED.clear()


def used() -> dict:
    """``{backend: unknowns}``: each backend `factorize` used since `forget_used`, with the
    largest system it factored (the automatic choice included, resolved to its backend)."""
    return dict(_USED)


def _canonical(A) -> sp.csr_matrix:
    A = sp.csr_matrix(A, dtype=np.float64)
    A.sum_duplicates()
    A.sort_indices()
    return A


def _pattern_key(name: str, A: sp.csr_matrix) -> tuple:
    h = hashlib.blake2b(digest_size=16)
    h.update(np.asarray(A.shape, np.int64).tobytes())
    h.update(np.ascontiguousarray(A.indptr, np.int64).tobytes())
    h.update(np.ascontiguousarray(A.indices, np.int64).tobytes())
    return (name, h.hexdigest())


def clear_cache() -> None:
    """Drop every cached symbolic analysis (benchmarks use it to time cold factorizations)."""
    while _SYMBOLIC:
        _, old = _SYMBOLIC.popitem()
        free = getattr(old, "free", None)
        if callable(free):
            free()


def forget_inputs() -> None:
    """`clear_cache`, and the factorization ``pypardiso.spsolve`` keeps in its module-level
    solver: it reuses it, without solving anew, whenever it sees the same matrix again, so a
    plugin calling it would have every timed sample flattered by the cold call's factorization.
    pypardiso is not imported for this (a method that never loaded it has nothing kept)."""
    clear_cache()
    ps = getattr(sys.modules.get("pypardiso"), "ps", None)
    if getattr(getattr(ps, "factorized_A", None), "shape", (0, 0)) != (0, 0):   # one kept: forget it
        try:
            ps.remove_stored_factorization()
        except Exception:  # noqa: BLE001 - another pypardiso version: nothing to forget there
            pass


def factorize(A, solver: str = "auto", reuse_symbolic: bool = True) -> Factor:
    """Factor the SPD matrix ``A`` with ``solver`` (a name of ``SOLVER_CHOICES``).

    Parameters
    ----------
    A : (n, n) scipy sparse, symmetric positive definite
    solver : str
        ``auto`` (see :func:`auto_solver`) or a backend name; ValueError when unknown or not
        installed.
    reuse_symbolic : bool
        Look up / store the symbolic analysis in the pattern-keyed cache.

    Returns
    -------
    Factor
        ``.solve(B)`` returns ``A^-1 B``; ``.name`` is the backend used.
    """
    name = auto_solver(A.shape[0]) if solver == "auto" else solver
    if name not in _BACKENDS:
        raise ValueError(f"unknown solver {solver!r}; expected one of {SOLVER_CHOICES}")
    if not _importable(name):
        raise ValueError(f"solver {name!r} is not installed here (installed: {installed_solvers()})")
    A = _canonical(A)
    key = _pattern_key(name, A) if reuse_symbolic else None
    fac = _BACKENDS[name](A, key)
    _USED[name] = max(_USED.get(name, 0), int(A.shape[0]))
    return fac


def spd_solve(A, B, solver: str = "auto") -> np.ndarray:
    """``A^-1 B`` for one SPD system (factor, solve, discard the numeric factor)."""
    return factorize(A, solver).solve(B)


def backward_euler(V, F, operator, h, iterations, reassemble, solver="auto"):
    """Shared core of the implicit methods: ``(M - h W) X_{k+1} = M X_k``, ``iterations`` times.

    ``operator(X) -> (W, m)`` builds the operator at positions ``X``; with ``reassemble``
    false it is built once from ``V`` and the matrix is factored once; with ``reassemble``
    true it is rebuilt (and refactored, reusing the cached symbolic analysis of the unchanged
    pattern) before every step. ``h`` stays fixed.
    """
    X = V.copy()
    fac = m = None
    for it in range(iterations):
        if fac is None or reassemble:
            W, m = operator(X)
            fac = factorize(sp.diags(m) - h * W, solver)
        X = fac.solve(m[:, None] * X)
    return X
