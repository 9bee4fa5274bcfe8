"""Probes of a case's own process and of the machine, read around the timed calls
(`harness.runner.run_case`): the process's peak resident memory (``getrusage``) and its
``/proc/self/status`` fields, returning freed heap memory to the OS (glibc ``malloc_trim``),
resetting the kernel's resident high-water mark, the CPU time all processes of the machine
have used (``/proc/stat``) and each thread's CPU clock ticks (``/proc/self/task``), and from
those the number of threads that were busy in a window. Where the OS has no such file, a
probe returns None (or does nothing)."""
from __future__ import annotations

import os
import resource


def peak_rss_mb() -> float:
    """Peak resident set size of this process so far, from the OS (getrusage), in MiB."""
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def _status_kib(field: str) -> int | None:
    try:
        with open("/proc/self/status") as fh:
            for line in fh:
                if line.startswith(field + ":"):
                    return int(line.split()[1])
    except (OSError, ValueError, IndexError):
        return None
    return None


def _trim_heap() -> None:
    """Return freed heap memory to the OS (glibc ``malloc_trim``; nothing elsewhere): pages the
    allocator kept from earlier calls neither hide a call's allocations from the memory
    measurement nor spare it the cost of touching fresh memory."""
    try:
        import ctypes
        ctypes.CDLL("libc.so.6").malloc_trim(0)
    except (OSError, AttributeError):
        pass


def _reset_peak() -> bool:
    """Reset the kernel's resident high-water mark (VmHWM) of this process (Linux); after
    `_trim_heap`, so that the peak counts the call's own allocations."""
    try:
        with open("/proc/self/clear_refs", "w") as fh:
            fh.write("5")
        return True
    except OSError:
        return False


def _machine_busy_s() -> float | None:
    """CPU seconds all processes of the machine have used (``/proc/stat``: user, nice, system,
    irq, softirq and, on a virtual machine, steal), None where unknown."""
    try:
        with open("/proc/stat") as fh:
            f = fh.readline().split()
        ticks = os.sysconf("SC_CLK_TCK")
        return sum(int(x) for x in f[1:4] + f[6:9]) / ticks
    except (OSError, ValueError, IndexError, AttributeError):
        return None


def _thread_ticks() -> dict[int, int] | None:
    """CPU clock ticks (user + system) of each thread of this process (``/proc/self/task``), None
    where unknown."""
    out = {}
    try:
        for d in os.scandir("/proc/self/task"):
            try:
                with open(f"/proc/self/task/{d.name}/stat") as fh:
                    f = fh.read().rsplit(")", 1)[1].split()
                out[int(d.name)] = int(f[11]) + int(f[12])      # utime, stime: fields 14 and 15
            except (OSError, ValueError, IndexError):
                continue                                        # a thread that ended meanwhile
    except OSError:
        return None
    return out


def threads_busy(before: dict | None, after: dict | None, wall_s: float) -> int | None:
    """How many threads ran for at least 5% of a window of ``wall_s`` seconds and 2 clock ticks
    (10 ms each), from `_thread_ticks` before and after it (a thread that ended within the
    window is not seen: pools persist, so theirs are); None without both or under 0.05 s."""
    if before is None or after is None or wall_s < 0.05:
        return None
    floor = max(2, 0.05 * wall_s * os.sysconf("SC_CLK_TCK"))
    return sum(1 for tid, t in after.items() if t - before.get(tid, 0) >= floor)
