"""The neutral core shared by the judge (``harness``) and the contestants (``methods``).

``geometry``: vectorized mesh primitives (edges, areas, normals, lengths, cotangents,
boundaries, compaction, surface sampling). ``solvers``: the sparse SPD direct-solver layer.
Nothing here imports from the rest of ``harness`` or from ``methods``.
"""
