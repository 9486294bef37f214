"""COCO RLE, YOLO and KITTI writers (synthgen.outputs: coco, yolo, kitti): pure functions, no rendering."""
from __future__ import annotations

import numpy as np
import pytest

from synthgen.outputs import coco as C, kitti as K, yolo as Y


def test_coco_worked_example():
    # COCO's column-major runs: columns [0, 1, 0] and [1, 1, 0] -> 0 1 0 1 1 0.
    rle = C.rle_encode(np.array([[0, 1], [1, 1], [0, 0]], dtype=bool))
    assert rle == {"size": [3, 2], "counts": [1, 1, 1, 2, 1]}


@pytest.mark.parametrize("case", ["empty", "full", "single", "corner", "border", "first_pixel", "last_pixel"])
def test_rle_round_trip_edge_cases(case):
    h, w = 7, 5
    m = np.zeros((h, w), bool)
    if case == "full":
        m[:] = True
    elif case == "single":
        m[3, 2] = True
    elif case == "corner":
        m[-1, -1] = True
    elif case == "border":
        m[0, :] = m[:, 0] = m[-1, :] = m[:, -1] = True
    elif case == "first_pixel":
        m[0, 0] = True
    elif case == "last_pixel":
        m[h - 1, w - 1] = True
    rle = C.rle_encode(m)
    assert sum(rle["counts"]) == h * w
    if m[0, 0]:
        assert rle["counts"][0] == 0, "runs start with the count of zeros"
    np.testing.assert_array_equal(C.rle_decode(rle), m)
    s = C.rle_to_string(rle["counts"])
    assert C.rle_from_string(s) == rle["counts"]
    np.testing.assert_array_equal(C.rle_decode({"size": rle["size"], "counts": s}), m)
    assert C.rle_area(rle) == m.sum()


def test_rle_round_trip_random_masks():
    rng = np.random.default_rng(3)
    for _ in range(300):
        h, w = rng.integers(1, 40, size=2)
        density = rng.uniform(0.0, 1.0)
        m = rng.random((h, w)) < density
        if rng.random() < 0.3:  # blobs: long runs, large count differences in the string form
            m = np.zeros((h, w), bool)
            y0, x0 = rng.integers(0, h), rng.integers(0, w)
            m[y0:y0 + rng.integers(1, h + 1), x0:x0 + rng.integers(1, w + 1)] = True
        rle = C.rle_encode(m)
        np.testing.assert_array_equal(C.rle_decode(rle), m)
        s = C.rle_to_string(rle["counts"])
        assert C.rle_from_string(s) == rle["counts"]


def test_rle_string_hand_derived_values():
    # Derived by hand from pycocotools' rleToString: counts before the third are written as
    # they are, later ones as the difference to the count two places back, 5 bits per
    # character (+48), bit 0x20 = more characters follow, bit 0x10 of the last = negative.
    assert C.rle_to_string([1, 2, 13]) == "12="  # 13 -> 13 + 48 = '='
    assert C.rle_from_string("12=") == [1, 2, 13]
    # [5, 1, 2, 1, 1]: index 3 -> 1 - 1 = 0 -> '0'; index 4 -> 1 - 2 = -1 -> 0x1f + 48 = 'O'.
    assert C.rle_to_string([5, 1, 2, 1, 1]) == "5120O"
    assert C.rle_from_string("5120O") == [5, 1, 2, 1, 1]
    # 100 needs two characters: 100 = 0b11_00100 -> (4 | 0x20) + 48 = 'T', then 3 + 48 = '3'.
    assert C.rle_to_string([100]) == "T3"
    assert C.rle_from_string("T3") == [100]


def test_rle_decode_rejects_bad_counts():
    with pytest.raises(ValueError, match="counts sum"):
        C.rle_decode({"size": [2, 2], "counts": [1, 2]})
    with pytest.raises(ValueError, match="invalid character"):
        C.rle_from_string("1 2")


def test_bbox_equals_mask_extents():
    m = np.zeros((10, 12), bool)
    assert C.mask_bbox(m) is None
    m[5, 3] = True
    assert C.mask_bbox(m) == [3, 5, 1, 1]
    m[2:4, 7:12] = True
    assert C.mask_bbox(m) == [3, 2, 9, 4]
    rng = np.random.default_rng(1)
    for _ in range(100):
        m = rng.random((9, 13)) < 0.05
        box = C.mask_bbox(m)
        if box is None:
            assert not m.any()
            continue
        x, y, w, h = box
        assert m[y:y + h, x:x + w].sum() == m.sum(), "box holds every pixel"
        assert m[y, :].any() and m[y + h - 1, :].any() and m[:, x].any() and m[:, x + w - 1].any(), "box is tight"


def test_coco_annotation_fields_and_empty_mask():
    m = np.zeros((6, 8), bool)
    assert C.coco_annotation(1, 0, 1, m) is None, "nothing is labelled that is not visible"
    m[1:3, 2:5] = True
    ann = C.coco_annotation(4, 2, 3, m, extra={"occlusion": 0.5})
    assert ann["area"] == 6 and ann["bbox"] == [2.0, 1.0, 3.0, 2.0] and ann["iscrowd"] == 0
    assert ann["category_id"] == 3 and ann["image_id"] == 2 and ann["occlusion"] == 0.5
    np.testing.assert_array_equal(C.rle_decode(ann["segmentation"]), m)
    with pytest.raises(ValueError):
        C.coco_annotation(1, 0, 0, m)


def _mask_iou(a: np.ndarray, b: np.ndarray) -> float:
    u = np.logical_or(a, b).sum()
    return float(np.logical_and(a, b).sum() / u) if u else 0.0


def _coco_map(gt: dict, dets: list) -> float:
    """COCO-style mask mAP over IoU thresholds 0.50:0.05:0.95 (101-point interpolated AP per
    category, greedy matching by score), enough to check a dataset against itself."""
    aps = []
    for thr in np.arange(0.5, 0.951, 0.05):
        for cat in gt["categories"]:
            g = [a for a in gt["annotations"] if a["category_id"] == cat["id"]]
            d = sorted([a for a in dets if a["category_id"] == cat["id"]], key=lambda a: -a["score"])
            if not g:
                continue
            used = set()
            tp = []
            for det in d:
                best, best_iou = None, thr
                for gi, ga in enumerate(g):
                    if gi in used or ga["image_id"] != det["image_id"]:
                        continue
                    iou = _mask_iou(C.rle_decode(ga["segmentation"]), C.rle_decode(det["segmentation"]))
                    if iou >= best_iou:
                        best, best_iou = gi, iou
                tp.append(best is not None)
                if best is not None:
                    used.add(best)
            tp = np.array(tp, bool)
            rec = np.cumsum(tp) / len(g)
            prec = np.cumsum(tp) / np.arange(1, len(tp) + 1)
            ap = np.mean([prec[rec >= r].max() if np.any(rec >= r) else 0.0 for r in np.linspace(0, 1, 101)])
            aps.append(ap)
    return float(np.mean(aps))


def test_ground_truth_evaluated_against_itself_is_perfect():
    rng = np.random.default_rng(5)
    images, anns = [], []
    for image_id in range(3):
        ids = np.zeros((24, 32), np.uint16)
        for k in range(1, 5):
            y, x = rng.integers(0, 20), rng.integers(0, 28)
            ids[y:y + rng.integers(2, 8), x:x + rng.integers(2, 8)] = k
        images.append({"id": image_id, "width": 32, "height": 24, "file_name": f"{image_id:06d}.png"})
        for k in range(1, 5):
            a = C.coco_annotation(len(anns) + 1, image_id, 1 + k % 2, ids == k)
            if a:
                anns.append(a)
    ds = C.coco_dataset(images, anns, ["car", "sign"])
    assert [c["id"] for c in ds["categories"]] == [1, 2]
    assert [a["id"] for a in ds["annotations"]] == list(range(1, len(anns) + 1))
    dets = [dict(a, score=1.0) for a in ds["annotations"]]
    assert _coco_map(ds, dets) == pytest.approx(1.0)
    # A shifted detection set is not perfect: the evaluator can fail.
    shifted = []
    for a in dets:
        m = np.roll(C.rle_decode(a["segmentation"]), 3, axis=1)
        shifted.append(dict(a, segmentation=C.rle_encode(m)))
    assert _coco_map(ds, shifted) < 0.9


def test_yolo_round_trip():
    boxes = [(0, [3.0, 5.0, 10.0, 4.0]), (2, [0.0, 0.0, 640.0, 480.0]), (1, [639.0, 479.0, 1.0, 1.0])]
    text = "\n".join(Y.yolo_line(c, b, 640, 480) for c, b in boxes)
    back = Y.parse_yolo(text, 640, 480)
    assert [c for c, _ in back] == [c for c, _ in boxes]
    for (_, b), (_, bb) in zip(boxes, back):
        np.testing.assert_allclose(bb, b, atol=1e-3 * 640)


def test_kitti_round_trip():
    line = K.kitti_line("traffic sign", [10, 20, 30, 40], truncated=0.25, occluded=1, alpha=0.5,
                        dimensions=(1.5, 1.6, 3.9), location=(1.0, 1.5, 10.0), rotation_y=0.3)
    rec = K.parse_kitti(line)[0]
    assert rec["type"] == "traffic_sign" and rec["occluded"] == 1
    assert rec["bbox"] == [10.0, 20.0, 30.0, 40.0]
    assert rec["truncated"] == 0.25 and rec["alpha"] == 0.5 and rec["rotation_y"] == 0.3
    assert rec["dimensions"] == [1.5, 1.6, 3.9] and rec["location"] == [1.0, 1.5, 10.0]
    unknown = K.parse_kitti(K.kitti_line("car", [0, 0, 5, 5]))[0]
    assert unknown["location"] == [-1000.0] * 3 and unknown["dimensions"] == [-1.0] * 3
    assert K.kitti_occlusion_level(1.0) == 0 and K.kitti_occlusion_level(0.6) == 1 and K.kitti_occlusion_level(0.1) == 2
