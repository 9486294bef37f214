"""The reference detector: ShuffleNetV2 0.5x (:mod:`.backbone`), a light neck onto stride 8 and a
CenterNet head, saved to and loaded from one file. (CenterNet: Zhou, Wang and Kraehenbuehl 2019,
"Objects as Points"; targets, losses and decoding in :mod:`.targets`.)

* :class:`Detector` (a ``torch.nn.Module``, built on first use: PyTorch is optional):
  ``Detector(class_names, input_size=(384, 672))``. The neck: 1 x 1 lateral convolutions of the
  stride-8, 16 and 32 maps (48, 96, 192 channels) to :data:`NECK` channels, the stride-16 and 32
  ones upsampled (nearest) onto stride 8 and summed, then a 3 x 3 convolution; each with
  BatchNorm and ReLU. The head: three branches (3 x 3 convolution, ReLU, 1 x 1 convolution) for
  the per-class centre heatmap (logits; bias -2.19, a prior of 0.1, as CenterNet), the box size
  (``log(w / 8)``, ``log(h / 8)``) and the centre's sub-cell offset. ``forward(x)`` takes a
  normalised batch (:func:`.backbone.normalize`, sides multiples of 32) and returns
  ``{"heat", "size", "offset"}`` maps of ``H / 8 x W / 8`` cells.
* ``detect(images, k=100, threshold=0.05, iou_threshold=0.5)``: uint8 RGB images (any size: each
  is padded at the right and bottom to a multiple of 32; peaks in the padding are dropped) -> one
  :class:`synthgen.evaluate.score.Detections` per image, boxes in the image's pixels (clipped to
  it), after class-wise NMS (:func:`.targets.nms`). Runs in eval mode without gradients.
* ``train(mode)`` leaves the backbone's BatchNorm layers in eval mode (their running statistics
  stay the ImageNet ones; their scale and shift still learn) when ``freeze_backbone_bn`` (the
  default): the CPU batches are a few images, too few for batch statistics.
* ``save(path)`` writes one file (``torch.save`` of a dict: ``format`` :data:`FORMAT`,
  ``version`` :data:`VERSION`, ``class_names``, ``input_size``, ``normalization`` (``"rgb01"``:
  RGB values 0..1, :func:`.backbone.normalize`), ``neck_channels``, ``metadata`` (JSON text: how the
  model was made, the training manifest of :func:`.train.train`; ``{}`` if none; read back as
  the dict ``model.metadata``) and the ``state_dict``):
  plain containers, strings, numbers and tensors only, so it loads with
  ``torch.load(weights_only=True)`` (no code in a pickle runs). :meth:`Detector.from_file`
  reads it back; anything else is a :class:`synthgen.SynthgenError` naming the file.
* :func:`deterministic` seeds torch and turns on ``torch.use_deterministic_algorithms``: the
  same seed, data and steps give bit-identical weights on the CPU. (On CUDA it sets
  ``CUBLAS_WORKSPACE_CONFIG``, which cuBLAS needs for it, when unset.)
"""
from __future__ import annotations

import functools
import json
import math
from typing import Any, List, Sequence, Tuple

import numpy as np

from .._core import SynthgenError
from . import _torch
from . import backbone as _backbone
from . import targets as _targets
from .score import Detections

__all__ = ["Detector", "FORMAT", "VERSION", "NECK", "NORMALIZATION", "deterministic"]

#: The ``format`` value of a saved detector.
FORMAT = "synthgen-detector"
#: The file layout's version (:meth:`Detector.from_file` reads this one only).
VERSION = 1
#: The neck's and the head's channels.
NECK = 64
#: The input normalisation the backbone's weights expect (:func:`.backbone.normalize`).
NORMALIZATION = "rgb01"
#: The detector's largest stride: input sides must be multiples of it.
ALIGN = 32
#: The largest model file :meth:`Detector.from_file` reads (the model is about 1 MB).
MAX_FILE_BYTES = 256 << 20
#: The heatmap bias at initialisation: sigmoid(-2.19) = 0.1 (CenterNet).
HEAT_BIAS = -2.19


def deterministic(seed: int) -> None:
    """Seeds torch's generator and makes its algorithms deterministic (CPU training with the
    same seed, data and steps gives bit-identical weights)."""
    import os

    os.environ.setdefault("CUBLAS_WORKSPACE_CONFIG", ":4096:8")
    torch = _torch.torch()
    torch.manual_seed(seed)
    torch.use_deterministic_algorithms(True)


@functools.lru_cache(maxsize=None)
def _detector_class() -> type:
    torch = _torch.torch()
    nn = torch.nn
    F = nn.functional

    def conv_bn(i: int, o: int, k: int) -> Any:
        return nn.Sequential(nn.Conv2d(i, o, k, 1, k // 2, bias=False), nn.BatchNorm2d(o), nn.ReLU(inplace=True))

    def branch(ch: int, out: int, bias: float = 0.0) -> Any:
        last = nn.Conv2d(ch, out, 1)
        nn.init.constant_(last.bias, bias)
        nn.init.normal_(last.weight, std=0.01)
        return nn.Sequential(nn.Conv2d(ch, ch, 3, 1, 1), nn.ReLU(inplace=True), last)

    class Detector(nn.Module):
        """See the module docstring."""

        def __init__(self, class_names: Sequence[str], input_size: Tuple[int, int] = (384, 672), *,
                     neck_channels: int = NECK, freeze_backbone_bn: bool = True):
            super().__init__()
            names = [str(c) for c in class_names]
            if not names or len(set(names)) != len(names) or not all(names):
                raise SynthgenError(f"detector: class names must be distinct non-empty strings, got {names}")
            size = tuple(int(v) for v in input_size)
            if len(size) != 2 or any(v <= 0 or v % ALIGN for v in size):
                raise SynthgenError(f"detector: input size {tuple(input_size)} must be two positive multiples "
                                    f"of {ALIGN} (rows, columns)")
            self.class_names: List[str] = names
            self.input_size: Tuple[int, int] = size
            self.normalization = NORMALIZATION
            self.neck_channels = int(neck_channels)
            self.freeze_backbone_bn = freeze_backbone_bn
            self.metadata: dict = {}
            self.backbone = _backbone.ShuffleNetV2()
            c8, c16, c32 = _backbone.STAGE_WIDTHS[1:]
            ch = self.neck_channels
            self.lat8, self.lat16, self.lat32 = conv_bn(c8, ch, 1), conv_bn(c16, ch, 1), conv_bn(c32, ch, 1)
            self.fuse = conv_bn(ch, ch, 3)
            self.heat = branch(ch, len(names), HEAT_BIAS)
            self.size = branch(ch, 2)
            self.offset = branch(ch, 2)

        def train(self, mode: bool = True):
            super().train(mode)
            if mode and self.freeze_backbone_bn:
                for m in self.backbone.modules():
                    if isinstance(m, nn.BatchNorm2d):
                        m.eval()
            return self

        def forward(self, x):
            if x.shape[-2] % ALIGN or x.shape[-1] % ALIGN:
                raise SynthgenError(f"detector: input of {tuple(x.shape[-2:])} px; sides must be multiples of {ALIGN}")
            f8, f16, f32 = self.backbone(x)
            y = self.lat8(f8)
            y = y + F.interpolate(self.lat16(f16), size=y.shape[-2:], mode="nearest")
            y = y + F.interpolate(self.lat32(f32), size=y.shape[-2:], mode="nearest")
            y = self.fuse(y)
            return {"heat": self.heat(y), "size": self.size(y), "offset": self.offset(y)}

        def detect(self, images: Any, *, k: int = 100, threshold: float = 0.05,
                   iou_threshold: float = 0.5, device: Any = None) -> List[Detections]:
            """Detections of uint8 RGB ``images`` (N x H x W x 3 or H x W x 3): see the module
            docstring. ``device``: where the images go (default: where the model's weights are)."""
            a = np.asarray(images)
            if a.ndim == 3:
                a = a[None]
            x = _backbone.normalize(a)
            H, W = x.shape[-2:]
            ph, pw = -(-H // ALIGN) * ALIGN, -(-W // ALIGN) * ALIGN
            x = F.pad(x, (0, pw - W, 0, ph - H))
            x = x.to(device if device is not None else next(self.parameters()).device)
            was = self.training
            self.eval()
            try:
                with torch.no_grad():
                    out = self(x)
                    decoded = _targets.decode(out["heat"], out["size"], out["offset"], k=k, threshold=threshold)
            finally:
                self.train(was)
            result = []
            for boxes, scores, cls in decoded:
                boxes, scores, cls = boxes.cpu(), scores.cpu(), cls.cpu()
                inside = ((boxes[:, 0] + boxes[:, 2]) / 2 < W) & ((boxes[:, 1] + boxes[:, 3]) / 2 < H)
                boxes, scores, cls = boxes[inside], scores[inside], cls[inside]  # not a centre in the padding
                boxes = torch.stack((boxes[:, 0].clamp(0, W), boxes[:, 1].clamp(0, H),
                                     boxes[:, 2].clamp(0, W), boxes[:, 3].clamp(0, H)), 1)
                keep = _targets.nms(boxes, scores, cls, iou_threshold)
                result.append(Detections(boxes=boxes[keep].double().numpy(), scores=scores[keep].double().numpy(),
                                         classes=[self.class_names[int(c)] for c in cls[keep]]))
            return result

        def save(self, path: str, metadata: Any = None) -> None:
            """Writes the model to ``path`` (one file; see the module docstring), with
            ``metadata`` (plain dicts, lists, strings, numbers: how it was made) when given."""
            state = {k: v.detach().cpu().clone() for k, v in self.state_dict().items()}
            meta = dict(metadata if metadata is not None else self.metadata)
            _check_plain(meta, "metadata")
            # NOTE: JSON text, not a pickled dict: PyTorch 1.13's weights-only unpickler has no
            # float opcode (BINFLOAT), so a float in a pickled dict would make the file unreadable.
            torch.save({"format": FORMAT, "version": VERSION, "class_names": list(self.class_names),
                        "input_size": list(self.input_size), "normalization": self.normalization,
                        "neck_channels": self.neck_channels, "metadata": json.dumps(meta, sort_keys=True),
                        "state_dict": state}, path)

        @classmethod
        def from_file(cls, path: str) -> "Detector":
            """The model saved at ``path`` (in eval mode). SynthgenError naming ``path`` when it
            is missing, too large, not a torch file of plain contents, not a synthgen detector,
            of another version, or its tensors do not fit the model it describes."""
            return _load(cls, path)

    return Detector


def _load(cls: type, path: str) -> Any:
    torch = _torch.torch()
    d = _torch.load_file(path, MAX_FILE_BYTES, "detector model", "model file", "a synthgen detector takes",
                         "a detector model")
    if not isinstance(d, dict) or d.get("format") != FORMAT:
        what = f"a dict with format {d.get('format')!r}" if isinstance(d, dict) else f"a {type(d).__name__}"
        raise SynthgenError(f"{path}: not a synthgen detector model ({what}; expected format {FORMAT!r})")
    if d.get("version") != VERSION:
        raise SynthgenError(f"{path}: detector model version {d.get('version')!r}; this synthgen reads "
                            f"version {VERSION}")
    need = {"class_names": list, "input_size": list, "normalization": str, "neck_channels": int, "state_dict": dict}
    for key, typ in need.items():
        if not isinstance(d.get(key), typ):
            raise SynthgenError(f"{path}: detector model key {key!r} is missing or not a {typ.__name__}")
    if d["normalization"] != NORMALIZATION:
        raise SynthgenError(f"{path}: input normalization {d['normalization']!r}; this synthgen knows {NORMALIZATION!r}")
    try:
        model = cls(d["class_names"], tuple(d["input_size"]), neck_channels=d["neck_channels"])
    except SynthgenError as e:
        raise SynthgenError(f"{path}: {e}") from None
    own = model.state_dict()
    state = d["state_dict"]
    unknown, missing = sorted(set(state) - set(own)), sorted(set(own) - set(state))
    if unknown or missing:
        raise SynthgenError(f"{path}: the model's tensors do not match the detector: {len(unknown)} unknown "
                            f"{unknown[:4]}, {len(missing)} missing {missing[:4]}")
    for k, t in state.items():
        if not isinstance(t, torch.Tensor) or tuple(t.shape) != tuple(own[k].shape):
            shape = tuple(t.shape) if isinstance(t, torch.Tensor) else type(t).__name__
            raise SynthgenError(f"{path}: tensor {k} is {shape}, the detector needs {tuple(own[k].shape)}")
    model.load_state_dict(state, strict=True)
    try:
        meta = json.loads(d.get("metadata", "{}"))
    except (TypeError, ValueError) as e:
        raise SynthgenError(f"{path}: the model's metadata is not JSON text ({e})") from None
    model.metadata = meta if isinstance(meta, dict) else {}
    return model.eval()


def _check_plain(x: Any, where: str) -> None:
    """Metadata must load with ``weights_only=True``: plain containers, strings, numbers."""
    if isinstance(x, dict):
        for k, v in x.items():
            if not isinstance(k, str):
                raise SynthgenError(f"detector: {where} key {k!r} is not a string")
            _check_plain(v, f"{where}.{k}")
    elif isinstance(x, (list, tuple)):
        for i, v in enumerate(x):
            _check_plain(v, f"{where}[{i}]")
    elif isinstance(x, float) and not math.isfinite(x):
        raise SynthgenError(f"detector: {where} is {x}; metadata numbers must be finite (JSON)")
    elif not (x is None or isinstance(x, (str, int, float, bool))):
        raise SynthgenError(f"detector: {where} is a {type(x).__name__}; metadata holds plain values only")


def __getattr__(name: str) -> Any:
    """``Detector`` is defined when first asked for (PEP 562)."""
    if name == "Detector":
        return _detector_class()
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
