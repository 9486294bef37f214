"""Pure synthetic frames for bench/sim2real.py (issue 34: ``sim2real_car_ap50_pure``): a synthgen
scenario whose camera matches the real side-facing rig of ``../shared/realdata/cars_highway``
(676 x 380, the rig's horizontal field of view, lens distortion, height and horizon row) looking across a
multi-lane road with library cars driving along its lanes, clutter that is not a car, and a
sky or an HDR for light. No real pixels: everything in the frames is rendered.

Contract of :func:`write_pure_scenario`: it writes one scenario file (YAML; synthgen validates
it) and returns its path; the same arguments write the same bytes (the ground variants are
drawn from ``seed``), and ``synthgen run`` of it with that seed gives bit-identical frames.
Outputs are rgb and coco (plus any ``outputs`` given); every car is labelled ``car``.

The scene (world metres, y up; the road runs along x, the camera looks along +z across it):

- camera at x ~ 0, height ``rig["camera_height"]`` (+-0.05), z in ``CAMERA_Z`` (so the far
  carriageway is 5 to 20 m away, as the real cars are), pitched down so that the horizon lies
  on row ``rig["horizon"]`` (+-``PITCH_JITTER`` degrees), turned up to +-4.5 degrees off
  perpendicular to the road;
- the far carriageway: ``LANES`` lanes of ``LANE_WIDTH`` m from z = ``ROAD_Z``, cars on each
  lane (both directions, a few per lane, spaced by the placement's footprint test); in front of
  it a median (grass, concrete, or a painted double line) of random width and the camera's own
  carriageway or verge, beyond it a shoulder, kerb and verge: the ground is one of
  ``GROUND_VARIANTS`` textured layouts drawn per frame;
- clutter (unlabelled): tree crowns and conifers in a tree line, bushes on the verge, poles,
  road signs, buildings;
- light: a Preetham sky (random sun, turbidity) or one of the library's HDRs, rotated;
  auto-exposure (scenario version 2) with 0 to 1 stop less.

Cars at least a quarter visible (placement.min_visible_fraction 0.25) are kept; cars that find no
such place in a frame are left out of it (placement.allow_drops: the labels stay exact).

    .venv/bin/python bench/sim2real/pure.py -o out/pure -n 30   # render, seconds/frame, box heights vs real

The rig's ``distortion`` (OpenCV k1, k2, p1, p2[, k3], as ``synthgen calibrate`` gives it) goes
into the scenario camera (camera.k1 ...: the frames are rendered through that lens).
"""
from __future__ import annotations

import json
import math
import os
import sys
from typing import Any, Dict, List, Optional, Sequence

import numpy as np
import yaml

REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
if os.path.join(REPO, "python") not in sys.path:
    sys.path.insert(0, os.path.join(REPO, "python"))

from synthgen import SynthgenError  # noqa: E402

#: The real rig (docs/augmented_photos.md's first guess for cars_highway).
RIG = {"fov_x": 90.0, "camera_height": 1.45, "horizon": 188.0, "distortion": None}
RESOLUTION = (676, 380)
#: The far carriageway: its near edge (world z, metres), lanes and their width.
ROAD_Z = 6.0
LANES = 3
LANE_WIDTH = 3.6
#: Where the camera stands across the road (world z): the lanes' centres are then
#: ROAD_Z + 1.8 - z ... = 4.8 to 20.8 m away.
CAMERA_Z = (-4.0, 1.0)
#: Random pitch about the rig's (degrees; the real horizon moves with the road's slope).
PITCH_JITTER = 1.0
#: Yaw off perpendicular to the road (degrees).
YAW_JITTER = 4.5
GROUND_VARIANTS = 12

# Albedos (linear RGB).
ASPHALT = [(0.16, 0.16, 0.16), (0.12, 0.12, 0.125), (0.2, 0.195, 0.19), (0.09, 0.09, 0.095)]
CONCRETE = [(0.42, 0.41, 0.38), (0.33, 0.32, 0.3), (0.5, 0.49, 0.46)]
GRASS = [(0.08, 0.14, 0.04), (0.12, 0.15, 0.06), (0.17, 0.16, 0.08), (0.06, 0.11, 0.035)]
WHITE = (0.7, 0.7, 0.68)
YELLOW = (0.6, 0.45, 0.08)
KERB = (0.45, 0.44, 0.42)


def _rig(rig: Optional[Dict[str, Any]]) -> Dict[str, float]:
    r = dict(RIG)
    for k, v in (rig or {}).items():
        if k not in RIG:
            raise SynthgenError(f"write_pure_scenario: rig key {k!r} unknown (known: {', '.join(RIG)})")
        r[k] = v
    if r["distortion"] is not None:
        d = list(r["distortion"])
        if len(d) not in (4, 5) or not all(isinstance(v, (int, float)) and math.isfinite(v) for v in d):
            raise SynthgenError(f"write_pure_scenario: rig distortion {d}: expected OpenCV's 4 or 5 numbers "
                                "[k1, k2, p1, p2(, k3)]")
        r["distortion"] = [float(v) for v in d] + [0.0] * (5 - len(d))
    if not 0.0 < float(r["fov_x"]) < 180.0:
        raise SynthgenError(f"write_pure_scenario: rig fov_x {r['fov_x']}: must lie in (0, 180) degrees")
    if not float(r["camera_height"]) > 0.1:
        raise SynthgenError(f"write_pure_scenario: rig camera_height {r['camera_height']}: must exceed 0.1 m")
    return {k: (float(v) if k != "distortion" else v) for k, v in r.items()}


def _lens(r: Dict[str, Any]) -> Dict[str, float]:
    """The scenario camera's distortion keys of a rig (none for a lens without distortion)."""
    d = r["distortion"] or [0.0] * 5
    return {k: float(v) for k, v in zip(("k1", "k2", "p1", "p2", "k3"), d) if float(v) != 0.0}


def _ramp(bands: Sequence[tuple], z0: float, z1: float) -> Dict[str, Any]:
    """A gradient texture along world z over [z0, z1] with hard-edged colour bands
    ``(z_start, z_end, rgb)`` (sorted, contiguous)."""
    pos: List[float] = []
    col: List[float] = []
    eps = 1e-4
    for a, b, c in bands:
        pa, pb = (a - z0) / (z1 - z0), (b - z0) / (z1 - z0)
        pa = max(pa, pos[-1] + eps) if pos else pa
        pos += [round(pa, 5), round(max(pb - eps, pa + eps), 5)]
        col += [round(float(v), 4) for v in c] * 2
    return {"type": "gradient", "mapping": "world", "axis": "z", "remap": [z0, z1],
            "ramp_positions": pos, "ramp_colors": col}


def ground_variant(rng: np.random.Generator) -> Dict[str, Any]:
    """One ground layout (a diffuse material): the camera's own carriageway or a verge in front,
    the median, the far carriageway's lanes with their markings, shoulder, kerb and verge."""
    asphalt = ASPHALT[int(rng.integers(len(ASPHALT)))]
    lanes_end = ROAD_Z + LANES * LANE_WIDTH
    bands: List[tuple] = []
    median = ("grass", "concrete", "line")[int(rng.choice(3, p=[0.5, 0.25, 0.25]))]
    width = float(rng.uniform(1.0, 8.0)) if median != "line" else 0.0
    front = "road" if rng.random() < 0.6 else "verge"
    m0 = ROAD_Z - width
    near = asphalt if front == "road" else GRASS[int(rng.integers(len(GRASS)))]
    z_lo = -12.0
    if median == "line":
        bands += [(z_lo, m0 - 0.45, near), (m0 - 0.45, m0 - 0.33, YELLOW), (m0 - 0.33, m0 - 0.21, asphalt),
                  (m0 - 0.21, m0 - 0.09, YELLOW), (m0 - 0.09, ROAD_Z, asphalt)]
    else:
        fill = (GRASS[int(rng.integers(len(GRASS)))] if median == "grass"
                else CONCRETE[int(rng.integers(len(CONCRETE)))])
        k = 0.2 if rng.random() < 0.7 else 0.0
        bands += [(z_lo, m0 - 0.3, near)]
        if front == "road":
            bands += [(m0 - 0.3, m0 - 0.15, YELLOW if rng.random() < 0.6 else WHITE), (m0 - 0.15, m0, asphalt)]
        else:
            bands += [(m0 - 0.3, m0, near)]
        if k:
            bands += [(m0, m0 + k, KERB), (m0 + k, ROAD_Z - k, fill), (ROAD_Z - k, ROAD_Z, KERB)]
        else:
            bands += [(m0, ROAD_Z, fill)]
    inner = YELLOW if rng.random() < 0.6 else WHITE
    bands += [(ROAD_Z, ROAD_Z + 0.3, asphalt), (ROAD_Z + 0.3, ROAD_Z + 0.45, inner)]
    z = ROAD_Z + 0.45
    lane_line = WHITE if rng.random() < 0.8 else tuple(0.5 * np.asarray(WHITE) + 0.5 * np.asarray(asphalt))
    for i in range(1, LANES):
        c = ROAD_Z + i * LANE_WIDTH
        bands += [(z, c - 0.06, asphalt), (c - 0.06, c + 0.06, lane_line)]
        z = c + 0.06
    bands += [(z, lanes_end - 0.45, asphalt), (lanes_end - 0.45, lanes_end - 0.3, WHITE)]
    shoulder = float(rng.uniform(0.3, 2.5))
    s_col = tuple(np.clip(np.asarray(asphalt) * rng.uniform(1.0, 1.4), 0, 1))
    bands += [(lanes_end - 0.3, lanes_end + shoulder, s_col)]
    z = lanes_end + shoulder
    if rng.random() < 0.5:
        bands += [(z, z + 0.25, KERB)]
        z += 0.25
    verge = GRASS[int(rng.integers(len(GRASS)))]
    far = GRASS[int(rng.integers(len(GRASS)))] if rng.random() < 0.7 else CONCRETE[int(rng.integers(3))]
    zf = z + float(rng.uniform(4.0, 15.0))
    bands += [(z, zf, verge), (zf, 80.0, far)]
    noise_fine = {"type": "noise", "mapping": "world", "scale": 9, "octaves": 4, "remap": [-1, 1],
                  "seed": int(rng.integers(1 << 20)), "ramp_positions": [0, 1],
                  "ramp_colors": [0.8, 0.8, 0.8, 1.2, 1.2, 1.2]}
    lo = float(rng.uniform(0.6, 0.85))
    noise_patches = {"type": "noise", "mapping": "world", "scale": 0.35, "octaves": 3, "remap": [-1, 1],
                     "seed": int(rng.integers(1 << 20)), "ramp_positions": [0, 1],
                     "ramp_colors": [lo, lo, lo * 0.95, 1.15, 1.15, 1.1]}
    tex = {"type": "blend", "op": "multiply", "factor": 1.0,
           "a": {"texture": {"type": "blend", "op": "multiply", "factor": 1.0,
                             "a": {"texture": _ramp(bands, z_lo, 80.0)}, "b": {"texture": noise_fine}}},
           "b": {"texture": noise_patches}}
    return {"type": "diffuse", "albedo": {"texture": tex}}


def _foliage(rng: np.random.Generator) -> Dict[str, Any]:
    dark = np.asarray(GRASS[int(rng.integers(len(GRASS)))]) * rng.uniform(0.5, 0.9)
    light = dark * rng.uniform(1.6, 2.6)
    # Leaves: dark and light green in blotches, with a bumpy surface so that the crowns are not
    # smooth balls.
    return {"type": "diffuse", "albedo": {"texture": {
        "type": "noise", "mapping": "world", "scale": float(rng.uniform(0.8, 2.0)), "octaves": 4,
        "seed": int(rng.integers(1 << 20)), "remap": [-0.6, 0.6], "ramp_positions": [0, 1],
        "ramp_colors": [round(float(v), 4) for v in list(dark) + list(np.clip(light, 0, 1))]}},
        "bump_map": {"texture": {"type": "noise", "mapping": "world", "scale": float(rng.uniform(2.0, 4.0)),
                                 "octaves": 3, "seed": int(rng.integers(1 << 20))}},
        "bump_scale": 0.15}


def _lane_cars(lane: int, torcs: bool) -> List[Dict[str, Any]]:
    zc = ROAD_Z + (lane + 0.5) * LANE_WIDTH
    # NOTE: the view at distance d spans x in [-d tan(fov_x/2), +d ...]; the region reaches 3 m
    # past the widest view (the camera's farthest z) so that cars are cut by the image border.
    half = (zc - CAMERA_Z[0]) + 3.0
    region = [round(-half, 2), round(zc - 0.3, 2), round(half, 2), round(zc + 0.3, 2)]
    yaw = {"choice": [{"normal": [0, 1.5]}, {"normal": [180, 1.5]}]}
    wear = {"dirt": {"probability": 0.4, "amount": {"uniform": [0.05, 0.3]}}}
    plates = {"country": {"choice": ["ru", "de"]}, "front": {"choice": [True, False]}}
    cars = [
        {"class": "car", "name": f"lane{lane}-torcs", "count": {"int": [0, 2]},
         "asset": {"choice": ["mesh/torcs-p406", "mesh/torcs-155-DTM", "mesh/torcs-acura-nsx-sz"]},
         "yaw": yaw, "region": region, "plates": plates, "wear": wear},
        {"class": "car", "name": f"lane{lane}-sumo", "count": {"int": [0, 2]},
         # NOTE: SUMO's car is a short, tall hatchback (3.64 x 1.71 m); stretched along its
         # forward axis (+z) and lowered to a saloon's proportions (4.37 x 1.54 m).
         "asset": "mesh/sumo-car-normal-citrus", "size": [1.05, 0.9, 1.2],
         "paint": {"palette": "cars", "roughness": {"uniform": [0.03, 0.2]}},
         "yaw": yaw, "region": region, "plates": plates, "wear": wear},
        {"class": "car", "name": f"lane{lane}-van", "count": {"choice": [0, 1], "weights": [3, 1]},
         "asset": {"choice": ["mesh/sumo-car-minibus-citrus", "mesh/sumo-car-microcargo-citrus"]},
         "paint": {"palette": "cars"}, "yaw": yaw, "region": region, "plates": plates, "wear": wear},
    ]
    return cars if torcs else cars[1:]


def scenario_dict(*, seed: int, count: int, spp: int = 16, rig: Optional[Dict[str, Any]] = None,
                  resolution: Sequence[int] = RESOLUTION, outputs: Sequence[str] = ("rgb", "coco"),
                  max_depth: int = 4, torcs: bool = True) -> Dict[str, Any]:
    """The scenario (a dict) that :func:`write_pure_scenario` writes."""
    r = _rig(rig)
    w, h = int(resolution[0]), int(resolution[1])
    # The rig's horizon row is given for 676 x 380: scaled with the image.
    horizon = r["horizon"] * h / RESOLUTION[1]
    fx = 0.5 * w / math.tan(math.radians(0.5 * r["fov_x"]))
    # NOTE: principal point at the image centre; a camera pitched down by theta puts the horizon
    # at row cy - fx tan(theta), so theta = atan((cy - horizon) / fx). The target 100 m ahead sits
    # that far below the eye.
    pitch = math.degrees(math.atan((0.5 * h - horizon) / fx))
    ty = [round(r["camera_height"] - 100.0 * math.tan(math.radians(pitch + s * PITCH_JITTER)), 3) for s in (1, -1)]
    tx = round(100.0 * math.tan(math.radians(YAW_JITTER)), 3)
    ch = r["camera_height"]
    rng = np.random.default_rng(seed)
    grounds = [ground_variant(rng) for _ in range(GROUND_VARIANTS)]
    foliage = [_foliage(rng) for _ in range(4)]
    objects: List[Dict[str, Any]] = []
    for lane in range(LANES):
        objects += _lane_cars(lane, torcs)
    lanes_end = ROAD_Z + LANES * LANE_WIDTH
    trees_region = [-70.0, lanes_end + 6.5, 70.0, 75.0]
    objects += [
        {"label": False, "name": "tree", "count": {"int": [16, 34]}, "primitive": "sphere",
         "size": {"uniform": [[5, 9, 5], [13, 24, 13]]}, "material": {"choice": foliage}, "region": trees_region},
        {"label": False, "name": "conifer", "count": {"int": [0, 10]}, "primitive": "cone",
         "size": {"uniform": [[3, 9, 3], [6, 22, 6]]}, "material": {"choice": foliage}, "region": trees_region},
        {"label": False, "name": "bush", "count": {"int": [0, 8]}, "primitive": "sphere",
         "size": {"uniform": [[1, 0.7, 1], [3.5, 2.5, 3.5]]}, "material": {"choice": foliage},
         "region": [-30.0, lanes_end + 3.2, 30.0, lanes_end + 6.0]},
        {"label": False, "name": "pole", "count": {"int": [0, 3]}, "primitive": "cylinder",
         "size": {"uniform": [[0.18, 6, 0.18], [0.35, 11, 0.35]]},
         "material": {"type": "diffuse", "albedo": {"choice": [[0.35, 0.35, 0.34], [0.2, 0.2, 0.2], [0.5, 0.5, 0.48],
                                                                [0.16, 0.11, 0.07], [0.3, 0.22, 0.14]]}},
         "region": [-30.0, lanes_end + 2.0, 30.0, lanes_end + 3.0]},
        {"label": False, "name": "sign", "count": {"int": [0, 2]},
         "sign": {"family": {"choice": ["prohibitory", "warning", "information", "give_way", "stop"]},
                  "size": {"uniform": [0.5, 1.2]}, "mount_height": {"uniform": [1.2, 2.5]}},
         "yaw": {"uniform": [160, 200]}, "region": [-25.0, lanes_end + 0.8, 25.0, lanes_end + 1.8]},
        {"label": False, "name": "median sign", "count": {"choice": [0, 1], "weights": [4, 1]},
         "sign": {"family": {"choice": ["prohibitory", "information", "warning"]},
                  "size": {"uniform": [0.5, 1.0]}, "mount_height": {"uniform": [1.2, 2.2]}},
         "yaw": {"uniform": [150, 210]}, "region": [-6.0, 2.5, 6.0, ROAD_Z - 0.5]},
        {"label": False, "name": "building", "count": {"int": [0, 3]}, "primitive": "box",
         "size": {"uniform": [[8, 3.5, 8], [25, 12, 15]]},
         "material": {"type": "diffuse", "albedo": {"choice": [[0.45, 0.42, 0.38], [0.3, 0.18, 0.13], [0.6, 0.58, 0.55],
                                                                [0.25, 0.25, 0.27], [0.5, 0.4, 0.3]]}},
         "yaw": {"uniform": [-10, 10]}, "region": [-90.0, 80.0, 90.0, 110.0]},
    ]
    # Mostly clear summer days, as in the real video (a low sun through haze is the rarer case).
    sky = [{"type": "sky", "elevation": {"uniform": [15, 75]}, "azimuth": {"uniform": [0, 360]},
            "turbidity": {"uniform": [2, 4.5]}, "strength": 0.02}]
    hdrs = [[{"type": "envmap", "asset": a, "rotation": {"uniform": [0, 360]}}]
            for a in ("hdr/forest", "hdr/sunrise", "hdr/city")]
    return {
        "version": 2,
        "description": "pure synthetic frames for sim2real: the cars_highway rig (side-facing, "
                       f"fov_x {r['fov_x']:g}, height {ch:g} m, horizon row {r['horizon']:g}) across a multi-lane road",
        "seed": int(seed),
        "count": int(count),
        "resolution": [w, h],
        # NOTE: metered auto-exposure (version 2) with up to a stop less: the frames are mostly
        # dark road and trees, and metering them to mid-grey washes out the sky, which the real
        # camera keeps blue.
        "camera": {"fx": round(fx, 4), **_lens(r), "exposure": {"mode": "auto", "ev": {"uniform": [-1.0, 0.0]}},
                   "pose": {"type": "look_at",
                            "eye": {"uniform": [[-0.5, ch - 0.05, CAMERA_Z[0]], [0.5, ch + 0.05, CAMERA_Z[1]]]},
                            "target": {"uniform": [[-tx, min(ty), 100.0], [tx, max(ty), 100.0]]}}},
        "lights": {"choice": [sky] + hdrs, "weights": [6, 2, 1, 1]},
        "ground": {"material": {"choice": grounds}},
        "objects": objects,
        "placement": {"region": [-20.0, ROAD_Z, 20.0, lanes_end], "non_overlapping": True, "margin": 0.4,
                      "min_visible_fraction": 0.25, "min_pixels": max(8, int(60 * w * h / (676 * 380))),
                      "max_retries": 8, "allow_drops": True},
        "render": {"spp": int(spp), "max_depth": int(max_depth), "clamp_indirect": 3},
        "outputs": list(dict.fromkeys(list(outputs))),
    }


def write_pure_scenario(path: str, *, seed: int, count: int, spp: int = 16, rig: Optional[Dict[str, Any]] = None,
                        resolution: Sequence[int] = RESOLUTION, outputs: Sequence[str] = ("rgb", "coco"),
                        max_depth: int = 4, torcs: bool = True) -> str:
    """Write the pure synthetic scenario (see the module docstring) to ``path``; returns it.
    ``rig``: fov_x (degrees), camera_height (m), horizon (row at 676 x 380; scaled with
    ``resolution``), distortion (None, or OpenCV's [k1, k2, p1, p2(, k3)]: the lens the frames
    are rendered through; the kitti outputs are refused with it). ``torcs=False`` leaves out
    the TORCS cars (optional assets: Debian torcs-data), keeping SUMO's."""
    sc = scenario_dict(seed=seed, count=count, spp=spp, rig=rig, resolution=resolution, outputs=outputs,
                       max_depth=max_depth, torcs=torcs)
    text = ("# Written by bench/sim2real/pure.py (write_pure_scenario): pure synthetic frames for sim2real.\n"
            + yaml.safe_dump(sc, sort_keys=False, default_flow_style=None, width=120))
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    with open(path, "w") as f:
        f.write(text)
    return path


def box_heights_coco(path: str, category: str = "car") -> np.ndarray:
    """Heights (pixels) of the ``category`` boxes of a COCO file."""
    with open(path) as f:
        coco = json.load(f)
    cat = {c["id"] for c in coco["categories"] if c["name"] == category}
    return np.asarray([a["bbox"][3] for a in coco["annotations"] if a["category_id"] in cat], np.float64)


def box_heights_csv(path: str) -> np.ndarray:
    """Heights (pixels) of the boxes of cars_highway's boxes.csv (image_id,xmin,ymin,xmax,ymax)."""
    import csv

    with open(path, newline="") as f:
        return np.asarray([float(r["ymax"]) - float(r["ymin"]) for r in csv.DictReader(f)], np.float64)


def height_line(name: str, h: np.ndarray) -> str:
    q = np.percentile(h, [10, 50, 90]) if len(h) else [float("nan")] * 3
    return (f"{name}: {len(h)} boxes, median height {q[1]:.1f} px (10%: {q[0]:.1f}, 90%: {q[2]:.1f}), "
            f"under 40 px: {int((h < 40).sum())} ({(h < 40).mean() if len(h) else float('nan'):.2f})")


def main(argv: Optional[Sequence[str]] = None) -> int:
    """Write the scenario, render it, print seconds per frame and the cars' box heights beside
    the real frames' (../shared/realdata/cars_highway/boxes.csv, when there)."""
    import argparse

    from synthgen import run as runner

    ap = argparse.ArgumentParser(description="render pure synthetic sim2real frames and compare their box heights "
                                             "with the real frames'")
    ap.add_argument("-o", "--out", required=True, help="output folder (the scenario goes in as pure.yaml)")
    ap.add_argument("-n", "--count", type=int, default=30)
    ap.add_argument("--seed", type=int, default=2)
    ap.add_argument("--spp", type=int, default=16)
    ap.add_argument("--workers", type=int, default=1)
    args = ap.parse_args(argv)
    os.makedirs(args.out, exist_ok=True)
    path = write_pure_scenario(os.path.join(args.out, "pure.yaml"), seed=args.seed, count=args.count, spp=args.spp)
    s = runner.run(path, os.path.join(args.out, "frames"), workers=args.workers)
    print(s.text())
    if s["failures"]:
        return 1
    print(height_line("pure synthetic", box_heights_coco(os.path.join(args.out, "frames", "annotations", "coco.json"))))
    real = os.path.join(REPO, "..", "shared", "realdata", "cars_highway", "boxes.csv")
    if os.path.isfile(real):
        print(height_line("real (cars_highway)", box_heights_csv(real)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
