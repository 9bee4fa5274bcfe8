"""Task ``laplacian``: a discrete Laplace operator ``W`` (and mass ``M``) of the input mesh,
measured for the properties of Wardetzky, Mathur, Kaelberer & Grinspun 2007 (SGP), "Discrete
Laplace operators: no free lunch" (definitions in `harness.metrics.laplacian_properties`)."""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import scipy.sparse as sp

from ..errors import MethodFailed
from ..metrics.laplacian_properties import laplacian_properties
from .base import Metric, Task, assembled_sparse


@dataclass
class LaplacianResult:
    """Laplacian in libigl's sign convention.

    ``W``: scipy sparse (n, n); off-diagonal entries are the edge weights (positive where POS
    holds), each row sums to zero. ``M``: diagonal mass matrix (n, n) or None. The pointwise
    operator is ``M^-1 W``.
    """

    W: Any
    M: Any = None


def _check(result: LaplacianResult, V, F):
    n = V.shape[0]
    for what in ("W", "M"):
        A = getattr(result, what)
        if A is None and what == "M":
            continue
        A = assembled_sparse(what, A, n)
        if not np.isfinite(A.data).all():      # NaN weights would pass as NaN metrics
            k = int((~np.isfinite(A.data)).sum())
            raise MethodFailed(f"returned {what} with {k} non-finite (NaN or inf) entries")
        setattr(result, what, A)
    M = result.M
    if M is not None:
        if not M.has_canonical_format:                          # duplicates summed, as M's value has them
            M = M.copy()
            M.sum_duplicates()
        d = M.diagonal()
        rows = np.repeat(np.arange(n), np.diff(M.indptr))      # M is CSR here: a stored entry off the diagonal
        if (M.data[M.indices != rows] != 0).any():             # and not 0 (one pass, no matrix built)
            raise MethodFailed("returned a non-diagonal M; the task takes a lumped (diagonal) mass matrix")
        if (d < 0).any():
            raise MethodFailed(f"returned M with {int((d < 0).sum())} negative diagonal entries (areas)")
    return result


def _measure(inp, result, params) -> dict:
    return laplacian_properties(result.W, result.M, inp.V, inp.F, mesh=inp.cache.setdefault("laplacian_mesh", {}))


def _warm():
    """Load the compiled PSD certificate once (in the driver, before forking case processes)."""
    from ..metrics._psd_kernel import warm
    warm()


def _rows_sum_to_zero(method, V, F):
    res = method(V, F)
    W = res.W
    n = len(V)
    scale = abs(W).max()
    assert scale > 0, "W is all zero"
    worst = np.abs(np.asarray(W.sum(axis=1)).ravel()).max()
    assert worst <= 1e-10 * scale * max(1, n ** 0.5), f"a row of W sums to {worst:g} (max |W| {scale:g})"


def _sign_convention(method, V, F):
    """libigl's sign: W negative semi-definite, so its diagonal is <= 0 and not all zero (a
    flipped sign passes the other checks and reads as 'not PSD' in every row)."""
    d = method(V, F).W.diagonal()
    assert (d <= 0).all() and d.sum() < 0, (f"W's diagonal has {int((d > 0).sum())} positive entries of {len(d)}: "
                                            "the task takes libigl's sign (cotmatrix: negative diagonal)")


def _mass_matrix(method, V, F):
    M = method(V, F).M
    if M is not None:
        assert abs(M - sp.diags(M.diagonal())).max() == 0 if M.nnz else True, "M is not diagonal"
        assert (M.diagonal() > 0).all(), "M has a non-positive diagonal entry on a mesh without degenerate faces"


_REL = 0.01
TASK = Task(
    name="laplacian", title="Laplacians", result_type=LaplacianResult,
    intro="Discrete Laplacians W (libigl's sign convention) measured for Wardetzky et al.'s properties "
          "on each input mesh.",
    metrics=(
        Metric("sym_error", "lower", "max |W - W^T| / max |W|", rel=_REL, abs=1e-10),
        Metric("loc_violations", "count", "non-zeros between vertices that share no edge", kind="int"),
        Metric("lin_error", "lower", "max |W X| / (max|W| diag) at interior vertices (planar meshes only)",
               rel=_REL, abs=1e-9),
        Metric("neg_weights", "lower", "fraction of negative off-diagonal weights", rel=_REL, abs=1e-6),
        Metric("min_eig", "higher", "symmetric W: smallest eigenvalue of -(W + W^T)/2 over the largest magnitude; "
               "non-symmetric W: that of the symmetric S in W = D^-1 S, or 0 when Gershgorin certifies it "
               "(then it is not the symmetric part's)", rel=_REL, abs=1e-10),
        Metric("psd", "true", "symmetric W: -(W + W^T)/2 positive semi-definite (min_eig >= -1e-10); non-symmetric "
               "W: every eigenvalue of -W has a non-negative real part (the symmetric part may be indefinite)",
               kind="bool"),
        Metric("nnz", "info", "stored non-zero entries of W", kind="int"),
        Metric("SYM", "true", "sym_error <= 1e-10", kind="bool"),
        Metric("LOC", "true", "loc_violations == 0", kind="bool"),
        Metric("LIN", "true", "lin_error <= 1e-9 (planar meshes only)", kind="bool"),
        Metric("POS", "true", "no negative off-diagonal weight", kind="bool"),
        Metric("operator_symmetric", "true", "the pointwise operator M^-1 W is a symmetric matrix", kind="bool"),
    ),
    measure=_measure, check_result=_check, sections=("property_matrix",), order=10, preload=_warm,
    input_facts=("laplacian_mesh",),
    checks=(("rows_sum_to_zero", _rows_sum_to_zero), ("sign_convention", _sign_convention),
            ("mass_matrix", _mass_matrix)))
