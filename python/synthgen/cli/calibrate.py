"""``synthgen calibrate PHOTO``: reads a photo's calibration (sidecar, folder file, or
--calibration) and draws it over the photo: horizon, a metric ground grid, the placement
region, real labels and ignore regions, a reference car at three distances. Prints the
calibration, per labelled car how wide its box is against a real car turned along the road there
(its width seen from behind, its length from the side), and what in its geometry would let
nothing stand in the photo (synthgen.background.geometry: errors, exit status 2) or is
suspicious (warnings)."""
from __future__ import annotations

import argparse
import os
import sys

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
    from ..background.geometry import geometry_findings
    from ..background.preview import CAR_LENGTH, CAR_WIDTH, REFERENCE_CAR, draw_preview, label_checks
    from ..scenario.schema import BACKGROUND
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
        elif chk["expected"] is None:
            print(f"    {chk['class']} {[round(v) for v in chk['box']]}: {chk['distance']:.1f} m away")
        else:
            lo, hi = chk["expected"]
            flag = "" if chk["plausible"] else ("  <- not a car's size there: check camera_height, the horizon and "
                                                "the field of view (or the car is partly hidden, or not along the "
                                                "road)")
            print(f"    {chk['class']} {[round(v) for v in chk['box']]}: {chk['distance']:.1f} m away, seen "
                  f"{chk['angle']:.0f} deg off the road's direction; its box is {chk['box_width']:.0f} px wide, a car "
                  f"({CAR_LENGTH[0]:g} to {CAR_LENGTH[1]:g} m long, {CAR_WIDTH[0]:g} to {CAR_WIDTH[1]:g} m wide) "
                  f"turned along the road {lo:.0f} to {hi:.0f} px there{flag}")
    near, far = (BACKGROUND.fields[k].default for k in ("min_distance", "max_distance"))
    findings = geometry_findings(setup, near, far, [("a car (the reference car)", REFERENCE_CAR[0], REFERENCE_CAR[1])],
                                 distance_keys="background.min_distance .. max_distance's defaults", scenario=False)
    for f in findings:
        print(f"{'error' if f.error else 'warning'}: {f}", file=sys.stderr)
    print(f"preview: {out}")
    return 2 if any(f.error for f in findings) else 0


register(Command("calibrate", "check a photo's calibration on a preview",
                 "Read a photo's calibration (PHOTO.yaml, the folder's calibration.yaml, or --calibration) and "
                 "draw it over the photo: the horizon, a metric ground grid, the placement region, the real labels "
                 "and ignore regions, and a reference car at 8, 15 and 30 m ahead, turned along the road. Prints the calibration "
                 "and, per labelled car, its box's width against a real car's there (seen from behind or from the "
                 "side: road_direction); errors (exit status 2) where nothing could stand in the photo, warnings "
                 "where its geometry is suspicious.", add_arguments, run, order=47, module=__name__))
