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


PHOTO_SCENARIO = """seed: 3
count: 2
resolution: [96, 64]
background: {photos: [photos/street.exr], ground_albedo: 0.2}
objects:
  - {class: box, primitive: box, size: [1.6, 1.2, 1.6], count: 1, material: {type: diffuse, albedo: 0.6}}
render: {spp: 1, max_depth: 2}
outputs: [rgb, instance, semantic, coco, yolo, kitti]
"""


def test_inspect_and_verify_count_the_same_objects_in_photos(tmp_path, capsys):
    """Over a photo, a frame's labels are the inserted objects and the photo's real ones
    (source: real): `inspect` counted only the inserted ones where `verify` counted both. Both
    now count and print the same: N objects (I inserted, R real)."""
    from synthgen.cli import main
    from synthgen.outputs.verify import verify_dataset

    photos = tmp_path / "photos"
    photos.mkdir()
    img = oiio.ImageBuf(oiio.ImageSpec(96, 64, 3, oiio.FLOAT))
    img.set_pixels(oiio.ROI(), np.full((64, 96, 3), 0.2, np.float32))
    assert img.write(str(photos / "street.exr"))
    (photos / "calibration.yaml").write_text(
        "intrinsics: {fx: 85, cx: 48, cy: 30}\nground: {camera_height: 1.6, pitch: 6}\nsun: {overcast: true}\n"
        "objects:\n  - {class: box, box: [4, 40, 20, 52]}\nignore:\n  - {box: [75, 32, 95, 40]}\n")
    (tmp_path / "s.yaml").write_text(PHOTO_SCENARIO)
    assert main(["run", str(tmp_path / "s.yaml"), "-o", str(tmp_path / "ds"), "--no-progress"]) == 0
    st = statistics(read_dataset(tmp_path / "ds"))
    v = verify_dataset(str(tmp_path / "ds"))
    coco = json.loads((tmp_path / "ds" / "annotations" / "coco.json").read_text())
    anns = [a for a in coco["annotations"] if not a["iscrowd"]]
    assert st["objects"] == v["annotations"] == len(anns)
    assert st["real"] == v["real"] == sum(a["source"] == "real" for a in anns) == 2  # one per frame
    assert st["inserted"] == v["inserted"] == sum(a["source"] != "real" for a in anns) == len(anns) - 2 >= 1
    assert st["per_class"] == {"box": len(anns)} and sum(st["objects_per_frame"]) == len(anns)
    assert sorted(st["box_heights"]) == sorted(float(a["bbox"][3]) for a in anns)
    assert main(["inspect", str(tmp_path / "ds"), "-n", "2"]) == 0
    assert f"2 frames, {len(anns)} labelled visible objects ({st['inserted']} inserted, 2 real;" in \
        capsys.readouterr().out
    assert main(["verify", str(tmp_path / "ds")]) == 0
    assert f"ok: 2 frames, {len(anns)} objects ({st['inserted']} inserted, 2 real);" in capsys.readouterr().out
