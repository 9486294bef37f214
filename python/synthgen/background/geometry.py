"""Whether a photo's geometry lets anything stand in it: the checks ``synthgen validate`` (with the
scenario's distances and objects) and ``synthgen calibrate`` (with a reference car) make of a
calibration before a run would drop every object it places.

:func:`geometry_findings` looks at the photo's ground through its camera (a grid of 128 x 128
cells over the photo, each cell's corners cast onto the ground through the lens) and reports:

* errors -- the run cannot place anything: the horizon below the image (no ground in view), a
  placement region outside the photo or entirely above the horizon, a region whose ground lies
  nowhere between ``min_distance`` and ``max_distance``, a region inside the image whose ground
  there is smaller than an object's footprint;
* warnings -- merely suspicious: the horizon more than an image height above the image (a
  camera looking steeply down), a camera height outside 0.1 to 30 m, a footprint larger than
  the region's ground where the region reaches the image's border (only objects sticking out of
  the image can stand there); without a scenario (``synthgen calibrate``: the default distances
  and a reference car), the distance and footprint findings too.

Each finding names the calibration file, line, column and key it comes from (the key's
position as :func:`synthgen.background.sidecar.read_photo_setup` recorded it), and the numbers.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import List, Sequence, Tuple

import numpy as np

from .labels import PolygonSet
from .sidecar import PhotoSetup

__all__ = ["Finding", "geometry_findings", "CAMERA_HEIGHT_RANGE", "GRID"]

#: Camera heights (metres) a road photo's camera plausibly has: a toy or a kerb camera to a mast or
#: a bridge; outside them a calibration is suspicious (a warning).
CAMERA_HEIGHT_RANGE = (0.1, 30.0)
#: Cells of the ground grid across and down the photo.
GRID = 128


@dataclass
class Finding:
    """One problem of a photo's geometry: an error (nothing can be placed) or a warning."""

    error: bool
    file: str          #: the calibration file (or the photo when no key applies)
    line: int
    column: int
    key: str           #: the calibration key, e.g. ``ground.horizon``
    message: str

    def __str__(self) -> str:
        where = f"{self.file}:{self.line}:{self.column}" if self.line else self.file
        return f"{where}: {self.key}: {self.message}"


def _find(setup: PhotoSetup, error: bool, keys: Sequence[str], message: str) -> Finding:
    """A finding at the first of ``keys`` the calibration gives (else at the photo)."""
    for k in keys:
        if k in setup.where:
            f, line, col = setup.where[k]
            return Finding(error, f, line, col, k, message)
    return Finding(error, setup.photo, 0, 0, keys[0] if keys else "", message)


#: Where a calibration puts its ground, most specific first.
GROUND_KEYS = ("ground.horizon", "ground.pitch", "ground.plane", "ground.from_depth", "ground", "cityscapes")


def geometry_findings(setup: PhotoSetup, min_distance: float, max_distance: float,
                      footprints: Sequence[Tuple[str, float, float]] = (),
                      distance_keys: str = "background.min_distance .. max_distance",
                      scenario: bool = True) -> List[Finding]:
    """The errors and warnings of a photo's geometry (see the module docstring) for objects
    standing ``min_distance`` .. ``max_distance`` metres from the camera; ``footprints``: (what,
    length, width in metres) of the smallest object of each kind that must stand in the region;
    ``distance_keys`` names where the distances come from in messages. ``scenario`` False (no
    scenario: default distances, a reference object): what depends on the distances and the
    objects is a warning only."""
    cal = setup.calibration
    w, h = cal.width, cal.height
    out: List[Finding] = []
    # -- the camera ---------------------------------------------------------------------------------
    lo, hi = CAMERA_HEIGHT_RANGE
    if not lo <= cal.camera_height <= hi:
        out.append(_find(setup, False, ("ground.camera_height", "ground.plane", "ground.from_depth", "ground",
                                        "cityscapes"),
                         f"the camera stands {cal.camera_height:g} m above the ground: a road photo's camera "
                         f"stands {lo:g} to {hi:g} m high (a dashboard about 1.3 m, a mast or a bridge up to 30 m)"))
    # The horizon's row at the image's centre column (pinhole model).
    (u0, v0), (u1, v1) = cal.horizon()
    vh = v0 + (v1 - v0) * (0.5 * w - u0) / (u1 - u0) if math.isfinite(v0) and math.isfinite(v1) else float("nan")
    # -- the ground in view: a grid of cells, their corners cast onto the ground ---------------------
    us, vs = np.linspace(0.0, w, GRID + 1), np.linspace(0.0, h, GRID + 1)
    corners = np.stack(np.meshgrid(us, vs), -1).reshape(-1, 2)
    g = cal.ground_point(corners)[:, [0, 2]].reshape(GRID + 1, GRID + 1, 2)
    q = np.stack([g[:-1, :-1], g[:-1, 1:], g[1:, 1:], g[1:, :-1]], 2)          # cells x 4 corners x (x, z)
    on_ground = np.all(np.isfinite(q[..., 0]), axis=2)
    if not on_ground.any():
        where = (f"{vh - h:.0f} px below the image (row {vh:.0f} of a photo {h} px high)" if math.isfinite(vh)
                 else "out of the image")
        out.append(_find(setup, True, GROUND_KEYS,
                         f"the horizon lies {where}, pitch {cal.pitch:.1f} deg: the photo shows no ground, nothing "
                         f"inserted can stand on it"))
        return out
    if math.isfinite(vh) and vh < -h:
        out.append(_find(setup, False, GROUND_KEYS,
                         f"the horizon lies {-vh:.0f} px above the image (row {vh:.0f} of a photo {h} px high), pitch "
                         f"{cal.pitch:.1f} deg: a camera looking this steeply down is unusual for a road photo; "
                         f"check the horizon or pitch"))
    xs = 0.5 * (us[:-1] + us[1:])
    ys = 0.5 * (vs[:-1] + vs[1:])
    centres = np.stack(np.meshgrid(xs, ys), -1).reshape(-1, 2)
    region_keys = ("region",) if setup.regions else GROUND_KEYS
    if setup.regions:
        inside = PolygonSet(setup.regions).contains(centres).reshape(GRID, GRID)
        allp = np.concatenate([np.asarray(p, np.float64) for p in setup.regions])
        rows = f"rows {allp[:, 1].min():.0f} to {allp[:, 1].max():.0f}"
        if not inside.any():
            out.append(_find(setup, True, region_keys,
                             f"the placement region ({rows}, columns {allp[:, 0].min():.0f} to "
                             f"{allp[:, 0].max():.0f}) lies outside the photo ({w} x {h}): nothing can stand there"))
            return out
        if not (inside & on_ground).any():
            out.append(_find(setup, True, region_keys,
                             f"the placement region ({rows}) lies entirely above the horizon (row {vh:.0f}): nothing "
                             f"can stand there"))
            return out
    else:
        inside = np.ones((GRID, GRID), bool)
    cells = inside & on_ground
    # Each cell's ground area (its quad's, shoelace) and distance (its corners' mean) from the camera.
    x, z = q[..., 0], q[..., 1]
    area = 0.5 * np.abs(np.sum(x * np.roll(z, -1, axis=2) - np.roll(x, -1, axis=2) * z, axis=2))
    dist = np.hypot(x.mean(axis=2), z.mean(axis=2))
    d = dist[cells]
    ok = cells & (dist >= min_distance) & (dist <= max_distance)
    if not ok.any():
        out.append(_find(setup, scenario, region_keys + ("ground.camera_height",),
                         f"the {'placement region' if setup.regions else 'ground in view'} lies {d.min():.1f} to "
                         f"{d.max():.1f} m from the camera (camera height {cal.camera_height:g} m), none of it "
                         f"within {distance_keys} ({min_distance:g} .. {max_distance:g} m): nothing can be placed"))
        return out
    ground = float(area[ok].sum())
    border = bool(ok[0, :].any() or ok[-1, :].any() or ok[:, 0].any() or ok[:, -1].any())
    for what, length, width in footprints:
        if length * width > ground:
            out.append(_find(setup, scenario and not border, region_keys,
                             f"the {'placement region' if setup.regions else 'ground in view'}'s ground within "
                             f"{min_distance:g} .. {max_distance:g} m covers {ground:.1f} m^2, less than the footprint "
                             f"of {what} ({length:.2f} x {width:.2f} m = {length * width:.1f} m^2): "
                             + ("only objects sticking out of the image can stand there" if border
                                else "it cannot stand there")))
    return out

