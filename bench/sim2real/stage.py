"""Stages training jobs of bench/sim2real.py for the accelerator machine: copies every image the
jobs read, the backbone's weights and the code of the evaluate stage (with
bench/sim2real/remote.py) into one folder of the checkout that git ignores (``.device/``), with
the jobs' paths rewritten relative to it, so that one ``device`` call carries it (64 MiB at
most: :data:`LIMIT`; stage fewer jobs per call when it is more). The copies of
../shared/realdata are transient (the folder is replaced by the next staging and ignored by
git): they are never committed."""
from __future__ import annotations

import hashlib
import json
import os
import shutil
from typing import Any, Dict, List

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.abspath(os.path.join(HERE, "..", ".."))
#: The most the folder may hold (a device call carries 64 MiB with the checkout's ~11 MiB).
LIMIT = 48 << 20


def stage(jobs: List[Dict[str, Any]], out: str) -> str:
    shutil.rmtree(out, ignore_errors=True)
    data = os.path.join(out, "data")
    os.makedirs(data)
    names: Dict[str, str] = {}

    def rel(path: str) -> str:
        if path not in names:
            d = hashlib.sha256(os.path.dirname(os.path.realpath(path)).encode()).hexdigest()[:10]
            names[path] = f"{d}/{os.path.basename(path)}"
            os.makedirs(os.path.join(data, d), exist_ok=True)
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
    size = sum(os.path.getsize(os.path.join(dp, f)) for dp, _, fs in os.walk(out) for f in fs)
    print(f"staged {len(staged)} jobs, {len(names)} files, {size / 2**20:.1f} MiB in {out}; on the accelerator:\n"
          f"  python3 .device/code/bench/sim2real/remote.py .device/jobs.json --root .device/data --out $OUT "
          f"--device cuda --workers 14   (carry: .device)")
    if size > LIMIT:
        raise SystemExit(f"sim2real stage: {size / 2**20:.1f} MiB is more than one call carries "
                         f"({LIMIT / 2**20:.0f} MiB): stage fewer jobs (--jobs)")
    return out
