"""Writers: exact round trips through OpenImageIO, sRGB encoding, 16-bit ids, meta.json,
atomic replacement. No rendering needed."""
from __future__ import annotations

import json
import os

import numpy as np
import OpenImageIO as oiio
import pytest

import synthgen
from synthgen.outputs import files as W
from synthgen.outputs import render as R

H, W_ = 6, 9


def read(path):
    buf = oiio.ImageBuf(str(path))
    assert not buf.has_error, buf.geterror()
    return buf.spec(), buf


def arrays(seed=0):
    rng = np.random.default_rng(seed)
    depth = (rng.random((H, W_)) * 20).astype(np.float32)
    depth[rng.random((H, W_)) < 0.3] = np.inf
    depth[0, 0] = np.float32(1e-30)  # denormal-ish tiny value must survive too
    inst = rng.integers(0, 65536, (H, W_)).astype(np.uint32)
    inst[0, :2] = [0, 65535]
    return {
        "rgb": (rng.random((H, W_, 3)) * 3 - 0.5).astype(np.float32),
        "depth": depth,
        "normal": rng.standard_normal((H, W_, 3)).astype(np.float32),
        "albedo": rng.random((H, W_, 3)).astype(np.float32),
        "instance_id": inst,
        "class_id": rng.integers(0, 20, (H, W_)).astype(np.uint32),
    }


class FakeCamera:
    fx, fy, cx, cy = 50.0, 51.0, 4.5, 3.0
    width, height = W_, H
    world_from_camera = np.array([[0, 0, 1, 1], [1, 0, 0, 2], [0, 1, 0, 3], [0, 0, 0, 1]], dtype=np.float32)


def srgb_reference(x):
    x = np.clip(np.nan_to_num(np.asarray(x, np.float64), nan=0.0), 0, 1)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * x ** (1 / 2.4) - 0.055)


def test_srgb_oetf_known_values():
    x = np.array([0.0, 0.0031308, 0.18, 0.5, 1.0, 2.0, -1.0, np.nan])
    y = W.srgb_encode(x)
    np.testing.assert_allclose(y[:5], [0.0, 0.0404499, 0.4613561, 0.7353570, 1.0], atol=1e-6)
    assert y[5] == 1.0 and y[6] == 0.0 and y[7] == 0.0
    # continuous at the breakpoint
    assert abs(W.srgb_encode(0.0031308 - 1e-9) - W.srgb_encode(0.0031308 + 1e-9)) < 1e-6


def test_exr_round_trip_is_bit_exact(tmp_path):
    a = arrays()
    for name in ("rgb", "normal", "albedo", "depth"):
        path = W.write_exr(tmp_path / f"{name}.exr", a[name])
        spec, buf = read(path)
        assert spec.format == oiio.FLOAT
        back = buf.get_pixels(oiio.FLOAT)
        expect = a[name] if a[name].ndim == 3 else a[name][:, :, None]
        assert back.shape == expect.shape
        assert np.array_equal(back.view(np.uint32), expect.view(np.uint32)), name
    spec, buf = read(tmp_path / "depth.exr")
    assert spec.nchannels == 1 and list(spec.channelnames) == ["Y"]
    depth = buf.get_pixels(oiio.FLOAT)[..., 0]
    assert np.array_equal(np.isinf(depth), np.isinf(a["depth"])) and np.isinf(depth).any()
    assert depth[0, 0] == np.float32(1e-30)


def test_srgb_png_matches_the_formula(tmp_path):
    rgb = arrays()["rgb"]
    rgb[0, 0] = [np.nan, -1.0, 1e9]
    path = W.write_srgb_png(tmp_path / "rgb.png", rgb)
    spec, buf = read(path)
    assert spec.format == oiio.UINT8 and spec.nchannels == 3
    back = buf.get_pixels(oiio.UINT8).astype(np.float64) / 255.0
    expect = srgb_reference(rgb)
    assert np.abs(back - expect).max() <= 0.5 / 255 + 1e-9  # rounded to nearest
    assert list(back[0, 0]) == [0.0, 0.0, 1.0]


def test_id_png_is_16_bit_and_exact(tmp_path):
    ids = arrays()["instance_id"]
    path = W.write_id_png(tmp_path / "instance.png", ids)
    spec, buf = read(path)
    assert spec.format == oiio.UINT16 and spec.nchannels == 1
    back = buf.get_pixels(oiio.UINT16)[..., 0]
    assert np.array_equal(back, ids) and back.max() == 65535


@pytest.mark.parametrize("bad, fragment", [(65536, "found 65536"), (-1, "found -1")])
def test_id_png_rejects_out_of_range_ids(tmp_path, bad, fragment):
    ids = np.zeros((4, 5), np.int64)
    ids[1, 2] = bad
    with pytest.raises(synthgen.SynthgenError) as info:
        W.write_id_png(tmp_path / "class.png", ids)
    msg = str(info.value)
    assert "class.png" in msg and "[0, 65535]" in msg and fragment in msg and "1 pixel" in msg
    assert os.listdir(tmp_path) == []


def test_write_outputs_files_and_meta(tmp_path):
    a = arrays(3)
    settings = {"spp": 4, "max_depth": 3, "rr_depth": 5, "seed": 11, "threads": 2, "tile_size": 16}
    stats = {"wall_time_s": 0.5, "samples_per_s": 1e6, "rays_per_s": 2e6}
    meta = R.make_meta(camera=FakeCamera(), settings=settings, stats=stats, scene={"source": "x.yaml"},
                       extra={"note": "hello"})
    out = tmp_path / "frame" / "0001"
    paths = R.write_outputs(out, a, meta)
    assert list(paths) == list(R.OUTPUT_FILES)
    assert sorted(os.listdir(out)) == sorted(R.OUTPUT_FILES)  # and no temporary files left
    for name, path in paths.items():
        assert path == str(out / name) and os.path.getsize(path) > 0
    _, buf = read(paths["class.png"])
    assert np.array_equal(buf.get_pixels(oiio.UINT16)[..., 0], a["class_id"])
    _, buf = read(paths["depth.exr"])
    assert np.array_equal(buf.get_pixels(oiio.FLOAT)[..., 0].view(np.uint32), a["depth"].view(np.uint32))

    m = json.loads((out / "meta.json").read_text())
    assert m["settings"] == settings and m["seed"] == 11 and m["stats"] == stats
    assert m["camera"]["K"] == [[50.0, 0.0, 4.5], [0.0, 51.0, 3.0], [0.0, 0.0, 1.0]]
    assert m["camera"]["world_from_camera"] == FakeCamera.world_from_camera.tolist()
    assert (m["camera"]["width"], m["camera"]["height"]) == (W_, H) and m["image_size"] == [W_, H]
    assert m["versions"]["synthgen"] == synthgen.__version__
    assert m["versions"]["OpenImageIO"] == oiio.VERSION_STRING
    assert m["scene"] == {"source": "x.yaml"} and m["note"] == "hello"
    assert m["files"] == list(R.OUTPUT_FILES)


def test_write_outputs_checks_everything_before_writing(tmp_path):
    a = arrays()
    a["class_id"] = a["class_id"].astype(np.int64) + 70000
    with pytest.raises(synthgen.SynthgenError, match="class_id: ids must lie in \\[0, 65535\\]"):
        R.write_outputs(tmp_path / "out", a, {})
    assert not (tmp_path / "out").exists()
    a = arrays()
    a["depth"] = a["depth"][:, :-1]
    with pytest.raises(synthgen.SynthgenError, match="'depth' has shape"):
        R.write_outputs(tmp_path / "out", a, {})
    a = arrays()
    del a["albedo"]
    with pytest.raises(synthgen.SynthgenError, match="missing array 'albedo'"):
        R.write_outputs(tmp_path / "out", a, {})


def test_interrupted_write_keeps_the_old_file(tmp_path, monkeypatch):
    path = tmp_path / "rgb.exr"
    old = np.ones((H, W_, 3), np.float32)
    W.write_exr(path, old)
    before = path.read_bytes()

    def interrupted(tmp, final):
        assert os.path.exists(tmp) and os.path.dirname(tmp) == str(tmp_path)
        raise KeyboardInterrupt

    monkeypatch.setattr(W, "_commit", interrupted)
    with pytest.raises(KeyboardInterrupt):
        W.write_exr(path, np.zeros((H, W_, 3), np.float32))
    assert path.read_bytes() == before
    assert os.listdir(tmp_path) == ["rgb.exr"]  # the temporary file was removed


def test_json_is_strict_and_readable(tmp_path):
    path = W.write_json(tmp_path / "m.json", {"a": float("inf"), "b": np.float32(0.5), "c": np.arange(3),
                                              "m": np.eye(2)})
    text = open(path).read()
    assert json.loads(text) == {"a": None, "b": 0.5, "c": [0, 1, 2], "m": [[1.0, 0.0], [0.0, 1.0]]}
    assert "[1.0, 0.0]" in text  # matrix rows on one line


def test_camera_meta_of_a_real_camera():
    wfc = synthgen.PinholeCamera.look_at([1, 2, 3], [0, 0, 0], [0, 1, 0])
    cam = synthgen.PinholeCamera.from_fov(50, 64, 48, wfc)
    m = R.camera_meta(cam)
    np.testing.assert_allclose(m["K"], cam.K)
    np.testing.assert_allclose(m["world_from_camera"], wfc)
    assert m["convention"] == "opencv" and (m["width"], m["height"]) == (64, 48)
