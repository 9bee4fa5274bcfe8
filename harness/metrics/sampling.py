"""Area-uniform random points on a triangle mesh."""
import numpy as np


def sample_surface(V: np.ndarray, F: np.ndarray, n: int, seed: int = 0) -> np.ndarray:
    """``n`` points (n, 3), faces drawn with probability proportional to area, points uniform
    in the face (barycentric (1 - sqrt(r1), sqrt(r1)(1 - r2), sqrt(r1) r2))."""
    rng = np.random.default_rng(seed)
    dbl = np.linalg.norm(np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]]), axis=1)
    if n <= 0 or dbl.sum() <= 0:
        return np.zeros((0, 3))
    f = rng.choice(len(F), size=n, p=dbl / dbl.sum())
    r1 = np.sqrt(rng.random(n))
    r2 = rng.random(n)
    a, b, c = 1 - r1, r1 * (1 - r2), r1 * r2
    return a[:, None] * V[F[f, 0]] + b[:, None] * V[F[f, 1]] + c[:, None] * V[F[f, 2]]
