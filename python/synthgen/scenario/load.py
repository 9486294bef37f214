"""Loading a scenario: validation (everything is checked before anything renders) into a
:class:`Scenario`, the validated tree whose random slots hold distributions.

Errors read ``FILE:LINE:COLUMN: key.path: reason`` with close spellings and allowed ranges.
"""
from __future__ import annotations

import hashlib
import json
import os
import re
from typing import Any, List, Optional, Sequence, Tuple

import numpy as np

from ..schema import distributions as D
from ..schema import limits
from ..schema.errors import Loc, SceneFileError, ValidationContext, suggest
from ..schema.fields import Validated
from ..schema.yaml_io import parse_yaml, read_text
from .schema import SCENARIO_SCHEMA, exposure_mode

__all__ = ["Scenario", "load_scenario", "parse_scenario", "check_memory", "scenario_warnings"]


class Scenario:
    """A validated scenario: ``spec`` (validated tree with distributions), ``source``,
    ``base_dir``, ``class_names`` (category order: COCO id = index + 1), ``text_sha256``,
    ``warnings``: what is valid but will not come out as meant (``FILE:LINE:COLUMN: key: why``;
    ``synthgen validate`` and ``synthgen run`` print them)."""

    def __init__(self, spec: Validated, source: str, base_dir: str, text: str):
        self.spec = spec
        self.source = source
        self.base_dir = base_dir
        self.text = text
        self.sha256 = hashlib.sha256(text.encode()).hexdigest()
        names: List[str] = []
        for o in spec["objects"]:
            if o["label"] and o["class"] not in names:
                names.append(o["class"])
        for o in spec["objects"]:  # plate-only labels (objects[].plates.class)
            cls = (o.get("plates") or {}).get("class") if o["label"] else None
            if cls and cls not in names:
                names.append(cls)
        self.class_names = names
        self.warnings: List[str] = scenario_warnings(spec, source)

    @property
    def seed(self) -> int:
        return int(self.spec["seed"])

    @property
    def count(self) -> int:
        return int(self.spec["count"])

    @property
    def resolution(self) -> Tuple[int, int]:
        return tuple(self.spec["resolution"])  # type: ignore[return-value]


def _check_assets(tree: Any, loc: Loc, ctx: ValidationContext, kind: str) -> None:
    """Every asset id (constant or among choice options) exists in the manifest with `kind`."""
    from ..scene import assets

    values = tree.options if isinstance(tree, D.Choice) else [tree]
    manifest = assets.load_manifest()
    for v in values:
        if v is None:
            continue
        if isinstance(v, D.Distribution):
            ctx.error(loc, "asset ids take a constant or a choice")
        try:
            e = assets.entry(v, manifest)
        except assets.AssetError as err:
            ctx.error(loc, str(err))
        if e["kind"] != kind:
            ctx.error(loc, f"asset '{v}' is a {e['kind']}, not a {kind}")


def _largest(v: Any) -> float:
    """The largest value a count may take (a constant, or a distribution's upper bound)."""
    if isinstance(v, D.Choice):
        return max(_largest(o) for o in v.options)
    if isinstance(v, (D.IntUniform, D.Uniform)):
        return float(np.max(v.hi))
    if isinstance(v, D.Distribution):
        return float("inf")
    return float(v)


def check_memory(width: int, height: int, workers: int = 1) -> Optional[str]:
    """Why ``workers`` frames of ``width`` x ``height`` at once do not fit in this machine's
    available memory, or None."""
    need = limits.frame_memory(width, height) * max(1, workers)
    have = limits.available_memory()
    if have is not None and need > have:
        per = f" x {workers} workers" if workers > 1 else ""
        return (f"{width} x {height} pixels need about {limits.fmt_bytes(need)} of memory{per} (about "
                f"{limits.BYTES_PER_PIXEL} bytes per pixel: render buffers, amodal masks, image conversions); "
                f"this machine has {limits.fmt_bytes(have)} available")
    return None


def _check(spec: Validated, ctx: ValidationContext) -> None:
    n = sum(_largest(o["count"]) for o in spec["objects"])
    if n > limits.MAX_OBJECTS_PER_FRAME:
        ctx.error(spec.locs.get("objects", spec.loc), f"up to {n:g} object instances per frame (the entries' largest "
                                                      f"counts); at most {limits.MAX_OBJECTS_PER_FRAME:,}")
    w, h = spec["resolution"]
    why = check_memory(w, h)
    if why:
        ctx.error(spec.locs.get("resolution", spec.loc), why)
    if not any(o["label"] for o in spec["objects"]):
        ctx.error(spec.locs.get("objects", spec.loc), "every object entry has label: false; a dataset needs at least "
                                                      "one labelled entry")
    for i, o in enumerate(spec["objects"]):
        if o["label"] and o["class"] is None:
            ctx.error(o.loc, "missing key 'class' (the class name; or label: false for an unlabelled object)")
        if not o["label"] and o["class"] is not None:
            ctx.error(o.locs["class"], "an object with label: false has no class (remove 'class' or the label: false)")
        if o.get("forward") and o.get("up") and o["forward"][1] == o["up"][1]:
            ctx.error(o.locs["up"], f"forward ({o['forward']}) and up ({o['up']}) must be different axes")
        if "asset" in o.given:
            _check_assets(o["asset"], o.locs["asset"], ctx, "mesh")
    lights = spec["lights"]
    setups = lights.options if isinstance(lights, D.Choice) else [lights]
    for setup in setups:
        for li in setup:
            if isinstance(li, dict) and li.get("type") == "envmap":
                if li.get("asset") is not None:
                    _check_assets(li["asset"], li.locs["asset"], ctx, "hdr")
    g = spec["ground"]
    if g["backplate"]:
        if not g["enabled"]:
            ctx.error(g.locs.get("backplate", g.loc), "backplate needs the ground (enabled: true)")
        for setup in setups:
            if not any(isinstance(li, dict) and li.get("type") == "envmap" for li in setup):
                ctx.error(g.locs.get("backplate", g.loc), "backplate needs an envmap light in every light set-up (the "
                                                          "environment's own image is the background)")
        if spec["background"] is not None:
            ctx.error(g.locs.get("backplate", g.loc), "backplate and background: a photo is the background already")
    pl = spec["placement"]
    for o in spec["objects"]:
        lo = o["min_visible_fraction"] if o["min_visible_fraction"] is not None else pl["min_visible_fraction"]
        hi = o["max_visible_fraction"] if o["max_visible_fraction"] is not None else pl["max_visible_fraction"]
        if hi < lo:
            ctx.error(o.locs.get("max_visible_fraction", o.locs.get("min_visible_fraction", o.loc)),
                      f"max_visible_fraction {hi} < min_visible_fraction {lo}")
    if pl["max_visible_fraction"] < pl["min_visible_fraction"]:
        ctx.error(pl.locs.get("max_visible_fraction", pl.loc), "max_visible_fraction must be >= min_visible_fraction")
    sp = spec["split"]
    if sp["val"] + sp["test"] > 1.0:
        ctx.error(sp.locs.get("test", sp.locs.get("val", sp.loc)),
                  f"val + test = {sp['val'] + sp['test']:g} leaves no frames for train (at most 1)")
    x0, z0, x1, z1 = spec["placement"]["region"]
    if not (x0 < x1 and z0 < z1):
        ctx.error(spec["placement"].locs.get("region", spec.loc), "region must satisfy x_min < x_max and z_min < z_max")
    for o in spec["objects"]:
        if o["region"] is not None:
            a, b, c, d = o["region"]
            if not (a < c and b < d):
                ctx.error(o.locs["region"], "region must satisfy x_min < x_max and z_min < z_max")
        if o["rests_on"] is not None and o["pixel_height"] is not None:
            ctx.error(o.locs["pixel_height"], "an object that rests_on another cannot also be placed by pixel_height")
    support_of(spec, ctx)
    _check_exposure(spec, ctx)
    _check_distortion(spec, ctx)


def _check_distortion(spec: Validated, ctx: ValidationContext) -> None:
    """camera k1..k3: not with KITTI's labels (its P2 projects without a lens) nor a photo
    background (the photo's calibration has its own)."""
    from .schema import DISTORTION_KEYS

    cam = spec["camera"]
    given = [k for k in DISTORTION_KEYS if k in cam.given]
    if not given:
        return
    kitti = [k for k in ("kitti", "kitti_calib") if k in spec["outputs"]]
    if kitti:
        where = "" if "outputs" in spec.given else " (the default outputs have them: list yours without)"
        plural = "s" if len(kitti) > 1 else ""
        ctx.error(cam.locs[given[0]], f"lens distortion with the {' and '.join(kitti)} output{plural}{where}: KITTI's "
                                      "P2 projects the 3D boxes without a lens, so they would miss the objects")
    if spec["background"] is not None:
        ctx.error(cam.locs[given[0]], "lens distortion with a photo background: the photo's calibration gives the "
                                      "lens (distortion in its calibration file)")


def _check_exposure(spec: Validated, ctx: ValidationContext) -> None:
    """camera.exposure: its keys agree with its mode; none on photo backgrounds."""
    cam = spec["camera"]
    ex = cam["exposure"]
    mode = exposure_mode(ex, spec["version"])
    if mode == "auto" and "factor" in ex.given:
        ctx.error(ex.locs["factor"], "a fixed factor with mode: auto (the metered exposure): give mode: fixed, or no "
                                     "factor (ev compensates the metered exposure)")
    if mode == "fixed" and "key" in ex.given:
        ctx.error(ex.locs["key"], "key is auto-exposure's (mode: auto); a fixed exposure is factor (and ev)")
    if spec["background"] is not None and ex.given:
        ctx.error(cam.locs.get("exposure", cam.loc), "photo backgrounds take the photo's own exposure (the render is "
                                                     "matched to the photo's light, meta background.exposure): "
                                                     "camera.exposure is for synthetic frames; remove it")


def scenario_warnings(spec: Validated, source: str) -> List[str]:
    """Valid but likely not meant: a sky at physical scale (no strength) in a frame that nothing
    exposes (format version 1, no camera.exposure, no exposure step, no dusk or night) is white
    in an 8-bit image; an ``exposure`` post step on top of version 2's auto-exposure (a
    version 1 scenario's hand exposure, moved to version 2) multiplies the metered image."""
    from ..randomize import weather

    ex = spec["camera"]["exposure"]
    if spec["background"] is not None:
        return []
    if exposure_mode(ex, spec["version"]) == "auto" and "mode" not in ex.given:
        return [str(SceneFileError(source, p.loc.line, p.loc.column, p.loc.path,
                                   "an exposure step on top of version 2's auto-exposure multiplies the metered image "
                                   "(exposure compensation); a hand exposure (version 1's) is camera.exposure: "
                                   "{mode: fixed, ev: ...}, compensation of the metered one camera.exposure.ev"))
                for p in spec["post"] if p["type"] == "exposure"]
    if ex.given or exposure_mode(ex, spec["version"]) != "fixed":
        return []
    if any(p["type"] == "exposure" for p in spec["post"]):
        return []
    if any(c.exposes and spec["weather"].get(c.key) is not None for c in weather.conditions()):
        return []
    lights = spec["lights"]
    out = []
    for setup in (lights.options if isinstance(lights, D.Choice) else [lights]):
        for li in setup:
            if isinstance(li, Validated) and li.get("type") == "sky" and "strength" not in li.given:
                out.append(str(SceneFileError(
                    source, li.loc.line, li.loc.column, li.loc.path,
                    "a sky without strength is at physical scale (a clear day's sky about 5-15, white in an 8-bit "
                    "image) and format version 1 leaves the image as rendered: write version: 2 (auto-exposure; "
                    "docs/scenarios.md#exposure), a camera.exposure, or the sky's strength (0.02: display range)")))
    return out


def support_of(spec: Validated, ctx: Optional[ValidationContext] = None) -> List[Optional[int]]:
    """For each object entry, the index of the entry its objects rest on (rests_on: a name, else a
    class), or None; errors (with ``ctx``) for unknown names, itself and cycles."""
    entries = spec["objects"]
    out: List[Optional[int]] = []
    for i, o in enumerate(entries):
        if o["rests_on"] is None:
            out.append(None)
            continue
        by_name = [j for j, e in enumerate(entries) if e["name"] == o["rests_on"]]
        by_class = [j for j, e in enumerate(entries) if e["class"] == o["rests_on"] and e["name"] is None]
        found = by_name or by_class
        if ctx is not None:
            if not found:
                names = sorted({e["name"] for e in entries if e["name"]} | {e["class"] for e in entries if e["class"]})
                ctx.error(o.locs["rests_on"], f"no object entry is named {o['rests_on']!r}{suggest(o['rests_on'], names)}")
            if len(found) > 1:
                ctx.error(o.locs["rests_on"], f"{len(found)} entries are named {o['rests_on']!r}; give the support a unique name")
            if found[0] == i:
                ctx.error(o.locs["rests_on"], "an entry cannot rest on itself")
        out.append(found[0] if found else None)
    if ctx is not None:
        for i in range(len(entries)):
            seen, j = {i}, out[i]
            while j is not None:
                if j in seen:
                    ctx.error(entries[i].locs["rests_on"], "the entries' rests_on form a cycle")
                seen.add(j)
                j = out[j]
    return out


def parse_scenario(data: Any, source: str = "<scenario>", base_dir: Optional[str] = None, text: str = "",
                   allow_extensions: bool = False) -> Scenario:
    """Validates a scenario tree (from :func:`synthgen.schema.read_yaml`). ``allow_extensions``:
    the caller's consent to compile and run the C files under ``extensions`` (the scenario must
    say ``allow_extensions: true`` too; docs/extensions.md)."""
    ctx = ValidationContext(source, base_dir)
    if isinstance(data, dict) and data.get("extensions"):
        from ..scene.scene_file import load_file_extensions

        load_file_extensions(data, SCENARIO_SCHEMA, ctx, allow_extensions)
    spec = SCENARIO_SCHEMA.validate(data, Loc.root(data), ctx)
    _check(spec, ctx)
    return Scenario(spec, source, ctx.base_dir, text or json.dumps(D.plain(spec), sort_keys=True))


_STEP = re.compile(r"([A-Za-z_][A-Za-z0-9_]*)((?:\[\d+\])*)")


def parse_override(text: str) -> Tuple[str, Any]:
    """``KEY.PATH=VALUE`` (the command line's ``--set``) as (path, value); VALUE is YAML
    (``64``, ``[320, 240]``, ``{uniform: [1, 2]}``). SceneFileError when malformed."""
    key, sep, value = text.partition("=")
    key = key.strip()
    if not sep or not key:
        raise SceneFileError("--set", None, None, "", f"expected KEY.PATH=VALUE, got {text!r}")
    for part in key.split("."):
        if not _STEP.fullmatch(part):
            raise SceneFileError("--set", None, None, "", f"{key!r}: not a key path (keys separated by '.', list "
                                                          f"items as [N], e.g. objects[0].count)")
    return key, parse_yaml(value, f"--set {key}")


def apply_overrides(data: Any, overrides: Sequence[Tuple[str, Any]], source: str) -> Any:
    """The tree with each (key path, value) set, creating mappings on the way; a list item
    must exist. The values carry no file position (errors name the key path)."""
    from ..schema.yaml_io import MarkedDict

    if data is None:
        data = MarkedDict()
    if not isinstance(data, dict):
        raise SceneFileError(source, None, None, "", "the scenario must be a mapping to take --set values")
    for key, value in overrides:
        node: Any = data
        steps: List[Any] = []
        for part in key.split("."):
            m = _STEP.fullmatch(part)
            steps.append(m.group(1))
            steps.extend(int(i) for i in re.findall(r"\[(\d+)\]", m.group(2)))
        for i, step in enumerate(steps[:-1]):
            if isinstance(step, int):
                if not isinstance(node, list) or step >= len(node):
                    raise SceneFileError(source, None, None, key, f"--set: there is no item {step} here")
                node = node[step]
            else:
                if not isinstance(node, dict):
                    raise SceneFileError(source, None, None, key, f"--set: '{step}' is not inside a mapping")
                if node.get(step) is None:
                    node[step] = MarkedDict() if isinstance(steps[i + 1], str) else []
                node = node[step]
        last = steps[-1]
        if isinstance(last, int):
            if not isinstance(node, list) or last >= len(node):
                raise SceneFileError(source, None, None, key, f"--set: there is no item {last} here")
        elif not isinstance(node, dict):
            raise SceneFileError(source, None, None, key, f"--set: '{last}' is not inside a mapping")
        node[last] = value
        if isinstance(node, MarkedDict):
            node.key_marks.pop(last, None)
            node.value_marks.pop(last, None)
    return data


def load_scenario(path: str | os.PathLike, overrides: Sequence[Tuple[str, Any]] = (),
                  allow_extensions: bool = False) -> Scenario:
    """Reads and validates a scenario file; raises :class:`SceneFileError` (file:line:col).

    ``overrides``: (key path, value) pairs set before validation, e.g. ``("render.spp", 64)``
    (the command line's ``--set``, ``--spp``, ``--resolution``); they are part of the scenario
    (its hash, the run manifest). ``allow_extensions``: see :func:`parse_scenario`."""
    path = os.fspath(path)
    text = read_text(path, what="scenario")
    data = parse_yaml(text, path)
    if not overrides:
        return parse_scenario(data, path, os.path.dirname(os.path.abspath(path)), text, allow_extensions)
    data = apply_overrides(data, overrides, path)
    text += "".join(f"\n# --set {k}={json.dumps(D.plain(v), sort_keys=True)}" for k, v in overrides)
    try:
        return parse_scenario(data, path, os.path.dirname(os.path.abspath(path)), text, allow_extensions)
    except SceneFileError as e:
        # An error in a value from the command line names the option, not a line of the file.
        for k, _ in reversed(list(overrides)):
            if e.key_path == k or e.key_path.startswith((k + ".", k + "[")):
                raise SceneFileError(f"{path} (--set {k})", None, None, e.key_path, e.reason) from None
        raise
