"""The firefly remedy: render setting clamp_indirect (cpp/integrator/path_tracer.cpp, as Cycles'
"clamp indirect"). The default scenario's fireflies are caustics -- the sun focused by the
glass ball and reflected by the glossy spheres onto the diffuse ground -- found only when a
diffuse bounce happens to hit the sphere and the sun (0.53 deg) behind it: rare samples of
huge value. Clamping every indirect contribution to a sum of RGB of 10 (displayed units)
removes them at a measured cost in energy. References: tests/python/references/quality/
default.exr (with the scenario's clamp) and default_unclamped.exr (bench/quality_references.py
--unclamped)."""
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
def default():
    from quality_references import regression_scene

    return regression_scene("default")


def test_the_clamp_removes_the_fireflies_at_a_bounded_bias(default):
    """At 64 spp the clamped render is >= 3 dB closer to its converged image than the unclamped
    one is to its own; the two converged images differ by < 0.6 % in mean (the caustics'
    energy) and agree to >= 36 dB PSNR."""
    from quality_references import render

    scene, depth, scale, _ = default
    clamped_ref, unclamped_ref = _reference("default"), _reference("default_unclamped")
    bias = float(clamped_ref.mean() / unclamped_ref.mean() - 1.0)
    agree = psnr(clamped_ref, unclamped_ref, scale)
    gains = []
    for seed in (71, 72):
        c = render("default", scene, 64, depth, seed, scale)
        u = render("default", scene, 64, depth, seed, scale, clamp_indirect=0.0)
        pc, pu = psnr(np.asarray(c.rgb), clamped_ref, scale), psnr(np.asarray(u.rgb), unclamped_ref, scale)
        gains.append(pc - pu)
        print(f"\nseed {seed}: clamped {pc:.2f} dB vs its reference, unclamped {pu:.2f} dB vs its own")
    print(f"clamp bias: mean {100 * bias:+.3f} %, references agree to {agree:.2f} dB")
    assert min(gains) >= 3.0, gains
    assert abs(bias) < 0.006 and agree >= 36.0


def test_the_clamp_only_lowers_indirect_light(default):
    """Same random numbers: every pixel of the clamped render is at most the unclamped one (a
    clamped contribution is scaled down, nothing else changes), and with a clamp so low that
    all indirect light is cut, direct light alone (max_depth 2) is untouched."""
    from quality_references import render

    scene, depth, scale, _ = default
    c = np.asarray(render("default", scene, 16, depth, 3, scale, clamp_indirect=1.0).rgb)
    u = np.asarray(render("default", scene, 16, depth, 3, scale, clamp_indirect=0.0).rgb)
    assert (c <= u * (1 + 1e-5) + 1e-7).all()
    assert (c < u * (1 - 1e-3)).any()
    d0 = np.asarray(render("default", scene, 16, 2, 3, scale, clamp_indirect=0.0).rgb)
    d1 = np.asarray(render("default", scene, 16, 2, 3, scale, clamp_indirect=1e-6).rgb)
    assert np.array_equal(d0, d1)
