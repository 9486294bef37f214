#!/usr/bin/env python3
"""Converged synthgen references of the five regression scenes, for the quality tests
(tests/python/test_quality_estimate.py) and the speed-accuracy benchmarks: the Ignis Cornell
box and the `materials` and `sunlit` scenes of bench/vs_cycles.py, frame 0 of
scenarios/default.yaml and of scenarios/road_signs.yaml -- each at 128 x 96, 4096 spp by default,
written as float EXR to tests/python/references/quality/<scene>.exr (committed: small). The
scenario scenes render with their scenario's settings (clamp_indirect); --unclamped renders
them without the clamp, as <scene>_unclamped.exr (what measures the clamp's bias).

    .venv/bin/python bench/quality_references.py [--spp 4096] [--scenes cbox,sunlit] [--out DIR] [--unclamped]

The scenes are built by :func:`regression_scene` (shared with the tests): one committed scene
each, rendered with a seed the tests do not use. Prints per scene its render time and the
reference's own estimated PSNR (synthgen.post.quality), how far it is from converged."""
from __future__ import annotations

import argparse
import os
import sys
import time
from typing import Any, Tuple

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
REPO = os.path.abspath(os.path.join(HERE, ".."))
sys.path.insert(0, os.path.join(REPO, "python"))
sys.path.insert(0, HERE)

SCENES = ("cbox", "materials", "sunlit", "default", "road_signs")
SIZE = (128, 96)
REF_DIR = os.path.join(REPO, "tests", "python", "references", "quality")
REF_SEED = 918273


def regression_scene(name: str, width: int = SIZE[0], height: int = SIZE[1]) -> Tuple[Any, int, float, Any]:
    """(committed synthgen.Scene, max_depth, exposure scale, its owner) of a regression scene;
    keep the owner (a scenario frame's renderer) alive while the scene is used."""
    if name in ("cbox", "materials", "sunlit"):
        from vs_cycles_scenes import build_spec, synthgen_scene

        spec = build_spec(name, width, height)
        scene = synthgen_scene(spec)
        scene.commit()
        return scene, int(spec["max_depth"]), 1.0, None
    from synthgen.frame.renderer import FrameRenderer
    from synthgen.post.quality import exposure_scale
    from synthgen.scenario import check_inputs, load_scenario

    sc = load_scenario(os.path.join(REPO, "scenarios", f"{name}.yaml"), overrides=[("resolution", [width, height])])
    check_inputs(sc)
    fr = FrameRenderer(sc)
    _, meta, _ = fr.render(0)
    fr.scene.commit()
    return fr.scene, int(sc.spec["render"]["max_depth"]), exposure_scale(meta.get("post", [])), fr


def regression_settings(name: str, scale: float = 1.0) -> dict:
    """The render settings a regression scene is rendered with besides spp, max_depth and seed:
    a scenario's own (its render section: clamp_indirect, ...) and the exposure ``scale``
    (regression_scene's) that its displayed-unit thresholds refer to; none for the bench scenes."""
    if name in ("cbox", "materials", "sunlit"):
        return {}
    from synthgen.scenario import load_scenario

    rs = load_scenario(os.path.join(REPO, "scenarios", f"{name}.yaml")).spec["render"]
    return {"exposure": float(scale), "clamp_indirect": float(rs["clamp_indirect"])}


def render(name: str, scene: Any, spp: int, max_depth: int, seed: int, scale: float = 1.0, **extra: Any) -> Any:
    """A render of regression scene ``name`` (see regression_settings; ``extra`` overrides)."""
    kw = dict(regression_settings(name, scale), **extra)
    return scene.render(spp=int(spp), max_depth=int(max_depth), seed=int(seed), **kw)


def read_reference(name: str, ref_dir: str = REF_DIR) -> np.ndarray:
    """The committed converged reference of regression scene ``name`` (H x W x 3 float32)."""
    import OpenImageIO as oiio

    path = os.path.join(ref_dir, f"{name}.exr")
    if not os.path.exists(path):
        raise FileNotFoundError(f"{path} is missing: run bench/quality_references.py --scenes {name}")
    return oiio.ImageBuf(path).get_pixels(oiio.FLOAT)[..., :3]


def write_exr(path: str, rgb: np.ndarray, attrs: dict) -> None:
    import OpenImageIO as oiio

    rgb = np.ascontiguousarray(rgb, np.float32)
    spec = oiio.ImageSpec(rgb.shape[1], rgb.shape[0], 3, oiio.FLOAT)
    spec.attribute("compression", "zip")
    for k, v in attrs.items():
        spec.attribute(f"synthgen:{k}", str(v))
    buf = oiio.ImageBuf(spec)
    buf.set_pixels(oiio.ROI(), rgb)
    if not buf.write(path):
        raise RuntimeError(f"cannot write {path}: {buf.geterror()}")


def main(argv=None) -> int:
    from synthgen.post.quality import estimate_noise

    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--spp", type=int, default=4096)
    ap.add_argument("--scenes", default=",".join(SCENES))
    ap.add_argument("--out", default=REF_DIR)
    ap.add_argument("--unclamped", action="store_true",
                    help="render with clamp_indirect 0 (written as <scene>_unclamped.exr: the clamp's bias)")
    args = ap.parse_args(argv)
    os.makedirs(args.out, exist_ok=True)
    for name in args.scenes.split(","):
        scene, depth, scale, _owner = regression_scene(name)
        extra = {"clamp_indirect": 0.0} if args.unclamped and regression_settings(name) else {}
        t0 = time.perf_counter()
        res = render(name, scene, args.spp, depth, REF_SEED, scale, **extra)
        secs = time.perf_counter() - t0
        est = estimate_noise(np.asarray(res.rgb_even), np.asarray(res.rgb_odd), args.spp, scale)
        path = os.path.join(args.out, f"{name}{'_unclamped' if extra else ''}.exr")
        write_exr(path, np.asarray(res.rgb), {"spp": args.spp, "seed": REF_SEED, "max_depth": depth,
                                             "exposure_scale": scale, **regression_settings(name, scale), **extra})
        print(f"{name}: {args.spp} spp in {secs:.1f} s, estimated PSNR {est['psnr_db']:.2f} dB -> {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
