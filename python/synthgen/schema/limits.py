"""Resource limits checked while validating, before anything is built: what a file may
expand to, how many objects a frame may hold, how much memory a frame may need.

Every limit is named in its error message, and every check runs in well under a second
whatever the input (a YAML "billion laughs" of nested aliases is measured, not expanded).
"""
from __future__ import annotations

import os
from typing import Any, Dict, Optional

__all__ = ["MAX_YAML_DEPTH", "MAX_YAML_VALUES", "MAX_OBJECTS_PER_FRAME", "BYTES_PER_PIXEL", "expanded_size", "available_memory",
           "frame_memory", "fmt_bytes"]

#: Values (mappings, lists, scalars) a YAML document may expand to through its aliases.
MAX_YAML_VALUES = 200_000
#: Nesting depth of a YAML document (mappings and lists inside each other); real files
#: nest a handful of levels, and PyYAML's composer recurses once per level.
MAX_YAML_DEPTH = 64
#: Object instances a scenario frame may hold (the sum of the entries' largest counts).
MAX_OBJECTS_PER_FRAME = 10_000
#: Peak memory of a frame per image pixel (bytes): the render buffers (colour, alpha, depth,
#: distance, normal, albedo, ids: 56 B), the label render of an amodal mask on a canvas
#: padded by half the image on every side (4 x 56 B), and the image conversions of the
#: writers (~100 B).
BYTES_PER_PIXEL = 400


def expanded_size(tree: Any, limit: int = MAX_YAML_VALUES) -> int:
    """The number of values of a loaded YAML tree counting every use of a shared (aliased)
    node, computed in time linear in the *distinct* nodes; stops counting past ``limit``."""
    memo: Dict[int, int] = {}

    def size(x: Any) -> int:
        if isinstance(x, (dict, list, tuple)):
            key = id(x)
            if key in memo:
                return memo[key]
            memo[key] = limit + 1  # a cycle counts as too large
            n = 1
            for v in (x.values() if isinstance(x, dict) else x):
                n += size(v)
                if n > limit:
                    break
            memo[key] = min(n, limit + 1)
            return memo[key]
        return 1

    return size(tree)


def available_memory() -> Optional[int]:
    """Bytes of memory available to new allocations (Linux MemAvailable), or None."""
    try:
        with open("/proc/meminfo", encoding="ascii") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    try:
        return int(os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE"))
    except (ValueError, OSError, AttributeError):
        return None


def frame_memory(width: int, height: int) -> int:
    """Estimated peak bytes of rendering and writing one frame of ``width`` x ``height``."""
    return int(width) * int(height) * BYTES_PER_PIXEL


def fmt_bytes(n: float) -> str:
    for unit, scale in (("GiB", 1 << 30), ("MiB", 1 << 20)):
        if n >= scale:
            return f"{n / scale:.1f} {unit}"
    return f"{n:.0f} bytes"
