"""The plate stroke font (synthgen.scene.glyphs): exact geometry of the rasterized glyphs --
their height, stroke width and ink area against the analytic values of their centrelines."""
import math

import numpy as np
import pytest

from synthgen.scene.glyphs import GLYPHS, WIDTH, glyph_coverage, glyph_primitives


@pytest.mark.parametrize("ch", GLYPHS)
def test_every_glyph_spans_its_height_and_stays_in_its_box(ch):
    h, s = 120.0, 16.0
    cov, (ox, oy) = glyph_coverage(ch, h, s)
    rows = np.nonzero(cov.max(axis=1) > 0.5)[0]
    assert rows.min() == oy and rows.max() == oy + h - 1, (ch, rows.min(), rows.max())
    cols = np.nonzero(cov.max(axis=0) > 0.5)[0]
    # Slanted legs cut at the baseline (A, K, V, X ...) may reach half a stroke past the box.
    assert cols.min() >= ox - 0.5 * s - 1 and cols.max() <= ox + WIDTH[ch] * h + 0.5 * s, (ch, cols.min(), cols.max())


def test_a_stem_is_as_wide_as_the_stroke():
    for stroke in (9.0, 11.0, 16.5):
        cov, (ox, oy) = glyph_coverage("I", 100.0, stroke)
        assert cov[int(oy) + 50].sum() == pytest.approx(stroke, abs=0.05)


def test_o_and_zero_are_one_glyph_with_the_stadiums_area():
    h, s = 200.0, 24.0
    a, _ = glyph_coverage("O", h, s)
    b, _ = glyph_coverage("0", h, s)
    assert np.array_equal(a, b)
    W, prims = glyph_primitives("O", s / h)
    hw = 0.5 * s / h
    R = 0.5 * (W - 2 * hw)
    perimeter = 2 * math.pi * R + 2 * ((1 - hw - R) - (hw + R))
    # NOTE: the band of constant width s around a closed convex centreline has area perimeter x s.
    assert a.sum() / h ** 2 == pytest.approx(perimeter * s / h, rel=0.01)
