"""Low-spp renders are unbiased: two independent averages of 12 renders at 32 spp (different
seeds) each differ from a converged render only by noise -- their regional errors (16 x 16
pixel blocks) do not agree with each other. A sampler whose 2D points lie on a curve over
the seeds (the two coordinates' scrambles not independent) biased every low-spp render the
same way: block errors of the two averages then correlated at 0.9 and above (Cornell box,
one bounce)."""
import os
import sys

import numpy as np
import pytest

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "..", "bench"))


def test_low_spp_renders_average_to_the_converged_image():
    from vs_cycles_scenes import CBOX_DIR, build_spec, synthgen_scene

    if not os.path.isdir(CBOX_DIR):
        pytest.skip(f"shared test data not found: {CBOX_DIR}")
    spec = build_spec("cbox", 128, 96)
    scene = synthgen_scene(spec)
    scene.commit()
    depth = 3
    ref = np.asarray(scene.render(spp=4096, max_depth=depth, seed=5).rgb, np.float64)

    def average(seed0):
        return np.mean([np.asarray(scene.render(spp=32, max_depth=depth, seed=seed0 + k).rgb, np.float64)
                        for k in range(12)], axis=0)

    a, b = average(100), average(200)
    B = 16
    blocks = lambda x: x.reshape(96 // B, B, 128 // B, B, 3).mean(axis=(1, 3)).ravel()  # noqa: E731
    ea, eb = blocks(a - ref), blocks(b - ref)
    corr = float(np.corrcoef(ea, eb)[0, 1])
    noise = float(np.sqrt(np.mean(blocks(a - b) ** 2) / 2))  # one average's block noise
    err = float(np.sqrt(0.5 * (np.mean(ea ** 2) + np.mean(eb ** 2))))
    print(f"\nblock errors of two 12 x 32-spp averages: correlation {corr:.2f}; rms {err:.5f} vs their noise "
          f"{noise:.5f}")
    assert corr < 0.5
    assert err < 1.5 * noise
