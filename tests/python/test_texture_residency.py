"""Loading only the mip levels a frame needs (docs/texture_lod.md): tiled mip-mapped copies of
image files written once and read lazily, levels dropped and read back, the render with the
estimated levels equal to the full one where the renderer reads no finer level, and a scene
rendered without the estimate seeing every level."""
from __future__ import annotations

import hashlib
import math

import numpy as np
import OpenImageIO as oiio
import pytest

from synthgen._core import PinholeCamera, Scene, TextureRef
from synthgen.scene import primitives as P

N = 512
W, H, FOV = 160, 120, 40.0
HEIGHT = 5.0


def write_png(path, n=N, channels=3):
    rng = np.random.default_rng(7)
    tex = rng.integers(0, 256, (n, n, channels), dtype=np.uint8)
    out = oiio.ImageOutput.create(str(path))
    out.open(str(path), oiio.ImageSpec(n, n, channels, oiio.UINT8))
    out.write_image(tex)
    out.close()


def plane_scene(png, cache_dir=None, memory=False, size=6.0, look_at=(0.0, 0.0)):
    """A 6 m textured square seen head-on from HEIGHT metres (every pixel 2.59 texels of the
    512^2 map: the estimate picks level 1), under a constant environment; or a ``size`` m one
    seen above the point ``look_at`` (x, z)."""
    s = Scene()
    if cache_dir is not None:
        s.set_mip_cache_dir(str(cache_dir))
    if memory:
        buf = oiio.ImageBuf(str(png))
        t = s.add_image_texture(np.asarray(buf.get_pixels(oiio.UINT8)), {})
    else:
        t = s.add_texture("image", {"file": str(png)})
    m = s.add_material("diffuse", {"albedo": TextureRef(t)})
    pl = P.plane(size, size)
    mesh = s.add_mesh(pl["positions"], pl["indices"], normals=pl["normals"], uvs=pl["uvs"])
    s.add_instance(mesh, np.eye(4), class_id=1, material_id=m)
    s.add_light("environment", {"radiance": 1.0})
    x, z = look_at
    s.set_camera(PinholeCamera.from_fov(FOV, W, H, PinholeCamera.look_at((x, HEIGHT, z), (x, 0, z), (0, 0, 1))))
    s.commit()
    return s, t


def digest(s, spp=1):
    r = s.render(spp=spp, max_depth=2, seed=11)
    return hashlib.sha256(np.asarray(r.rgb).tobytes()).hexdigest()


def rgb(s, spp):
    return np.asarray(s.render(spp=spp, max_depth=2, seed=11).rgb)


def test_mip_file_written_once_then_read_lazily(tmp_path):
    png = tmp_path / "noise.png"
    write_png(png)
    cache = tmp_path / "mips"
    full, _ = plane_scene(png)  # no cache: decoded whole, as always
    reference = digest(full)
    s1, _ = plane_scene(png, cache)
    assert s1.commit_stats["mip_files_written"] == 1 and s1.commit_stats["image_loads"] == 1
    assert len(list(cache.glob("*.exr"))) == 1
    assert digest(s1) == reference
    # A second scene (another worker, another run) reads the copy lazily: only the tail now.
    s2, t = plane_scene(png, cache)
    assert s2.commit_stats["mip_files_opened"] == 1 and s2.commit_stats["image_loads"] == 0
    row = s2.estimate_texture_resolution()["textures"][0]
    tail_bytes = sum((N >> k) ** 2 for k in range(row["tail_level"], 10)) * 12
    assert row["first_resident"] == row["tail_level"] == 3 and row["bytes_resident"] == tail_bytes
    # Rendered without choosing levels: every level is read first; the image is the decoded one's.
    assert digest(s2) == reference
    assert s2.estimate_texture_resolution()["textures"][0]["first_resident"] == 0


def lod(s, spp=1, budget=0.0):
    """A render with texture_lod (texture memory budget `budget` MiB): (rgb, stats)."""
    r = s.render(spp=spp, max_depth=2, seed=11, texture_lod=True, texture_budget_mib=budget)
    return np.asarray(r.rgb), r.stats


@pytest.mark.parametrize("memory", [False, True], ids=["file", "in-memory pixels"])
def test_estimated_levels_render_like_full_resolution(tmp_path, memory):
    png = tmp_path / "noise.png"
    write_png(png)
    full, _ = plane_scene(png, memory=memory)
    reference = digest(full)
    s, t = plane_scene(png, tmp_path / "mips", memory=memory)
    rgb1, st = lod(s)
    row = s.estimate_texture_resolution()["textures"][0]
    print(f"texture_lod: {st['texture_bytes_resident']} of {st['texture_bytes_full']} bytes resident "
          f"(level {row['first_used']}; estimate {st['texture_lod_time_s'] * 1e3:.1f} ms)")
    assert row["needed_level"] == row["first_used"] == row["first_resident"] == 1
    assert st["texture_bytes_resident"] == row["bytes_needed"] < st["texture_bytes_full"] / 3
    # At 1 spp every camera cone is a pixel wide: the renderer reads level 1 or coarser
    # everywhere, so without level 0 no pixel changes.
    assert hashlib.sha256(rgb1.tobytes()).hexdigest() == reference
    # At 16 spp the cones are a quarter pixel: the full render averages level-0 texels over
    # the pixel, the level-1 one averages level 1 (one box filter more). On white noise -- all
    # of its energy at the finest scale, the worst case -- that costs contrast (documented).
    a, b = rgb(full, 16), lod(s, 16)[0]
    psnr = 10 * math.log10(1.0 / float(np.mean((np.clip(a, 0, 1) - np.clip(b, 0, 1)) ** 2)))
    print(f"16 spp, white-noise texture: PSNR of the level-1 render against the full one {psnr:.1f} dB")
    assert 20 < psnr < 40
    # A render without texture_lod reads every level again, as if none had been dropped.
    assert digest(s, 16) == hashlib.sha256(a.tobytes()).hexdigest()
    # set_texture_levels: coarser than the tail is clamped to it; level 0 is read back.
    s.set_texture_levels({t: 99})
    assert s.estimate_texture_resolution()["textures"][0]["first_resident"] == row["tail_level"]
    s.set_texture_levels({t: 0})
    assert s.estimate_texture_resolution()["textures"][0]["first_resident"] == 0


@pytest.mark.parametrize("memory", [False, True], ids=["file", "in-memory pixels"])
def test_only_the_tiles_the_camera_sees_are_read(tmp_path, memory):
    # A 24 m square of the 512^2 map seen from 5 m above a point off its centre: level 0
    # (0.6 texels per pixel) in the 64^2-texel tiles under the view, 3.6 x 2.7 m of 24 x 24 m.
    png = tmp_path / "noise.png"
    write_png(png)
    view = dict(size=24.0, look_at=(5.0, -7.0))
    full, _ = plane_scene(png, memory=memory, **view)
    s, t = plane_scene(png, tmp_path / "mips", memory=memory, **view)
    rgb1, st = lod(s, 16)
    row = s.estimate_texture_resolution()["textures"][0]
    print(f"tiles: {row['needed_tiles']} of {row['tiles']} at level {row['needed_level']}; "
          f"{st['texture_bytes_resident']} of {st['texture_bytes_full']} bytes resident")
    assert row["needed_level"] == row["first_used"] == 0 and row["tiles"] == 64
    assert 2 <= row["needed_tiles"] <= 9
    # Resident: the used tiles of level 0, levels 1 and coarser whole.
    level1_on = sum((N >> k) ** 2 for k in range(1, 10)) * 12
    assert st["texture_bytes_resident"] == row["bytes_needed"] == level1_on + row["needed_tiles"] * 64 * 64 * 12
    # Every lookup falls in a resident tile: the image is the full-resolution render's, bit for bit.
    assert np.array_equal(rgb1, rgb(full, 16))
    # Seen from above the centre, other tiles: read then, and the image is again the full one's.
    s.set_camera(PinholeCamera.from_fov(FOV, W, H, PinholeCamera.look_at((0, HEIGHT, 0), (0, 0, 0), (0, 0, 1))))
    full.set_camera(PinholeCamera.from_fov(FOV, W, H, PinholeCamera.look_at((0, HEIGHT, 0), (0, 0, 0), (0, 0, 1))))
    assert np.array_equal(lod(s, 4)[0], rgb(full, 4))


def test_levels_kept_from_earlier_frames_change_no_pixel(tmp_path):
    # Within the budget a worker keeps levels it read for earlier frames (here: all of them);
    # lookups still read only this frame's levels, so the image is the fresh worker's.
    png = tmp_path / "noise.png"
    write_png(png)
    fresh, _ = plane_scene(png, tmp_path / "mips")
    a, st_fresh = lod(fresh, 4)
    warm, t = plane_scene(png, tmp_path / "mips")
    warm.set_texture_levels({t: 0})
    b, st_warm = lod(warm, 4, budget=256.0)
    assert st_warm["texture_bytes_resident"] == st_warm["texture_bytes_full"] > st_fresh["texture_bytes_resident"]
    assert np.array_equal(a, b)
    # Over the budget the unused level is freed.
    c, st = lod(warm, 4, budget=0.0)
    assert st["texture_bytes_resident"] == st_fresh["texture_bytes_resident"] and np.array_equal(a, c)


def test_alpha_stays_whole_while_colour_levels_drop(tmp_path):
    png = tmp_path / "rgba.png"
    write_png(png, channels=4)
    reference = digest(plane_scene(png)[0])
    plane_scene(png, tmp_path / "mips")  # writes the copy: colour and alpha
    s, t = plane_scene(png, tmp_path / "mips")
    assert s.commit_stats["mip_files_opened"] == 1
    rgb1, st = lod(s)
    row = s.estimate_texture_resolution()["textures"][0]
    alpha_bytes = sum((N >> k) ** 2 for k in range(10)) * 4
    assert row["alpha"] and row["first_used"] == 1
    assert st["texture_bytes_resident"] == sum((N >> k) ** 2 for k in range(1, 10)) * 12 + alpha_bytes
    assert hashlib.sha256(rgb1.tobytes()).hexdigest() == reference


def test_unknown_or_non_image_texture_is_an_error(tmp_path):
    png = tmp_path / "noise.png"
    write_png(png, 8)
    s, t = plane_scene(png)
    c = s.add_texture("constant", {"value": 0.5})
    with pytest.raises(Exception, match="texture 99 does not exist"):
        s.set_texture_levels({99: 0})
    with pytest.raises(Exception, match=f"texture {c}: not an image texture"):
        s.set_texture_levels({c: 0})


def test_a_corrupt_mip_file_is_rebuilt(tmp_path):
    png = tmp_path / "noise.png"
    write_png(png)
    cache = tmp_path / "mips"
    reference = digest(plane_scene(png)[0])
    plane_scene(png, cache)
    (f,) = cache.glob("*.exr")
    f.write_bytes(b"not an exr at all")
    s, _ = plane_scene(png, cache)
    assert s.commit_stats["mip_files_written"] == 1 and s.commit_stats["image_loads"] == 1
    assert digest(s) == reference


def test_over_budget_the_least_recently_seen_pyramid_drops_first(tmp_path):
    # Two textured squares 10 m apart, the camera over one of them at a time; each needs
    # level 1 (1 MiB) of its own 512^2 map; a 1.5 MiB budget holds one of them.
    a_png, b_png = tmp_path / "a.png", tmp_path / "b.png"
    write_png(a_png)
    write_png(b_png)  # the same texels under another path: a pyramid of its own
    s = Scene()
    s.set_mip_cache_dir(str(tmp_path / "mips"))
    ids = []
    for png, x in ((a_png, -5.0), (b_png, 5.0)):
        t = s.add_texture("image", {"file": str(png)})
        m = s.add_material("diffuse", {"albedo": TextureRef(t)})
        pl = P.plane(6.0, 6.0)
        mesh = s.add_mesh(pl["positions"], pl["indices"], normals=pl["normals"], uvs=pl["uvs"])
        T = np.eye(4)
        T[0, 3] = x
        s.add_instance(mesh, T, class_id=1, material_id=m)
        ids.append(t)
    s.add_light("environment", {"radiance": 1.0})

    def frame(x):
        s.set_camera(PinholeCamera.from_fov(FOV, W, H, PinholeCamera.look_at((x, HEIGHT, 0), (x, 0, 0), (0, 0, 1))))
        s.render(spp=1, max_depth=1, seed=1, texture_lod=True, texture_budget_mib=1.5)
        rows = {r["texture_id"]: r for r in s.estimate_texture_resolution()["textures"]}
        return [(rows[t]["first_used"], rows[t]["first_resident"]) for t in ids]

    first = frame(-5.0)
    tail = s.estimate_texture_resolution()["textures"][0]["tail_level"]
    assert first == [(1, 1), (tail, tail)]   # A seen: level 1; B never seen: its tail
    assert frame(5.0) == [(tail, tail), (1, 1)]    # B seen; A (least recently seen) freed
    assert frame(-5.0) == [(1, 1), (tail, tail)]   # A read back; B freed
