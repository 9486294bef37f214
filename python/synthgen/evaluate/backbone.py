"""The reference detector's backbone: ShuffleNetV2 0.5x in Megvii's block layout, its
ImageNet-pretrained weights loaded by an explicit key table, and the input normalisation they
were trained with.

* :class:`ShuffleNetV2` (a ``torch.nn.Module``; built on first use, PyTorch being optional):
  a 3x3 stride-2 stem convolution and a 3x3 stride-2 max-pool, then three stages of
  :class:`ShuffleBlock` (4, 8 and 4 blocks; widths 48, 96, 192). ``forward(x)`` takes a
  normalised ``N x 3 x H x W`` batch (:func:`normalize`) and returns the feature maps of stride
  8, 16 and 32 (``C8 = 48``, ``C16 = 96``, ``C32 = 192`` channels; ``ceil(H / s)`` rows: 48 x 84,
  24 x 42 and 12 x 21 for a 384 x 672 input). No conv5, no classifier.
* :class:`ShuffleBlock` is Megvii's: a stride-1 block splits its input into the **even and odd
  channels** (the even ones pass through, the odd ones go through the main branch: 1x1, 3x3
  depthwise, 1x1) and concatenates ``[passed, main]`` without shuffling after; a stride-2 block
  concatenates ``[projection branch, main branch]`` of its whole input. The shuffle thus
  happens at the next block's split. torchvision's ``shufflenet_v2_x0_5`` has tensors of the
  same shapes but chunks the input into halves and shuffles after the concatenation: the
  pretrained weights load into it by shape and compute different features (the BatchNorm test
  of ``tests/python/test_evaluate_backbone.py`` tells the two apart on real photos).
* :func:`load_pretrained` reads a state_dict with the FastestDet project's key names
  (``first_conv.0.weight``, ``stage2.0.branch_main.3.weight``, ``stage3.1.branch_proj...``) and
  maps each key onto the module through :func:`key_table`: every tensor of the file is used
  exactly once, every tensor of the module is set; an unknown or missing key, a wrong shape or a
  file that is no state_dict is a :class:`synthgen.SynthgenError` naming the file and the keys.
* :func:`normalize`: the weights' input convention, 8-bit sRGB photos as **RGB values 0..1**
  (the bytes divided by 255; no mean, no std). Measured, not assumed: with it the batch
  statistics of the BatchNorm layers' inputs on real highway photos match the stored running
  means and variances (the stem's means correlate 0.988 across channels, the mean variance is
  0.78 of the stored one); BGR order correlates less (0.931), bytes 0..255 give 5e4 times the
  stored variance and ImageNet's mean/std a negative correlation (-0.69) (docs/evaluate.md,
  "Backbone").

Same weights and input give bit-identical features on the CPU.
"""
from __future__ import annotations

import functools
from typing import Any, Dict, List, Tuple

import numpy as np

from .._core import SynthgenError
from . import _torch

__all__ = ["ShuffleNetV2", "ShuffleBlock", "STAGE_REPEATS", "STAGE_WIDTHS", "STRIDES", "key_table",
           "load_pretrained", "normalize"]

#: Blocks per stage (stage2, stage3, stage4).
STAGE_REPEATS: Tuple[int, ...] = (4, 8, 4)
#: Output channels of the stem and of each stage (0.5x).
STAGE_WIDTHS: Tuple[int, ...] = (24, 48, 96, 192)
#: The strides of the three feature maps ``forward`` returns.
STRIDES: Tuple[int, ...] = (8, 16, 32)

#: The largest weights file :func:`load_pretrained` reads (the 0.5x file is about 0.7 MB).
MAX_FILE_BYTES = 64 << 20

# The layers of a block: (the file's name inside the block, the module's attribute).
_MAIN = (("branch_main.0", "main_conv1"), ("branch_main.1", "main_bn1"),
         ("branch_main.3", "main_dwconv"), ("branch_main.4", "main_bn2"),
         ("branch_main.5", "main_conv2"), ("branch_main.6", "main_bn3"))
_PROJ = (("branch_proj.0", "proj_dwconv"), ("branch_proj.1", "proj_bn1"),
         ("branch_proj.2", "proj_conv"), ("branch_proj.3", "proj_bn2"))
_STEM = (("first_conv.0", "stem_conv"), ("first_conv.1", "stem_bn"))
_CONV_TENSORS = ("weight",)
_BN_TENSORS = ("weight", "bias", "running_mean", "running_var", "num_batches_tracked")


def key_table() -> Dict[str, str]:
    """The file's key -> the module's key, for every tensor of ShuffleNetV2 0.5x (330 rows):
    ``first_conv.{0,1}`` is the stem's convolution and BatchNorm, ``stageS.B.branch_main.{0,1,
    3,4,5,6}`` block B's main branch (1x1, BN, depthwise 3x3, BN, 1x1, BN; 2 and 7 are ReLUs),
    ``stageS.B.branch_proj.{0,1,2,3}`` a stride-2 block's projection (depthwise 3x3, BN, 1x1,
    BN). A one-to-one table: no two file keys name one module tensor."""
    rows: List[Tuple[str, str]] = []

    def layer(src: str, dst: str) -> None:
        names = _BN_TENSORS if "_bn" in dst else _CONV_TENSORS
        rows.extend((f"{src}.{t}", f"{dst}.{t}") for t in names)

    for src, dst in _STEM:
        layer(src, dst)
    for s, repeats in enumerate(STAGE_REPEATS):
        for b in range(repeats):
            src, dst = f"stage{s + 2}.{b}", f"stage{s + 2}.{b}"
            for a, m in _MAIN + (_PROJ if b == 0 else ()):
                layer(f"{src}.{a}", f"{dst}.{m}")
    table = dict(rows)
    assert len(table) == len(rows) and len(set(table.values())) == len(table), "key table is not one-to-one"
    return table


@functools.lru_cache(maxsize=None)
def _classes() -> Tuple[type, type]:
    """The module classes, defined on first use (PyTorch is optional)."""
    torch = _torch.torch()
    nn = torch.nn

    class ShuffleBlock(nn.Module):
        """One ShuffleNetV2 unit in Megvii's layout (see the module docstring): ``inp``
        channels in, ``out`` out; stride 2 halves the size and has a projection branch."""

        def __init__(self, inp: int, out: int, stride: int):
            super().__init__()
            assert stride in (1, 2)
            self.stride = stride
            mid = out // 2
            side = inp if stride == 2 else inp // 2  # channels into the main branch
            self.main_conv1 = nn.Conv2d(side, mid, 1, 1, 0, bias=False)
            self.main_bn1 = nn.BatchNorm2d(mid)
            self.main_dwconv = nn.Conv2d(mid, mid, 3, stride, 1, groups=mid, bias=False)
            self.main_bn2 = nn.BatchNorm2d(mid)
            self.main_conv2 = nn.Conv2d(mid, out - side, 1, 1, 0, bias=False)
            self.main_bn3 = nn.BatchNorm2d(out - side)
            if stride == 2:
                self.proj_dwconv = nn.Conv2d(inp, inp, 3, stride, 1, groups=inp, bias=False)
                self.proj_bn1 = nn.BatchNorm2d(inp)
                self.proj_conv = nn.Conv2d(inp, inp, 1, 1, 0, bias=False)
                self.proj_bn2 = nn.BatchNorm2d(inp)

        def main(self, x):
            x = torch.relu(self.main_bn1(self.main_conv1(x)))
            x = self.main_bn2(self.main_dwconv(x))
            return torch.relu(self.main_bn3(self.main_conv2(x)))

        def forward(self, x):
            if self.stride == 2:
                proj = torch.relu(self.proj_bn2(self.proj_conv(self.proj_bn1(self.proj_dwconv(x)))))
                return torch.cat((proj, self.main(x)), 1)
            # the shuffle: even channels pass, odd channels go through the main branch
            return torch.cat((x[:, 0::2], self.main(x[:, 1::2])), 1)

    class ShuffleNetV2(nn.Module):
        """ShuffleNetV2 0.5x without conv5 and classifier: ``forward(x)`` -> the stride-8, 16
        and 32 feature maps (48, 96, 192 channels) of a :func:`normalize`\\ d batch."""

        def __init__(self):
            super().__init__()
            self.stem_conv = nn.Conv2d(3, STAGE_WIDTHS[0], 3, 2, 1, bias=False)
            self.stem_bn = nn.BatchNorm2d(STAGE_WIDTHS[0])
            self.maxpool = nn.MaxPool2d(3, 2, 1)
            inp = STAGE_WIDTHS[0]
            for s, repeats in enumerate(STAGE_REPEATS):
                out = STAGE_WIDTHS[s + 1]
                blocks = [ShuffleBlock(inp if b == 0 else out, out, 2 if b == 0 else 1) for b in range(repeats)]
                setattr(self, f"stage{s + 2}", nn.Sequential(*blocks))
                inp = out

        def forward(self, x):
            x = self.maxpool(torch.relu(self.stem_bn(self.stem_conv(x))))
            c8 = self.stage2(x)
            c16 = self.stage3(c8)
            c32 = self.stage4(c16)
            return c8, c16, c32

    return ShuffleBlock, ShuffleNetV2


def __getattr__(name: str) -> Any:
    """``ShuffleNetV2`` and ``ShuffleBlock`` are defined when first asked for (PEP 562)."""
    if name == "ShuffleBlock":
        return _classes()[0]
    if name == "ShuffleNetV2":
        return _classes()[1]
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def _count(keys) -> str:
    return f"{len(keys)} key{'' if len(keys) == 1 else 's'}"


def _names(keys) -> str:
    keys = sorted(keys)
    more = f" and {len(keys) - 8} more" if len(keys) > 8 else ""
    return ", ".join(keys[:8]) + more


def load_pretrained(path: str, module: Any = None) -> Any:
    """Loads the FastestDet-named ShuffleNetV2 0.5x state_dict at ``path`` into ``module`` (a
    new :class:`ShuffleNetV2` when None) through :func:`key_table` and returns the module, in
    eval mode. SynthgenError naming ``path`` when the file is missing, too large, not a
    state_dict of tensors, has keys the table does not know or lacks keys it needs, or a tensor
    of the wrong shape. The module is left untouched on any error."""
    torch = _torch.torch()
    state = _torch.load_file(path, MAX_FILE_BYTES, "backbone weights", "backbone weights file",
                             "a ShuffleNetV2 0.5x state_dict takes",
                             "the backbone weights as a PyTorch state_dict of tensors")
    if not isinstance(state, dict) or not all(isinstance(v, torch.Tensor) for v in state.values()):
        raise SynthgenError(f"{path}: not a state_dict of tensors (a {type(state).__name__})")
    table = key_table()
    unknown = set(state) - set(table)
    missing = set(table) - set(state)
    if unknown or missing:
        parts = []
        if unknown:
            parts.append(f"{_count(unknown)} the backbone does not have ({_names(unknown)})")
        if missing:
            parts.append(f"{_count(missing)} missing ({_names(missing)})")
        hint = ""
        if "conv1.0.weight" in state:
            hint = ("; this looks like torchvision's ShuffleNetV2, whose blocks split and shuffle the "
                    "channels differently (docs/evaluate.md, \"Backbone\")")
        raise SynthgenError(f"{path}: not a ShuffleNetV2 0.5x state_dict with FastestDet's key names: "
                            f"{'; '.join(parts)}{hint}")
    if module is None:
        module = _classes()[1]()
    own = module.state_dict()
    if set(own) != set(table.values()):
        raise SynthgenError(f"{path}: the module's tensors ({_names(set(own) ^ set(table.values()))}) "
                            f"do not match the key table")
    mapped = {}
    for src, dst in table.items():
        t = state[src]
        if tuple(t.shape) != tuple(own[dst].shape):
            raise SynthgenError(f"{path}: {src} has shape {tuple(t.shape)}, the backbone's {dst} "
                                f"needs {tuple(own[dst].shape)}")
        mapped[dst] = t
    module.load_state_dict(mapped, strict=True)
    return module.eval()


def normalize(images: np.ndarray) -> Any:
    """8-bit sRGB images (``N x H x W x 3`` or ``H x W x 3``, RGB order, uint8) -> the float32
    ``N x 3 x H x W`` tensor the pretrained weights expect: RGB order, values 0..1 (see the
    module docstring)."""
    torch = _torch.torch()
    a = np.asarray(images)
    if a.ndim == 3:
        a = a[None]
    if a.ndim != 4 or a.shape[3] != 3 or a.dtype != np.uint8:
        raise SynthgenError(f"normalize: expected N x H x W x 3 uint8 RGB images, got an array "
                            f"{a.shape} of {a.dtype}")
    x = np.ascontiguousarray(a.transpose(0, 3, 1, 2), dtype=np.float32)
    return torch.from_numpy(x) / 255.0
