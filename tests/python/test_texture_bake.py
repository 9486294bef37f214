"""Procedural textures baked at the resolution the camera needs (`bake: auto`,
docs/texture_lod.md): the image's size from the estimate's footprints, renders against the
procedural evaluation, determinism, and the errors of textures that cannot bake."""
from __future__ import annotations

import hashlib
import math

import numpy as np
import pytest

from synthgen._core import PinholeCamera, Scene, SynthgenError, TextureRef
from synthgen.scene import primitives as P

W, H, FOV, HEIGHT, SIZE = 160, 120, 40.0, 5.0, 6.0


def noise_scene(bake="auto", mapping="uv"):
    """A 6 m square with uv-mapped fbm noise seen head-on from 5 m, under a constant sky."""
    s = Scene()
    t = s.add_texture("noise", {"pattern": "fbm", "octaves": 8, "mapping": mapping, "scale": 40.0, "bake": bake,
                                "ramp_positions": [0.0, 1.0], "ramp_colors": [0.1, 0.15, 0.2, 0.8, 0.7, 0.5]})
    m = s.add_material("diffuse", {"albedo": TextureRef(t)})
    pl = P.plane(SIZE, SIZE)
    mesh = s.add_mesh(pl["positions"], pl["indices"], normals=pl["normals"], uvs=pl["uvs"])
    s.add_instance(mesh, np.eye(4), class_id=1, material_id=m)
    s.add_light("environment", {"radiance": 1.0})
    s.set_camera(PinholeCamera.from_fov(FOV, W, H, PinholeCamera.look_at((0, HEIGHT, 0), (0, 0, 0), (0, 0, 1))))
    s.commit()
    return s


def render(s, spp, lod):
    r = s.render(spp=spp, max_depth=2, seed=5, texture_lod=lod)
    return np.asarray(r.rgb), r.stats


def pyramid_bytes(w, h):
    n = 0
    while True:
        n += w * h * 3 * 4
        if w == 1 and h == 1:
            return n
        w, h = max(1, w // 2), max(1, h // 2)


def test_baked_image_has_one_texel_per_pixel_and_renders_like_the_noise():
    procedural = noise_scene()
    baked = noise_scene()
    a, st_a = render(procedural, 16, False)
    b, st_b = render(baked, 16, True)
    assert st_a["texture_baked_bytes"] == 0
    # The view: 3.64 m over 120 rows from 5 m, 0.0303 m per pixel = 0.00505 uv; the rectangle
    # seen, 0.81 x 0.61 uv, plus two texels a side, is 164 x 124 texels: 256 x 128.
    assert st_b["texture_baked_bytes"] == pyramid_bytes(256, 128)
    mse = float(np.mean((np.clip(a, 0, 1) - np.clip(b, 0, 1)) ** 2))
    psnr = 10 * math.log10(1.0 / mse)
    print(f"16 spp: PSNR of the baked render against the evaluated one {psnr:.1f} dB; "
          f"bake + estimate {st_b['texture_lod_time_s'] * 1e3:.0f} ms, {st_b['texture_baked_bytes']} bytes")
    assert psnr > 35
    # The same frame again: the same image (kept), the same pixels.
    assert np.array_equal(render(baked, 16, True)[0], b)
    # Without texture_lod the noise is evaluated again, as if never baked.
    assert np.array_equal(render(baked, 16, False)[0], a)


def test_bake_needs_uv_mapping():
    with pytest.raises(SynthgenError, match="bake.*needs mapping: uv"):
        noise_scene(mapping="object")


def test_bake_off_is_the_procedural_texture():
    off, auto = noise_scene("off"), noise_scene("auto")
    a, st = render(off, 4, True)
    assert st["texture_baked_bytes"] == 0
    b, _ = render(auto, 4, False)
    assert hashlib.sha256(a.tobytes()).hexdigest() == hashlib.sha256(b.tobytes()).hexdigest()
