"""The direct-solver backends of `harness.core.solvers`: one `Factor` subclass per library
(SuperLU through scipy, PARDISO through pypardiso, QDLDL, cholespy, CHOLMOD through
scikit-sparse), each given a canonical CSR SPD matrix and a pattern key (None: no reuse), and
`_BACKENDS`, name -> class. The symbolic analyses they reuse live in `_SYMBOLIC`, a
least-recently-used cache of at most `_CACHE_SIZE` patterns; an evicted entry's ``free`` is
called. `_new_pardiso` makes PARDISO handles without locating MKL again.
"""
from __future__ import annotations

import os
from collections import OrderedDict

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as sla

_SYMBOLIC: "OrderedDict[tuple, object]" = OrderedDict()
_CACHE_SIZE = 4
_PARDISO_TEMPLATE: list = []


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
