"""Every render's error estimate (synthgen.post.quality.estimate_noise, from the film's two
half-sample images): on the five regression scenes at 128 x 96 (bench/quality_references.py
renders their converged references, committed in tests/python/references/quality/), the
estimated PSNR is within 1.5 dB of the true PSNR against the reference at 4, 16 and 64 spp.
Also: the estimator's arithmetic on samples of known variance (odd sample counts included),
the variance buffer against the half-sample difference, and the estimate in dataset meta."""
import json
import math
import os
import sys

import numpy as np
import pytest

from synthgen.post.quality import estimate_noise, psnr, relmse

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.abspath(os.path.join(HERE, "..", ".."))
REF_DIR = os.path.join(HERE, "references", "quality")
sys.path.insert(0, os.path.join(REPO, "bench"))

SCENES = ("cbox", "materials", "sunlit", "default", "road_signs")


def _reference(name):
    from quality_references import read_reference

    return read_reference(name)


_scenes = {}


def _scene(name):
    from quality_references import regression_scene

    if name not in _scenes:
        try:
            _scenes[name] = regression_scene(name)
        except Exception as e:  # noqa: BLE001 - an asset this machine lacks (HDR maps, the Cornell box)
            pytest.skip(f"{name}: {e}")
    return _scenes[name]


SEEDS = (71, 72, 73, 74)  # not the references' (bench/quality_references.py REF_SEED)

#: (scene, spp) where the estimate is known to miss, and why (docs/quality.md). None since the
#: scenarios clamp indirect light (clamp_indirect): before, the default frame's glass ball
#: focused the sun into caustic fireflies that the halves rarely saw (+4.2 dB at 64 spp).
KNOWN_MISSES = {}


@pytest.mark.parametrize("spp", [4, 16, 64])
@pytest.mark.parametrize("name", SCENES)
def test_the_estimate_is_within_1_5_db_of_the_true_psnr(name, spp, request):
    """Over four renders (seeds), the mean estimated PSNR is within 1.5 dB of the mean true
    PSNR against the converged reference; each render's difference is printed."""
    if (name, spp) in KNOWN_MISSES:
        request.applymarker(pytest.mark.xfail(strict=True, reason=KNOWN_MISSES[(name, spp)]))
    from quality_references import render

    scene, depth, scale, _ = _scene(name)
    ref = _reference(name)
    est, true, rel_e, rel_t = [], [], [], []
    for seed in SEEDS:
        res = render(name, scene, spp, depth, seed, scale)
        e = estimate_noise(np.asarray(res.rgb_even), np.asarray(res.rgb_odd), spp, scale)
        est.append(e["psnr_db"])
        rel_e.append(e["relmse"])
        true.append(psnr(np.asarray(res.rgb), ref, scale))
        rel_t.append(relmse(np.asarray(res.rgb), ref, scale))
    diff = float(np.mean(est) - np.mean(true))
    print(f"\n{name:10s} {spp:3d} spp: estimated {np.mean(est):6.2f} dB, true {np.mean(true):6.2f} dB ({diff:+.2f}; "
          f"per render {' '.join(f'{a - b:+.2f}' for a, b in zip(est, true))}); relMSE estimated "
          f"{np.mean(rel_e):.4g}, true {np.mean(rel_t):.4g}", end="")
    assert abs(diff) <= 1.5, (name, spp, est, true)


@pytest.mark.parametrize("spp", [2, 3, 7, 16])
def test_the_estimator_on_samples_of_known_variance(spp):
    """Gaussian samples per pixel (sigma 0.05 around 0.4: no clamping): the estimated MSE of the
    mean is the true one (sigma^2 / spp) within 5%, with uneven halves too."""
    rng = np.random.default_rng(spp)
    h, w = 256, 256
    sigma = 0.05
    samples = 0.4 + sigma * rng.standard_normal((spp, h, w, 3))
    even, odd = samples[0::2].mean(axis=0), samples[1::2].mean(axis=0)
    est = estimate_noise(even, odd, spp)
    want = sigma ** 2 / spp
    assert est["mse"] == pytest.approx(want, rel=0.05)
    assert est["psnr_db"] == pytest.approx(-10 * math.log10(want), abs=0.25)
    assert estimate_noise(even, even, 1) is None


def test_the_variance_buffer_is_the_variance_of_the_mean():
    """The variance buffer is the samples' unbiased variance over their number: with 2 samples
    it equals the half-sample estimate exactly; with more, stratified samples err less than
    independent ones, so it bounds the half-sample estimate from above on the whole."""
    scene, depth, scale, _ = _scene("sunlit")
    res = scene.render(spp=2, max_depth=depth, seed=SEEDS[0])
    a, b = np.asarray(res.rgb_even, np.float64), np.asarray(res.rgb_odd, np.float64)
    np.testing.assert_allclose(np.asarray(res.variance), (a - b) ** 2 / 4, rtol=1e-4, atol=1e-9)
    res = scene.render(spp=64, max_depth=depth, seed=SEEDS[0])
    a, b = np.asarray(res.rgb_even, np.float64), np.asarray(res.rgb_odd, np.float64)
    np.testing.assert_allclose(np.asarray(res.rgb), 0.5 * (a + b), rtol=1e-5, atol=1e-6)
    ratio = float(np.asarray(res.variance, np.float64).mean() / (((a - b) ** 2).mean() / 4))
    print(f"\nvariance buffer / half-sample estimate at 64 spp: {ratio:.2f}")
    assert ratio > 1.0


def test_datasets_record_the_estimate(tmp_path):
    from synthgen import run as runner

    (tmp_path / "s.yaml").write_text("""
seed: 2
resolution: [64, 48]
camera: {fov_y: 40, pose: {type: orbit, target: [0, 0.5, 0], distance: 4}}
lights: [{type: environment, radiance: 1.0}]
objects: [{class: box, primitive: box}]
render: {spp: 8}
post: [{type: exposure, ev: 1}]
outputs: [rgb]
""")
    s = runner.run(str(tmp_path / "s.yaml"), str(tmp_path / "ds"), count=1, progress=False)
    assert not s["failures"], s.text()
    meta = json.load(open(tmp_path / "ds" / "meta" / "000000.json"))
    noise = meta["noise"]
    assert noise["spp"] == 8 and 10.0 < noise["psnr_db"] < 80.0 and noise["relmse"] > 0.0
