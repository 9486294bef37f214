#!/usr/bin/env python3
"""Prints the ``lods:`` block of a library model's manifest entry: its coarser versions, finest
first, each with its checksum and geometric error (the symmetric Hausdorff distance to the main
file, in mesh units: synthgen.scene.lod.geometric_error).

    .venv/bin/python tools/lod_errors.py ROOT MAIN LOD [LOD ...]

ROOT: where the package's files are (a ``dpkg -x`` of it, or /); MAIN and LOD: paths inside the
package (as the manifest's ``source.path``). A level is left out, with the reason printed on
stderr, when it reads textures its main file does not (AC3D ``texture`` lines: the TORCS cars'
coarsest levels carry wheels of their own, textured with tex-wheel.rgb, which synthgen builds
itself) or when it has no fewer triangles than the level before it.
"""
from __future__ import annotations

import os
import re
import sys

import numpy as np

from synthgen._core import Scene
from synthgen.scene.assets import file_sha256
from synthgen.scene.lod import geometric_error


def textures(path: str) -> set:
    """Texture files an AC3D model reads (empty for other formats)."""
    if not path.lower().endswith((".ac", ".acc")):
        return set()
    with open(path, encoding="latin-1") as f:
        return set(re.findall(r'^texture "([^"]+)"', f.read(), flags=re.M))


def mesh(path: str):
    s = Scene()
    r = s.load_mesh_file(path)
    a = s.mesh_arrays(r["mesh_id"])
    return np.asarray(a["positions"]), np.asarray(a["indices"])


def main(argv) -> int:
    if len(argv) < 3:
        print(__doc__, file=sys.stderr)
        return 2
    root, main_path, levels = argv[0], argv[1], argv[2:]
    full = lambda p: os.path.join(root, p.lstrip("/"))  # noqa: E731
    finest = mesh(full(main_path))
    own = textures(full(main_path))
    last = len(finest[1])
    print("  lods:")
    for p in levels:
        extra = textures(full(p)) - own
        m = mesh(full(p))
        if extra:
            print(f"{p}: left out: reads textures the main file does not: {', '.join(sorted(extra))}",
                  file=sys.stderr)
            continue
        if len(m[1]) >= last:
            print(f"{p}: left out: {len(m[1])} triangles, not fewer than the level before ({last})", file=sys.stderr)
            continue
        last = len(m[1])
        err = geometric_error(finest, m)
        print(f"  - {{path: {p}, error: {err:.4f},\n     sha256: {file_sha256(full(p))}}}")
        print(f"{p}: {len(m[1])} triangles (main {len(finest[1])}), error {err:.4f}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
