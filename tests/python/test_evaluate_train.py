"""Training the reference detector (synthgen.evaluate.train, synthgen.evaluate.augment): the
augmentation moves boxes exactly with the pixels (a white rectangle's extent after scale, crop,
padding and flip), the photometric jitter against torchvision's formulas, the batch plan's
shares and passes, bit-identical CPU training for a seed (any number of data workers), the
manifest saved in the model file, and errors. Every test skips without PyTorch; tiny images
and a few steps only (CI trains here)."""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import List

import numpy as np
import pytest

from synthgen import SynthgenError

torch = pytest.importorskip("torch", reason="PyTorch (python3-torch) is not installed")

from synthgen.evaluate import augment as A  # noqa: E402
from synthgen.evaluate import train as T  # noqa: E402
from synthgen.evaluate.detector import Detector  # noqa: E402
from synthgen.evaluate.images import read_rgb8  # noqa: E402


@dataclass
class Sample:
    image: str
    boxes: np.ndarray
    classes: List[str]
    ignore: np.ndarray = field(default=None)
    source: str = "synthetic"
    where: str = ""

    def __post_init__(self):
        self.boxes = np.asarray(self.boxes, np.float64).reshape(-1, 4)
        if self.ignore is None:
            self.ignore = np.zeros(len(self.boxes), bool)


def _rect_image(h, w, box, value=255):
    a = np.zeros((h, w, 3), np.uint8)
    x0, y0, x1, y1 = box
    a[y0:y1, x0:x1] = value
    return a


def _extent(a, thr=128):
    ys, xs = np.nonzero(a[:, :, 0] >= thr)
    return [xs.min(), ys.min(), xs.max() + 1, ys.max() + 1]


def test_no_augmentation_places_the_image_top_left_cut_or_padded():
    img = _rect_image(40, 60, (10, 5, 30, 25))
    out, boxes, kept = A.apply(img, [[10, 5, 30, 25], [50, 30, 70, 50]], (64, 32), A.Augment.none(), None)
    assert out.shape == (64, 32, 3)
    assert np.array_equal(out[:40, :32], img[:, :32]) and not out[40:].any()
    # the second box (20 x 20 px) is cut at column 32: none of it is left inside 32 columns
    assert boxes.tolist() == [[10, 5, 30, 25], [32, 30, 32, 50]]
    assert kept.tolist() == [1.0, 0.0]
    _, boxes, kept = A.apply(img, [[20, 5, 40, 25]], (64, 32), A.Augment.none(), None)
    assert boxes.tolist() == [[20, 5, 32, 25]] and kept[0] == pytest.approx(12 / 20)


@pytest.mark.parametrize("seed", range(8))
def test_boxes_move_exactly_with_the_pixels(seed):
    # Scale, crop or pad, flip: the white rectangle's extent in the output is the returned box
    # (within the resampling's half pixel at each edge).
    box = (37, 21, 93, 61)
    img = _rect_image(96, 160, box)
    aug = A.Augment(scale=(0.6, 1.6), brightness=0, contrast=0, saturation=0)
    out, boxes, kept = A.apply(img, [box], (96, 128), aug, np.random.default_rng(seed))
    assert out.shape == (96, 128, 3)
    if kept[0] == 1.0:
        assert np.abs(np.array(_extent(out)) - boxes[0]).max() <= 1.0
    elif kept[0] > 0:
        # cut by the crop: what is left is the box clipped to the window
        assert np.abs(np.array(_extent(out)) - boxes[0]).max() <= 1.0
        assert 0 < kept[0] < 1
    else:
        assert not (out[:, :, 0] >= 128).any()   # cropped away entirely: nothing white left


def test_flip_mirrors_pixels_and_boxes():
    img = _rect_image(32, 64, (4, 8, 20, 24))
    aug = A.Augment(scale=(1, 1), crop=False, flip=1.0, brightness=0, contrast=0, saturation=0)
    out, boxes, _ = A.apply(img, [[4, 8, 20, 24]], (32, 64), aug, np.random.default_rng(0))
    assert np.array_equal(out, img[:, ::-1]) and boxes.tolist() == [[44, 8, 60, 24]]


def test_brightness_and_saturation_follow_torchvision_formulas():
    rng_img = np.random.default_rng(5)
    img = rng_img.integers(0, 256, (16, 16, 3), dtype=np.uint8)
    aug = A.Augment(scale=(1, 1), crop=False, flip=0, brightness=0.5, contrast=0, saturation=0)
    rng = np.random.default_rng(3)
    out, _, _ = A.apply(img, [], (16, 16), aug, rng)
    # the same draws as apply's: the permutation, then the brightness factor
    r = np.random.default_rng(3)
    r.permutation(3)
    f = r.uniform(0.5, 1.5)
    want = np.rint(np.clip(img / 255.0 * f, 0, 1) * 255)
    assert np.abs(out.astype(float) - want).max() <= 1
    aug = A.Augment(scale=(1, 1), crop=False, flip=0, brightness=0, contrast=0, saturation=0.9)
    grey_img = np.full((4, 4, 3), 77, np.uint8)   # a grey image keeps its grey at any saturation
    out, _, _ = A.apply(grey_img, [], (4, 4), aug, np.random.default_rng(1))
    assert np.abs(out.astype(int) - 77).max() <= 1


def test_batch_plan_shares_and_passes():
    pools = {"real": list(range(6)), "synthetic": list(range(10)), "negative": list(range(3))}
    plan = T.batch_plan(pools, {"real": 0.5, "synthetic": 0.4, "negative": 0.1}, 4, 30, seed=7)
    assert all(len(step) == 4 for step in plan)
    counts = {n: sum(1 for step in plan for p, _ in step if p == n) for n in pools}
    assert counts == {"real": 60, "synthetic": 48, "negative": 12}
    # every pool walked in passes: each index once per pass
    seq = [i for step in plan for p, i in step if p == "real"]
    for k in range(0, 60, 6):
        assert sorted(seq[k:k + 6]) == list(range(6))
    # a share under one slot a batch still gets its slots over the steps
    plan = T.batch_plan(pools, {"real": 0.95, "negative": 0.05}, 2, 50, seed=0)
    assert sum(1 for step in plan for p, _ in step if p == "negative") == 5
    assert T.batch_plan(pools, None, 19, 1, seed=1)[0].count(("real", 0)) == 1   # by size: every sample once
    assert T.batch_plan(pools, None, 4, 9, seed=3) == T.batch_plan(pools, None, 4, 9, seed=3)
    assert T.batch_plan(pools, None, 4, 9, seed=3) != T.batch_plan(pools, None, 4, 9, seed=4)


@pytest.mark.parametrize("mix, message", [
    ({"fake": 1.0}, "do not exist"),
    ({"real": -1.0}, "finite and >= 0"),
    ({"real": 0.0}, "no pool a share"),
    ({"empty": 1.0}, "no samples"),
])
def test_batch_plan_errors(mix, message):
    with pytest.raises(SynthgenError, match=message):
        T.batch_plan({"real": [1, 2], "empty": []}, mix, 2, 2, seed=0)


def _tiny_set(tmp_path, n=4):
    from PIL import Image

    rng = np.random.default_rng(0)
    out = []
    for i in range(n):
        img = (rng.random((64, 96, 3)) * 60).astype(np.uint8)
        x0, y0 = int(rng.integers(4, 50)), int(rng.integers(4, 24))
        img[y0:y0 + 24, x0:x0 + 36] = (200, 40, 40)
        p = str(tmp_path / f"im{i}.png")
        Image.fromarray(img).save(p)
        out.append(Sample(p, [[x0, y0, x0 + 36, y0 + 24], [0, 0, 10, 10]], ["car", ""], np.array([False, True])))
    return out


def _state(model):
    return {k: v.clone() for k, v in model.state_dict().items()}


def test_cpu_training_is_bit_identical_for_a_seed_with_any_workers(tmp_path):
    pools = {"synthetic": _tiny_set(tmp_path)}
    o = T.TrainOptions(steps=3, batch=2, size=(64, 96), warmup=1, seed=11)
    a = T.train(pools, ["car"], o, progress=False)
    b = T.train(pools, ["car"], o, progress=False)
    sa, sb = _state(a.model), _state(b.model)
    assert all(torch.equal(sa[k], sb[k]) for k in sa)
    assert [l["total"] for l in a.losses] == [l["total"] for l in b.losses]
    o.workers = 2
    c = T.train(pools, ["car"], o, progress=False)
    sc = _state(c.model)
    assert all(torch.equal(sa[k], sc[k]) for k in sa)
    o.workers, o.seed = 0, 12
    d = T.train(pools, ["car"], o, progress=False)
    assert not all(torch.equal(sa[k], v) for k, v in _state(d.model).items())


def test_training_lowers_the_loss_and_saves_its_manifest(tmp_path):
    pools = {"synthetic": _tiny_set(tmp_path, 2)}
    o = T.TrainOptions(steps=25, batch=2, size=(64, 96), warmup=2, lr=3e-3, seed=0, augment=A.Augment.none())
    r = T.train(pools, ["car"], o, progress=False)
    first, last = np.mean([l["total"] for l in r.losses[:3]]), np.mean([l["total"] for l in r.losses[-3:]])
    assert last < 0.6 * first
    assert r.manifest["pools"]["synthetic"]["samples"] == 2
    assert r.manifest["pools"]["synthetic"]["boxes"] == 2 and r.manifest["pools"]["synthetic"]["ignore_regions"] == 2
    assert r.manifest["options"]["steps"] == 25
    path = str(tmp_path / "m.model")
    r.model.save(path, metadata=r.manifest)
    m = Detector.from_file(path)
    assert m.metadata["pools"] == r.manifest["pools"] and m.metadata["options"]["seed"] == 0
    dets = T.detect_samples(m, pools["synthetic"], batch=2)
    assert set(dets) == {s.image for s in pools["synthetic"]}


def test_training_errors(tmp_path):
    s = _tiny_set(tmp_path, 1)
    s[0].classes = ["truck", ""]
    with pytest.raises(SynthgenError, match="class 'truck' is not one the detector learns"):
        T.train({"a": s}, ["car"], T.TrainOptions(steps=1, batch=1, size=(64, 96)), progress=False)
    with pytest.raises(SynthgenError, match="multiples of 32"):
        T.train({"a": s}, ["car"], T.TrainOptions(steps=1, batch=1, size=(60, 96)), progress=False)
    with pytest.raises(SynthgenError, match="metadata holds plain values only"):
        Detector(["car"], (64, 96)).save(str(tmp_path / "x.model"), metadata={"a": object()})


def test_read_rgb8_refuses_a_truncated_image(tmp_path):
    from PIL import Image

    p = tmp_path / "a.jpg"
    Image.fromarray(np.full((64, 64, 3), 120, np.uint8)).save(p, quality=90)
    assert read_rgb8(str(p)).shape == (64, 64, 3)
    data = p.read_bytes()
    (tmp_path / "b.jpg").write_bytes(data[: len(data) // 2])
    with pytest.raises(SynthgenError, match="b.jpg"):
        read_rgb8(str(tmp_path / "b.jpg"))
