"""A run's progress on stderr: a tqdm bar on a terminal, else (CI logs, ``| tee``) one line
every few seconds with the cases done, the time spent and the time left at the session's pace."""
from __future__ import annotations

import sys
import time


class _Lines:
    """Progress for a non-terminal stderr (CI logs, ``| tee``): one line every ``every`` seconds."""

    def __init__(self, total: int, initial: int, every: float = 5.0):
        self.total, self.n, self.every, self.initial = total, initial, every, initial
        self.t0 = self.last = time.perf_counter()
        self.what = ""
        if initial:
            print(f"shootout: resuming, {initial} of {total} case(s) already done", file=sys.stderr, flush=True)

    def set_postfix_str(self, what, refresh=False):
        self.what = what

    def update(self, k=1):
        self.n += k
        now = time.perf_counter()
        if now - self.last >= self.every or self.n == self.total:
            self.last = now
            done, left = self.n - self.initial, self.total - self.n
            eta = (f", about {_duration((now - self.t0) / done * left)} left at this session's pace"
                   if done > 0 and left > 0 else "")
            print(f"shootout: {self.n}/{self.total} cases, {now - self.t0:.0f} s{eta}"
                  + (f" (last: {self.what})" if self.what else ""), file=sys.stderr, flush=True)

    def close(self):
        pass


def _duration(s: float) -> str:
    """Seconds as a rounded duration: ``45 s``, ``12 min``, ``3.4 h``."""
    return f"{s:.0f} s" if s < 90 else f"{s / 60:.0f} min" if s < 5400 else f"{s / 3600:.1f} h"


def _progress(total: int, initial: int):
    if sys.stderr.isatty():
        from tqdm import tqdm
        return tqdm(total=total, initial=initial, unit="case", dynamic_ncols=True)
    return _Lines(total, initial)
