"""Benchmarks against peer renderers: the shared scene specs, the Blender Cycles and Embree
runners and ``synthgen bench`` (speed against accuracy); used by bench/vs_cycles.py too.

Modules: :mod:`.scenes` (scene specs built identically by synthgen and Cycles),
:mod:`.cycles_scene` (runs inside Blender), :mod:`.peers` (Cycles and Embree processes,
image reading), :mod:`.speed` (the benchmark, its table and chart)."""
