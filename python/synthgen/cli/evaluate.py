"""``synthgen evaluate train|score|detect``: train the reference detector on synthgen datasets
(and real label sets), score a detector on real labelled photos, run one over a folder of images
(docs/evaluate.md). PyTorch is needed for train and detect, and for score with a model (scoring
a detections file needs numpy only)."""
from __future__ import annotations

import argparse
import json
import os
import sys
from typing import Dict, List, Optional

from .._core import SynthgenError
from . import Command, register
from .common import nonnegative_float, nonnegative_int, positive_int


def _names(text: str) -> List[str]:
    names = [t.strip() for t in text.split(",") if t.strip()]
    if not names:
        raise argparse.ArgumentTypeError(f"expected class names separated by commas, got {text!r}")
    return names


def _pair(text: str) -> tuple:
    if "=" not in text:
        raise argparse.ArgumentTypeError(f"expected FILE_CLASS=CLASS, got {text!r}")
    a, b = text.split("=", 1)
    return a.strip(), (b.strip() or None)


def _share(text: str) -> tuple:
    if "=" not in text:
        raise argparse.ArgumentTypeError(f"expected POOL=SHARE (synthetic, real or negative), got {text!r}")
    a, b = text.split("=", 1)
    try:
        return a.strip(), float(b)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r}: the share is not a number") from None


def _size(text: str) -> tuple:
    try:
        rows, cols = (int(v) for v in text.lower().split("x"))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected ROWSxCOLUMNS (e.g. 384x672), got {text!r}") from None
    if rows <= 0 or cols <= 0 or rows % 32 or cols % 32:
        raise argparse.ArgumentTypeError(f"{text}: rows and columns must be positive multiples of 32")
    return rows, cols


def _range(text: str) -> tuple:
    try:
        lo, hi = (float(v) for v in text.split(","))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected LOW,HIGH, got {text!r}") from None
    return lo, hi


def _label_options(p: argparse.ArgumentParser, required: bool) -> None:
    p.add_argument("--real", action="append", default=[], metavar="LABELS", required=required,
                   help="a real labelled set: a COCO/CSV file, or a folder of images with a label file each "
                        "(KITTI, YOLO, VOC, labelme, OpenALPR); repeatable")
    p.add_argument("--real-format", default=None, metavar="FMT",
                   help="the label format of every --real (default: detected)")
    p.add_argument("--images", default=None, metavar="DIR", help="where --real's images are (default: found "
                   "beside the labels)")
    p.add_argument("--negatives", action="append", default=[], metavar="DIR",
                   help="a folder (or glob) of images showing none of the classes; repeatable")
    p.add_argument("--classes", type=_names, default=None, metavar="A,B",
                   help="the classes (default: train: every class in the data; score: the model's)")
    p.add_argument("--map", action="append", type=_pair, default=[], metavar="FILE_CLASS=CLASS",
                   help="rename a class of the label files (e.g. Car=car, Van=car; Truck= drops it); repeatable")
    p.add_argument("--default-class", default=None, metavar="NAME", help="the class of a CSV file's rows "
                   "when it has no class column")
    p.add_argument("--device", default="cpu", help="cpu or cuda (default cpu)")
    p.add_argument("--no-progress", action="store_true", help="no progress bars")


def _read_real(args: argparse.Namespace, classes: Optional[List[str]]) -> list:
    from ..evaluate import datasets

    out = []
    mapping: Dict[str, Optional[str]] = dict(args.map) or None
    for path in args.real:
        s = datasets.read_real(path, args.real_format, images=args.images, classes=classes, mapping=mapping,
                               default_class=args.default_class)
        print(s.summary(), file=sys.stderr)
        out.extend(s)
    for path in args.negatives:
        s = datasets.read_negatives(path)
        print(s.summary(), file=sys.stderr)
        out.extend(s)
    return out


def _train(args: argparse.Namespace) -> int:
    from ..evaluate import augment, datasets
    from ..evaluate import train as tr

    if not args.datasets and not args.real:
        raise SynthgenError("evaluate train: nothing to train on: give synthgen datasets and/or --real label sets")
    if args.backbone is None and args.init is None:
        raise SynthgenError("evaluate train: give --backbone FILE (ImageNet weights of the ShuffleNetV2 0.5x "
                            "backbone, docs/evaluate.md), --init MODEL (fine-tune a model), or --backbone none "
                            "(train from random weights: far worse)")
    mapping: Dict[str, Optional[str]] = dict(args.map) or None
    pools: Dict[str, list] = {"synthetic": [], "real": [], "negative": []}
    for path in args.datasets:
        s = datasets.read_synthgen(path, classes=args.classes, mapping=mapping, max_occlusion=args.max_occlusion)
        print(s.summary(), file=sys.stderr)
        pools["synthetic"].extend(s)
    for smp in _read_real(args, args.classes):
        pools["negative" if smp.source == "negative" else "real"].append(smp)
    pools = {k: v for k, v in pools.items() if v}
    model = None
    if args.init:
        from ..evaluate.detector import Detector

        model = Detector.from_file(args.init)
        classes = list(model.class_names)
    else:
        classes = args.classes or datasets.class_names([s for v in pools.values() for s in v])
    if not classes:
        raise SynthgenError("evaluate train: the data has no labelled box of any class")
    aug = augment.Augment.none() if args.no_augment else augment.Augment(
        scale=args.scale, flip=args.flip, brightness=args.jitter, contrast=args.jitter, saturation=args.jitter)
    o = tr.TrainOptions(steps=args.steps, batch=args.batch, lr=args.lr, warmup=min(args.warmup, args.steps),
                        size=args.size, augment=aug, seed=args.seed, mix=dict(args.mix) or None, device=args.device,
                        workers=args.workers,
                        backbone=None if (args.backbone in (None, "none") or args.init) else args.backbone)
    print(f"training a detector of {', '.join(classes)}: {args.steps} steps of {args.batch} images "
          f"({', '.join(f'{k} {len(v)}' for k, v in pools.items())} images), seed {args.seed}, on {args.device}",
          file=sys.stderr)
    res = tr.train(pools, classes, o, model=model, progress=not args.no_progress)
    res.manifest["arguments"] = {k: (list(v) if isinstance(v, tuple) else v) for k, v in vars(args).items()
                                 if k not in ("func", "command", "evaluate_command", "debug", "no_progress")}
    out_dir = os.path.dirname(os.path.abspath(args.output))
    os.makedirs(out_dir, exist_ok=True)
    tmp = args.output + ".part"
    res.model.save(tmp, metadata=res.manifest)
    os.replace(tmp, args.output)
    print(f"{args.output}: {', '.join(classes)} detector, {res.seconds:.0f} s, final loss "
          f"{res.manifest['final_loss']:.4f}")
    return 0


def _score(args: argparse.Namespace) -> int:
    from ..evaluate import datasets
    from ..evaluate.plots import pr_figure
    from ..evaluate.score import format_table, read_detect_records, score

    model = None
    if args.model.endswith(".json"):
        classes = args.classes
        found = read_detect_records(args.model)
    else:
        from ..evaluate.detector import Detector

        model = Detector.from_file(args.model)
        classes = args.classes or list(model.class_names)
    samples = _read_real(args, classes)
    if not samples:
        raise SynthgenError("evaluate score: no images to score on (give --real and/or --negatives)")
    gt = datasets.ground_truth(samples)
    if model is not None:
        from ..evaluate.train import detect_samples

        dets = detect_samples(model, samples, device=args.device, threshold=args.threshold,
                              progress=not args.no_progress)
    else:
        by_name: Dict[str, str] = {}
        for k in gt:
            by_name.setdefault(os.path.basename(k), k)
        dets = {}
        for name, d in found.items():
            key = next((k for k in gt if k.replace(os.sep, "/").endswith("/" + name)), None) or by_name.get(
                os.path.basename(name))
            if key is None:
                raise SynthgenError(f"{args.model}: detections of {name}, which is not among the scored images")
            dets[key] = d
        if len(dets) < len(gt):
            print(f"synthgen: warning: {args.model} has detections of {len(dets)} of the {len(gt)} images scored; "
                  "the others count as images where the detector found nothing", file=sys.stderr)
    sc = score(gt, dets, classes=classes, min_height=args.min_height, bootstrap=args.bootstrap, seed=args.seed)
    print(format_table(sc))
    stem = os.path.splitext(os.path.basename(args.model))[0]
    pr = args.pr or f"{stem}_pr.png"
    pr_figure(sc, pr, title=f"{os.path.basename(args.model)} on {', '.join(os.path.basename(p.rstrip('/')) for p in args.real + args.negatives)}")
    print(f"precision-recall curves: {pr}")
    if args.json:
        rows = [{"class": r.cls, "size": r.bucket, "gt": r.n_gt, "ignored": r.n_ignored, "detections": r.n_det,
                 "ap50": r.ap50, "ap50_ci": list(r.ap50_ci), "ap50_95": r.ap, "ap50_95_ci": list(r.ap_ci),
                 "recall_at_fppi": r.recall_at_fppi} for r in sc.rows]
        with open(args.json, "w", encoding="utf-8") as f:
            json.dump({"images": sc.n_images, "min_height": sc.min_height, "fppi": sc.fppi, "bootstrap": sc.bootstrap,
                       "rows": rows}, f, indent=1)
    return 0


def _detect(args: argparse.Namespace) -> int:
    import numpy as np

    from ..background.photos import expand_photos
    from ..evaluate import datasets
    from ..evaluate.detector import Detector
    from ..evaluate.score import coco_results, detect_records
    from ..evaluate.train import detect_samples

    model = Detector.from_file(args.model)
    root = args.images if os.path.isdir(args.images) else os.path.dirname(args.images.split("*")[0]) or "."
    files = expand_photos([args.images], os.getcwd())
    samples = [datasets.Sample(os.path.abspath(f), np.zeros((0, 4)), [], np.zeros(0, bool), "negative", None, f)
               for f in files]
    dets = detect_samples(model, samples, device=args.device, threshold=args.threshold,
                          progress=not args.no_progress)
    if args.coco:
        ids = {s.image: i + 1 for i, s in enumerate(samples)}
        records = coco_results(dets, ids, {c: i + 1 for i, c in enumerate(model.class_names)})
    else:
        records = detect_records(dets, root)
    tmp = args.output + ".part"
    with open(tmp, "w", encoding="utf-8") as f:
        json.dump(records, f)
    os.replace(tmp, args.output)
    print(f"{args.output}: {len(records)} detections in {len(files)} images (score >= {args.threshold:g})")
    return 0


def add_arguments(p: argparse.ArgumentParser) -> None:
    sub = p.add_subparsers(dest="evaluate_command", metavar="ACTION", required=True)
    t = sub.add_parser("train", help="train the reference detector on synthgen datasets (and real label sets)",
                       description="Train the reference detector (ShuffleNetV2 0.5x + CenterNet head at stride 8) "
                                   "on synthgen datasets and/or real label sets; writes one model file.")
    t.add_argument("datasets", nargs="*", metavar="DATASET", help="synthgen dataset folders (or COCO / split files)")
    _label_options(t, required=False)
    t.add_argument("-o", "--output", required=True, metavar="MODEL", help="the model file to write")
    t.add_argument("--backbone", default=None, metavar="FILE",
                   help="ImageNet weights of the ShuffleNetV2 0.5x backbone (FastestDet's key names), or none")
    t.add_argument("--init", default=None, metavar="MODEL", help="fine-tune this model instead")
    t.add_argument("--steps", type=positive_int, default=2000)
    t.add_argument("--batch", type=positive_int, default=16)
    t.add_argument("--lr", type=nonnegative_float, default=2e-3, help="AdamW learning rate (default 2e-3)")
    t.add_argument("--warmup", type=nonnegative_int, default=100, help="warm-up steps (default 100)")
    t.add_argument("--size", type=_size, default=(384, 672), metavar="ROWSxCOLS",
                   help="training crops (default 384x672; multiples of 32)")
    t.add_argument("--mix", action="append", type=_share, default=[], metavar="POOL=SHARE",
                   help="share of each batch from a pool (synthetic, real, negative); default: by pool size")
    t.add_argument("--max-occlusion", type=nonnegative_float, default=0.7,
                   help="synthetic objects hidden more than this are ignore regions (default 0.7)")
    t.add_argument("--no-augment", action="store_true", help="no augmentation")
    t.add_argument("--scale", type=_range, default=(0.75, 1.33), metavar="LOW,HIGH", help="scale range")
    t.add_argument("--flip", type=nonnegative_float, default=0.5, help="horizontal flip probability")
    t.add_argument("--jitter", type=nonnegative_float, default=0.25, help="brightness/contrast/saturation jitter")
    t.add_argument("--seed", type=nonnegative_int, default=0)
    t.add_argument("--workers", type=nonnegative_int, default=0, help="data-loading processes (default 0)")
    t.set_defaults(func=_train)

    s = sub.add_parser("score", help="score a detector on real labelled photos (table + precision-recall PNG)",
                       description="Score a model (or a detections JSON of `synthgen evaluate detect`) on real "
                                   "labelled photos the COCO way: AP50, AP50:95, recall at 0.1 false positives "
                                   "per image, per class and box height, with bootstrap 95%% intervals.")
    s.add_argument("model", metavar="MODEL", help="a model file, or a detections JSON")
    _label_options(s, required=False)
    s.add_argument("--threshold", type=nonnegative_float, default=0.01, help="lowest score kept (default 0.01)")
    s.add_argument("--min-height", type=nonnegative_float, default=20.0,
                   help="boxes lower than this (px) are neither hit nor miss (default 20)")
    s.add_argument("--bootstrap", type=nonnegative_int, default=1000)
    s.add_argument("--seed", type=nonnegative_int, default=0, help="the bootstrap's seed")
    s.add_argument("--pr", default=None, metavar="PNG", help="precision-recall figure (default MODEL_pr.png here)")
    s.add_argument("--json", default=None, metavar="FILE", help="also write the scores as JSON")
    s.set_defaults(func=_score)

    d = sub.add_parser("detect", help="run a detector over images; detections as JSON",
                       description="Run a model over a folder (or glob) of images; writes records with file_name "
                                   "(relative to IMAGES), bbox [x, y, w, h] px, score and category, or COCO results.")
    d.add_argument("model", metavar="MODEL")
    d.add_argument("images", metavar="IMAGES", help="a folder or a glob of images")
    d.add_argument("-o", "--output", required=True, metavar="JSON")
    d.add_argument("--threshold", type=nonnegative_float, default=0.05, help="lowest score kept (default 0.05)")
    d.add_argument("--coco", action="store_true", help="COCO results (image_id = position in the sorted list)")
    d.add_argument("--device", default="cpu")
    d.add_argument("--no-progress", action="store_true")
    d.set_defaults(func=_detect)


register(Command("evaluate", "train a detector on synthgen data and score it on real photos",
                 "Does the data work: train the reference detector on synthgen datasets, score it (or any "
                 "detector's output) on real labelled photos, run it over images (docs/evaluate.md).",
                 add_arguments, None, order=55, module=__name__))
