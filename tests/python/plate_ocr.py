"""Reading plates back with an OCR engine that was not written from our glyph code (Debian
tesseract-ocr), as an ANPR pipeline would: the plate's four corners (from the labels) rectify
it to 1 px/mm, the fields inside the rim are cropped by the plate's layout, and each field is
read as one line with the plate alphabet as whitelist. Helpers for the tests, not a test."""
from __future__ import annotations

import shutil
import subprocess
import tempfile
import os
from typing import Dict, List, Sequence, Tuple

import numpy as np

import OpenImageIO as oiio

#: Fields of each plate layout, in millimetres (x0, y0, x1, y1 from the top left; inside the
#: rim), with the alphabet an ANPR reader expects there.
FIELDS = {
    "ru": [((5, 5, 395, 107), "ABCEHKMOPTXY0123456789"), ((405, 4, 515, 70), "0123456789")],
    "de": [((48, 5, 515, 105), "ABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789")],
}
SIZE_MM = {"ru": (520, 112), "de": (520, 110)}


def available() -> bool:
    return shutil.which("tesseract") is not None


def tesseract_line(gray: np.ndarray, whitelist: str, psm: int = 7) -> str:
    """One line of text (``psm`` 7; 10: one character) in a grey image (values in [0, 1])."""
    fd, path = tempfile.mkstemp(suffix=".png", prefix="synthgen-ocr-")
    os.close(fd)
    try:
        a = np.ascontiguousarray((np.clip(gray, 0, 1) * 255 + 0.5).astype(np.uint8)[..., None])
        b = oiio.ImageBuf(oiio.ImageSpec(a.shape[1], a.shape[0], 1, oiio.UINT8))
        b.set_pixels(oiio.ROI(), a)
        b.write(path)
        r = subprocess.run(["tesseract", path, "stdout", "--psm", str(psm), "-c", f"tessedit_char_whitelist={whitelist}"],
                           capture_output=True, text=True, timeout=60)
        return "".join(r.stdout.split())
    finally:
        os.unlink(path)


def homography(src: np.ndarray, dst: np.ndarray) -> np.ndarray:
    """3 x 3 H with dst ~ H src (4 point pairs, DLT)."""
    A = []
    for (x, y), (u, v) in zip(src, dst):
        A.append([-x, -y, -1, 0, 0, 0, u * x, u * y, u])
        A.append([0, 0, 0, -x, -y, -1, v * x, v * y, v])
    _, _, vt = np.linalg.svd(np.asarray(A, float))
    return vt[-1].reshape(3, 3) / vt[-1, -1]


def rectify(gray: np.ndarray, corners_uv: np.ndarray, size_mm: Tuple[int, int]) -> np.ndarray:
    """The plate at 1 px/mm from its image corners (top left, top right, bottom right, bottom
    left), bilinear."""
    w, h = size_mm
    H = homography(np.array([[0, 0], [w, 0], [w, h], [0, h]], float), np.asarray(corners_uv, float))
    ys, xs = np.mgrid[0:h, 0:w].astype(float) + 0.5
    q = H @ np.stack([xs.ravel(), ys.ravel(), np.ones(xs.size)])
    u, v = q[0] / q[2] - 0.5, q[1] / q[2] - 0.5
    u0, v0 = np.clip(np.floor(u).astype(int), 0, gray.shape[1] - 2), np.clip(np.floor(v).astype(int), 0, gray.shape[0] - 2)
    fu, fv = np.clip(u - u0, 0, 1), np.clip(v - v0, 0, 1)
    out = ((1 - fu) * (1 - fv) * gray[v0, u0] + fu * (1 - fv) * gray[v0, u0 + 1] + (1 - fu) * fv * gray[v0 + 1, u0] +
           fu * fv * gray[v0 + 1, u0 + 1])
    return out.reshape(h, w)


def read_plate(gray: np.ndarray, corners_uv: np.ndarray, country: str) -> str:
    """The plate's text as the OCR reads it (fields concatenated, no spaces)."""
    plate = rectify(gray, corners_uv, SIZE_MM[country])
    out = ""
    for (x0, y0, x1, y1), wl in FIELDS[country]:
        field = np.pad(plate[y0:y1, x0:x1], 16, mode="edge")
        out += tesseract_line(field, wl)
    return out


def _levenshtein(a: str, b: str) -> int:
    d = list(range(len(b) + 1))
    for i, ca in enumerate(a, 1):
        prev, d[0] = d[0], i
        for j, cb in enumerate(b, 1):
            prev, d[j] = d[j], min(d[j] + 1, d[j - 1] + 1, prev + (ca != cb))
    return d[len(b)]


def characters_read(truth: str, got: str) -> int:
    """Characters read right: the truth's length less the edit distance (O and 0 count alike, as
    the standards draw them alike)."""
    t, g = truth.replace(" ", "").replace("O", "0"), got.replace(" ", "").replace("O", "0")
    return max(0, len(t) - _levenshtein(t, g))


def plate_corners(meta: Dict, obj: Dict) -> np.ndarray:
    """Image corners (top left, top right, bottom right, bottom left) of a plate object: its unit
    box's front face through world_from_object and the camera."""
    wfo = np.asarray(obj["world_from_object"])
    cam = meta["camera"]
    cfw = np.linalg.inv(np.asarray(cam["world_from_camera"]))
    K = np.asarray(cam["K"])
    # The readable face is the box's -z face, seen with the object's +x on the left.
    pts = np.array([[0.5, 0.5, -0.5, 1], [-0.5, 0.5, -0.5, 1], [-0.5, -0.5, -0.5, 1], [0.5, -0.5, -0.5, 1]]).T
    c = (cfw @ wfo @ pts)[:3]
    uv = K @ c
    return (uv[:2] / uv[2]).T


def srgb_gray(linear_rgb: np.ndarray) -> np.ndarray:
    g = np.clip(np.asarray(linear_rgb, np.float64).mean(axis=2), 0, 1)
    return np.where(g <= 0.0031308, 12.92 * g, 1.055 * g ** (1 / 2.4) - 0.055)


def summary(rows: Sequence[Tuple[str, float, float, str, str]]) -> List[str]:
    """Lines of a read-back table: (country, width px, angle, truth, read)."""
    return [f"{c} {w:5.0f} px {a:4.0f} deg  {t:>12}  read {g:>12}  ({characters_read(t, g)}/{len(t.replace(' ', ''))})"
            for c, w, a, t, g in rows]
