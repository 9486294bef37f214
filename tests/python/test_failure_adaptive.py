"""Where adaptive sampling fails (docs/failure_modes.md): pixels stop when their half-sample
images agree (cpp/integrator/adaptive.h), and two halves that both missed a rare bright path
agree perfectly. A glass ball's sun caustic is such a path: next-event estimation cannot reach
the sun through glass, so only a ground sample whose bounce happens to go through the ball to
the sun's 0.53-degree disc finds it. With the first rounds finding nothing, the caustic's pixels
and their neighbours look converged and stop; the image's estimated PSNR then claims a quality
the image does not have. The remedy is a minimum sample count large enough for the rare path
to be found in the first round (`min_spp`)."""
import os
import sys

import numpy as np
import pytest

from synthgen.post.quality import psnr

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "..", "bench"))

SEEDS = (71, 72, 73)
MAX_SPP = 1024
THRESHOLD = 0.01


@pytest.fixture(scope="module")
def caustic():
    from failure_modes import CAUSTIC_REF, caustic_pixels, caustic_scene, read_exr

    if not os.path.exists(CAUSTIC_REF):
        pytest.fail(f"{CAUSTIC_REF} is missing: run bench/failure_modes.py --reference")
    ref = read_exr(CAUSTIC_REF)
    pixels = caustic_pixels(ref)
    assert pixels.sum() >= 15, f"the reference shows {pixels.sum()} caustic pixels"
    return caustic_scene(), ref, pixels


def _run(caustic, min_spp, seed):
    """(fraction of the caustic's energy the render found, caustic pixels missed -- stopped
    before max_spp with less than a quarter of their reference value --, their sample counts,
    estimated and true PSNR of the image, mean spp)."""
    from failure_modes import CAUSTIC_DEPTH, LUMA

    scene, ref, pixels = caustic
    r = scene.render(spp=MAX_SPP, max_depth=CAUSTIC_DEPTH, seed=seed, noise_threshold=THRESHOLD, min_spp=min_spp)
    img = np.asarray(r.rgb, np.float64)
    count = np.asarray(r.sample_count)
    y, y_ref = img @ LUMA, ref @ LUMA
    missed = pixels & (y < 0.25 * y_ref) & (count < MAX_SPP)
    found = float(y[pixels].sum() / y_ref[pixels].sum())
    return found, int(missed.sum()), count[pixels], float(r.stats["estimated_psnr_db"]), psnr(img, ref), float(count.mean())


def test_caustic_pixels_stop_too_early(caustic):
    """Threshold 0.01, min_spp 16 (the default), seeds 71-73: in at least one seed the render
    finds less than 10% of the caustic's energy and more than half of its pixels stop with less
    than a quarter of their value (measured: seed 71 finds 1%, all 41 pixels stopped at 32-112
    spp; seeds 72 and 73 miss 13 and 24 of them), and the image's estimated PSNR exceeds its true
    PSNR by more than 3 dB (measured 19.8 / 8.4 / 11.5 dB; the estimate cannot see what neither
    half found; its bound on the regression scenes is +-1.5 dB, test_quality_estimate.py; with
    min_spp 256 the gap is still 6.6-8.4 dB: the ball's own rare paths, fireflies)."""
    n = int(caustic[2].sum())
    worst = None
    for seed in SEEDS:
        found, missed, counts, est, true, mean = _run(caustic, 16, seed)
        print(f"\nmin_spp 16 seed {seed}: mean {mean:.1f} spp; caustic energy found {found:.2f}, {missed} of {n} caustic "
              f"pixels missed (their counts {int(counts.min())}..{int(counts.max())}); PSNR estimated {est:.2f} dB, "
              f"true {true:.2f} dB", end="")
        if worst is None or found < worst[0]:
            worst = (found, missed, est - true)
    print()
    found, missed, overclaim = worst
    assert found < 0.1 and missed > n / 2, f"the caustic is no longer missed ({worst}): update docs/failure_modes.md"
    assert overclaim > 3.0, worst


def test_a_larger_minimum_finds_the_caustic(caustic):
    """min_spp 256 (the remedy, at 3.6 x the mean samples): at most 10% of the caustic's pixels
    stop early (measured 0 / 2 / 0 of 41), and every seed finds at least 40% of the caustic's
    energy."""
    n = int(caustic[2].sum())
    for seed in SEEDS:
        found, missed, counts, est, true, mean = _run(caustic, 256, seed)
        print(f"\nmin_spp 256 seed {seed}: mean {mean:.1f} spp; caustic energy found {found:.2f}, {missed} of {n} caustic "
              f"pixels missed (their counts {int(counts.min())}..{int(counts.max())}); PSNR estimated {est:.2f} dB, "
              f"true {true:.2f} dB", end="")
        assert missed <= 0.1 * n and found >= 0.4, (seed, found, missed)
    print()
