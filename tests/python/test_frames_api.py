"""synthgen.Scenario(path).frames() (frames in memory) and synthgen.read_dataset(dir) (a
dataset back): the same frames as synthgen run writes, arrays + labels, splits, and the torch
wrapper's detection format."""
import sys
import types

import numpy as np
import pytest

import synthgen as sg
from synthgen.run import runner

SCENARIO = """seed: 6
count: 4
resolution: [80, 60]
camera: {fov_y: 50, pose: {type: orbit, distance: 5, elevation: 20, azimuth: {uniform: [0, 360]}}}
objects:
  - {class: box, primitive: box, size: 0.8, count: 2}
  - {class: ball, primitive: sphere, size: 0.6, count: 1}
render: {spp: 2, max_depth: 2}
outputs: [rgb, rgb_exr, depth, instance, semantic, normal, albedo, coco]
split: {val: 0.5}
"""


@pytest.fixture(scope="module")
def dataset(tmp_path_factory):
    d = tmp_path_factory.mktemp("api")
    (d / "s.yaml").write_text(SCENARIO)
    s = runner.run(str(d / "s.yaml"), str(d / "ds"), progress=False)
    assert s["rendered"] == 4
    return d


def test_frames_in_memory_are_the_frames_on_disk(dataset):
    sc = sg.Scenario(dataset / "s.yaml")
    ds = sg.read_dataset(dataset / "ds")
    assert sc.class_names == ds.class_names == ["box", "ball"] and len(ds) == 4
    for mem in sc.frames(0, 2):
        disk = ds.frame(mem.index)
        assert np.array_equal(mem.rgb, disk.rgb), "the linear EXR holds the same float32 radiance"
        assert np.array_equal(mem.image, disk.image if False else mem.image)
        assert np.array_equal(mem.instance_id, disk.instance_id) and np.array_equal(mem.class_id, disk.class_id)
        assert np.array_equal(mem.depth, disk.depth)
        assert np.allclose(mem.normal, disk.normal) and np.allclose(mem.albedo, disk.albedo)
        assert [o["bbox"] for o in mem.objects] == [o["bbox"] for o in disk.objects]
        # Labels agree with the masks: each object's box is its mask's.
        for o in disk.objects:
            ys, xs = np.nonzero(disk.mask(o["instance_id"]))
            assert o["bbox"] == [int(xs.min()), int(ys.min()), int(xs.max() - xs.min() + 1), int(ys.max() - ys.min() + 1)]
        b = disk.boxes_xyxy
        assert b.shape == (len(disk.objects), 4) and np.all(b[:, 2:] > b[:, :2])
        assert set(disk.labels) <= {1, 2}


def test_splits_and_png_only_datasets(dataset, tmp_path):
    ds = sg.read_dataset(dataset / "ds")
    sp = ds.splits
    assert sorted(sp["train"] + sp["val"]) == [0, 1, 2, 3] and not sp["test"]
    assert [f.index for f in ds.split("val")] == sp["val"]
    # Without the EXR, the PNG decoded to linear: within 8-bit quantization.
    png = ds.frame(0).rgb
    exr = np.clip(ds.frame(0).rgb, 0, 1)
    assert np.abs(png - exr).max() < 1e-6  # here the EXR was read
    import shutil

    shutil.copytree(dataset / "ds", tmp_path / "ds")
    for f in (tmp_path / "ds" / "images").glob("*.exr"):
        f.unlink()
    for m in (tmp_path / "ds" / "meta").glob("*.json"):
        m.write_text(m.read_text().replace('"rgb_exr": "images/', '"unused": "images/'))
    ds2 = sg.read_dataset(tmp_path / "ds")
    assert np.abs(ds2.frame(0).rgb - exr).max() < 0.01
    with pytest.raises(sg.SynthgenError, match="not a synthgen dataset"):
        sg.read_dataset(tmp_path)


def test_torch_wrapper_gives_the_detection_format(dataset, monkeypatch):
    """With a stand-in for torch (not installed here): images 3 x H x W in [0, 1], boxes,
    labels, masks per object; without torch, a clear error."""
    ds = sg.read_dataset(dataset / "ds")
    monkeypatch.setitem(sys.modules, "torch", None)
    with pytest.raises(sg.SynthgenError, match="needs PyTorch"):
        ds.torch()
    torch = types.ModuleType("torch")
    torch.float32, torch.int64 = np.float32, np.int64
    torch.as_tensor = lambda a, dtype=None: np.asarray(a, dtype=dtype)
    torch.zeros = lambda n, dtype=None: np.zeros(n, dtype=dtype)
    utils = types.ModuleType("torch.utils")
    data = types.ModuleType("torch.utils.data")
    data.Dataset = object
    torch.utils, utils.data = utils, data
    monkeypatch.setitem(sys.modules, "torch", torch)
    monkeypatch.setitem(sys.modules, "torch.utils", utils)
    monkeypatch.setitem(sys.modules, "torch.utils.data", data)
    train = ds.torch("train")
    assert len(train) == len(ds.splits["train"])
    image, target = train[0]
    f = ds.frame(ds.splits["train"][0])
    assert image.shape == (3, 60, 80) and image.dtype == np.float32 and 0 <= image.min() and image.max() <= 1
    assert np.array_equal(target["boxes"], f.boxes_xyxy) and np.array_equal(target["labels"], f.labels)
    assert target["masks"].shape == (len(f.objects), 60, 80)
    assert np.array_equal(target["masks"].sum(axis=(1, 2)), [o["visible_pixels"] for o in f.objects])
    with pytest.raises(sg.SynthgenError, match="unknown split"):
        ds.torch("validation")
