"""Renders a scenario with every output kind and prints a content hash of the dataset.

    .venv/bin/python tools/dataset_hash.py scenarios/default.yaml -n 6
    .venv/bin/python tools/dataset_hash.py scenarios/road_signs.yaml -n 6 --keep out/hash-signs

Used to show that a change (a refactoring, a new default) leaves a dataset bit-identical:
run it before and after and compare the printed ``dataset_sha256``. The scenario is
copied next to itself with ``outputs:`` replaced by the list of every output kind (so
relative paths resolve as before) and rendered into a fixed directory name; every file of
the dataset except ``run_summary.json`` (wall-clock timings) is hashed by relative path and
content. One digest per top-level directory is printed too, to locate a difference.
"""
from __future__ import annotations

import argparse
import hashlib
import os
import re
import shutil
import subprocess
import sys
import tempfile

ALL_OUTPUTS = ["rgb", "rgb_exr", "depth", "depth16", "instance", "semantic", "coco", "yolo", "kitti"]
EXCLUDE = {"run_summary.json"}


def all_outputs_text(text: str) -> str:
    """The scenario text with its top-level ``outputs:`` entry replaced (or added)."""
    line = "outputs: [" + ", ".join(ALL_OUTPUTS) + "]"
    pattern = re.compile(r"^outputs:.*(?:\n[ \t]+.*)*", re.MULTILINE)
    if pattern.search(text):
        return pattern.sub(line, text, count=1)
    return text.rstrip("\n") + "\n" + line + "\n"


def digest_tree(root: str) -> tuple[str, dict[str, str]]:
    total = hashlib.sha256()
    per_dir: dict[str, hashlib._Hash] = {}
    for dirpath, dirnames, filenames in os.walk(root):
        dirnames.sort()
        for name in sorted(filenames):
            path = os.path.join(dirpath, name)
            rel = os.path.relpath(path, root)
            if rel in EXCLUDE:
                continue
            with open(path, "rb") as f:
                data = f.read()
            entry = rel.encode() + b"\0" + hashlib.sha256(data).digest()
            total.update(entry)
            top = rel.split(os.sep, 1)[0] if os.sep in rel else "."
            per_dir.setdefault(top, hashlib.sha256()).update(entry)
    return total.hexdigest(), {k: v.hexdigest() for k, v in sorted(per_dir.items())}


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("scenario")
    ap.add_argument("-n", "--count", type=int, default=6)
    ap.add_argument("--workers", type=int, default=1)
    ap.add_argument("--keep", metavar="DIR", help="keep the dataset in DIR (default: a temporary directory)")
    args = ap.parse_args(argv)

    src = os.path.abspath(args.scenario)
    with open(src, encoding="utf-8") as f:
        text = all_outputs_text(f.read())
    derived = os.path.join(os.path.dirname(src), "." + os.path.basename(src) + ".all-outputs.yaml")
    # A fixed directory name: dataset.yaml records the dataset's absolute path.
    out = os.path.abspath(args.keep) if args.keep else os.path.join(tempfile.gettempdir(), "synthgen-dataset-hash")
    shutil.rmtree(out, ignore_errors=True)
    try:
        with open(derived, "w", encoding="utf-8") as f:
            f.write(text)
        exe = os.path.join(os.path.dirname(sys.executable), "synthgen")
        cmd = [exe, "run", derived, "-o", out, "-n", str(args.count), "--workers", str(args.workers), "--no-progress"]
        r = subprocess.run(cmd, capture_output=True, text=True)
        if r.returncode != 0:
            sys.stderr.write(r.stdout + r.stderr)
            return r.returncode
        total, per_dir = digest_tree(out)
    finally:
        if os.path.exists(derived):
            os.unlink(derived)
        if not args.keep:
            shutil.rmtree(out, ignore_errors=True)
    print(f"scenario: {args.scenario}, {args.count} frames, outputs: {', '.join(ALL_OUTPUTS)}")
    for k, v in per_dir.items():
        print(f"  {k}: {v[:16]}")
    print(f"dataset_sha256={total}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
