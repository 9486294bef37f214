"""Fuzz target: scenario and scene-file YAML validation (a coverage-guided mutation fuzzer).

    .venv/bin/python fuzz/fuzz_yaml.py --seconds 600            # fuzz (bench/fuzz.sh runs this)
    .venv/bin/python fuzz/fuzz_yaml.py --replay fuzz/corpus/fuzz_yaml   # replay (make test does)

What a user's YAML reaches is run on every input: ``synthgen validate`` for scenarios
(:func:`load_scenario`, then :func:`check_inputs`, which loads every file named) and
:func:`load_scene` for scene files (validation and building, no rendering). An input is a
file named ``scenario-*`` or ``scene-*`` (its kind); it is written next to a link to the
repository's ``../shared`` so the examples' relative paths resolve.

The input passes when it is accepted or refused with :class:`SynthgenError` whose message
names the input file. Everything else is a crash: another exception (a bug in validation),
an error that does not say which file, more than ``--timeout`` seconds, or running out of
the memory limit.

Mutations (no third-party fuzzing library; Debian has none for Python 3.11): on the text --
bytes, lines, numbers replaced by boundary values, tokens of YAML syntax (anchors, aliases,
tags, flow collections) -- and on the parsed tree -- values replaced by values of other types
and boundary values, keys deleted, added (known keys from the corpus, misspellings), entries
duplicated, subtrees spliced from other inputs. Coverage (line pairs in ``synthgen`` code,
by :func:`sys.settrace`) decides which mutants join the working corpus.
"""
from __future__ import annotations

import argparse
import hashlib
import math
import os
import random
import re
import resource
import shutil
import signal
import sys
import tempfile
import time
import traceback
from typing import Any, Callable, Dict, List, Optional, Set, Tuple

import yaml

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))
sys.path.insert(0, os.path.join(ROOT, "python"))

import synthgen  # noqa: E402
from synthgen import SynthgenError  # noqa: E402

PKG_DIR = os.path.dirname(os.path.abspath(synthgen.__file__))
KINDS = ("scenario", "scene")
MAX_LEN = 64 * 1024

INTERESTING_NUMBERS = ["0", "-0", "1", "-1", "0.5", "-0.5", "2", "3", "7", "255", "256", "65535", "65536",
                       "4294967295", "4294967296", "9223372036854775807", "1e9", "1e12", "1e38", "3.5e38",
                       "1e308", "1e309", "-1e309", ".nan", ".inf", "-.inf", "nan", "inf", "0x10", "0o17",
                       "1_000", "1e-45", "1e-320", "12345678901234567890123"]
SYNTAX_TOKENS = ["&a ", "*a", "<<: *a\n", "!!str ", "!!int ", "!!float ", "!!binary ", "!!python/object:os.system ",
                 "!custom ", "[", "]", "{", "}", ", ", ": ", "- ", "? ", "|\n  ", ">\n  ", "'", '"', "#", "\t",
                 "\n", "~", "null", "true", "false", "yes", "no", "on", "off", "---\n", "...\n", "%YAML 1.1\n",
                 "\\x00", "\u00e9", "\u202e", "\ufeff", "\x00", "\x85", "\x0b"]


class Crash(Exception):
    """An input that made the target misbehave; ``kind`` says how."""

    def __init__(self, kind: str, detail: str):
        super().__init__(f"{kind}: {detail}")
        self.kind = kind
        self.detail = detail


class _Timeout(BaseException):
    pass


# Target -----------------------------------------------------------------------------------

class Target:
    """Runs one input in a scratch directory laid out like the repository (``main/scenarios``
    next to ``shared``), so the examples' relative references resolve."""

    def __init__(self, timeout: float):
        self.timeout = timeout
        self.root = tempfile.mkdtemp(prefix="synthgen-fuzz-yaml-")
        self.dir = os.path.join(self.root, "main", "scenarios")
        os.makedirs(self.dir)
        shared = os.path.abspath(os.path.join(ROOT, "..", "shared"))
        if os.path.isdir(shared):
            os.symlink(shared, os.path.join(self.root, "shared"))

    def close(self) -> None:
        shutil.rmtree(self.root, ignore_errors=True)

    def run(self, kind: str, data: bytes) -> None:
        """Raises :class:`Crash` when the input is mishandled."""
        from synthgen.scenario import check_inputs, load_scenario
        from synthgen.scene.scene_file import load_scene

        path = os.path.join(self.dir, f"input-{kind}.yaml")
        with open(path, "wb") as f:
            f.write(data)

        def on_alarm(signum, frame):
            raise _Timeout()

        old = signal.signal(signal.SIGALRM, on_alarm)
        signal.setitimer(signal.ITIMER_REAL, self.timeout)
        try:
            if kind == "scenario":
                check_inputs(load_scenario(path))
            else:
                load_scene(path)
        except _Timeout:
            raise Crash("timeout", f"more than {self.timeout:g} s") from None
        except MemoryError:
            raise Crash("oom", "MemoryError (the memory limit was reached)") from None
        except RecursionError:
            raise Crash("recursion", traceback.format_exc(limit=-8)) from None
        except SynthgenError as e:
            if path not in str(e):
                raise Crash("unnamed-error", f"the message does not name the file: {e}") from None
        except Exception:
            raise Crash("exception", traceback.format_exc(limit=-12)) from None
        finally:
            signal.setitimer(signal.ITIMER_REAL, 0)
            signal.signal(signal.SIGALRM, old)


class Coverage:
    """Edges (previous line, line) executed in synthgen's Python code."""

    def __init__(self) -> None:
        self.seen: Set[Tuple[int, int]] = set()
        self._cur: Set[Tuple[int, int]] = set()
        self._codes: Dict[Any, bool] = {}

    def _mine(self, code: Any) -> bool:
        v = self._codes.get(code)
        if v is None:
            v = self._codes[code] = code.co_filename.startswith(PKG_DIR)
        return v

    def _tracer(self, frame, event, arg):
        if event != "call" or not self._mine(frame.f_code):
            return None
        prev = [hash(frame.f_code) & 0xFFFFFFFF]
        cur = self._cur

        def local(frame, event, arg):
            if event == "line":
                h = (hash(frame.f_code) ^ frame.f_lineno) & 0xFFFFFFFF
                cur.add((prev[0], h))
                prev[0] = h
            return local

        return local

    def measure(self, fn: Callable[[], None]) -> int:
        """Runs fn; returns how many edges it reached for the first time."""
        self._cur = set()
        sys.settrace(self._tracer)
        try:
            fn()
        finally:
            sys.settrace(None)
        new = self._cur - self.seen
        self.seen |= new
        return len(new)


# Mutations --------------------------------------------------------------------------------

def _words(corpus: List[bytes]) -> List[str]:
    """Identifiers of the corpus (keys, plugin names, enum values): known words to insert."""
    words: Set[str] = set()
    for data in corpus:
        words.update(w.decode() for w in re.findall(rb"[A-Za-z_][A-Za-z0-9_]{1,40}", data))
    return sorted(words) or ["objects"]


class Mutator:
    def __init__(self, rng: random.Random, corpus: List[bytes]):
        self.rng = rng
        self.corpus = corpus
        self.words = _words(corpus)

    def value(self) -> Any:
        r = self.rng
        choice = r.randrange(14)
        if choice == 0:
            return None
        if choice == 1:
            return r.choice([True, False])
        if choice == 2:
            return r.choice([0, -1, 1, 2, 3, 255, 65536, 2 ** 31, 2 ** 63, 10 ** 30, -(10 ** 30)])
        if choice == 3:
            return r.choice([0.0, -0.0, 0.5, -0.5, 1e-320, 1e38, 3.5e38, 1e308, math.inf, -math.inf, math.nan])
        if choice == 4:
            return r.choice(["", " ", "x" * r.choice([1, 100, 5000]), "../../../../etc/passwd", "/dev/zero",
                             "/proc/self/mem", "nonexistent.obj", "\u00e9\u202e", "a" * 300 + ".png"])
        if choice == 5:
            return r.choice(self.words)
        if choice == 6:
            return []
        if choice == 7:
            return {}
        if choice == 8:
            return [self.value() for _ in range(r.randrange(1, 4))]
        if choice == 9:
            return {r.choice(self.words): self.value() for _ in range(r.randrange(1, 3))}
        if choice == 10:
            return {r.choice(["uniform", "normal", "choice", "range", "min", "max", "mean", "std", "options",
                              "weights", "values"]): self.value() for _ in range(r.randrange(1, 3))}
        if choice == 11:
            deep: Any = 1
            for _ in range(r.choice([10, 100, 400])):
                deep = [deep]
            return deep
        if choice == 12:
            return [r.random() * 10 - 5 for _ in range(r.choice([2, 3, 4, 16]))]
        return r.choice(self.words)[:-1] or "x"  # a misspelling

    @staticmethod
    def _nodes(tree: Any, out: List[Tuple[Any, Any]]) -> None:
        """(container, key) of every value in the tree."""
        if isinstance(tree, dict):
            for k in list(tree):
                out.append((tree, k))
                Mutator._nodes(tree[k], out)
        elif isinstance(tree, list):
            for i in range(len(tree)):
                out.append((tree, i))
                Mutator._nodes(tree[i], out)

    def tree(self, data: bytes) -> Optional[bytes]:
        try:
            tree = yaml.safe_load(data.decode("utf-8"))
        except Exception:
            return None
        if not isinstance(tree, (dict, list)):
            return None
        r = self.rng
        for _ in range(r.choice([1, 1, 2, 3])):
            nodes: List[Tuple[Any, Any]] = []
            self._nodes(tree, nodes)
            if not nodes:
                break
            parent, key = r.choice(nodes)
            op = r.randrange(7)
            if op <= 1:
                parent[key] = self.value()
            elif op == 2:
                del parent[key]
            elif op == 3 and isinstance(parent, dict):
                parent[r.choice(self.words)] = self.value()
            elif op == 4 and isinstance(parent, list):
                parent.insert(r.randrange(len(parent) + 1), parent[key])
            elif op == 5:
                other: List[Tuple[Any, Any]] = []
                try:
                    self._nodes(yaml.safe_load(r.choice(self.corpus).decode("utf-8")), other)
                except Exception:
                    pass
                if other:
                    p2, k2 = r.choice(other)
                    parent[key] = p2[k2]
            else:
                v = parent[key]
                if isinstance(v, (int, float)) and not isinstance(v, bool):
                    parent[key] = r.choice([v * -1, v * 1e6, v + 1, v - 1, 0, v / 3])
                elif isinstance(v, str):
                    parent[key] = v + r.choice(["x", "_", " ", "0", ".yaml"])
                else:
                    parent[key] = self.value()
        try:
            return yaml.safe_dump(tree, allow_unicode=True, sort_keys=False, width=r.choice([80, 10 ** 6])).encode()
        except Exception:
            return None

    def text(self, data: bytes) -> bytes:
        r = self.rng
        b = bytearray(data)
        for _ in range(r.choice([1, 1, 2, 4])):
            op = r.randrange(9)
            pos = r.randrange(len(b) + 1)
            if op == 0 and b:
                del b[pos:pos + r.randrange(1, 9)]
            elif op == 1 and b:
                b[min(pos, len(b) - 1)] = r.randrange(256)
            elif op == 2:
                b[pos:pos] = r.choice(SYNTAX_TOKENS).encode("utf-8", "surrogatepass")
            elif op == 3:
                nums = list(re.finditer(rb"-?\d+(\.\d+)?(e-?\d+)?", bytes(b)))
                if nums:
                    m = r.choice(nums)
                    b[m.start():m.end()] = r.choice(INTERESTING_NUMBERS).encode()
            elif op == 4:
                lines = bytes(b).split(b"\n")
                i, j = r.randrange(len(lines)), r.randrange(len(lines))
                what = r.randrange(3)
                if what == 0:
                    lines.insert(j, lines[i])
                elif what == 1 and len(lines) > 1:
                    del lines[i]
                else:
                    lines[i], lines[j] = lines[j], lines[i]
                b = bytearray(b"\n".join(lines))
            elif op == 5:
                other = r.choice(self.corpus).split(b"\n")
                lines = bytes(b).split(b"\n")
                a = r.randrange(len(other))
                lines[r.randrange(len(lines)):r.randrange(len(lines) + 1)] = other[a:a + r.randrange(1, 6)]
                b = bytearray(b"\n".join(lines))
            elif op == 6:
                b[pos:pos] = (r.choice(self.words) + r.choice([": ", ":", " ", "\n"])).encode()
            elif op == 7:
                lines = bytes(b).split(b"\n")
                i = r.randrange(len(lines))
                lines[i] = b" " * r.choice([1, 2, 4]) + lines[i] if r.random() < 0.5 else lines[i].lstrip()
                b = bytearray(b"\n".join(lines))
            else:
                b[pos:pos] = r.choice(self.words).encode()
        return bytes(b[:MAX_LEN])

    def mutate(self, data: bytes) -> bytes:
        if self.rng.random() < 0.5:
            out = self.tree(data)
            if out is not None:
                return out[:MAX_LEN]
        return self.text(data)


# Driver -------------------------------------------------------------------------------------

def kind_of(name: str) -> str:
    base = os.path.basename(name)
    for k in KINDS:
        if base.startswith(k + "-") or base.startswith("crash-" + k + "-"):
            return k
    return "scenario"


def seed_corpus() -> List[Tuple[str, bytes]]:
    """The example scenarios and scene files of scenarios/, by kind."""
    out = []
    for f in sorted(os.listdir(os.path.join(ROOT, "scenarios"))):
        if not f.endswith(".yaml"):
            continue
        data = open(os.path.join(ROOT, "scenarios", f), "rb").read()
        kind = "scenario" if re.search(rb"^count:", data, re.M) else "scene"
        out.append((f"{kind}-{f}", data))
    return out


def read_dir(d: str) -> List[Tuple[str, bytes]]:
    if not os.path.isdir(d):
        return [(d, open(d, "rb").read())] if os.path.isfile(d) else []
    return [(f, open(os.path.join(d, f), "rb").read()) for f in sorted(os.listdir(d))
            if os.path.isfile(os.path.join(d, f)) and not f.endswith(".txt")]


def limit_memory(megabytes: int) -> None:
    cap = megabytes << 20
    resource.setrlimit(resource.RLIMIT_AS, (cap, cap))


def replay(paths: List[str], timeout: float) -> int:
    target = Target(timeout)
    n = failed = 0
    try:
        for p in paths:
            for name, data in read_dir(p):
                n += 1
                try:
                    target.run(kind_of(name), data)
                except Crash as c:
                    failed += 1
                    print(f"{name}: {c}", file=sys.stderr)
    finally:
        target.close()
    print(f"replayed {n} input(s), {failed} crash(es)")
    return 1 if failed or not n else 0


def fuzz(args: argparse.Namespace) -> int:
    rng = random.Random(args.seed)
    os.makedirs(args.corpus, exist_ok=True)
    os.makedirs(args.crashes, exist_ok=True)
    entries: List[Tuple[str, bytes]] = []
    for name, data in seed_corpus() + read_dir(os.path.join(ROOT, "fuzz", "corpus", "fuzz_yaml")) + read_dir(args.corpus):
        entries.append((kind_of(name), data))
    target = Target(args.timeout)
    cov = Coverage()
    corpus: List[Tuple[str, bytes]] = []
    crashes = 0
    execs = 0

    def run(kind: str, data: bytes) -> Tuple[int, Optional[Crash]]:
        crash: List[Crash] = []

        def go():
            try:
                target.run(kind, data)
            except Crash as c:
                crash.append(c)

        return cov.measure(go), (crash[0] if crash else None)

    def record_crash(kind: str, data: bytes, c: Crash) -> None:
        nonlocal crashes
        h = hashlib.sha1(data).hexdigest()
        name = f"crash-{kind}-{h[:12]}"
        path = os.path.join(args.crashes, name)
        if not os.path.exists(path):
            crashes += 1
            with open(path, "wb") as f:
                f.write(data)
            with open(path + ".txt", "w") as f:
                f.write(str(c) + "\n")
            print(f"CRASH {name}: {str(c).splitlines()[0]}", file=sys.stderr)
            print(str(c), file=sys.stderr)

    start = time.monotonic()
    for kind, data in entries:
        new, c = run(kind, data)
        execs += 1
        if c:
            record_crash(kind, data, c)
        else:
            corpus.append((kind, data))
    if not corpus:
        print("fuzz_yaml: no usable seed", file=sys.stderr)
        return 2
    mut = Mutator(rng, [d for _, d in corpus])
    while time.monotonic() - start < args.seconds and (args.runs is None or execs < args.runs):
        kind, parent = rng.choice(corpus)
        child = mut.mutate(parent)
        new, c = run(kind, child)
        execs += 1
        if c:
            record_crash(kind, child, c)
        elif new:
            corpus.append((kind, child))
            mut.corpus.append(child)
            h = hashlib.sha1(child).hexdigest()[:12]
            with open(os.path.join(args.corpus, f"{kind}-{h}"), "wb") as f:
                f.write(child)
    target.close()
    print(f"stat::number_of_executed_units: {execs}")
    print(f"fuzz_yaml: executions={execs} crashes={crashes} seconds={args.seconds:g} corpus={len(corpus)} "
          f"edges={len(cov.seen)}")
    return 1 if crashes else 0


def main(argv: Optional[List[str]] = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--replay", nargs="+", metavar="PATH", help="run these inputs (files or directories) once")
    p.add_argument("--seconds", type=float, default=60.0)
    p.add_argument("--runs", type=int, default=None, help="stop after this many executions")
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--timeout", type=float, default=20.0, help="seconds per input")
    p.add_argument("--memory-mb", type=int, default=4096, help="address-space limit of this process")
    p.add_argument("--corpus", default=os.path.join(ROOT, "build-fuzz", "corpus", "fuzz_yaml"))
    p.add_argument("--crashes", default=os.path.join(ROOT, "build-fuzz", "crashes", "fuzz_yaml"))
    args = p.parse_args(argv)
    synthgen.load_image_plugin()  # before the limit: OpenImageIO maps much address space
    if args.memory_mb:
        limit_memory(args.memory_mb)
    if args.replay:
        return replay(args.replay, args.timeout)
    return fuzz(args)


if __name__ == "__main__":
    sys.exit(main())
