"""The neutral core shared by the judge (``harness``) and the contestants (``methods``).

``geometry``: vectorized mesh primitives (edges, areas, normals, lengths, cotangents,
boundaries, compaction, surface sampling). ``solvers``: the sparse SPD direct-solver layer (the
choice of backend, factorization, backward Euler); ``solver_backends``: one factor class per
backend library. ``params``: ``Param``, a method's declared parameter.
Nothing here imports from the rest of ``harness`` or from ``methods``.
"""
