"""Damaged image files are errors naming the file, for every image a scenario reads (photos,
textures, decals, HDR environment maps, a photo's depth map, occluder mask and environment),
found by ``synthgen validate``; harmless metadata warnings are printed once and the image is
used (io/decoder_messages.h). The real photos in ../shared/realdata all read without one."""
from __future__ import annotations

import glob
import os

import numpy as np
import OpenImageIO as oiio
import pytest

import synthgen as sg
from synthgen.cli import main
from synthgen.schema.errors import SceneFileError
from synthgen.scenario import check_inputs, load_scenario

W, H = 160, 96
REALDATA = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..", "..", "shared", "realdata"))


def _noise(h=H, w=W, seed=0):
    """Detail everywhere, so that a cut file loses pixels (and a JPEG is large enough to cut)."""
    rng = np.random.default_rng(seed)
    return (rng.random((h, w, 3)) * 0.8 + 0.1).astype(np.float32)


def _write(path, rgb, fmt=None):
    spec = oiio.ImageSpec(rgb.shape[1], rgb.shape[0], rgb.shape[2], fmt or (oiio.FLOAT if path.endswith(".exr")
                                                                             else oiio.UINT8))
    if path.endswith(".jpg"):
        spec.attribute("Compression", "jpeg:95")
    b = oiio.ImageBuf(spec)
    b.set_pixels(oiio.ROI(), np.ascontiguousarray(rgb, np.float32))
    assert b.write(path), b.geterror()


def _cut(path, keep):
    data = open(path, "rb").read()
    keep = keep if keep > 0 else len(data) + keep
    assert 0 < keep < len(data)
    with open(path, "wb") as f:
        f.write(data[:keep])


def _padded_jpeg(path, rgb):
    """A JPEG with 3 bytes between its first two segments: libjpeg's harmless "extraneous bytes
    before marker" warning."""
    _write(path, rgb)
    d = open(path, "rb").read()
    end_of_app0 = 4 + int.from_bytes(d[4:6], "big")
    with open(path, "wb") as f:
        f.write(d[:end_of_app0] + b"\x00\x01\x02" + d[end_of_app0:])


CALIBRATION = """intrinsics: {fx: 150.0}
ground: {camera_height: 1.5, pitch: 5.0}
objects: []
"""


def _scenario(tmp_path, photos=None, material="{type: diffuse, albedo: 0.5}", extra_object="", lights=""):
    bg = f"background: {{photos: [{photos}]}}\n" if photos else ""
    p = tmp_path / "s.yaml"
    p.write_text(f"""seed: 1
count: 2
resolution: [{W}, {H}]
{bg}objects:
  - class: box
    primitive: box
    size: [1, 1, 1]
    material: {material}
{extra_object}{lights}render: {{spp: 2}}
""")
    return str(p)


def _error(path):
    with pytest.raises(SceneFileError) as e:
        check_inputs(load_scenario(path))
    return e.value


@pytest.fixture
def photo(tmp_path):
    d = tmp_path / "photos"
    d.mkdir()
    _write(str(d / "road.jpg"), _noise())
    (d / "road.yaml").write_text(CALIBRATION)
    return d


@pytest.mark.parametrize("keep", [3000, -40])
def test_a_truncated_photo_is_an_error_at_validate(tmp_path, photo, capsys, keep):
    """A JPEG cut to its first 3000 bytes, or cut 40 bytes before its end (the decoder returns
    all but the last rows and warns "Premature end of JPEG file"): validate refuses it, naming
    the photo, and run writes no frame."""
    assert os.path.getsize(photo / "road.jpg") > 3000
    _cut(str(photo / "road.jpg"), keep)
    path = _scenario(tmp_path, photos="photos/road.jpg")
    e = _error(path)
    assert "road.jpg" in str(e) and ("damaged or truncated" in str(e) or "cannot" in str(e)), str(e)
    assert e.key_path.startswith("background"), e.key_path
    assert main(["validate", path]) == 2
    assert "road.jpg" in capsys.readouterr().err
    out = str(tmp_path / "ds")
    assert main(["run", path, "-o", out, "-n", "1", "--no-progress"]) != 0
    assert not glob.glob(os.path.join(out, "images", "*"))


def test_a_corrupt_photo_of_each_format_is_an_error(tmp_path):
    """PNG with a broken IDAT checksum region, EXR cut in its pixel data."""
    d = tmp_path / "photos"
    d.mkdir()
    _write(str(d / "a.png"), _noise())
    data = bytearray(open(d / "a.png", "rb").read())
    i = data.find(b"IDAT")
    data[i + 20:i + 60] = bytes(40)
    (d / "a.png").write_bytes(bytes(data))
    (d / "a.yaml").write_text(CALIBRATION)
    e = _error(_scenario(tmp_path, photos="photos/a.png"))
    assert "a.png" in str(e), str(e)
    _write(str(d / "b.exr"), _noise())
    _cut(str(d / "b.exr"), os.path.getsize(d / "b.exr") // 2)
    (d / "b.yaml").write_text(CALIBRATION)
    e = _error(_scenario(tmp_path, photos="photos/b.exr"))
    assert "b.exr" in str(e), str(e)


def test_damaged_files_the_photo_brings_are_errors_at_validate(tmp_path, photo):
    """The photo's depth map, occluder mask and environment map: decoded at validate."""
    d = photo
    _write(str(d / "depth.exr"), np.full((H, W, 1), 7.0, np.float32))
    _write(str(d / "mask.png"), np.zeros((H, W, 1), np.float32))
    _write(str(d / "env.exr"), _noise(32, 64))
    for name, key in (("depth.exr", "depth: {file: depth.exr}"), ("mask.png", "occluders: mask.png"),
                      ("env.exr", "envmap: {file: env.exr}")):
        (d / "road.yaml").write_text(CALIBRATION + key + "\n")
        path = _scenario(tmp_path, photos="photos/road.jpg")
        check_inputs(load_scenario(path))  # intact: fine
        good = open(d / name, "rb").read()
        _cut(str(d / name), len(good) // 2)
        e = _error(path)
        assert name in str(e), (name, str(e))
        (d / name).write_bytes(good)


def test_damaged_textures_and_environment_maps_are_errors_at_validate(tmp_path):
    _write(str(tmp_path / "t.jpg"), _noise(64, 64))
    _cut(str(tmp_path / "t.jpg"), -40)
    e = _error(_scenario(tmp_path, material="{type: diffuse, albedo: {texture: {type: image, file: t.jpg}}}"))
    assert "t.jpg" in str(e) and "damaged or truncated" in str(e), str(e)
    _write(str(tmp_path / "sky.exr"), _noise(32, 64))
    _cut(str(tmp_path / "sky.exr"), os.path.getsize(tmp_path / "sky.exr") // 2)
    e = _error(_scenario(tmp_path, lights="lights:\n  - {type: envmap, file: sky.exr}\n"))
    assert "sky.exr" in str(e), str(e)


def test_a_harmless_metadata_warning_is_printed_once_and_the_photo_used(tmp_path, photo, capfd):
    _padded_jpeg(str(photo / "road.jpg"), _noise())
    path = _scenario(tmp_path, photos="photos/road.jpg")
    check_inputs(load_scenario(path))
    px, info = sg._core.read_image_info(str(photo / "road.jpg"))
    px2, _ = sg._core.read_image_info(str(photo / "road.jpg"))
    assert px.shape == (H, W, 3) and np.array_equal(px, px2)
    assert len(info["warnings"]) == 1 and "extraneous bytes" in info["warnings"][0], info
    err = capfd.readouterr().err
    assert err.count("extraneous bytes") == 1 and "road.jpg" in err and "synthgen: warning" in err, err
    # The same file cut: the first (harmless) warning does not hide the truncation.
    _cut(str(photo / "road.jpg"), -40)
    with pytest.raises(sg.FileError, match="road.jpg.*end-of-image marker"):
        sg._core.read_image_info(str(photo / "road.jpg"))


@pytest.mark.skipif(not os.path.isdir(REALDATA), reason="needs ../shared/realdata")
def test_every_real_photo_reads_without_an_error():
    files = sorted(f for ext in ("jpg", "jpeg", "png") for f in glob.glob(os.path.join(REALDATA, "**", "*." + ext),
                                                                          recursive=True))
    assert len(files) > 400, len(files)
    warned = []
    for f in files:
        px, info = sg._core.read_image_info(f)
        assert px.ndim == 3 and px.shape[0] > 0 and np.isfinite(px).all(), f
        warned += [(f, w) for w in info["warnings"]]
    assert len(warned) < len(files), warned[:5]
