"""Methods of mesh-shootout: one interface, one adapter module per backend.

``methods.get(name)`` returns a callable `Method`; ``methods.available(task)`` lists the names
that can run here; ``register`` adds a method (built-ins, plugins and entry points alike).
"""
from .base import (LaplacianResult, Method, Param, SimplificationResult, SmoothingResult,
                   TASKS, check_arrays)
from .registry import all_methods, available, get, load_plugins, register

__all__ = ["LaplacianResult", "SmoothingResult", "SimplificationResult", "Method", "Param",
           "TASKS", "check_arrays", "register", "get", "available", "all_methods", "load_plugins"]
