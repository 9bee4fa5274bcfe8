"""Band-by-band shift-invert for many eigenpairs (Vallet & Levy 2008, "Spectral geometry
processing with manifold harmonics", Sec. 4), with an inertia check of completeness.

The k smallest eigenpairs of ``A x = lambda M x`` (``A = -W`` symmetric positive semi-definite,
``M`` symmetric positive definite) are computed in bands of ``band`` pairs: for a shift
``sigma`` the matrix ``A - sigma M`` (indefinite) is factored as ``P (A - sigma M) P^T = L D L^T``
(QDLDL, no pivoting) and ARPACK returns the ``band`` eigenvalues nearest ``sigma``, i.e. every
eigenvalue in the window ``(sigma - r, sigma + r)``. Each window starts below the top of the
part already collected; the next shift is placed from the band's own eigenvalue density (for a
surface, ``N(lambda)`` grows linearly: Weyl's law). Per band the ARPACK work is
``O(n band^2)`` instead of ``O(n k^2)`` for one k-pair run.

Completeness is certified, not assumed: by Sylvester's law of inertia the number of negative
entries of ``D`` is the number of eigenvalues below ``sigma``, and after each band the pairs
collected below ``sigma`` must be exactly that many; at the end, one more factorization at the
k-th value less ``1e-6`` of it certifies the pairs the last band found above its own shift (a
multiplet cut at k is whole below that point, as the spectrum task's ``k_missed`` counts it).
A band whose window leaves a gap, whose count disagrees, or that finds nothing new (its window
above the part collected is one cluster) is redone with a closer shift; after ``retries`` failures `BandFailure` is
raised and the caller falls back to one ARPACK run. At the top of each window the outermost
cluster (eigenvalues within ``1e-6`` relative of the largest found) is left to the next band,
so a multiplet is never split between bands. ARPACK converges slowly when a window's edge
falls inside a cluster of nearly equal eigenvalues (the sphere's ``2 l + 1``-fold multiplets):
on such spectra a band can cost as much as one run for all k pairs; on generic meshes (no
multiplets) the bands are about twice as fast at k = 200 (`benchmarks/bench_spectrum.py`).
"""
from __future__ import annotations

import numpy as np
import scipy.sparse as sp


class BandFailure(RuntimeError):
    """The bands could not be certified complete (gap or inertia mismatch)."""


def _factor(S: sp.csc_matrix):
    """(solve, number of negative pivots) of the symmetric indefinite ``S`` (QDLDL)."""
    import qdldl
    f = qdldl.Solver(S)
    _, D, _ = f.factors()
    if not np.isfinite(D).all() or (D == 0).any():
        raise BandFailure("zero or non-finite pivot")
    return f.solve, int(np.count_nonzero(D < 0))


def band_eigenpairs(A, M, k: int, sigma0: float, band: int = 50, seed: int = 0, retries: int = 4,
                    zeros: int | None = None):
    """The ``k`` smallest eigenpairs ``(lam ascending (k,), X (n, k))`` of ``A x = lam M x``
    (module docstring); ``sigma0`` is a shift below the smallest eigenvalue (``A - sigma0 M``
    positive definite). Eigenvectors are M-orthonormal within a band and, as eigenvectors of
    distinct eigenvalues, M-orthogonal across bands (to the accuracy of the solve). ``zeros``:
    the dimension of A's kernel where known (a Laplacian's: the mesh's connected components);
    when ``k <= zeros`` every pair is a zero mode, whose inertia is rounding, and the final check
    is skipped. Unknown: the pairs are taken as zero modes when the k-th eigenvalue is at most
    ``1e-8 max |A_ii / M_ii|`` (on slivers, whose scale reaches 1e12, that cut can lie above
    real eigenvalues: give ``zeros``)."""
    from scipy.sparse.linalg import LinearOperator, eigsh
    A, M = sp.csc_matrix(A), sp.csc_matrix(M)
    n = A.shape[0]
    m = int(min(band, n - 1, k + max(8, k // 20)))     # no wider than one run for a small k
    rng = np.random.default_rng(seed)
    lams, vecs = [], []
    collected = 0
    top = -np.inf                       # every eigenvalue below `top` has been collected
    sigma, step = float(sigma0), None
    failures = 0
    while collected < k:
        try:
            solve, below = _factor((A - sigma * M).tocsc())
            op = LinearOperator((n, n), matvec=solve, dtype=np.float64)
            lam, X = eigsh(A, k=m, M=M, sigma=sigma, which="LM", OPinv=op, v0=rng.standard_normal(n))
            order = np.argsort(lam)
            lam, X = lam[order], X[:, order]
            r = float(np.abs(lam - sigma).max())
            if np.isfinite(top) and sigma - r >= top:
                raise BandFailure(f"window ({sigma - r:.6g}, {sigma + r:.6g}) leaves a gap above {top:.6g}")
            hi = lam[-1]
            inner = lam < hi - 1e-6 * max(abs(hi), 1e-300)
            if not inner.any():
                raise BandFailure("a band holds one cluster only")
            new = inner & (lam > top)
            if not new.any():           # the window above `top` is one cluster, left to the next band: no progress
                raise BandFailure(f"the band at {sigma:.6g} found nothing new above {top:.6g} (a cluster as wide "
                                  "as the band)")
            n_below = collected + int(np.count_nonzero(lam[new] < sigma))   # all collected lie below top < sigma
            if n_below != below:
                raise BandFailure(f"{n_below} eigenvalues collected below {sigma:.6g}, inertia says {below}")
        except BandFailure:
            failures += 1
            if failures > retries or step is None:
                raise
            step *= 0.5                 # a closer shift: the window reaches further down
            sigma = top + step
            continue
        lams.append(lam[new])
        vecs.append(X[:, new])
        collected += int(new.sum())
        top = 0.5 * (lam[inner].max() + lam[~inner].min())
        density = len(lam) / max(lam[-1] - lam[0], 1e-300)      # eigenvalues per unit of lambda
        step = 0.3 * m / density        # window half-width is ~0.5 m / density: 20% overlap
        sigma = top + step
    lam = np.concatenate(lams)
    X = np.concatenate(vecs, axis=1)
    order = np.argsort(lam)[:k]
    lam, X = lam[order], X[:, order]
    s = float(lam[-1]) - 1e-6 * max(abs(float(lam[-1])), 1e-300)     # the last band's pairs above its shift too
    if zeros is not None:
        all_zero = k <= zeros
    else:
        d = M.diagonal()
        all_zero = not lam[-1] > 1e-8 * float(np.max(np.abs(np.divide(A.diagonal(), d, out=np.zeros_like(d),
                                                                         where=d > 0)), initial=0.0))
    if s > sigma0 and not all_zero:        # k zero eigenvalues (k components or more): their inertia is rounding
        _, below = _factor((A - s * M).tocsc())
        if below != int(np.count_nonzero(lam < s)):
            raise BandFailure(f"{int(np.count_nonzero(lam < s))} eigenvalues returned below {s:.6g}, inertia says {below}")
    return lam, X
