"""Training the reference detector (:mod:`.detector`) on samples (:class:`.datasets.Sample`:
an image path, boxes, class names, ignore flags) drawn from named pools by a fixed mixing
policy; and running a trained detector over samples (:func:`detect_samples`).

:func:`train` ``(pools, class_names, options)``:

* **Pools and mixing.** ``pools`` maps a name (``"synthetic"``, ``"real"``, ``"negative"``, ...)
  to its samples; ``options.mix`` gives each pool's share of every batch (default: shares
  proportional to the pools' sizes, i.e. every sample equally often). The slots of batch ``t``
  go to the pools by the largest remainder of ``(t + 1) * batch * share`` less the slots given
  so far, so over any run each pool gets its share to within one slot, also when a share is
  below one slot a batch. Each pool is walked in a fresh random order per pass (seeded by
  ``options.seed`` and the pool's name).
* **One sample.** Its image (:func:`.images.read_rgb8`, kept decoded in memory up to
  ``options.cache_bytes``) and boxes go through :func:`.augment.apply` with a generator seeded
  by ``(seed, step, slot)``: the batches depend on the seed alone, not on the number of data
  workers. A box that keeps less than :data:`.augment.MIN_KEPT` of its area inside the crop
  becomes an ignore region of its class; ignore regions stay ignore regions (of their class, or
  of every class when their class is ``""``); :func:`.targets.encode` makes the targets (boxes
  under :data:`.targets.MIN_SIZE` px are ignore regions there).
* **Optimisation.** AdamW (``lr``, ``weight_decay``), a linear warm-up over ``warmup`` steps then
  a cosine decay to zero, the gradient norm clipped at ``clip``; the loss is
  :func:`.targets.loss`. The backbone starts from ImageNet weights (``backbone``, loaded by
  :func:`.backbone.load_pretrained`) or from a given model (fine-tuning); its BatchNorm layers
  keep their ImageNet statistics (``Detector.train``).
* **Determinism.** On the CPU, the same pools, options and seed give bit-identical weights
  (:func:`.detector.deterministic`; any ``workers``). On CUDA the result is close, not
  bit-identical (some of its kernels have no deterministic version).
* **Record.** The returned :class:`TrainResult` holds the model, the loss per step and a
  manifest (options, pools: per pool its sample count, boxes, and a SHA-256 over its image
  paths and labels); the manifest is saved inside the model file (``Detector.save(metadata=)``).

:func:`detect_samples` runs ``Detector.detect`` over samples in batches of equal-sized images
and returns detections keyed like :func:`.datasets.ground_truth` (the image path).
"""
from __future__ import annotations

import hashlib
import math
import os
import sys
import time
from dataclasses import dataclass, field
from typing import Any, Callable, Dict, List, Mapping, Optional, Sequence, Tuple

import numpy as np

from .._core import SynthgenError
from . import _torch
from . import augment as _augment
from . import targets as _targets
from .images import read_rgb8
from .score import Detections

__all__ = ["TrainOptions", "TrainResult", "train", "batch_plan", "detect_samples", "pool_manifest"]


@dataclass
class TrainOptions:
    """Training options (see the module docstring)."""
    steps: int = 2000
    batch: int = 16
    lr: float = 2e-3
    weight_decay: float = 1e-4
    warmup: int = 100
    clip: float = 10.0
    size: Tuple[int, int] = (384, 672)          #: training crops (rows, columns), multiples of 32
    augment: _augment.Augment = field(default_factory=_augment.Augment)
    seed: int = 0
    mix: Optional[Mapping[str, float]] = None   #: pool -> share of each batch (default: by size)
    device: str = "cpu"
    workers: int = 0                            #: data-loading processes (0: in this process)
    cache_bytes: int = 4 << 30                  #: decoded images kept in memory (per process)
    backbone: Optional[str] = None              #: ImageNet weights of the backbone
    threads: int = 0                            #: PyTorch threads on the CPU (0: every CPU usable)

    def describe(self) -> Dict[str, Any]:
        return {"steps": self.steps, "batch": self.batch, "lr": self.lr, "weight_decay": self.weight_decay,
                "warmup": self.warmup, "clip": self.clip, "size": list(self.size), "augment": self.augment.describe(),
                "seed": self.seed, "mix": dict(self.mix) if self.mix else None}


@dataclass
class TrainResult:
    model: Any
    losses: List[Dict[str, float]]
    manifest: Dict[str, Any]
    seconds: float


def _shares(pools: Mapping[str, Sequence[Any]], mix: Optional[Mapping[str, float]]) -> Dict[str, float]:
    names = [n for n in pools]
    if mix is None:
        total = sum(len(pools[n]) for n in names)
        if total == 0:
            raise SynthgenError("train: no samples to train on")
        return {n: len(pools[n]) / total for n in names if len(pools[n])}
    unknown = sorted(set(mix) - set(names))
    if unknown:
        raise SynthgenError(f"train: mix names pool(s) {unknown} that do not exist (pools: {names})")
    bad = {n: w for n, w in mix.items() if not (isinstance(w, (int, float)) and math.isfinite(w) and w >= 0)}
    if bad:
        raise SynthgenError(f"train: mix shares must be finite and >= 0, got {bad}")
    empty = sorted(n for n, w in mix.items() if w > 0 and not len(pools[n]))
    if empty:
        raise SynthgenError(f"train: pool(s) {empty} have a share of each batch but no samples")
    total = float(sum(mix.values()))
    if total <= 0:
        raise SynthgenError("train: the mix gives no pool a share of the batches")
    return {n: float(w) / total for n, w in mix.items() if w > 0}


def batch_plan(pools: Mapping[str, Sequence[Any]], mix: Optional[Mapping[str, float]], batch: int, steps: int,
               seed: int) -> List[List[Tuple[str, int]]]:
    """Per step, the ``batch`` (pool, index) pairs it trains on (see the module docstring)."""
    if batch < 1 or steps < 0:
        raise SynthgenError(f"train: batch {batch} and steps {steps} must be >= 1 and >= 0")
    shares = _shares(pools, mix)
    names = sorted(shares)
    given = {n: 0 for n in names}
    orders: Dict[str, List[int]] = {n: [] for n in names}
    passes = {n: 0 for n in names}
    plan = []
    for t in range(steps):
        want = {n: (t + 1) * batch * shares[n] - given[n] for n in names}
        slots = {n: int(math.floor(want[n])) for n in names}
        left = batch - sum(slots.values())
        # NOTE: largest remainder (Hamilton's method); ties by name, so the plan is reproducible.
        for n in sorted(names, key=lambda n: (-(want[n] - slots[n]), n))[:left]:
            slots[n] += 1
        step = []
        for n in names:
            for _ in range(slots[n]):
                if not orders[n]:
                    digest = hashlib.sha256(f"{seed}/{n}/{passes[n]}".encode()).digest()
                    rng = np.random.default_rng(int.from_bytes(digest[:8], "little"))
                    orders[n] = list(rng.permutation(len(pools[n]))[::-1])
                    passes[n] += 1
                step.append((n, int(orders[n].pop())))
            given[n] += slots[n]
        plan.append(step)
    return plan


def pool_manifest(pools: Mapping[str, Sequence[Any]]) -> Dict[str, Any]:
    """Per pool: samples, boxes, ignore regions, and a SHA-256 over every sample's image path and
    labels (which data a model was trained on)."""
    out = {}
    for name, samples in pools.items():
        h = hashlib.sha256()
        boxes = ignored = 0
        for s in samples:
            ig = np.asarray(s.ignore, bool)
            boxes += int((~ig).sum())
            ignored += int(ig.sum())
            h.update(repr((s.image, np.asarray(s.boxes, np.float64).round(3).tolist(), list(s.classes),
                           ig.tolist())).encode())
        out[name] = {"samples": len(samples), "boxes": boxes, "ignore_regions": ignored, "sha256": h.hexdigest()}
    return out


class _Batches:
    """Batch ``t`` of the plan as tensors (a map-style dataset: one item = one whole batch)."""

    def __init__(self, pools, plan, class_names, options: TrainOptions):
        self.pools, self.plan, self.options = pools, plan, options
        self.index = {c: i for i, c in enumerate(class_names)}
        self.cache: Dict[str, np.ndarray] = {}
        self.cached = 0

    def __len__(self) -> int:
        return len(self.plan)

    def image(self, path: str) -> np.ndarray:
        a = self.cache.get(path)
        if a is None:
            a = read_rgb8(path)
            if self.cached + a.nbytes <= self.options.cache_bytes:
                self.cache[path] = a
                self.cached += a.nbytes
        return a

    def sample(self, s: Any, rng: np.random.Generator) -> Tuple[np.ndarray, Dict[str, np.ndarray]]:
        o = self.options
        img, boxes, kept = _augment.apply(self.image(s.image), s.boxes, o.size, o.augment, rng)
        ig = np.asarray(s.ignore, bool).reshape(-1)
        pos, pos_c, ign, ign_c = [], [], [], []
        for b, c, i, k in zip(boxes, s.classes, ig, kept):
            if k <= 0:
                continue
            ci = -1 if c == "" else self.index.get(c)
            if ci is None:
                raise SynthgenError(f"{s.where or s.image}: class {c!r} is not one the detector learns "
                                    f"({', '.join(self.index)})")
            if i or k < _augment.MIN_KEPT or ci < 0:
                ign.append(b)
                ign_c.append(ci)
            else:
                pos.append(b)
                pos_c.append(ci)
        t = _targets.encode(np.asarray(pos).reshape(-1, 4), pos_c, o.size, len(self.index),
                            ignore=np.asarray(ign).reshape(-1, 4), ignore_classes=ign_c)
        return img, t

    def __getitem__(self, step: int):
        torch = _torch.torch()
        images, tgts = [], []
        for slot, (pool, i) in enumerate(self.plan[step]):
            rng = np.random.default_rng([self.options.seed, step, slot])
            img, t = self.sample(self.pools[pool][i], rng)
            images.append(img)
            tgts.append(t)
        x = torch.from_numpy(np.ascontiguousarray(np.stack(images).transpose(0, 3, 1, 2)))
        y = {k: torch.from_numpy(np.stack([t[k] for t in tgts])) for k in tgts[0]}
        return x, y


def _lr_at(step: int, o: TrainOptions) -> float:
    if step < o.warmup:
        return o.lr * (step + 1) / o.warmup
    span = max(1, o.steps - o.warmup)
    return o.lr * 0.5 * (1 + math.cos(math.pi * min(1.0, (step - o.warmup) / span)))


def train(pools: Mapping[str, Sequence[Any]], class_names: Sequence[str], options: Optional[TrainOptions] = None, *,
          model: Any = None, progress: bool = True, log: Optional[Callable[[str], None]] = None) -> TrainResult:
    """Trains a detector of ``class_names`` (or fine-tunes ``model``) on ``pools``; see the
    module docstring."""
    torch = _torch.torch()
    from .backbone import load_pretrained
    from .detector import Detector, deterministic

    o = options or TrainOptions()
    if o.steps < 1:
        raise SynthgenError(f"train: steps {o.steps} must be >= 1")
    if any(v <= 0 or v % 32 for v in o.size):
        raise SynthgenError(f"train: training size {tuple(o.size)} must be two positive multiples of 32")
    if o.device not in ("cpu", "cuda") and not str(o.device).startswith("cuda:"):
        raise SynthgenError(f"train: device {o.device!r} is not cpu or cuda")
    if str(o.device).startswith("cuda") and not torch.cuda.is_available():
        raise SynthgenError("train: --device cuda asked for, but this PyTorch sees no CUDA device")
    deterministic(o.seed)
    if str(o.device).startswith("cuda"):
        torch.use_deterministic_algorithms(True, warn_only=True)
    if model is None:
        model = Detector(list(class_names), tuple(o.size))
        if o.backbone:
            load_pretrained(o.backbone, model.backbone)
    elif list(model.class_names) != list(class_names):
        raise SynthgenError(f"train: the model detects {model.class_names}, the data has {list(class_names)}")
    plan = batch_plan(pools, o.mix, o.batch, o.steps, o.seed)
    data = _Batches(pools, plan, list(class_names), o)
    manifest = {"options": o.describe(), "pools": pool_manifest(pools), "class_names": list(class_names),
                "backbone": o.backbone or "", "torch": torch.__version__, "device": str(o.device)}
    if o.workers > 0:
        loader = torch.utils.data.DataLoader(data, batch_size=None, shuffle=False, num_workers=o.workers,
                                             persistent_workers=False, prefetch_factor=4)
    else:
        loader = (data[t] for t in range(len(data)))
    model.to(o.device).train()
    threads = torch.get_num_threads()
    if o.device == "cpu":
        # NOTE: PyTorch defaults to one thread per physical core (one on a 2-vCPU machine); with
        # every usable CPU a CPU run trains ~2.7x faster there (300 steps of 8: 272 s against 749 s)
        usable = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)
        torch.set_num_threads(o.threads or usable)
    opt = torch.optim.AdamW(model.parameters(), lr=o.lr, weight_decay=o.weight_decay)
    bar = None
    if progress:
        from tqdm import tqdm
        bar = tqdm(total=o.steps, unit="step", desc="train", dynamic_ncols=True, file=sys.stderr)
    losses: List[Dict[str, float]] = []
    start = time.perf_counter()
    try:
        for step, (x, y) in enumerate(loader):
            for g in opt.param_groups:
                g["lr"] = _lr_at(step, o)
            x = x.to(o.device, non_blocking=True).float().div_(255.0)
            y = {k: v.to(o.device, non_blocking=True) for k, v in y.items()}
            out = model(x)
            total, parts = _targets.loss(out, y)
            if not math.isfinite(float(total)):
                raise SynthgenError(f"train: the loss is {float(total)} at step {step} (learning rate "
                                    f"{o.lr} too high?); nothing saved")
            opt.zero_grad(set_to_none=True)
            total.backward()
            torch.nn.utils.clip_grad_norm_(model.parameters(), o.clip)
            opt.step()
            parts["total"] = float(total)
            losses.append(parts)
            if bar is not None:
                bar.update(1)
                bar.set_postfix(loss=f"{parts['total']:.3f}")
            if log is not None and (step + 1) % max(1, o.steps // 20) == 0:
                log(f"step {step + 1}/{o.steps}: loss {parts['total']:.4f} (heat {parts['heat']:.4f}, "
                    f"size {parts['size']:.4f}, offset {parts['offset']:.4f})")
    finally:
        torch.set_num_threads(threads)
        if bar is not None:
            bar.close()
    seconds = time.perf_counter() - start
    model.to("cpu").eval()
    manifest["seconds"] = round(seconds, 1)
    manifest["final_loss"] = float(np.mean([p["total"] for p in losses[-max(1, len(losses) // 20):]]))
    return TrainResult(model=model, losses=losses, manifest=manifest, seconds=seconds)


def detect_samples(model: Any, samples: Sequence[Any], *, batch: int = 8, device: str = "cpu", threshold: float = 0.01,
                   progress: bool = False) -> Dict[str, Detections]:
    """Detections of ``model`` on every sample's image (key: the image path)."""
    out: Dict[str, Detections] = {}
    paths = list(dict.fromkeys(s.image for s in samples))
    model.to(device)
    bar = None
    if progress:
        from tqdm import tqdm
        bar = tqdm(total=len(paths), unit="image", desc="detect", dynamic_ncols=True, file=sys.stderr)
    try:
        group: List[str] = []
        arrays: List[np.ndarray] = []

        def flush() -> None:
            for p, d in zip(group, model.detect(np.stack(arrays), threshold=threshold, device=device)):
                out[p] = d
            if bar is not None:
                bar.update(len(group))
            group.clear()
            arrays.clear()

        for p in paths:
            a = read_rgb8(p)
            if arrays and (a.shape != arrays[0].shape or len(group) == batch):
                flush()
            group.append(p)
            arrays.append(a)
        if group:
            flush()
    finally:
        if bar is not None:
            bar.close()
        model.to("cpu")
    return out
