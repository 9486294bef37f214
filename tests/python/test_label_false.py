"""objects[].label: false: unlabelled objects (occluders, clutter) are rendered and occlude,
but have no class, id 0 in the masks, no annotation, and no visibility limits of their own."""
import json

import numpy as np
import pytest

import synthgen as sg
from synthgen import scenario
from synthgen.frame.renderer import FrameRenderer

SCENARIO = """seed: 4
count: 6
resolution: [96, 72]
camera: {fov_y: 55, pose: {type: orbit, distance: 6, elevation: 12, azimuth: {uniform: [0, 360]}}}
placement: {region: [-2, -2, 2, 2], min_pixels: 20}
objects:
  - {class: box, primitive: box, size: 0.6, count: 2}
  - {label: false, primitive: box, size: [2.5, 1.5, 0.3], count: 2, name: wall}
render: {spp: 1, max_depth: 1}
"""


def test_unlabelled_objects_occlude_and_stay_out_of_the_labels(tmp_path):
    p = tmp_path / "s.yaml"
    p.write_text(SCENARIO)
    sc = scenario.load_scenario(p)
    assert sc.class_names == ["box"]
    fr = FrameRenderer(sc)
    occluded = unlabelled_pixels = 0
    for k in range(sc.count):
        arrays, meta, _ = fr.render(k)
        walls = [o for o in meta["objects"] if o.get("label") is False]
        boxes = [o for o in meta["objects"] if o.get("label", True)]
        assert len(walls) == 2 and all(o["class_id"] == 0 and o["instance_id"] == 0 for o in walls)
        assert all("bbox" not in o and "visible_pixels" not in o for o in walls)
        ids = np.asarray(arrays["instance_id"])
        assert set(np.unique(ids)) <= {0} | {o["instance_id"] for o in boxes}
        assert set(np.unique(np.asarray(arrays["class_id"]))) <= {0, 1}
        # The walls are in the image: hits (finite depth) with id 0 whose normal is not the
        # ground's, and they hide parts of the boxes behind them.
        hit = np.isfinite(np.asarray(arrays["depth"]))
        up = np.abs(np.asarray(arrays["normal"])[..., 1]) > 0.999
        unlabelled_pixels += int((hit & (ids == 0) & ~up).sum())
        occluded += sum(o["occlusion"] > 0.05 for o in boxes if "occlusion" in o)
    assert unlabelled_pixels > 100 and occluded > 0


def test_the_dataset_has_no_trace_of_them(tmp_path):
    from synthgen.run import runner

    p = tmp_path / "s.yaml"
    p.write_text(SCENARIO.replace("count: 6", "count: 2") + "outputs: [rgb, coco, yolo, kitti, instance]\n")
    s = runner.run(str(p), str(tmp_path / "ds"), progress=False)
    assert s["rendered"] == 2, s.text()
    coco = json.loads((tmp_path / "ds" / "annotations" / "coco.json").read_text())
    assert [c["name"] for c in coco["categories"]] == ["box"]
    assert all(a["category_id"] == 1 for a in coco["annotations"])
    for k in range(2):
        assert all(line.split()[0] == "0" for line in (tmp_path / "ds" / "labels" / f"{k:06d}.txt").read_text().split("\n") if line)


@pytest.mark.parametrize("entry, message", [
    ("{primitive: box}", r"objects\[0\]: missing key 'class'.*or label: false"),
    ("{label: false, class: wall, primitive: box}", r"objects\[0\].class: an object with label: false has no class"),
])
def test_label_and_class_go_together(tmp_path, entry, message):
    p = tmp_path / "s.yaml"
    p.write_text(f"objects:\n  - {entry}\n  - {{class: box, primitive: box}}\n")
    with pytest.raises(sg.SynthgenError, match=message):
        scenario.load_scenario(p)
    p.write_text("objects:\n  - {label: false, primitive: box}\n")
    with pytest.raises(sg.SynthgenError, match="needs at least one labelled entry"):
        scenario.load_scenario(p)
