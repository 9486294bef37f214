"""Adaptive sampling (render settings noise_threshold, target_psnr, min_spp, max_spp;
cpp/integrator/adaptive.h): pixels stop in rounds of 16 samples once their neighbourhood's
estimated error is below the threshold, or the whole image once its estimated PSNR reaches
the target. Measured on the regression scenes against their converged references
(tests/python/references/quality): adaptive sampling beats uniform sampling at the same mean
sample count; images are bit-identical for any thread count; labels are unaffected."""
import os
import sys

import numpy as np
import pytest

from synthgen.post.quality import psnr

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "..", "bench"))


def _reference(name):
    from quality_references import read_reference

    return read_reference(name)


@pytest.fixture(scope="module")
def cbox():
    from quality_references import regression_scene

    try:
        return regression_scene("cbox")
    except Exception as e:  # noqa: BLE001 - the shared Cornell box is missing
        pytest.skip(f"cbox: {e}")


@pytest.fixture(scope="module")
def sunlit():
    from quality_references import regression_scene

    return regression_scene("sunlit")


def test_adaptive_beats_uniform_at_the_same_mean_spp(cbox):
    """Cornell box, threshold 0.01, up to 256 spp: the mean count, then a uniform render with
    that many samples (rounded up to a multiple of 16: at least as many): adaptive is >= 1 dB
    better (measured +1.48 / +2.55 dB for seeds 71 / 72: its samples go to the noisy ceiling
    and shadows; the flat walls stop early)."""
    scene, depth, scale, _ = cbox
    ref = _reference("cbox")
    gains = []
    for seed in (71, 72):
        res = scene.render(spp=256, noise_threshold=0.01, max_depth=depth, seed=seed)
        count = np.asarray(res.sample_count)
        mean = float(count.mean())
        uniform_spp = int(np.ceil(mean / 16.0) * 16)
        uni = scene.render(spp=uniform_spp, max_depth=depth, seed=seed)
        a, u = psnr(np.asarray(res.rgb), ref, scale), psnr(np.asarray(uni.rgb), ref, scale)
        print(f"\nseed {seed}: adaptive {a:.2f} dB at mean {mean:.1f} spp ({count.min()}..{count.max()}), "
              f"uniform {uniform_spp} spp {u:.2f} dB")
        gains.append(a - u)
        assert count.min() >= 16 and count.max() <= 256 and mean < 128
    assert min(gains) >= 1.0, gains


def test_counts_rounds_determinism_and_labels(sunlit):
    """Counts are whole rounds of 16 between min_spp and max_spp (the last round may be short);
    the image is bit-identical with 1 and 2 threads; labels equal a uniform render's."""
    scene, depth, scale, _ = sunlit
    kw = dict(spp=64, max_spp=200, min_spp=20, noise_threshold=0.004, max_depth=depth, seed=5)
    one = scene.render(threads=1, **kw)
    two = scene.render(threads=2, **kw)
    count = np.asarray(one.sample_count)
    assert set(np.unique(count).tolist()) <= {32, 48, 64, 80, 96, 112, 128, 144, 160, 176, 192, 200}
    assert count.min() == 32 and count.max() > 32
    assert np.array_equal(count, np.asarray(two.sample_count))
    for buf in ("rgb", "rgb_even", "rgb_odd", "albedo_even", "depth_odd"):
        assert np.array_equal(np.asarray(getattr(one, buf)), np.asarray(getattr(two, buf))), buf
    plain = scene.render(spp=16, max_depth=depth, seed=5)
    for buf in ("depth", "normal", "albedo", "instance_id", "class_id"):
        assert np.array_equal(np.asarray(getattr(one, buf)), np.asarray(getattr(plain, buf))), buf
    assert one.stats["samples"] == int(count.sum())


def test_target_psnr_stops_the_image_when_reached(sunlit):
    """target_psnr 45: every pixel gets the same count; the image stops at the first round whose
    estimate reaches 45 dB, and the true PSNR against the reference is within 1.5 dB of it or
    better; a target it cannot reach stops at max_spp."""
    scene, depth, scale, _ = sunlit
    ref = _reference("sunlit")
    res = scene.render(spp=1024, target_psnr=45.0, max_depth=depth, seed=9)
    count = np.asarray(res.sample_count)
    assert count.min() == count.max() < 1024
    est = res.stats["estimated_psnr_db"]
    true = psnr(np.asarray(res.rgb), ref, scale)
    print(f"\ntarget 45 dB: {count.max()} spp, estimated {est:.2f} dB, true {true:.2f} dB")
    assert est >= 45.0 and true >= 45.0 - 1.5
    capped = scene.render(spp=32, target_psnr=90.0, max_depth=depth, seed=9)
    assert np.asarray(capped.sample_count).min() == 32


def test_bad_adaptive_settings_are_errors(sunlit):
    scene, depth, _, _ = sunlit
    with pytest.raises(Exception, match="min_spp"):
        scene.render(spp=64, noise_threshold=0.01, min_spp=128, max_depth=depth)
    with pytest.raises(Exception, match="noise_threshold"):
        scene.render(spp=64, noise_threshold=-1.0, max_depth=depth)


def test_scenarios_sample_adaptively(tmp_path):
    """A scenario's render section takes the adaptive settings; meta.noise records the mean
    count and the estimate."""
    import json

    from synthgen import run as runner

    (tmp_path / "s.yaml").write_text("""
seed: 2
resolution: [64, 48]
camera: {fov_y: 40, pose: {type: orbit, target: [0, 0.5, 0], distance: 4}}
lights: [{type: environment, radiance: 1.0}]
objects: [{class: box, primitive: box}]
render: {spp: 128, noise_threshold: 0.02, max_depth: 4}
outputs: [rgb]
""")
    s = runner.run(str(tmp_path / "s.yaml"), str(tmp_path / "ds"), count=1, progress=False)
    assert not s["failures"], s.text()
    meta = json.load(open(tmp_path / "ds" / "meta" / "000000.json"))
    assert meta["render"]["noise_threshold"] == 0.02
    assert 16 <= meta["noise"]["spp"] < 128
    assert meta["noise"]["psnr_db"] > 30
