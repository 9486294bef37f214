"""Objects inserted into a photo rendered until they are less noisy than the photo.

Camera matching (:mod:`synthgen.post.photo.camera_match`) adds to each inserted object only the
noise it lacks: an object whose Monte Carlo noise already exceeds the photo's cannot be matched
(its noise loop drives the gain to 0 and stays above target). So, after the frame's render,
:func:`refine_objects` renders the objects' pixels again -- the 16 x 16 tiles that hold them
(and the 2 pixels around them: their edges, the blur's reach), in runs along the rows, with the
same camera rays, scene and settings -- with adaptive sampling (``noise_threshold``,
``cpp/integrator/adaptive.h``) whose target is a fraction of the photo's noise at the object's
level, from the frame's samples per pixel up to a cap, and puts the pieces' buffers in place of
the frame's. Labels stay the frame's (the pieces' pixel-centre rays are the same rays); shadows
keep the frame's samples. Everything is a function of the frame's render, its photo and seed:
the pieces, their thresholds and seeds, and the renderer's rounds are bit-identical for any
thread count.

Per object, ``info["objects"]`` records the photo's noise at its level, the target, the noise
achieved (both as sRGB sigmas, as :func:`synthgen.post.photo.measure.fit_noise` measures the
photo's), its samples and whether the cap stopped it short (``reached``: false).
"""
from __future__ import annotations

import math
from typing import Any, Dict, List, Mapping, Optional, Tuple

import numpy as np

from ..post.photo.measure import dilate, fit_noise, srgb
from ..post.quality import estimate_noise

__all__ = ["refine_objects", "PatchedResult", "srgb_slope", "DEFAULT_FRACTION", "DEFAULT_CAP_FACTOR"]

#: The objects' render noise target: this fraction of the photo's noise sigma at their level.
DEFAULT_FRACTION = 0.5
#: The default sample cap: this many times the render's spp. NOTE: measured (docs/augmented_photos.md),
#: clean photos need about 100 x spp to bring the objects' raw noise below half theirs, so the cap
#: is what a frame costs: 4 x took augmented_road.yaml from 13.6 to 28.8 CPU s a frame, 16 x to 65.0.
DEFAULT_CAP_FACTOR = 4

#: The buffers a piece's render replaces (the composite's, the rgb and its error estimate's).
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


#: The pieces rendered again are runs of TILE x TILE tiles along the image's rows.
TILE = 16


def _pieces(ids: np.ndarray, objects: List[int], threshold: Mapping[int, float]
            ) -> List[Tuple[float, Tuple[int, int, int, int]]]:
    """(threshold, (x0, y0, x1, y1)) of the pieces to render again: the TILE x TILE tiles (aligned
    to the image) that hold a pixel of an object or one within 2 pixels of it (its edges and the
    blur's reach), each with the smallest threshold of the objects it holds; consecutive tiles of
    a row of tiles with the same threshold make one piece. In the order of the rows, then of x."""
    h, w = ids.shape
    ty, tx = -(-h // TILE), -(-w // TILE)
    tile_t = np.full((ty, tx), np.inf)
    for o in objects:
        m = dilate(ids == o, 2)
        pad = np.zeros((ty * TILE, tx * TILE), bool)
        pad[:h, :w] = m
        touched = pad.reshape(ty, TILE, tx, TILE).any(axis=(1, 3))
        tile_t = np.where(touched, np.minimum(tile_t, threshold[o]), tile_t)
    pieces = []
    for r in range(ty):
        c = 0
        while c < tx:
            t = tile_t[r, c]
            if not np.isfinite(t):
                c += 1
                continue
            e = c + 1
            while e < tx and tile_t[r, e] == t:
                e += 1
            pieces.append((float(t), (c * TILE, r * TILE, min(w, e * TILE), min(h, (r + 1) * TILE))))
            c = e
    return pieces


def refine_objects(scene: Any, res: Any, fp: Any, camera: Any, settings: Mapping[str, Any],
                   match: Optional[Mapping[str, Any]] = None, *, exposure: float, seed: int, threads: int
                   ) -> Tuple[Any, Dict[str, Any]]:
    """(render, info): ``res`` (the frame's RenderResult, rendered with ``settings`` -- the
    scenario's render section -- and ``exposure``) with the objects' pixels rendered again until
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
    # The photo's noise (sRGB, over the whole photo, as camera matching fits it) and the
    # render's exposure into the photo's linear units (as the composite's).
    fit = fit_noise(srgb(fp.pixels))
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
    pieces = {"renders": 0, "pixels": 0, "samples": 0}
    if cap > spp:
        from .._core import PinholeCamera

        out = PatchedResult(res)
        base = {key: settings[key] for key in RENDER_KEYS if key != "threads" and key in settings}
        # A noiseless photo (threshold 0, which would turn adaptive sampling off): to the cap.
        thresholds = {o: max(target[o]["threshold"], 1e-9) for o in objects}
        try:
            for n, (t, (x0, y0, x1, y1)) in enumerate(_pieces(ids, objects, thresholds)):
                cam = PinholeCamera(camera.fx, camera.fy, camera.cx - x0, camera.cy - y0, x1 - x0, y1 - y0,
                                    np.asarray(camera.world_from_camera, np.float64),
                                    distortion=tuple(camera.distortion))
                scene.set_camera(cam)
                kw = dict(base, spp=cap, min_spp=spp, max_spp=cap, noise_threshold=t, target_psnr=0.0,
                          denoise=False)
                piece_seed = int(np.random.SeedSequence([int(seed), 7, n]).generate_state(1, np.uint64)[0])
                r = scene.render(seed=piece_seed, threads=threads, exposure=exposure, **kw)
                for name, buf in out.buffers.items():
                    buf[y0:y1, x0:x1] = np.asarray(getattr(r, name))
                pieces["renders"] += 1
                pieces["pixels"] += (x1 - x0) * (y1 - y0)
                pieces["samples"] += int(r.stats["samples"])
        finally:
            scene.set_camera(camera)
        out.stats["samples"] = int(np.asarray(out.sample_count, np.int64).sum())
    info["rendered_again"] = pieces
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
