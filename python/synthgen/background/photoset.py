"""The photos of a scenario's ``background``: the files, each photo's calibration (read once per
worker), which photo a frame uses, and the frame's crop of it.

Photos are used in turn: frame f uses photo ``order[f mod N]`` of a permutation drawn per round
(``f div N``) from the scenario's seed, so every photo is used once per round, any frame's photo
is known without the others, and ``max_uses`` caps the rounds.
"""
from __future__ import annotations

import os
from collections import OrderedDict
from dataclasses import dataclass
from typing import Any, Dict, List, Mapping, Optional, Tuple

import numpy as np

from .._core import SynthgenError
from .labels import RealObject, check_classes
from ..scene.assets import file_sha256
from .photos import Photo, expand_photos, load_photo
from .sidecar import PhotoSetup, find_calibration_files, read_depth, read_photo_setup

__all__ = ["PhotoSet", "FramePhoto", "resize_linear", "read_depth", "nearest_crop"]

#: A real box the crop cuts to less than this many pixels wide or high, or to less than this
#: share of its area, is an ignore region in the frame: too little is left to learn it from.
MIN_REAL_CUT_PIXELS = 4.0
MIN_REAL_CUT_SHARE = 0.25


def occluder_mask(setup: PhotoSetup, photo: Photo) -> np.ndarray:
    """The photo's occluder mask (H x W bool: real things in front of every inserted object)."""
    from .._core import read_image

    m = read_image(setup.occluders, "linear")
    if m.shape[:2] != (photo.height, photo.width):
        raise SynthgenError(f"{setup.occluders}: the occluder mask is {m.shape[1]} x {m.shape[0]}, the photo "
                            f"{photo.width} x {photo.height}")
    return m[:, :, 0] > 0.5


def nearest_crop(a: np.ndarray, sw: int, sh: int, crop: Tuple[int, int, int, int]) -> np.ndarray:
    """A per-pixel map (H x W) of the photo resized to sw x sh by nearest neighbour (depths and
    masks are not blended across edges), then cropped."""
    h, w = a.shape[:2]
    x0, y0, cw, ch = crop
    xs = np.minimum(((np.arange(x0, x0 + cw) + 0.5) * w / sw).astype(np.int64), w - 1)
    ys = np.minimum(((np.arange(y0, y0 + ch) + 0.5) * h / sh).astype(np.int64), h - 1)
    return a[ys][:, xs]


def resize_linear(pixels: np.ndarray, width: int, height: int) -> np.ndarray:
    """Resamples linear pixels to width x height (OpenImageIO's resize: a Lanczos-3 filter on
    reduction, so a downscaled photo keeps its noise statistics honest, not aliased)."""
    import OpenImageIO as oiio

    h, w, c = pixels.shape
    if (w, h) == (width, height):
        return pixels
    src = oiio.ImageBuf(oiio.ImageSpec(w, h, c, oiio.FLOAT))
    src.set_pixels(oiio.ROI(), np.ascontiguousarray(pixels, np.float32))
    dst = oiio.ImageBufAlgo.resize(src, filtername="lanczos3", roi=oiio.ROI(0, width, 0, height, 0, 1, 0, c))
    return np.maximum(np.asarray(dst.get_pixels(oiio.FLOAT), np.float32).reshape(height, width, c), 0.0)


@dataclass
class FramePhoto:
    """The photo of one frame: the crop of the (scaled) photo the image shows, its camera
    geometry, and the real objects in crop pixels."""

    index: int
    photo: Photo
    setup: PhotoSetup
    scale: float                       #: photo pixels -> scaled pixels
    crop: Tuple[int, int, int, int]    #: x0, y0, width, height in scaled pixels
    pixels: np.ndarray                 #: the crop, H x W x 3 linear
    calibration: Any                   #: Calibration of the scaled photo
    objects: List[RealObject]          #: real objects, boxes in crop pixels (clipped; polygons shifted;
                                       #: slivers the crop leaves are ignore regions)
    regions: List[np.ndarray]          #: placement polygons in crop pixels
    depth: Optional[np.ndarray] = None      #: the photo's metric depth in the crop (+inf: unknown)
    occluders: Optional[np.ndarray] = None  #: real things in front of everything inserted (crop)

    def camera(self):
        return self.calibration.camera(self.crop)

    def meta(self) -> Dict[str, Any]:
        return {"path": self.photo.path, "sha256": self.photo.sha256, "size": [self.photo.width, self.photo.height],
                "scale": self.scale, "crop": list(self.crop), "format": self.photo.format,
                "jpeg_quality": self.photo.jpeg_quality, **self.setup.meta()}


class PhotoSet:
    """The photos of a validated ``background`` section (see the module docstring)."""

    def __init__(self, background: Mapping[str, Any], base_dir: str, seed: int, cache: int = 4):
        self.bg = background
        self.paths: List[str] = []
        self._calibration: Dict[str, Optional[str]] = {}   # photo -> its entry's calibration file
        for entry in background["photos"]:
            if isinstance(entry, str):
                found, cal = expand_photos([entry], base_dir), None
            elif entry.get("asset") is not None:
                from ..scene import assets

                found, cal = [os.path.abspath(assets.resolve(entry["asset"]))], entry.get("calibration")
            else:
                found, cal = expand_photos([entry["file"]], base_dir), entry.get("calibration")
            for p in found:
                if p not in self._calibration:
                    self.paths.append(p)
                    self._calibration[p] = cal
        self.shared = background.get("calibration")
        self.seed = int(seed)
        self._photos: "OrderedDict[str, Photo]" = OrderedDict()
        self._setups: Dict[str, PhotoSetup] = {}
        self._depths: Dict[str, np.ndarray] = {}
        self._cache = cache

    def __len__(self) -> int:
        return len(self.paths)

    def check_count(self, count: int) -> None:
        cap = self.bg.get("max_uses")
        if cap is not None and count > cap * len(self.paths):
            raise SynthgenError(f"background: {count} frames need more than max_uses {cap} x {len(self.paths)} photos")

    def index_for_frame(self, frame: int) -> int:
        n = len(self.paths)
        rnd, k = divmod(int(frame), n)
        cap = self.bg.get("max_uses")
        if cap is not None and rnd >= cap:
            raise SynthgenError(f"background: frame {frame} would use a photo more than max_uses {cap} times")
        order = np.random.default_rng(np.random.SeedSequence([self.seed, 0x70686f74, rnd])).permutation(n)
        return int(order[k])

    def photo(self, i: int) -> Photo:
        path = self.paths[i]
        if path in self._photos:
            self._photos.move_to_end(path)
            return self._photos[path]
        p = load_photo(path)
        self._photos[path] = p
        while len(self._photos) > self._cache:
            self._photos.popitem(last=False)
        return p

    def setup(self, i: int, photo: Optional[Photo] = None) -> PhotoSetup:
        path = self.paths[i]
        if path not in self._setups:
            p = photo or self.photo(i)
            self._setups[path] = read_photo_setup(path, p.width, p.height, shared=self.shared,
                                                  entry=self._calibration.get(path),
                                                  exif_focal_mm=p.exif_focal_mm, exif_focal_35mm=p.exif_focal_35mm)
        return self._setups[path]

    def input_files(self, with_labels: bool = False) -> Dict[str, str]:
        """Every file the photos bring: path -> sha256 of the photos and their calibration files,
        and with ``with_labels`` the label, depth, mask and environment files those name
        (reading each calibration)."""
        out = {}
        for i, path in enumerate(self.paths):
            out[path] = file_sha256(path)
            for f in find_calibration_files(path, self.shared, self._calibration.get(path)):
                out[f] = file_sha256(f)
            if with_labels:
                s = self.setup(i)
                extra = list(s.files) + [p for p in (s.depth and s.depth["file"], s.occluders,
                                                     s.envmap and s.envmap[0]) if p]
                for f in extra:
                    out[f] = file_sha256(f)
        return out

    def check(self, class_names: List[str]) -> int:
        """Reads every photo and its calibration once (validation), and decodes the depth map,
        occluder mask and environment map each names (a damaged file is an error here, not in a
        frame); refuses a photo without real labels unless unlabelled_ok, and real objects of
        classes the scenario does not have. Returns the number of photos."""
        from .._core import read_image

        for i, path in enumerate(self.paths):
            p = self.photo(i)
            s = self.setup(i, p)
            check_classes(s.label_files, s.objects, class_names, path)
            if s.depth is not None:
                read_depth(s, p.width, p.height)
            if s.occluders is not None:
                occluder_mask(s, p)
            if s.envmap is not None:
                read_image(s.envmap[0], "linear")
            if not s.labelled and not self.bg["unlabelled_ok"]:
                raise SynthgenError(
                    f"{path}: the photo declares no real labels (labels or objects in its calibration): real "
                    f"{'/'.join(class_names)} it shows would be learnt as background. Label them (or write "
                    "'objects: []' when there are none), or set background.unlabelled_ok: true")
        return len(self.paths)

    @staticmethod
    def _crop(setup: PhotoSetup, sw: int, sh: int, w: int, h: int, rng: np.random.Generator) -> Tuple[int, int]:
        """The top-left corner of a w x h crop of the photo scaled to sw x sh: uniform, but among
        up to 16 draws the first whose share of the placement region is at least half the best
        share any crop can have (so crops show ground to put objects on)."""
        if (sw, sh) == (w, h):
            return 0, 0
        if not setup.regions:
            return int(rng.integers(0, sw - w + 1)), int(rng.integers(0, sh - h + 1))
        from .labels import polygon_mask

        f = 8.0  # the region at 1/8 scale
        sx, sy = sw / setup.calibration.width, sh / setup.calibration.height
        mw, mh = max(1, int(sw / f)), max(1, int(sh / f))
        mask = np.zeros((mh, mw), bool)
        for p in setup.regions:
            mask |= polygon_mask(np.asarray(p) * [sx / f, sy / f], mw, mh)
        integral = np.pad(mask.cumsum(0).cumsum(1), ((1, 0), (1, 0)))

        def share(x0: int, y0: int) -> float:
            a, b = int(x0 / f), int(y0 / f)
            c, d = min(mw, a + max(1, int(w / f))), min(mh, b + max(1, int(h / f)))
            return float(integral[d, c] - integral[b, c] - integral[d, a] + integral[b, a]) / max((c - a) * (d - b), 1)

        best = max(share(x, y) for x in np.linspace(0, sw - w, 9).astype(int) for y in np.linspace(0, sh - h, 5).astype(int))
        draws = []
        for _ in range(16):
            x0, y0 = int(rng.integers(0, sw - w + 1)), int(rng.integers(0, sh - h + 1))
            draws.append((share(x0, y0), x0, y0))
            if draws[-1][0] >= 0.5 * best:
                return x0, y0
        return max(draws)[1:]

    def frame(self, frame: int, resolution: Tuple[int, int], rng: np.random.Generator, zoom: float) -> FramePhoto:
        i = self.index_for_frame(frame)
        photo = self.photo(i)
        setup = self.setup(i, photo)
        w, h = resolution
        # The smallest scale that covers the image, then zoom; a random crop of the result.
        scale = max(w / photo.width, h / photo.height) * float(zoom)
        sw, sh = max(w, int(round(photo.width * scale))), max(h, int(round(photo.height * scale)))
        x0, y0 = self._crop(setup, sw, sh, w, h, rng)
        scaled = resize_linear(photo.pixels, sw, sh) if (sw, sh) != (photo.width, photo.height) else photo.pixels
        sx, sy = sw / photo.width, sh / photo.height
        cal = setup.calibration.scaled(sx, sy)
        objects = []
        for o in setup.objects:
            bx = np.array(o.box, np.float64) * [sx, sy, sx, sy] - [x0, y0, x0, y0]
            clipped = [max(bx[0], 0.0), max(bx[1], 0.0), min(bx[2], w), min(bx[3], h)]
            if clipped[2] <= clipped[0] or clipped[3] <= clipped[1]:
                continue  # outside the crop
            poly = None if o.polygon is None else np.asarray(o.polygon) * [sx, sy] - [x0, y0]
            cw, ch = clipped[2] - clipped[0], clipped[3] - clipped[1]
            sliver = (cw < MIN_REAL_CUT_PIXELS or ch < MIN_REAL_CUT_PIXELS or
                      cw * ch < MIN_REAL_CUT_SHARE * (bx[2] - bx[0]) * (bx[3] - bx[1]))
            objects.append(RealObject(o.cls, clipped, poly, o.ignore or sliver, o.source))
            objects[-1].full_box = [float(v) for v in bx]  # type: ignore[attr-defined]
        regions = [np.asarray(p) * [sx, sy] - [x0, y0] for p in setup.regions]
        fp = FramePhoto(i, photo, setup, scale, (x0, y0, w, h),
                        np.ascontiguousarray(scaled[y0:y0 + h, x0:x0 + w], np.float32), cal, objects, regions)
        if setup.depth is not None:
            if photo.path not in self._depths:
                self._depths = {photo.path: read_depth(setup, photo.width, photo.height)}
            fp.depth = nearest_crop(self._depths[photo.path], sw, sh, fp.crop)
        if setup.occluders is not None:
            fp.occluders = nearest_crop(occluder_mask(setup, photo), sw, sh, fp.crop)
        return fp

