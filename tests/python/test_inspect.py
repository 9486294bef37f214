"""synthgen inspect DIR: statistics equal the annotations', the contact sheet draws every
labelled object's box in its class colour, the command prints and writes both PNGs."""
import json
import subprocess
import sys

import matplotlib
import numpy as np
import OpenImageIO as oiio

from synthgen.outputs.inspect import statistics
from synthgen.outputs.read import read_dataset

SCENARIO = """seed: 9
count: 3
resolution: [96, 72]
camera: {fov_y: 50, pose: {type: orbit, distance: 5, elevation: 20, azimuth: {uniform: [0, 360]}}}
objects:
  - {class: box, primitive: box, size: 0.7, count: 2, material: {type: diffuse, albedo: 0.5}}
  - {class: can, primitive: cylinder, size: [0.3, 0.8, 0.3], count: 1}
negative_frames: 0.0
render: {spp: 1, max_depth: 1}
outputs: [rgb, instance, coco]
"""


def test_inspect_a_dataset(tmp_path):
    (tmp_path / "s.yaml").write_text(SCENARIO)
    r = subprocess.run([sys.executable, "-m", "synthgen", "run", "s.yaml", "-o", "ds", "--no-progress"], cwd=tmp_path,
                       capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    r = subprocess.run([sys.executable, "-m", "synthgen", "inspect", "ds", "-n", "3", "--columns", "3"], cwd=tmp_path,
                       capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    coco = json.loads((tmp_path / "ds" / "annotations" / "coco.json").read_text())
    st = statistics(read_dataset(tmp_path / "ds"))
    per_cat = {c["name"]: sum(a["category_id"] == c["id"] for a in coco["annotations"]) for c in coco["categories"]}
    assert st["per_class"] == per_cat and st["objects"] == len(coco["annotations"])
    assert sorted(st["box_heights"]) == sorted(float(a["bbox"][3]) for a in coco["annotations"])
    assert f"3 frames, {st['objects']} labelled visible objects" in r.stdout
    assert "objects per class: " + ", ".join(f"{n} {c}" for n, c in per_cat.items()) in r.stdout
    sheet = np.asarray(oiio.ImageBuf(str(tmp_path / "ds" / "inspect" / "contact_sheet.png")).get_pixels(oiio.UINT8))
    assert sheet.shape[1] > sheet.shape[0] > 100  # three tiles side by side
    for class_id in (1, 2):  # the box edges in each class's colour
        c = np.round(np.array(matplotlib.colormaps["tab10"](class_id - 1)[:3]) * 255)
        assert (np.abs(sheet[..., :3].astype(int) - c).max(axis=-1) <= 2).sum() > 8, class_id
    assert (tmp_path / "ds" / "inspect" / "statistics.png").stat().st_size > 10000
