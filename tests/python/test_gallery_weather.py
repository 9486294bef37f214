"""The gallery's weather row (`synthgen gallery --weather`, docs/weather.md): one frame of a
street scenario under each condition, deterministic, with the drawn parameters captioned."""
import os

import numpy as np

from synthgen.frame import gallery

HERE = os.path.dirname(os.path.abspath(__file__))
TINY = os.path.join(HERE, "scenarios", "tiny.yaml")


def test_weather_row_same_frame_under_each_condition():
    w, h = 64, 48
    tiles = [("clear", {}), ("fog", {"fog": {"visibility": 8.0, "top": 20.0}})]
    img = gallery.render_weather_row(TINY, frame=0, tile_w=w, tile_h=h, spp=4, tiles=tiles, denoise=False)
    assert img.shape == (h + 32, 2 * w, 3) and np.isfinite(img).all()
    clear, fog = img[:h, :w], img[:h, w:]
    # Dense fog (visibility 8 m; the objects 1.6-3.3 m away and more, the layer hiding the sky)
    # changes the whole image.
    assert np.abs(fog - clear).mean() > 0.2 * clear.mean()
    # Captions: dark text on a light strip under each tile.
    cap = img[h:, :w]
    assert cap.max() > 0.5 and cap.min() < 0.05
    again = gallery.render_weather_row(TINY, frame=0, tile_w=w, tile_h=h, spp=4, tiles=tiles[1:], denoise=False)
    assert np.array_equal(again[:h], fog)
