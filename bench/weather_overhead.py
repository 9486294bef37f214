#!/usr/bin/env python3
"""Render time of the same street frames clear and in weather (docs/weather.md): frames of
scenarios/weather.yaml rendered with its weather section replaced -- clear air, then
homogeneous fog (visibility 100 m, a 40 m layer) -- alternating per frame, each render timed
by the runner's own render stage (path tracing and the denoiser), medians over the frames and
repeats. The last three lines are exactly

    fog_overhead_pct=<float>
    ground_fog_overhead_pct=<float>
    night_overhead_pct=<float>

(median fog time / median clear time - 1, in percent; `nan` where the weather does not exist
yet: heterogeneous ground fog and night with lights are still to come in issue [6/9]).

    .venv/bin/python bench/weather_overhead.py [--frames 3] [--repeats 2] [--resolution 640 480] [--spp 32]
"""
from __future__ import annotations

import argparse
import os
import statistics
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.abspath(os.path.join(HERE, ".."))
sys.path.insert(0, os.path.join(REPO, "python"))

SCENARIO = os.path.join(REPO, "scenarios", "weather.yaml")
FOG = {"fog": {"visibility": 100.0, "top": 40.0}}


def main(argv=None) -> int:
    from synthgen.frame.renderer import FrameRenderer
    from synthgen.scenario import check_inputs, load_scenario

    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--frames", type=int, default=3)
    ap.add_argument("--repeats", type=int, default=2)
    ap.add_argument("--resolution", type=int, nargs=2, default=(640, 480))
    ap.add_argument("--spp", type=int, default=32)
    args = ap.parse_args(argv)

    renderers = {}
    for name, weather in (("clear", {}), ("fog", FOG)):
        sc = load_scenario(SCENARIO, overrides=[("weather", weather), ("resolution", list(args.resolution)),
                                                ("render.spp", args.spp)])
        check_inputs(sc)
        renderers[name] = FrameRenderer(sc)
    print(f"scenario: {os.path.relpath(SCENARIO, REPO)} frames 0..{args.frames - 1}, "
          f"{args.resolution[0]}x{args.resolution[1]}, {args.spp} spp, render settings as the scenario's "
          f"(denoised); fog: visibility {FOG['fog']['visibility']} m, layer top {FOG['fog']['top']} m")
    times = {"clear": [], "fog": []}
    for rep in range(args.repeats):
        for k in range(args.frames):
            for name in ("clear", "fog"):
                _, meta, t = renderers[name].render(k)
                times[name].append(t["render_s"])
                print(f"repeat {rep} frame {k} {name:5s}: render {t['render_s']:.3f} s, weather {meta['weather']}",
                      flush=True)
    med = {k: statistics.median(v) for k, v in times.items()}
    print(f"median render s: clear {med['clear']:.3f}, fog {med['fog']:.3f}")
    print("ground fog (heterogeneous media) and night with lights: not implemented yet (nan)")
    print(f"fog_overhead_pct={100.0 * (med['fog'] / med['clear'] - 1.0):.1f}")
    print("ground_fog_overhead_pct=nan")
    print("night_overhead_pct=nan")
    return 0


if __name__ == "__main__":
    sys.exit(main())
