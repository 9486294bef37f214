"""File writers: arrays -> files, atomically (pure functions, no rendering).

EXR (float32, lossless, a fixed header date so equal images are equal files), 8-bit sRGB
PNG, 16-bit id PNG, strictly valid JSON and plain text. All image I/O goes through
OpenImageIO. Every file is written to a temporary file in the same directory and renamed
over the target (``os.replace``), so an interrupted run never leaves a truncated file
under a final name.
"""
from __future__ import annotations

import json
import math
import os
import uuid
from collections.abc import Mapping
from typing import Any, Dict, Optional, Sequence

import numpy as np
import OpenImageIO as oiio

from .._core import SynthgenError

__all__ = ["ID_MAX", "srgb_encode", "to_srgb8", "write_exr", "write_srgb_png", "write_id_png", "write_json",
           "write_text", "check_ids", "as_hwc"]

#: DateTime written into every EXR header (see :func:`write_exr`).
EXR_DATETIME = "2000:01:01 00:00:00"
#: Largest id a 16-bit PNG can hold.
ID_MAX = 65535


# ---------------------------------------------------------------------------------------
# Atomic file replacement


def _temp_path(path: str) -> str:
    d, base = os.path.split(path)
    stem, ext = os.path.splitext(base)
    # Keep the extension: OpenImageIO picks the format from it.
    return os.path.join(d, f".{stem}.{os.getpid()}.{uuid.uuid4().hex[:8]}.tmp{ext}")


def _fsync(path: str) -> None:
    fd = os.open(path, os.O_RDONLY)
    try:
        os.fsync(fd)
    finally:
        os.close(fd)


def _commit(tmp: str, path: str) -> None:
    _fsync(tmp)
    os.replace(tmp, path)


def _discard(tmp: str) -> None:
    try:
        os.unlink(tmp)
    except OSError:
        pass


def _oiio_write(path: str, pixels: np.ndarray, fmt: Any, channel_names: Sequence[str],
                attributes: Optional[Mapping[str, Any]] = None) -> str:
    """Writes ``pixels`` (H x W x C) to ``path`` atomically through OpenImageIO."""
    path = os.fspath(path)
    h, w, c = pixels.shape
    spec = oiio.ImageSpec(w, h, c, fmt)
    spec.channelnames = tuple(channel_names)
    for k, v in (attributes or {}).items():
        spec.attribute(k, v)
    tmp = _temp_path(path)
    try:
        out = oiio.ImageOutput.create(tmp)
        if out is None:
            raise OSError(f"{path}: cannot create an image writer: {oiio.geterror()}")
        try:
            if not out.open(tmp, spec):
                raise OSError(f"{path}: cannot open for writing: {out.geterror()}")
            if not out.write_image(np.ascontiguousarray(pixels)):
                raise OSError(f"{path}: write failed: {out.geterror()}")
        finally:
            out.close()
        _commit(tmp, path)
    except BaseException:
        _discard(tmp)
        raise
    return path


# ---------------------------------------------------------------------------------------
# Image writers


def srgb_encode(linear: np.ndarray) -> np.ndarray:
    """sRGB OETF (IEC 61966-2-1) of linear values, clipped to [0, 1]; NaN -> 0."""
    x = np.nan_to_num(np.asarray(linear, dtype=np.float64), nan=0.0, posinf=1.0, neginf=0.0)
    x = np.clip(x, 0.0, 1.0)
    y = np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1.0 / 2.4) - 0.055)
    return np.where(x >= 1.0, 1.0, y)  # exactly 1 (the formula gives 1 - 1e-16)


def to_srgb8(linear: np.ndarray) -> np.ndarray:
    """8-bit sRGB (rounded to nearest) of linear values."""
    return np.round(srgb_encode(linear) * 255.0).astype(np.uint8)


def as_hwc(a: np.ndarray, what: str, channels: Optional[int] = None) -> np.ndarray:
    a = np.asarray(a)
    if a.ndim == 2:
        a = a[:, :, None]
    if a.ndim != 3 or a.shape[0] == 0 or a.shape[1] == 0:
        raise SynthgenError(f"{what}: expected an H x W or H x W x C array, got shape {a.shape}")
    if channels is not None and a.shape[2] != channels:
        raise SynthgenError(f"{what}: expected {channels} channel(s), got shape {a.shape}")
    return a


def write_exr(path: str | os.PathLike, array: np.ndarray, channel_names: Optional[Sequence[str]] = None) -> str:
    """Writes a float32 OpenEXR image (H x W, or H x W x C) bit-exactly (ZIP compression).

    Default channel names: one channel "Y", three "R", "G", "B", four "R", "G", "B", "A".
    Infinities and NaNs are stored as they are. The header's DateTime is a fixed
    :data:`EXR_DATETIME` (OpenImageIO would write the current time), so equal images are
    byte-identical files (reproducible datasets, comparable hashes). Returns the path.
    """
    path = os.fspath(path)
    a = as_hwc(array, path).astype(np.float32, copy=False)
    c = a.shape[2]
    if channel_names is None:
        defaults = {1: ("Y",), 3: ("R", "G", "B"), 4: ("R", "G", "B", "A")}
        channel_names = defaults.get(c) or tuple(f"C{i}" for i in range(c))
    if len(channel_names) != c:
        raise SynthgenError(f"{path}: {c} channels but {len(channel_names)} channel names")
    return _oiio_write(path, a, oiio.FLOAT, channel_names, {"compression": "zip", "DateTime": EXR_DATETIME})


def write_srgb_png(path: str | os.PathLike, rgb: np.ndarray) -> str:
    """Writes linear RGB (H x W x 3) as an 8-bit sRGB PNG (clipped). Returns the path."""
    path = os.fspath(path)
    a = as_hwc(rgb, path, 3)
    return _oiio_write(path, to_srgb8(a), oiio.UINT8, ("R", "G", "B"), {"oiio:ColorSpace": "sRGB"})


def write_id_png(path: str | os.PathLike, ids: np.ndarray) -> str:
    """Writes integer ids (H x W) as a 16-bit single-channel PNG. Returns the path.

    Raises SynthgenError when an id is negative or exceeds 65535 (instead of wrapping).
    """
    path = os.fspath(path)
    a = check_ids(ids, path)
    return _oiio_write(path, a.astype(np.uint16)[:, :, None], oiio.UINT16, ("Y",))


def check_ids(ids: np.ndarray, what: str) -> np.ndarray:
    a = np.asarray(ids)
    if a.ndim != 2 or a.size == 0:
        raise SynthgenError(f"{what}: expected an H x W id array, got shape {a.shape}")
    if not (np.issubdtype(a.dtype, np.integer) or a.dtype == np.bool_):
        raise SynthgenError(f"{what}: ids must be integers, got dtype {a.dtype}")
    hi, lo = int(a.max()), int(a.min())
    if hi > ID_MAX or lo < 0:
        bad = int(np.count_nonzero((a > ID_MAX) | (a < 0)))
        raise SynthgenError(f"{what}: ids must lie in [0, {ID_MAX}] for a 16-bit PNG; found "
                            f"{hi if hi > ID_MAX else lo} ({bad} pixel{'s' if bad != 1 else ''} out of range)")
    return a


def _json_default(o: Any) -> Any:
    if isinstance(o, np.ndarray):
        return o.tolist()
    if isinstance(o, np.generic):
        return o.item()
    if isinstance(o, (set, frozenset)):
        return sorted(o)
    if isinstance(o, os.PathLike):
        return os.fspath(o)
    raise TypeError(f"{type(o).__name__} is not JSON serialisable")


def _finite_json(o: Any) -> Any:
    """Replaces non-finite floats by None (JSON has no inf / NaN)."""
    if isinstance(o, float):
        return o if math.isfinite(o) else None
    if isinstance(o, Mapping):
        return {str(k): _finite_json(v) for k, v in o.items()}
    if isinstance(o, (list, tuple)):
        return [_finite_json(v) for v in o]
    if isinstance(o, np.ndarray):
        return _finite_json(o.tolist())
    if isinstance(o, np.generic):
        return _finite_json(o.item())
    return o


def _dumps(o: Any, indent: str) -> str:
    """JSON with 2-space indentation; lists of scalars stay on one line (matrices read
    as one row per line)."""
    inner = indent + "  "
    if isinstance(o, dict):
        if not o:
            return "{}"
        items = [f"{inner}{json.dumps(k)}: {_dumps(v, inner)}" for k, v in o.items()]
        return "{\n" + ",\n".join(items) + "\n" + indent + "}"
    if isinstance(o, list):
        if all(not isinstance(v, (dict, list)) for v in o):
            return "[" + ", ".join(json.dumps(v) for v in o) + "]"
        return "[\n" + ",\n".join(inner + _dumps(v, inner) for v in o) + "\n" + indent + "]"
    return json.dumps(o)


def write_json(path: str | os.PathLike, obj: Any) -> str:
    """Writes ``obj`` as indented, strictly valid JSON (non-finite floats become null),
    atomically. numpy arrays and scalars are converted. Returns the path."""
    path = os.fspath(path)
    text = _dumps(json.loads(json.dumps(_finite_json(obj), default=_json_default, allow_nan=False)), "")
    tmp = _temp_path(path)
    try:
        with open(tmp, "x", encoding="utf-8") as f:
            f.write(text + "\n")
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except BaseException:
        _discard(tmp)
        raise
    return path


def write_text(path: str | os.PathLike, text: str) -> str:
    """Writes text (UTF-8) atomically. Returns the path."""
    path = os.fspath(path)
    tmp = _temp_path(path)
    try:
        with open(tmp, "w", encoding="utf-8") as f:
            f.write(text)
        _commit(tmp, path)
    except BaseException:
        _discard(tmp)
        raise
    return path
