"""The wear gallery: every effect on a road sign, a car body panel and a sphere, one tile each,
with the effect's parameters printed under it (``synthgen gallery -o docs/gallery.png``).

Columns: clean, rust, dirt, scratches, ice, and three projected decals (``wear.decal``:
projective mapping with an occlusion test): hazard stripes, a licence plate, a sign pictogram. Rows: a stop sign (pictogram texture with an alpha cut-out on
a plate), a bent car body panel (car paint), a sphere (painted metal). Deterministic.
"""
from __future__ import annotations

from typing import Any, Dict, List, Tuple

import numpy as np

from .._core import PinholeCamera, Scene, TextureRef
from ..outputs.files import write_srgb_png
from ..scenario import check_inputs, load_scenario
from ..scene import plates, primitives as P, raster as R, signs, vehicles, wear
from .renderer import FrameRenderer
from .resources import Shapes

__all__ = ["EFFECTS", "OBJECTS", "CAR", "CAR_EFFECTS", "WEATHER_TILES", "render_gallery", "render_car_row",
           "render_weather_row"]

EFFECTS: List[Tuple[str, Dict[str, Any]]] = [
    ("clean", {}),
    ("rust", {"amount": 0.4, "scale": 3, "bottom_bias": 0.8}),
    ("dirt", {"amount": 0.45, "scale": 5, "bottom_bias": 1.5}),
    ("scratches", {"density": 6, "width": 0.08, "amount": 0.8, "elongation": 12}),
    ("ice", {"amount": 0.5, "scale": 4, "top_bias": 0.8}),
    ("decal", {"image": "stripes"}),
    ("plate", {"country": "de"}),
    ("pictogram", {"family": "prohibitory", "text": "60"}),
]
OBJECTS = ("sign", "panel", "sphere")


def _panel_mesh(width: float = 1.4, height: float = 0.8, bend: float = 0.25, n: int = 48) -> Dict[str, np.ndarray]:
    """A car-door-like panel: a sheet curved about the vertical axis (no uvs needed)."""
    xs = np.linspace(-0.5 * width, 0.5 * width, n)
    ys = np.linspace(0.0, height, 8)
    X, Y = np.meshgrid(xs, ys)
    Z = bend * (X / (0.5 * width)) ** 2 - 0.05 * np.sin(np.pi * Y / height)
    pos = np.stack([X, Y, Z], -1).reshape(-1, 3).astype(np.float32)
    idx = []
    for j in range(len(ys) - 1):
        for i in range(n - 1):
            a, b, c, d = j * n + i, j * n + i + 1, (j + 1) * n + i, (j + 1) * n + i + 1
            idx += [[a, c, b], [b, c, d]]
    uv = np.stack([(X - X.min()) / np.ptp(X), (Y - Y.min()) / np.ptp(Y)], -1).reshape(-1, 2).astype(np.float32)
    return {"positions": pos, "indices": np.asarray(idx, np.uint32), "uvs": uv}


def _tile(obj: str, effect: str, params: Dict[str, Any], w: int, h: int, spp: int) -> np.ndarray:
    s = Scene()
    ground = P.ground()
    s.add_instance(s.add_mesh(ground["positions"], ground["indices"], normals=ground["normals"]), np.eye(4),
                   material_id=s.add_material("diffuse", {"albedo": 0.35}))
    target = (0.0, 0.55, 0.0)
    if obj == "sign":
        sign = signs.render_sign("stop", None, 256)
        tex = s.add_image_texture(np.asarray(sign["rgba"], np.float32), {"wrap": "clamp", "colorspace": "linear"})
        base = s.add_material("principled", {"base_color": TextureRef(tex), "roughness": 0.4, "alpha": TextureRef(tex),
                                             "alpha_mode": "mask"})
        q = np.array([[-0.4, 0.3, 0.0], [0.4, 0.3, 0.0], [0.4, 1.1, 0.0], [-0.4, 1.1, 0.0]], np.float32)
        mesh = s.add_mesh(q, np.array([[0, 2, 1], [0, 3, 2]], np.uint32),
                          uvs=np.array([[0, 0], [1, 0], [1, 1], [0, 1]], np.float32))
        pole = P.box((0.05, 0.3, 0.05))
        s.add_instance(s.add_mesh(pole["positions"], pole["indices"], normals=pole["normals"]),
                       P.translate([0.0, 0.15, 0.02]), material_id=s.add_material("conductor", {"metal": "iron",
                                                                                              "roughness": 0.5}))
        world = P.rotate([0, 1, 0], 180.0)
    elif obj == "panel":
        base = s.add_material("coated", {"albedo": [0.5, 0.03, 0.03], "roughness": 0.05})
        m = _panel_mesh()
        mesh = s.add_mesh(m["positions"], m["indices"], uvs=m["uvs"])
        world = P.translate([0.0, 0.15, 0.0]) @ P.rotate([0, 1, 0], 180.0)
    else:
        base = s.add_material("coated", {"albedo": [0.05, 0.2, 0.45], "roughness": 0.1})
        sp = P.uv_sphere(0.45, 96, 48)
        mesh = s.add_mesh(sp["positions"], sp["indices"], normals=sp["normals"])
        world = P.translate([0.0, 0.45, 0.0])
    inst = s.add_instance(mesh, world, class_id=1, material_id=base)
    pose = PinholeCamera.look_at((0.9, 1.0, -2.6), target, (0.0, 1.0, 0.0))
    s.set_camera(PinholeCamera.from_fov(30.0, w, h, pose))
    mat = base
    if effect in ("rust", "dirt", "scratches", "ice"):
        mat = getattr(wear, effect)(s, base, seed=3, **params)
    elif effect in ("decal", "plate", "pictogram"):
        if effect == "plate":
            reg = plates.random_registration(params.get("country", "de"), np.random.default_rng(5))
            img, aspect, fov = plates.render_plate(reg, px_per_mm=1.0)["rgb"], 520.0 / 110.0, 4.2
        elif effect == "pictogram":
            img, aspect, fov = signs.on_background(signs.render_sign(params["family"], params.get("text"), 128)["rgba"]), \
                1.0, 7.0
        else:  # hazard stripes
            y, x = np.mgrid[0:64, 0:256]
            band = ((x + y) // 16) % 2 == 0
            img = np.where(band[..., None], np.array([0.8, 0.6, 0.0], np.float32), np.float32(0.02)).astype(np.float32)
            aspect, fov = 4.0, 3.5
        mat = wear.decal(s, base, np.asarray(img, np.float32), position=[0.0, target[1], -3.0], look_at=list(target),
                         fov=fov, aspect=aspect, occlusion=True)
    s.set_instance_material(inst, mat)
    s.add_light("sky", {"elevation": 35.0, "azimuth": 150.0, "turbidity": 3.0, "strength": 0.02})
    return np.asarray(s.render(spp=spp, max_depth=6, seed=1).rgb)


def _caption(text: str, w: int, h: int) -> np.ndarray:
    img = R.canvas(h, w, (0.92, 0.92, 0.92))
    font = R.font_path("DejaVuSans")
    lines = text.split("\n")
    for i, line in enumerate(lines):
        m = R.text_mask(h, w, line, 4, 12 + 13 * i, 10, font)
        R.paint(img, m, (0.05, 0.05, 0.05))
    return img[..., :3]


def render_gallery(tile_w: int = 240, tile_h: int = 180, spp: int = 32) -> np.ndarray:
    """The gallery image (linear RGB): rows OBJECTS, columns EFFECTS, a caption under each tile."""
    rows = []
    for obj in OBJECTS:
        row = []
        for effect, params in EFFECTS:
            tile = _tile(obj, effect, params, tile_w, tile_h, spp)
            ptxt = ", ".join(f"{k}={v}" for k, v in params.items())
            cap = _caption(f"{obj}: {effect}\n{ptxt}" if ptxt else f"{obj}: {effect}", tile_w, 32)
            # Captions are in display values already: undo the sRGB encoding applied on output.
            cap = np.where(cap <= 0.04045, cap / 12.92, ((cap + 0.055) / 1.055) ** 2.4)
            row.append(np.concatenate([tile, cap], axis=0))
        rows.append(np.concatenate(row, axis=1))
    return np.concatenate(rows, axis=0).astype(np.float32)


#: The library car of the gallery's car row, and the effects shown on it (the scenario presets'
#: parameters as a dataset would draw them).
CAR = "mesh/sumo-car-normal-citrus"
CAR_EFFECTS: List[Tuple[str, Dict[str, Any]]] = [
    ("clean", {}),
    ("rust", {"amount": 0.15, "bottom_bias": 0.6}),
    ("dirt", {"amount": 0.3}),
    ("scratches", {"density": 8, "width": 0.08, "amount": 0.7}),
    ("ice", {"amount": 0.35, "top_bias": 1.0}),
]


def _car_tile(effect: str, params: Dict[str, Any], w: int, h: int, spp: int) -> np.ndarray:
    """The library car (its own materials, a silver paint, a plate) with one effect, seen as in a
    dataset: from a driver's height, the car about a third of the image's width."""
    s = Scene()
    ground = P.ground()
    s.add_instance(s.add_mesh(ground["positions"], ground["indices"], normals=ground["normals"]), np.eye(4),
                   material_id=s.add_material("diffuse", {"albedo": 0.2}))
    shape = Shapes(s).get("asset", CAR)
    keys = list(shape.material_ids)
    paint = set(shape.roles.get("paint", ()))
    silver = s.add_material("coated", {"albedo": [0.42, 0.43, 0.45], "roughness": 0.06, "ior": 1.5})
    mats = [silver if k in paint else k for k in keys]
    if shape.plate_material:
        reg = plates.random_registration("ru", np.random.default_rng(4))
        tex = plates.render_plate(reg, px_per_mm=1.5)
        col = s.add_image_texture(np.asarray(tex["rgb"], np.float32), {"wrap": "clamp", "colorspace": "linear"})
        pm = s.add_material("principled", {"base_color": TextureRef(col), "roughness": 0.35})
        mats = [pm if k in shape.plate_material.values() else m for k, m in zip(keys, mats)]
    if effect in ("rust", "dirt", "scratches", "ice"):
        mats = getattr(wear, effect)(s, mats, seed=3, **params)
    # The model turned to +x forward, +y up, standing on the ground, at its real scale.
    turn = vehicles.model_axes(shape.forward or "+x", shape.up or "+y")
    m = np.eye(4)
    m[:3, :3] = turn * shape.unit
    lo = (turn @ np.asarray(shape.lo)) * shape.unit
    hi = (turn @ np.asarray(shape.hi)) * shape.unit
    m[1, 3] = -min(lo[1], hi[1])
    inst = s.add_instance(shape.mesh_id, P.rotate([0, 1, 0], -35.0) @ m, class_id=1, instance_id=1,
                          material_id=-1)
    s.set_instance_material_map(inst, {k: v for k, v in zip(keys, mats) if k != v})
    pose = PinholeCamera.look_at((0.0, 1.4, -10.5), (0.0, 0.7, 0.0), (0.0, 1.0, 0.0))
    s.set_camera(PinholeCamera.from_fov(40.0, w, h, pose))
    s.add_light("sky", {"elevation": 35.0, "azimuth": 150.0, "turbidity": 3.0, "strength": 0.02})
    return np.asarray(s.render(spp=spp, max_depth=6, seed=1).rgb)


def render_car_row(tile_w: int = 640, tile_h: int = 480, spp: int = 32) -> np.ndarray:
    """The gallery's car row (linear RGB): the library car :data:`CAR` at dataset resolution,
    clean and with each effect of :data:`CAR_EFFECTS`, a caption under each tile."""
    row = []
    for effect, params in CAR_EFFECTS:
        tile = _car_tile(effect, params, tile_w, tile_h, spp)
        ptxt = ", ".join(f"{k}={v}" for k, v in params.items())
        cap = _caption(f"{CAR}: {effect}\n{ptxt}" if ptxt else f"{CAR}: {effect}", tile_w, 32)
        cap = np.where(cap <= 0.04045, cap / 12.92, ((cap + 0.055) / 1.055) ** 2.4)
        row.append(np.concatenate([tile, cap], axis=0))
    return np.concatenate(row, axis=1).astype(np.float32)


#: The gallery's weather row (docs/weather.md): one frame of a street scenario under each
#: condition of synthgen.randomize.weather, its parameters as a dataset would draw them.
WEATHER_TILES: List[Tuple[str, Dict[str, Any]]] = [
    ("clear", {}),
    ("fog", {"fog": {"visibility": 120.0, "top": 30.0}}),
    ("ground fog", {"ground_fog": {"visibility": 30.0, "scale_height": 2.5, "coverage": 0.6, "feature_size": 30.0}}),
    ("clouds", {"clouds": {"visibility": 60.0, "bottom": 300.0, "top": 700.0, "coverage": 0.6}}),
    ("wet", {"wet": {"wetness": 0.9, "puddles": 0.15}}),
    ("snow", {"snow": {"amount": 0.9}}),
    ("dusk", {"dusk": {}}),
    ("night", {"night": {}}),
]


def render_weather_row(scenario: str, frame: int = 0, tile_w: int = 320, tile_h: int = 240, spp: int = 64,
                       tiles: Any = None, denoise: bool = True) -> np.ndarray:
    """The weather row (linear RGB): frame ``frame`` of ``scenario`` (its layout, camera and
    objects) with its weather section replaced by each of :data:`WEATHER_TILES` in turn
    (denoised, as scenarios/weather.yaml renders), a caption under each tile."""
    row = []
    for name, weather in (tiles or WEATHER_TILES):
        sc = load_scenario(scenario, overrides=[("weather", weather), ("resolution", [tile_w, tile_h]),
                                                ("render.spp", spp), ("render.denoise", bool(denoise))])
        check_inputs(sc)
        arrays, meta, _ = FrameRenderer(sc).render(frame)
        drawn = meta["weather"] or {}
        ptxt = "; ".join(f"{k}: " + ", ".join(f"{p}={_short(v)}" for p, v in params.items())
                         for k, params in drawn.items())
        cap = _caption(f"{name}\n{ptxt}" if ptxt else name, tile_w, 32)
        cap = np.where(cap <= 0.04045, cap / 12.92, ((cap + 0.055) / 1.055) ** 2.4)
        row.append(np.concatenate([np.asarray(arrays["rgb"], np.float32)[..., :3], cap], axis=0))
    return np.concatenate(row, axis=1).astype(np.float32)


def _short(v: Any) -> str:
    if isinstance(v, float):
        return f"{v:.3g}"
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(_short(x) for x in v) + "]"
    return str(v)


def write_weather_row(path: str, scenario: str, **kw: Any) -> str:
    return write_srgb_png(path, render_weather_row(scenario, **kw))


def write_gallery(path: str, **kw: Any) -> str:
    return write_srgb_png(path, render_gallery(**kw))


def write_car_row(path: str, **kw: Any) -> str:
    return write_srgb_png(path, render_car_row(**kw))
