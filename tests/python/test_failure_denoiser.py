"""Where the denoiser fails (docs/failure_modes.md): at 2 samples per pixel, and on fine detail
whose contrast is not in the albedo feature. Each test prints the figures the document quotes
and asserts the documented bound -- and that the failure is still there, so that an
improvement updates the document too.

At 2 spp each half-sample image holds one sample: the halves' difference is a poor variance
estimate and the outlier clamp (a half's value above 2 x the other half's 3 x 3 maximum) cannot
tell a firefly from an ordinary bright sample, so it removes energy. On fine detail the
denoiser keeps what the albedo explains (plate text: demodulated, never filtered) and smooths
what it does not: the glints of 1-pixel metal scratches in a glossy paint, whose brightness
comes from the sky reflected at a tilted groove wall."""
import os
import sys

import numpy as np
import pytest

from synthgen.post.quality import relmse

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "..", "bench"))

LUMA = np.array([0.2126, 0.7152, 0.0722])
SEEDS = (71, 72, 73)


def _reference(name):
    from quality_references import read_reference

    return read_reference(name)


def test_two_samples_per_pixel():
    """The five regression scenes at 2 spp, seeds 71-73: denoising still divides the relMSE
    (bound: by >= 1.4 on every scene, mean of the seeds), but its own change of the image mean
    (denoised against the raw render it was given, luminance) reaches past the 1% it keeps from
    16 spp (tests/python/test_denoise.py): bound 3.5%, and at least one scene beyond 1%
    (measured: cbox -1.39 / -0.28 / -1.61%, the light's edge row; materials about -1%, the
    outlier clamp)."""
    from quality_references import regression_scene, render

    worst = 0.0
    for name in ("cbox", "materials", "sunlit", "default", "road_signs"):
        try:
            scene, depth, scale, _owner = regression_scene(name)
        except Exception as e:  # noqa: BLE001 - the shared Cornell box is missing
            pytest.skip(f"{name}: {e}")
        ref = _reference(name)
        raw_err, den_err, shifts = [], [], []
        for seed in SEEDS:
            r = render(name, scene, 2, depth, seed, scale, denoise=True)
            raw, den = np.asarray(r.rgb_noisy, np.float64), np.asarray(r.rgb, np.float64)
            raw_err.append(relmse(raw, ref, scale))
            den_err.append(relmse(den, ref, scale))
            shifts.append(100.0 * ((den @ LUMA).mean() / (raw @ LUMA).mean() - 1.0))
        gain = np.mean(raw_err) / np.mean(den_err)
        print(f"\n{name:10s} 2 spp: relMSE raw {np.mean(raw_err):.5f} denoised {np.mean(den_err):.5f} "
              f"(raw / denoised {gain:.2f}); the denoiser's mean shift % "
              + " ".join(f"{s:+.2f}" for s in shifts), end="")
        assert gain >= 1.4, (name, gain)
        assert max(abs(s) for s in shifts) <= 3.5, (name, shifts)
        worst = max(worst, max(abs(s) for s in shifts))
    print()
    assert worst > 1.0, f"no scene shifts its mean by more than 1% at 2 spp ({worst:.2f}%): update docs/failure_modes.md"


def _dilate(mask, r=1):
    out = mask.copy()
    for dy in range(-r, r + 1):
        for dx in range(-r, r + 1):
            out |= np.roll(np.roll(mask, dy, axis=0), dx, axis=1)
    return out


def _highpass(x):
    """x minus the mean of its 4 neighbours (luminance): the pixel-scale detail."""
    y = x @ LUMA
    return y - 0.25 * (np.roll(y, 1, 0) + np.roll(y, -1, 0) + np.roll(y, 1, 1) + np.roll(y, -1, 1))


def measure_detail(kind, ref_spp=256, seeds=(71, 72)):
    """Per seed: relMSE of raw 16, denoised 16 and raw 64 spp on the detail pixels (within a
    pixel of an albedo change, from the albedo label) and on the rest of the object and ground,
    against a ``ref_spp`` render; and the detail's contrast kept: the standard deviation of the
    high-pass image (clamped, exposed) over the detail pixels, denoised over reference."""
    from failure_modes import detail_scene

    s = detail_scene(kind)
    ref = np.asarray(s.render(spp=ref_spp, max_depth=4, seed=9).rgb, np.float64)
    scale = 0.18 / float(np.median(ref @ LUMA))  # a mid-grey exposure
    alb = np.asarray(s.render(spp=1, labels_only=True).albedo, np.float64)
    edge = (np.abs(np.diff(alb, axis=0, prepend=alb[:1])).sum(-1) + np.abs(np.diff(alb, axis=1, prepend=alb[:, :1])).sum(-1)) > 0.05
    detail = _dilate(edge)
    detail[[0, -1]] = False
    detail[:, [0, -1]] = False
    rows = []
    for seed in seeds:
        r16 = s.render(spp=16, max_depth=4, seed=seed, denoise=True)
        raw16, den = np.asarray(r16.rgb_noisy, np.float64), np.asarray(r16.rgb, np.float64)
        raw64 = np.asarray(s.render(spp=64, max_depth=4, seed=seed).rgb, np.float64)

        def err(x, m):
            return relmse(x[m][None], ref[m][None], scale)

        def contrast(x):
            return float(np.std(_highpass(np.clip(x * scale, 0.0, 1.0))[detail]))

        row = {"seed": seed, "kept": contrast(den) / contrast(ref)}
        for part, m in (("detail", detail), ("rest", ~detail)):
            row[part] = (err(raw16, m), err(den, m), err(raw64, m))
        rows.append(row)
        print(f"\n{kind:9s} seed {seed}: detail {detail.mean():.2f} of the image, relMSE raw16 / denoised16 / raw64 "
              f"{row['detail'][0]:.5f} / {row['detail'][1]:.5f} / {row['detail'][2]:.5f}; rest "
              f"{row['rest'][0]:.5f} / {row['rest'][1]:.5f} / {row['rest'][2]:.5f}; detail contrast kept {row['kept']:.2f}",
              end="")
    print()
    return rows


def test_plate_text_stays_sharp():
    """Plate text is albedo: demodulated, it is not filtered. Bound: the denoised 16-spp image
    keeps >= 0.9 of the reference's pixel-scale contrast at the characters' edges and has a
    lower error there than raw 16 spp; but those edges keep more error than raw 64 spp (> 1.5 x:
    the radiance changes across an edge within the pixel, which one albedo mean does not
    explain exactly) while flat areas are far below it."""
    for row in measure_detail("plate"):
        assert row["kept"] >= 0.9, row
        raw16, den, raw64 = row["detail"]
        assert den < raw16, row
        assert den > 1.5 * raw64, f"plate edges now beat raw 64 spp: update docs/failure_modes.md {row}"
        assert row["rest"][1] < row["rest"][2], row


def test_scratch_glints_are_smoothed():
    """Scratch glints are not in the albedo (the aluminium's albedo is, but their brightness
    is the sky reflected by a tilted groove wall, a normal the 1-pixel groove averages out):
    the denoiser spreads them. Bound: it keeps >= 0.5 of their pixel-scale contrast but < 0.95
    (measured 0.61 and 0.85), it still divides the error at the scratches by >= 4 (their raw
    error is the glints' noise), and the paint around them gets more error than raw 64 spp
    (> 3 x, halos of spread glints; measured 5.8 and 10 x)."""
    rows = measure_detail("scratches")
    for row in rows:
        raw16, den, raw64 = row["detail"]
        assert 0.5 <= row["kept"], row
        assert raw16 / den >= 4.0, row
        assert row["rest"][1] > 3.0 * row["rest"][2], row
    assert min(r["kept"] for r in rows) < 0.95, rows
