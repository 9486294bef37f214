"""The picture a user checks a calibration by (``synthgen calibrate PHOTO``): the photo with its
horizon, a metric grid on the ground, the placement region, the real labels and ignore regions,
and a reference car (4.5 x 1.8 x 1.5 m) at three distances ahead, turned along the road; and, per labelled
car, how wide its box is against the box a real car turned along the road would have there (its
width seen from behind or ahead, its length seen from the side: ``road_direction``)."""
from __future__ import annotations

import math
from typing import Any, Dict, List, Optional, Sequence

import numpy as np

from .calibration import Calibration
from .sidecar import PhotoSetup

__all__ = ["REFERENCE_CAR", "REFERENCE_DISTANCES", "CAR_LENGTH", "CAR_WIDTH", "label_checks", "draw_preview",
           "box_corners", "car_box_width"]

#: Length, width, height in metres of the reference car drawn (a mid-size saloon).
REFERENCE_CAR = (4.5, 1.8, 1.5)
REFERENCE_DISTANCES = (8.0, 15.0, 30.0)
#: Lengths and widths (metres) of real cars, 0.1 m of labelling slack included: a city car of
#: 3.5 m to a large saloon or SUV of 5.3 m; 1.6 to 2.0 m wide.
CAR_LENGTH = (3.4, 5.4)
CAR_WIDTH = (1.5, 2.1)


def box_corners(centre_x: float, centre_z: float, yaw_right: float, size: Sequence[float]) -> np.ndarray:
    """8 world corners of a box standing on the ground at (x, z), its length along a direction
    ``yaw_right`` degrees to the right of +z (the camera's forward)."""
    length, width, height = size
    a = math.radians(yaw_right)
    fwd = np.array([-math.sin(a), 0.0, math.cos(a)])   # right of +z is -x (see calibration.py)
    side = np.array([math.cos(a), 0.0, math.sin(a)])
    c = np.array([centre_x, 0.0, centre_z])
    out = []
    for sy in (0.0, height):
        for sl, sw in ((-1, -1), (1, -1), (1, 1), (-1, 1)):
            out.append(c + sl * 0.5 * length * fwd + sw * 0.5 * width * side + np.array([0.0, sy, 0.0]))
    return np.array(out)


def _segment(cal: Calibration, a: np.ndarray, b: np.ndarray, n: int = 24) -> np.ndarray:
    t = np.linspace(0.0, 1.0, n)[:, None]
    return cal.project(a + t * (b - a))


def car_box_width(cal: Calibration, box: Sequence[float], road_direction: float, length: float, width: float,
                  height: float = REFERENCE_CAR[2]) -> Optional[float]:
    """Width in pixels of the image box of a car (``length`` x ``width`` x ``height`` metres)
    standing on the ground turned along the road, placed where its image box's bottom centre is
    that of ``box`` (found by moving it until they agree within 0.05 px); None when no such
    place is in view."""
    x0, y0, x1, y1 = box
    target = np.array([0.5 * (x0 + x1), float(y1)])
    a = math.radians(road_direction)
    fwd, side = np.array([-math.sin(a), 0.0, math.cos(a)]), np.array([math.cos(a), 0.0, math.sin(a)])
    anchor = target.copy()
    for _ in range(20):
        # The car's nearest point (seen from the camera) on the ground under ``anchor``, its
        # centre half its extent along the line of sight beyond.
        p = cal.ground_point(anchor[None])[0]
        if not np.all(np.isfinite(p)):
            return None
        ray = np.array([p[0], 0.0, p[2]]) / max(math.hypot(p[0], p[2]), 1e-9)
        c = p + 0.5 * (length * abs(float(fwd @ ray)) + width * abs(float(side @ ray))) * ray
        uv = cal.project(box_corners(float(c[0]), float(c[2]), road_direction, (length, width, height)))
        if not np.all(np.isfinite(uv)):
            return None
        err = target - np.array([0.5 * (uv[:, 0].min() + uv[:, 0].max()), uv[:, 1].max()])
        if np.abs(err).max() < 0.05:
            break
        anchor = anchor + err
    return float(uv[:, 0].max() - uv[:, 0].min())


def label_checks(setup: PhotoSetup, classes: Sequence[str] = ("car",)) -> List[Dict[str, Any]]:
    """Per real object of ``classes``: its distance (camera z of the ground point below its box's
    bottom centre), the width the calibration gives it (box width x distance / fx: a car seen
    from behind), the angle between the road (``road_direction``) and the line of sight there
    (0: seen from behind or ahead, 90: from the side), its box's width in pixels and the range a
    real car turned along the road would have there (``expected``: :func:`car_box_width` of the
    smallest and largest cars, :data:`CAR_LENGTH` x :data:`CAR_WIDTH`); ``plausible``: the box
    within that range."""
    cal = setup.calibration
    rd = setup.road_direction
    out = []
    for o in setup.objects:
        if o.ignore or o.cls not in classes:
            continue
        x0, y0, x1, y1 = o.box
        p = cal.ground_point(np.array([[0.5 * (x0 + x1), y1]]))[0]
        if not np.all(np.isfinite(p)):
            out.append({"class": o.cls, "box": list(o.box), "distance": None, "width": None})
            continue
        z_cam = float((np.linalg.inv(cal.world_from_camera()) @ np.r_[p, 1.0])[2])
        a = math.radians(rd)
        ray = np.array([p[0], p[2]]) / max(math.hypot(p[0], p[2]), 1e-9)
        angle = math.degrees(math.acos(min(1.0, abs(float(ray @ [-math.sin(a), math.cos(a)])))))
        small = car_box_width(cal, o.box, rd, CAR_LENGTH[0], CAR_WIDTH[0])
        large = car_box_width(cal, o.box, rd, CAR_LENGTH[1], CAR_WIDTH[1])
        expected = None if small is None or large is None else [small, large]
        out.append({"class": o.cls, "box": [float(v) for v in o.box], "distance": z_cam,
                    "width": (x1 - x0) * z_cam / cal.fx, "angle": angle, "box_width": float(x1 - x0),
                    "expected": expected,
                    "plausible": None if expected is None else bool(expected[0] <= x1 - x0 <= expected[1])})
    return out


def draw_preview(image_srgb: np.ndarray, setup: PhotoSetup, path: str) -> None:
    """Writes the calibration preview of a photo (its sRGB 8-bit pixels) to PNG ``path``."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.patches import Polygon, Rectangle

    cal = setup.calibration
    h, w = image_srgb.shape[:2]
    dpi = 100
    fig = plt.figure(figsize=(w / dpi, h / dpi), dpi=dpi)
    ax = fig.add_axes([0, 0, 1, 1])
    ax.imshow(image_srgb, interpolation="nearest")
    ax.set_xlim(0, w)
    ax.set_ylim(h, 0)
    ax.axis("off")
    lw = max(1.0, w / 900.0)
    # The metric ground grid: 1 m lines near the camera, out to 60 m.
    rd = setup.road_direction
    for x in np.arange(-12.0, 12.01, 2.0):
        uv = _segment(cal, np.array([x, 0.0, 1.0]), np.array([x, 0.0, 60.0]), 60)
        ax.plot(uv[:, 0], uv[:, 1], color=(0.3, 0.9, 1.0), lw=0.6 * lw, alpha=0.7)
    for z in list(np.arange(2.0, 20.01, 2.0)) + [25.0, 30.0, 40.0, 50.0, 60.0]:
        uv = _segment(cal, np.array([-12.0, 0.0, z]), np.array([12.0, 0.0, z]), 40)
        ax.plot(uv[:, 0], uv[:, 1], color=(0.3, 0.9, 1.0), lw=(1.2 if z % 10 == 0 else 0.6) * lw, alpha=0.7)
        if z % 10 == 0:
            p = cal.project(np.array([[11.5, 0.0, z]]))[0]
            if np.all(np.isfinite(p)) and 0 <= p[0] < w and 0 <= p[1] < h:
                ax.text(p[0], p[1], f"{z:g} m", color="white", fontsize=7, va="bottom")
    (u0, v0), (u1, v1) = cal.horizon()
    ax.plot([u0, u1], [v0, v1], color=(1.0, 0.3, 0.2), lw=1.5 * lw, ls="--")
    ax.text(8, v0 - 4, "horizon", color=(1.0, 0.3, 0.2), fontsize=8)
    for poly in setup.regions:
        ax.add_patch(Polygon(poly, closed=True, fill=True, fc=(0.2, 1.0, 0.3, 0.15), ec=(0.2, 1.0, 0.3), lw=lw))
    for o in setup.objects:
        x0, y0, x1, y1 = o.box
        col = (0.6, 0.6, 0.6) if o.ignore else (1.0, 0.85, 0.1)
        ax.add_patch(Rectangle((x0, y0), x1 - x0, y1 - y0, fill=False, ec=col, lw=lw, ls=":" if o.ignore else "-"))
        ax.text(x0, y0 - 2, "ignore" if o.ignore else o.cls, color=col, fontsize=7)
    # The reference car at three distances ahead of the camera, turned along the road.
    for d, lateral in zip(REFERENCE_DISTANCES, (-3.0, 0.0, 3.0)):
        c = box_corners(lateral, d, rd, REFERENCE_CAR)
        for i, j in [(0, 1), (1, 2), (2, 3), (3, 0), (4, 5), (5, 6), (6, 7), (7, 4), (0, 4), (1, 5), (2, 6), (3, 7)]:
            uv = _segment(cal, c[i], c[j], 8)
            ax.plot(uv[:, 0], uv[:, 1], color=(1.0, 0.2, 0.8), lw=1.2 * lw)
        top = cal.project(c[4:5])[0]
        if np.all(np.isfinite(top)):
            ax.text(top[0], top[1] - 3, f"{d:g} m", color=(1.0, 0.2, 0.8), fontsize=7)
    fig.savefig(path, dpi=dpi)
    plt.close(fig)
