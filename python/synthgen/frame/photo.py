"""A frame inserted into a real photo (the scenario's ``background``): the photo's camera and
ground, placement on its ground inside its region and clear of its real objects, its light,
the composite by differential rendering, real occluders, and the labels of real and inserted
objects together.

The world is the photo's (synthgen.background.calibration): y up, the ground y = 0, the camera
above the origin looking along +z. The ground is a shadow catcher (``Scene.set_instance_catcher``):
rendered with and without the inserted objects, never labelled.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Dict, List, Mapping, Optional, Sequence, Tuple

import numpy as np

from .._core import SynthgenError
from ..background.labels import PolygonSet, object_mask, polygon_mask
from ..background.photoset import FramePhoto
from ..post.photo.composite import composite

__all__ = ["PhotoPlacement", "photo_lights", "ground_albedo", "exposure_factor", "finish_photo_frame",
           "road_yaw", "MIN_REAL_VISIBLE", "photo_dome"]

#: Real objects an inserted one covers more than this fraction of (by pixels) keep their label,
#: with its visible fraction; below this visible fraction they become ignore regions.
MIN_REAL_VISIBLE = 0.1


def road_yaw(road_direction: float) -> float:
    """The ``yaw`` (about +y, degrees) that turns an object's forward (+x) along the road, which
    runs ``road_direction`` degrees to the right of the camera's forward (+z)."""
    return -90.0 - float(road_direction)


@dataclass
class PhotoPlacement:
    """Where objects may stand in a photo: spots drawn in its placement region (pixels; by
    default the image below the horizon), at min..max distance, whose footprint lies in the
    region, and which hides little of a real object or an ignore region behind it, and is
    hidden little by one in front of it (at most ``max_overlap`` of the farther box) -- and not
    at all by one known only by its box."""

    fp: FramePhoto
    camera: Any
    min_distance: float
    max_distance: float
    max_overlap: float
    real_boxes: List[Tuple[float, float, float, float]] = field(default_factory=list)

    def __post_init__(self):
        self.real_boxes = [tuple(o.box) for o in self.fp.objects]
        self.real_outlined = [o.polygon is not None for o in self.fp.objects]
        w, h = self.camera.width, self.camera.height
        if self.fp.regions:
            self.polys = self.fp.regions
        else:
            (u0, v0), (u1, v1) = self.fp.calibration.horizon()
            (u0, v0), (u1, v1) = (u0 - self.fp.crop[0], v0 - self.fp.crop[1]), (u1 - self.fp.crop[0], v1 - self.fp.crop[1])
            # Below the horizon (2 % of the height below it: the far ground is ill-conditioned).
            m = 0.02 * h
            vl = v0 + (v1 - v0) * (0 - u0) / (u1 - u0) + m
            vr = v0 + (v1 - v0) * (w - u0) / (u1 - u0) + m
            self.polys = [np.array([[0.0, vl], [w, vr], [w, h], [0.0, h]])]
        self.region = PolygonSet(self.polys)
        allp = np.concatenate(self.polys)
        self.bounds = (max(allp[:, 0].min(), 0.0), max(allp[:, 1].min(), 0.0), min(allp[:, 0].max(), w),
                       min(allp[:, 1].max(), h))

    def _ground(self, u: float, v: float) -> Optional[np.ndarray]:
        o, d = self.camera.generate_ray(float(u), float(v))
        o, d = np.asarray(o, np.float64), np.asarray(d, np.float64)
        if d[1] >= -1e-9:
            return None
        return o + (-o[1] / d[1]) * d

    def sample(self, rng: np.random.Generator) -> Tuple[float, float]:
        """A ground spot (x, z) under a pixel drawn uniformly in the region, within the distance
        range; NaN when 50 draws found none."""
        x0, y0, x1, y1 = self.bounds
        if not (x1 > x0 and y1 > y0):
            return float("nan"), float("nan")
        cam = np.asarray(self.camera.world_from_camera, np.float64)[:3, 3]
        for _ in range(50):
            uv = np.array([[rng.uniform(x0, x1), rng.uniform(y0, y1)]])
            if not self.region.contains(uv)[0]:
                continue
            g = self._ground(*uv[0])
            if g is None:
                continue
            dist = math.hypot(g[0] - cam[0], g[2] - cam[2])
            if self.min_distance <= dist <= self.max_distance:
                return float(g[0]), float(g[2])
        return float("nan"), float("nan")

    def accepts(self, corners_world: np.ndarray) -> bool:
        """An object whose box has these 8 world corners: in front of the camera, its footprint
        (the 4 lowest corners) in the region, its image box over no real box by more than
        max_overlap of the farther one's box, and behind no real object known only by its box
        (no polygon)."""
        corners_world = np.asarray(corners_world, np.float64)
        uv_all = self.camera.project_points(corners_world)
        if np.isnan(uv_all).any():
            return False
        uv = uv_all[np.argsort(corners_world[:, 1])[:4]]
        # The region covers the image only: corners outside the image (a truncated object) pass.
        w, h = self.camera.width, self.camera.height
        seen = (uv[:, 0] >= 0) & (uv[:, 0] <= w) & (uv[:, 1] >= 0) & (uv[:, 1] <= h)
        if not np.all(self.region.contains(uv[seen])):
            return False
        box = (float(uv_all[:, 0].min()), float(uv_all[:, 1].min()), float(uv_all[:, 0].max()),
               float(uv_all[:, 1].max()))
        own = max((box[2] - box[0]) * (box[3] - box[1]), 1e-9)
        for rb, outlined in zip(self.real_boxes, self.real_outlined):
            ix = max(0.0, min(box[2], rb[2]) - max(box[0], rb[0]))
            iy = max(0.0, min(box[3], rb[3]) - max(box[1], rb[1]))
            area = (rb[2] - rb[0]) * (rb[3] - rb[1])
            # Whichever is farther (its box's bottom higher in the image: both stand on the
            # ground) is hidden by the other: at most max_overlap of it.
            real_in_front = rb[3] >= box[3]
            hidden = own if real_in_front else area
            # A real object known only by its box would hide the inserted one by that whole
            # rectangle, background corners included (a rectangular notch cut out of the object):
            # nothing inserted stands behind one.
            limit = self.max_overlap if outlined or not real_in_front else 0.0
            if hidden > 0 and ix * iy / hidden > limit:
                return False
        return True


def envmap_rotation_to(path: str, azimuth: float) -> float:
    """The ``rotation`` of an equirectangular map that puts its sun (the pixels within 10 % of
    the brightest luminance, their circular mean) at compass ``azimuth``. NOTE: envmap's world_from_map is a right-handed turn by
    the rotation r about +y, which takes map azimuth m to world azimuth m - r (u = m / 360 in the
    map), so r = m - azimuth."""
    from .._core import read_image

    img = read_image(path)
    lum = img[..., :3] @ np.array([0.2126, 0.7152, 0.0722], np.float32) if img.shape[2] >= 3 else img[..., 0]
    # The sun's disc: pixels within 10 % of the brightest, their circular mean azimuth.
    ys, xs = np.nonzero(lum >= 0.9 * float(lum.max()))
    a = 2.0 * np.pi * (xs + 0.5) / lum.shape[1]
    m = float(np.degrees(np.arctan2(np.sin(a).mean(), np.cos(a).mean()))) % 360.0
    return float((m - azimuth) % 360.0)


def photo_lights(fp: FramePhoto, scenario_lights: List[Tuple[str, Dict[str, Any]]]
                 ) -> Tuple[List[Tuple[str, Dict[str, Any]]], Dict[str, Any]]:
    """The lights of a photo frame and how they were chosen: the photo's HDR environment
    (rotated as given), else a clear sky whose sun stands where the photo's does, else an
    overcast sky when the photo says so, else the scenario's lights (a fallback: flagged, since
    its sun contradicts the shadows the photo shows)."""
    s = fp.setup
    if s.envmap is not None:
        path, rot = s.envmap
        how = "the photo's environment map"
        if rot is None:
            rot = 0.0
            if s.sun is not None:
                rot = envmap_rotation_to(path, s.sun[0])
                how += f" turned so that its sun stands at the photo's sun azimuth ({rot:.1f} degrees)"
        return [("envmap", {"file": path, "rotation": rot})], {"lighting": how}
    if s.sun is not None:
        az, el = s.sun
        return [("sky", {"elevation": max(0.0, min(90.0, el)), "azimuth": az, "strength": 0.02})], \
            {"lighting": f"sky with the photo's sun ({s.sun_source})"}
    if s.overcast:
        return [("environment", {"radiance": 1.0})], {"lighting": "overcast (uniform sky), as the photo says"}
    return scenario_lights, {"lighting": "the scenario's lights (fallback: the photo gives no sun; shadows may "
                                         "contradict the photo's)", "lighting_fallback": True}


def photo_dome(photo: np.ndarray, calibration: Any, width: int = 512) -> np.ndarray:
    """The photo projected onto a distant dome: an equirectangular map (width x width/2, the
    ``envmap`` convention: top row up, centre +z) whose directions the photo's camera sees hold
    the photo's (linear) pixels, bilinearly; the others the mean of the photo's top rows (above
    the horizon) or bottom rows (below). What inserted objects reflect (envmap reflection_only)."""
    h = width // 2
    v = (np.arange(h) + 0.5) / h
    u = (np.arange(width) + 0.5) / width
    theta, phi = np.pi * v[:, None], 2 * np.pi * u[None, :]
    d = np.stack([np.sin(theta) * np.sin(phi), np.cos(theta) * np.ones_like(phi), -np.sin(theta) * np.cos(phi)], -1)
    wfc = calibration.world_from_camera()
    pc = d @ wfc[:3, :3]  # camera-space directions (rows: R^T d)
    ph, pw = photo.shape[:2]
    top = photo[: max(1, ph // 7)].reshape(-1, 3).mean(axis=0)
    bottom = photo[-max(1, ph // 5):].reshape(-1, 3).mean(axis=0)
    out = np.where((d[..., 1] >= 0)[..., None], top, bottom).astype(np.float32)
    front = pc[..., 2] > 1e-6
    x = np.where(front, pc[..., 0] / np.where(front, pc[..., 2], 1.0), 0.0)
    y = np.where(front, pc[..., 1] / np.where(front, pc[..., 2], 1.0), 0.0)
    cam = calibration.camera()
    if any(calibration.distortion):
        xy = np.array([cam.distort(float(a), float(b)) if f else (0.0, 0.0)
                       for a, b, f in zip(x.ravel(), y.ravel(), front.ravel())]).reshape(h, width, 2)
        x, y = xy[..., 0], xy[..., 1]
    px = calibration.fx * x + calibration.cx - 0.5
    py = calibration.fy * y + calibration.cy - 0.5
    inside = front & (px >= 0) & (px <= pw - 1) & (py >= 0) & (py <= ph - 1)
    # NOTE: directions far outside the photo (past a barrel lens's fold) map to NaN or to
    # coordinates beyond any integer; they are outside (the means above), so they are clipped
    # to the photo before the cast instead of after it.
    px = np.clip(np.nan_to_num(px, nan=-1.0), -1.0, float(pw))
    py = np.clip(np.nan_to_num(py, nan=-1.0), -1.0, float(ph))
    x0 = np.clip(np.floor(px).astype(int), 0, pw - 2)
    y0 = np.clip(np.floor(py).astype(int), 0, ph - 2)
    fx, fy = np.clip(px - x0, 0, 1)[..., None], np.clip(py - y0, 0, 1)[..., None]
    s = ((1 - fx) * (1 - fy) * photo[y0, x0] + fx * (1 - fy) * photo[y0, x0 + 1] + (1 - fx) * fy * photo[y0 + 1, x0] +
         fx * fy * photo[y0 + 1, x0 + 1])
    return np.where(inside[..., None], s, out).astype(np.float32)


def ground_albedo(fp: FramePhoto, given: Optional[Sequence[float]]) -> List[float]:
    """The catcher's albedo: given, or an asphalt-like 0.15 tinted by the median colour of the
    photo's ground (the region, or the lower third)."""
    if given is not None:
        return [float(v) for v in given]
    h, w = fp.pixels.shape[:2]
    if fp.regions:
        mask = np.zeros((h, w), bool)
        for p in fp.regions:
            mask |= polygon_mask(p, w, h)
    else:
        mask = np.zeros((h, w), bool)
        mask[2 * h // 3:] = True
    px = fp.pixels[mask] if mask.any() else fp.pixels.reshape(-1, 3)
    med = np.median(px, axis=0)
    tint = med / max(float(med.mean()), 1e-6)
    return [float(v) for v in np.clip(0.15 * tint, 0.02, 0.6)]


def _lum(rgb: np.ndarray) -> np.ndarray:
    return rgb @ np.array([0.2126, 0.7152, 0.0722], np.float32)


def exposure_factor(photo: np.ndarray, without: np.ndarray, synthetic_alpha: np.ndarray, ground: np.ndarray,
                    boxes: Sequence[Sequence[float]], exclude: np.ndarray) -> Tuple[np.ndarray, str]:
    """Per channel, the factor that makes the rendered ground match the photo's: the luminance
    factor is the median over ground pixels in a ring around each object's box (twice its size;
    none of the object, not a real object) of photo / rendered luminance without the objects
    (over all the ground when the rings hold fewer than 50 pixels); the channels' ratios of
    means there give the white balance (clamped to 0.7 .. 1.4 of it). NOTE: radiance is linear
    in the lights, so scaling the render afterwards is the same as scaling the lights."""
    h, w = ground.shape
    ring = np.zeros((h, w), bool)
    for x0, y0, x1, y1 in boxes:
        cx, cy, bw, bh = 0.5 * (x0 + x1), 0.5 * (y0 + y1), x1 - x0, y1 - y0
        a0, a1 = int(max(0, math.floor(cx - bw))), int(min(w, math.ceil(cx + bw)))
        b0, b1 = int(max(0, math.floor(cy - bh))), int(min(h, math.ceil(cy + bh)))
        ring[b0:b1, a0:a1] = True
    usable = ground & (synthetic_alpha == 0) & ~exclude
    lw = _lum(without)
    lp = _lum(photo)
    sel = ring & usable & (lw > 1e-6)
    where = "ring around the objects"
    if sel.sum() < 50:
        sel = usable & (lw > 1e-6)
        where = "the whole ground"
    if sel.sum() < 10:
        return np.ones(3, np.float32), "no ground visible: 1"
    k = float(np.median(lp[sel] / lw[sel]))
    chroma = photo[sel].mean(axis=0) / np.maximum(without[sel].mean(axis=0), 1e-9)
    chroma = chroma / max(float(_lum(chroma[None])[0]), 1e-9)
    return (k * np.clip(chroma, 0.7, 1.4)).astype(np.float32), where


def frame_exposure(fp: FramePhoto, res: Any, ids: np.ndarray, depth: np.ndarray,
                   boxes: Sequence[Sequence[float]]) -> Tuple[np.ndarray, str]:
    """:func:`exposure_factor` of a photo frame's render: its ground (instance 0, finite depth;
    within the placement region when the photo has one) without the objects, in rings around
    ``boxes``, real objects' boxes excluded."""
    ground = (ids == 0) & np.isfinite(depth)
    exclude = np.zeros(ids.shape, bool)
    h, w = ids.shape
    if fp.regions:
        # NOTE: the catcher's albedo is tinted by the region's median colour (ground_albedo),
        # so only there is photo / render the light's colour; a ring reaching grass or trees
        # below the horizon would take their colour for the light's.
        region = np.zeros((h, w), bool)
        for p in fp.regions:
            region |= polygon_mask(p, w, h)
        ground &= region
    for o in fp.objects:
        x0, y0, x1, y1 = (int(round(v)) for v in o.box)
        exclude[max(y0, 0):min(y1, h), max(x0, 0):min(x1, w)] = True
    return exposure_factor(fp.pixels, np.asarray(res.catcher_without) + np.asarray(res.behind_synthetic),
                           np.asarray(res.synthetic_alpha), ground, boxes, exclude)


def real_object_depth(fp: FramePhoto, camera: Any) -> np.ndarray:
    """H x W camera-space depth of the photo's outlined real objects (and ignore regions) as
    the calibration places them: each stands on the ground at its box's bottom edge, upright, so
    its depth is that of the ground point below its bottom centre (a billboard over its
    polygon); +inf elsewhere. Where a real object is nearer than an inserted one, it hides it.
    One known only by its box hides nothing: its rectangle's corners are background, and
    placement (PhotoPlacement.accepts) puts nothing behind it."""
    h, w = camera.height, camera.width
    out = np.full((h, w), np.inf, np.float32)
    wfc = np.asarray(camera.world_from_camera, np.float64)
    cfw = np.linalg.inv(wfc)
    for o in fp.objects:
        if o.polygon is None:
            continue
        x0, y0, x1, y1 = o.box
        full = getattr(o, "full_box", list(o.box))
        if full[3] > h + 0.5:
            continue  # its bottom is cut by the image: where it stands is unknown
        org, d = camera.generate_ray(0.5 * (x0 + x1), float(min(y1, h - 1e-3)))
        org, d = np.asarray(org, np.float64), np.asarray(d, np.float64)
        if d[1] >= -1e-9:
            continue
        g = org + (-org[1] / d[1]) * d
        z = float((cfw @ np.r_[g, 1.0])[2])
        out = np.where(polygon_mask(o.polygon, w, h), np.minimum(out, z), out)
    return out


def finish_photo_frame(fp: FramePhoto, res: Any, arrays: Dict[str, np.ndarray], mode: str,
                       boxes: Sequence[Sequence[float]], real_depth: Optional[np.ndarray],
                       occluder_mask: Optional[np.ndarray], camera: Any = None,
                       match: Optional[Mapping[str, Any]] = None, rng: Optional[np.random.Generator] = None,
                       sampling: Optional[Dict[str, Any]] = None) -> Tuple[Dict[str, np.ndarray], Dict[str, Any]]:
    """The composite and the labels of a photo frame (arrays from the render, ``boxes`` the
    inserted objects' boxes as x0, y0, x1, y1), then camera matching (``match``: the scenario's
    background.match); returns (arrays, meta). ``sampling``: what
    :func:`synthgen.frame.photo_samples.refine_objects` did, recorded as ``camera_match.sampling``;
    its objects short of their noise target join ``camera_match.unmatched`` (check
    "render_noise")."""
    ids = np.asarray(arrays["instance_id"])
    depth = np.asarray(arrays["depth"], np.float32)
    k, where = frame_exposure(fp, res, ids, depth, boxes)
    rgb = composite(fp.pixels, res, mode, exposure=k)
    # Real things in front of the inserted objects: the photo's nearer depth, or the occluder mask.
    synthetic = ids > 0
    front = np.zeros(ids.shape, bool)
    if real_depth is not None:
        front |= np.isfinite(real_depth) & (real_depth < depth)
    labelled_depth = real_object_depth(fp, camera) if camera is not None and fp.objects else None
    if labelled_depth is not None:
        front |= np.isfinite(labelled_depth) & (labelled_depth < depth)
    if occluder_mask is not None:
        front |= occluder_mask
    if front.any():
        rgb = np.where(front[..., None], fp.pixels, rgb)
    camera_info: Dict[str, Any] = {}
    if match is not None and (match["noise"] or match["blur"] or match["jpeg"] or match["vignetting"] or
                              match["chromatic_aberration"]):
        from ..post.photo.camera_match import match_camera

        influence = ((np.asarray(res.synthetic_alpha) > 0) |
                     np.any(np.asarray(res.catcher_with) != np.asarray(res.catcher_without), axis=2)) & ~front
        cam = camera if camera is not None else fp.camera()
        rgb, camera_info = match_camera(
            fp.pixels, rgb, influence, rng if rng is not None else np.random.default_rng(0),
            jpeg_quality=fp.photo.jpeg_quality if match["jpeg"] else None, noise=match["noise"],
            blur=match["blur"], vignetting=match["vignetting"], chromatic=match["chromatic_aberration"],
            cx=float(cam.cx), cy=float(cam.cy), focal=float(cam.fx),
            synthetic=np.where(front, 0.0, np.asarray(res.synthetic_alpha)), ids=ids,
            albedo=arrays.get("albedo"), normal=arrays.get("normal"), denoise=match["denoise"])
        if front.any():  # what real things hide stays the photo's (blur may have spread into it)
            rgb = np.where(front[..., None], fp.pixels, rgb)
    if sampling is not None:
        camera_info["sampling"] = sampling
        short = {o: [{"check": "render_noise", "noise": r["achieved"], "target": r["target"],
                      "photo_noise": r["photo_noise"], "spp_mean": r["spp_mean"], "cap_spp": sampling["cap_spp"]}]
                 for o, r in sampling["objects"].items() if not r["reached"]}
        if short:
            merged = dict(short)
            for o, checks in camera_info.get("unmatched", {}).items():
                merged[o] = merged.get(o, []) + checks
            camera_info["unmatched"] = merged
    out = dict(arrays)
    out["rgb"] = rgb.astype(np.float32)
    out["instance_id"] = np.where(front, 0, ids).astype(ids.dtype)
    out["class_id"] = np.where(front, 0, np.asarray(arrays["class_id"])).astype(ids.dtype)
    visible = synthetic & ~front
    # Depth, normals and albedo are those of the inserted objects (and the photo's depth map);
    # the calibrated ground is a model, not a measurement of the photo.
    base_depth = real_depth if real_depth is not None else np.full(ids.shape, np.inf, np.float32)
    out["depth"] = np.where(visible, depth, base_depth).astype(np.float32)
    for key in ("normal", "albedo"):
        if key in out:
            out[key] = np.where(visible[..., None], out[key], 0.0).astype(np.float32)
    meta = {"exposure": {"factor": float(_lum(k[None])[0]), "white_balance": [float(v) for v in k / _lum(k[None])[0]],
                         "from": where}, "composite": mode,
            "camera_match": camera_info,
            "real_occlusion": {"pixels": int((synthetic & front).sum()),
                               "by": [s for s, m in (("depth", real_depth), ("mask", occluder_mask),
                                                     ("real labels", labelled_depth)) if m is not None]}}
    return out, meta


def real_object_records(fp: FramePhoto, instance_id: np.ndarray, class_names: Sequence[str]) -> List[Dict[str, Any]]:
    """The real objects of a frame for the outputs: class (the scenario's), box in the image,
    polygon, ignore, and the fraction an inserted object leaves visible (a real object mostly
    hidden becomes an ignore region)."""
    h, w = instance_id.shape
    covered = instance_id > 0
    out = []
    for i, o in enumerate(fp.objects):
        if not o.ignore and o.cls not in class_names:  # validation refuses these (labels.check_classes)
            raise SynthgenError(f"{o.source}: real object of class '{o.cls}', not a class of the scenario "
                                f"({', '.join(class_names)}): it would be left out of the labels")
        mask = object_mask(o.polygon, o.box, w, h)
        area = int(mask.sum())
        vis = float((mask & ~covered).sum() / area) if area else 0.0
        full = getattr(o, "full_box", list(o.box))
        full_area = max((full[2] - full[0]) * (full[3] - full[1]), 1e-9)
        inside_area = (o.box[2] - o.box[0]) * (o.box[3] - o.box[1])
        rec = {"index": i, "source": "real", "class": None if o.ignore else o.cls,
               "class_id": 0 if o.ignore else class_names.index(o.cls) + 1,
               "ignore": bool(o.ignore or vis < MIN_REAL_VISIBLE),
               "bbox": [float(v) for v in o.box], "visible_fraction": vis,
               "truncation": float(max(0.0, 1.0 - inside_area / full_area)), "from": o.source}
        if o.polygon is not None:
            rec["polygon"] = np.asarray(o.polygon, float).round(2).tolist()
        if o.ignore:
            rec["what"] = o.cls
        out.append(rec)
    return out
