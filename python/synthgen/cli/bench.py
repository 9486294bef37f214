"""``synthgen bench``: speed against accuracy -- PSNR against render time of synthgen's sampling
methods, Blender Cycles and Embree's tutorial path tracer (synthgen.bench.speed)."""
from __future__ import annotations

import argparse
import os
import tempfile
from typing import List

from . import Command, register
from .common import nonnegative_int, positive_int

#: --quick: image size, budgets and reference samples (CI: well under a minute without peers).
QUICK = {"width": 64, "height": 48, "budgets": [4, 16], "ref_spp": 256}


def scene_list(text: str) -> List[str]:
    """Comma-separated scene names, each one of synthgen.bench.speed.SCENES."""
    from ..bench.speed import SCENES

    names = [s.strip() for s in text.split(",") if s.strip()]
    bad = [s for s in names if s not in SCENES]
    if bad or not names:
        raise argparse.ArgumentTypeError(f"unknown scene(s) {', '.join(bad) or repr(text)}; valid scenes: "
                                         f"{', '.join(SCENES)}")
    return list(dict.fromkeys(names))


def budget_list(text: str) -> List[int]:
    """Comma-separated samples-per-pixel budgets, at least two, increasing."""
    try:
        v = [int(x) for x in text.split(",") if x.strip()]
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected comma-separated positive integers, got {text!r}") from None
    if len(v) < 2 or min(v) < 1 or any(b <= a for a, b in zip(v, v[1:])):
        raise argparse.ArgumentTypeError(f"expected at least two increasing positive integers, got {text!r}")
    return v


def seconds_list(text: str) -> List[float]:
    try:
        v = [float(x) for x in text.split(",") if x.strip()]
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected comma-separated seconds, got {text!r}") from None
    if len(v) < 2 or min(v) <= 0 or any(b <= a for a, b in zip(v, v[1:])):
        raise argparse.ArgumentTypeError(f"expected at least two increasing positive times, got {text!r}")
    return v


def add_arguments(p: argparse.ArgumentParser) -> None:
    from ..bench.speed import SCENES, Options

    d = Options()
    p.add_argument("--scenes", type=scene_list, default=list(d.scenes), metavar="A,B",
                   help=f"scenes (default: all of {','.join(SCENES)})")
    p.add_argument("-o", "--output", metavar="DIR", default=d.out_dir,
                   help=f"output directory: benchmarks_table.md, speed_accuracy.png, results.json (default {d.out_dir})")
    p.add_argument("--budgets", type=budget_list, metavar="N,N,...",
                   help=f"samples-per-pixel ladder (default {','.join(map(str, d.budgets))}; --quick "
                        f"{','.join(map(str, QUICK['budgets']))})")
    p.add_argument("--width", type=positive_int, metavar="W", help=f"image width (default {d.width}; --quick {QUICK['width']})")
    p.add_argument("--height", type=positive_int, metavar="H",
                   help=f"image height (default {d.height}; --quick {QUICK['height']})")
    p.add_argument("--threads", type=nonnegative_int, default=d.threads, metavar="T",
                   help=f"render threads of every renderer (default {d.threads})")
    p.add_argument("--ref-spp", type=positive_int, metavar="N",
                   help=f"samples of the converged references (default {d.ref_spp}; --quick {QUICK['ref_spp']})")
    p.add_argument("--ref-dir", metavar="DIR",
                   help="cache of the references (default DIR/references; --quick: a temporary directory)")
    p.add_argument("--chart", metavar="PNG", help="chart path (default DIR/speed_accuracy.png)")
    p.add_argument("--noise-threshold", type=float, default=d.noise_threshold, metavar="T",
                   help=f"synthgen adaptive methods' noise_threshold (default {d.noise_threshold})")
    p.add_argument("--cycles-threshold", type=float, default=d.cycles_threshold, metavar="T",
                   help=f"Cycles adaptive_threshold (default {d.cycles_threshold}, Blender's; 0 = Cycles' automatic)")
    p.add_argument("--cycles-time-limits", type=seconds_list, metavar="S,S,...",
                   help="Cycles budgets as time limits (cycles.time_limit, samples up to --ref-spp) instead of "
                        "the spp budgets")
    p.add_argument("--runs", type=positive_int, default=d.runs, metavar="N",
                   help="renders per point; the median time is used (default 1)")
    p.add_argument("--no-peers", action="store_true", help="synthgen's methods only (no Blender, no Embree)")
    p.add_argument("--quick", action="store_true",
                   help=f"CI mode: {QUICK['width']}x{QUICK['height']}, budgets {','.join(map(str, QUICK['budgets']))}, "
                        f"{QUICK['ref_spp']}-spp references in a temporary directory")


def run(args: argparse.Namespace) -> int:
    from ..bench.speed import Options, last_line, run_benchmark

    q = QUICK if args.quick else {}
    d = Options()
    o = Options(scenes=args.scenes, out_dir=args.output, budgets=args.budgets or q.get("budgets", d.budgets),
                width=args.width or q.get("width", d.width), height=args.height or q.get("height", d.height),
                threads=args.threads, ref_spp=args.ref_spp or q.get("ref_spp", d.ref_spp), ref_dir=args.ref_dir,
                chart=args.chart, noise_threshold=args.noise_threshold, cycles_threshold=args.cycles_threshold,
                cycles_time_limits=args.cycles_time_limits or (), runs=args.runs, peers=not args.no_peers,
                quick=args.quick, say=lambda s: print(s, flush=True))
    if args.quick and args.ref_dir is None:
        with tempfile.TemporaryDirectory(prefix="synthgen_bench_refs_") as refs:
            o.ref_dir = os.path.join(refs, "references")
            result = run_benchmark(o)
    else:
        result = run_benchmark(o)
    print(last_line(result["speedup"]), flush=True)
    return 0


register(Command("bench", "speed against accuracy: PSNR vs render time of synthgen, Cycles and Embree",
                 "Render each scene with synthgen's sampling methods (uniform, adaptive, adaptive + denoise), "
                 "Blender Cycles (CPU, its adaptive sampling) and Embree's tutorial pathtracer (its Cornell box) at "
                 "a ladder of budgets; PSNR of each against a converged image of the same renderer (cached). Writes "
                 "DIR/speed_accuracy.png, DIR/benchmarks_table.md and DIR/results.json; prints each scene's time to "
                 "35 dB per method. Last line: time_to_35db_speedup_vs_cycles=<geometric mean over scenes of Cycles' "
                 "time to 35 dB / synthgen's best method's>, nan when no scene has both. See docs/benchmarks.md.",
                 add_arguments, run, order=90, module=__name__))
