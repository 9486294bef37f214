"""synthgen.evaluate.score: COCO scoring on hand-computed cases, against an independent
brute-force port of pycocotools' COCOeval on random cases (pycocotools is not in Debian 12),
bootstrap intervals, and the exports. Pure numpy: no test here needs PyTorch."""
from __future__ import annotations

import json
import math
import os
import re
import subprocess
import sys

import numpy as np
import pytest

from synthgen import SynthgenError
from synthgen.evaluate import score as score_module
from synthgen.evaluate.score import (IOU_THRESHOLDS, SIZE_BUCKETS, Detections, GroundTruth, bootstrap_draws,
                                     coco_results, detect_records, format_table, read_coco_results,
                                     read_detect_records, score)

REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
SHARED = os.path.abspath(os.path.join(REPO, "..", "shared"))


def gt(boxes, classes=None, crowd=None, ignore=None):
    return GroundTruth(np.array(boxes, float).reshape(-1, 4), classes or ["car"] * len(boxes), crowd, ignore)


def dt(boxes, scores, classes=None):
    return Detections(np.array(boxes, float).reshape(-1, 4), scores, classes or ["car"] * len(boxes))


#: An AP of 1: COCO's precision is tp / (tp + fp + eps), so one true positive has 1 / (1 + eps).
ONE = pytest.approx(1.0, abs=1e-12)


def car(x=0, h=50):
    """A car box 20 px wide, h px tall, at x."""
    return [x, 0, x + 20, h]


# ---------------------------------------------------------------------------------------
# Hand-computed cases


def test_single_perfect_detection():
    s = score({"a": gt([car()])}, {"a": dt([car()], [0.9])}, bootstrap=0)
    r = s.row("car")
    assert (r.ap50, r.ap, r.recall_at_fppi, r.n_gt) == (ONE, ONE, 1.0, 1)


def test_false_positive_ranked_above_true_positive():
    # Two cars, detections ranked FP (0.9), TP (0.8); the second car is missed.
    # recall 0, 1/2; precision 0, 1/2 -> monotone 1/2, 1/2; the recall thresholds 0, 0.01,
    # ..., 0.50 (51 of 101) take 1/2, those above 1/2 take 0: AP = 51 * 0.5 / 101.
    s = score({"a": gt([car(0), car(100)])}, {"a": dt([car(300), car(0)], [0.9, 0.8])}, bootstrap=0)
    assert s.row("car").ap50 == pytest.approx(51 * 0.5 / 101, abs=1e-12)


def test_duplicate_detection_is_a_false_positive():
    # Cars A, B; detections A (0.9), A again (0.8), B (0.7): recall 1/2, 1/2, 1; precision
    # 1, 1/2, 2/3 -> monotone 1, 2/3, 2/3; thresholds 0..0.50 (51) take 1, 0.51..1 (50) 2/3.
    s = score({"a": gt([car(0), car(100)])},
              {"a": dt([car(0), [0, 0, 20, 48], car(100)], [0.9, 0.8, 0.7])}, bootstrap=0)
    assert s.row("car").ap50 == pytest.approx((51 + 50 * 2 / 3) / 101, abs=1e-12)


def test_crowd_region_takes_any_number_of_detections():
    # A crowd region 200 x 100; two detections inside it (IoU with it 0.04, but intersection
    # over the detection's area 1) rank above the one true positive: neither counts.
    g = gt([car(300), [0, 0, 200, 100]], crowd=[False, True])
    d = dt([[10, 10, 30, 60], [50, 10, 70, 60], car(300)], [0.9, 0.8, 0.7])
    r = score({"a": g}, {"a": d}, bootstrap=0).row("car")
    assert (r.ap50, r.ap, r.n_gt, r.n_ignored) == (ONE, ONE, 1, 1)
    # The same detections against a plain box there are two false positives first.
    g2 = gt([car(300), [0, 0, 200, 100]], crowd=[False, False])
    assert score({"a": g2}, {"a": d}, bootstrap=0).row("car").ap50 < 0.5


def test_classless_crowd_region_applies_to_every_class():
    g = GroundTruth(np.array([car(300), [0, 0, 200, 100]], float), ["car", ""], crowd=[False, True])
    d = dt([[10, 10, 30, 60], car(300)], [0.9, 0.7])
    assert score({"a": g}, {"a": d}, bootstrap=0).row("car").ap50 == ONE


def test_ignore_box_is_matched_once():
    # An ignore box (not crowd) is neither hit nor miss, and the first detection on it is not
    # a false positive; as in COCO it is matched like a box, once: a second detection on it is.
    g = gt([car(0), car(100)], ignore=[False, True])
    one = score({"a": g}, {"a": dt([car(100), car(0)], [0.9, 0.8])}, bootstrap=0).row("car")
    assert (one.ap50, one.n_gt, one.n_ignored) == (ONE, 1, 1)
    two = score({"a": g}, {"a": dt([car(100), car(100), car(0)], [0.9, 0.85, 0.8])}, bootstrap=0).row("car")
    assert two.ap50 == pytest.approx(0.5)  # FP then TP: precision 1/2 at every recall


def test_a_counted_box_is_matched_before_an_ignored_one():
    # The detection overlaps the ignore box more (IoU 1160/1200) than the car (1000/1160), but
    # COCO takes the car: a true positive, not a detection lost on the ignore box.
    g = gt([[0, 0, 20, 50], [0, 0, 20, 60]], ignore=[False, True])
    r = score({"a": g}, {"a": dt([[0, 0, 20, 58]], [0.9])}, bootstrap=0).row("car")
    assert (r.ap50, r.recall_at_fppi) == (ONE, 1.0)


def test_equal_ious_go_to_the_later_box():
    # The first detection has IoU 0.6 with both cars (750 / 1250) and takes the later one (as
    # pycocotools' loop does), so the second, exactly on the first car, is a true positive too.
    g = gt([[0, 0, 20, 50], [10, 0, 30, 50]])
    d = dt([[5, 0, 25, 50], [0, 0, 20, 50]], [0.9, 0.8])
    r = score({"a": g}, {"a": d}, bootstrap=0).row("car")
    # AP per threshold: both true positives up to 0.60; above, the first is a false positive
    # ranked above the second (51 recall thresholds of 101 at precision 1/2).
    assert r.precision.mean(1).tolist() == [ONE] * 3 + [pytest.approx(51 * 0.5 / 101, abs=1e-12)] * 7


def test_boxes_under_min_height_are_neither_hit_nor_miss():
    # A 15 px tall car, detected (0.9) and a 15 px tall car missed; a 30 px car found (0.5).
    g = gt([[0, 0, 10, 15], [50, 0, 60, 15], car(100, 30)])
    d = dt([[0, 0, 10, 15], car(100, 30)], [0.9, 0.5])
    r = score({"a": g}, {"a": d}, bootstrap=0).row("car")
    assert (r.ap50, r.recall_at_fppi, r.n_gt, r.n_ignored) == (ONE, 1.0, 1, 2)
    # A detection 22 px tall on the 19 px car (IoU 19/22 >= 0.5) is matched to it: not a FP;
    # an unmatched detection under 20 px tall is not a FP either.
    g = gt([[0, 0, 10, 19], car(100, 30)])
    d = dt([[0, 0, 10, 22], [200, 0, 210, 12], car(100, 30)], [0.9, 0.8, 0.5])
    assert score({"a": g}, {"a": d}, bootstrap=0).row("car").ap50 == ONE
    # With min_height 10 the 19 px car counts and the 12 px detection is a false positive.
    r = score({"a": g}, {"a": d}, min_height=10, bootstrap=0).row("car")
    assert (r.n_gt, r.ap50) == (2, pytest.approx((51 * 1 + 50 * 2 / 3) / 101))


def test_size_buckets_by_height():
    # cars 30, 60, 100 px tall, each detected; one false positive 60 px tall ranked first.
    g = gt([car(0, 30), car(100, 60), car(200, 100)])
    d = dt([car(500, 60), car(0, 30), car(100, 60), car(200, 100)], [0.95, 0.9, 0.8, 0.7])
    s = score({"a": g}, {"a": d}, bootstrap=0)
    assert (s.row("car", "small").ap50, s.row("car", "large").ap50) == (ONE, ONE)  # the FP is medium
    assert s.row("car", "medium").ap50 == pytest.approx(0.5)
    assert [s.row("car", b).n_gt for b in SIZE_BUCKETS] == [3, 1, 1, 1]
    assert [s.row("car", b).n_ignored for b in SIZE_BUCKETS] == [0, 2, 2, 2]


def test_classes_are_scored_separately():
    # Image a: a car, detected as a person (0.9) and as a car (0.5), and a bike detection
    # (bike has no box anywhere: no AP). Image b: a person, detected as a car (0.95).
    g = {"a": gt([car(0)], ["car"]), "b": gt([car(0)], ["person"])}
    d = {"a": dt([car(0), car(0), car(300)], [0.9, 0.5, 0.3], ["person", "car", "bike"]),
         "b": dt([car(0)], [0.95], ["car"])}
    s = score(g, d, bootstrap=0)
    assert s.classes == ["bike", "car", "person"]
    assert s.row("car").ap50 == pytest.approx(0.5)  # FP (0.95, on the person) then TP (0.5)
    assert s.row("person").ap50 == 0.0              # FP (0.9, on the car), its person missed
    assert math.isnan(s.row("bike").ap50) and s.row("bike").n_det == 1
    assert s.row("all classes").ap50 == pytest.approx(0.25)  # the mean leaves out bike
    assert re.search(r"\nbike +all +0 +0 +1 +- +- +-\n", format_table(s))


def test_images_without_ground_truth_make_false_positives():
    s = score({"a": gt([car()]), "b": gt([])}, {"a": dt([car()], [0.5]), "b": dt([car()], [0.9])}, bootstrap=0)
    assert s.row("car").ap50 == pytest.approx(0.5)
    assert s.row("car").recall_at_fppi == 0.0  # 1 FP on 2 images is 0.5 per image


def test_no_detections():
    s = score({"a": gt([car()]), "b": gt([])}, {}, bootstrap=10)
    r = s.row("car")
    assert (r.ap50, r.ap, r.recall_at_fppi, r.n_det) == (0.0, 0.0, 0.0, 0)
    assert r.ap50_ci == (0.0, 0.0)


def test_ap50_95_on_an_iou_of_exactly_0_7():
    # 10 x 100 car, 10 x 70 detection on it: IoU 700 / 1000 = 0.7 exactly: a true positive
    # at 0.50 ... 0.70 (5 thresholds), a false positive at 0.75 ... 0.95 (5): AP50:95 = 0.5.
    s = score({"a": gt([[0, 0, 10, 100]])}, {"a": dt([[0, 0, 10, 70]], [0.9])}, bootstrap=0)
    r = s.row("car")
    assert (r.ap50, r.ap) == (ONE, pytest.approx(0.5, abs=1e-12))
    assert r.precision[:, 0].tolist() == [ONE] * 5 + [0.0] * 5
    assert IOU_THRESHOLDS.tolist() == [0.5, 0.55, 0.6, 0.65, 0.7, 0.75, 0.8, 0.85, 0.9, 0.95]


def test_recall_at_0_1_false_positives_per_image():
    # 10 images, one car each; ranked TP, FP, TP, TP, FP, TP: 1 FP allowed on 10 images, so the
    # recall before the second FP: 3 / 10. With fppi 0: 1 / 10.
    g = {i: gt([car()]) for i in range(10)}
    hits = [(0, True), (1, False), (2, True), (3, True), (4, False), (5, True)]
    d = {i: dt([car() if ok else car(200)], [1.0 - 0.1 * k]) for k, (i, ok) in enumerate(hits)}
    assert score(g, d, bootstrap=0).row("car").recall_at_fppi == pytest.approx(0.3)
    assert score(g, d, fppi=0, bootstrap=0).row("car").recall_at_fppi == pytest.approx(0.1)


# ---------------------------------------------------------------------------------------
# An independent brute-force port of pycocotools' COCOeval (evaluateImg, accumulate)


def ref_iou(d, g, crowd):
    iw = min(d[2], g[2]) - max(d[0], g[0])
    ih = min(d[3], g[3]) - max(d[1], g[1])
    inter = max(iw, 0) * max(ih, 0)
    da = (d[2] - d[0]) * (d[3] - d[1])
    union = da if crowd else da + (g[2] - g[0]) * (g[3] - g[1]) - inter
    return inter / union if union > 0 else 0.0


def ref_score(gts, dets, cls, lo, hi, fppi=0.1, max_dets=100):
    """AP per threshold and recall at fppi, the COCOeval way, loop by loop."""
    T = list(IOU_THRESHOLDS)
    recs = list(np.linspace(0.0, 1.0, 101))  # as pycocotools (its 0.15 is 0.15000000000000002)
    all_scores, all_m, all_ig, npig = [], [], [], 0
    for key in gts:
        g, d = gts[key], dets.get(key)
        gl = [(list(g.boxes[j]), bool(g.crowd[j]), bool(g.crowd[j] or g.ignore[j]))
              for j in range(len(g.classes)) if g.classes[j] == cls or (g.classes[j] == "" and (g.crowd[j] or g.ignore[j]))]
        gl = [(b, c, ig or not (lo <= b[3] - b[1] < hi)) for b, c, ig in gl]
        gl = [x for x in gl if not x[2]] + [x for x in gl if x[2]]
        dl = [] if d is None else [(float(d.scores[i]), list(d.boxes[i])) for i in range(len(d.classes)) if d.classes[i] == cls]
        dl = sorted(dl, key=lambda x: -x[0])[:max_dets]
        npig += sum(1 for x in gl if not x[2])
        if not gl and not dl:
            continue
        m = [[0] * len(dl) for _ in T]
        dig = [[False] * len(dl) for _ in T]
        for ti, t in enumerate(T):
            gtm = [0] * len(gl)
            for di, (_, db) in enumerate(dl):
                iou, best = min(t, 1 - 1e-10), -1
                for gi, (gb, crowd, ig) in enumerate(gl):
                    if gtm[gi] and not crowd:
                        continue
                    if best > -1 and not gl[best][2] and ig:
                        break
                    v = ref_iou(db, gb, crowd)
                    if v < iou:
                        continue
                    iou, best = v, gi
                if best == -1:
                    continue
                dig[ti][di] = gl[best][2]
                m[ti][di] = 1
                gtm[best] = 1
        for di, (s, db) in enumerate(dl):
            out = not (lo <= db[3] - db[1] < hi)
            all_scores.append(s)
            all_m.append([m[ti][di] for ti in range(len(T))])
            all_ig.append([dig[ti][di] or (not m[ti][di] and out) for ti in range(len(T))])
    order = sorted(range(len(all_scores)), key=lambda i: -all_scores[i])
    aps = []
    rec_fppi = None
    for ti in range(len(T)):
        if npig == 0:
            aps.append(float("nan"))
            continue
        tp = fp = 0
        rc, pr = [], []
        for i in order:
            tp += all_m[i][ti] and not all_ig[i][ti]
            fp += (not all_m[i][ti]) and not all_ig[i][ti]
            rc.append(tp / npig)
            pr.append(tp / (tp + fp + np.spacing(1)))
            if ti == 0 and fp <= fppi * len(gts) + 1e-9:
                rec_fppi = max(rec_fppi or 0.0, tp / npig)
        for i in range(len(pr) - 1, 0, -1):
            pr[i - 1] = max(pr[i - 1], pr[i])
        q = []
        for r in recs:
            k = next((k for k, x in enumerate(rc) if x >= r), None)
            q.append(pr[k] if k is not None else 0.0)
        aps.append(sum(q) / len(q))
    return aps, (rec_fppi or 0.0) if npig else float("nan")


def random_case(rng, n_images, classes=("car", "person")):
    gts, dets = {}, {}
    for i in range(n_images):
        n = int(rng.integers(0, 5))
        xy = rng.uniform(0, 300, (n, 2))
        wh = rng.uniform(5, 120, (n, 2))
        b = np.round(np.c_[xy, xy + wh])
        cl = [str(rng.choice(classes)) for _ in range(n)]
        crowd = rng.random(n) < 0.1
        if n and rng.random() < 0.2:
            cl[0] = ""  # a class-less crowd region
            crowd[0] = True
        gts[f"img{i}"] = GroundTruth(b, cl, crowd, rng.random(n) < 0.1)
        m = int(rng.integers(0, 9))
        if m == 0 and rng.random() < 0.5:
            continue
        src = b[rng.integers(0, n, m)] if n else rng.uniform(0, 300, (m, 4))
        db = np.round(src + rng.normal(0, 6, (m, 4)))
        db[:, 2:] = np.maximum(db[:, 2:], db[:, :2] + 2)
        dets[f"img{i}"] = Detections(db, np.round(rng.random(m), 6), [str(rng.choice(classes)) for _ in range(m)])
    return gts, dets


@pytest.mark.parametrize("seed", range(6))
def test_matches_a_brute_force_cocoeval(seed):
    rng = np.random.default_rng(seed)
    gts, dets = random_case(rng, 25)
    s = score(gts, dets, bootstrap=0, max_dets=5 if seed == 0 else 100)
    for cls in ("car", "person"):
        for b, (lo, hi) in SIZE_BUCKETS.items():
            aps, rec = ref_score(gts, dets, cls, max(lo, 20.0), hi, max_dets=5 if seed == 0 else 100)
            r = s.row(cls, b)
            np.testing.assert_allclose([r.ap50, r.ap, r.recall_at_fppi], [aps[0], np.mean(aps), rec],
                                       rtol=0, atol=1e-12, err_msg=f"{cls} {b}")


# ---------------------------------------------------------------------------------------
# Bootstrap


def test_bootstrap_is_scoring_the_resampled_images(monkeypatch):
    rng = np.random.default_rng(7)
    gts, dets = random_case(rng, 12, classes=("car",))
    s = score(gts, dets, bootstrap=8, seed=3)
    monkeypatch.setattr(score_module, "_BOOT_CELLS", 20)  # a few resamples at a time: the same
    chunked = score(gts, dets, bootstrap=8, seed=3).row("car")
    np.testing.assert_array_equal(chunked.ap_boot, s.row("car").ap_boot)
    keys = list(gts)
    for k, draw in enumerate(bootstrap_draws(len(keys), 8, 3)):
        g = {(c, keys[i]): gts[keys[i]] for c, i in enumerate(draw)}
        d = {(c, keys[i]): dets[keys[i]] for c, i in enumerate(draw) if keys[i] in dets}
        aps, _ = ref_score(g, d, "car", 20.0, math.inf)
        np.testing.assert_allclose([s.row("car").ap50_boot[k], s.row("car").ap_boot[k]], [aps[0], np.mean(aps)],
                                   rtol=0, atol=1e-12)


def test_bootstrap_interval_contains_the_estimate_and_is_deterministic():
    gts, dets = random_case(np.random.default_rng(11), 60, classes=("car",))
    a = score(gts, dets, seed=5)
    b = score(gts, dets, seed=5)
    c = score(gts, dets, seed=6)
    for r in a.rows:
        if r.bucket == "all":
            assert r.ap50_ci[0] <= r.ap50 <= r.ap50_ci[1] and r.ap_ci[0] <= r.ap <= r.ap_ci[1]
            assert r.ap50_ci[0] < r.ap50_ci[1]
    assert [(r.ap50_ci, r.ap_ci) for r in a.rows] == [(r.ap50_ci, r.ap_ci) for r in b.rows]
    assert [(r.ap50_ci, r.ap_ci) for r in a.rows] != [(r.ap50_ci, r.ap_ci) for r in c.rows]
    table = format_table(a)
    r = a.row("car")
    assert f"{r.ap50:.3f} [{r.ap50_ci[0]:.3f}, {r.ap50_ci[1]:.3f}]" in table
    assert "B=1000, seed 5" in table


# ---------------------------------------------------------------------------------------
# Inputs and exports


def test_bad_input_is_an_error():
    with pytest.raises(SynthgenError, match=r"box 1 \[5.0, 0.0, 4.0, 10.0\] has x1 < x0"):
        gt([car(), [5, 0, 4, 10]])
    with pytest.raises(SynthgenError, match="score 0 is not finite"):
        dt([car()], [float("nan")])
    with pytest.raises(SynthgenError, match="image.* without ground truth, e.g. 'b'"):
        score({"a": gt([])}, {"b": dt([car()], [0.5])})


def test_coco_results_round_trip(tmp_path):
    gts, dets = random_case(np.random.default_rng(3), 10)
    image_ids = {k: i + 1 for i, k in enumerate(gts)}
    cats = {"car": 1, "person": 2}
    recs = coco_results(dets, image_ids, cats)
    assert recs and set(recs[0]) == {"image_id", "category_id", "bbox", "score"}
    k0 = next(iter(dets))
    top = int(np.argmax(dets[k0].scores))
    x0, y0, x1, y1 = dets[k0].boxes[top]
    assert recs[0] == {"image_id": image_ids[k0], "category_id": cats[dets[k0].classes[top]],
                       "bbox": [x0, y0, x1 - x0, y1 - y0], "score": dets[k0].scores[top]}
    path = tmp_path / "dets.json"
    path.write_text(json.dumps(recs))
    back = read_coco_results(str(path), image_ids, cats)
    np.testing.assert_equal([(r.ap50, r.ap, r.recall_at_fppi) for r in score(gts, back, bootstrap=0).rows],
                            [(r.ap50, r.ap, r.recall_at_fppi) for r in score(gts, dets, bootstrap=0).rows])
    for k, d in dets.items():
        if not len(d):
            assert k not in back
            continue
        o = np.argsort(-d.scores, kind="mergesort")
        np.testing.assert_array_equal(back[k].boxes, d.boxes[o])
        assert back[k].classes == [d.classes[i] for i in o]
    with pytest.raises(SynthgenError, match="has no category_id"):
        coco_results(dets, image_ids, {"car": 1})
    path.write_text(json.dumps([{"image_id": 1, "category_id": 9, "bbox": [0, 0, 1, 1], "score": 0.5}]))
    with pytest.raises(SynthgenError, match=r"dets.json: \[0\].category_id: unknown category id 9"):
        read_coco_results(str(path), image_ids, cats)


def test_detect_records_are_relative_to_the_images_folder(tmp_path):
    d = {str(tmp_path / "imgs" / "sub" / "a.jpg"): dt([car()], [0.5]), "b.png": dt([], [])}
    recs = detect_records(d, str(tmp_path / "imgs"))
    assert recs == [{"file_name": "sub/a.jpg", "bbox": [0.0, 0.0, 20.0, 50.0], "score": 0.5, "category": "car"}]
    back = read_detect_records(recs)
    assert list(back) == ["sub/a.jpg"] and back["sub/a.jpg"].boxes.tolist() == [car()]
    with pytest.raises(SynthgenError, match="not inside the images folder"):
        detect_records({str(tmp_path / "elsewhere.jpg"): dt([car()], [0.5])}, str(tmp_path / "imgs"))
    with pytest.raises(SynthgenError, match=r"\[0\].bbox: must be \[x, y, w, h\]"):
        read_detect_records([{"file_name": "a.jpg", "bbox": [0, 0, -1, 2], "score": 0.5, "category": "car"}])


def test_scoring_imports_no_torch():
    code = ("import sys, numpy as np; from synthgen.evaluate.score import score, GroundTruth; "
            "score({'a': GroundTruth(np.zeros((0, 4)), [])}, {}); assert 'torch' not in sys.modules")
    subprocess.run([sys.executable, "-c", code], check=True, env={**os.environ, "PYTHONPATH": os.path.join(REPO, "python")})


@pytest.mark.skipif(not os.path.isdir(os.path.join(SHARED, "realdata", "cars_highway")),
                    reason="../shared/realdata is not here")
def test_real_boxes_scored_against_themselves():
    """The real highway frames' boxes (read by the CSV label reader) as detections of
    themselves score 1; shifted by half their width, about nothing."""
    from synthgen.background.label_files import label_images, read_label_file
    path = os.path.join(SHARED, "realdata", "cars_highway", "boxes.csv")
    gts = {}
    for image in label_images(path, "csv"):
        objs = read_label_file(path, "csv", image, (676, 380), default_class="car")
        gts[image] = GroundTruth(np.array([o.box for o in objs], float).reshape(-1, 4), [o.cls for o in objs],
                                 ignore=[o.ignore for o in objs])
    assert len(gts) > 100
    dets = {k: Detections(g.boxes, np.linspace(1, 0.5, len(g.classes)), g.classes) for k, g in gts.items()}
    s = score(gts, dets, bootstrap=50)
    assert s.row(s.classes[0]).ap50 == ONE and s.row(s.classes[0]).n_gt > 100
    # shifted right by half their width: IoU 1/3 with their own box
    shifted = {k: Detections(d.boxes + np.outer((d.boxes[:, 2] - d.boxes[:, 0]) / 2, [1, 0, 1, 0]), d.scores,
                             d.classes) for k, d in dets.items()}
    assert score(gts, shifted, bootstrap=0).row(s.classes[0]).ap50 < 0.05
