"""Placing a frame's objects on the ground until each is visible enough.

A layout draws a free spot per object in the placement region (footprint circles do not
overlap when asked), shows the objects and checks, with label-only renders (one camera ray
per pixel), that every object has ``min_pixels`` visible pixels and a visible fraction of
its amodal mask (the object rendered alone on a padded canvas) within the asked range.
Layouts are retried up to ``max_retries`` times; the best one is kept and objects that
still fail are dropped (with the reason in the metadata).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Dict, List, Mapping, Optional, Sequence, Tuple

import numpy as np

from .._core import PinholeCamera, Scene
from ..scene import primitives as P
from .records import PlacedObject

__all__ = ["TRUNCATION_PAD", "FrameView", "Layout", "search_layout", "amodal_pixels"]

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
    spots: List[Optional[Tuple[float, float]]]
    dropped: Dict[int, str]
    attempts: int

    def kept(self) -> List[bool]:
        return [s is not None and k not in self.dropped for k, s in enumerate(self.spots)]


def _spots(view: FrameView, placement: Mapping[str, Any], rng: np.random.Generator) -> List[Optional[Tuple[float, float]]]:
    """Positions (x, z) on the ground; None where an object found no free spot."""
    x0, z0, x1, z1 = placement["region"]
    placed: List[Tuple[float, float, float]] = []
    out: List[Optional[Tuple[float, float]]] = []
    for o in view.objects:
        r = o.radius
        spot = None
        for _ in range(100):
            x, z = float(rng.uniform(x0, x1)), float(rng.uniform(z0, z1))
            if not placement["non_overlapping"] or all(
                    math.hypot(x - px, z - pz) >= r + pr + placement["margin"] for px, pz, pr in placed):
                spot = (x, z)
                break
        if spot is not None:
            placed.append((spot[0], spot[1], r))
        out.append(spot)
    return out


def amodal_pixels(view: FrameView, camera: PinholeCamera, k: int) -> Tuple[int, int]:
    """(amodal pixels inside the image, amodal pixels on a canvas padded by TRUNCATION_PAD on
    every side) of object k rendered alone."""
    w, h = view.resolution
    pw, ph = int(round(TRUNCATION_PAD * w)), int(round(TRUNCATION_PAD * h))
    K = np.asarray(camera.K, np.float64)
    padded = PinholeCamera(float(K[0, 0]), float(K[1, 1]), float(K[0, 2]) + pw, float(K[1, 2]) + ph,
                           w + 2 * pw, h + 2 * ph, np.asarray(camera.world_from_camera, np.float64))
    for i, o in enumerate(view.objects):
        view.scene.set_instance_visible(o.instance, i == k)
    for d in view.decor:
        view.scene.set_instance_visible(d, False)
    if view.ground is not None:
        view.scene.set_instance_visible(view.ground, False)
    mask = np.asarray(view.labels(padded).instance_id) == k + 1
    inside = int(mask[ph:ph + h, pw:pw + w].sum())
    return inside, int(mask.sum())


def _put(view: FrameView, o: PlacedObject, spot: Tuple[float, float]) -> None:
    base = P.translate([spot[0], 0.0, spot[1]]) @ P.rotate([0.0, 1.0, 0.0], float(o.spec.yaw))
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
        spots = _spots(view, placement, rng)
        for o, spot in zip(objects, spots):
            if spot is not None:
                _put(view, o, spot)
        view.show([s is not None for s in spots])
        ids = np.asarray(view.labels(camera).instance_id)
        counts = np.bincount(ids.ravel(), minlength=len(objects) + 1)
        fails = []
        for k, spot in enumerate(spots):
            if spot is None:
                fails.append((k, "no free spot in the placement region"))
            elif counts[k + 1] < max(1 if objects[k].spec.labelled else 0, limits[k]["min_pixels"]):
                fails.append((k, f"{int(counts[k + 1])} visible pixels < min_pixels {limits[k]['min_pixels']}"))
        if need_amodal and not fails:
            for k in range(len(objects)):
                lim = limits[k]
                if lim["min_visible_fraction"] <= 0.0 and lim["max_visible_fraction"] >= 1.0:
                    continue
                inside, _ = amodal_pixels(view, camera, k)
                frac = counts[k + 1] / inside if inside else 0.0
                if frac < lim["min_visible_fraction"]:
                    fails.append((k, f"visible fraction {frac:.3f} < {lim['min_visible_fraction']}"))
                elif frac > lim["max_visible_fraction"]:
                    fails.append((k, f"visible fraction {frac:.3f} > {lim['max_visible_fraction']}"))
            view.show([s is not None for s in spots])
        if best is None or len(fails) < len(best[1]):
            best = (spots, fails, [(o.world, o.post_world) for o in objects])
        if not fails:
            break
    spots, fails, worlds = best
    for o, (world, post) in zip(objects, worlds):  # the best layout, posts included
        if world is not None:
            view.move(o, world, post)
    return Layout(spots, {k: reason for k, reason in fails}, attempts)
