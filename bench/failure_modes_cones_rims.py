#!/usr/bin/env python3
"""Regenerates docs/failure_ray_cones.png and docs/failure_catcher_rims.png (the figures of the
two failure modes measured by tests/python/test_failure_ray_cones.py and
test_failure_catcher_rims.py, whose scenes it reuses), and prints the converged rim error of the
catcher composite (the rim bias, which the 64-spp test cannot separate from noise).

    PYTHONPATH=python .venv/bin/python bench/failure_modes_cones_rims.py
"""
from __future__ import annotations

import os
import sys
import tempfile

REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))
sys.path.insert(0, os.path.join(REPO, "python"))
sys.path.insert(0, os.path.join(REPO, "tests", "python"))

import matplotlib  # noqa: E402

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import test_failure_catcher_rims as rims  # noqa: E402
import test_failure_ray_cones as cones  # noqa: E402
from synthgen.post.photo.composite import composite  # noqa: E402


def srgb(x: np.ndarray) -> np.ndarray:
    x = np.clip(x, 0.0, 1.0)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)


def panels(images, titles, path, scale, cmap_last=True, vmax_err=0.5):
    fig, axes = plt.subplots(1, len(images), figsize=(len(images) * scale, scale * 0.85), dpi=110)
    for k, (ax, im, t) in enumerate(zip(axes, images, titles)):
        if cmap_last and k == len(images) - 1:
            h = ax.imshow(im, cmap="magma", vmin=0.0, vmax=vmax_err, interpolation="nearest")
            fig.colorbar(h, ax=ax, fraction=0.035, pad=0.02)
        else:
            ax.imshow(im, interpolation="nearest")
        ax.set_title(t, fontsize=9)
        ax.set_xticks([])
        ax.set_yticks([])
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)
    print("wrote", path)


def ray_cones(tmp: str) -> None:
    path = os.path.join(tmp, "checker.exr")
    cones.write_texture(path)
    s = cones.mirror_scene(path)
    kw = dict(max_depth=cones.MAX_DEPTH)
    ref = np.asarray(s.render(spp=cones.REF_SPP, texture_filtering=False, seed=101, **kw).rgb)
    filt = np.asarray(s.render(spp=1, texture_filtering=True, seed=1, **kw).rgb)
    point = np.asarray(s.render(spp=1, texture_filtering=False, seed=1, **kw).rgb)
    # Crop: the three specular objects and the ground below them (rows 20-80).
    c = (slice(22, 78), slice(0, cones.W))
    err = np.abs(filt - ref).max(axis=2)
    panels([srgb(ref[c]), srgb(filt[c]), srgb(point[c]), err[c]],
           ["reference, 2048 spp point-sampled\n(glass sphere | mirror sphere | flat mirror)", "1 spp, ray-cone filtered", "1 spp, point-sampled",
            "|filtered - reference|"],
           os.path.join(REPO, "docs", "failure_ray_cones.png"), 3.6)


def catcher_rims(tmp: str) -> None:
    path = os.path.join(tmp, "checker.exr")
    rims.write_checker(path)
    kw = dict(max_depth=rims.MAX_DEPTH)
    full, objects = rims.rim_scene(path)
    truth = np.asarray(full.render(spp=2048, seed=101, **kw).rgb)
    for o in objects:
        full.set_instance_visible(o, False)
    photo = np.asarray(full.render(spp=2048, seed=202, **kw).rgb)
    du = rims.rim_scene(path, catcher=True, textured=False)[0].render(spp=1024, seed=7, **kw)
    dt = rims.rim_scene(path, catcher=True, textured=True)[0].render(spp=1024, seed=7, **kw)
    cu, ct = composite(photo, du, "ratio"), composite(photo, dt, "ratio")
    a = np.asarray(du.synthetic_alpha)
    rim = (a > 0) & (a < 1)
    ground = (a == 0) & (np.abs(truth - photo).max(axis=2) > 0.02 * float(photo.max()))
    scale = float(np.percentile(truth, 99.5))
    for name, c in (("ratio, uniform", cu), ("ratio, textured", ct), ("additive, textured", composite(photo, dt, "additive"))):
        e_rim = float(np.mean(np.abs(c[rim] - truth[rim])) / np.mean(truth[rim]))
        e_gr = float(np.mean(np.abs(c[ground] - truth[ground])) / np.mean(truth[ground]))
        worst = float(np.percentile(np.abs(c[rim] - truth[rim]).max(axis=1), 99)) / scale
        print(f"catcher rims converged (1024 spp), {name} catcher: rim px {int(rim.sum())} mean abs error "
              f"{100 * e_rim:.1f}% of the mean (99th percentile {100 * worst:.1f}% of white); changed ground px "
              f"{int(ground.sum())} {100 * e_gr:.1f}%")
    c = (slice(30, 80), slice(25, 110))
    err = np.abs(cu - truth).max(axis=2) / scale
    panels([srgb(truth[c] / scale), srgb(cu[c] / scale), srgb(ct[c] / scale), err[c]],
           ["full render (truth)", "composite, uniform catcher", "composite, textured catcher",
            "|uniform composite - truth| / white"],
           os.path.join(REPO, "docs", "failure_catcher_rims.png"), 3.6, vmax_err=0.1)


if __name__ == "__main__":
    with tempfile.TemporaryDirectory() as tmp:
        ray_cones(tmp)
        catcher_rims(tmp)
