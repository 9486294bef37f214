"""A photo's calibration: its camera (intrinsics, lens distortion) and where the ground is.

Conventions (those of every synthgen scene): world y up, the ground is the plane y = 0, metres.
The camera stands at (0, h, 0) above the world origin; its optical axis, projected onto the
ground, is +z; camera space is OpenCV's (x right, y down, z forward), so the camera's right,
projected onto the ground, is -x (``PinholeCamera.look_at``'s convention).

* ``pitch``: degrees the optical axis points below the horizontal (positive: looking down);
* ``roll``: degrees the camera is turned about its optical axis, positive clockwise as its
  user sees it from behind (its right side down); the horizon in the image then rises to the
  right.
* Sun directions use the ``sun`` and ``sky`` lights' compass: azimuth 0 = -z (behind the
  camera), 90 = +x (the camera's left), 180 = +z (ahead: the photo is backlit), 270 = -x.

What a calibration can give and what follows (:func:`ground_from_horizon`,
:func:`ground_from_plane`):

* ``camera_height`` + ``pitch`` (+ ``roll``): the pose itself;
* a ground plane ``n . X + d = 0`` in camera coordinates (OpenCV axes; n pointing up, out of the
  ground): the height is d / |n|, the pitch and roll follow from n;
* a horizon (one image row, or two points on it) + ``camera_height``: the pitch (and roll) that
  put the horizon there. Assumed: the ground is flat and level out to the horizon (a road on a
  slope has a vanishing line of its own), the horizon given is the vanishing line of the ground
  (not a skyline of hills or buildings), and with one row only, the camera has no roll.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Any, Dict, List, Optional, Sequence, Tuple

import numpy as np

from .._core import PinholeCamera, SynthgenError

__all__ = ["Calibration", "ground_from_horizon", "ground_from_plane", "sun_from_shadow", "sun_azimuth",
           "sun_direction", "world_from_camera", "fov_to_focal"]


def fov_to_focal(fov_degrees: float, extent_px: float) -> float:
    """Focal length in pixels of a field of view spanning ``extent_px`` pixels."""
    return 0.5 * float(extent_px) / math.tan(0.5 * math.radians(float(fov_degrees)))


def world_from_camera(height: float, pitch: float, roll: float) -> np.ndarray:
    """4x4 world_from_camera (OpenCV camera axes) of a camera ``height`` metres above the ground
    at the world origin, its axis ``pitch`` degrees below the horizontal along +z, turned
    ``roll`` degrees clockwise about its axis."""
    p = math.radians(float(pitch))
    forward = np.array([0.0, -math.sin(p), math.cos(p)])
    eye = np.array([0.0, float(height), 0.0])
    m = np.asarray(PinholeCamera.look_at(eye.tolist(), (eye + forward).tolist(), [0.0, 1.0, 0.0]), np.float64)
    if roll:
        # A clockwise turn of the camera (as its user sees it) about its z (forward) axis: the
        # camera's x (right) axis turns towards its y (down) axis.
        r = math.radians(float(roll))
        rz = np.eye(4)
        rz[:2, :2] = [[math.cos(r), -math.sin(r)], [math.sin(r), math.cos(r)]]
        m = m @ rz
    return m


@dataclass
class Calibration:
    """The camera of a photo (pixels of the photo as stored, after EXIF orientation) and its
    ground. ``source`` and ``assumptions`` say where the numbers came from (recorded in every
    frame's metadata)."""

    width: int
    height: int
    fx: float
    fy: float
    cx: float
    cy: float
    camera_height: float
    pitch: float = 0.0
    roll: float = 0.0
    distortion: Tuple[float, float, float, float, float] = (0.0, 0.0, 0.0, 0.0, 0.0)
    source: str = ""
    assumptions: List[str] = field(default_factory=list)

    # -- the camera --------------------------------------------------------------------------
    def world_from_camera(self) -> np.ndarray:
        return world_from_camera(self.camera_height, self.pitch, self.roll)

    def camera(self, crop: Optional[Tuple[int, int, int, int]] = None) -> PinholeCamera:
        """The PinholeCamera of the photo, or of the crop (x0, y0, width, height) of it: the
        same lens, the principal point shifted."""
        x0, y0, w, h = crop if crop is not None else (0, 0, self.width, self.height)
        return PinholeCamera(float(self.fx), float(self.fy), float(self.cx - x0), float(self.cy - y0), int(w), int(h),
                             self.world_from_camera(), distortion=tuple(float(k) for k in self.distortion))

    def scaled(self, s: float, sy: Optional[float] = None) -> "Calibration":
        """The calibration of the photo resized by ``s`` (by ``s`` along x and ``sy`` along y when
        given; pixel units scale, metric ones do not). NOTE: pixel centres map as
        (u + 0.5) s - 0.5, so the principal point shifts with them."""
        sy = s if sy is None else sy
        return replace(self, width=int(round(self.width * s)), height=int(round(self.height * sy)), fx=self.fx * s,
                       fy=self.fy * sy, cx=(self.cx + 0.5) * s - 0.5, cy=(self.cy + 0.5) * sy - 0.5)

    # -- geometry in the image -----------------------------------------------------------------
    def rays(self, uv: np.ndarray) -> np.ndarray:
        """World-space unit directions of the camera rays through image points uv (N x 2)."""
        cam = self.camera()
        uv = np.atleast_2d(np.asarray(uv, np.float64))
        out = np.empty((len(uv), 3))
        for i, (u, v) in enumerate(uv):
            out[i] = cam.generate_ray(float(u), float(v))[1]
        return out

    def ground_point(self, uv: np.ndarray) -> np.ndarray:
        """World points (N x 3) where the rays through image points uv meet the ground; NaN for
        rays at or above the horizon."""
        d = self.rays(uv)
        t = np.where(d[:, 1] < -1e-9, self.camera_height / np.maximum(-d[:, 1], 1e-12), np.nan)
        p = np.array([0.0, self.camera_height, 0.0]) + t[:, None] * d
        p[:, 1] = 0.0
        return np.where(np.isfinite(t)[:, None], p, np.nan)

    def project(self, points: np.ndarray) -> np.ndarray:
        """Image points (N x 2) of world points (N x 3), through the lens; NaN behind the camera."""
        cam = self.camera()
        out = np.full((len(points), 2), np.nan)
        for i, p in enumerate(np.asarray(points, np.float64)):
            uv = cam.project([float(x) for x in p])
            if uv is not None:
                out[i] = uv
        return out

    def horizon(self) -> Tuple[Tuple[float, float], Tuple[float, float]]:
        """Two image points of the horizon (the vanishing line of the ground) at the left and
        right image borders, for a distortion-free camera (NOTE: with distortion the horizon
        bends; these points are those of the pinhole model)."""
        wfc = self.world_from_camera()
        up_cam = wfc[:3, :3].T @ np.array([0.0, 1.0, 0.0])  # the world's up in camera space
        # Points (x, y, 1) of the normalized image plane with direction . up = 0.
        a, b, c = up_cam
        pts = []
        for u in (0.0, float(self.width)):
            x = (u - self.cx) / self.fx
            y = -(a * x + c) / b if abs(b) > 1e-12 else float("nan")
            pts.append((u, self.fy * y + self.cy))
        return pts[0], pts[1]

    def meta(self) -> Dict[str, Any]:
        return {"width": self.width, "height": self.height, "fx": self.fx, "fy": self.fy, "cx": self.cx,
                "cy": self.cy, "distortion": list(self.distortion), "camera_height": self.camera_height,
                "pitch": self.pitch, "roll": self.roll, "source": self.source, "assumptions": list(self.assumptions)}


def ground_from_horizon(horizon: Sequence[Sequence[float]] | float, fx: float, fy: float, cx: float, cy: float
                        ) -> Tuple[float, float]:
    """(pitch, roll) in degrees that put the horizon (the ground's vanishing line) on an image
    row, or through two image points [(u0, v0), (u1, v1)].

    NOTE: a level camera pitched down by theta sees horizontal directions at
    v = cy - fy tan(theta) on its vertical centre line, so theta = atan((cy - v_h) / fy); with
    two points, see the code (normalized coordinates, exact for any fx, fy)."""
    if isinstance(horizon, (int, float)):
        return math.degrees(math.atan((cy - float(horizon)) / fy)), 0.0
    (u0, v0), (u1, v1) = horizon
    if abs(u1 - u0) < 1e-9:
        raise SynthgenError("horizon: its two points must differ in u (a vertical horizon is no horizon)")
    # NOTE: world_from_camera's up in camera space is (-sin r cos p, -cos r cos p, -sin p), so the
    # horizon (directions (x, y, 1) perpendicular to up) is the line sin r x + cos r y = -tan p
    # of normalized coordinates: its direction (cos r, -sin r) gives the roll, its offset the pitch.
    x0, y0, x1, y1 = (u0 - cx) / fx, (v0 - cy) / fy, (u1 - cx) / fx, (v1 - cy) / fy
    if x1 < x0:
        x0, y0, x1, y1 = x1, y1, x0, y0
    roll = math.atan2(-(y1 - y0), x1 - x0)
    dist = -(math.sin(roll) * x0 + math.cos(roll) * y0)
    return math.degrees(math.atan(dist)), math.degrees(roll)


def ground_from_plane(normal: Sequence[float], offset: float) -> Tuple[float, float, float]:
    """(camera_height, pitch, roll) of a ground plane n . X + offset = 0 given in camera
    coordinates (OpenCV axes), n its normal pointing up (out of the ground, towards the camera).

    NOTE: the camera (X = 0) is at distance offset / |n| from the plane: its height. The world's
    up in camera space is n / |n|; :func:`world_from_camera` gives up = (-sin r cos p,
    -cos r cos p, -sin p) for pitch p and roll r, hence p = asin(-n_z), r = atan2(-n_x, -n_y)."""
    n = np.asarray(normal, np.float64)
    norm = float(np.linalg.norm(n))
    if not norm > 0 or not np.all(np.isfinite(n)):
        raise SynthgenError("ground plane: the normal must be a non-zero finite vector")
    n = n / norm
    height = float(offset) / norm
    if not height > 0:
        raise SynthgenError(f"ground plane: the camera must be above the ground (n . X + d = 0 with the normal "
                            f"pointing up gives height d / |n| = {height:g} m)")
    # world_from_camera(h, pitch, roll) maps the world's up to camera space as
    # up_cam = Rz(roll)^T (0, -cos p, -sin p)... solve for p and roll.
    pitch = math.degrees(math.asin(max(-1.0, min(1.0, -float(n[2])))))
    roll = math.degrees(math.atan2(-float(n[0]), -float(n[1])))
    return height, pitch, roll


def sun_from_shadow(cal: Calibration, base: Sequence[float], tip: Sequence[float],
                    top: Optional[Sequence[float]] = None, object_height: Optional[float] = None
                    ) -> Tuple[float, float]:
    """(azimuth, elevation) in degrees of the sun (the ``sun`` light's compass, see the module
    docstring), from a vertical object's base point and the tip of its shadow marked in the
    photo (both on the ground), and the object's height: given in metres, or from its top point
    marked in the photo.

    NOTE: the shadow of a vertical object of height H is the ground segment from its base away
    from the sun, of length H / tan(elevation): elevation = atan(H / length), and the sun lies
    in the direction from the tip to the base."""
    b, t = cal.ground_point(np.array([base, tip], np.float64))
    if not (np.all(np.isfinite(b)) and np.all(np.isfinite(t))):
        raise SynthgenError("marked shadow: its base and tip must lie below the horizon (on the ground)")
    if object_height is None:
        if top is None:
            raise SynthgenError("marked shadow: give the object's height in metres or its top point")
        object_height = _height_from_top(cal, b, top)
    length = float(np.hypot(*(t - b)[[0, 2]]))
    if not length > 1e-6:
        raise SynthgenError("marked shadow: the tip coincides with the base")
    elevation = math.degrees(math.atan2(float(object_height), length))
    d = b - t  # from the shadow's tip towards the object: towards the sun
    return sun_azimuth(d), elevation


def sun_azimuth(direction: Sequence[float]) -> float:
    """Compass azimuth in [0, 360) degrees of a world direction (its horizontal part), in the
    ``sun`` light's convention: 0 = -z, 90 = +x, 180 = +z."""
    d = np.asarray(direction, np.float64)
    return math.degrees(math.atan2(float(d[0]), -float(d[2]))) % 360.0


def sun_direction(azimuth: float, elevation: float) -> np.ndarray:
    """Unit world direction towards the sun of a compass azimuth and an elevation (degrees)."""
    az, el = math.radians(float(azimuth)), math.radians(float(elevation))
    return np.array([math.cos(el) * math.sin(az), math.sin(el), -math.cos(el) * math.cos(az)])


def _height_from_top(cal: Calibration, base: np.ndarray, top: Sequence[float]) -> float:
    """Height of a vertical segment from its base (a ground point) to the point whose image is
    ``top``: the point of the vertical line through the base closest to the top's camera ray."""
    c = np.array([0.0, cal.camera_height, 0.0])
    d = cal.rays(np.array([top], np.float64))[0]
    up = np.array([0.0, 1.0, 0.0])
    # Closest points of the lines c + s d and base + h up.
    w0 = c - base
    a, bb, cc, dd, e = d @ d, d @ up, up @ up, d @ w0, up @ w0
    den = a * cc - bb * bb
    if abs(den) < 1e-12:
        raise SynthgenError("marked shadow: the top's ray is parallel to the object")
    h = (a * e - bb * dd) / den
    if not h > 0:
        raise SynthgenError("marked shadow: the marked top is not above the base")
    return float(h)
