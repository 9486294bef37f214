"""Which real frames of ``../shared/realdata/cars_highway`` test, and which may train.

The frames come from one video (numbered ``vid_4_N.jpg``; neighbouring frames are
near-duplicates), so the split is by frame number in contiguous blocks, never at random:

* **test**: the labelled frames in :data:`TEST_BLOCKS` (frame numbers [low, high)) -- 90 of the
  216 labelled frames, 152 cars; every figure of ``bench/sim2real.py`` is scored on them;
* **dev**: the other labelled frames at least :data:`GAP` frames from every test frame (124
  frames): the real frames that may train (``real_trained_ap50``, the K-frame draws of
  ``augment_gain_ap50_at_K``);
* **backgrounds**: the car-free frames (``negatives/``) at least :data:`GAP` frames from every
  test frame: the photos cars are inserted into and the negatives of real training. (Those
  nearer the test blocks are used nowhere: a detector should not have seen the test frames'
  road and trees.)
* :data:`RECIPE_TRAIN` / :data:`RECIPE_VAL`: two halves of the dev frames, again :data:`GAP`
  apart, on which the training recipe (steps, learning rate, mixing) was chosen, never on the
  test frames.
"""
from __future__ import annotations

import os
import re
from typing import Dict, List, Sequence, Tuple

#: Frame-number blocks [low, high) whose labelled frames are the test set.
TEST_BLOCKS: Tuple[Tuple[int, int], ...] = ((0, 3000), (9000, 10300))
#: No frame within this many frame numbers of a test frame trains.
GAP = 200
#: Dev blocks the recipe was tuned on: train on the first, validate on the second.
RECIPE_TRAIN: Tuple[Tuple[int, int], ...] = ((3000, 9000),)
RECIPE_VAL: Tuple[Tuple[int, int], ...] = ((10300, 15000),)

_NUMBER = re.compile(r"_(\d+)\.[A-Za-z]+$")


def frame_number(path: str) -> int:
    m = _NUMBER.search(os.path.basename(path))
    if not m:
        raise ValueError(f"{path}: not a frame of the highway video (vid_4_N.jpg)")
    return int(m.group(1))


def in_blocks(n: int, blocks: Sequence[Tuple[int, int]]) -> bool:
    return any(lo <= n < hi for lo, hi in blocks)


def split(labelled: Sequence[str], negatives: Sequence[str]) -> Dict[str, List[str]]:
    """``{"test", "dev", "backgrounds", "recipe_train", "recipe_val", "unused"}``: paths."""
    test = [p for p in labelled if in_blocks(frame_number(p), TEST_BLOCKS)]
    tn = sorted(frame_number(p) for p in test)

    def far(p: str) -> bool:
        n = frame_number(p)
        return all(abs(n - t) >= GAP for t in tn)

    dev = [p for p in labelled if p not in set(test) and far(p)]
    backgrounds = [p for p in negatives if far(p)]
    used = set(test) | set(dev) | set(backgrounds)
    rt = [p for p in dev if in_blocks(frame_number(p), RECIPE_TRAIN)]
    rv = [p for p in dev if in_blocks(frame_number(p), RECIPE_VAL)]
    rtn = [frame_number(p) for p in rt]
    rv = [p for p in rv if all(abs(frame_number(p) - t) >= GAP for t in rtn)]
    return {"test": test, "dev": dev, "backgrounds": backgrounds, "recipe_train": rt, "recipe_val": rv,
            "unused": [p for p in list(labelled) + list(negatives) if p not in used]}
