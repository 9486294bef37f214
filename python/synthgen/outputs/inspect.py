"""Looking at a dataset (``synthgen inspect DIR``): a contact sheet of frames with every
labelled object's box, class and instance id drawn over the image, and the statistics a
user checks first -- objects per class, box sizes (the scale coverage a detector sees),
occlusion and truncation, objects per frame -- as numbers and plots (matplotlib, Agg).
"""
from __future__ import annotations

import os
from typing import Any, Dict, List, Optional, Sequence

import numpy as np

from .read import Dataset

__all__ = ["statistics", "format_statistics", "contact_sheet", "plot_statistics", "inspect"]


def statistics(ds: Dataset, frames: Optional[Sequence[int]] = None) -> Dict[str, Any]:
    """Counts and distributions over the labelled, visible objects of ``frames`` (default:
    all), from the frames' metadata: the inserted (rendered) objects and a photo's labelled
    real ones (``source: real`` in COCO) alike, as ``synthgen verify`` counts them (``objects``
    = ``inserted`` + ``real``); occlusion and truncation are the inserted objects'."""
    frames = list(ds.frames if frames is None else frames)
    names = ds.class_names
    per_class = {n: 0 for n in names}
    heights: List[float] = []
    widths: List[float] = []
    classes: List[int] = []
    occlusion: List[float] = []
    truncation: List[float] = []
    per_frame: List[int] = []
    dropped = negatives = inserted = real = 0
    for k in frames:
        meta = ds.meta(k)
        objs = [o for o in meta.get("objects", []) if o.get("label", True) and not o.get("dropped")
                and o.get("visible_pixels")]
        reals = [o for o in meta.get("real_objects", []) if not o["ignore"]]
        dropped += sum(1 for o in meta.get("objects", []) if o.get("dropped"))
        negatives += bool(meta.get("negative"))
        per_frame.append(len(objs) + len(reals))
        inserted += len(objs)
        real += len(reals)
        for o in objs:
            per_class[o["class"]] = per_class.get(o["class"], 0) + 1
            widths.append(float(o["bbox"][2]))
            heights.append(float(o["bbox"][3]))
            classes.append(int(o["class_id"]))
            occlusion.append(float(o["occlusion"]))
            truncation.append(float(o["truncation"]))
        for o in reals:  # bbox [x0, y0, x1, y1]
            per_class[o["class"]] = per_class.get(o["class"], 0) + 1
            widths.append(float(o["bbox"][2] - o["bbox"][0]))
            heights.append(float(o["bbox"][3] - o["bbox"][1]))
            classes.append(int(o["class_id"]))
    return {"frames": len(frames), "objects": len(heights), "inserted": inserted, "real": real,
            "per_class": per_class, "box_heights": heights,
            "box_widths": widths, "classes": classes, "occlusion": occlusion, "truncation": truncation,
            "objects_per_frame": per_frame, "dropped": dropped, "negative_frames": negatives,
            "empty_frames": sum(1 for n in per_frame if n == 0), "class_names": list(names)}


def format_statistics(st: Dict[str, Any]) -> str:
    """A plain-text summary of :func:`statistics`."""
    lines = [f"{st['frames']} frames, {st['objects']} labelled visible objects "
             f"({st['inserted']} inserted, {st['real']} real; {st['empty_frames']} frames without any, "
             f"{st['negative_frames']} of them negatives; {st['dropped']} objects dropped by placement)"]
    lines.append("objects per class: " + ", ".join(f"{n} {c}" for n, c in st["per_class"].items()))
    if st["objects"]:
        h = np.array(st["box_heights"])
        q = np.percentile(h, [0, 10, 50, 90, 100])
        lines.append("box height, pixels: min {:.0f}, 10% {:.0f}, median {:.0f}, 90% {:.0f}, max {:.0f}".format(*q))
    if st["occlusion"]:
        occ, tr = np.array(st["occlusion"]), np.array(st["truncation"])
        lines.append(f"occlusion (inserted objects): mean {occ.mean():.2f}, {np.mean(occ > 0.5) * 100:.0f}% more "
                     f"than half hidden; truncation: mean {tr.mean():.2f}, {np.mean(tr > 0) * 100:.0f}% cut by the "
                     "image border")
    if st["objects"]:
        pf = np.array(st["objects_per_frame"])
        lines.append(f"objects per frame: mean {pf.mean():.1f}, max {pf.max()}")
    return "\n".join(lines)


def _colour(class_id: int) -> Any:
    import matplotlib

    return matplotlib.colormaps["tab10"]((class_id - 1) % 10)


def contact_sheet(ds: Dataset, path: str, frames: Sequence[int], columns: int = 4, tile_width: float = 4.0) -> str:
    """A PNG of ``frames`` in a grid, each with its objects' boxes (colour per class), class
    names and instance ids, and its frame index; returns ``path``."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.patches import Rectangle

    frames = list(frames)
    cols = max(1, min(columns, len(frames)))
    rows = max(1, (len(frames) + cols - 1) // cols)
    w, h = (ds.meta(frames[0])["image_size"] if frames else (4, 3))
    tile_h = tile_width * h / w
    fig, axes = plt.subplots(rows, cols, figsize=(cols * tile_width, rows * (tile_h + 0.3)), squeeze=False)
    for ax in axes.ravel():
        ax.axis("off")
    for ax, k in zip(axes.ravel(), frames):
        f = ds.frame(k)
        ax.imshow(f.image, interpolation="nearest")
        for o in f.objects:
            x, y, bw, bh = o["bbox"]
            c = _colour(o["class_id"])
            ax.add_patch(Rectangle((x - 0.5, y - 0.5), bw, bh, fill=False, edgecolor=c, linewidth=1.2))
            ax.text(x - 0.5, y - 1.0, f"{o['class']} #{o['instance_id']}", color="white", fontsize=6,
                    va="bottom", bbox={"facecolor": c, "edgecolor": "none", "pad": 0.5, "alpha": 0.85})
        # A photo's real objects (dashed, their class) and ignore regions (grey, dotted).
        for o in f.real_objects:
            x0, y0, x1, y1 = o["bbox"]
            c = _colour(o["class_id"])
            ax.add_patch(Rectangle((x0, y0), x1 - x0, y1 - y0, fill=False, edgecolor=c, linewidth=1.0, linestyle="--"))
            ax.text(x0, y0 - 1.0, f"{o['class']} (real)", color="white", fontsize=5, va="bottom",
                    bbox={"facecolor": c, "edgecolor": "none", "pad": 0.4, "alpha": 0.6})
        for o in f.ignore_regions:
            x0, y0, x1, y1 = o["bbox"]
            ax.add_patch(Rectangle((x0, y0), x1 - x0, y1 - y0, fill=True, facecolor=(0.5, 0.5, 0.5, 0.25),
                                   edgecolor=(0.6, 0.6, 0.6), linewidth=0.8, linestyle=":"))
        tag = " (negative)" if f.meta.get("negative") else ""
        n, r = len(f.objects), len(f.real_objects)
        real = f" ({n} inserted, {r} real)" if r else ""
        ax.set_title(f"frame {k}: {n + r} objects{real}{tag}", fontsize=8)
    fig.tight_layout()
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def plot_statistics(st: Dict[str, Any], path: str) -> str:
    """A PNG of four plots: objects per class, box heights (log scale), occlusion and
    truncation, objects per frame; returns ``path``."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import matplotlib.ticker  # noqa: F401

    fig, ax = plt.subplots(2, 2, figsize=(10, 7))
    names = list(st["per_class"])
    ax[0, 0].bar(range(len(names)), [st["per_class"][n] for n in names],
                 color=[_colour(i + 1) for i in range(len(names))])
    ax[0, 0].set_xticks(range(len(names)), names, rotation=30, ha="right", fontsize=8)
    ax[0, 0].set_title("labelled visible objects per class")
    h = np.array(st["box_heights"]) if st["box_heights"] else np.array([1.0])
    bins = np.geomspace(max(1.0, h.min()), max(2.0, h.max()), 25)
    classes = np.array(st["classes"]) if st["classes"] else np.array([1])
    for i, n in enumerate(names):
        sel = h[classes == i + 1] if st["box_heights"] else np.array([])
        if sel.size:
            ax[0, 1].hist(sel, bins=bins, histtype="step", color=_colour(i + 1), label=n, linewidth=1.5)
    ax[0, 1].set_xscale("log")
    ax[0, 1].xaxis.set_major_formatter(matplotlib.ticker.ScalarFormatter())
    ax[0, 1].set_xlabel("box height, pixels")
    ax[0, 1].set_title("box heights (scale coverage)")
    if names:
        ax[0, 1].legend(fontsize=7)
    ax[1, 0].hist([st["occlusion"], st["truncation"]], bins=np.linspace(0, 1, 21), label=["occlusion", "truncation"])
    ax[1, 0].set_xlabel("fraction of the object hidden")
    ax[1, 0].set_title("occlusion and truncation")
    ax[1, 0].legend(fontsize=7)
    pf = st["objects_per_frame"] or [0]
    ax[1, 1].hist(pf, bins=np.arange(0, max(pf) + 2) - 0.5)
    ax[1, 1].set_xlabel("labelled visible objects")
    ax[1, 1].set_title(f"objects per frame ({st['frames']} frames)")
    fig.tight_layout()
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return path


def inspect(root: str, out_dir: Optional[str] = None, count: int = 16, split: Optional[str] = None,
            columns: int = 4) -> Dict[str, Any]:
    """Writes ``contact_sheet.png`` (the first ``count`` frames) and ``statistics.png`` into
    ``out_dir`` (default: ``root/inspect``); returns the statistics and the paths."""
    from .read import read_dataset

    ds = read_dataset(root)
    frames = ds.frames if split is None else ds.splits[split]
    out_dir = out_dir or os.path.join(ds.root, "inspect")
    st = statistics(ds, frames)
    st["contact_sheet"] = contact_sheet(ds, os.path.join(out_dir, "contact_sheet.png"), frames[:count], columns)
    st["plots"] = plot_statistics(st, os.path.join(out_dir, "statistics.png"))
    return st
