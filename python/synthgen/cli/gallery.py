"""``synthgen gallery``: render the wear gallery."""
from __future__ import annotations

import argparse
import os

from . import Command, register
from .common import EXIT_OK, positive_int


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("-o", "--output", metavar="FILE.png", default=os.path.join("out", "gallery.png"))
    p.add_argument("--spp", type=positive_int, default=32, help="samples per pixel of each tile (default 32)")
    p.add_argument("--car", metavar="FILE.png", help="also render the car row (the library car at dataset "
                                                     "resolution, clean and with each effect) into this file")
    p.add_argument("--weather", metavar="FILE.png", help="also render the weather row (one frame of --scenario under "
                                                         "each weather condition) into this file")
    p.add_argument("--scenario", default=os.path.join("scenarios", "vehicles.yaml"),
                   help="the weather row's street scenario (default scenarios/vehicles.yaml)")
    p.add_argument("--frame", type=int, default=0, help="the weather row's frame of --scenario (default 0)")


def run(args: argparse.Namespace) -> int:
    from ..frame import gallery

    os.makedirs(os.path.dirname(os.path.abspath(args.output)), exist_ok=True)
    print(gallery.write_gallery(args.output, spp=args.spp))
    if args.car:
        os.makedirs(os.path.dirname(os.path.abspath(args.car)), exist_ok=True)
        print(gallery.write_car_row(args.car, spp=args.spp))
    if args.weather:
        os.makedirs(os.path.dirname(os.path.abspath(args.weather)), exist_ok=True)
        print(gallery.write_weather_row(args.weather, args.scenario, frame=args.frame, spp=args.spp))
    return EXIT_OK


register(Command("gallery", "render the wear gallery",
                 "Render every wear effect on a sign, a car body panel and a sphere, with the parameters under each "
                 "tile (and, with --car, on a library car at dataset resolution).", add_arguments, run, order=70,
                 module=__name__))
