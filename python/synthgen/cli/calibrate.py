"""``synthgen calibrate PHOTO``: reads a photo's calibration (sidecar, folder file, or
--calibration) and draws it over the photo: horizon, a metric ground grid, the placement
region, real labels and ignore regions, a reference car at three distances. Prints the
calibration and, per labelled car, the width the calibration gives it."""
from __future__ import annotations

import argparse
import os

from . import Command, register


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("photo", metavar="PHOTO")
    p.add_argument("-o", "--output", metavar="PNG", help="preview file (default: PHOTO's name + .calibration.png "
                                                        "in the current directory)")
    p.add_argument("--calibration", metavar="FILE", help="a calibration file shared by photos (as the scenario's "
                                                         "background.calibration)")
    p.add_argument("--classes", metavar="NAMES", help="the scenario's classes, comma-separated: real labels of "
                                                      "other classes are refused, as synthgen validate does")


def run(args: argparse.Namespace) -> int:
    from ..background.photos import load_photo
    from ..background.preview import draw_preview, label_checks
    from ..background.sidecar import read_photo_setup
    from ..outputs.files import to_srgb8

    photo = load_photo(args.photo)
    setup = read_photo_setup(photo.path, photo.width, photo.height, shared=args.calibration,
                             exif_focal_mm=photo.exif_focal_mm, exif_focal_35mm=photo.exif_focal_35mm)
    if args.classes is not None:
        from ..background.labels import check_classes

        check_classes(setup.label_files, setup.objects, [c for c in args.classes.split(",") if c], photo.path)
    c = setup.calibration
    out = args.output or os.path.splitext(os.path.basename(args.photo))[0] + ".calibration.png"
    draw_preview(to_srgb8(photo.pixels), setup, out)
    print(f"{args.photo}: {photo.width} x {photo.height}, {photo.format}"
          + (f", JPEG quality ~{photo.jpeg_quality:.0f}" if photo.jpeg_quality else ""))
    print(f"  intrinsics fx {c.fx:.1f} fy {c.fy:.1f} cx {c.cx:.1f} cy {c.cy:.1f}; distortion "
          f"{', '.join(f'{k:g}' for k in c.distortion)} ({c.source})")
    print(f"  camera {c.camera_height:.2f} m above the ground, pitch {c.pitch:.2f} deg, roll {c.roll:.2f} deg; road "
          f"direction {setup.road_direction:g} deg")
    for a in c.assumptions:
        print(f"  assumed: {a}")
    if setup.sun is not None:
        print(f"  sun: azimuth {setup.sun[0]:.1f} deg, elevation {setup.sun[1]:.1f} deg ({setup.sun_source})")
    for lf in setup.label_files:
        print(f"  labels {lf.path} ({lf.format}): {lf.describe()}")
    real = [o for o in setup.objects if not o.ignore]
    print(f"  real objects: {len(real)} labelled, {len(setup.objects) - len(real)} ignore regions"
          + ("" if setup.labelled else " (the photo declares no labels)"))
    for chk in label_checks(setup):
        if chk["distance"] is None:
            print(f"    {chk['class']} {[round(v) for v in chk['box']]}: its bottom is above the horizon")
        else:
            flag = "" if 1.5 <= chk["width"] <= 2.1 else \
                "  <- a car seen from behind is 1.6 to 2.0 m wide (seen at an angle, its box holds its side too)"
            print(f"    {chk['class']} {[round(v) for v in chk['box']]}: {chk['distance']:.1f} m away, "
                  f"{chk['width']:.2f} m wide{flag}")
    print(f"preview: {out}")
    return 0


register(Command("calibrate", "check a photo's calibration on a preview",
                 "Read a photo's calibration (PHOTO.yaml, the folder's calibration.yaml, or --calibration) and "
                 "draw it over the photo: the horizon, a metric ground grid, the placement region, the real labels "
                 "and ignore regions, and a reference car at 8, 15 and 30 m ahead, turned along the road. Prints the calibration "
                 "and the width it gives each labelled car.", add_arguments, run, order=47, module=__name__))
