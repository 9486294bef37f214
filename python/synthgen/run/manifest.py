"""The run manifest: what a dataset directory was made from, so a resumed or extended run
never mixes datasets.

``run_manifest.json`` is written into the output directory before its first frame: the
synthgen version, a canonical hash of the validated scenario (its values, not its text:
comments and spacing do not count, the frame count does not either), the class list, the
resolution and outputs, and the content hash of every input file the scenario reads (meshes
with the material and texture files they name, images, environment maps, assets by their
manifest checksums, the fonts of generated plates and signs). Rendering into a directory
that holds frames compares its manifest with the run's and refuses, naming what differs.
"""
from __future__ import annotations

import hashlib
import json
import os
import re
from typing import Any, Dict, Iterable, List, Optional, Set

from .._core import __version__
from .._core import SynthgenError
from ..outputs.files import write_json
from ..scenario import Scenario
from ..scene.assets import file_sha256
from ..schema import distributions as D
from ..schema.fields import InputPath

__all__ = ["MANIFEST", "build_manifest", "check_manifest", "write_manifest", "ManifestMismatch"]

MANIFEST = "run_manifest.json"


class ManifestMismatch(SynthgenError):
    """The output directory holds frames of another run."""



def _companions(path: str) -> List[str]:
    """Files a model file names (an OBJ's MTL files and their texture maps, a glTF's
    buffers and images), that exist."""
    out: List[str] = []
    d = os.path.dirname(path)
    ext = os.path.splitext(path)[1].lower()
    try:
        if ext == ".obj":
            with open(path, encoding="utf-8", errors="replace") as f:
                mtls = [line.split(None, 1)[1].strip() for line in f if line.startswith("mtllib ")]
            for m in mtls:
                mp = os.path.join(d, m)
                if os.path.isfile(mp):
                    out.append(mp)
                    with open(mp, encoding="utf-8", errors="replace") as f:
                        for line in f:
                            if re.match(r"\s*(map_\w+|bump|disp|decal|refl)\s", line):
                                t = os.path.join(os.path.dirname(mp), line.split()[-1])
                                if os.path.isfile(t):
                                    out.append(t)
        elif ext == ".gltf":
            with open(path, encoding="utf-8") as f:
                doc = json.load(f)
            for item in doc.get("buffers", []) + doc.get("images", []):
                uri = item.get("uri", "")
                if uri and not uri.startswith("data:") and os.path.isfile(os.path.join(d, uri)):
                    out.append(os.path.join(d, uri))
    except (OSError, ValueError):
        pass  # the loader reports unreadable files; the model file's own hash still counts
    return sorted(set(out))


def _walk(tree: Any, paths: Set[str], assets: Set[str], key: str = "") -> Any:
    """The canonical form of a validated tree (distributions by kind and parameters, every
    choice option walked), collecting input paths and asset ids."""
    if isinstance(tree, D.Choice):
        return {"choice": [_walk(o, paths, assets, key) for o in tree.options], "weights": tree.weights}
    if isinstance(tree, D.Distribution):
        return tree.spec()
    if isinstance(tree, InputPath):
        paths.add(str(tree))
        return {"file": os.path.basename(tree)}
    if isinstance(tree, dict):
        return {str(k): _walk(v, paths, assets, str(k)) for k, v in sorted(tree.items(), key=lambda kv: str(kv[0]))}
    if isinstance(tree, (list, tuple)):
        return [_walk(v, paths, assets, key) for v in tree]
    if key == "asset" and isinstance(tree, str):
        assets.add(tree)
    return tree


def build_manifest(sc: Scenario) -> Dict[str, Any]:
    """The manifest of a run of ``sc`` (see the module docstring)."""
    paths: Set[str] = set()
    assets: Set[str] = set()
    spec = {k: v for k, v in sc.spec.items() if k != "count"}
    canonical = _walk(spec, paths, assets)
    files: Dict[str, str] = {}
    for p in sorted(paths):
        for f in [p] + _companions(p):
            files[f] = file_sha256(f)
    if sc.spec.get("background") is not None:
        # The photos the globs and folders expand to, their calibrations and label files: adding
        # one photo to a folder changes which photo every later frame uses.
        from ..background.photoset import PhotoSet

        ps = PhotoSet(sc.spec["background"], sc.base_dir, sc.seed)
        for f, h in ps.input_files(with_labels=True).items():
            files[f] = h
    inputs = {"files": {os.path.basename(f) + " (" + f + ")": h for f, h in files.items()}}
    if assets:
        from ..scene import assets as A

        manifest = A.load_manifest()
        inputs["assets"] = {a: A.entry(a, manifest)["sha256"] for a in sorted(assets)}
    if any(r in sc.spec["objects"][i] and sc.spec["objects"][i][r] is not None
           for i in range(len(sc.spec["objects"])) for r in ("sign", "plate", "decals")):
        from ..scene import raster

        for name in ("DejaVuSans-Bold", "DejaVuSans"):
            try:
                inputs["files"][f"font {name}"] = file_sha256(raster.font_path(name))
            except (OSError, SynthgenError):
                pass
    blob = json.dumps(canonical, sort_keys=True, separators=(",", ":"), default=str)
    manifest = {
        "format": "synthgen-run-manifest", "format_version": 1,
        "synthgen_version": __version__,
        "scenario_hash": hashlib.sha256(blob.encode()).hexdigest(),
        "scenario": canonical,
        "class_names": list(sc.class_names),
        "resolution": list(sc.resolution),
        "outputs": list(sc.spec["outputs"]),
        "inputs": inputs,
    }
    return json.loads(json.dumps(manifest, default=str))  # the form it has when read back


def _differences(old: Dict[str, Any], new: Dict[str, Any], path: str = "") -> List[str]:
    out: List[str] = []
    if isinstance(old, dict) and isinstance(new, dict):
        for k in sorted(set(old) | set(new), key=str):
            p = f"{path}.{k}" if path else str(k)
            if k not in old:
                out.append(f"{p}: added ({json.dumps(new[k], default=str)[:80]})")
            elif k not in new:
                out.append(f"{p}: removed (was {json.dumps(old[k], default=str)[:80]})")
            else:
                out += _differences(old[k], new[k], p)
        return out
    if old != new:
        out.append(f"{path}: {json.dumps(old, default=str)[:80]} -> {json.dumps(new, default=str)[:80]}")
    return out


def check_manifest(out_dir: str, manifest: Dict[str, Any], frames: Iterable[int]) -> None:
    """Refuses (ManifestMismatch) when ``out_dir`` holds frames of another run: its manifest
    differs from ``manifest`` (naming the differences), or it has frames and no manifest."""
    frames = list(frames)
    path = os.path.join(out_dir, MANIFEST)
    if not os.path.exists(path):
        if frames:
            raise ManifestMismatch(f"{out_dir} holds {len(frames)} frame(s) but no {MANIFEST}: they cannot be "
                                   f"checked against this run (made by an older synthgen?); use a new output "
                                   f"directory")
        return
    try:
        with open(path, encoding="utf-8") as f:
            old = json.load(f)
    except (OSError, ValueError) as e:
        raise ManifestMismatch(f"{path}: unreadable run manifest ({e}); use a new output directory") from None
    if old == manifest:
        return
    diffs = [d for d in _differences(old, manifest) if not d.startswith("scenario_hash")]
    raise ManifestMismatch(f"{out_dir} was made by another run: {'; '.join(diffs[:8])}"
                           f"{f' (and {len(diffs) - 8} more)' if len(diffs) > 8 else ''}; use a new output directory")


def write_manifest(out_dir: str, manifest: Dict[str, Any]) -> Optional[str]:
    path = os.path.join(out_dir, MANIFEST)
    if os.path.exists(path):
        return None
    return write_json(path, manifest)
