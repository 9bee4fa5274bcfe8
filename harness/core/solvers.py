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
from collections import OrderedDict

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as sla

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

_SYMBOLIC: "OrderedDict[tuple, object]" = OrderedDict()
_CACHE_SIZE = 4
_LAST_USED: dict = {}


_IMPORTABLE: dict = {}
_PARDISO_TEMPLATE: list = []


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


def _new_pardiso(mtype: int = 2):
    """A fresh PARDISO handle. pypardiso's constructor locates mkl_rt (``find_library``'s
    subprocesses, then a recursive glob of the whole environment when they miss it, as they do
    for the pip wheel: 0.5 s or more), and importing pypardiso builds one such solver: both run
    once, pointed at the wheel's library where pip puts it, and later handles copy the loaded
    library and get fresh state arrays."""
    import copy
    if not _PARDISO_TEMPLATE:
        import glob
        import sys
        env = os.environ.get("PYPARDISO_MKL_RT")
        hits = sorted(glob.glob(os.path.join(sys.prefix, "lib", "libmkl_rt.so*")), key=len)
        if env is None and hits:
            os.environ["PYPARDISO_MKL_RT"] = hits[0]
        try:
            import pypardiso
            _PARDISO_TEMPLATE.append(pypardiso.PyPardisoSolver(mtype=mtype))
        finally:
            if env is None and hits:
                del os.environ["PYPARDISO_MKL_RT"]
    s = copy.copy(_PARDISO_TEMPLATE[0])
    s.pt = np.zeros(64, dtype=s._pt_type[1])
    s.iparm = np.zeros(64, dtype=np.int32)
    s.perm = np.zeros(0, dtype=np.int32)
    s.mtype = mtype
    s.phase = 13
    s.factorized_A = sp.csr_matrix((0, 0))
    return s


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
            "installed": installed_solvers(), "versions": versions,
            "last_used": dict(_LAST_USED)}


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


def _cache_get(key):
    if key in _SYMBOLIC:
        _SYMBOLIC.move_to_end(key)
        return _SYMBOLIC[key]
    return None


def _cache_put(key, value) -> None:
    _SYMBOLIC[key] = value
    _SYMBOLIC.move_to_end(key)
    while len(_SYMBOLIC) > _CACHE_SIZE:
        _, old = _SYMBOLIC.popitem(last=False)
        free = getattr(old, "free", None)
        if callable(free):
            free()


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


class Factor:
    """A numeric factorization of an SPD matrix; ``solve(B)`` for B (n,) or (n, k)."""

    name = ""

    def solve(self, B: np.ndarray) -> np.ndarray:  # pragma: no cover - interface
        raise NotImplementedError

    def _columns(self, B, one):
        B = np.asarray(B, dtype=np.float64)
        if B.ndim == 1:
            return one(B)
        return np.column_stack([one(B[:, k]) for k in range(B.shape[1])])


class _ScipyFactor(Factor):
    name = "scipy"

    def __init__(self, A: sp.csr_matrix, key):
        cached = _cache_get(key) if key is not None else None
        opts = {"SymmetricMode": True}
        if cached is None:
            # first matrix of this pattern: order and factor in one SuperLU call
            perm, self._lu, self._perm = self._ordering(A)
            if key is not None:
                _cache_put(key, _ScipyOrdering(perm))
        else:
            perm = cached.perm
            Ap = A[perm][:, perm].tocsc()
            self._lu = sla.splu(Ap, permc_spec="NATURAL", diag_pivot_thresh=0.0, options=opts)
            self._perm = perm

    @staticmethod
    def _ordering(A: sp.csr_matrix):
        """Symmetric fill-reducing ordering: reverse Cuthill-McKee, then SuperLU's MMD on
        A + A^T. MMD breaks its many ties by index, and on very regular meshes (icospheres)
        the input numbering alone made SuperLU 5-10x slower at equal fill; the RCM
        pre-ordering removes that (bunny, armadillo: no change).

        Returns ``(perm, lu, r)``: the ordering to cache, and the factorization of
        ``A[r][:, r]`` made while computing it."""
        from scipy.sparse.csgraph import reverse_cuthill_mckee
        r = np.asarray(reverse_cuthill_mckee(A, symmetric_mode=True), dtype=np.int64)
        Ar = A[r][:, r].tocsc()
        lu = sla.splu(Ar, permc_spec="MMD_AT_PLUS_A", diag_pivot_thresh=0.0,
                      options={"SymmetricMode": True})
        # SuperLU factors Ar[:, q] with q = argsort(perm_c) (rows alike, diagonal pivots)
        q = np.argsort(np.asarray(lu.perm_c, dtype=np.int64))
        return r[q], lu, r

    def solve(self, B):
        B = np.asarray(B, dtype=np.float64)
        X = np.empty_like(B)
        X[self._perm] = self._lu.solve(np.ascontiguousarray(B[self._perm]))
        return X


class _ScipyOrdering:
    __slots__ = ("perm",)

    def __init__(self, perm):
        self.perm = perm


class _PardisoSymbolic:
    """A PARDISO handle that has run the analysis phase (11) for one pattern."""

    owner = None

    def __init__(self, U: sp.csr_matrix):
        self.solver = _new_pardiso(mtype=2)
        # user settings: parallel nested-dissection ordering (iparm[1] = 3), pivot perturbation
        # 1e-8 (iparm[9] = 8, the SPD default), two-level parallel factorization (iparm[23] = 1),
        # one-based indices (pypardiso passes them so). Measured 0.78-0.80x the default
        # settings' analysis + factor + solve at 327k-1.31M faces (benchmarks/bench_implicit_vs_user.py).
        ip = self.solver.iparm
        ip[0], ip[1], ip[9], ip[23], ip[34] = 1, 3, 8, 1, 0
        self.solver._check_A(U)
        self.solver.set_phase(11)
        self.solver._call_pardiso(U, np.zeros((U.shape[0], 1)))

    def free(self):
        """Release the handle (evicted or `clear_cache`); a Factor still holding it analyses again."""
        self.owner = None
        self.freed = True
        try:
            self.solver.free_memory(everything=True)
        except Exception:  # already released; nothing else to do
            pass


class _PardisoFactor(Factor):
    name = "pypardiso"

    def __init__(self, A: sp.csr_matrix, key):
        U = sp.triu(A, format="csr")
        U.sort_indices()
        sym = _cache_get(key) if key is not None else None
        if sym is None:
            sym = _PardisoSymbolic(U)
            if key is not None:
                _cache_put(key, sym)
        self._sym = sym
        self._U = U
        self._numeric()

    def _numeric(self):
        # The cached handle holds one numeric factor: the last Factor that ran phase 22 owns it.
        s = self._sym.solver
        s.set_phase(22)
        s._call_pardiso(self._U, np.zeros((self._U.shape[0], 1)))
        self._sym.owner = self

    def solve(self, B):
        B = np.asarray(B, dtype=np.float64)
        if getattr(self._sym, "freed", False):       # its handle was released since: analyse again
            self._sym = _PardisoSymbolic(self._U)
        if getattr(self._sym, "owner", None) is not self:
            self._numeric()
        s = self._sym.solver
        s.set_phase(33)
        one = B.ndim == 1
        X = s._call_pardiso(self._U, np.asfortranarray(B[:, None] if one else B))
        return X[:, 0] if one else X


class _QdldlFactor(Factor):
    name = "qdldl"

    def __init__(self, A: sp.csr_matrix, key):
        import qdldl
        U = sp.triu(A, format="csc")
        U.sort_indices()
        holder = _cache_get(key) if key is not None else None
        if holder is None:
            holder = _QdldlHolder(qdldl.Solver(U, upper=True))
            if key is not None:
                _cache_put(key, holder)
        else:
            holder.solver.update(U, upper=True)
        holder.owner = self
        self._holder = holder
        self._U = U

    def solve(self, B):
        h = self._holder
        if h.owner is not self:  # another matrix of the same pattern was factored since
            h.solver.update(self._U, upper=True)
            h.owner = self
        return self._columns(B, h.solver.solve)


class _QdldlHolder:
    __slots__ = ("solver", "owner")

    def __init__(self, solver):
        self.solver = solver
        self.owner = None


class _CholespyFactor(Factor):
    name = "cholespy"

    def __init__(self, A: sp.csr_matrix, key):
        import cholespy
        self._n = A.shape[0]
        self._s = cholespy.CholeskySolverD(
            self._n, A.indptr.astype(np.int32), A.indices.astype(np.int32),
            np.ascontiguousarray(A.data), cholespy.MatrixType.CSR)

    def solve(self, B):
        B = np.ascontiguousarray(B, dtype=np.float64)
        X = np.zeros_like(B)
        self._s.solve(B, X)
        return X


class _CholmodFactor(Factor):
    name = "cholmod"

    def __init__(self, A: sp.csr_matrix, key):
        from sksparse.cholmod import analyze
        Ac = A.tocsc()
        sym = _cache_get(key) if key is not None else None
        if sym is None:
            sym = analyze(Ac)
            if key is not None:
                _cache_put(key, sym)
        self._f = sym.cholesky(Ac)

    def solve(self, B):
        return np.asarray(self._f(np.asarray(B, dtype=np.float64)))


_BACKENDS = {"scipy": _ScipyFactor, "pypardiso": _PardisoFactor, "qdldl": _QdldlFactor,
             "cholespy": _CholespyFactor, "cholmod": _CholmodFactor}


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
    _LAST_USED["solver"] = name
    _LAST_USED["n"] = int(A.shape[0])
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
