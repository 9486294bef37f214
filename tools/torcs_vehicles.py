#!/usr/bin/env python3
"""Prints assets-manifest entries for TORCS cars (Debian torcs-data): the body model, its
textures (companions, with checksums), and what the TORCS car file says of its wheels (axle
positions, track, tyre and rim sizes) and ride height. TORCS draws the wheels itself; synthgen
builds them from these numbers (synthgen.scene.vehicles).

    .venv/bin/python tools/torcs_vehicles.py ROOT CAR [CAR ...]   # ROOT: a dpkg -x of torcs-data

Model axes: TORCS' x is forward; assimp reads the AC3D bodies with y up (checked by rendering:
the headlights are at +x). The licence of each car is from the package's copyright file:
the cars listed under "Free-Art-License" there, GPL-2+ otherwise.
"""
from __future__ import annotations

import hashlib
import os
import re
import sys
import xml.etree.ElementTree as ET

FREE_ART = {"acura-nsx-sz", "baja-bug", "car1-trb1", "car1-ow1", "car8-trb1", "car2-trb1", "car6-trb1", "car7-trb1",
            "car1-stock2", "car3-trb1", "car1-trb3", "car5-trb1", "car1-stock1", "car4-trb1"}
CARS = "/usr/share/games/torcs/cars"


def sha(path: str) -> str:
    return hashlib.sha256(open(path, "rb").read()).hexdigest()


def num(sec, name: str) -> float:
    for a in sec.iter("attnum"):
        if a.get("name") == name:
            v, u = float(a.get("val")), a.get("unit", "")
            return {"mm": v / 1000.0, "in": v * 0.0254}.get(u, v)
    raise KeyError(name)


def main(argv) -> int:
    root, cars = argv[1], argv[2:]
    for car in cars:
        d = os.path.join(root, CARS.lstrip("/"), car)
        text = open(os.path.join(d, car + ".xml"), encoding="latin-1").read()
        text = re.sub(r"<!DOCTYPE[^>]*>", "", re.sub(r"&[a-z]+;", "", text))
        x = ET.fromstring(text)
        sec = {s.get("name"): s for s in x.iter("section")}
        axles = [num(sec["Front Axle"], "xpos"), num(sec["Rear Axle"], "xpos")]
        wheels = [sec[n] for n in ("Front Right Wheel", "Front Left Wheel", "Rear Right Wheel", "Rear Left Wheel")]
        track = [round(num(wheels[0], "ypos") * -1 + num(wheels[1], "ypos"), 3),
                 round(num(wheels[2], "ypos") * -1 + num(wheels[3], "ypos"), 3)]
        rim = num(wheels[0], "rim diameter") / 2
        width = num(wheels[0], "tire width")
        radius = rim + width * num(wheels[0], "tire height-width ratio")
        ride = sum(num(w, "ride height") for w in wheels) / 4
        texs = sorted({m for m in re.findall(r'texture "([^"]+)"', open(os.path.join(d, car + ".acc"),
                                                                           encoding="latin-1").read())})
        print(f"- id: mesh/torcs-{car}")
        print("  kind: mesh")
        print("  class: car")
        print("  optional: true")
        print(f"  licence: {'Free-Art-1.3' if car in FREE_ART else 'GPL-2.0-or-later'}")
        print(f"  description: TORCS car {car} (Debian torcs-data), textured body; wheels built from its car file")
        print("  scale: 1.0")
        print('  forward: "+x"')
        print('  up: "+y"')
        print(f"  ride_height: {ride:.3f}")
        print(f"  wheels: {{axles: [{axles[0]:.3f}, {axles[1]:.3f}], track: [{track[0]:.3f}, {track[1]:.3f}], "
              f"radius: {radius:.4f}, width: {width:.3f}, rim_radius: {rim:.4f}}}")
        print("  source:")
        print("    deb: torcs-data")
        print(f"    path: {CARS}/{car}/{car}.acc")
        print(f"  sha256: {sha(os.path.join(d, car + '.acc'))}")
        if texs:
            print("  companions:")
            for t in texs:
                print(f"  - path: {CARS}/{car}/{t}")
                print(f"    sha256: {sha(os.path.join(d, t))}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
