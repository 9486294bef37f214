"""Objects inserted into a photo rendered until they are less noisy than the photo.

Camera matching (:mod:`synthgen.post.photo.camera_match`) adds to each inserted object only the
noise it lacks: an object whose Monte Carlo noise already exceeds the photo's cannot be matched
(its noise loop drives the gain to 0 and stays above target). So, after the frame's render,
:func:`refine_objects` renders each object again -- a crop of the image around it (its box, its
edges and the shadow under it) with the same camera, scene and settings -- with adaptive
sampling (``noise_threshold``, ``cpp/integrator/adaptive.h``) whose target is a fraction of the
photo's noise at the object's level, from the frame's samples per pixel up to a cap, and puts
the crop's buffers in place of the frame's. Labels stay the frame's (the crop's pixel-centre
rays are the same rays). Everything is a function of the frame's render, its photo and seed:
the crops, their thresholds and seeds, and the renderer's rounds are bit-identical for any
thread count.

Per object, ``info["objects"]`` records the photo's noise at its level, the target, the noise
achieved (both as sRGB sigmas, as :func:`synthgen.post.photo.measure.fit_noise` measures the
photo's), its samples and whether the cap stopped it short (``reached``: false).
"""
from __future__ import annotations

import math
from typing import Any, Dict, List, Mapping, Optional, Tuple

import numpy as np

from ..post.photo.composite import influence_mask
from ..post.photo.measure import dilate, fit_noise, srgb
from ..post.quality import estimate_noise

__all__ = ["refine_objects", "PatchedResult", "srgb_slope", "DEFAULT_FRACTION", "DEFAULT_CAP_FACTOR"]

#: The objects' render noise target: this fraction of the photo's noise sigma at their level.
DEFAULT_FRACTION = 0.5
#: The default sample cap: this many times the render's spp.
DEFAULT_CAP_FACTOR = 16

#: The buffers a crop render replaces (the composite's, the rgb and its error estimate's).
PATCHED = ("rgb", "rgb_even", "rgb_odd", "variance", "sample_count", "synthetic_rgb", "synthetic_alpha",
           "catcher_with", "catcher_without", "behind_synthetic")


def srgb_slope(e: np.ndarray) -> np.ndarray:
    """d(linear) / d(sRGB) at sRGB value ``e`` (IEC 61966-2-1's decoding, differentiated)."""
    e = np.clip(np.asarray(e, np.float64), 0.0, 1.0)
    return np.where(e <= 0.04045, 1.0 / 12.92, 2.4 / 1.055 * np.power((e + 0.055) / 1.055, 1.4))


class PatchedResult:
    """A RenderResult with some buffers replaced (numpy copies); every other attribute is the
    base's (labels, distance, stats other than ``samples``)."""

    def __init__(self, base: Any):
        self._base = base
        self.buffers: Dict[str, np.ndarray] = {}
        for name in PATCHED:
            v = getattr(base, name, None)
            if v is not None:
                self.buffers[name] = np.array(v)
        self.stats = dict(base.stats)

    def __getattr__(self, name: str) -> Any:
        buffers = self.__dict__.get("buffers", {})
        if name in buffers:
            return buffers[name]
        return getattr(self.__dict__["_base"], name)


def _crops(ids: np.ndarray, objects: List[int]) -> List[Tuple[List[int], Tuple[int, int, int, int]]]:
    """(objects, (x0, y0, x1, y1)) of the crops that render them: each object's box grown by a
    quarter of its size sideways and up and by half its height down (its edges, the blur's reach
    and the shadow under it), overlapping boxes merged; in the order of their objects' ids."""
    h, w = ids.shape
    boxes = []
    for o in objects:
        ys, xs = np.nonzero(ids == o)
        bw, bh = xs.max() + 1 - xs.min(), ys.max() + 1 - ys.min()
        mx, my = max(4, int(math.ceil(0.25 * bw))), max(4, int(math.ceil(0.25 * bh)))
        boxes.append(([o], (max(0, xs.min() - mx), max(0, ys.min() - my), min(w, xs.max() + 1 + mx),
                           min(h, ys.max() + 1 + max(4, int(math.ceil(0.5 * bh)))))))
    merged = True
    while merged:
        merged = False
        for i in range(len(boxes)):
            for j in range(i + 1, len(boxes)):
                (oa, a), (ob, b) = boxes[i], boxes[j]
                if a[0] < b[2] and b[0] < a[2] and a[1] < b[3] and b[1] < a[3]:
                    boxes[i] = (oa + ob, (min(a[0], b[0]), min(a[1], b[1]), max(a[2], b[2]), max(a[3], b[3])))
                    del boxes[j]
                    merged = True
                    break
            if merged:
                break
    return boxes


def refine_objects(scene: Any, res: Any, fp: Any, camera: Any, settings: Mapping[str, Any],
                   match: Optional[Mapping[str, Any]] = None, *, exposure: float, seed: int, threads: int
                   ) -> Tuple[Any, Dict[str, Any]]:
    """(render, info): ``res`` (the frame's RenderResult, rendered with ``settings`` -- the
    scenario's render section -- and ``exposure``) with the objects' crops rendered again until
    their noise is below ``match["render_noise"]`` (the scenario's background.match; default
    :data:`DEFAULT_FRACTION`) of the photo's (see the module docstring), up to ``match["max_spp"]``
    samples per pixel (0: :data:`DEFAULT_CAP_FACTOR` x spp). A fraction of 0: ``res`` as it is,
    nothing checked."""
    from ..scenario.schema import RENDER_KEYS
    from .photo import frame_exposure

    fraction = float((match or {}).get("render_noise", DEFAULT_FRACTION))
    max_spp = int((match or {}).get("max_spp", 0))

    ids = np.asarray(res.instance_id)
    alpha = np.asarray(res.synthetic_alpha)
    depth = np.asarray(res.depth)
    spp = int(settings["spp"])
    cap = int(max_spp) if max_spp else DEFAULT_CAP_FACTOR * spp
    info: Dict[str, Any] = {"fraction": float(fraction), "cap_spp": cap, "objects": {}}
    whole = (ids > 0) & (alpha > 0.999)
    objects = [int(o) for o in np.unique(ids[whole])]
    if not objects or not fraction > 0:
        return res, info
    # The photo's noise (sRGB, fitted where the objects change nothing: as camera matching
    # fits it) and the render's exposure into the photo's linear units (as the composite's).
    influence = influence_mask(res)
    fit = fit_noise(srgb(fp.pixels), ~dilate(influence, 3))
    boxes = []
    for o in objects:
        ys, xs = np.nonzero(ids == o)
        boxes.append([xs.min(), ys.min(), xs.max() + 1, ys.max() + 1])
    k, _ = frame_exposure(fp, res, ids, depth, boxes)
    info["noise"] = {"a": fit["a"], "b": fit["b"]}
    rgb = np.asarray(res.synthetic_rgb, np.float64)
    target: Dict[int, Dict[str, float]] = {}
    for o in objects:
        pix = whole & (ids == o)
        r = np.median(rgb[pix], axis=0)  # the object's colour in the render (displayed / exposure)
        enc = srgb(np.asarray(k, np.float64) * r).astype(np.float64)
        level = float(enc.mean())
        photo_sigma = math.sqrt(max(fit["a"] * level + fit["b"], 0.0))
        # NOTE: the renderer's per-pixel error (adaptive.h) is the RMS of its channels' errors in
        # displayed units (x the render's exposure); the photo's noise is fitted on the mean of the
        # sRGB channels (camera_match adds one draw to all of them). With the channels' Monte Carlo
        # errors fully correlated and proportional to their values (the same paths, scaled by the
        # surface's colour: sigma_c = rho r_c), first-order propagation of uncertainty (the delta
        # method: sigma_f(x) = |f'(x)| sigma_x) through the composite (x k_c) and the sRGB encoding
        # (d sRGB / d linear = 1 / srgb_slope) gives
        #   render error = rho exposure sqrt(mean_c r_c^2),
        #   sRGB sigma   = rho mean_c (k_c r_c / srgb_slope(sRGB_c)),
        # and their ratio ``per_srgb`` turns the photo's sRGB sigma into the renderer's threshold.
        # For a grey object it is exposure x srgb_slope / k.
        rms_r = float(np.sqrt(np.mean(r * r))) * exposure
        per_srgb_den = float(np.mean(np.asarray(k, np.float64) * r / srgb_slope(enc)))
        per_srgb = (rms_r / per_srgb_den if per_srgb_den > 0 and rms_r > 0 else  # a black object: as if grey
                    exposure * float(srgb_slope(level)) / max(float(np.mean(k)), 1e-12))
        threshold = fraction * photo_sigma * per_srgb
        target[o] = {"level": level, "photo_sigma": photo_sigma, "per_srgb": per_srgb, "threshold": threshold}
    out = res
    crops = []
    if cap > spp:
        out = PatchedResult(res)
        base = {key: settings[key] for key in RENDER_KEYS if key != "threads" and key in settings}
        try:
            for n, (objs, (x0, y0, x1, y1)) in enumerate(_crops(ids, objects)):
                # A noiseless photo (threshold 0, which would turn adaptive sampling off): to the cap.
                t = max(min(target[o]["threshold"] for o in objs), 1e-9)
                if not math.isfinite(t):
                    continue
                from .._core import PinholeCamera

                cam = PinholeCamera(camera.fx, camera.fy, camera.cx - x0, camera.cy - y0, x1 - x0, y1 - y0,
                                    np.asarray(camera.world_from_camera, np.float64),
                                    distortion=tuple(camera.distortion))
                scene.set_camera(cam)
                kw = dict(base, spp=cap, min_spp=spp, max_spp=cap, noise_threshold=t, target_psnr=0.0,
                          denoise=False)
                crop_seed = int(np.random.SeedSequence([int(seed), 7, n]).generate_state(1, np.uint64)[0])
                r = scene.render(seed=crop_seed, threads=threads, exposure=exposure, **kw)
                for name, buf in out.buffers.items():
                    buf[y0:y1, x0:x1] = np.asarray(getattr(r, name))
                crops.append({"box": [int(x0), int(y0), int(x1), int(y1)], "objects": objs,
                              "noise_threshold": t, "samples": int(r.stats["samples"])})
        finally:
            scene.set_camera(camera)
        out.stats["samples"] = int(np.asarray(out.sample_count, np.int64).sum())
    info["crops"] = crops
    count = np.asarray(out.sample_count)
    for o in objects:
        pix = whole & (ids == o)
        est = estimate_noise(np.asarray(out.rgb_even), np.asarray(out.rgb_odd), count, exposure, mask=pix)
        tg = target[o]
        rms = math.sqrt(est["mse"]) if est is not None else float("nan")
        # Back into the photo's sRGB sigma (the inverse of the conversion above).
        achieved = rms / tg["per_srgb"] if tg["per_srgb"] > 0 else float("nan")
        at_cap = float(np.mean(count[pix] >= cap))
        want = fraction * tg["photo_sigma"]
        info["objects"][o] = {"level": tg["level"], "photo_noise": tg["photo_sigma"], "target": want,
                              "achieved": achieved, "spp_mean": float(count[pix].mean()),
                              "spp_max": int(count[pix].max()), "at_cap": at_cap,
                              "reached": bool(not (achieved > want) or (cap > spp and at_cap == 0))}
    return out, info
