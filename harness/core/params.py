"""A declared parameter: name, default, type, bounds or choices, and a one-line doc.

Shared by task declarations (parameters every method of a task takes) and method
declarations; validation messages name the parameter and what was expected.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Callable

import numpy as np


@dataclass(frozen=True)
class Param:
    """A declared method parameter.

    ``kind`` is one of ``int``, ``float``, ``bool``, ``str``; ``low``/``high`` are inclusive
    bounds for numbers, ``choices`` the allowed values of a string. ``default=None`` with
    ``optional=True`` means "not given". ``alt``: another accepted form of a value that is not
    of ``kind`` (a config gives it as a mapping, or as a list inside the sweep's list: a list of
    values is a sweep), as ``alt(value) -> (normalised JSON-ready value, None)`` or
    ``(None, why not)``. ``id_as``: the
    name a case id records the parameter under (the one it had when earlier runs were recorded,
    so their cases keep their ids); ``id_omit_default``: a parameter added after runs were
    recorded is left out of the case id at its default, for the same reason.
    """

    name: str
    default: Any
    kind: str = ""
    low: float | None = None
    high: float | None = None
    choices: tuple | None = None
    doc: str = ""
    optional: bool = False
    alt: Callable[[Any], tuple] | None = None
    id_as: str | None = None
    id_omit_default: bool = False

    def __post_init__(self):
        if not self.kind:
            d = self.default
            kind = ("bool" if isinstance(d, bool) else "int" if isinstance(d, int)
                    else "float" if isinstance(d, float) else "str" if isinstance(d, str) else "")
            if not kind:
                raise TypeError(f"parameter {self.name!r}: give kind= for default {d!r}")
            object.__setattr__(self, "kind", kind)
        if self.choices is not None:
            object.__setattr__(self, "choices", tuple(self.choices))

    def problem(self, value) -> str | None:
        """Return why ``value`` is not acceptable, or None."""
        if value is None and self.optional:
            return None
        k = self.kind
        if k == "bool":
            ok = isinstance(value, (bool, np.bool_))
        elif k == "int":
            ok = isinstance(value, (int, np.integer)) and not isinstance(value, bool)
        elif k == "float":
            ok = isinstance(value, (int, float, np.integer, np.floating)) and not isinstance(value, bool)
        else:
            ok = isinstance(value, str)
        if not ok and self.alt is not None:
            return self.alt(value)[1]
        if not ok:
            return f"expected {k}, got {type(value).__name__} {value!r}"
        if k in ("int", "float"):
            if not math.isfinite(float(value)):
                return f"expected a finite number, got {value!r}"
            if self.low is not None and value < self.low:
                return f"must be >= {self.low}, got {value!r}"
            if self.high is not None and value > self.high:
                return f"must be <= {self.high}, got {value!r}"
        if self.choices is not None and value not in self.choices:
            return f"must be one of {list(self.choices)}, got {value!r}"
        return None

    def normalised(self, value):
        """``value`` in its ``alt`` form's normal form where it is one, else unchanged."""
        if self.alt is None or value is None:
            return value
        v, why = self.alt(value)
        return value if why else v

    def describe(self) -> str:
        s = f"{self.name}={self.default!r}"
        if self.choices:
            s += f" {{{'|'.join(map(str, self.choices))}}}"
        elif self.low is not None or self.high is not None:
            lo = "-inf" if self.low is None else self.low
            hi = "inf" if self.high is None else self.high
            s += f" [{lo}, {hi}]"
        return s


def id_spec(params: dict) -> dict:
    """How case ids record a method's parameters (``{name: Param}``): ``{name: {"as": id name,
    "omit_default": default}}`` for those with an ``id_as`` or ``id_omit_default``, JSON-ready (a
    run records it in run.json, so reading a run folder needs no method)."""
    out = {}
    for name, p in params.items():
        if p.id_as or p.id_omit_default:
            out[name] = {**({"as": p.id_as} if p.id_as else {}),
                         **({"omit_default": p.default} if p.id_omit_default else {})}
    return out


def id_form(values: dict, spec: dict | None) -> dict:
    """``values`` (a case's parameters) as its case id records them under ``spec`` (`id_spec`):
    a parameter under its ``as`` name, one with ``omit_default`` left out at that value."""
    if not spec:
        return values
    out = {}
    for k, v in values.items():
        s = spec.get(k) or {}
        if "omit_default" in s and v == s["omit_default"]:
            continue
        out[s.get("as") or k] = v
    return out
