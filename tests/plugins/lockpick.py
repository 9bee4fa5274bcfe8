"""A method that tries to release its run folder's lock (tests/test_hardening_driver.py): it
unlocks every inherited descriptor of a ``.shootout.lock``, then fails if the folder's lock can
be taken, i.e. if the driver no longer holds it."""
import fcntl
import os

from methods import SmoothingResult, register


@register("lockpick.unlock", task="smoothing", library="lockpick")
def unlock(V, F):
    found = None
    for fd in os.listdir("/proc/self/fd"):
        try:
            target = os.readlink(f"/proc/self/fd/{fd}")
        except OSError:
            continue
        if target.endswith(".shootout.lock"):
            found = target
            fcntl.flock(int(fd), fcntl.LOCK_UN)
    lock = os.environ.get("LOCKPICK_LOCK") or found
    if lock:
        fd = os.open(lock, os.O_RDWR)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            return SmoothingResult(V=V)          # still the driver's
        finally:
            os.close(fd)
        raise RuntimeError("the run folder's lock was released by a case")
    return SmoothingResult(V=V)
