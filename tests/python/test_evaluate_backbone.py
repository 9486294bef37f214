"""The reference detector's backbone (synthgen.evaluate.backbone): ShuffleNetV2 0.5x in Megvii's
layout, the pretrained weights of ../shared/realdata/backbones mapped onto it key by key, and the
input normalisation they expect.

The mapping is checked by what it computes, not by shapes (a wrong channel shuffle loads by
shape): on a batch of real highway photos, each BatchNorm layer's batch statistics of its input
agree with the running mean and variance stored with the weights; the same weights loaded by
shape into torchvision's layout (halves, shuffle after the concatenation) disagree. Tests that
need ../shared or PyTorch skip without them.
"""
from __future__ import annotations

import os
import sys
from typing import Dict, List, Tuple

import numpy as np
import pytest

from synthgen import SynthgenError
from synthgen.evaluate import backbone as bb

REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
SHARED = os.path.abspath(os.path.join(REPO, "..", "shared"))
WEIGHTS = os.path.join(SHARED, "realdata", "backbones", "shufflenetv2_x0.5_imagenet.pth")
HIGHWAY = os.path.join(SHARED, "realdata", "cars_highway")

try:
    import torch
except ImportError:  # pragma: no cover - CI installs python3-torch
    torch = None

needs_torch = pytest.mark.skipif(torch is None, reason="PyTorch (python3-torch) is not installed")
needs_weights = pytest.mark.skipif(not (os.path.isfile(WEIGHTS) and os.path.isdir(HIGHWAY)),
                                   reason="../shared/realdata is not here")

#: The detector's input size (rows, columns): the 676 x 380 highway frames resized.
SIZE = (384, 672)

#: The agreement the right mapping must show (measured: see docs/evaluate.md, "Backbone"):
#: the mean variance of each layer's input within a factor of VAR_FACTOR of the stored one, and
#: the means of the layers that read a block's (or the photo's) features directly -- the stem,
#: each block's first main-branch BN and a stride-2 block's first projection BN, the layers
#: where a wrong channel split shows first -- correlated across channels above MEAN_CORR. (The
#: other BN layers read a 1x1 convolution of a BatchNorm output without ReLU: their means are
#: close to zero and their correlation is noise; they are held to the variance test.)
VAR_FACTOR = 2.0
MEAN_CORR = 0.9


def _photos(n_cars: int = 16, n_empty: int = 16) -> np.ndarray:
    """Frames spread evenly over the video (cars and car-free), resized to SIZE, as uint8 RGB."""
    from PIL import Image

    def pick(folder: str, n: int) -> List[str]:
        names = sorted(f for f in os.listdir(folder) if f.lower().endswith((".jpg", ".jpeg", ".png")))
        return [os.path.join(folder, names[i]) for i in np.linspace(0, len(names) - 1, n).round().astype(int)]

    files = pick(os.path.join(HIGHWAY, "images"), n_cars) + pick(os.path.join(HIGHWAY, "negatives"), n_empty)
    return np.stack([np.asarray(Image.open(f).convert("RGB").resize(SIZE[::-1], Image.BILINEAR)) for f in files])


Stats = Dict[str, Tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]]


def _bn_stats(model, x) -> Stats:
    """Per BatchNorm layer (by name, in forward order): the batch mean and variance of its
    input over images and pixels, and its stored running mean and variance. The model runs in
    eval mode (each layer normalises by the stored statistics, as when detecting)."""
    out: Stats = {}
    hooks = []
    for name, mod in model.named_modules():
        if isinstance(mod, torch.nn.BatchNorm2d):
            def hook(mod, inputs, name=name):
                t = inputs[0].double()
                out[name] = (t.mean((0, 2, 3)).numpy(), t.var((0, 2, 3), unbiased=False).numpy(),
                             mod.running_mean.double().numpy(), mod.running_var.double().numpy())
            hooks.append(mod.register_forward_pre_hook(hook))
    try:
        with torch.no_grad():
            model.eval()(x)
    finally:
        for h in hooks:
            h.remove()
    return out


def _mean_checked(name: str) -> bool:
    return name.endswith(("stem_bn", "conv1.1", "main_bn1", "branch2.1", "proj_bn1", "branch1.1"))


def _agreement(stats: Stats) -> List[Tuple[str, float, float, bool]]:
    """(layer, correlation of the batch and running means across live channels, mean batch
    variance / mean running variance, agrees) per layer. Dead channels (a running variance
    under 1e-6 of the layer's largest) are left out."""
    rows = []
    for name, (bm, bv, rm, rv) in stats.items():
        live = rv > 1e-6 * rv.max()
        corr = float(np.corrcoef(bm[live], rm[live])[0, 1])
        ratio = float(bv[live].mean() / rv[live].mean())
        ok = 1 / VAR_FACTOR <= ratio <= VAR_FACTOR and (corr > MEAN_CORR or not _mean_checked(name))
        rows.append((name, corr, ratio, ok))
    return rows


def _print(title: str, rows) -> None:
    print(f"\n{title}: layer, mean correlation, variance ratio, agrees")
    for name, corr, ratio, ok in rows:
        print(f"  {name:26s} {corr:7.3f} {ratio:7.3f}  {'yes' if ok else 'NO '}"
              f"{'' if _mean_checked(name) else '  (mean not checked)'}")


def _torchvision_layout(state):
    """torchvision's shufflenet_v2_x0_5 (halves, shuffle after) with the file's tensors loaded by
    shape (renamed: first_conv -> conv1, branch_main -> branch2, branch_proj -> branch1): a
    module computing the stride-32 features like :class:`ShuffleNetV2` would, with the wrong
    split."""
    torchvision = pytest.importorskip("torchvision")
    tv = torchvision.models.shufflenet_v2_x0_5()
    renamed = {k.replace("first_conv", "conv1").replace("branch_main", "branch2").replace("branch_proj", "branch1"): v
               for k, v in state.items()}
    own = tv.state_dict()
    assert set(renamed) == {k for k in own if not k.startswith(("conv5", "fc"))}
    assert all(tuple(v.shape) == tuple(own[k].shape) for k, v in renamed.items()), "loads by shape"
    tv.load_state_dict(renamed, strict=False)

    class Features(torch.nn.Module):
        def __init__(self):
            super().__init__()
            self.conv1, self.maxpool, self.stage2, self.stage3, self.stage4 = (
                tv.conv1, tv.maxpool, tv.stage2, tv.stage3, tv.stage4)

        def forward(self, x):
            return self.stage4(self.stage3(self.stage2(self.maxpool(self.conv1(x)))))

    return Features()


@pytest.fixture(scope="module")
def photos():
    return _photos()


@pytest.fixture(scope="module")
def model():
    return bb.load_pretrained(WEIGHTS)


@needs_torch
@needs_weights
def test_batchnorm_statistics_on_real_photos_match_the_stored_ones(photos, model):
    """The right mapping: every BN layer agrees; the wrong layout (torchvision's, same tensors
    by shape): the layers past the first block, where the two layouts part, disagree."""
    x = bb.normalize(photos)
    right = _agreement(_bn_stats(model, x))
    _print("Megvii layout (synthgen.evaluate.backbone)", right)
    assert len(right) == 55  # the stem, 3 per block, 2 more per stride-2 block
    bad = [r[0] for r in right if not r[3]]
    assert not bad, f"BatchNorm statistics disagree with the stored ones at {bad}"

    wrong = _agreement(_bn_stats(_torchvision_layout(torch.load(WEIGHTS, map_location="cpu")), x))
    _print("torchvision layout, same tensors by shape", wrong)
    assert len(wrong) == len(right)
    # Up to the first block's output the two layouts compute the same thing ...
    first = [r for r in wrong if r[0].startswith(("conv1", "stage2.0."))]
    assert all(r[3] for r in first)
    # ... after it, the layers whose means are checked disagree (every one of the 17).
    later = [r for r in wrong if not r[0].startswith(("conv1", "stage2.0.")) and _mean_checked(r[0])]
    assert len(later) == 17
    assert not any(r[3] for r in later), [r for r in later if r[3]]


@needs_torch
@needs_weights
def test_the_normalisation_is_the_one_the_weights_were_trained_with(photos, model):
    """RGB 0..1 (normalize): the stem's statistics agree; bytes 0..255 give a variance far
    off, ImageNet's mean/std anti-correlated means, BGR order a weaker correlation."""
    x = bb.normalize(photos[:8])
    assert float(x.min()) >= 0.0 and float(x.max()) <= 1.0

    def stem(t):
        return next(r for r in _agreement(_bn_stats(model, t)) if r[0] == "stem_bn")

    ok = stem(x)
    assert ok[3], ok
    bytes_ = stem(x * 255)
    assert not bytes_[3] and bytes_[2] > 100
    mean = torch.tensor([0.485, 0.456, 0.406]).view(1, 3, 1, 1)
    std = torch.tensor([0.229, 0.224, 0.225]).view(1, 3, 1, 1)
    imagenet = stem((x - mean) / std)
    assert not imagenet[3] and imagenet[1] < 0
    assert stem(x.flip(1))[1] < ok[1]


@needs_torch
@needs_weights
def test_every_tensor_of_the_file_is_used_once(model):
    state = torch.load(WEIGHTS, map_location="cpu")
    table = bb.key_table()
    assert set(table) == set(state) and len(table) == 330
    assert len(set(table.values())) == len(table)
    own = model.state_dict()
    assert set(own) == set(table.values())
    for src, dst in table.items():
        assert torch.equal(own[dst], state[src]), (src, dst)
    assert sum(v.numel() for k, v in own.items() if k.endswith(("weight", "bias"))) == 143136


@needs_torch
def test_feature_shapes_and_determinism():
    torch.manual_seed(0)
    net = bb.ShuffleNetV2().eval()
    x = torch.rand(2, 3, *SIZE)
    with torch.no_grad():
        a = net(x)
        b = net(x.clone())
    assert [tuple(t.shape) for t in a] == [(2, 48, 48, 84), (2, 96, 24, 42), (2, 192, 12, 21)]
    assert bb.STRIDES == (8, 16, 32)
    assert all(torch.equal(p, q) for p, q in zip(a, b))


@needs_torch
def test_the_stride_1_block_passes_the_even_channels_and_transforms_the_odd_ones():
    """Megvii's split, on a block alone: changing an odd input channel leaves the first half of
    the output alone (it is the even channels, passed through), changing an even one changes
    only its own output channel."""
    torch.manual_seed(0)
    block = bb.ShuffleBlock(48, 48, 1).eval()
    x = torch.rand(1, 48, 8, 8)
    with torch.no_grad():
        y = block(x)
        assert torch.equal(y[:, :24], x[:, 0::2])
        odd = x.clone()
        odd[:, 5] += 1.0
        y_odd = block(odd)
        even = x.clone()
        even[:, 4] += 1.0
        y_even = block(even)
    assert torch.equal(y_odd[:, :24], y[:, :24]) and not torch.equal(y_odd[:, 24:], y[:, 24:])
    changed = [c for c in range(48) if not torch.equal(y_even[:, c], y[:, c])]
    assert changed == [2]


@needs_torch
def test_bad_weight_files_are_errors_naming_the_file_and_keys(tmp_path):
    net = bb.ShuffleNetV2()
    good = {src: net.state_dict()[dst].clone() for src, dst in bb.key_table().items()}
    before = {k: v.clone() for k, v in net.state_dict().items()}

    with pytest.raises(SynthgenError, match=r"nope\.pth: backbone weights not found"):
        bb.load_pretrained(str(tmp_path / "nope.pth"), net)

    path = tmp_path / "junk.pth"
    path.write_bytes(b"not a torch file")
    with pytest.raises(SynthgenError, match=r"junk\.pth: cannot read the backbone weights as a PyTorch "
                                            r"state_dict of tensors \(UnpicklingError: "):
        bb.load_pretrained(str(path), net)

    path = tmp_path / "list.pth"
    torch.save([torch.zeros(1)], path)
    with pytest.raises(SynthgenError, match=r"list\.pth: not a state_dict of tensors \(a list\)"):
        bb.load_pretrained(str(path), net)

    extra = dict(good)
    extra["stage2.0.branch_main.7.weight"] = torch.zeros(3)
    del extra["stage4.3.branch_main.6.running_var"]
    path = tmp_path / "keys.pth"
    torch.save(extra, path)
    with pytest.raises(SynthgenError, match=r"keys\.pth: not a ShuffleNetV2 0\.5x state_dict with FastestDet's key "
                                            r"names: 1 key the backbone does not have \(stage2\.0\.branch_main\.7\."
                                            r"weight\); 1 key missing \(stage4\.3\.branch_main\.6\.running_var\)$"):
        bb.load_pretrained(str(path), net)

    path = tmp_path / "torchvision.pth"
    torch.save(pytest.importorskip("torchvision").models.shufflenet_v2_x0_5().state_dict(), path)
    with pytest.raises(SynthgenError, match=r"torchvision\.pth: .*338 keys the backbone does not have \(conv1\.0\."
                                            r"weight, .* and 330 more\); 330 keys missing .*torchvision's ShuffleNetV2"):
        bb.load_pretrained(str(path), net)

    shaped = dict(good)
    shaped["stage3.2.branch_main.0.weight"] = torch.zeros(48, 48, 3, 3)
    path = tmp_path / "shape.pth"
    torch.save(shaped, path)
    with pytest.raises(SynthgenError, match=r"shape\.pth: stage3\.2\.branch_main\.0\.weight has shape "
                                            r"\(48, 48, 3, 3\), the backbone's stage3\.2\.main_conv1\.weight "
                                            r"needs \(48, 48, 1, 1\)"):
        bb.load_pretrained(str(path), net)
    after = net.state_dict()
    assert all(torch.equal(before[k], after[k]) for k in before), "a failed load changed the module"


def test_without_torch_the_error_names_the_debian_packages(monkeypatch):
    from synthgen.evaluate import _torch

    monkeypatch.setitem(sys.modules, "torch", None)  # import torch raises ImportError
    bb._classes.cache_clear()
    try:
        with pytest.raises(SynthgenError, match=r"needs PyTorch.*apt-get install python3-torch python3-torchvision"):
            bb.ShuffleNetV2
        with pytest.raises(SynthgenError, match="python3-torch python3-torchvision"):
            _torch.torch()
    finally:
        bb._classes.cache_clear()
