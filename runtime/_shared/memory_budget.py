"""Memory budgets: refuse work whose size the caller chose (frames, times, strokes, items) when it
cannot fit, before any of it is allocated.

Without a check, an absurd size fails late and badly: ``cgaskin skin --frames 100000000`` ran for
minutes and ended in numpy's bare ``MemoryError``; an allocation the kernel overcommits fails later
still, in the operating system's out-of-memory killer. Where cgaskin allocates in proportion to a
size the user gave, it first estimates the bytes and calls ``require_memory``, which raises
``MemoryLimitError`` naming the size, the estimate and what there is.

What there is: the memory the kernel says it can give without swapping (``MemAvailable``), less where
the process's cgroup (a container) or its address-space limit (``ulimit -v``) leaves less; unknown
(no check) where the system says none of these (then numpy's own errors stay).
"""
from __future__ import annotations

import os
from pathlib import Path

from ..errors import MemoryLimitError

try:
    import resource
except ImportError:                 # Windows
    resource = None

__all__ = ["available_memory", "require_memory", "format_bytes"]

#: where Linux says what it can give, and what a cgroup (v2, then v1) allows and uses
_MEMINFO = Path("/proc/meminfo")
_CGROUP_LIMITS = (("/sys/fs/cgroup/memory.max", "/sys/fs/cgroup/memory.current"),
                  ("/sys/fs/cgroup/memory/memory.limit_in_bytes", "/sys/fs/cgroup/memory/memory.usage_in_bytes"))


def _meminfo_available() -> int | None:
    try:
        for line in _MEMINFO.read_text().splitlines():
            if line.startswith("MemAvailable:"):
                return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    try:                            # other Unixes: free pages
        return os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    except (AttributeError, ValueError, OSError):
        return None


def _cgroup_available() -> int | None:
    for limit_path, usage_path in _CGROUP_LIMITS:
        try:
            limit = Path(limit_path).read_text().strip()
            usage = int(Path(usage_path).read_text().strip())
        except (OSError, ValueError):
            continue
        if limit == "max" or not limit.isdigit() or int(limit) >= 1 << 60:   # (v1 writes "no limit" so)
            return None
        return max(int(limit) - usage, 0)
    return None


def _address_space_available() -> int | None:
    if resource is None:
        return None
    limit = resource.getrlimit(resource.RLIMIT_AS)[0]
    if limit == resource.RLIM_INFINITY:
        return None
    try:                            # the process's virtual size now (pages), Linux
        used = int(Path("/proc/self/statm").read_text().split()[0]) * os.sysconf("SC_PAGE_SIZE")
    except (OSError, ValueError, IndexError):
        used = 0
    return max(limit - used, 0)


def available_memory() -> int | None:
    """Bytes this process can still allocate and use: the least of what the system can give without
    swapping, what its cgroup allows beyond its use, and what its address-space limit leaves; None
    where none of them is known."""
    known = [x for x in (_meminfo_available(), _cgroup_available(), _address_space_available()) if x is not None]
    return min(known) if known else None


def format_bytes(count: float) -> str:
    """``count`` bytes for a message: "512 B", "3.2 MiB", "2.4 TiB"."""
    for unit in ("B", "KiB", "MiB", "GiB", "TiB", "PiB"):
        if count < 1024 or unit == "PiB":
            return f"{count:.0f} {unit}" if unit == "B" else f"{count:.1f} {unit}"
        count /= 1024
    raise AssertionError("unreachable")


def require_memory(estimate: float, what: str, advice: str, limit: int | None = None) -> None:
    """Raise ``MemoryLimitError`` when ``estimate`` bytes exceed the memory available
    (``available_memory``) or ``limit``, a budget the caller gave (``max_memory``, ``--max-memory``).

    what : the size as the caller gave it ("--frames 100000000", "times (1e+12 values)")
    advice : what to do instead ("bake fewer frames")
    """
    if limit is not None and estimate > limit:
        raise MemoryLimitError(f"{what} would take about {format_bytes(estimate)} of memory, more than the limit of "
                               f"{format_bytes(limit)} given: {advice}")
    available = available_memory()
    if available is not None and estimate > available:
        raise MemoryLimitError(f"{what} would take about {format_bytes(estimate)} of memory, more than the "
                               f"{format_bytes(available)} available: {advice}")
