"""synthgen frames for ``sim2real_plate_ap50`` (issue 34): cars with EU-style plates, framed as
the real plate photos frame them (``../shared/realdata/plates_openalpr/eu``, measured by
:func:`real_stats`; docs/sim2real.md, "Plates").

- :func:`write_plate_scenario` writes a synthgen scenario (YAML): one library car in front of
  the camera, which is aimed above the plate facing it from the distance at which the plate
  covers the fraction of the image width the real photos show; seen from behind or in front, a
  little off axis, from a person's eye height or lower; its plates German (DIN 74069: white with the blue
  EU band, the style of the real EU photos) unless ``countries`` says otherwise, every visible
  plate labelled as class ``plate`` (COCO: its exact visible mask), the car as ``car``. Around
  it: a car further back (its plates labelled too), walls or hedges behind, a textured
  ground, a physical sky or an HDR environment, paint from the palette of real cars, dirt.
- :func:`real_stats` / :func:`coco_plate_stats`: the plate boxes of a real OpenALPR folder and of
  a rendered synthgen dataset, as the same statistics.
- ``python bench/sim2real/plates.py OUT -n 12`` writes both scenarios (``OUT/painted.yaml``,
  ``OUT/textured.yaml``), renders half the frames each (``synthgen run``), prints seconds per
  frame and both box distributions, and writes a side-by-side PNG (``OUT/vs_real.png``).

The real set's classes: one ``plate`` per photo. The detector trains on the ``plate`` class only
(``car`` is there for the tests and for other uses)."""
from __future__ import annotations

import argparse
import glob
import json
import os
import subprocess
import sys
import time
from typing import Any, Dict, List, Optional, Sequence

import numpy as np
import yaml

#: Image size of the frames: the commonest size of the real EU photos (12 of 54; median width
#: 543 px). NOTE: the detector works at an image's own pixels, so what must match is the plate's
#: size in pixels (real median 122 px wide), which the car's pixel height sets below.
RESOLUTION = (576, 432)

#: Library vehicles (``synthgen assets list``; all have front and rear plate mounts), by kind:
#: ``painted`` (the SUMO car and vans: body paint from the palette of real cars' colours) and
#: ``textured`` (TORCS cars in their own textures: no paint material, so ``paint`` cannot go on
#: them, and one scenario entry cannot mix the two kinds). The real set has vans (test_026,
#: test_043) beside hatchbacks and saloons.
VEHICLES = {"painted": ("mesh/sumo-car-normal-citrus", "mesh/sumo-car-normal-citrus",
                        "mesh/sumo-car-minibus-citrus", "mesh/sumo-car-microcargo-citrus"),
            "textured": ("mesh/torcs-p406", "mesh/torcs-p406", "mesh/torcs-baja-bug", "mesh/torcs-155-DTM")}

#: Distance of a library vehicle's plates from its centre along its axis, metres: the mean of
#: its vehicles' (measured: a plate's width in pixels, from its labelled corners, at 8 m, yaw 0
#: and 180): SUMO car 1.80 / 1.82 (rear / front), minibus 2.14 / 2.17, micro van 1.81 / 1.82;
#: TORCS Peugeot 406 2.30 / 2.31, Beetle 1.87 / 1.90, Alfa 155 2.16 / 2.29 (docs/sim2real.md, "Plates").
PLATE_OFFSET = 2.0

#: HDR environments of the asset library used as light and background beside the physical sky.
HDRS = ("hdr/city", "hdr/forest", "hdr/sunrise")


def _asphalt() -> Dict[str, Any]:
    """A ground of asphalt, paving or packed gravel: grey of random lightness, fbm noise."""
    return {"type": "diffuse", "albedo": {"texture": {
        "type": "blend", "op": "multiply",
        "a": {"uniform": [0.08, 0.32]},
        "b": {"texture": {"type": "noise", "mapping": "world", "scale": {"uniform": [2, 12]},
                          "octaves": 4, "remap": [-1, 1],
                          "ramp_positions": [0, 1], "ramp_colors": [0.7, 0.7, 0.7, 1.3, 1.3, 1.3]}},
        "factor": 1.0}}}


#: Colours of walls, fences and hedges behind the parked cars of the real photos: white and
#: beige render, grey concrete, brick, a dark hedge, yellow and blue plaster.
WALL_COLOURS = ([0.75, 0.74, 0.70], [0.62, 0.55, 0.42], [0.40, 0.40, 0.38], [0.25, 0.25, 0.25],
                [0.45, 0.20, 0.13], [0.10, 0.18, 0.07], [0.70, 0.58, 0.25], [0.15, 0.30, 0.55])


def _wall() -> Dict[str, Any]:
    """A wall, fence or hedge behind the car: one of :data:`WALL_COLOURS` with noise."""
    return {"type": "diffuse", "albedo": {"texture": {
        "type": "blend", "op": "multiply",
        "a": {"choice": [list(c) for c in WALL_COLOURS]},
        "b": {"texture": {"type": "noise", "mapping": "world", "scale": {"uniform": [0.5, 8]},
                          "octaves": 5, "remap": [-1, 1],
                          "ramp_positions": [0, 1], "ramp_colors": [0.5, 0.5, 0.5, 1.4, 1.4, 1.4]}},
        "factor": 1.0}}}


def write_plate_scenario(path: str, *, seed: int, count: int, spp: int = 16, vehicles: str = "painted",
                         resolution: Sequence[int] = RESOLUTION, countries: Sequence[str] = ("de",),
                         distance: Sequence[float] = (1.4, 2.9), background_cars: bool = True,
                         hdr: bool = True, wear: bool = True, paint: bool = True,
                         outputs: Sequence[str] = ("rgb", "coco")) -> Dict[str, Any]:
    """Write the plate scenario to ``path`` (YAML) and return it as a dict.

    ``vehicles``: ``painted`` or ``textured`` (:data:`VEHICLES`: render both for the whole
    library); ``distance``: the camera's distance from the plate it faces, metres (at
    :data:`PLATE_OFFSET` from the car's centre, the vehicles' own within 0.3 m of it);
    ``countries``: plate styles
    (``synthgen.scene.plates.COUNTRIES``); ``background_cars``, ``hdr``, ``wear``, ``paint``:
    the ablation switches (further cars, HDR environments beside the sky, dirt, the paint
    palette)."""
    if vehicles not in VEHICLES:
        raise ValueError(f"vehicles '{vehicles}' is not one of {', '.join(VEHICLES)}")
    fleet = list(VEHICLES[vehicles])
    paint = paint and vehicles == "painted"
    w, h = int(resolution[0]), int(resolution[1])
    country: Any = countries[0] if len(countries) == 1 else {"choice": list(countries)}
    plates = {"country": country, "class": "plate", "front": True}
    dirt = {"dirt": {"probability": 0.4, "amount": {"uniform": [0.02, 0.08]}}} if wear else None
    # NOTE: the camera sits on the -x side of the car (at the origin) looking along +x at a
    # point 0.9 m high above the plate that faces it (orbit azimuth 270, target at x =
    # -PLATE_OFFSET, jittered by up to 0.3 m): a car of yaw 0 shows its rear, of yaw 180 its
    # front (the library's plates stand as far in front of the centre as behind it), the plate
    # (0.36 to 0.72 m high) below the image centre as in the real photos. A 520 mm plate d
    # metres away covers 0.52 / (d 2 tan(fov_x / 2)) of the image width: fov_y 36 to 48 degrees
    # (fov_x 47 to 61 at 4:3) and d 1.4 to 2.9 m give 0.15 to 0.43 (median about 0.24), the
    # real photos' 0.15 to 0.30 (p10 to p90, median 0.23) and a margin. The camera's height is
    # 0.9 m + d sin(elevation): 1.1 to 2.3 m (a crouching to a standing photographer); the
    # view is off axis by the car's yaw (sd 12 degrees) and the orbit's azimuth (sd 6).
    main: Dict[str, Any] = {
        "class": "car", "name": "car", "count": 1,
        "asset": {"choice": fleet},
        "yaw": {"choice": [{"normal": [0, 12]}, {"normal": [0, 12]}, {"normal": [180, 12]}]},
        "region": [-0.2, -0.2, 0.2, 0.2],
        "plates": plates, "min_visible_fraction": 0.5}
    if paint:
        main["paint"] = {"palette": "cars"}
    if dirt:
        main["wear"] = dirt
    objects: List[Dict[str, Any]] = [main]
    if background_cars:
        # Half the frames without one: other vehicles are in 14 of the 54 real photos.
        back = {"class": "car", "name": "parked", "count": {"choice": [0, 1]},
                "asset": {"choice": fleet},
                "yaw": {"choice": [{"normal": [0, 20]}, {"normal": [180, 20]}, {"uniform": [0, 360]}]},
                "region": [5, -9, 6.5, 9], "plates": plates, "min_visible_fraction": 0.0, "min_pixels": 0}
        if paint:
            back["paint"] = {"palette": "cars"}
        objects.append(back)
    objects.append({"label": False, "name": "wall", "count": {"int": [1, 5]}, "primitive": "box",
                    "size": {"uniform": [[0.2, 1.0, 2], [1.0, 4.0, 4]]},
                    "yaw": {"normal": [0, 10]}, "region": [10, -8, 12, 8], "material": _wall(),
                    "min_visible_fraction": 0.0, "min_pixels": 0})
    sky = [{"type": "sky", "elevation": {"uniform": [10, 70]}, "azimuth": {"uniform": [0, 360]},
            "turbidity": {"uniform": [2, 6]}, "strength": 0.02}]
    overcast = [{"type": "sky", "elevation": {"uniform": [20, 70]}, "azimuth": {"uniform": [0, 360]},
                 "turbidity": {"uniform": [8, 10]}, "strength": 0.02, "sun": False}]
    setups: List[Any] = [sky, sky, overcast]
    if hdr:
        setups += [[{"type": "envmap", "asset": a, "rotation": {"uniform": [0, 360]}, "strength": 1.0}]
                   for a in HDRS]
    scenario: Dict[str, Any] = {
        "version": 2,
        "description": "sim2real plates: a library car with EU (German) plates framed as the real plate "
                       "photos frame them (bench/sim2real/plates.py)",
        "seed": int(seed), "count": int(count), "resolution": [w, h],
        "camera": {"fov_y": {"uniform": [36, 48]},
                   "pose": {"type": "orbit", "target": [-PLATE_OFFSET, 0.9, 0], "jitter": 0.3,
                            "distance": {"uniform": [float(distance[0]), float(distance[1])]},
                            "elevation": {"uniform": [8, 28]}, "azimuth": {"normal": [270, 6]}},
                   "exposure": {"mode": "auto", "ev": {"normal": [0, 0.3]}}},
        "lights": {"choice": setups},
        "ground": {"material": _asphalt()},
        "objects": objects,
        "placement": {"region": [-4, -4, 4, 4], "non_overlapping": True, "margin": 0.3,
                      "min_visible_fraction": 0.0, "min_pixels": 0, "max_retries": 60},
        "render": {"spp": int(spp), "max_depth": 6, "clamp_indirect": 3},
        "outputs": list(outputs),
        "split": {"val": 0.0, "test": 0.0},
    }
    with open(path, "w") as f:
        f.write("# written by bench/sim2real/plates.py (write_plate_scenario): do not edit, regenerate\n")
        yaml.safe_dump(scenario, f, sort_keys=False, default_flow_style=None, width=110)
    return scenario


def _stats(w: np.ndarray, h: np.ndarray, W: np.ndarray, H: np.ndarray, cx: np.ndarray,
           cy: np.ndarray) -> Dict[str, np.ndarray]:
    return {"plate_w_px": w, "plate_h_px": h, "plate_w_frac": w / W, "aspect": w / h,
            "centre_x_frac": cx / W, "centre_y_frac": cy / H}


def real_stats(folder: str) -> Dict[str, np.ndarray]:
    """The plate boxes of a real OpenALPR folder (``synthgen.evaluate.datasets.read_real``)."""
    from PIL import Image
    from synthgen.evaluate.datasets import read_real
    rows = []
    for s in read_real(folder):
        with Image.open(s.image) as im:
            W, H = im.size
        for b in s.boxes:
            rows.append((b[2] - b[0], b[3] - b[1], W, H, (b[0] + b[2]) / 2, (b[1] + b[3]) / 2))
    a = np.asarray(rows, np.float64)
    return _stats(*a.T)


def coco_plate_stats(dataset: str, cls: str = "plate", parent: Optional[int] = None) -> Dict[str, np.ndarray]:
    """The ``cls`` boxes of a rendered synthgen dataset (``annotations/coco.json``); with
    ``parent``, only those of that instance (1: the scenario's main car, its first object)."""
    with open(os.path.join(dataset, "annotations", "coco.json")) as f:
        coco = json.load(f)
    cat = {c["id"]: c["name"] for c in coco["categories"]}
    size = {i["id"]: (i["width"], i["height"]) for i in coco["images"]}
    rows = []
    for a in coco["annotations"]:
        if cat[a["category_id"]] != cls or a.get("iscrowd", 0):
            continue
        if parent is not None and a.get("parent_instance_id") != parent:
            continue
        x, y, w, h = a["bbox"]
        W, H = size[a["image_id"]]
        rows.append((w, h, W, H, x + w / 2, y + h / 2))
    a = np.asarray(rows, np.float64).reshape(-1, 6)
    return _stats(*a.T)


def print_stats(name: str, st: Dict[str, np.ndarray]) -> None:
    """One line per statistic: min, p10, p25, median, p75, p90, max."""
    n = len(st["plate_w_px"])
    print(f"{name}: {n} plates (min p10 p25 median p75 p90 max)")
    for k, v in st.items():
        q = np.percentile(v, [0, 10, 25, 50, 75, 90, 100]) if n else []
        print(f"  {k:14s} " + " ".join(f"{x:7.3g}" for x in q))


def side_by_side(real: str, datasets: Sequence[str], out_png: str, n: int = 12, tile=(288, 216)) -> None:
    """Real photos (top rows, their plate box in red) beside rendered frames (bottom rows, their
    labelled plate boxes in green) in one PNG."""
    from PIL import Image, ImageDraw
    every = sorted(glob.glob(os.path.join(real, "*.jpg")))
    reals = every[:: max(1, len(every) // n)][:n]
    synth = []   # (image path, [(class, bbox)])
    for d in datasets:
        with open(os.path.join(d, "annotations", "coco.json")) as f:
            coco = json.load(f)
        cat = {c["id"]: c["name"] for c in coco["categories"]}
        boxes: Dict[int, List[Any]] = {}
        for a in coco["annotations"]:
            boxes.setdefault(a["image_id"], []).append((cat[a["category_id"]], a["bbox"]))
        synth += [(os.path.join(d, i["file_name"]), boxes.get(i["id"], [])) for i in coco["images"]]
    synth = synth[:n]
    cols = 6
    rows = 2 * ((n + cols - 1) // cols)
    sheet = Image.new("RGB", (cols * tile[0], rows * tile[1]), "white")

    def put(im: Image.Image, k: int) -> None:
        im.thumbnail(tile)
        sheet.paste(im, ((k % cols) * tile[0], (k // cols) * tile[1]))

    for k, p in enumerate(reals):
        im = Image.open(p).convert("RGB")
        with open(p[:-4] + ".txt") as f:
            x, y, w, h = (int(v) for v in f.read().split("\t")[1:5])
        ImageDraw.Draw(im).rectangle([x, y, x + w, y + h], outline=(255, 0, 0), width=2)
        put(im, k)
    base = ((n + cols - 1) // cols) * cols
    for k, (path, bxs) in enumerate(synth):
        im = Image.open(path).convert("RGB")
        for c, (x, y, w, h) in bxs:
            if c == "plate":
                ImageDraw.Draw(im).rectangle([x, y, x + w, y + h], outline=(0, 255, 0), width=1)
        put(im, base + k)
    sheet.save(out_png)


def render(scenario: str, out: str, threads: int = 0, tries: int = 3) -> Dict[str, float]:
    """``synthgen run`` the scenario into ``out``, then ``--resume`` it while frames failed (at most
    ``tries`` runs; exit status 3, every frame written with some clutter dropped, is a success:
    the run lists them). NOTE: the resume is a guard against frames that fail in a long-lived
    worker and render in a fresh one ("texture N is still used by material M" was one, fixed:
    docs/sim2real.md, "Plates").
    Returns wall and child CPU seconds; raises when frames are still missing after ``tries``."""
    t0, c0 = time.time(), os.times()
    for k in range(tries):
        cmd = [sys.executable, "-m", "synthgen", "run", scenario, "-o", out] + (["--resume"] if k else [])
        if threads:
            cmd += ["--threads", str(threads)]
        r = subprocess.run(cmd)
        if r.returncode in (0, 3):
            break
    else:
        raise SystemExit(f"{out}: frames still failing after {tries} runs")
    c1 = os.times()
    return {"wall": time.time() - t0,
            "cpu": (c1.children_user - c0.children_user) + (c1.children_system - c0.children_system)}


def main(argv: Optional[Sequence[str]] = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("out", help="output folder: OUT/painted and OUT/textured (half the frames each), "
                                "their scenarios beside them")
    ap.add_argument("-n", "--count", type=int, default=12, help="frames in all")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--spp", type=int, default=16)
    ap.add_argument("--real", default=os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "..",
                                                   "shared", "realdata", "plates_openalpr", "eu"))
    ap.add_argument("--threads", type=int, default=0)
    a = ap.parse_args(argv)
    os.makedirs(a.out, exist_ok=True)
    wall = cpu = 0.0
    stats: Dict[str, List[np.ndarray]] = {}
    main_stats: Dict[str, List[np.ndarray]] = {}
    for k, kind in enumerate(VEHICLES):
        n = a.count // 2 + (a.count % 2 if k == 0 else 0)
        scen = os.path.join(a.out, kind + ".yaml")
        write_plate_scenario(scen, seed=a.seed + k, count=n, spp=a.spp, vehicles=kind)
        t = render(scen, os.path.join(a.out, kind), a.threads)
        wall, cpu = wall + t["wall"], cpu + t["cpu"]
        for key, v in coco_plate_stats(os.path.join(a.out, kind)).items():
            stats.setdefault(key, []).append(v)
        for key, v in coco_plate_stats(os.path.join(a.out, kind), parent=1).items():
            main_stats.setdefault(key, []).append(v)
    print(f"frames={a.count} seconds_per_frame={wall / a.count:.2f} cpu_seconds_per_frame={cpu / a.count:.2f}")
    if os.path.isdir(a.real):
        print_stats("real " + os.path.normpath(a.real), real_stats(a.real))
    print_stats("synthgen " + a.out + ", the main car's plate",
                {key: np.concatenate(v) for key, v in main_stats.items()})
    print_stats("synthgen " + a.out + ", every plate", {key: np.concatenate(v) for key, v in stats.items()})
    if os.path.isdir(a.real):
        png = os.path.join(a.out, "vs_real.png")
        side_by_side(a.real, [os.path.join(a.out, kind) for kind in VEHICLES], png, n=a.count)
        print("side by side:", png)
    return 0


if __name__ == "__main__":
    sys.exit(main())
