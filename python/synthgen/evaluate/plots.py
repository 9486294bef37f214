"""Figures of a scoring: :func:`pr_figure` draws each class's precision-recall curve at IoU 0.5
(the 101-point interpolated precision of :func:`.score.score`, the curve AP50 is the mean of)
with its AP50 and bootstrap interval in the legend, and writes it as a PNG (matplotlib, Agg)."""
from __future__ import annotations

import math
from typing import Optional

import numpy as np

from .score import RECALL_THRESHOLDS, Scores

__all__ = ["pr_figure"]


def pr_figure(scores: Scores, path: str, title: Optional[str] = None, bucket: str = "all") -> str:
    """Writes the precision-recall curves of ``scores`` (one per class, size ``bucket``) to the
    PNG ``path``; returns ``path``."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(5.5, 4.2), dpi=120)
    for r in scores.rows:
        if r.bucket != bucket or r.cls == "all classes" or r.precision is None or math.isnan(r.ap50):
            continue
        p = np.asarray(r.precision[0], float)  # IoU 0.5
        lo, hi = r.ap50_ci
        ci = "" if math.isnan(lo) else f" [{lo:.3f}, {hi:.3f}]"
        ax.step(RECALL_THRESHOLDS, np.where(p < 0, 0, p), where="post",
                label=f"{r.cls}: AP50 {r.ap50:.3f}{ci} ({r.n_gt} boxes)")
    ax.set_xlim(0, 1)
    ax.set_ylim(0, 1.02)
    ax.set_xlabel("recall")
    ax.set_ylabel("precision (interpolated)")
    ax.grid(alpha=0.3)
    ax.set_title(title or f"{scores.n_images} images, IoU 0.5, boxes >= {scores.min_height:g} px tall",
                 fontsize=9)
    ax.legend(fontsize=8, loc="lower left")
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)
    return path
