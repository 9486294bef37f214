"""Placing a frame's objects on the ground until each is visible enough.

A layout draws a free spot per object in the placement region (footprint circles do not
overlap when asked), shows the objects and checks, with one camera ray per pixel
(Scene.instance_coverage: the pixels a label-only render gives each object), that every
object has ``min_pixels`` visible pixels and a visible fraction of its amodal mask (the object
as rendered alone on a padded canvas: every object's from one pass) within the asked range.
Layouts are retried up to ``max_retries`` times; the best one is kept and objects that
still fail are dropped (with the reason in the metadata).
"""
from __future__ import annotations

import functools
import math
from dataclasses import dataclass, field
from typing import Any, Dict, List, Mapping, Optional, Sequence, Tuple

import numpy as np

from .._core import PinholeCamera, Scene, SynthgenError
from ..scene import primitives as P
from .records import PlacedObject

__all__ = ["TRUNCATION_PAD", "FrameView", "Layout", "search_layout", "tilted", "amodal_pixels", "amodal_masks",
           "bit_counts", "bit_mask"]

#: Objects may extend this far beyond the image on each side (fraction of the image size)
#: and still be measured for truncation.
TRUNCATION_PAD = 0.5


@dataclass
class FrameView:
    """The scene objects a layout moves and toggles."""

    scene: Scene
    objects: List[PlacedObject]
    decor: List[int]               #: post / pole instances (index = PlacedObject.decor)
    ground: Optional[int]          #: the ground instance, if any
    resolution: Tuple[int, int]
    threads: int
    #: In a photo (background): where objects may stand (frame.photo.PhotoPlacement).
    photo: Any = None

    def labels(self, camera: PinholeCamera) -> Any:
        self.scene.set_camera(camera)
        self.scene.commit()
        return self.scene.render(spp=1, labels_only=True, threads=self.threads)

    def show(self, visible: Sequence[bool]) -> None:
        """Shows the objects (and their posts) where ``visible``, hides the others."""
        for o, v in zip(self.objects, visible):
            self.scene.set_instance_visible(o.instance, bool(v))
        for o, v in zip(self.objects, visible):
            if o.decor is not None:
                self.scene.set_instance_visible(self.decor[o.decor], bool(v))
        if self.ground is not None:
            self.scene.set_instance_visible(self.ground, True)

    def move(self, o: PlacedObject, world: np.ndarray, post: Optional[np.ndarray] = None) -> None:
        """Puts an object (and its post, if it has one) where ``world`` says."""
        o.world = world
        self.scene.set_instance_transform(o.instance, world.astype(np.float32))
        if post is not None:
            o.post_world = post
            self.scene.set_instance_transform(self.decor[o.decor], post.astype(np.float32))


@dataclass
class Layout:
    spots: List[Optional[Tuple[float, float, float]]]
    dropped: Dict[int, str]
    attempts: int
    #: object -> the object it rests on (rests_on)
    rests: Dict[int, int] = field(default_factory=dict)

    def kept(self) -> List[bool]:
        return [s is not None and k not in self.dropped for k, s in enumerate(self.spots)]


#: A spot: (x, z) on the ground, and the height y the object stands at (0, or the top of
#: the object it rests on).
Spot = Tuple[float, float, float]


def tilted(local: np.ndarray, dims: np.ndarray, roll: float, pitch: float) -> Tuple[np.ndarray, float]:
    """(local, footprint radius) of an object (forward +x, up +y, its box of ``dims`` standing
    on y = 0) tilted by ``roll`` about its forward axis and ``pitch`` about its lateral axis
    (positive: front up), about the box's centre, then lowered until its lowest box corner
    touches y = 0 (it rests on an edge or a corner, as a dropped box would)."""
    r = P.rotate([0.0, 0.0, 1.0], float(pitch)) @ P.rotate([1.0, 0.0, 0.0], float(roll))
    r = r.astype(np.float64)
    half = 0.5 * np.asarray(dims, np.float64)
    centre = np.array([0.0, half[1], 0.0])
    corners = np.array([[sx * half[0], sy * half[1], sz * half[2]] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)])
    turned = corners @ r[:3, :3].T
    lift = np.eye(4)
    lift[1, 3] = -turned[:, 1].min()
    shift = np.eye(4)
    shift[:3, 3] = -centre
    m = lift @ r @ shift @ local
    radius = float(np.hypot(turned[:, 0], turned[:, 2]).max())
    return m, radius


def _corners(o: PlacedObject) -> np.ndarray:
    """The 8 corners of an object's box after its local transform (scale, lift, tilt)."""
    half = 0.5 * np.asarray(o.dims, np.float64)
    box = np.array([[sx * half[0], half[1] + sy * half[1], sz * half[2], 1.0]
                    for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)])
    kind = o.spec.shape[0]
    if kind not in ("primitive", "mesh", "asset"):  # signs and plates: their local is not a box's
        return box[:, :3]
    # The canonical box (forward +x, up +y, on y = 0) through the tilt the local carries:
    # compare the local with the untilted box via the tilt alone (roll/pitch about the centre).
    if not (o.spec.roll or o.spec.pitch):
        return box[:, :3]
    m, _ = tilted(np.eye(4), o.dims, o.spec.roll, o.spec.pitch)
    return (box @ m.T)[:, :3]


def _top(o: PlacedObject) -> float:
    """Height of the top of an object's box above its base."""
    return float(_corners(o)[:, 1].max())


@functools.lru_cache(maxsize=1024)
def _yaw(degrees: float) -> np.ndarray:
    """P.rotate about +y (float32 4 x 4, read-only): placement asks for the same yaw thousands of
    times a frame."""
    m = P.rotate([0.0, 1.0, 0.0], degrees)
    m.setflags(write=False)
    return m


def _world_corners(o: PlacedObject, x: float, z: float, y: float = 0.0) -> np.ndarray:
    """The 8 world corners of an object's box standing at (x, y, z) with its yaw (as _put puts it)."""
    base = (P.translate([x, y, z]) @ _yaw(float(o.spec.yaw))).astype(np.float64)
    c = _corners(o)
    return (np.concatenate([c, np.ones((len(c), 1))], axis=1) @ base.T)[:, :3]


def _on_ground(view: FrameView, camera: PinholeCamera, o: PlacedObject, rng: np.random.Generator,
               region: Sequence[float]) -> Tuple[float, float]:
    """A spot for an object on the ground: uniform in ``region``, or, with ``pixel_height``,
    in a random image column at the camera depth where its box is that many pixels high and
    wholly inside the image's height (NaN when there is none). In a photo: under a pixel of its
    placement region, the footprint in the region and clear of its real objects."""
    if view.photo is not None:
        if o.spec.pixel_height is None:
            x, z = view.photo.sample(rng)
        else:
            x, z = _on_ground(FrameView(view.scene, view.objects, view.decor, view.ground, view.resolution,
                                        view.threads), camera, o, rng, region)
        if math.isfinite(x) and not view.photo.accepts(_world_corners(o, x, z)):
            return float("nan"), float("nan")
        return x, z
    if o.spec.pixel_height is None:
        x0, z0, x1, z1 = region
        return float(rng.uniform(x0, x1)), float(rng.uniform(z0, z1))
    w, h = view.resolution
    wfc = np.asarray(camera.world_from_camera, np.float64)
    right, down, fwd, c = wfc[:3, 0], wfc[:3, 1], wfc[:3, 2], wfc[:3, 3]
    cam_from_world = np.linalg.inv(wfc)
    target = float(o.spec.pixel_height)
    fx, fy, cx, cy = (float(v) for v in (camera.fx, camera.fy, camera.cx, camera.cy))
    yaw = P.rotate([0.0, 1.0, 0.0], float(o.spec.yaw)).astype(np.float64)[:3, :3]
    corners = _corners(o) @ yaw.T
    if abs(down[1]) < 1e-6:  # a camera looking straight down or up: no ground column
        return float("nan"), float("nan")
    u = float(rng.uniform(0.0, w))
    # NOTE: pinhole projection: an extent H at camera depth z spans fy H / z pixels, so the
    # depth is refined by z <- z * (extent(z) / target), a fixed-point iteration that converges
    # in a few steps (extent ~ 1/z); the box's own depth and the camera's pitch are included.
    z = fy * float(corners[:, 1].max()) / target
    ground = None
    for _ in range(8):
        x = z * (u - cx) / fx
        t = -(c[1] + z * fwd[1] + x * right[1]) / down[1]  # the ground point of that column at depth z
        ground = c + z * fwd + x * right + t * down
        pc = (np.c_[corners + ground, np.ones(8)] @ cam_from_world.T)[:, :3]
        if np.any(pc[:, 2] <= 1e-3):
            return float("nan"), float("nan")
        v = fy * pc[:, 1] / pc[:, 2] + cy
        extent = float(v.max() - v.min())
        z *= extent / target
    uu = fx * pc[:, 0] / pc[:, 2] + cx
    if v.min() < 0.0 or v.max() > h or uu.min() < 0.0 or uu.max() > w or abs(extent / target - 1.0) > 0.01:
        return float("nan"), float("nan")
    return float(ground[0]), float(ground[2])


def _spots(view: FrameView, placement: Mapping[str, Any], rng: np.random.Generator,
           camera: PinholeCamera, rests: Dict[int, int]) -> List[Optional[Spot]]:
    """A spot per object; None where an object found none. Objects resting on others are
    placed after them, on the top of one of them chosen at random (``rests``: which)."""
    objects = view.objects
    order = sorted(range(len(objects)), key=lambda k: _depth(objects, k))
    ground: List[Tuple[float, float, float]] = []              # (x, z, radius) on the ground
    on_top: Dict[int, List[Tuple[float, float, float]]] = {}   # support index -> (x, z, radius)
    out: List[Optional[Spot]] = [None] * len(objects)
    margin = placement["margin"]

    def free(x: float, z: float, r: float, others: Sequence[Tuple[float, float, float]]) -> bool:
        return not placement["non_overlapping"] or all(math.hypot(x - px, z - pz) >= r + pr + margin
                                                       for px, pz, pr in others)

    for k in order:
        o = objects[k]
        r = o.radius
        if o.spec.support is not None:
            supports = [j for j in range(len(objects))
                        if objects[j].spec.kind == o.spec.support and out[j] is not None and j != k]
            if not supports:
                continue
            j = supports[int(rng.integers(len(supports)))]
            s, sp = objects[j], out[j]
            half = 0.5 * np.asarray(s.dims, np.float64)
            yaw = math.radians(float(s.spec.yaw))
            for _ in range(100):
                # Uniform on the support's top face (its own x, z), kept on it when it fits.
                lx = float(rng.uniform(-max(half[0] - r, 0.0), max(half[0] - r, 0.0)))
                lz = float(rng.uniform(-max(half[2] - r, 0.0), max(half[2] - r, 0.0)))
                x = sp[0] + math.cos(yaw) * lx + math.sin(yaw) * lz
                z = sp[1] - math.sin(yaw) * lx + math.cos(yaw) * lz
                if free(x, z, r, on_top.get(j, [])):
                    out[k] = (x, z, sp[2] + _top(s))
                    rests[k] = j
                    on_top.setdefault(j, []).append((x, z, r))
                    break
            continue
        for _ in range(100):
            x, z = _on_ground(view, camera, o, rng, o.spec.region or placement["region"])
            if math.isfinite(x) and free(x, z, r, ground):
                out[k] = (x, z, 0.0)
                ground.append((x, z, r))
                break
    return out


def _no_spot_reason(o: PlacedObject, photo: bool = False) -> str:
    if o.spec.support is not None:
        return "no free spot on the top of the objects it rests on (rests_on)"
    if photo:
        return ("no free spot in the photo's placement region (within background's min/max_distance, clear of its "
                "real objects)")
    if o.spec.pixel_height is not None:
        return "no free spot at the distance its pixel_height asks for, inside the image"
    return "no free spot in the placement region"


def _depth(objects: Sequence[PlacedObject], k: int) -> int:
    """How many supports are below object k (0: it stands on the ground)."""
    n, s = 0, objects[k].spec.support
    seen = set()
    while s is not None and s not in seen:
        seen.add(s)
        n += 1
        s = next((o.spec.support for o in objects if o.spec.kind == s), None)
    return n


def bit_counts(bits: np.ndarray, n: int) -> np.ndarray:
    """Pixels per instance (the first ``n``) of a Scene.instance_coverage array."""
    if n == 0:
        return np.zeros(0, np.int64)
    flat = bits.reshape(-1, bits.shape[-1])
    flat = flat[flat.any(axis=1)]  # the few pixels some instance covers
    if not len(flat):
        return np.zeros(n, np.int64)
    unpacked = np.unpackbits(flat.astype("<u8", copy=False).view(np.uint8), axis=1, bitorder="little")
    return unpacked[:, :n].sum(axis=0, dtype=np.int64)


def bit_mask(bits: np.ndarray, i: int) -> np.ndarray:
    """The mask (bool, H x W) of instance ``i`` of a Scene.instance_coverage array."""
    return ((bits[..., i // 64] >> np.uint64(i % 64)) & np.uint64(1)).astype(bool)


def _padded(camera: PinholeCamera, resolution: Tuple[int, int]) -> Tuple[PinholeCamera, int, int]:
    """(the camera on a canvas padded by TRUNCATION_PAD on every side, the padding in x, in y),
    with the camera's lens distortion."""
    w, h = resolution
    K = np.asarray(camera.K, np.float64)
    d = tuple(float(v) for v in camera.distortion)
    # NOTE: the same lens on a larger canvas (the distortion acts on normalized coordinates, so
    # the image's own pixels keep their rays): without it, amodal pixels were counted through no
    # lens against visible ones through the lens (a whole, unoccluded box 0.6 or 1.17 visible). A
    # lens that folds back inside the padded canvas gets a smaller pad (truncation counted
    # against less of the object's outside: lower).
    def make(f: float) -> Tuple[PinholeCamera, int, int]:
        pw, ph = int(round(f * TRUNCATION_PAD * w)), int(round(f * TRUNCATION_PAD * h))
        return (PinholeCamera(float(K[0, 0]), float(K[1, 1]), float(K[0, 2]) + pw, float(K[1, 2]) + ph,
                              w + 2 * pw, h + 2 * ph, np.asarray(camera.world_from_camera, np.float64),
                              distortion=d), pw, ph)

    for f in ((1.0, 0.5, 0.25) if any(d) else ()):
        try:
            return make(f)
        except SynthgenError:
            continue
    return make(0.0 if any(d) else 1.0)


def amodal_masks(view: FrameView, camera: PinholeCamera, ks: Sequence[int],
                 masks: Sequence[int] = ()) -> Dict[int, Tuple[Any, ...]]:
    """{k: (amodal pixels inside the image, amodal pixels on a canvas padded by TRUNCATION_PAD on
    every side)} of objects ``ks``, each as if rendered alone (the others, posts and ground
    hidden), from one ray per pixel (Scene.instance_coverage); objects in ``masks`` also get
    their padded mask (bool). Shows the objects ``ks``."""
    ks = list(ks)
    for k in ks:
        view.scene.set_instance_visible(view.objects[k].instance, True)
    padded, pw, ph = _padded(camera, view.resolution)
    w, h = view.resolution
    bits = view.scene.instance_coverage(padded, [view.objects[k].instance for k in ks], view.threads)
    total = bit_counts(bits, len(ks))
    inside = bit_counts(bits[ph:ph + h, pw:pw + w], len(ks))
    wanted = set(masks)
    return {k: (int(inside[i]), int(total[i])) + ((bit_mask(bits, i),) if k in wanted else ())
            for i, k in enumerate(ks)}


def amodal_pixels(view: FrameView, camera: PinholeCamera, k: int, mask: bool = False) -> Tuple[Any, ...]:
    """(amodal pixels inside the image, amodal pixels on a canvas padded by TRUNCATION_PAD on
    every side) of object k rendered alone; with ``mask``, also that padded mask (bool)."""
    return amodal_masks(view, camera, [k], [k] if mask else ())[k]


def _put(view: FrameView, o: PlacedObject, spot: Spot) -> None:
    base = P.translate([spot[0], spot[2], spot[1]]) @ P.rotate([0.0, 1.0, 0.0], float(o.spec.yaw))
    post = None
    if o.decor is not None:  # a 5 cm post behind the panel, from the ground to its middle
        h = float(o.post_height)
        post = base @ P.translate([0.0, 0.5 * h, 0.03]) @ P.scale([0.05, max(h, 1e-3), 0.05])
    view.move(o, base @ o.local, post)


def search_layout(view: FrameView, camera: PinholeCamera, placement: Mapping[str, Any],
                  rng: np.random.Generator) -> Layout:
    """Tries layouts until every object meets the visibility criteria (or the retries run
    out); leaves the scene in the best layout found, every object shown or hidden."""
    objects = view.objects
    # Unlabelled objects (label: false) may be hidden or cut by the image unless their entry
    # sets limits: the placement's limits are for what gets labelled.
    free = {"min_pixels": 0, "min_visible_fraction": 0.0, "max_visible_fraction": 1.0}
    limits = [{k: o.spec.limits.get(k, placement[k] if o.spec.labelled else free[k])
               for k in ("min_pixels", "min_visible_fraction", "max_visible_fraction")} for o in objects]
    need_amodal = any(li["min_visible_fraction"] > 0.0 or li["max_visible_fraction"] < 1.0 for li in limits)
    best = None
    attempts = 0
    for attempt in range(placement["max_retries"] + 1):
        attempts = attempt + 1
        rests: Dict[int, int] = {}
        spots = _spots(view, placement, rng, camera, rests)
        for o, spot in zip(objects, spots):
            if spot is not None:
                _put(view, o, spot)
        view.show([s is not None for s in spots])
        # Visible pixels: where each object is the first hit (its id in a label-only render).
        counts = bit_counts(view.scene.instance_coverage(camera, [o.instance for o in objects], view.threads,
                                                         first_hit=True), len(objects))
        fails = []
        for k, spot in enumerate(spots):
            if spot is None:
                fails.append((k, _no_spot_reason(objects[k], view.photo is not None)))
            elif counts[k] < max(1 if objects[k].spec.labelled else 0, limits[k]["min_pixels"]):
                fails.append((k, f"{int(counts[k])} visible pixels < min_pixels {limits[k]['min_pixels']}"))
        if need_amodal and not fails:
            checked = [k for k in range(len(objects)) if limits[k]["min_visible_fraction"] > 0.0
                       or limits[k]["max_visible_fraction"] < 1.0]
            amodal = amodal_masks(view, camera, checked)
            for k in checked:
                lim = limits[k]
                inside = amodal[k][0]
                frac = counts[k] / inside if inside else 0.0
                if frac < lim["min_visible_fraction"]:
                    fails.append((k, f"visible fraction {frac:.3f} < {lim['min_visible_fraction']}"))
                elif frac > lim["max_visible_fraction"]:
                    fails.append((k, f"visible fraction {frac:.3f} > {lim['max_visible_fraction']}"))
            view.show([s is not None for s in spots])
        if best is None or len(fails) < len(best[1]):
            best = (spots, fails, [(o.world, o.post_world) for o in objects], rests)
        if not fails:
            break
    spots, fails, worlds, rests = best
    for o, (world, post) in zip(objects, worlds):  # the best layout, posts included
        if world is not None:
            view.move(o, world, post)
    dropped = {k: reason for k, reason in fails}
    # What rests on a dropped object goes with it (it would float), down the stacks.
    for k in sorted(rests, key=lambda k: _depth(objects, k)):
        if rests[k] in dropped and k not in dropped:
            dropped[k] = "the object it rests on was dropped"
    return Layout(spots, dropped, attempts, rests)
