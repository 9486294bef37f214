"""Photos: which files a scenario's ``photos`` names, and each photo read as linear light with
what its file says about itself (EXIF orientation applied, EXIF focal length, JPEG quality).

Decoding goes through the isolated reader (``synthgen.read_image``: a corrupt or hostile file
is a clear error, never a crash); the JPEG quantization tables are read here from the file's
header only (bounded: the first 256 kB, at most 64 segments).
"""
from __future__ import annotations

import glob
import os
from dataclasses import dataclass, field
from typing import Any, Dict, List, Optional, Sequence

import numpy as np

from .._core import SynthgenError, read_image_info
from ..scene.assets import file_sha256

__all__ = ["PHOTO_EXTENSIONS", "Photo", "expand_photos", "load_photo", "apply_orientation", "jpeg_quality"]

#: Files a folder or glob of photos contributes (case-insensitive).
PHOTO_EXTENSIONS = (".jpg", ".jpeg", ".png", ".tif", ".tiff", ".exr", ".hdr", ".bmp")


def expand_photos(entries: Sequence[str], base_dir: str) -> List[str]:
    """The photo files of ``entries`` (files, globs, folders; relative to ``base_dir``), each
    once, in a stable order: entry by entry, files of a glob or folder sorted. Raises
    SynthgenError naming an entry that matches nothing."""
    out: List[str] = []
    seen = set()
    for entry in entries:
        path = entry if os.path.isabs(entry) else os.path.join(base_dir, entry)
        if os.path.isdir(path):
            found = sorted(os.path.join(path, f) for f in os.listdir(path)
                           if f.lower().endswith(PHOTO_EXTENSIONS) and os.path.isfile(os.path.join(path, f)))
            what = "folder"
        elif any(ch in entry for ch in "*?["):
            found = sorted(f for f in glob.glob(path, recursive=True)
                           if os.path.isfile(f) and f.lower().endswith(PHOTO_EXTENSIONS))
            what = "pattern"
        else:
            if not os.path.isfile(path):
                raise SynthgenError(f"photo '{entry}': file not found ({path})")
            found, what = [path], "file"
        if not found:
            raise SynthgenError(f"photos: the {what} '{entry}' holds no photo ({', '.join(PHOTO_EXTENSIONS)})")
        for f in found:
            f = os.path.abspath(f)
            if f not in seen:
                seen.add(f)
                out.append(f)
    return out


def apply_orientation(a: np.ndarray, orientation: int) -> np.ndarray:
    """Pixels as a viewer shows a file with EXIF ``orientation`` (1..8; EXIF 2.3, tag 0x0112)."""
    o = int(orientation)
    if o == 2:
        return a[:, ::-1]
    if o == 3:
        return a[::-1, ::-1]
    if o == 4:
        return a[::-1]
    if o == 5:  # mirrored, then turned 270 degrees clockwise: the transpose
        return np.swapaxes(a, 0, 1)
    if o == 6:  # turned 90 degrees clockwise
        return np.rot90(a, k=-1)
    if o == 7:  # mirrored, then turned 90 degrees clockwise: the anti-diagonal transpose
        return np.swapaxes(a[::-1, ::-1], 0, 1)
    if o == 8:  # turned 270 degrees clockwise
        return np.rot90(a, k=1)
    return a


# The IJG (libjpeg) luminance quantization table at quality 50, in natural order
# (ITU-T T.81 Annex K, table K.1).
_IJG_LUMA = np.array([
    16, 11, 10, 16, 24, 40, 51, 61, 12, 12, 14, 19, 26, 58, 60, 55, 14, 13, 16, 24, 40, 57, 69, 56,
    14, 17, 22, 29, 51, 87, 80, 62, 18, 22, 37, 56, 68, 109, 103, 77, 24, 35, 55, 64, 81, 104, 113, 92,
    49, 64, 78, 87, 103, 121, 120, 101, 72, 92, 95, 98, 112, 100, 103, 99], np.float64)
# Zig-zag order -> natural order index (DQT segments store tables in zig-zag order).
_ZIGZAG = np.array([
    0, 1, 8, 16, 9, 2, 3, 10, 17, 24, 32, 25, 18, 11, 4, 5, 12, 19, 26, 33, 40, 48, 41, 34, 27, 20, 13, 6, 7, 14,
    21, 28, 35, 42, 49, 56, 57, 50, 43, 36, 29, 22, 15, 23, 30, 37, 44, 51, 58, 59, 52, 45, 38, 31, 39, 46, 53,
    60, 61, 54, 47, 55, 62, 63])


def jpeg_quality(path: str) -> Optional[float]:
    """The IJG quality (1..100) a JPEG file was most likely saved at, from its luminance
    quantization table; None for other files or tables that are not scaled IJG ones.

    NOTE: libjpeg scales the standard table by S = 5000 / q (q < 50) or 200 - 2 q (q >= 50),
    in percent (jcparam.c, jpeg_quality_scaling); S is estimated as the mean of table / standard
    and inverted (the method of ImageMagick's and Neal Krawetz's estimators)."""
    try:
        with open(path, "rb") as f:
            data = f.read(256 * 1024)
    except OSError:
        return None
    if data[:2] != b"\xff\xd8":
        return None
    i, segments = 2, 0
    while i + 4 <= len(data) and segments < 64:
        if data[i] != 0xFF:
            return None
        marker = data[i + 1]
        if marker in (0xD8, 0x01) or 0xD0 <= marker <= 0xD7:
            i += 2
            continue
        length = int.from_bytes(data[i + 2:i + 4], "big")
        if length < 2 or i + 2 + length > len(data):
            return None
        if marker == 0xDA:  # start of scan: no table came before the image data
            return None
        segments += 1
        if marker == 0xDB:
            j, end = i + 4, i + 2 + length
            while j < end:
                pq, tq = data[j] >> 4, data[j] & 15
                n = 128 if pq else 64
                if j + 1 + n > end:
                    return None
                raw = np.frombuffer(data[j + 1:j + 1 + n], dtype=">u2" if pq else np.uint8).astype(np.float64)
                if tq == 0:
                    table = np.empty(64)
                    table[_ZIGZAG] = raw
                    # Entries clamp at 1 (quality near 100) and 255 (8-bit, low quality): left out.
                    ok = (table > 1) & (table < 255)
                    if ok.sum() < 8:
                        return 100.0 if np.all(table <= 1) else None
                    s = float(np.mean(table[ok] * 100.0 / _IJG_LUMA[ok]))
                    q = (200.0 - s) / 2.0 if s <= 100.0 else 5000.0 / s
                    return float(min(100.0, max(1.0, q)))
                j += 1 + n
        i += 2 + length
    return None


@dataclass
class Photo:
    """A photo read for a frame: linear RGB pixels as a viewer shows them (EXIF orientation
    applied), and what its file says."""

    path: str
    pixels: np.ndarray                       #: H x W x 3 float32, linear (sRGB files decoded)
    sha256: str
    format: str = ""
    orientation: int = 1
    exif_focal_mm: float = 0.0
    exif_focal_35mm: float = 0.0
    jpeg_quality: Optional[float] = None
    info: Dict[str, Any] = field(default_factory=dict)

    @property
    def width(self) -> int:
        return int(self.pixels.shape[1])

    @property
    def height(self) -> int:
        return int(self.pixels.shape[0])


def load_photo(path: str) -> Photo:
    """Reads a photo (see :class:`Photo`); FileError naming the file when it cannot be read."""
    pixels, info = read_image_info(path)
    if pixels.shape[2] == 1:
        pixels = np.repeat(pixels, 3, axis=2)
    elif pixels.shape[2] == 2:  # grey + alpha
        pixels = np.repeat(pixels[:, :, :1], 3, axis=2)
    pixels = np.ascontiguousarray(apply_orientation(pixels[:, :, :3], info["orientation"]), np.float32)
    fmt = str(info["format"])
    return Photo(path=os.path.abspath(path), pixels=pixels, sha256=file_sha256(path), format=fmt,
                 orientation=int(info["orientation"]), exif_focal_mm=float(info["exif_focal_mm"]),
                 exif_focal_35mm=float(info["exif_focal_35mm"]),
                 jpeg_quality=jpeg_quality(path) if fmt == "jpeg" else None)
