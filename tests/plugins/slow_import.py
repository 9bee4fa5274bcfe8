"""A plugin whose import sleeps ``SHOOTOUT_TEST_IMPORT_S`` seconds when that variable is set (a
slow start of a case's fresh interpreter, without slowing the process that first imports it)."""
import os
import time

from methods import SmoothingResult, register

time.sleep(float(os.environ.get("SHOOTOUT_TEST_IMPORT_S") or 0))


@register("slow_import.identity", task="smoothing", library="slow_import")
def identity(V, F):
    """The input, unchanged."""
    return SmoothingResult(V=V.copy())
