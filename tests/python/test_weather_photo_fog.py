"""Fog and haze over photo backgrounds (docs/weather.md): Koschmieder's law in image space over
the composite, from the photo's depth map where the pixel is the photo and the render's depth
where an inserted object is -- the same extinction the medium would have (3.912 / visibility),
the same path inside the layer -- with the airlight from the photo's dark channel. The "photo"
is a render of the empty world with its depth map, so every answer is known."""
import os

import numpy as np
import pytest

import synthgen as sg
from synthgen.scenario import check_inputs, load_scenario

from test_augmented_photo import CALIBRATION, H, W, _photo, _scenario, _write_exr


@pytest.fixture(scope="module")
def photo_with_depth(tmp_path_factory):
    """The photo (folder ``photos``) with its depth map (beside the folder: a file in it would be
    a photo) -- the empty world's render and its camera z (+inf: sky)."""
    root = tmp_path_factory.mktemp("fogphoto")
    d = root / "photos"
    d.mkdir()
    rgb = _photo(str(d / "street.exr"))
    from synthgen.background.calibration import Calibration
    from test_augmented_photo import CAL
    from synthgen import primitives as P

    s = sg.Scene()
    g = P.ground()
    s.add_instance(s.add_mesh(g["positions"], g["indices"], g["normals"], g["uvs"]), np.eye(4, dtype=np.float32))
    s.set_camera(Calibration(**CAL).camera())
    depth = np.asarray(s.render(spp=1, labels_only=True).depth, np.float32)
    _write_exr(str(root / "depth.exr"), np.repeat(depth[..., None], 3, axis=2))
    (d / "calibration.yaml").write_text(CALIBRATION + f"depth: {{file: {root / 'depth.exr'}}}\nobjects: []\n")
    return root, rgb, depth


def _frames(root, tmp_path, weather, name, count=2):
    os.symlink(root / "photos", tmp_path / f"photos_{name}")
    path = _scenario(tmp_path, photos=f"photos_{name}", count=count, extra=weather)
    os.rename(path, tmp_path / f"{name}.yaml")
    sc = sg.Scenario(str(tmp_path / f"{name}.yaml"))
    return [sc.frame(k) for k in range(count)]


def _expected_transmittance(f, beta, top):
    """exp(-beta x the pixel ray's path below ``top`` up to its depth), from the frame's own
    depth and camera (the distance along the ray; sky: up to the layer's top)."""
    K = np.asarray(f.meta["camera"]["K"])
    wfc = np.asarray(f.meta["camera"]["world_from_camera"])
    v, u = np.mgrid[0:H, 0:W] + 0.5
    d = np.stack([(u - K[0, 2]) / K[0, 0], (v - K[1, 2]) / K[1, 1], np.ones((H, W))], axis=-1)
    per_z = np.linalg.norm(d, axis=-1)
    dy = (d / per_z[..., None]) @ wfc[:3, :3].T
    y0 = wfc[1, 3]
    dist = np.asarray(f.depth, np.float64) * per_z
    up = dy[..., 1] > 0
    path = np.where(np.isfinite(dist), dist, np.where(up, (top - y0) / np.where(up, dy[..., 1], 1.0), np.inf))
    assert np.all(np.isfinite(dist) | up), "every pixel without a depth is sky"
    return np.exp(-beta * path)


def test_fog_on_a_photo_is_koschmieder_from_its_depth(photo_with_depth, tmp_path):
    """Each pixel of the fogged frame is J t + A (1 - t): J the same frame without fog (a scenario
    whose fog never happens), t = exp(-3.912 / V x the path in the layer) from the frame's depth
    (the photo's map, the object's render where it shows) and camera, A the mean of the photo's
    pixels at the brightest 0.1% of its dark channel (as meta records it); the objects' labels
    carry the same t; photo pixels and object pixels at the same distance get the same t."""
    from scipy.ndimage import minimum_filter

    root, photo, depth = photo_with_depth
    fog = _frames(root, tmp_path, "weather: {fog: {visibility: 40, top: 30}}", "fog")
    clear = _frames(root, tmp_path, "weather: {fog: {probability: 0, visibility: 40, top: 30}}", "clear")
    dc = minimum_filter(photo.min(axis=2), size=15, mode="nearest").ravel()
    k = max(1, int(round(0.001 * dc.size)))
    a = photo.reshape(-1, 3)[np.argsort(dc)[-k:]].astype(np.float64).mean(axis=0)
    checked = 0
    for f, j in zip(fog, clear):
        assert j.meta["weather"] is None and np.array_equal(f.instance_id, j.instance_id)
        assert np.array_equal(f.depth, j.depth)
        w = f.meta["weather"]["fog"]
        assert w["visibility"] == 40.0 and w["on_photo"] == "koschmieder"
        assert w["extinction"] == pytest.approx(3.912 / 40, rel=1e-6)
        np.testing.assert_allclose(w["airlight"], a, rtol=1e-5)
        t = _expected_transmittance(f, 3.912 / 40, 30.0)
        expect = j.rgb * t[..., None] + np.asarray(w["airlight"]) * (1 - t[..., None])
        np.testing.assert_allclose(f.rgb, expect, rtol=1e-4, atol=1e-5)
        assert t.min() < 0.01 and t.max() > 0.6, "the view spans thin to thick fog"
        for o in f.meta["objects"]:
            if o.get("dropped") or not o.get("visible_pixels"):
                continue
            m = f.instance_id == o["instance_id"]
            assert o["weather"]["transmittance"] == pytest.approx(float(t[m].mean()), abs=1e-5)
            # The photo at the same distance as the object's pixels is fogged alike: the
            # realized transmittance (I - A) / (J - A) of ground pixels whose distance is within
            # 1 cm of an object pixel's is that pixel's.
            dist = f.depth * np.linalg.norm(np.stack(np.broadcast_arrays(
                ((np.arange(W) + 0.5 - f.meta["camera"]["K"][0][2]) / f.meta["camera"]["K"][0][0])[None, :],
                ((np.arange(H) + 0.5 - f.meta["camera"]["K"][1][2]) / f.meta["camera"]["K"][1][1])[:, None],
                np.ones((H, W))), axis=-1), axis=-1)
            ground = (f.instance_id == 0) & np.isfinite(dist)
            realized = (f.rgb - a) / (j.rgb - a)
            for py, px in zip(*np.nonzero(m)):
                near = ground & (np.abs(dist - dist[py, px]) < 0.01)
                if not near.any():
                    continue
                gy, gx = np.argwhere(near)[0]
                if np.all(np.abs(j.rgb[gy, gx] - a) > 0.05) and np.all(np.abs(j.rgb[py, px] - a) > 0.05):
                    np.testing.assert_allclose(realized[py, px], realized[gy, gx], atol=2e-3)
                    checked += 1
    assert checked >= 10, checked


def test_haze_on_a_photo_uses_its_own_extinction(photo_with_depth, tmp_path):
    root, _, _ = photo_with_depth
    (f,) = _frames(root, tmp_path, "weather: {haze: {visibility: 300, top: 500}}", "haze", count=1)
    w = f.meta["weather"]["haze"]
    assert w["extinction"] == pytest.approx(3.912 / 300, rel=1e-6)


def test_fog_over_a_photo_without_depth_is_an_error_at_its_key(tmp_path):
    """A photo without a depth map cannot be fogged consistently: refused at weather.fog before
    anything renders."""
    d = tmp_path / "photos"
    d.mkdir()
    _photo(str(d / "street.exr"))
    (d / "calibration.yaml").write_text(CALIBRATION + "objects: []\n")
    path = _scenario(tmp_path, photos=str(d), extra="weather: {fog: {visibility: 50}}")
    with pytest.raises(sg.SynthgenError, match=r"aug\.yaml:\d+:\d+: weather\.fog: over a photo background it "
                                               r"needs the photo's depth map: .*street\.exr has none"):
        check_inputs(load_scenario(path))
