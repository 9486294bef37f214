"""Synthgen frames for bench/sim2real.py's car experiment: library cars inserted into the
car-free frames of the side-facing highway camera (../shared/realdata/cars_highway/negatives).

`write_scenario(out_dir, frames, seed=..., spp=..., **variant)` writes into `out_dir`:
- `rig.yaml`: the camera rig (bench/sim2real/highway_rig.yaml, copied): the scenario's shared
  `background.calibration`;
- `cal/STEM.yaml`, one per frame: its placement region (bench/sim2real/road_regions.py) and
  its real labels (`objects: []` for a car-free frame, or the frame's rows of a boxes CSV) --
  keys that override the rig's (docs/augmented_photos.md, "A photo's calibration");
- `scenario.yaml`: the scenario (photos by absolute path, calibrations relative to it, so that
  its text and the calibrations' texts alone decide the frames).

The variants are keyword knobs (VARIANT_DEFAULTS): `wear`, `shadow_catcher`, `camera_match`,
`denoise`, `lighting` ("overcast": the photo's uniform overcast sky, "sun": a physical sky with
a low sun, "plain": one plain sun light of the scenario, no sky), `paint_variety`, `vehicles`
("library" or "one"), and `paste_control`. `shadow_catcher=False` and `paste_control=True` are
post steps on the rendered dataset of the same scenario (same frames, placements and labels):
outside the inserted objects' instance mask every pixel is the photo's again (no shadow, no
camera-matched JPEG around them), and with `paste_control` the objects' pixels are their albedo
(sRGB-encoded: no light, no shading, no camera matching) -- flat silhouettes.

`render(cache_dir, n, frames, ...)` writes the scenario, runs `synthgen run --resume` into
`cache_dir/<hash>/data` (hash: the scenario's and calibrations' texts but its frame count, post
steps excluded) and applies the post step into `cache_dir/<hash>/<post>`; an interrupted render
continues where it stopped, a finished one is reused, a longer one adds frames to it. It returns
the dataset's directory.
"""
from __future__ import annotations

import csv
import glob
import hashlib
import json
import os
import shutil
import subprocess
import sys

import numpy as np
import yaml
from PIL import Image

from synthgen import SynthgenError

from . import road_regions

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.abspath(os.path.join(HERE, "..", ".."))
RIG = os.path.join(HERE, "highway_rig.yaml")
SHARED = os.path.abspath(os.path.join(REPO, "..", "shared"))
HIGHWAY = os.path.join(SHARED, "realdata", "cars_highway")
RESOLUTION = (676, 380)

VARIANT_DEFAULTS = dict(wear=True, shadow_catcher=True, camera_match=True, denoise=True,
                        lighting="overcast", paint_variety=True, vehicles="library",
                        paste_control=False)

# Library vehicles that look like the video's traffic (sedans, hatchbacks, vans; `synthgen assets
# list`), all labelled `car` as boxes.csv labels vans too. TORCS cars: Debian torcs-data, fetched
# once into the asset cache. Kenney's cartoon truck and the TORCS dune buggy are left out.
SUMO = ("mesh/sumo-car-normal-citrus", "mesh/sumo-car-microcargo-citrus",
        "mesh/sumo-car-minibus-citrus")
TORCS = ("mesh/torcs-p406", "mesh/torcs-155-DTM", "mesh/torcs-acura-nsx-sz")
# The video's traffic is mostly cars: the saloons (SUMO's car, TORCS' 406) drawn twice as often
# as the vans and the sports cars.
WEIGHTS = {"mesh/sumo-car-normal-citrus": 2, "mesh/torcs-p406": 2}
ONE = "mesh/sumo-car-normal-citrus"

# The real cars' distances: box bottoms at rows 213 - 248 (10th - 90th percentile of
# boxes.csv; median 230), 9.7 - 18.7 m with the rig's horizon 175 and camera height 2.1 m (5.5 m
# at the lowest box, row 304), mostly on the far carriageway. 6 - 30 m put the median box at
# row 247 and 60 px tall (12 frames; real: 42 px), so the near lanes are left out.
MIN_DISTANCE = 9.0
MAX_DISTANCE = 30.0
GROUND_ALBEDO = 0.12      # grey asphalt


def negatives():
    """The car-free frames, sorted by name (empty without ../shared)."""
    return sorted(glob.glob(os.path.join(HIGHWAY, "negatives", "*.jpg")))


def rig_horizon(rig=RIG):
    with open(rig) as f:
        return float(yaml.safe_load(f)["ground"]["horizon"])


def _boxes_by_image(labels_csv):
    out = {}
    with open(labels_csv, newline="") as f:
        for row in csv.DictReader(f):
            out.setdefault(row["image_id"], []).append(row)
    return out


def _knobs(variant):
    bad = sorted(set(variant) - set(VARIANT_DEFAULTS))
    if bad:
        raise SynthgenError(f"write_scenario: unknown variant knob(s) {bad}; known: {sorted(VARIANT_DEFAULTS)}")
    v = dict(VARIANT_DEFAULTS, **variant)
    if v["lighting"] not in ("overcast", "sun", "plain"):
        raise SynthgenError(f"lighting: one of overcast, sun, plain, not {v['lighting']!r}")
    if v["vehicles"] not in ("library", "one"):
        raise SynthgenError(f"vehicles: one of library, one, not {v['vehicles']!r}")
    return v


def frame_calibration(photo, horizon, *, lighting="overcast", labels_csv=None, boxes=None):
    """The per-frame calibration keys (a dict): the road region, the sun, the real labels."""
    polys, _ = road_regions.road_region(photo, horizon)
    if not polys:
        raise SynthgenError(f"{photo}: the road-region method found no road below the horizon (row {horizon:g})")
    cal = {"region": polys}
    if lighting == "overcast":
        cal["sun"] = {"overcast": True}
    elif lighting == "sun":
        # The video is shot at dusk, the sun low behind the trees across the road.
        cal["sun"] = {"azimuth": 180, "elevation": 8}
    name = os.path.basename(photo)
    if labels_csv and boxes is not None and name in boxes:
        cal["labels"] = [{"file": os.path.realpath(labels_csv), "format": "csv", "class": "car"}]
    else:
        cal["objects"] = []          # a car-free frame: it shows no car to label
    return cal


def _car(assets, count, v, paint):
    asset = ({"choice": list(assets), "weights": [WEIGHTS.get(a, 1) for a in assets]}
             if len(assets) > 1 else assets[0])
    car = {"class": "car", "asset": asset,
           "count": count,
           # Along the road (road_direction 90: seen from the side), both ways.
           "yaw": {"choice": [{"normal": [0, 3]}, {"normal": [180, 3]}]},
           "plates": {"country": "de"}}
    if paint and v["paint_variety"]:
        car["paint"] = {"palette": "cars"}
    if v["wear"]:
        # Light dust: the video's cars are clean (0.1 - 0.35, as scenarios/augmented_road.yaml,
        # turned most of them mud-brown).
        car["wear"] = {"dirt": {"probability": 0.3, "amount": {"uniform": [0.03, 0.12]}}}
    return car


def scenario_dict(n, seed, spp, v, photo_entries):
    if v["vehicles"] == "library":
        # SUMO's models name their paint (a palette colour); TORCS' have their own liveries.
        cars = [_car(SUMO, {"int": [1, 2]}, v, True), _car(TORCS, {"int": [0, 1]}, v, False)]
    else:
        cars = [_car([ONE], {"int": [1, 3]}, v, True)]
    if v["camera_match"]:
        match = {"denoise": bool(v["denoise"])}
    else:
        match = {"denoise": bool(v["denoise"]), "noise": False, "blur": False, "jpeg": False,
                 "render_noise": 0}
    sc = {
        "version": 1,
        "description": "sim2real: cars inserted into the highway camera's car-free frames",
        "seed": int(seed), "count": int(n), "resolution": list(RESOLUTION),
        "background": {"photos": photo_entries, "calibration": "rig.yaml", "composite": "ratio",
                       "min_distance": MIN_DISTANCE, "max_distance": MAX_DISTANCE,
                       "max_real_overlap": 0.5, "match": match,
                       # NOTE: asphalt is grey; its blue in these dusk frames is the sky's
                       # light. A neutral catcher albedo lets the white balance (photo / render
                       # of the ground around each car) find that blue and light the cars with
                       # it; the default (0.15 tinted by the region's colour) takes the blue for
                       # the asphalt's and lit the cars white to orange (white balance up to
                       # [1.32, 0.93, 0.77]: silver and white cars turned beige).
                       "ground_albedo": GROUND_ALBEDO},
        "objects": cars,
        "placement": {"min_pixels": 100, "min_visible_fraction": 0.3, "max_retries": 40,
                      "allow_drops": True},
        "render": {"spp": int(spp), "max_depth": 6, "clamp_indirect": 3},
        # instance and albedo: the post steps (shadow_catcher off, paste_control) need them.
        "outputs": ["rgb", "instance", "albedo", "coco"],
    }
    if v["lighting"] == "plain":
        # behind the camera, high: the cars front-lit (scenario azimuth 0 = -z, the camera looks +z)
        sc["lights"] = [{"type": "sun", "azimuth": 20, "elevation": 45, "irradiance": [3, 3, 3]}]
    return sc


def write_scenario(out_dir, frames=None, *, n=None, seed=0, spp=16, labels_csv=None, rig=RIG,
                   **variant):
    """Write rig.yaml, cal/*.yaml and scenario.yaml into out_dir (module docstring); returns
    the scenario's path. `frames`: photo paths (default: the car-free frames); `n` frames
    (default: one per photo); `labels_csv`: real boxes (boxes.csv style) for frames with cars."""
    v = _knobs(variant)
    frames = list(frames) if frames is not None else negatives()
    if not frames:
        raise SynthgenError("write_scenario: no frames (is ../shared/realdata there?)")
    horizon = rig_horizon(rig)
    boxes = _boxes_by_image(labels_csv) if labels_csv else None
    os.makedirs(os.path.join(out_dir, "cal"), exist_ok=True)
    shutil.copyfile(rig, os.path.join(out_dir, "rig.yaml"))
    entries = []
    for p in frames:
        stem = os.path.splitext(os.path.basename(p))[0]
        cal = frame_calibration(p, horizon, lighting=v["lighting"], labels_csv=labels_csv, boxes=boxes)
        rel = f"cal/{stem}.yaml"
        with open(os.path.join(out_dir, rel), "w") as f:
            f.write(f"# {stem}: road region (bench/sim2real/road_regions.py) and labels; the rig is rig.yaml\n")
            region = cal.pop("region")
            f.write("region:\n" + "".join("  - " + json.dumps(p, separators=(", ", ": ")) + "\n" for p in region))
            yaml.safe_dump(cal, f, default_flow_style=None, sort_keys=False)
        # real paths: every checkout that reaches ../shared through a link writes the same text
        entries.append({"file": os.path.realpath(p), "calibration": rel})
    sc = scenario_dict(n if n is not None else len(frames), seed, spp, v, entries)
    path = os.path.join(out_dir, "scenario.yaml")
    with open(path, "w") as f:
        f.write("# written by bench/sim2real/data.py: " + json.dumps(
            {k: v[k] for k in sorted(v)}, sort_keys=True) + "\n")
        yaml.safe_dump(sc, f, default_flow_style=None, sort_keys=False)
    return path


#: Part of every render's cache key beside its texts: changed when synthgen's photo path changes
#: what a frame of the same scenario holds, so that no stale frame is reused (the run manifest
#: records synthgen's version, not its code). "2": camera matching fits the photo's noise over
#: the whole photo where it is flat (the foliage-as-noise fit speckled the cars).
RENDER_REV = "2"


def _text_hash(scn_dir):
    """Hash of the scenario's and calibrations' texts, the scenario's `count:` line left out:
    frame k depends only on k (photos in turn, per-frame seeds), so a longer render of the same
    scenario continues the shorter one's frames."""
    h = hashlib.sha256(b"rev\0" + RENDER_REV.encode() + b"\0")
    for rel in ["scenario.yaml", "rig.yaml"] + sorted(
            os.path.join("cal", x) for x in os.listdir(os.path.join(scn_dir, "cal"))):
        with open(os.path.join(scn_dir, rel), "rb") as f:
            text = f.read()
        if rel == "scenario.yaml":
            text = b"".join(line for line in text.splitlines(True) if not line.startswith(b"count:"))
        h.update(rel.encode() + b"\0" + text + b"\0")
    return h.hexdigest()[:16]


def render(cache_dir, n, frames=None, *, seed=0, spp=16, labels_csv=None, workers=1, nice=10,
           python=sys.executable, log=None, **variant):
    """Render n frames of the variant (cached; module docstring); returns the dataset's dir,
    whose frames 0 .. n-1 are complete (a dataset rendered further before holds more)."""
    v = _knobs(variant)
    base = {k: v[k] for k in v if k not in ("shadow_catcher", "paste_control")}
    stage = os.path.join(cache_dir, "staging")
    shutil.rmtree(stage, ignore_errors=True)
    write_scenario(stage, frames, n=n, seed=seed, spp=spp, labels_csv=labels_csv, **base)
    key = _text_hash(stage)
    root = os.path.join(cache_dir, key)
    if os.path.isdir(root):
        # the same frames; only the count may differ
        os.replace(os.path.join(stage, "scenario.yaml"), os.path.join(root, "scenario.yaml"))
        shutil.rmtree(stage)
    else:
        os.replace(stage, root)
    data = os.path.join(root, "data")
    cmd = [python, "-m", "synthgen", "run", os.path.join(root, "scenario.yaml"), "-o", data,
           "-n", str(n), "--workers", str(workers), "--no-progress"]
    if os.path.isdir(data):
        cmd.append("--resume")
    if nice:
        cmd = ["nice", "-n", str(nice)] + cmd
    env = dict(os.environ, PYTHONPATH=os.path.join(REPO, "python") + os.pathsep + os.environ.get("PYTHONPATH", ""))
    res = subprocess.run(cmd, env=env, stdout=log, stderr=subprocess.STDOUT if log else None)
    if res.returncode != 0:
        raise SynthgenError(f"synthgen run failed (exit status {res.returncode}): {' '.join(cmd)}")
    if v["paste_control"]:
        return post_composite(data, os.path.join(root, "paste_control"), albedo=True)
    if not v["shadow_catcher"]:
        return post_composite(data, os.path.join(root, "no_shadow_catcher"), albedo=False)
    return data


def srgb8(linear):
    """Linear values in [0, 1] -> 8-bit sRGB (the IEC 61966-2-1 curve), rounded."""
    x = np.clip(np.asarray(linear, np.float64), 0.0, 1.0)
    s = np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)
    return np.round(s * 255.0).astype(np.uint8)


def composite_frame(photo_rgb, rgb, instance, albedo=None):
    """The post step on one frame: the photo's pixels outside the objects' instance mask;
    inside it the frame's (albedo None) or the albedo's sRGB (paste control)."""
    inside = np.asarray(instance) > 0
    if inside.ndim == 3:
        inside = inside[..., 0]
    out = np.array(photo_rgb[..., :3], np.uint8, copy=True)
    src = srgb8(np.asarray(albedo)[..., :3]) if albedo is not None else np.asarray(rgb)[..., :3]
    out[inside] = src[inside]
    return out


def _link_or_copy(src, dst):
    try:
        os.link(src, dst)
    except OSError:
        shutil.copy2(src, dst)


def post_composite(data, out, *, albedo):
    """Copy dataset `data` into `out` (labels, masks, meta as they are: hard links) with every
    frame's image replaced by composite_frame(). The photo must fill the frame unscaled (zoom 1)."""
    from synthgen import read_dataset
    done = os.path.join(out, ".complete")
    # the marker holds the source's run summary: a source rendered further since is redone
    with open(os.path.join(data, "run_summary.json"), "rb") as f:
        stamp = hashlib.sha256(f.read()).hexdigest()
    if os.path.exists(done) and open(done).read() == stamp:
        return out
    shutil.rmtree(out, ignore_errors=True)
    # hard links (the metadata lists every file, albedo included: a frame missing one is not
    # complete); each image is unlinked before it is written, so the source keeps its own
    shutil.copytree(data, out, copy_function=_link_or_copy)
    ds = read_dataset(data)
    for k in ds.frames:
        fr = ds.frame(k)
        bg = fr.meta["background"]
        photo = bg["path"]
        if float(bg["scale"]) != 1.0 or list(bg["crop"])[:2] != [0, 0]:
            raise SynthgenError(f"{data}: frame {k}: photo {photo} scaled by {bg['scale']} and cropped at "
                             f"{bg['crop']}: the post step needs the photo unscaled (zoom 1)")
        with Image.open(photo) as im:
            ph = np.asarray(im.convert("RGB"))
        if ph.shape[:2] != fr.instance_id.shape[:2]:
            raise SynthgenError(f"{photo}: {ph.shape[1]} x {ph.shape[0]} photo, {fr.instance_id.shape[1]} x "
                             f"{fr.instance_id.shape[0]} frame: the post step needs the photo unscaled (zoom 1)")
        rgb8 = np.asarray(Image.open(os.path.join(data, "images", f"{k:06d}.png")).convert("RGB"))
        img = composite_frame(ph, rgb8, fr.instance_id, fr.albedo if albedo else None)
        dst = os.path.join(out, "images", f"{k:06d}.png")
        os.remove(dst)
        Image.fromarray(img).save(dst)
    with open(done, "w") as f:
        f.write(stamp)
    return out
