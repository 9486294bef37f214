"""``synthgen evaluate train|score|detect`` end to end on tiny images: a model trained a few
steps on CPU from a CSV label set and negatives is written with its manifest; detect writes
records relative to the images folder (and COCO results); score prints the table and writes the
precision-recall PNG, from a model and from a detections file, and a detections file that is
exactly the ground truth scores AP50 1. Errors exit 2 with the reason. Skips without PyTorch."""
from __future__ import annotations

import json
import os

import numpy as np
import pytest

pytest.importorskip("torch", reason="PyTorch (python3-torch) is not installed")

from synthgen.cli import main  # noqa: E402
from synthgen.evaluate.detector import Detector  # noqa: E402


def _set(tmp_path):
    from PIL import Image

    rng = np.random.default_rng(1)
    img_dir = tmp_path / "photos"
    neg_dir = tmp_path / "empty"
    img_dir.mkdir()
    neg_dir.mkdir()
    rows = ["image,x0,y0,x1,y1,class"]
    boxes = {}
    for i in range(3):
        a = (rng.random((64, 96, 3)) * 50).astype(np.uint8)
        x0, y0 = 10 + 20 * i, 8 + 6 * i
        a[y0:y0 + 28, x0:x0 + 40] = (220, 60, 40)
        Image.fromarray(a).save(img_dir / f"f{i}.png")
        rows.append(f"f{i}.png,{x0},{y0},{x0 + 40},{y0 + 28},car")
        boxes[f"f{i}.png"] = [x0, y0, x0 + 40, y0 + 28]
    Image.fromarray((rng.random((64, 96, 3)) * 50).astype(np.uint8)).save(neg_dir / "n0.png")
    (img_dir / "labels.csv").write_text("\n".join(rows) + "\n")
    return img_dir, neg_dir, boxes


def test_train_detect_score(tmp_path, capsys):
    img_dir, neg_dir, boxes = _set(tmp_path)
    model = str(tmp_path / "m.model")
    rc = main(["evaluate", "train", "--real", str(img_dir / "labels.csv"), "--negatives", str(neg_dir),
               "--backbone", "none", "--steps", "2", "--batch", "2", "--size", "64x96", "--mix", "real=0.5",
               "--mix", "negative=0.5", "-o", model, "--no-progress"])
    assert rc == 0
    err = capsys.readouterr()
    assert "labels.csv: 3 images, 3 boxes (car 3), 0 ignore regions" in err.err
    m = Detector.from_file(model)
    assert m.class_names == ["car"] and m.input_size == (64, 96)
    assert m.metadata["pools"]["real"]["samples"] == 3 and m.metadata["pools"]["negative"]["samples"] == 1
    assert m.metadata["options"]["mix"] == {"real": 0.5, "negative": 0.5}
    assert m.metadata["arguments"]["steps"] == 2
    assert not os.path.exists(model + ".part")

    dets = str(tmp_path / "d.json")
    assert main(["evaluate", "detect", model, str(img_dir), "-o", dets, "--threshold", "0", "--no-progress"]) == 0
    recs = json.load(open(dets))
    assert {r["file_name"] for r in recs} == set(boxes)
    assert all(set(r) == {"file_name", "bbox", "score", "category"} and r["category"] == "car" for r in recs)
    coco = str(tmp_path / "c.json")
    assert main(["evaluate", "detect", model, str(img_dir), "-o", coco, "--coco", "--threshold", "0",
                 "--no-progress"]) == 0
    assert {r["image_id"] for r in json.load(open(coco))} == {1, 2, 3}

    pr = str(tmp_path / "pr.png")
    assert main(["evaluate", "score", model, "--real", str(img_dir / "labels.csv"), "--pr", pr, "--bootstrap", "20",
                 "--json", str(tmp_path / "s.json"), "--no-progress"]) == 0
    out = capsys.readouterr().out
    assert "AP50 [95% CI]" in out and "car    all" in out
    assert open(pr, "rb").read(8) == b"\x89PNG\r\n\x1a\n"
    s = json.load(open(tmp_path / "s.json"))
    assert s["images"] == 3 and s["rows"][0]["gt"] == 3

    # a detections file that is the ground truth scores AP50 1.0
    perfect = [{"file_name": f, "bbox": [b[0], b[1], b[2] - b[0], b[3] - b[1]], "score": 0.9, "category": "car"}
               for f, b in boxes.items()]
    pj = tmp_path / "perfect.json"
    pj.write_text(json.dumps(perfect))
    assert main(["evaluate", "score", str(pj), "--real", str(img_dir / "labels.csv"), "--negatives", str(neg_dir),
                 "--pr", pr, "--bootstrap", "0"]) == 0
    line = [l for l in capsys.readouterr().out.splitlines() if l.startswith("car    all")][0]
    assert line.split()[5] == "1.000"


@pytest.mark.parametrize("argv, message", [
    (["evaluate", "train", "-o", "x.model", "--backbone", "none"], "nothing to train on"),
    (["evaluate", "train", "--real", "LABELS", "-o", "x.model"], "give --backbone FILE"),
    (["evaluate", "detect", "missing.model", ".", "-o", "d.json"], "missing.model: detector model not found"),
])
def test_errors_exit_2_with_the_reason(tmp_path, capsys, argv, message):
    img_dir, _, _ = _set(tmp_path)
    argv = [str(img_dir / "labels.csv") if a == "LABELS" else a for a in argv]
    assert main(argv) == 2
    assert message in capsys.readouterr().err
