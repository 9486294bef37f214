"""The train / val / test split (synthgen.outputs.split): frames that share a source photo or
a scene layout never land in two splits; a group's split depends only on the seed and its key;
dataset.yaml and the COCO files follow it (dataset.yaml listed every image for train and val)."""
import json
import os
from pathlib import Path

import numpy as np
import pytest
import yaml

import synthgen as sg
from synthgen.outputs import split

ROOT = Path(__file__).resolve().parents[2]


def _metas(n, photos=37, seed=0):
    rng = np.random.default_rng(seed)
    return [{"frame": k, "split_keys": [f"layout:{k}", f"photo:{int(rng.integers(photos))}"]} for k in range(n)]


def test_groups_never_straddle_splits_and_fractions_hold():
    metas = _metas(3000, photos=900)
    a = split.assign(metas, seed=5, val=0.2, test=0.1)
    by_photo = {}
    for m in metas:
        by_photo.setdefault(m["split_keys"][1], set()).add(a[m["frame"]])
    assert all(len(s) == 1 for s in by_photo.values()), "a photo in two splits"
    groups = split.groups(metas)
    assert sum(len(g) for g in groups) == 3000
    counts = {s: sum(1 for g in groups if a[g[0]] == s) for s in split.SPLITS}
    n = len(groups)
    # Binomial: 4 standard deviations.
    for s, p in (("val", 0.2), ("test", 0.1)):
        assert abs(counts[s] - p * n) < 4 * np.sqrt(n * p * (1 - p)), counts


def test_keys_chain_frames_together():
    """Frames sharing a key are together even through other frames (a-b, b-c: a, b, c)."""
    metas = [{"frame": 0, "split_keys": ["x", "y"]}, {"frame": 1, "split_keys": ["y", "z"]},
             {"frame": 2, "split_keys": ["z"]}, {"frame": 3, "split_keys": ["w"]}, {"frame": 4}]
    assert split.groups(metas) == [[0, 1, 2], [3], [4]]


def test_a_groups_split_depends_on_seed_and_key_only():
    metas = _metas(400)
    full = split.assign(metas, seed=3, val=0.3, test=0.0)
    # Another order, and a subset: the same answer for the frames present (resume, --only).
    part = split.assign(list(reversed(metas[::3])) + metas[1::3], seed=3, val=0.3, test=0.0)
    assert all(part[k] == full[k] for k in part)
    other = split.assign(metas, seed=4, val=0.3, test=0.0)
    assert other != full


TINY = """
seed: 11
count: 8
resolution: [48, 32]
camera: {fov_y: 50, pose: {type: orbit, distance: 6, elevation: 25}}
objects:
  - {class: box, primitive: box, count: 1, size: 1.0}
render: {spp: 1, max_depth: 2}
outputs: [rgb, coco, yolo]
split: {val: 0.5, test: 0.0}
"""


def test_a_run_writes_the_split_and_formats_follow_it(tmp_path):
    from synthgen.run import runner

    sc = tmp_path / "tiny.yaml"
    sc.write_text(TINY)
    out = tmp_path / "ds"
    s = runner.run(str(sc), str(out), progress=False)
    assert s["rendered"] == 8, s.text()
    lists = {x: (out / "splits" / f"{x}.txt").read_text().split() for x in split.SPLITS}
    assert sorted(lists["train"] + lists["val"]) == sorted(f"images/{k:06d}.png" for k in range(8))
    assert not set(lists["train"]) & set(lists["val"]) and lists["test"] == []
    assert lists["train"] and lists["val"]
    ds = yaml.safe_load((out / "dataset.yaml").read_text())
    assert ds["train"] == "splits/train.txt" and ds["val"] == "splits/val.txt" and "test" not in ds
    for x in ("train", "val"):
        coco = json.loads((out / "annotations" / f"coco_{x}.json").read_text())
        assert sorted(im["file_name"] for im in coco["images"]) == sorted(lists[x])
    info = json.loads((out / "splits" / "splits.json").read_text())
    assert info["counts"] == {"train": len(lists["train"]), "val": len(lists["val"]), "test": 0}
    meta = json.loads((out / "meta" / "000000.json").read_text())
    assert meta["split_keys"][0].startswith("layout:")


def test_fractions_are_checked(tmp_path):
    from synthgen.scenario import load_scenario

    p = tmp_path / "s.yaml"
    p.write_text(TINY.replace("split: {val: 0.5, test: 0.0}", "split: {val: 0.7, test: 0.4}"))
    with pytest.raises(sg.SynthgenError, match=r":10:\d+: split.test: val \+ test = 1.1 leaves no frames for train"):
        load_scenario(p)
