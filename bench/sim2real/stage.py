"""Stages training jobs of bench/sim2real.py for the accelerator machine: copies every image the
jobs read, the backbone's weights and the code of the evaluate stage (with
bench/sim2real/remote.py) into one folder of the checkout that git ignores (``.device/``), with
the jobs' paths rewritten relative to it, so that one ``device`` call carries it (64 MiB at
most: :data:`LIMIT`; stage fewer jobs per call when it is more, or pass ``split=True``: the jobs
are then packed, in order, into folders ``OUT/part0``, ``OUT/part1``, ... of at most LIMIT each,
one call each, a job's files travelling with every part that has one of its jobs). The copies of
../shared/realdata are transient (the folder is replaced by the next staging and ignored by
git): they are never committed.

Rendered PNG frames travel as JPEG of quality :data:`JPEG_QUALITY` (a 676 x 380 render: ~390 KB
as PNG, ~89 KB as JPEG 90), so that a call carries 512 of them: the trained-on pixels
are then those of a JPEG, as the real photos are (JPEGs of quality 95, copied as they are). Pass
``jpeg=0`` to copy PNGs unchanged."""
from __future__ import annotations

import hashlib
import json
import os
import shutil
from typing import Any, Dict, List

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.abspath(os.path.join(HERE, "..", ".."))
#: The most the folder may hold (a device call carries 64 MiB with the checkout's ~10.3 MiB).
LIMIT = 52 << 20
#: JPEG quality of staged PNG renders (Pillow's scale; 4:2:0 chroma like the real frames).
JPEG_QUALITY = 90


class _Folder:
    """One call's folder: images (deduplicated, PNG -> JPEG), the code, jobs.json."""

    def __init__(self, out: str, jpeg: int) -> None:
        shutil.rmtree(out, ignore_errors=True)
        self.out, self.jpeg = out, jpeg
        self.data = os.path.join(out, "data")
        os.makedirs(self.data)
        self.names: Dict[str, str] = {}
        self.sizes: Dict[str, int] = {}
        self.jobs: List[Dict[str, Any]] = []
        code = os.path.join(out, "code")
        shutil.copytree(os.path.join(REPO, "python", "synthgen", "evaluate"),
                        os.path.join(code, "python", "synthgen", "evaluate"),
                        ignore=shutil.ignore_patterns("__pycache__"))
        os.makedirs(os.path.join(code, "bench", "sim2real"))
        shutil.copyfile(os.path.join(HERE, "remote.py"), os.path.join(code, "bench", "sim2real", "remote.py"))
        self.base = sum(os.path.getsize(os.path.join(dp, f)) for dp, _, fs in os.walk(code) for f in fs)

    @property
    def size(self) -> int:
        return self.base + sum(self.sizes.values()) + len(json.dumps({"jobs": self.jobs}))

    def rel(self, path: str) -> str:
        if path not in self.names:
            d = hashlib.sha256(os.path.dirname(os.path.realpath(path)).encode()).hexdigest()[:10]
            base = os.path.basename(path)
            os.makedirs(os.path.join(self.data, d), exist_ok=True)
            if self.jpeg and base.lower().endswith(".png"):
                from PIL import Image

                name = f"{d}/{os.path.splitext(base)[0]}.jpg"
                with Image.open(path) as im:
                    im.convert("RGB").save(os.path.join(self.data, name), "JPEG", quality=int(self.jpeg))
            else:
                name = f"{d}/{base}"
                shutil.copyfile(path, os.path.join(self.data, name))
            self.names[path] = name
            self.sizes[path] = os.path.getsize(os.path.join(self.data, name))
        return self.names[path]

    def add(self, job: Dict[str, Any]) -> List[str]:
        """Adds ``job`` (paths rewritten); returns the source paths it brought in."""
        before = set(self.names)
        j = json.loads(json.dumps(job))
        for rows in j["pools"].values():
            for r in rows:
                r[0] = self.rel(r[0])
        if j["options"].get("backbone"):
            j["options"]["backbone"] = self.rel(j["options"]["backbone"])
        self.jobs.append(j)
        return [p for p in self.names if p not in before]

    def undo(self, job_paths: List[str]) -> None:
        """Takes the last job back out, with the files only it brought."""
        self.jobs.pop()
        for p in job_paths:
            os.remove(os.path.join(self.data, self.names.pop(p)))
            del self.sizes[p]

    def close(self) -> int:
        """Writes jobs.json and prints the device command; returns the folder's size (bytes)."""
        with open(os.path.join(self.out, "jobs.json"), "w") as f:
            json.dump({"jobs": self.jobs}, f)
        size = sum(os.path.getsize(os.path.join(dp, f)) for dp, _, fs in os.walk(self.out) for f in fs)
        rel_out = os.path.relpath(self.out, REPO)
        print(f"staged {len(self.jobs)} jobs, {len(self.names)} files, {size / 2**20:.1f} MiB in {self.out}; "
              f"on the accelerator:\n  python3 {rel_out}/code/bench/sim2real/remote.py {rel_out}/jobs.json "
              f"--root {rel_out}/data --out $OUT --device cuda --workers 15 --parallel 3 --pack 15   "
              f"(carry: {rel_out})")
        return size


def stage(jobs: List[Dict[str, Any]], out: str, jpeg: int = JPEG_QUALITY, split: bool = False) -> List[str]:
    """Stages ``jobs`` into ``out`` (``split``: into ``out/partK``, as many as LIMIT needs);
    returns the folders, one device call each."""
    if not split:
        f = _Folder(out, jpeg)
        for j in jobs:
            f.add(j)
        size = f.close()
        if size > LIMIT:
            raise SystemExit(f"sim2real stage: {size / 2**20:.1f} MiB is more than one call carries "
                             f"({LIMIT / 2**20:.0f} MiB): stage fewer jobs (--jobs) or split them (--split)")
        return [out]
    shutil.rmtree(out, ignore_errors=True)
    folders: List[str] = []
    f = None
    for j in jobs:
        if f is None:
            f = _Folder(os.path.join(out, f"part{len(folders)}"), jpeg)
            folders.append(f.out)
        new = f.add(j)
        if f.size > LIMIT:
            if len(f.jobs) == 1:
                raise SystemExit(f"sim2real stage: job {j['name']} alone is {f.size / 2**20:.1f} MiB, more than "
                                 f"one call carries ({LIMIT / 2**20:.0f} MiB)")
            f.undo(new)
            f.close()
            f = _Folder(os.path.join(out, f"part{len(folders)}"), jpeg)
            folders.append(f.out)
            f.add(j)
    if f is not None:
        f.close()
    return folders
