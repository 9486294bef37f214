"""Scoring detections against ground truth the COCO way (pure numpy: no PyTorch).

Input, per image (any hashable key: a file name, an id): :class:`GroundTruth` (boxes x0 y0 x1
y1 in pixels, class names, crowd and ignore flags) and :class:`Detections` (boxes, scores,
class names). :func:`score` returns :class:`Scores`: per class and per size bucket, AP50,
AP50:95 (each with a bootstrap 95% interval over images) and the recall at 0.1 false positives
per image; :func:`format_table` prints them. :func:`coco_results` / :func:`read_coco_results`
and :func:`detect_records` / :func:`read_detect_records` export and read detections.

The rules are pycocotools' ``COCOeval`` (bbox) exactly, except where a ``NOTE:`` says:

- detections are matched greedily per image and class, by descending score (stable: equal
  scores keep their order), at most ``max_dets`` (100) per image and class; at each IoU
  threshold (0.50, 0.55, ..., 0.95) a detection takes the unmatched ground truth box of
  highest IoU >= the threshold, a box that counts before an ignored one;
- an ignored box (``crowd``, ``ignore``, under ``min_height`` px tall, outside the size
  bucket) is neither a hit nor a miss, and a detection matched to it is neither a true nor a
  false positive; a crowd region can take any number of detections, and its IoU with a
  detection is the intersection over the detection's area; an unmatched detection whose
  height is outside the bucket (or under ``min_height``) is ignored too;
- AP is the mean of the precision at the recall thresholds 0, 0.01, ..., 1 (101 points), the
  precision made monotone (at each recall, the highest precision at that recall or beyond);
  AP50 at IoU 0.5, AP50:95 the mean over the ten thresholds; a class without a counted
  ground truth box has no AP (``nan``, printed ``-``) and is left out of the mean over classes.

Size buckets are by box height, not area (the real frames' median car is 42 px tall, so
COCO's area buckets would put almost every car in one): ``small`` [min_height, 40),
``medium`` [40, 80), ``large`` [80, inf) px, ``all`` [min_height, inf).

Recall at 0.1 FP per image (IoU 0.5): over the whole set's detections ranked by score, the
highest recall reached while the false positives so far are at most 0.1 per image (every
image scored counts, those without a box of the class too).

Bootstrap intervals: ``bootstrap`` (1000) resamples of the images with replacement (seed
``seed``), the percentile interval. Matches are computed once per threshold; a resample
weighs each image's detections and boxes by how often it was drawn (identical to scoring the
resampled set, up to the order of equal scores).
"""
from __future__ import annotations

import json
import math
import os
from dataclasses import dataclass, field
from typing import Any, Dict, Hashable, List, Mapping, Optional, Sequence, Tuple

import numpy as np

from .._core import SynthgenError

__all__ = ["IOU_THRESHOLDS", "RECALL_THRESHOLDS", "SIZE_BUCKETS", "GroundTruth", "Detections", "Row", "Scores",
           "box_iou", "score", "bootstrap_draws", "format_table", "coco_results", "read_coco_results", "detect_records",
           "read_detect_records"]

#: IoU thresholds 0.50:0.05:0.95.
#: NOTE: pycocotools uses ``np.linspace(.5, .95, 10)``, whose 0.9 is 0.9000000000000001; these
#: are the decimal values (an IoU of exactly 0.9 counts at 0.9), otherwise the same.
IOU_THRESHOLDS = np.round(np.linspace(0.5, 0.95, 10), 2)
#: Recall thresholds of the 101-point interpolated precision (pycocotools' ``recThrs``).
RECALL_THRESHOLDS = np.linspace(0.0, 1.0, 101)
#: Size buckets by box height in pixels, [low, high); each starts at ``min_height`` at least.
SIZE_BUCKETS: Dict[str, Tuple[float, float]] = {"all": (0.0, math.inf), "small": (0.0, 40.0),
                                                "medium": (40.0, 80.0), "large": (80.0, math.inf)}
#: Largest results file :func:`read_coco_results` / :func:`read_detect_records` read.
MAX_RESULTS_BYTES = 1 << 30

#: Resamples x detections weighed at a time in the bootstrap (memory: a few such float arrays).
_BOOT_CELLS = 1 << 21
_EPS = np.spacing(1)  # pycocotools: precision = tp / (tp + fp + np.spacing(1))


def _boxes(boxes: Any, n: Optional[int], what: str) -> np.ndarray:
    b = np.asarray(boxes, dtype=np.float64)
    if b.size == 0:
        b = b.reshape(0, 4)
    if b.ndim != 2 or b.shape[1] != 4:
        raise SynthgenError(f"{what}: boxes must be N x 4 (x0, y0, x1, y1), got shape {b.shape}")
    if n is not None and len(b) != n:
        raise SynthgenError(f"{what}: {len(b)} boxes but {n} classes")
    if not np.isfinite(b).all():
        raise SynthgenError(f"{what}: box {int(np.nonzero(~np.isfinite(b).all(1))[0][0])} is not finite")
    bad = np.nonzero((b[:, 2] < b[:, 0]) | (b[:, 3] < b[:, 1]))[0]
    if len(bad):
        raise SynthgenError(f"{what}: box {int(bad[0])} {b[bad[0]].tolist()} has x1 < x0 or y1 < y0")
    return b


def _flags(x: Any, n: int, what: str, name: str) -> np.ndarray:
    if x is None:
        return np.zeros(n, bool)
    f = np.asarray(x, dtype=bool).reshape(-1)
    if len(f) != n:
        raise SynthgenError(f"{what}: {len(f)} {name} flags for {n} boxes")
    return f


@dataclass
class GroundTruth:
    """An image's labelled boxes. A crowd or ignore box whose class is ``""`` (or None) applies to
    every class (as synthgen's COCO datasets write a class-less ignore region)."""
    boxes: Any                            #: N x 4, x0 y0 x1 y1 in pixels
    classes: Sequence[Optional[str]]      #: N class names
    crowd: Any = None                     #: N bools: crowd / ignore regions (COCO ``iscrowd``)
    ignore: Any = None                    #: N bools: boxes neither hit nor miss, matched as boxes

    def __post_init__(self) -> None:
        self.classes = ["" if c is None else str(c) for c in self.classes]
        self.boxes = _boxes(self.boxes, len(self.classes), "ground truth")
        self.crowd = _flags(self.crowd, len(self.classes), "ground truth", "crowd")
        self.ignore = _flags(self.ignore, len(self.classes), "ground truth", "ignore")


@dataclass
class Detections:
    """An image's detections."""
    boxes: Any                            #: N x 4, x0 y0 x1 y1 in pixels
    scores: Any                           #: N confidences
    classes: Sequence[str]                #: N class names

    def __post_init__(self) -> None:
        self.classes = [str(c) for c in self.classes]
        self.boxes = _boxes(self.boxes, len(self.classes), "detections")
        s = np.asarray(self.scores, dtype=np.float64).reshape(-1)
        if len(s) != len(self.classes):
            raise SynthgenError(f"detections: {len(s)} scores for {len(self.classes)} boxes")
        if not np.isfinite(s).all():
            raise SynthgenError(f"detections: score {int(np.nonzero(~np.isfinite(s))[0][0])} is not finite")
        self.scores = s

    def __len__(self) -> int:
        return len(self.classes)


def box_iou(dt: np.ndarray, gt: np.ndarray, crowd: Optional[np.ndarray] = None) -> np.ndarray:
    """IoU of every detection box (D x 4) with every ground truth box (G x 4), x0 y0 x1 y1; for a
    crowd box the intersection over the detection's area.
    NOTE: as pycocotools' ``maskUtils.iou`` for boxes (areas w * h, no +1 pixel)."""
    dt = np.asarray(dt, np.float64).reshape(-1, 4)
    gt = np.asarray(gt, np.float64).reshape(-1, 4)
    iw = np.minimum(dt[:, None, 2], gt[None, :, 2]) - np.maximum(dt[:, None, 0], gt[None, :, 0])
    ih = np.minimum(dt[:, None, 3], gt[None, :, 3]) - np.maximum(dt[:, None, 1], gt[None, :, 1])
    inter = np.clip(iw, 0, None) * np.clip(ih, 0, None)
    da = (dt[:, 2] - dt[:, 0]) * (dt[:, 3] - dt[:, 1])
    ga = (gt[:, 2] - gt[:, 0]) * (gt[:, 3] - gt[:, 1])
    union = da[:, None] + ga[None, :] - inter
    if crowd is not None:
        union = np.where(np.asarray(crowd, bool)[None, :], da[:, None], union)
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(union > 0, inter / np.where(union > 0, union, 1), 0.0)


def _match(ious: np.ndarray, dvalid: np.ndarray, gvalid: np.ndarray, gig: np.ndarray, crowd: np.ndarray,
           thr: np.ndarray) -> Tuple[np.ndarray, np.ndarray]:
    """Greedy matching of many (image, class, bucket) items at once, padded: ``ious`` N x D x G
    (detections by descending score), ``dvalid`` N x D, ``gvalid``/``gig``/``crowd`` N x G, ``thr``
    T. Returns (matched, matched to an ignored box), each N x T x D.
    NOTE: pycocotools ``COCOeval.evaluateImg``: per detection and threshold, the unmatched (or
    crowd) box of highest IoU >= min(t, 1 - 1e-10), boxes that count before ignored ones (its
    ``break`` once a counted box is found), equal IoUs going to the later box."""
    n, d_max, g_max = ious.shape
    t_count = len(thr)
    taken = np.zeros((n, t_count, g_max), bool)
    matched = np.zeros((n, t_count, d_max), bool)
    to_ig = np.zeros((n, t_count, d_max), bool)
    t_eff = np.minimum(thr, 1 - 1e-10)[None, :, None]
    reusable = crowd[:, None, :]
    ig = gig[:, None, :]
    for d in range(d_max):
        iou = ious[:, d, None, :]                                          # N x 1 x G
        ok = (iou >= t_eff) & gvalid[:, None, :] & (~taken | reusable) & dvalid[:, d, None, None]
        ok_counted = ok & ~ig
        sel = np.where(ok_counted.any(-1, keepdims=True), ok_counted, ok & ig)
        val = np.where(sel, iou, -1.0)
        best = g_max - 1 - np.argmax(val[..., ::-1], axis=-1)              # N x T, last of equals
        hit = sel.any(-1)
        matched[:, :, d] = hit
        to_ig[:, :, d] = hit & np.take_along_axis(np.broadcast_to(ig, sel.shape), best[..., None], -1)[..., 0]
        i, t = np.nonzero(hit)
        taken[i, t, best[i, t]] = True
    return matched, to_ig


def _interp_ap(tpc: np.ndarray, fpc: np.ndarray, npig: np.ndarray) -> Tuple[np.ndarray, np.ndarray]:
    """101-point interpolated precision and AP of cumulative TP/FP rows (... x n) over ``npig``
    (...) counted boxes; nan where ``npig`` is 0.
    NOTE: pycocotools ``COCOeval.accumulate``: rc = tp / npig, pr = tp / (tp + fp + eps), pr made
    monotone from the right, q[r] = pr at the first rank with rc >= r (``searchsorted`` left),
    0 beyond the last rank."""
    shape = tpc.shape[:-1]
    n = tpc.shape[-1]
    rows = int(np.prod(shape, dtype=np.int64))
    tpc = tpc.reshape(rows, n)
    fpc = fpc.reshape(rows, n)
    npig = np.broadcast_to(npig, shape).reshape(-1).astype(np.float64)
    prec = np.zeros((len(tpc), len(RECALL_THRESHOLDS)))
    if n:
        with np.errstate(divide="ignore", invalid="ignore"):
            rc = tpc / npig[:, None]
        pr = tpc / (tpc + fpc + _EPS)
        env = np.maximum.accumulate(pr[:, ::-1], axis=1)[:, ::-1]
        for r in range(len(tpc)):
            if npig[r] > 0:
                q = np.searchsorted(rc[r], RECALL_THRESHOLDS, side="left")
                inside = q < n
                prec[r, inside] = env[r, q[inside]]
    prec[npig <= 0] = np.nan
    return prec.reshape(shape + (len(RECALL_THRESHOLDS),)), prec.mean(-1).reshape(shape)


@dataclass
class Row:
    """The scores of one class (or ``"all classes"``, the mean over classes) in one size bucket."""
    cls: str
    bucket: str
    n_gt: int                       #: counted ground truth boxes
    n_ignored: int                  #: ignored ground truth boxes (crowd, ignore, too small, other size)
    n_det: int                      #: detections of the class (all heights)
    ap50: float                     #: nan without a counted box
    ap50_ci: Tuple[float, float]
    ap: float                       #: AP50:95
    ap_ci: Tuple[float, float]
    recall_at_fppi: float           #: at IoU 0.5
    precision: Optional[np.ndarray] = field(default=None, repr=False)  #: T x 101 interpolated precision
    ap50_boot: Optional[np.ndarray] = field(default=None, repr=False)  #: AP50 of each resample (nan: no box)
    ap_boot: Optional[np.ndarray] = field(default=None, repr=False)    #: AP50:95 of each resample


@dataclass
class Scores:
    """What :func:`score` found: one :class:`Row` per class and bucket, classes first then ``all
    classes``, and the settings (for the table's header)."""
    rows: List[Row]
    n_images: int
    classes: List[str]
    buckets: Dict[str, Tuple[float, float]]
    min_height: float
    fppi: float
    bootstrap: int
    seed: int
    confidence: float

    def row(self, cls: str = "all classes", bucket: str = "all") -> Row:
        for r in self.rows:
            if r.cls == cls and r.bucket == bucket:
                return r
        raise KeyError((cls, bucket))


def _sorted_dets(d: Detections, cls: str, max_dets: int) -> np.ndarray:
    """Indices of an image's detections of ``cls`` by descending score (stable), at most max_dets."""
    idx = np.array([i for i, c in enumerate(d.classes) if c == cls], dtype=np.int64)
    if not len(idx):
        return idx
    return idx[np.argsort(-d.scores[idx], kind="mergesort")][:max_dets]


def score(ground_truth: Mapping[Hashable, GroundTruth], detections: Mapping[Hashable, Detections], *,
          classes: Optional[Sequence[str]] = None, min_height: float = 20.0,
          buckets: Mapping[str, Tuple[float, float]] = SIZE_BUCKETS, max_dets: int = 100, fppi: float = 0.1,
          bootstrap: int = 1000, seed: int = 0, confidence: float = 0.95) -> Scores:
    """Scores ``detections`` against ``ground_truth`` (see the module's rules). The images scored
    are ``ground_truth``'s keys (an image without boxes is a :class:`GroundTruth` with none);
    an image missing from ``detections`` has none; a detection of an image that has no ground
    truth raises :class:`SynthgenError`. ``classes`` defaults to every class named in either
    (sorted); ``bootstrap`` 0 gives no intervals (nan)."""
    images = list(ground_truth)
    unknown = [k for k in detections if k not in ground_truth]
    if unknown:
        raise SynthgenError(f"detections of {len(unknown)} image(s) without ground truth, e.g. {unknown[0]!r}: "
                            f"every image scored needs a ground truth entry (empty when it shows nothing)")
    for k in images:
        if not isinstance(ground_truth[k], GroundTruth):
            raise SynthgenError(f"ground truth of image {k!r} is a {type(ground_truth[k]).__name__}, not a GroundTruth")
        if k in detections and not isinstance(detections[k], Detections):
            raise SynthgenError(f"detections of image {k!r} are a {type(detections[k]).__name__}, not Detections")
    if not images:
        raise SynthgenError("no images to score")
    if max_dets < 1 or bootstrap < 0 or not 0 < confidence < 1 or min_height < 0 or fppi < 0:
        raise SynthgenError(f"score: bad settings max_dets={max_dets} bootstrap={bootstrap} confidence={confidence} "
                            f"min_height={min_height} fppi={fppi}")
    empty = Detections(np.zeros((0, 4)), [], [])
    dets = [detections.get(k, empty) for k in images]
    gts = [ground_truth[k] for k in images]
    if classes is None:
        names = {c for g in gts for c in g.classes if c} | {c for d in dets for c in d.classes}
        classes = sorted(names)
    classes = [str(c) for c in classes]
    bnames = list(buckets)
    lo = np.array([max(float(buckets[b][0]), float(min_height)) for b in bnames])
    hi = np.array([float(buckets[b][1]) for b in bnames])
    thr = IOU_THRESHOLDS
    n_img, n_b, n_t = len(images), len(bnames), len(thr)

    weights = None
    if bootstrap:
        draws = bootstrap_draws(n_img, bootstrap, seed)
        weights = np.zeros((bootstrap, n_img))
        np.add.at(weights, (np.repeat(np.arange(bootstrap), n_img), draws.reshape(-1)), 1.0)

    alpha = (1 - confidence) / 2 * 100
    rows: List[Row] = []
    per_class_b: Dict[Tuple[int, int], Tuple[np.ndarray, np.ndarray]] = {}  # (class, bucket) -> AP50, AP b-samples
    results: Dict[Tuple[int, int], Row] = {}
    for ci, cls in enumerate(classes):
        # Items: images with detections of the class; each with its boxes of the class (and
        # class-less crowd/ignore boxes).
        det_idx = [_sorted_dets(d, cls, max_dets) for d in dets]
        gt_idx = [np.array([j for j, c in enumerate(g.classes)
                            if c == cls or (c == "" and (g.crowd[j] or g.ignore[j]))], dtype=np.int64) for g in gts]
        gheights = [g.boxes[j, 3] - g.boxes[j, 1] for g, j in zip(gts, gt_idx)]
        # counted boxes per image and bucket (n_img x n_b)
        counted = np.zeros((n_img, n_b))
        ignored = np.zeros((n_img, n_b))
        for i, (g, j, h) in enumerate(zip(gts, gt_idx, gheights)):
            base = g.crowd[j] | g.ignore[j]
            for b in range(n_b):
                ig = base | (h < lo[b]) | (h >= hi[b])
                counted[i, b] = np.count_nonzero(~ig)
                ignored[i, b] = np.count_nonzero(ig)
        items = [i for i in range(n_img) if len(det_idx[i])]
        d_max = max((len(det_idx[i]) for i in items), default=0)
        g_max = max((len(gt_idx[i]) for i in items), default=0)
        n_it = len(items)
        # Per bucket: the detections of the items in image order, TP/FP per threshold.
        tp = np.zeros((n_b, n_t, n_it, d_max), bool)
        fp = np.zeros((n_b, n_t, n_it, d_max), bool)
        dvalid = np.zeros((n_it, d_max), bool)
        dscore = np.full((n_it, d_max), -np.inf)
        dh = np.zeros((n_it, d_max))
        for k, i in enumerate(items):
            m = len(det_idx[i])
            dvalid[k, :m] = True
            dscore[k, :m] = dets[i].scores[det_idx[i]]
            b = dets[i].boxes[det_idx[i]]
            dh[k, :m] = b[:, 3] - b[:, 1]
        out_of = (dh[None] < lo[:, None, None]) | (dh[None] >= hi[:, None, None])   # n_b x n_it x d_max
        if n_it and g_max:
            ious = np.zeros((n_it, d_max, g_max))
            gvalid = np.zeros((n_it, g_max), bool)
            crowd = np.zeros((n_it, g_max), bool)
            gbase = np.zeros((n_it, g_max), bool)
            gh = np.zeros((n_it, g_max))
            for k, i in enumerate(items):
                j = gt_idx[i]
                if not len(j):
                    continue
                g = gts[i]
                ious[k, :len(det_idx[i]), :len(j)] = box_iou(dets[i].boxes[det_idx[i]], g.boxes[j], g.crowd[j])
                gvalid[k, :len(j)] = True
                crowd[k, :len(j)] = g.crowd[j]
                gbase[k, :len(j)] = g.crowd[j] | g.ignore[j]
                gh[k, :len(j)] = gheights[i]
            # all buckets at once: N = n_b * n_it
            gig = gbase[None] | (gh[None] < lo[:, None, None]) | (gh[None] >= hi[:, None, None])
            matched, to_ig = _match(np.broadcast_to(ious, (n_b,) + ious.shape).reshape(-1, d_max, g_max),
                                    np.broadcast_to(dvalid, (n_b,) + dvalid.shape).reshape(-1, d_max),
                                    np.broadcast_to(gvalid, (n_b,) + gvalid.shape).reshape(-1, g_max),
                                    gig.reshape(-1, g_max),
                                    np.broadcast_to(crowd, (n_b,) + crowd.shape).reshape(-1, g_max), thr)
            matched = matched.reshape(n_b, n_it, n_t, d_max).transpose(0, 2, 1, 3)
            to_ig = to_ig.reshape(n_b, n_it, n_t, d_max).transpose(0, 2, 1, 3)
        else:
            matched = to_ig = np.zeros((n_b, n_t, n_it, d_max), bool)
        valid = dvalid[None, None]
        tp = matched & ~to_ig & valid
        fp = ~matched & ~out_of[:, None] & valid
        # Rank over the set: image order, then descending score (stable, as pycocotools'
        # concatenation of the images' lists and its mergesort).
        flat = np.nonzero(dvalid.reshape(-1))[0]
        order = flat[np.argsort(-dscore.reshape(-1)[flat], kind="mergesort")]
        img_of = np.repeat(np.array(items, dtype=np.int64), d_max)[order] if n_it else np.zeros(0, np.int64)
        tp_r = tp.reshape(n_b, n_t, -1)[:, :, order]
        fp_r = fp.reshape(n_b, n_t, -1)[:, :, order]
        n_det = len(order)
        for b in range(n_b):
            npig = counted[:, b].sum()
            tpc = np.cumsum(tp_r[b], -1, dtype=np.float64)
            fpc = np.cumsum(fp_r[b], -1, dtype=np.float64)
            prec, ap_t = _interp_ap(tpc, fpc, np.full(n_t, npig))
            rec = math.nan
            if npig > 0:
                ok = fpc[0] <= fppi * n_img * (1 + 1e-12)
                rec = float(max([0.0] + list(tpc[0][ok] / npig)))
            ap50_b = ap_b = np.full(bootstrap, np.nan)
            if weights is not None:
                keep = (tp_r[b] | fp_r[b]).any(0)          # other detections change no point of the curve
                np_b = weights @ counted[:, b]             # B
                ap_tb = np.empty((bootstrap, n_t))
                step = max(1, _BOOT_CELLS // max(1, int(keep.sum())))  # resamples at a time: bounded memory
                for r0 in range(0, bootstrap, step):
                    w = weights[r0:r0 + step, img_of[keep]]               # resamples x detections
                    for t in range(n_t):
                        _, ap_tb[r0:r0 + step, t] = _interp_ap(np.cumsum(w * tp_r[b, t, keep], -1),
                                                               np.cumsum(w * fp_r[b, t, keep], -1), np_b[r0:r0 + step])
                ap50_b, ap_b = ap_tb[:, 0], ap_tb.mean(1)
            per_class_b[(ci, b)] = (ap50_b, ap_b)
            r = Row(cls, bnames[b], int(npig), int(ignored[:, b].sum()), n_det, float(ap_t[0]),
                    _interval(ap50_b, alpha), float(ap_t.mean()), _interval(ap_b, alpha), rec, prec, ap50_b, ap_b)
            results[(ci, b)] = r
    for ci in range(len(classes)):
        rows += [results[(ci, b)] for b in range(n_b)]
    for b in range(n_b):
        cr = [results[(ci, b)] for ci in range(len(classes))]
        ap50_b = _nanmean_rows([per_class_b[(ci, b)][0] for ci in range(len(classes))], bootstrap)
        ap_b = _nanmean_rows([per_class_b[(ci, b)][1] for ci in range(len(classes))], bootstrap)
        rows.append(Row("all classes", bnames[b], sum(r.n_gt for r in cr), sum(r.n_ignored for r in cr),
                        sum(r.n_det for r in cr), _nanmean([r.ap50 for r in cr]), _interval(ap50_b, alpha),
                        _nanmean([r.ap for r in cr]), _interval(ap_b, alpha),
                        _nanmean([r.recall_at_fppi for r in cr]), None, ap50_b, ap_b))
    return Scores(rows, n_img, classes, {b: (float(lo[i]), float(hi[i])) for i, b in enumerate(bnames)},
                  float(min_height), float(fppi), int(bootstrap), int(seed), float(confidence))


def bootstrap_draws(n_images: int, bootstrap: int, seed: int) -> np.ndarray:
    """The images (indices) of each resample: ``bootstrap`` x ``n_images``, drawn with replacement."""
    return np.random.default_rng(seed).integers(0, n_images, size=(bootstrap, n_images))


def _nanmean(xs: Sequence[float]) -> float:
    xs = [x for x in xs if not math.isnan(x)]
    return float(np.mean(xs)) if xs else math.nan


def _nanmean_rows(rows: List[np.ndarray], n: int) -> np.ndarray:
    if not rows or not n:
        return np.full(n, np.nan)
    a = np.stack(rows)
    cnt = np.count_nonzero(~np.isnan(a), 0)
    with np.errstate(invalid="ignore"):
        return np.where(cnt > 0, np.nansum(a, 0) / np.maximum(cnt, 1), np.nan)


def _interval(samples: np.ndarray, alpha: float) -> Tuple[float, float]:
    s = samples[~np.isnan(samples)]
    if not len(s):
        return (math.nan, math.nan)
    lo, hi = np.percentile(s, [alpha, 100 - alpha])
    return (float(lo), float(hi))


def _fmt(x: float) -> str:
    return "-" if math.isnan(x) else f"{x:.3f}"


def _fmt_ci(x: float, ci: Tuple[float, float]) -> str:
    if math.isnan(x):
        return "-"
    if math.isnan(ci[0]):
        return _fmt(x)
    return f"{x:.3f} [{ci[0]:.3f}, {ci[1]:.3f}]"


def format_table(s: Scores) -> str:
    """The scores as a plain-text table: a header with the settings, a line per class and
    bucket (``-``: no counted box, so no AP), and the mean over classes when there are several."""
    bk = ", ".join(f"{b} {lo:g}-{hi:g}" if hi < math.inf else f"{b} >= {lo:g}" for b, (lo, hi) in s.buckets.items())
    ci = (f"{s.confidence * 100:g}% bootstrap intervals over images (B={s.bootstrap}, seed {s.seed})"
          if s.bootstrap else "no intervals (bootstrap 0)")
    head = [f"images: {s.n_images}; IoU 0.50:0.05:0.95; 101-point AP; boxes under {s.min_height:g} px tall ignored",
            f"size: box height in px, [low, high): {bk}",
            f"AP: {ci}; R@{s.fppi:g}FPPI: recall at {s.fppi:g} false positives per image, IoU 0.5"]
    cols = ["class", "size", "gt", "ignored", "dets", "AP50 [95% CI]", "AP50:95 [95% CI]", f"R@{s.fppi:g}FPPI"]
    cols[5] = f"AP50 [{s.confidence * 100:g}% CI]"
    cols[6] = f"AP50:95 [{s.confidence * 100:g}% CI]"
    rows = [r for r in s.rows if len(s.classes) > 1 or r.cls != "all classes"]
    body = [[r.cls, r.bucket, str(r.n_gt), str(r.n_ignored), str(r.n_det), _fmt_ci(r.ap50, r.ap50_ci),
             _fmt_ci(r.ap, r.ap_ci), _fmt(r.recall_at_fppi)] for r in rows]
    widths = [max(len(x) for x in col) for col in zip(cols, *body)]
    line = lambda cells: "  ".join(c.ljust(w) if k < 2 else c.rjust(w) for k, (c, w) in enumerate(zip(cells, widths)))
    return "\n".join(head + [line(cols)] + [line(b).rstrip() for b in body]) + "\n"


# ---------------------------------------------------------------------------------------
# Export


def _xywh(b: np.ndarray) -> List[float]:
    return [float(b[0]), float(b[1]), float(b[2] - b[0]), float(b[3] - b[1])]


def coco_results(detections: Mapping[Hashable, Detections], image_ids: Mapping[Hashable, int],
                 category_ids: Mapping[str, int]) -> List[Dict[str, Any]]:
    """Detections as COCO results (``image_id``, ``category_id``, ``bbox`` [x, y, w, h] in
    pixels, ``score``), images in ``detections``' order, each image's by descending score.
    An image or class without an id raises :class:`SynthgenError`."""
    out = []
    for key, d in detections.items():
        if key not in image_ids:
            raise SynthgenError(f"COCO results: image {key!r} has no image_id")
        for i in np.argsort(-d.scores, kind="mergesort"):
            c = d.classes[i]
            if c not in category_ids:
                raise SynthgenError(f"COCO results: class {c!r} (image {key!r}) has no category_id; "
                                    f"known: {', '.join(sorted(category_ids))}")
            out.append({"image_id": int(image_ids[key]), "category_id": int(category_ids[c]),
                        "bbox": _xywh(d.boxes[i]), "score": float(d.scores[i])})
    return out


def _load(records: Any, what: str) -> Tuple[List[Any], str]:
    if isinstance(records, (str, os.PathLike)):
        path = os.fspath(records)
        try:
            size = os.path.getsize(path)
            if size > MAX_RESULTS_BYTES:
                raise SynthgenError(f"{path}: {size} bytes, more than the {MAX_RESULTS_BYTES} a {what} file may have")
            with open(path, encoding="utf-8") as f:
                data = json.load(f)
        except (OSError, UnicodeDecodeError) as e:
            raise SynthgenError(f"{path}: cannot read {what}: {e}") from None
        except json.JSONDecodeError as e:
            raise SynthgenError(f"{path}:{e.lineno}:{e.colno}: not valid JSON: {e.msg}") from None
        where = path
    else:
        data, where = records, what
    if not isinstance(data, list):
        raise SynthgenError(f"{where}: {what} must be a JSON list of records, got {type(data).__name__}")
    return data, where


def _record_box(r: Any, where: str, keys: Sequence[str]) -> List[float]:
    if not isinstance(r, dict):
        raise SynthgenError(f"{where}: a record must be an object, got {type(r).__name__}")
    missing = [k for k in keys if k not in r]
    if missing:
        raise SynthgenError(f"{where}: missing key(s) {', '.join(missing)}")
    b = r["bbox"]
    if (not isinstance(b, list) or len(b) != 4 or not all(isinstance(v, (int, float)) and not isinstance(v, bool)
                                                          and math.isfinite(v) for v in b) or b[2] < 0 or b[3] < 0):
        raise SynthgenError(f"{where}.bbox: must be [x, y, w, h], four finite numbers with w, h >= 0; got {b!r}")
    s = r["score"]
    if not isinstance(s, (int, float)) or isinstance(s, bool) or not math.isfinite(s):
        raise SynthgenError(f"{where}.score: must be a finite number, got {s!r}")
    return [float(b[0]), float(b[1]), float(b[0]) + float(b[2]), float(b[1]) + float(b[3]), float(s)]


def _collect(per: Dict[Hashable, List[Tuple[List[float], str]]]) -> Dict[Hashable, Detections]:
    return {k: Detections(np.array([v[0][:4] for v in vs]).reshape(-1, 4), [v[0][4] for v in vs], [v[1] for v in vs])
            for k, vs in per.items()}


def read_coco_results(records: Any, image_ids: Mapping[Hashable, int],
                      category_ids: Mapping[str, int]) -> Dict[Hashable, Detections]:
    """COCO results (a list or a JSON file of it) back as :class:`Detections` per image key of
    ``image_ids`` (the inverse of :func:`coco_results`); an unknown id or a bad record raises
    :class:`SynthgenError` naming the file and record."""
    data, where = _load(records, "COCO results")
    images = {int(v): k for k, v in image_ids.items()}
    cats = {int(v): k for k, v in category_ids.items()}
    per: Dict[Hashable, List[Tuple[List[float], str]]] = {}
    for n, r in enumerate(data):
        w = f"{where}: [{n}]"
        box = _record_box(r, w, ("image_id", "category_id", "bbox", "score"))
        if r["image_id"] not in images:
            raise SynthgenError(f"{w}.image_id: unknown image id {r['image_id']!r}")
        if r["category_id"] not in cats:
            raise SynthgenError(f"{w}.category_id: unknown category id {r['category_id']!r}; "
                                f"known: {', '.join(str(c) for c in sorted(cats))}")
        per.setdefault(images[r["image_id"]], []).append((box, cats[r["category_id"]]))
    return _collect(per)


def detect_records(detections: Mapping[str, Detections], images: str) -> List[Dict[str, Any]]:
    """Detections of image files as ``synthgen evaluate detect`` records: ``file_name`` (the
    path relative to the folder ``images``, ``/``-separated), ``bbox`` [x, y, w, h] in pixels,
    ``score``, ``category`` (the class name); each image's by descending score. An image outside
    ``images`` raises :class:`SynthgenError`."""
    root = os.path.abspath(images)
    out = []
    for path, d in detections.items():
        rel = os.path.relpath(os.path.abspath(os.path.join(root, path)), root)
        if rel == os.curdir or rel.split(os.sep)[0] == os.pardir:
            raise SynthgenError(f"detect records: image {path!r} is not inside the images folder {images}")
        rel = rel.replace(os.sep, "/")
        for i in np.argsort(-d.scores, kind="mergesort"):
            out.append({"file_name": rel, "bbox": _xywh(d.boxes[i]), "score": float(d.scores[i]),
                        "category": d.classes[i]})
    return out


def read_detect_records(records: Any) -> Dict[str, Detections]:
    """``synthgen evaluate detect`` records (a list or a JSON file of it) back as
    :class:`Detections` per ``file_name``; a bad record raises :class:`SynthgenError` naming
    the file and record."""
    data, where = _load(records, "detect records")
    per: Dict[Hashable, List[Tuple[List[float], str]]] = {}
    for n, r in enumerate(data):
        w = f"{where}: [{n}]"
        box = _record_box(r, w, ("file_name", "bbox", "score", "category"))
        if not isinstance(r["file_name"], str) or not r["file_name"]:
            raise SynthgenError(f"{w}.file_name: must be a non-empty string, got {r['file_name']!r}")
        if not isinstance(r["category"], str):
            raise SynthgenError(f"{w}.category: must be a string, got {r['category']!r}")
        per.setdefault(r["file_name"], []).append((box, r["category"]))
    return _collect(per)  # type: ignore[return-value]
