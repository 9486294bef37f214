"""Randomizer ``decals``: the decal lands on the object's front -- the side its forward axis
points to -- upright along its up axis (it used to land on the -z side of every model, the
back of a car whose forward is +z)."""
import numpy as np
import pytest

from synthgen.randomize import ObjectContext
from synthgen.randomize import decals as D


def _projector(monkeypatch, forward, up, lo=(-1.0, 0.0, -2.0), hi=(1.0, 1.5, 2.0), height=0.5, size=0.4):
    seen = {}

    def fake_decal(scene, base, image, **kw):
        seen.update(kw)
        return base

    monkeypatch.setattr(D.wear, "decal", fake_decal)
    ctx = ObjectContext(scene=None, rng=np.random.default_rng(1), spec=None, shape_lo=np.array(lo),
                        shape_hi=np.array(hi), forward=forward, up=up)
    value = [{"pictogram": {"family": "stop", "text": None}, "image": None, "plate": None, "probability": 1.0,
              "size": size, "height": height}]
    mats, info = D.Decals().apply(ctx, value, [7])
    assert mats == [7] and info[0]["kind"] == "pictogram"
    return seen, info[0]


@pytest.mark.parametrize("forward, axis, sign", [((1.0, 0.0, 0.0), 0, 1), ((0.0, 0.0, 1.0), 2, 1),
                                                 ((0.0, 0.0, -1.0), 2, -1), ((-1.0, 0.0, 0.0), 0, -1)])
def test_decal_projects_onto_the_forward_side(monkeypatch, forward, axis, sign):
    lo, hi = np.array([-1.0, 0.0, -2.0]), np.array([1.0, 1.5, 2.0])
    p, info = _projector(monkeypatch, forward, (0.0, 1.0, 0.0))
    pos, target = np.array(p["position"]), np.array(p["look_at"])
    # In front of that face, looking back at the object's centre line.
    assert (pos[axis] - (hi if sign > 0 else lo)[axis]) * sign > 0
    assert target[axis] == pytest.approx(0.5 * (lo + hi)[axis])
    assert np.allclose(np.delete(pos - target, axis), 0.0)
    assert p["up"] == [0.0, 1.0, 0.0] and p["space"] == "object"
    # Width: size x the extent across the forward axis (the lateral one).
    lateral = {0: 2, 2: 0}[axis]
    assert info["size"][0] == pytest.approx(0.4 * (hi - lo)[lateral])


def test_decal_height_follows_the_up_axis(monkeypatch):
    p, _ = _projector(monkeypatch, (0.0, 0.0, 1.0), (0.0, 1.0, 0.0), height=0.2)
    assert p["look_at"][1] == pytest.approx(0.2 * 1.5)  # 20% up from the bottom (y = 0)
    # A model whose up is -y: its bottom is at +y.
    p, _ = _projector(monkeypatch, (0.0, 0.0, 1.0), (0.0, -1.0, 0.0), height=0.2)
    assert p["look_at"][1] == pytest.approx(1.5 - 0.2 * 1.5) and p["up"] == [0.0, -1.0, 0.0]
