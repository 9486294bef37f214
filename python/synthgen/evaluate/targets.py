"""The reference detector's targets, losses, decoding and NMS: CenterNet's encoding on one
stride-8 output (CenterNet: Zhou, Wang and Kraehenbuehl 2019, "Objects as Points").

* :func:`encode` turns an image's boxes (pixels, x0 y0 x1 y1), class indices and ignore regions
  into dense target maps of ``ceil(H / 8) x ceil(W / 8)`` cells (numpy, no PyTorch):

  - ``heat`` (C x h x w): per class, a Gaussian around each counted box's centre cell, 1 at that
    cell (:func:`gaussian_radius`, :func:`draw_gaussian`; overlapping Gaussians take the
    maximum);
  - ``size`` (2 x h x w): ``log(w / 8)``, ``log(h / 8)`` of the box at its centre cell;
  - ``offset`` (2 x h x w): the centre's sub-cell position, ``cx / 8 - floor(cx / 8)`` (and y),
    in [0, 1);
  - ``reg_mask`` (h x w): 1 at the centre cell of each counted box (where size and offset are
    learnt), else 0;
  - ``heat_mask`` (C x h x w): 0 where the heatmap loss is not counted: every cell that overlaps
    an ignore region (of its class, or of every class for class -1) or a box under ``min_size``
    px (in width or height: too small for an 8 px cell to place; such boxes are ignored, not
    learnt as background), except the centre cells of counted boxes.

  Boxes are clipped to the image first, so a box at the border has its centre inside. Two boxes
  of one class whose centres fall into one cell share it (the later one's size and offset).
* :func:`focal_loss`, :func:`regression_loss`, :func:`loss`: CenterNet's penalty-reduced focal
  loss (alpha 2, beta 4) on the heatmap, masked by ``heat_mask`` and divided by the number of
  counted boxes; L1 on size (log space) and offset at the ``reg_mask`` cells, divided by the
  number of those cells.
* :func:`decode`: the top-k peaks of the sigmoid heatmap (a cell that is the maximum of its 3 x 3
  neighbourhood, as CenterNet's max-pool NMS) -> boxes in pixels, scores, class indices.
* :func:`nms`: greedy class-wise non-maximum suppression in plain torch (no ``torchvision.ops``,
  whose compiled operators are tied to its version): a box is dropped when its IoU with a kept
  box of the same class of higher score is above ``iou_threshold``.

Why the size is regressed in log space: the cars range from under 20 to over 200 px; an L1 loss
on raw sizes weighs a 4 px error on a 200 px car like one on a 20 px car, where it costs 20 times
the IoU. In log space the error is relative, so small boxes weigh as much as large ones.
"""
from __future__ import annotations

import math
from typing import Any, Dict, Optional, Sequence, Tuple

import numpy as np

from .._core import SynthgenError
from . import _torch

__all__ = ["STRIDE", "MIN_SIZE", "MIN_OVERLAP", "ALPHA", "BETA", "gaussian_radius", "draw_gaussian", "encode",
           "focal_loss", "regression_loss", "loss", "decode", "box_iou", "nms"]

#: The output's stride in pixels.
STRIDE = 8
#: Boxes narrower or lower than this (px) are ignore regions, not targets.
MIN_SIZE = 8.0
#: The IoU a box placed by a corner within the Gaussian's radius still reaches (CenterNet's 0.7).
MIN_OVERLAP = 0.7
#: The focal loss's exponents (CenterNet: alpha 2 on the prediction, beta 4 on the Gaussian).
ALPHA = 2.0
BETA = 4.0


def gaussian_radius(height: float, width: float, min_overlap: float = MIN_OVERLAP) -> float:
    """The radius (in output cells, for a box of ``height`` x ``width`` cells) within which a
    box's corners may move and keep an IoU of ``min_overlap`` with it: the smallest root of
    three quadratics, one per way the corners move.

    NOTE: CenterNet's ``gaussian_radius`` (src/lib/utils/image.py, from CornerNet) exactly,
    including its known deviations from the closed form (``r = (b + sq) / 2`` where the roots
    are ``(b + sq) / (2a)``): the trained behaviour of the published models depends on it."""
    h, w = float(height), float(width)
    b1 = h + w
    c1 = w * h * (1 - min_overlap) / (1 + min_overlap)
    r1 = (b1 + math.sqrt(b1 ** 2 - 4 * c1)) / 2
    b2 = 2 * (h + w)
    c2 = (1 - min_overlap) * w * h
    r2 = (b2 + math.sqrt(b2 ** 2 - 16 * c2)) / 2
    a3 = 4 * min_overlap
    b3 = -2 * min_overlap * (h + w)
    c3 = (min_overlap - 1) * w * h
    r3 = (b3 + math.sqrt(b3 ** 2 - 4 * a3 * c3)) / 2
    return min(r1, r2, r3)


def draw_gaussian(heat: np.ndarray, cx: int, cy: int, radius: int) -> None:
    """Draws ``exp(-(dx^2 + dy^2) / (2 sigma^2))``, ``sigma = (2 radius + 1) / 6``, on the
    ``(2 radius + 1)^2`` cells around ``(cx, cy)`` of ``heat`` (h x w, in place), taking the
    maximum with what is there; values under ``eps * max`` are 0.

    NOTE: CenterNet's ``draw_umich_gaussian`` / ``gaussian2D``."""
    d = 2 * radius + 1
    sigma = d / 6.0
    y, x = np.ogrid[-radius:radius + 1, -radius:radius + 1]
    g = np.exp(-(x * x + y * y) / (2 * sigma * sigma))
    g[g < np.finfo(g.dtype).eps * g.max()] = 0
    h, w = heat.shape
    left, right = min(cx, radius), min(w - cx, radius + 1)
    top, bottom = min(cy, radius), min(h - cy, radius + 1)
    region = heat[cy - top:cy + bottom, cx - left:cx + right]
    np.maximum(region, g[radius - top:radius + bottom, radius - left:radius + right], out=region)


def _as_boxes(boxes: Any, what: str) -> np.ndarray:
    b = np.asarray(boxes, dtype=np.float64).reshape(-1, 4) if len(boxes) else np.zeros((0, 4))
    if not np.isfinite(b).all():
        raise SynthgenError(f"encode: a {what} box is not finite")
    return b


def encode(boxes: Any, classes: Sequence[int], image_size: Tuple[int, int], num_classes: int, *,
           ignore: Any = (), ignore_classes: Optional[Sequence[int]] = None, min_size: float = MIN_SIZE,
           stride: int = STRIDE) -> Dict[str, np.ndarray]:
    """The target maps (float32, see the module docstring) of one image of ``image_size``
    (rows, columns) with ``boxes`` (N x 4, x0 y0 x1 y1 px) of ``classes`` (N indices in
    ``[0, num_classes)``) and ``ignore`` regions (M x 4 px) of ``ignore_classes`` (M indices,
    -1 for every class; default all -1)."""
    H, W = int(image_size[0]), int(image_size[1])
    h, w = -(-H // stride), -(-W // stride)
    b = _as_boxes(boxes, "")
    cls = np.asarray(classes, dtype=np.int64).reshape(-1)
    if len(cls) != len(b):
        raise SynthgenError(f"encode: {len(b)} boxes but {len(cls)} classes")
    if len(cls) and (cls.min() < 0 or cls.max() >= num_classes):
        raise SynthgenError(f"encode: class index {int(cls[(cls < 0) | (cls >= num_classes)][0])} "
                            f"outside 0..{num_classes - 1}")
    ig = _as_boxes(ignore, "ignore")
    igc = np.full(len(ig), -1, np.int64) if ignore_classes is None else np.asarray(ignore_classes, np.int64).reshape(-1)
    if len(igc) != len(ig):
        raise SynthgenError(f"encode: {len(ig)} ignore regions but {len(igc)} ignore classes")
    b = np.clip(b, 0, [W, H, W, H])
    bw, bh = b[:, 2] - b[:, 0], b[:, 3] - b[:, 1]
    small = (bw < min_size) | (bh < min_size)
    heat = np.zeros((num_classes, h, w), np.float32)
    size = np.zeros((2, h, w), np.float32)
    offset = np.zeros((2, h, w), np.float32)
    reg_mask = np.zeros((h, w), np.float32)
    heat_mask = np.ones((num_classes, h, w), np.float32)
    for (x0, y0, x1, y1), c in list(zip(np.clip(ig, 0, [W, H, W, H]), igc)) + list(zip(b[small], cls[small])):
        if x1 <= x0 or y1 <= y0:
            continue
        sl = (slice(int(y0 // stride), int(math.ceil(y1 / stride))), slice(int(x0 // stride), int(math.ceil(x1 / stride))))
        if c < 0:
            heat_mask[(slice(None),) + sl] = 0
        else:
            heat_mask[(int(c),) + sl] = 0
    centres = []
    for (x0, y0, x1, y1), c in zip(b[~small], cls[~small]):
        cx, cy = (x0 + x1) / 2 / stride, (y0 + y1) / 2 / stride
        ix, iy = min(int(cx), w - 1), min(int(cy), h - 1)
        r = max(0, int(gaussian_radius((y1 - y0) / stride, (x1 - x0) / stride)))
        draw_gaussian(heat[c], ix, iy, r)
        size[:, iy, ix] = (math.log((x1 - x0) / stride), math.log((y1 - y0) / stride))
        offset[:, iy, ix] = (cx - ix, cy - iy)
        reg_mask[iy, ix] = 1
        centres.append((c, iy, ix))
    for c, iy, ix in centres:
        heat_mask[c, iy, ix] = 1
    return {"heat": heat, "size": size, "offset": offset, "reg_mask": reg_mask, "heat_mask": heat_mask}


def focal_loss(logits: Any, target: Any, mask: Any = None, *, alpha: float = ALPHA, beta: float = BETA) -> Any:
    """CenterNet's penalty-reduced focal loss of heatmap ``logits`` (N x C x h x w, before the
    sigmoid) against the Gaussian ``target``: at cells where the target is 1,
    ``-(1 - p)^alpha log p``; elsewhere ``-(1 - y)^beta p^alpha log(1 - p)``; cells where
    ``mask`` is 0 add nothing; the sum is divided by the number of target cells equal to 1
    (counted by the mask), or by 1 when there is none.

    NOTE: CenterNet's ``_neg_loss`` (src/lib/models/losses.py), with ``log p`` computed as
    ``logsigmoid`` instead of the log of a sigmoid clamped to [1e-4, 1 - 1e-4] (same values
    inside the clamp, no overflow outside)."""
    torch = _torch.torch()
    F = torch.nn.functional
    p = torch.sigmoid(logits)
    m = torch.ones_like(target) if mask is None else mask
    pos = (target == 1).to(logits.dtype) * m
    neg = (target < 1).to(logits.dtype) * m
    pos_loss = (F.logsigmoid(logits) * (1 - p) ** alpha * pos).sum()
    neg_loss = (F.logsigmoid(-logits) * p ** alpha * (1 - target) ** beta * neg).sum()
    return -(pos_loss + neg_loss) / pos.sum().clamp(min=1)


def regression_loss(pred: Any, target: Any, reg_mask: Any) -> Any:
    """L1 between ``pred`` and ``target`` (N x 2 x h x w) at the cells where ``reg_mask``
    (N x h x w) is 1, summed over both channels and divided by the number of those cells (or
    1)."""
    m = reg_mask.unsqueeze(1)
    return ((pred - target).abs() * m).sum() / reg_mask.sum().clamp(min=1)


def loss(outputs: Dict[str, Any], targets: Dict[str, Any], *, size_weight: float = 1.0,
         offset_weight: float = 1.0) -> Tuple[Any, Dict[str, float]]:
    """The training loss of the detector's ``outputs`` (``heat`` logits, ``size``, ``offset``)
    against batched :func:`encode` ``targets`` (tensors with a leading batch dimension): focal
    + ``size_weight`` * L1(size) + ``offset_weight`` * L1(offset). Returns the loss tensor and
    its parts as floats."""
    lh = focal_loss(outputs["heat"], targets["heat"], targets["heat_mask"])
    ls = regression_loss(outputs["size"], targets["size"], targets["reg_mask"])
    lo = regression_loss(outputs["offset"], targets["offset"], targets["reg_mask"])
    total = lh + size_weight * ls + offset_weight * lo
    return total, {"heat": float(lh), "size": float(ls), "offset": float(lo)}


def decode(heat: Any, size: Any, offset: Any, *, k: int = 100, threshold: float = 0.0,
           stride: int = STRIDE) -> list:
    """Boxes from the detector's outputs (``heat`` logits N x C x h x w, ``size`` and ``offset``
    N x 2 x h x w): per image, the ``k`` highest cells of the sigmoid heatmap that are the
    maximum of their 3 x 3 neighbourhood and score above ``threshold``, each a box of centre
    ``((x + offset_x) * stride, (y + offset_y) * stride)`` and size ``exp(size) * stride``.
    Returns per image a tuple of tensors: boxes (K x 4, x0 y0 x1 y1 px), scores (K), classes (K,
    int64), by descending score.

    NOTE: CenterNet's ``_nms`` (3 x 3 max-pool, keep where equal) and ``_topk`` over classes and
    cells together."""
    torch = _torch.torch()
    F = torch.nn.functional
    p = torch.sigmoid(heat)
    peaks = p * (F.max_pool2d(p, 3, stride=1, padding=1) == p).to(p.dtype)
    n, c, h, w = p.shape
    kk = min(k, c * h * w)
    out = []
    for i in range(n):
        scores, idx = torch.topk(peaks[i].reshape(-1), kk)
        keep = scores > threshold
        scores, idx = scores[keep], idx[keep]
        cls = idx // (h * w)
        cell = idx % (h * w)
        ys, xs = cell // w, cell % w
        cx = (xs.to(p.dtype) + offset[i, 0, ys, xs]) * stride
        cy = (ys.to(p.dtype) + offset[i, 1, ys, xs]) * stride
        bw = torch.exp(size[i, 0, ys, xs]) * stride
        bh = torch.exp(size[i, 1, ys, xs]) * stride
        boxes = torch.stack((cx - bw / 2, cy - bh / 2, cx + bw / 2, cy + bh / 2), 1)
        out.append((boxes, scores, cls))
    return out


def box_iou(a: Any, b: Any) -> Any:
    """IoU of every box of ``a`` (N x 4) with every box of ``b`` (M x 4), x0 y0 x1 y1 (areas
    w * h, as :func:`synthgen.evaluate.score.box_iou`)."""
    torch = _torch.torch()
    area_a = (a[:, 2] - a[:, 0]).clamp(min=0) * (a[:, 3] - a[:, 1]).clamp(min=0)
    area_b = (b[:, 2] - b[:, 0]).clamp(min=0) * (b[:, 3] - b[:, 1]).clamp(min=0)
    lt = torch.max(a[:, None, :2], b[None, :, :2])
    rb = torch.min(a[:, None, 2:], b[None, :, 2:])
    wh = (rb - lt).clamp(min=0)
    inter = wh[..., 0] * wh[..., 1]
    union = area_a[:, None] + area_b[None, :] - inter
    return torch.where(union > 0, inter / union.clamp(min=1e-12), torch.zeros_like(inter))


def nms(boxes: Any, scores: Any, classes: Any, iou_threshold: float = 0.5) -> Any:
    """Greedy class-wise non-maximum suppression: the indices (int64, by descending score; equal
    scores keep their input order) of the boxes kept, a box being dropped when its IoU with a
    kept box of its class is above ``iou_threshold``. O(N^2) memory: give it the top-k of
    :func:`decode`, not every cell."""
    torch = _torch.torch()
    if len(boxes) == 0:
        return torch.zeros(0, dtype=torch.int64)
    order = torch.sort(scores, descending=True, stable=True).indices
    b, c = boxes[order], classes[order]
    drop = (box_iou(b, b) > iou_threshold) & (c[:, None] == c[None, :])
    removed = torch.zeros(len(b), dtype=torch.bool)
    keep = []
    for i in range(len(b)):
        if removed[i]:
            continue
        keep.append(i)
        removed |= drop[i]
    return order[torch.tensor(keep, dtype=torch.int64)]
