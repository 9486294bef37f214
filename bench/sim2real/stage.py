"""Stages training jobs of bench/sim2real.py for the accelerator machine: copies every image the
jobs read, the backbone's weights and the code of the evaluate stage (with
bench/sim2real/remote.py) into one folder of the checkout that git ignores (``.device/``), with
the jobs' paths rewritten relative to it, so that one ``device`` call carries it (64 MiB at
most: :data:`LIMIT`; stage fewer jobs per call when it is more). The copies of
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


def stage(jobs: List[Dict[str, Any]], out: str, jpeg: int = JPEG_QUALITY) -> str:
    shutil.rmtree(out, ignore_errors=True)
    data = os.path.join(out, "data")
    os.makedirs(data)
    names: Dict[str, str] = {}

    def rel(path: str) -> str:
        if path not in names:
            d = hashlib.sha256(os.path.dirname(os.path.realpath(path)).encode()).hexdigest()[:10]
            base = os.path.basename(path)
            os.makedirs(os.path.join(data, d), exist_ok=True)
            if jpeg and base.lower().endswith(".png"):
                from PIL import Image

                names[path] = f"{d}/{os.path.splitext(base)[0]}.jpg"
                with Image.open(path) as im:
                    im.convert("RGB").save(os.path.join(data, names[path]), "JPEG", quality=int(jpeg))
            else:
                names[path] = f"{d}/{base}"
                shutil.copyfile(path, os.path.join(data, names[path]))
        return names[path]

    staged = []
    for j in jobs:
        j = json.loads(json.dumps(j))
        for rows in j["pools"].values():
            for r in rows:
                r[0] = rel(r[0])
        if j["options"].get("backbone"):
            j["options"]["backbone"] = rel(j["options"]["backbone"])
        staged.append(j)
    with open(os.path.join(out, "jobs.json"), "w") as f:
        json.dump({"jobs": staged}, f)
    code = os.path.join(out, "code")
    shutil.copytree(os.path.join(REPO, "python", "synthgen", "evaluate"),
                    os.path.join(code, "python", "synthgen", "evaluate"), ignore=shutil.ignore_patterns("__pycache__"))
    os.makedirs(os.path.join(code, "bench", "sim2real"))
    shutil.copyfile(os.path.join(HERE, "remote.py"), os.path.join(code, "bench", "sim2real", "remote.py"))
    rel_out = os.path.relpath(out, REPO)
    size = sum(os.path.getsize(os.path.join(dp, f)) for dp, _, fs in os.walk(out) for f in fs)
    print(f"staged {len(staged)} jobs, {len(names)} files, {size / 2**20:.1f} MiB in {out}; on the accelerator:\n"
          f"  python3 {rel_out}/code/bench/sim2real/remote.py {rel_out}/jobs.json --root {rel_out}/data --out $OUT "
          f"--device cuda --workers 15 --parallel 3 --pack 15   (carry: {rel_out})")
    if size > LIMIT:
        raise SystemExit(f"sim2real stage: {size / 2**20:.1f} MiB is more than one call carries "
                         f"({LIMIT / 2**20:.0f} MiB): stage fewer jobs (--jobs)")
    return out
