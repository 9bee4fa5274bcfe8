"""Per-vertex error against the clean mesh (same vertex count and order)."""
import numpy as np


def vertex_error(V: np.ndarray, V_clean: np.ndarray) -> dict:
    """``ev_mean`` = mean_i |v_i - c_i|, ``ev_rms`` = sqrt(mean_i |v_i - c_i|^2) (input units)."""
    d = np.linalg.norm(V - V_clean, axis=1)
    return {"ev_mean": float(d.mean()), "ev_rms": float(np.sqrt((d ** 2).mean()))}
