"""bench/sim2real/plates.py: the plate scenario of ``sim2real_plate_ap50`` validates for both
vehicle kinds with the classes car and plate, and a tiny render labels the main car's plate:
one plate box per frame, inside its car's box (its ``parent_instance_id``), of a DIN 74069
plate's aspect (520 x 110 mm: 4.73, less when turned) and covering 0.1 to 0.6 of the image
width (the scenario's 0.15 to 0.43, the vehicles' plates up to 0.3 m off PLATE_OFFSET; the real
EU photos: 0.15 to 0.30 from p10 to p90, docs/sim2real.md, "Plates"), not high in the image."""
import json
import os
import sys

import pytest

from synthgen import run as runner
from synthgen.scenario.load import load_scenario

from test_output_kitti import _asset

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "..", "bench"))

from sim2real import plates  # noqa: E402


@pytest.mark.parametrize("kind", sorted(plates.VEHICLES))
def test_the_written_scenario_validates(tmp_path, kind):
    for a in plates.VEHICLES[kind]:
        _asset(a)
    p = str(tmp_path / "s.yaml")
    d = plates.write_plate_scenario(p, seed=5, count=7, spp=3, vehicles=kind)
    s = load_scenario(p)
    assert s.count == 7 and tuple(s.resolution) == plates.RESOLUTION
    assert d["render"]["spp"] == 3
    main = d["objects"][0]
    assert main["plates"] == {"country": "de", "class": "plate", "front": True}
    assert ("paint" in main) == (kind == "painted")   # TORCS bodies have no paint material
    with pytest.raises(ValueError, match="vehicles 'vans'"):
        plates.write_plate_scenario(p, seed=5, count=7, vehicles="vans")


def test_a_tiny_render_labels_the_plate_inside_its_car(tmp_path):
    for a in plates.VEHICLES["painted"]:
        _asset(a)
    p = str(tmp_path / "s.yaml")
    w, h = 320, 240
    plates.write_plate_scenario(p, seed=11, count=3, spp=2, resolution=(w, h), hdr=False, wear=False,
                                background_cars=False)
    out = str(tmp_path / "ds")
    s = runner.run(p, out, count=3, progress=False)
    assert not s["failures"], s.text()
    coco = json.load(open(os.path.join(out, "annotations", "coco.json")))
    cat = {c["name"]: c["id"] for c in coco["categories"]}
    assert set(cat) == {"car", "plate"}
    assert len(coco["images"]) == 3
    for im in coco["images"]:
        anns = [a for a in coco["annotations"] if a["image_id"] == im["id"]]
        cars = {a["instance_id"]: a for a in anns if a["category_id"] == cat["car"]}
        pl = [a for a in anns if a["category_id"] == cat["plate"]]
        assert len(cars) == 1 and len(pl) == 1, anns   # one car, its front or rear plate seen
        x, y, bw, bh = pl[0]["bbox"]
        cx, cy, cw, ch = cars[pl[0]["parent_instance_id"]]["bbox"]
        assert cx <= x and cy <= y and x + bw <= cx + cw and y + bh <= cy + ch
        # A plate turned by yaw (or seen from above) has a box narrower for its height than the
        # plate: at most its 4.73 (a pixel of rounding either way), at least 3 (turned 40 degrees).
        assert 3.0 <= bw / bh and (bw - 1) / (bh + 1) <= 520 / 110, (bw, bh)
        assert 0.1 <= bw / w <= 0.6, bw              # the real photos' framing, a margin either side
        assert 0.2 * w <= x + bw / 2 <= 0.8 * w      # seen from behind or in front, near the middle
        # The camera aims 0.9 m high, above the plates (0.36 to 0.72 m), jittered 0.3 m.
        assert y + bh / 2 >= 0.35 * h
        assert pl[0]["area"] > 0.5 * bw * bh         # its visible mask fills its box (a turned plate: less)
