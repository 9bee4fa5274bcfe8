"""libigl + scipy Laplacian spectrum (task ``spectrum``): the plain pipeline a user would write."""
from __future__ import annotations

import numpy as np

from methods import SpectrumResult, register
from methods.libigl import reject_zero_area_or_unreferenced


@register("libigl.eigsh", task="spectrum", library="libigl", requires=("igl",),
          precheck=reject_zero_area_or_unreferenced,
          cite="the plain pipeline: igl.cotmatrix + igl.massmatrix(VORONOI) + scipy eigsh(sigma)")
def libigl_eigsh(V, F, *, k=20):
    """What a user would write: libigl's cotangent matrix and Voronoi mass, scipy's ``eigsh`` in
    shift-invert mode (``sigma`` as `scratch.spectrum`'s) with scipy's own sparse LU inside.
    Zero-area faces, and vertices no face uses, are a ValueError naming them (libigl's
    cotangents are undefined there; its matrices are sized by the faces)."""
    import igl
    from scipy.sparse.linalg import eigsh

    from methods.scratch.spectrum import inversion_shift
    W = igl.cotmatrix(V, F)
    M = igl.massmatrix(V, F, igl.MASSMATRIX_TYPE_VORONOI)
    k = int(min(k, len(V) - 1))
    lam, X = eigsh(-W, k=k, M=M, sigma=inversion_shift(W, M), which="LM", v0=np.random.default_rng(0).standard_normal(len(V)))
    order = np.argsort(lam)
    return SpectrumResult(values=lam[order], vectors=X[:, order], W=W, M=M)
