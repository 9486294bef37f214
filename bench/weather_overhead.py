#!/usr/bin/env python3
"""Render time of the same street frames clear and in weather (docs/weather.md): frames of
scenarios/weather.yaml rendered with its weather section replaced -- clear air, homogeneous
fog (visibility 100 m, a 40 m layer), heterogeneous ground fog (banks of visibility 40 m,
scale height 3 m), night (street lights and the twilight sky's night) -- in turn per frame,
each render timed by the runner's own render stage (path tracing and the denoiser), medians
over the frames and repeats. The last three lines are exactly

    fog_overhead_pct=<float>
    ground_fog_overhead_pct=<float>
    night_overhead_pct=<float>

(median time in that weather / median clear time - 1, in percent).

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
GROUND_FOG = {"ground_fog": {"visibility": 40.0, "scale_height": 3.0}}


def main(argv=None) -> int:
    from synthgen.frame.renderer import FrameRenderer
    from synthgen.scenario import check_inputs, load_scenario

    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--frames", type=int, default=3)
    ap.add_argument("--repeats", type=int, default=2)
    ap.add_argument("--resolution", type=int, nargs=2, default=(640, 480))
    ap.add_argument("--spp", type=int, default=32)
    args = ap.parse_args(argv)

    from synthgen.randomize.weather.night import street_night

    NIGHT = street_night()  # the same street at night: street lights outside the plot, lamps on
    cases = [("clear", {}), ("fog", FOG), ("ground_fog", GROUND_FOG), ("night", NIGHT)]
    renderers = {}
    for name, weather in cases:
        sc = load_scenario(SCENARIO, overrides=[("weather", weather), ("resolution", list(args.resolution)),
                                                ("render.spp", args.spp)])
        check_inputs(sc)
        renderers[name] = FrameRenderer(sc)
    print(f"scenario: {os.path.relpath(SCENARIO, REPO)} frames 0..{args.frames - 1}, "
          f"{args.resolution[0]}x{args.resolution[1]}, {args.spp} spp, render settings as the scenario's "
          f"(denoised); {FOG}, {GROUND_FOG}, {NIGHT}")
    times = {name: [] for name, _ in cases}
    for rep in range(args.repeats):
        for k in range(args.frames):
            for name, _ in cases:
                _, meta, t = renderers[name].render(k)
                times[name].append(t["render_s"])
                print(f"repeat {rep} frame {k} {name:5s}: render {t['render_s']:.3f} s, weather {meta['weather']}",
                      flush=True)
    med = {k: statistics.median(v) for k, v in times.items()}
    print("median render s: " + ", ".join(f"{k} {v:.3f}" for k, v in med.items()))
    for name in ("fog", "ground_fog", "night"):
        print(f"{name}_overhead_pct={100.0 * (med[name] / med['clear'] - 1.0):.1f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
