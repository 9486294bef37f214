"""The texture resolution estimate as a table (docs/texture_lod.md).

:meth:`synthgen._core.Scene.estimate_texture_resolution` gives, per image texture, the
coarsest mip level that keeps at least one texel per pixel in at least one axis for the
scene's camera. Textures that share a pyramid (one file under several uv transforms) need
the finest level any of them needs; the table has one row per pyramid and the memory of its
texels before (every level) and after (the needed level and coarser).
"""
from __future__ import annotations

import os
from typing import Any, Dict, List, Mapping

__all__ = ["pyramids", "texture_table", "memory_totals"]


def pyramids(estimate: Mapping[str, Any]) -> List[Dict[str, Any]]:
    """One record per distinct pyramid of ``estimate["textures"]``, in texture id order: its
    figures (from the first texture using it) and ``texture_ids`` of the textures using it."""
    rows: Dict[int, Dict[str, Any]] = {}
    for t in estimate["textures"]:
        r = rows.get(t["pyramid"])
        if r is None:
            r = rows[t["pyramid"]] = {k: v for k, v in t.items() if k not in ("texture_id", "texture_level")}
            r["texture_ids"] = []
        r["texture_ids"].append(int(t["texture_id"]))
    return list(rows.values())


def memory_totals(estimate: Mapping[str, Any]) -> Dict[str, float]:
    """Texel memory of every pyramid (each counted once) before and after, and their ratio."""
    p = pyramids(estimate)
    before = sum(int(r["bytes_full"]) for r in p)
    after = sum(int(r["bytes_needed"]) for r in p)
    return {"pyramids": len(p), "bytes_full": before, "bytes_needed": after,
            "ratio": (before / after) if after else float("nan")}


def _mib(n: int) -> str:
    return f"{n / 2**20:.2f}"


def _name(source: str, width: int = 34) -> str:
    s = source if source.startswith("memory:") else os.path.basename(source)
    return s if len(s) <= width else s[: width - 1] + "~"


def texture_table(estimate: Mapping[str, Any]) -> str:
    """The per-pyramid table and a totals line, as printed by ``synthgen texres``."""
    head = (f"{'texture':34} {'ids':>7} {'size':>11} {'lv':>3} {'seen':>5} {'min texels/px':>13} "
            f"{'level':>5} {'needed':>11} {'tiles':>9} {'MiB full':>9} {'MiB needed':>10}")
    lines = [head, "-" * len(head)]
    for r in pyramids(estimate):
        ids = ",".join(str(i) for i in r["texture_ids"])
        rho = f"{r['min_rho']:.2f}" if r["seen"] else "-"
        lines.append(f"{_name(r['source']):34} {ids:>7} {str(r['width']) + 'x' + str(r['height']):>11} "
                     f"{r['levels']:>3} {'yes' if r['seen'] else 'no':>5} {rho:>13} {r['needed_level']:>5} "
                     f"{str(r['needed_width']) + 'x' + str(r['needed_height']):>11} "
                     f"{str(r['needed_tiles']) + '/' + str(r['tiles']):>9} {_mib(r['bytes_full']):>9} "
                     f"{_mib(r['bytes_needed']):>10}")
    m = memory_totals(estimate)
    lines.append("-" * len(head))
    lines.append(f"{m['pyramids']} pyramids: {_mib(m['bytes_full'])} MiB at full resolution, "
                 f"{_mib(m['bytes_needed'])} MiB needed (ratio {m['ratio']:.2f}); "
                 f"{estimate['camera_rays']} camera rays, {estimate['bounce_rays']} along sharp lobes")
    return "\n".join(lines)
