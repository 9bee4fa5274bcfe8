"""Methods of mesh-shootout: one interface, one adapter module per backend.

``methods.get(name)`` returns a callable `Method`; ``methods.available(task)`` lists the names
that can run here; ``register`` adds a method (built-ins, plugins and entry points alike).
Result types are declared by the tasks (`harness.tasks`) and re-exported here.
"""
from harness.errors import MethodFailed
from harness.tasks.curvature import CurvatureResult
from harness.tasks.geodesics import GeodesicResult
from harness.tasks.laplacian import LaplacianResult
from harness.tasks.simplification import SimplificationResult
from harness.tasks.smoothing import SmoothingResult
from harness.tasks.spectrum import SpectrumResult

from .base import Method, Param, check_arrays
from .registry import all_methods, available, get, load_plugins, register

__all__ = ["CurvatureResult", "GeodesicResult", "LaplacianResult", "SmoothingResult", "SpectrumResult", "SimplificationResult", "Method", "Param", "MethodFailed",
           "check_arrays", "register", "get", "available", "all_methods", "load_plugins"]
