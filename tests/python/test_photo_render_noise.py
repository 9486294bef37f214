"""Objects inserted into a photo are rendered until they are less noisy than the photo
(synthgen.frame.photo_samples: background.match.render_noise, max_spp), and what camera matching
could not match is reported per object in the frame's meta (background.camera_match.unmatched)
and in the run summary. The photo is a render of the empty world with Gaussian noise of a known
sigma added in sRGB, so the target is known."""
from __future__ import annotations

import json

import numpy as np
import OpenImageIO as oiio
import pytest

import synthgen as sg
from synthgen import primitives as P
from synthgen.background.calibration import Calibration
from synthgen.post.photo.measure import _inner, linear, srgb

W, H = 128, 88
CAL = dict(width=W, height=H, fx=115.0, fy=115.0, cx=64.0, cy=41.0, camera_height=1.6, pitch=6.0, roll=0.0)
SUN = (230.0, 35.0)
#: The photo's noise (sRGB sigma): below the 16-spp render's own on the object (0.0071 measured).
PHOTO_SIGMA = 0.006


@pytest.fixture(scope="module")
def photo_dir(tmp_path_factory):
    d = tmp_path_factory.mktemp("noise") / "photos"
    d.mkdir()
    s = sg.Scene()
    g = P.ground()
    s.add_instance(s.add_mesh(g["positions"], g["indices"], g["normals"], g["uvs"]), np.eye(4, dtype=np.float32),
                   material_id=s.add_material("diffuse", {"albedo": 0.15}))
    s.add_light("sky", {"elevation": SUN[1], "azimuth": SUN[0], "strength": 0.02})
    s.set_camera(Calibration(**CAL).camera())
    rgb = np.array(s.render(spp=128, seed=0).rgb)
    enc = srgb(rgb) + np.random.default_rng(1).standard_normal((H, W))[..., None] * PHOTO_SIGMA
    spec = oiio.ImageSpec(W, H, 3, oiio.FLOAT)
    b = oiio.ImageBuf(spec)
    b.set_pixels(oiio.ROI(), np.ascontiguousarray(linear(enc), np.float32))
    assert b.write(str(d / "street.exr"))
    (d / "calibration.yaml").write_text(f"""intrinsics: {{fx: {CAL['fx']}, cx: {CAL['cx']}, cy: {CAL['cy']}}}
ground: {{camera_height: {CAL['camera_height']}, pitch: {CAL['pitch']}}}
sun: {{azimuth: {SUN[0]}, elevation: {SUN[1]}}}
objects: []
""")
    return d


def _scenario(tmp_path, photo_dir, match):
    p = tmp_path / "s.yaml"
    p.write_text(f"""seed: 5
count: 1
resolution: [{W}, {H}]
background:
  photos: [{photo_dir}]
  ground_albedo: 0.15
  dome: false
  min_distance: 5
  max_distance: 9
  match: {match}
objects:
  - {{class: box, primitive: box, size: [1.6, 1.2, 1.6], material: {{type: diffuse, albedo: [0.7, 0.1, 0.1]}}}}
render: {{spp: 16}}
""")
    return str(p)


def _frame(path, threads=2, bump=0):
    """Frame 0 of the scenario (arrays, meta); ``bump``: another render seed, the same layout."""
    from synthgen.frame.renderer import FrameRenderer
    from synthgen.scenario import load_scenario

    fr = FrameRenderer(load_scenario(path), threads=threads)
    prepare = fr.prepare

    def reseeded(frame):
        f = prepare(frame)
        f.render_seed += bump
        return f

    fr.prepare = reseeded
    arrays, meta, _ = fr.render(0)
    return arrays, meta


def _object_noise(path):
    """The object's render noise in the frame as written (sRGB, the photo's space; camera
    matching off), measured independently of the renderer's estimate: two renders with different
    seeds, the RMS of their difference over the object's inner pixels / sqrt 2."""
    (a, meta), (b, _) = _frame(path), _frame(path, bump=1)
    inner = _inner(_inner(np.asarray(a["instance_id"]) == 1))
    d = srgb(a["rgb"])[inner].mean(axis=1) - srgb(b["rgb"])[inner].mean(axis=1)
    assert inner.sum() > 200
    return float(np.sqrt(np.mean(d * d) / 2.0)), meta, a


OFF = "{noise: false, blur: false, jpeg: false, denoise: false"


def test_objects_are_rendered_below_the_photos_noise(photo_dir, tmp_path):
    """At 16 spp the object is noisier than the photo; with render_noise 0.5 its noise as written
    is below half the photo's, the meta says so (reached, with its samples), and the frame is
    bit-identical for 1 and 2 threads."""
    plain, _, _ = _object_noise(_scenario(tmp_path, photo_dir, OFF + ", render_noise: 0}"))
    path = _scenario(tmp_path, photo_dir, OFF + ", render_noise: 0.5, max_spp: 256}")
    refined, meta, arrays = _object_noise(path)
    s = meta["background"]["camera_match"]["sampling"]["objects"][1]
    print(f"\nobject noise (sRGB): 16 spp {plain:.5f}, refined {refined:.5f} (photo {PHOTO_SIGMA}, target "
          f"{s['target']:.5f}, estimated {s['achieved']:.5f}, mean {s['spp_mean']:.1f} spp)")
    assert plain > PHOTO_SIGMA
    assert refined < 0.5 * PHOTO_SIGMA
    assert s["reached"] and s["achieved"] <= s["target"] and 16 < s["spp_mean"] <= 256
    assert s["photo_noise"] == pytest.approx(PHOTO_SIGMA, rel=0.15)
    assert "unmatched" not in meta["background"]["camera_match"]
    one, _ = _frame(path, threads=1)
    assert np.array_equal(one["rgb"], arrays["rgb"])


def test_a_sample_cap_short_of_the_target_is_reported(photo_dir, tmp_path):
    """max_spp 32 cannot bring the object below half the photo's noise: the frame's meta names
    the object, its noise and the target, and the run summary counts it."""
    from synthgen import run as runner

    path = _scenario(tmp_path, photo_dir, OFF + ", render_noise: 0.5, max_spp: 32}")
    s = runner.run(path, str(tmp_path / "ds"), count=1, progress=False)
    assert not s["failures"], s.text()
    meta = json.load(open(tmp_path / "ds" / "meta" / "000000.json"))
    (check,) = meta["background"]["camera_match"]["unmatched"]["1"]
    print("\n" + s.text())
    assert check["check"] == "render_noise" and check["cap_spp"] == 32
    assert check["noise"] > check["target"] == pytest.approx(0.5 * check["photo_noise"])
    assert ("camera matching not reached (meta background.camera_match.unmatched): render noise above the target "
            "for 1 object(s) in 1 frame(s) (sample cap 32 spp): frames 0") in s.text()
    assert json.load(open(tmp_path / "ds" / "run_summary.json"))["camera_match"]["render_noise"] == {"0": [1]}


def test_a_frame_whose_matching_converges_reports_so(photo_dir, tmp_path):
    """With the whole of camera matching on (noise loop, sharpness, the denoiser), a frame that
    converges says so: the render reached its target, the noise loop's last round is within
    3 %, nothing is unmatched and the summary has no camera-matching line."""
    from synthgen import run as runner

    path = _scenario(tmp_path, photo_dir, "{render_noise: 0.5, max_spp: 256}")
    s = runner.run(path, str(tmp_path / "ds"), count=1, progress=False)
    assert not s["failures"], s.text()
    cm = json.load(open(tmp_path / "ds" / "meta" / "000000.json"))["background"]["camera_match"]
    print(f"\nloop {cm['noise_loop_worst_error']}, blur {cm['blur_per_object']}, sampling {cm['sampling']['objects']}")
    assert cm["sampling"]["objects"]["1"]["reached"]
    assert cm["noise_loop_worst_error"][-1] < 0.03
    assert "unmatched" not in cm
    assert "camera matching" not in s.text()
