"""The reference detector (synthgen.evaluate.detector) and its CenterNet targets
(synthgen.evaluate.targets): the Gaussian radius and heatmap against hand-computed values, the
focal loss on a hand-made 3 x 3 case, ignore regions, encode -> decode round trips, NMS against
a brute-force reference, save/load, determinism, and a tiny overfit from the pretrained backbone
(the only test that needs ../shared). Every test skips without PyTorch.
"""
from __future__ import annotations

import math
import os

import numpy as np
import pytest

from synthgen import SynthgenError

REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
SHARED = os.path.abspath(os.path.join(REPO, "..", "shared"))
WEIGHTS = os.path.join(SHARED, "realdata", "backbones", "shufflenetv2_x0.5_imagenet.pth")

torch = pytest.importorskip("torch", reason="PyTorch (python3-torch) is not installed")

from synthgen.evaluate import backbone as B  # noqa: E402
from synthgen.evaluate import detector as D  # noqa: E402
from synthgen.evaluate import targets as T  # noqa: E402
from synthgen.evaluate.score import GroundTruth, score  # noqa: E402

needs_weights = pytest.mark.skipif(not os.path.isfile(WEIGHTS), reason="../shared/realdata is not here")


def _logits(target: np.ndarray) -> "torch.Tensor":
    """Heatmap logits that a perfect detector would output for ``target`` (sigmoid = target,
    clipped to +-10)."""
    t = np.clip(target.astype(np.float64), 1e-6, 1 - 1e-6)
    return torch.from_numpy(np.clip(np.log(t / (1 - t)), -10, 10).astype(np.float32))


def test_gaussian_radius_against_hand_computed_values():
    # A box of 6 x 8 cells (h x w), min_overlap 0.7: the three roots of CenterNet's quadratics
    # r1 = (14 + sqrt(14^2 - 4 * 48 * 0.3 / 1.7)) / 2 = 13.3663
    # r2 = (28 + sqrt(28^2 - 16 * 0.3 * 48)) / 2 = 25.7644
    # r3 = (-19.6 + sqrt(19.6^2 + 4 * 2.8 * 0.3 * 48)) / 2 = 1.87733; the smallest is r3.
    assert T.gaussian_radius(6, 8) == pytest.approx(1.87733, abs=1e-5)
    # 20 px cars are 2.5 cells: r1 = 4.76871, r2 = 9.18330,
    # r3 = (-7 + sqrt(49 + 4 * 2.8 * 0.3 * 6.25)) / 2 = 0.68330: radius int(0.68) = 0, one cell
    assert T.gaussian_radius(2.5, 2.5) == pytest.approx(0.68330, abs=1e-5)
    # A square of 30 cells: r3 = (-84 + sqrt(84^2 + 4 * 2.8 * 0.3 * 900)) / 2 = 8.19960
    assert T.gaussian_radius(30, 30) == pytest.approx(8.19960, abs=1e-5)


def test_heatmap_peak_and_gaussian_values():
    # A 64 x 48 px box centred at (76, 52) px: 8 x 6 cells, centre cell (9, 6) with offset
    # (0.5, 0.5); radius int(1.877) = 1, sigma (2 * 1 + 1) / 6 = 0.5: the 4 neighbours
    # exp(-1 / 0.5) = exp(-2), the diagonals exp(-4), nothing two cells away.
    e = T.encode([[44, 28, 108, 76]], [0], (128, 256), 1)
    heat = e["heat"][0]
    assert heat.shape == (16, 32)
    assert heat[6, 9] == 1.0
    assert heat[6, 8] == heat[6, 10] == heat[5, 9] == heat[7, 9] == pytest.approx(math.exp(-2), rel=1e-6)
    assert heat[5, 8] == heat[7, 10] == pytest.approx(math.exp(-4), rel=1e-6)
    assert np.count_nonzero(heat) == 9
    assert e["reg_mask"][6, 9] == 1 and e["reg_mask"].sum() == 1
    np.testing.assert_allclose(e["offset"][:, 6, 9], [0.5, 0.5])
    np.testing.assert_allclose(e["size"][:, 6, 9], [math.log(8), math.log(6)], rtol=1e-6)
    assert e["heat_mask"].min() == 1  # nothing ignored


def test_focal_loss_on_a_hand_made_3x3_case():
    # One positive (p 0.8), four negatives at target 0.5 (p 0.3), four at 0 (p 0.1):
    # -[(1 - 0.8)^2 log 0.8 + 4 (1 - 0.5)^4 0.3^2 log 0.7 + 4 (1 - 0)^4 0.1^2 log 0.9] / 1
    #  = 0.0089257 + 0.0080252 + 0.0042144 = 0.0211653
    target = np.array([[0, 0.5, 0], [0.5, 1, 0.5], [0, 0.5, 0]], np.float32)
    p = np.array([[0.1, 0.3, 0.1], [0.3, 0.8, 0.3], [0.1, 0.3, 0.1]])
    logits = torch.from_numpy(np.log(p / (1 - p)))[None, None]
    got = float(T.focal_loss(logits, torch.from_numpy(target).double()[None, None]))
    assert got == pytest.approx(0.0211653, abs=1e-6)
    # two positives halve the sum per box
    target2 = target.copy()
    target2[0, 0] = 1
    p2 = p.copy()
    p2[0, 0] = 0.8
    got2 = float(T.focal_loss(torch.from_numpy(np.log(p2 / (1 - p2)))[None, None],
                              torch.from_numpy(target2).double()[None, None]))
    assert got2 == pytest.approx((0.0089257 * 2 + 0.0080252 + 0.0042144 * 3 / 4) / 2, abs=1e-6)


def test_ignore_regions_and_small_boxes_zero_the_loss_there():
    H, W = 128, 256
    boxes = [[20, 20, 60, 60], [200, 40, 205, 90]]  # the second is 5 px wide: under MIN_SIZE, ignored
    e = T.encode(boxes, [0, 1], (H, W), 2, ignore=[[100, 64, 150, 120]], ignore_classes=[-1])
    m = e["heat_mask"]
    # the ignore region covers rows 8..14, columns 12..18 of every class
    assert (m[:, 8:15, 12:19] == 0).all() and m[:, 8:15, 11].all() and m[:, 15, 12:19].all()
    # the small box: class 1 only, cells 25..25 x 5..11; no target of it
    assert (m[1, 5:12, 25] == 0).all() and m[0, 5:12, 25].all()
    assert e["heat"][1].max() == 0 and e["reg_mask"].sum() == 1
    assert m.sum() == 2 * 16 * 32 - 2 * 7 * 7 - 7

    tg = {k: torch.from_numpy(v)[None] for k, v in e.items()}
    g = torch.Generator().manual_seed(3)
    base = torch.randn((1, 2, 16, 32), generator=g)
    inside = base.clone()
    inside[:, :, 8:15, 12:19] += 5 * torch.randn((1, 2, 7, 7), generator=g)
    inside[:, 1, 5:12, 25] = 8.0  # a confident detection of the ignored small box
    outside = base.clone()
    outside[:, :, 0:4, 0:4] += 5.0
    f = lambda x: float(T.focal_loss(x, tg["heat"], tg["heat_mask"]))  # noqa: E731
    assert f(inside) == f(base)
    assert f(outside) > f(base)
    # without the mask, the same change costs
    assert float(T.focal_loss(inside, tg["heat"])) > float(T.focal_loss(base, tg["heat"]))

    # an ignore region over a counted box keeps that box's centre cell
    e2 = T.encode([[20, 20, 60, 60]], [0], (H, W), 1, ignore=[[0, 0, 100, 100]])
    assert e2["heat_mask"][0, 5, 5] == 1 and e2["heat_mask"].sum() == 16 * 32 - 13 * 13 + 1


ROUND_TRIP_BOXES = np.array([
    [0, 0, 30, 22],           # top-left corner
    [226, 100, 256, 128],     # bottom-right corner
    [-12, 50, 30, 90],        # partly outside the left edge: clipped to [0, 50, 30, 90]
    [100, 10, 120, 30],       # 20 px
    [150.5, 70.25, 170.5, 90.75],  # 20 x 20.5 px, off the pixel grid
    [60, 40, 180, 110],       # large
    [236, 0, 256, 20],        # 20 px at the top-right corner
], np.float64)
ROUND_TRIP_CLASSES = [0, 0, 1, 1, 0, 1, 0]


def test_encode_decode_round_trip_recovers_the_boxes():
    H, W = 128, 256
    e = T.encode(ROUND_TRIP_BOXES, ROUND_TRIP_CLASSES, (H, W), 2)
    assert e["reg_mask"].sum() == len(ROUND_TRIP_BOXES)  # no two centres share a cell
    out = T.decode(_logits(e["heat"])[None], torch.from_numpy(e["size"])[None],
                   torch.from_numpy(e["offset"])[None], k=100, threshold=0.5)
    boxes, scores, cls = out[0]
    assert len(boxes) == len(ROUND_TRIP_BOXES)
    want = np.clip(ROUND_TRIP_BOXES, 0, [W, H, W, H])
    got = boxes.double().numpy()
    for b, c in zip(want, ROUND_TRIP_CLASSES):
        i = int(np.argmin(np.abs(got - b).sum(1)))
        np.testing.assert_allclose(got[i], b, atol=1e-3)  # exact up to float32
        assert int(cls[i]) == c


def test_detect_round_trip_and_padding():
    """A detector whose head outputs the encoded targets of a 100 x 200 image (padded to
    128 x 224) finds exactly its boxes, clipped to the image, and nothing in the padding."""
    D.deterministic(0)
    H, W = 100, 200
    boxes = np.array([[0, 0, 20, 20], [180, 78, 200, 100], [50, 30, 130, 90]], np.float64)
    e = T.encode(boxes, [0, 0, 0], (128, 224), 1)
    m = D.Detector(["car"], (128, 224))
    fake = {"heat": _logits(e["heat"])[None], "size": torch.from_numpy(e["size"])[None],
            "offset": torch.from_numpy(e["offset"])[None]}
    m.forward = lambda x: {k: v.expand(len(x), -1, -1, -1) for k, v in fake.items()}
    dets = m.detect(np.zeros((H, W, 3), np.uint8), threshold=0.5)
    assert len(dets) == 1 and len(dets[0]) == 3
    got = dets[0].boxes[np.argsort(dets[0].boxes[:, 0])]
    np.testing.assert_allclose(got, boxes[np.argsort(boxes[:, 0])], atol=1e-3)
    assert dets[0].classes == ["car"] * 3


def _nms_reference(boxes, scores, classes, thr):
    """Greedy NMS, one box at a time, in plain Python."""
    def iou(a, b):
        iw = max(0.0, min(a[2], b[2]) - max(a[0], b[0]))
        ih = max(0.0, min(a[3], b[3]) - max(a[1], b[1]))
        inter = iw * ih
        union = (a[2] - a[0]) * (a[3] - a[1]) + (b[2] - b[0]) * (b[3] - b[1]) - inter
        return inter / union if union > 0 else 0.0
    order = sorted(range(len(boxes)), key=lambda i: -scores[i])  # stable: ties keep input order
    keep = []
    for i in order:
        if all(classes[j] != classes[i] or iou(boxes[i], boxes[j]) <= thr for j in keep):
            keep.append(i)
    return keep


@pytest.mark.parametrize("thr", [0.3, 0.5, 0.7])
def test_nms_matches_a_brute_force_reference(thr):
    rng = np.random.default_rng(int(thr * 10))
    n = 300
    xy = rng.uniform(0, 200, (n, 2))
    wh = rng.uniform(5, 60, (n, 2))
    xy[:200] = xy[:200:10].repeat(10, 0) + rng.normal(0, 3, (200, 2))  # 20 clusters of 10 jittered boxes
    wh[:200] = wh[:200:10].repeat(10, 0) + rng.normal(0, 3, (200, 2))
    boxes = np.concatenate([xy, xy + np.maximum(wh, 1)], 1)
    scores = rng.integers(0, 50, n) / 50.0  # ties on purpose
    classes = rng.integers(0, 3, n)
    want = _nms_reference(boxes.tolist(), scores.tolist(), classes.tolist(), thr)
    got = T.nms(torch.from_numpy(boxes), torch.from_numpy(scores), torch.from_numpy(classes), thr)
    assert got.tolist() == want
    assert 0 < len(want) < n - 30  # suppression happened, often


def _tiny_batch(seed: int = 0, n: int = 4, H: int = 128, W: int = 256):
    """``n`` images of uniform noise with 3 flat-coloured rectangles each (20-63 x 20-47 px)."""
    rng = np.random.default_rng(seed)
    ims, gts = [], []
    for _ in range(n):
        im = rng.integers(0, 256, (H, W, 3), dtype=np.uint8)
        boxes = []
        for _ in range(3):
            w, h = int(rng.integers(20, 64)), int(rng.integers(20, 48))
            x0, y0 = int(rng.integers(0, W - w)), int(rng.integers(0, H - h))
            im[y0:y0 + h, x0:x0 + w] = rng.integers(0, 256, 3)
            boxes.append([x0, y0, x0 + w, y0 + h])
        ims.append(im)
        gts.append(boxes)
    return np.stack(ims), gts


def _train(model, ims, gts, steps: int, lr: float = 2e-3):
    H, W = ims.shape[1:3]
    enc = [T.encode(b, [0] * len(b), (H, W), 1) for b in gts]
    tg = {k: torch.from_numpy(np.stack([e[k] for e in enc])) for k in enc[0]}
    x = B.normalize(ims)
    opt = torch.optim.Adam(model.parameters(), lr=lr)
    model.train()
    parts = {}
    for _ in range(steps):
        total, parts = T.loss(model(x), tg)
        opt.zero_grad()
        total.backward()
        opt.step()
    return parts


@needs_weights
def test_tiny_overfit_from_the_pretrained_backbone():
    """The pipeline can learn: 4 images, 100 steps of Adam on the CPU, AP50 on the same images."""
    D.deterministic(0)
    ims, gts = _tiny_batch()
    model = D.Detector(["box"], (128, 256))
    B.load_pretrained(WEIGHTS, model.backbone)
    parts = _train(model, ims, gts, steps=100)
    dets = model.detect(ims)
    gt = {i: GroundTruth(boxes=b, classes=["box"] * len(b)) for i, b in enumerate(gts)}
    s = score(gt, dict(enumerate(dets)), bootstrap=0)
    row = s.row("box")
    print(f"\noverfit: final losses {', '.join(f'{k} {v:.4f}' for k, v in parts.items())}; "
          f"AP50 {row.ap50:.3f}, AP50:95 {row.ap:.3f} on {row.n_gt} boxes, {row.n_det} detections")
    assert row.ap50 >= 0.9


def test_same_seed_same_weights():
    ims, gts = _tiny_batch(seed=1, n=2, H=64, W=128)

    def run(seed):
        D.deterministic(seed)
        m = D.Detector(["box"], (64, 128))
        _train(m, ims, gts, steps=3)
        return m.state_dict()

    a, b, c = run(5), run(5), run(6)
    assert all(torch.equal(a[k], b[k]) for k in a)
    assert not all(torch.equal(a[k], c[k]) for k in a)


def test_save_load_round_trip_is_bit_identical(tmp_path):
    D.deterministic(0)
    ims, gts = _tiny_batch(seed=2, n=2, H=64, W=128)
    m = D.Detector(["car", "truck"], (64, 128))
    _train(m, ims, gts, steps=2)  # moves weights and BatchNorm statistics off their initial values
    m.eval()
    path = str(tmp_path / "m.model")
    m.save(path)
    raw = torch.load(path, map_location="cpu", weights_only=True)
    assert raw["format"] == D.FORMAT and raw["version"] == D.VERSION and raw["class_names"] == ["car", "truck"]
    assert raw["input_size"] == [64, 128] and raw["normalization"] == "rgb01"
    m2 = D.Detector.from_file(path)
    assert m2.class_names == ["car", "truck"] and m2.input_size == (64, 128) and not m2.training
    x = B.normalize(ims)
    with torch.no_grad():
        o1, o2 = m(x), m2(x)
    assert all(torch.equal(o1[k], o2[k]) for k in o1)
    d1, d2 = m.detect(ims, threshold=0.0), m2.detect(ims, threshold=0.0)
    for a, b in zip(d1, d2):
        assert np.array_equal(a.boxes, b.boxes) and np.array_equal(a.scores, b.scores) and a.classes == b.classes


def test_from_file_errors_name_the_file(tmp_path):
    m = D.Detector(["car"], (64, 128))
    good = str(tmp_path / "good.model")
    m.save(good)
    d = torch.load(good, map_location="cpu", weights_only=True)

    def bad(name, obj=None, data=None):
        p = str(tmp_path / name)
        if data is not None:
            with open(p, "wb") as f:
                f.write(data)
        elif obj is not None:
            torch.save(obj, p)
        with pytest.raises(SynthgenError) as e:
            D.Detector.from_file(p)
        msg = str(e.value)
        assert msg.startswith(p + ": ")
        print(msg)
        return msg

    assert "not found" in bad("missing.model")
    assert "cannot read a detector model" in bad("junk.model", data=b"not a torch file at all")
    assert "not a synthgen detector model" in bad("list.model", obj=[1, 2])
    assert "not a synthgen detector model" in bad("other.model", obj={"format": "yolo"})
    assert "version 2" in bad("v2.model", obj=dict(d, version=2))
    assert "tensor heat.2.weight is (1, 64, 1, 1), the detector needs (2, 64, 1, 1)" in \
        bad("classes.model", obj=dict(d, class_names=["car", "truck"]))
    assert "1 missing" in bad("keys.model", obj=dict(d, state_dict={k: v for k, v in d["state_dict"].items()
                                                                  if k != "fuse.1.running_var"}))
    assert "input size (64, 100) must be two positive multiples of 32" in bad("size.model", obj=dict(d, input_size=[64, 100]))


def test_bad_construction_and_targets():
    with pytest.raises(SynthgenError, match="class names must be distinct"):
        D.Detector(["car", "car"])
    with pytest.raises(SynthgenError, match="class index 3 outside 0..1"):
        T.encode([[0, 0, 10, 10]], [3], (64, 64), 2)
    with pytest.raises(SynthgenError, match="2 boxes but 1 classes"):
        T.encode([[0, 0, 10, 10], [0, 0, 20, 20]], [0], (64, 64), 1)
