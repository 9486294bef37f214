"""A photo's calibration file: the sidecar ``<photo>.yaml`` (``street.jpg.yaml`` or
``street.yaml``), a ``calibration.yaml`` for every photo of its folder, or the file the scenario's
``background.calibration`` names; a sidecar's keys override the folder's. In a shared file,
``{stem}`` and ``{name}`` in file paths stand for the photo's file name without and with its
extension (``labels: [{file: "{stem}.json", format: labelme}]``).

``synthgen schema --calibration`` prints the format; docs/augmented_photos.md explains it.
Every problem is reported as ``file:line:column: key: reason``.
"""
from __future__ import annotations

import os
from dataclasses import dataclass, field
from typing import Any, Dict, List, Optional, Sequence, Tuple

import numpy as np

from .._core import SynthgenError
from ..schema.errors import Loc, ValidationContext, show_value
from ..schema.fields import (REQUIRED, Bool, Choice, Field, FilePath, ListOf, MapOf, Number, Record, String,
                             Vector)
from ..schema.yaml_io import MarkedDict, MarkedList, read_yaml
from .calibration import (Calibration, fov_to_focal, ground_from_horizon, ground_from_plane, sun_from_shadow)
from .formats import focal_from_exif, read_cityscapes_camera, read_kitti_calib
from .labels import LABEL_FORMATS, LabelFile, RealObject, box_of, load_labels

__all__ = ["CALIBRATION_SCHEMA", "PhotoSetup", "find_calibration_files", "read_photo_setup", "read_depth",
           "FOLDER_FILE"]

#: The calibration file of every photo of a folder.
FOLDER_FILE = "calibration.yaml"


class _Points(Field):
    """A list of [u, v] image points (pixels) with at least ``min_points`` points."""

    def __init__(self, min_points: int, default: Any = REQUIRED, doc: str = ""):
        super().__init__(default, doc)
        self.min_points = min_points
        self.type_name = f"list of at least {min_points} [u, v] points (pixels)"

    def validate(self, value: Any, loc: Loc, ctx: ValidationContext) -> Any:
        if not isinstance(value, (list, tuple)) or len(value) < self.min_points:
            ctx.error(loc, f"expected a {self.type_name}, got {show_value(value)}")
        pt = Vector(2)
        return np.array([pt.validate(v, loc.index(i, value), ctx) for i, v in enumerate(value)], np.float64)


class _Horizon(Field):
    type_name = "image row (pixels) or two [u, v] points on the horizon"

    def validate(self, value: Any, loc: Loc, ctx: ValidationContext) -> Any:
        if isinstance(value, (int, float)) and not isinstance(value, bool):
            return Number().validate(value, loc, ctx)
        if isinstance(value, (list, tuple)) and len(value) == 2:
            return _Points(2).validate(value, loc, ctx)
        ctx.error(loc, f"expected an {self.type_name}, got {show_value(value)}")


class _MappedClass(String):
    """A scenario class a label file's class maps to, or null: that class's objects are dropped
    deliberately."""

    type_name = "string or null"

    def validate(self, value: Any, loc: Loc, ctx: ValidationContext) -> Any:
        return None if value is None else super().validate(value, loc, ctx)


_INTRINSICS = Record(
    {"fx": Number(None, min=0.0, min_open=True, doc="focal length in pixels along x"),
     "fy": Number(None, min=0.0, min_open=True, doc="focal length in pixels along y (default fx)"),
     "cx": Number(None, doc="principal point x, pixels (default: the image centre)"),
     "cy": Number(None, doc="principal point y, pixels (default: the image centre)"),
     "fov_x": Number(None, min=0.0, max=180.0, min_open=True, max_open=True,
                     doc="horizontal field of view, degrees (instead of fx, fy)"),
     "fov_y": Number(None, min=0.0, max=180.0, min_open=True, max_open=True,
                     doc="vertical field of view, degrees (instead of fx, fy)"),
     "sensor_width_mm": Number(None, min=0.0, min_open=True,
                               doc="sensor width in mm: with the EXIF FocalLength when the photo has no 35 mm "
                                   "equivalent"),
     "image_size": Vector(2, None, min=1.0, doc="[width, height] the intrinsics are for, when the photo was "
                                                "resized since (they are scaled)")},
    one_of=[], exclusive=[(("fx", "fy"), ("fov_x", "fov_y")), (("fov_x",), ("fov_y",))],
    requires={"fy": ["fx"]}, default=None, doc="the camera's intrinsics")

_GROUND = Record(
    {"camera_height": Number(None, min=0.0, min_open=True, doc="camera height above the ground, metres"),
     "pitch": Number(None, min=-89.0, max=89.0, doc="degrees the camera looks below the horizontal"),
     "roll": Number(None, min=-45.0, max=45.0, doc="degrees the camera is turned clockwise about its axis"),
     "horizon": _Horizon(None, doc="the horizon: an image row, or two [u, v] points on it (then the roll "
                                   "follows too); with camera_height, instead of pitch and roll"),
     "from_depth": Bool(False, doc="fit the ground plane to the photo's depth map (its region, else its lower "
                                   "third; RANSAC): for scenes without a horizon, such as a room's floor"),
     "plane": Record({"normal": Vector(3, doc="normal (pointing up) in camera coordinates (OpenCV: x right, "
                                              "y down, z forward)"),
                      "offset": Number(min=0.0, min_open=True, doc="d of n . X + d = 0: the camera height "
                                                                   "when n is a unit vector")},
                     default=None, doc="the ground plane n . X + d = 0 in camera coordinates")},
    exclusive=[(("pitch", "roll"), ("horizon",)), (("plane",), ("camera_height", "pitch", "roll", "horizon")),
               (("from_depth",), ("plane", "camera_height", "pitch", "roll", "horizon"))],
    default=None, doc="where the ground is: camera_height + pitch (+ roll), camera_height + horizon, or plane")

_SHADOW = Record(
    {"base": Vector(2, doc="image point where a vertical object (a pole, a post) meets the ground"),
     "tip": Vector(2, doc="image point of the tip of its shadow on the ground"),
     "top": Vector(2, None, doc="image point of the object's top (instead of height)"),
     "height": Number(None, min=0.0, min_open=True, doc="the object's height in metres (instead of top)")},
    one_of=[("top", "height")], default=None, doc="a shadow marked in the photo")

_SUN = Record(
    {"azimuth": Number(None, doc="compass azimuth, degrees (0 = behind the camera, 90 = its left, 180 = ahead)"),
     "elevation": Number(None, min=0.0, max=90.0, doc="degrees above the horizon"),
     "shadow": _SHADOW,
     "overcast": Bool(False, doc="no direct sun (an overcast day): a uniform sky lights the objects")},
    exclusive=[(("azimuth", "elevation"), ("shadow",)), (("azimuth", "elevation", "shadow"), ("overcast",))], requires={"azimuth": ["elevation"], "elevation": ["azimuth"]},
    default=None, doc="the sun's direction: azimuth + elevation, or a marked shadow")

_DEPTH = Record(
    {"file": String(doc="the photo's depth or disparity map: EXR / PFM / 16-bit PNG image, or .npy / .npz"),
     "kind": Choice(["depth", "disparity"], "depth", doc="depth: metres x scale; disparity: pixels"),
     "scale": Number(1.0, min=0.0, min_open=True, doc="metres per depth unit"),
     "focal": Number(None, min=0.0, min_open=True, doc="disparity: focal length in pixels (default fx)"),
     "baseline": Number(None, min=0.0, min_open=True, doc="disparity: stereo baseline in metres"),
     "doffs": Number(0.0, doc="disparity: x-difference of the principal points, pixels (Middlebury)")},
    default=None, doc="metric depth of the photo: inserted objects are hidden where it is nearer")

_LABELS = Record(
    {"file": String(doc="label file (paths in a folder's file may use {stem} and {name})"),
     "format": Choice(list(LABEL_FORMATS), doc="labelme, coco, yolo, kitti, csv (image,x0,y0,x1,y1[,class]), "
                                               "voc (Pascal VOC XML) or openalpr (plate .txt)"),
     "classes": MapOf(_MappedClass(None), None, doc="the file's class names -> the scenario's (a name mapped to "
                                                    "null is dropped; every class the file has must be listed)"),
     "names": ListOf(String(), None, doc="yolo: class names in the order of the class indices"),
     "class": String(None, doc="csv: the class of rows without a class column")},
    doc="a file of the photo's real labels")

_OBJECT = Record(
    {"class": String(doc="class name"),
     "box": Vector(4, None, doc="[x0, y0, x1, y1], pixels"),
     "polygon": _Points(3, None, doc="outline, [[u, v], ...] pixels")},
    one_of=[("box", "polygon")], doc="a real object the photo shows")

_REGION = _Points(3, doc="polygon [[u, v], ...] in pixels")

CALIBRATION_SCHEMA = Record(
    {"intrinsics": _INTRINSICS,
     "distortion": Vector(5, None, doc="OpenCV distortion coefficients [k1, k2, p1, p2, k3]"),
     "kitti": Record({"file": String(doc="KITTI calib file (paths in a folder's file may use {stem})"),
                      "camera": Choice(["P0", "P1", "P2", "P3"], "P2", doc="projection matrix")},
                     default=None, doc="intrinsics from a KITTI calibration file (give ground.camera_height: KITTI's "
                                       "is 1.65)"),
     "cityscapes": String(None, doc="Cityscapes camera.json: intrinsics, camera height, pitch, roll, road direction"),
     "ground": _GROUND,
     "region": ListOf(_REGION, None, doc="where objects may stand: polygons in pixels (the drivable area); "
                                         "default: the ground below the horizon"),
     "road_direction": Number(None, min=-180.0, max=180.0,
                              doc="the road's direction on the ground, degrees to the right of the camera's "
                                  "(objects' yaw is relative to it; default 0)"),
     "sun": _SUN,
     "depth": _DEPTH,
     "occluders": String(None, doc="mask image: non-zero pixels are real things in front of every inserted "
                                   "object"),
     "envmap": Record({"file": String(doc="equirectangular HDR image of the photo's surroundings"),
                       "rotation": Number(None, doc="degrees about the up axis (default: the map's sun, its "
                                                    "brightest pixel, turned to the photo's sun azimuth when "
                                                    "given; else 0)")},
                      default=None, doc="the photo's own HDR environment"),
     "labels": ListOf(_LABELS, None, doc="files of the photo's real labels"),
     "objects": ListOf(_OBJECT, None, doc="real objects written here (boxes or polygons)"),
     "ignore": ListOf(_OBJECT.extend({"class": String("ignore", doc="what it is (free text)")}), None,
                      doc="regions neither labelled nor used for training (boxes or polygons)"),
     "licence": String(None, doc="the photo's licence (recorded in every frame)"),
     "source": String(None, doc="where the photo comes from")},
    doc="a photo's calibration")


@dataclass
class PhotoSetup:
    """Everything a frame needs from one photo's calibration files (photo pixels)."""

    photo: str
    calibration: Calibration
    regions: List[np.ndarray] = field(default_factory=list)
    road_direction: float = 0.0
    sun: Optional[Tuple[float, float]] = None
    sun_source: str = ""
    overcast: bool = False
    depth: Optional[Dict[str, Any]] = None
    occluders: Optional[str] = None
    envmap: Optional[Tuple[str, Optional[float]]] = None
    objects: List[RealObject] = field(default_factory=list)
    labelled: bool = False
    licence: str = ""
    source: str = ""
    files: List[str] = field(default_factory=list)   #: calibration and label files read
    label_files: List[LabelFile] = field(default_factory=list)   #: the label files, their classes and mapping
    #: Where each key was given: "ground", "ground.horizon", ... -> (file, line, column).
    where: Dict[str, Tuple[str, int, int]] = field(default_factory=dict)

    def meta(self) -> Dict[str, Any]:
        return {"calibration": self.calibration.meta(), "road_direction": self.road_direction,
                "sun": None if self.sun is None else {"azimuth": self.sun[0], "elevation": self.sun[1],
                                                      "source": self.sun_source},
                "licence": self.licence, "source": self.source, "labelled": self.labelled,
                "calibration_files": list(self.files)}


#: A depth map file larger than this is refused before it is read.
MAX_DEPTH_BYTES = 1 << 30


def read_depth(setup: PhotoSetup, width: int, height: int) -> np.ndarray:
    """The photo's metric depth (H x W float32, +inf where unknown) from its calibration's
    ``depth``: an image (EXR, PFM, PNG) or a numpy .npy / .npz file, of depth x scale or of
    disparity (depth = baseline x focal / (disparity + doffs): Middlebury's convention)."""
    d = setup.depth
    path = d["file"]
    if os.path.getsize(path) > MAX_DEPTH_BYTES:
        raise SynthgenError(f"{path}: a depth map larger than {MAX_DEPTH_BYTES} bytes")
    if path.lower().endswith((".npy", ".npz")):
        try:
            a = np.load(path, allow_pickle=False)
            if isinstance(a, np.lib.npyio.NpzFile):
                with a:
                    if not a.files:
                        raise SynthgenError(f"{path}: the .npz file holds no array")
                    a = a[a.files[0]]
        except (OSError, ValueError) as e:
            raise SynthgenError(f"{path}: cannot read the depth map ({e})") from None
        a = np.asarray(a)
        if a.dtype.kind not in "fiu":
            raise SynthgenError(f"{path}: the depth map holds {a.dtype} values, not numbers")
        a = a.astype(np.float32)
    else:
        from .._core import read_image

        a = read_image(path, "linear", finite=False)
    if a.ndim == 3:
        a = a[:, :, 0]
    if a.shape != (height, width):
        raise SynthgenError(f"{path}: the depth map is {a.shape[1] if a.ndim == 2 else '?'} x {a.shape[0]}, the "
                            f"photo {width} x {height}")
    with np.errstate(divide="ignore", invalid="ignore"):
        if d["kind"] == "disparity":
            focal = d.get("focal") or setup.calibration.fx
            z = float(d["baseline"]) * float(focal) / (a + float(d["doffs"]))
        else:
            z = a * float(d["scale"])
    return np.where(np.isfinite(z) & (z > 0), z, np.inf).astype(np.float32)


def fit_ground_plane(depth: np.ndarray, k: Dict[str, float], regions: List[np.ndarray],
                     iterations: int = 400, tolerance: float = 0.02) -> Tuple[np.ndarray, float, int]:
    """(normal pointing at the camera, offset, inlier count) of the plane n . X + d = 0 (camera
    coordinates) that most of the depth map's points in ``regions`` (default: its lower third)
    lie on within ``tolerance`` metres x their distance / 10 m.

    NOTE: RANSAC (Fischler & Bolles 1981) with a fixed seed (deterministic), then a least-squares
    refit on the inliers (the smallest eigenvector of their covariance)."""
    from .labels import polygon_mask

    h, w = depth.shape
    if regions:
        mask = np.zeros((h, w), bool)
        for p in regions:
            mask |= polygon_mask(p, w, h)
    else:
        mask = np.zeros((h, w), bool)
        mask[2 * h // 3:] = True
    mask &= np.isfinite(depth)
    ys, xs = np.nonzero(mask)
    if len(ys) < 100:
        raise SynthgenError("from_depth: fewer than 100 pixels with a depth in the ground's region")
    step = max(1, len(ys) // 20000)
    ys, xs = ys[::step], xs[::step]
    z = depth[ys, xs].astype(np.float64)
    pts = np.stack([(xs + 0.5 - k["cx"]) / k["fx"] * z, (ys + 0.5 - k["cy"]) / k["fy"] * z, z], 1)
    tol = tolerance * np.maximum(z / 10.0, 0.1)
    rng = np.random.default_rng(0)
    best, best_n = None, -1
    for _ in range(iterations):
        a, b, c = pts[rng.choice(len(pts), 3, replace=False)]
        n = np.cross(b - a, c - a)
        if np.linalg.norm(n) < 1e-12:
            continue
        n /= np.linalg.norm(n)
        inl = np.abs((pts - a) @ n) < tol
        if inl.sum() > best_n:
            best, best_n = inl, int(inl.sum())
    if best is None or best_n < 50:
        raise SynthgenError("from_depth: no plane found in the depth map's ground region")
    q = pts[best]
    centre = q.mean(axis=0)
    n = np.linalg.eigh(np.cov((q - centre).T))[1][:, 0]
    d = -float(n @ centre)
    if d < 0:  # the normal towards the camera: the camera (origin) on its positive side
        n, d = -n, -d
    return n, d, best_n


def find_calibration_files(photo: str, shared: Optional[str] = None, entry: Optional[str] = None) -> List[str]:
    """The calibration files of a photo, the shared ones first: ``shared`` (the scenario's), the
    folder's ``calibration.yaml``, the sidecar, then ``entry`` (the scenario's photo entry's own).
    Two sidecars for one photo are an error."""
    out = []
    if shared:
        out.append(os.path.abspath(shared))
    folder = os.path.join(os.path.dirname(photo), FOLDER_FILE)
    if os.path.isfile(folder) and os.path.abspath(folder) not in out:
        out.append(os.path.abspath(folder))
    sidecars = [p for p in (photo + ".yaml", os.path.splitext(photo)[0] + ".yaml")
                if os.path.isfile(p) and os.path.basename(p) != FOLDER_FILE]
    if len(sidecars) == 2 and os.path.abspath(sidecars[0]) != os.path.abspath(sidecars[1]):
        raise SynthgenError(f"{photo}: two calibration sidecars ({os.path.basename(sidecars[0])} and "
                            f"{os.path.basename(sidecars[1])}): keep one")
    if sidecars:
        out.append(os.path.abspath(sidecars[0]))
    if entry and os.path.abspath(entry) not in out:
        out.append(os.path.abspath(entry))
    return out


def _substitute(tree: Any, photo: str) -> Any:
    """A copy of a YAML tree with {stem} / {name} replaced in strings (marks kept)."""
    if isinstance(tree, MarkedDict):
        out = MarkedDict((k, _substitute(v, photo)) for k, v in tree.items())
        out.mark, out.key_marks, out.value_marks = tree.mark, dict(tree.key_marks), dict(tree.value_marks)
        return out
    if isinstance(tree, MarkedList):
        out = MarkedList(_substitute(v, photo) for v in tree)
        out.mark, out.item_marks = tree.mark, list(tree.item_marks)
        return out
    if isinstance(tree, str):
        name = os.path.basename(photo)
        return tree.replace("{stem}", os.path.splitext(name)[0]).replace("{name}", name)
    return tree


def _path(ctx: ValidationContext, value: str, loc: Loc) -> str:
    return str(FilePath().validate(value, loc, ctx))


class _Reader:
    """Validates the files of one photo, in order, and keeps each key's file and location."""

    def __init__(self, photo: str, files: Sequence[str]):
        self.photo = photo
        self.values: Dict[str, Tuple[Any, ValidationContext, Loc]] = {}
        self.raw: Dict[str, Any] = {}   #: each key's YAML value (its items' positions)
        for f in files:
            data = read_yaml(f)
            if data is None:
                continue
            ctx = ValidationContext(f, os.path.dirname(f))
            data = _substitute(data, photo)
            v = CALIBRATION_SCHEMA.validate(data, Loc.root(data), ctx)
            for k in v.given:
                self.values[k] = (v[k], ctx, v.locs[k])
                self.raw[k] = data.get(k)

    def get(self, key: str) -> Any:
        return self.values[key][0] if key in self.values else None

    def error(self, key: str, reason: str):
        if key in self.values:
            _, ctx, loc = self.values[key]
            ctx.error(loc, reason)
        raise SynthgenError(f"{self.photo}: {reason}")

    def loc(self, key: str, sub: Optional[str] = None) -> Tuple[ValidationContext, Loc]:
        """The file (its context) and location of ``key`` (``sub``: a path below it, ``[0].file``)."""
        _, ctx, loc = self.values[key]
        if sub and sub.startswith("["):  # an item: its own line where the YAML marks it
            i, rest = sub[1:].split("]", 1)
            marks = getattr(self.raw.get(key), "item_marks", None) or []
            line, column = marks[int(i)] if int(i) < len(marks) and marks[int(i)] else (loc.line, loc.column)
            loc = Loc(f"{loc.path}[{i}]{rest}", line, column)
        elif sub:
            loc = Loc(f"{loc.path}.{sub}", loc.line, loc.column)
        return ctx, loc

    def path(self, key: str, value: str, sub: Optional[str] = None) -> str:
        """A file a calibration names: relative to the calibration file, else to the photo's folder
        (a calibration kept apart from photos fetched into the asset cache names their labels)."""
        ctx, loc = self.loc(key, sub)
        beside = os.path.join(os.path.dirname(self.photo), os.path.expanduser(value))
        if not os.path.isabs(value) and not os.path.isfile(os.path.join(ctx.base_dir, value)) and os.path.isfile(beside):
            return os.path.abspath(beside)
        return _path(ctx, value, loc)


def _check_box(o: RealObject, where: str = "") -> None:
    x0, y0, x1, y1 = o.box
    if not (x1 > x0 and y1 > y0):
        raise SynthgenError(f"{where + ': ' if where else ''}an empty box {list(o.box)}")


def read_photo_setup(photo: str, width: int, height: int, *, shared: Optional[str] = None,
                     entry: Optional[str] = None, exif_focal_mm: float = 0.0,
                     exif_focal_35mm: float = 0.0) -> PhotoSetup:
    """A photo's :class:`PhotoSetup` from its calibration files (see the module docstring);
    ``width`` x ``height``: the photo's size (after EXIF orientation). Raises SceneFileError /
    SynthgenError naming the file, key and reason; a photo without calibration files, without
    intrinsics or without a ground is refused."""
    files = find_calibration_files(photo, shared, entry)
    if not files:
        raise SynthgenError(f"{photo}: no calibration (write {os.path.basename(photo)}.yaml beside it, a "
                            f"{FOLDER_FILE} for its folder, or name one in background.calibration; "
                            "docs/augmented_photos.md)")
    r = _Reader(photo, files)
    assumptions: List[str] = []
    sources: List[str] = []
    extra: Dict[str, float] = {}
    # -- intrinsics: given > KITTI > Cityscapes > EXIF ---------------------------------------
    k: Dict[str, float] = {}
    intr = r.get("intrinsics")
    if r.get("kitti") is not None:
        kf = r.get("kitti")
        k = read_kitti_calib(r.path("kitti", kf["file"], "file"), kf["camera"])
        sources.append(f"KITTI {kf['camera']} of {os.path.basename(kf['file'])}")
    if r.get("cityscapes") is not None:
        cs = read_cityscapes_camera(r.path("cityscapes", r.get("cityscapes")))
        if not k:
            k = {key: cs[key] for key in ("fx", "fy", "cx", "cy")}
        extra = {key: cs[key] for key in ("camera_height", "pitch", "roll", "road_direction")}
        sources.append(f"Cityscapes {os.path.basename(r.get('cityscapes'))}")
    scale_from = None
    if intr is not None:
        if intr.get("image_size") is not None:
            scale_from = tuple(float(v) for v in intr["image_size"])
        iw, ih = scale_from or (float(width), float(height))
        if intr.get("fx") is not None:
            k = {"fx": intr["fx"], "fy": intr["fy"] if intr.get("fy") is not None else intr["fx"]}
        elif intr.get("fov_x") is not None:
            f = fov_to_focal(intr["fov_x"], iw)
            k = {"fx": f, "fy": f}
        elif intr.get("fov_y") is not None:
            f = fov_to_focal(intr["fov_y"], ih)
            k = {"fx": f, "fy": f}
        elif intr.get("sensor_width_mm") is not None:
            got = focal_from_exif(int(iw), int(ih), 0.0, exif_focal_mm, intr["sensor_width_mm"])
            if got is None:
                r.error("intrinsics", "sensor_width_mm needs the photo's EXIF FocalLength, which it does not have")
            k = {"fx": got[0], "fy": got[0]}
            sources.append(got[1])
        if k:
            k["cx"] = intr["cx"] if intr.get("cx") is not None else k.get("cx", 0.5 * iw)
            k["cy"] = intr["cy"] if intr.get("cy") is not None else k.get("cy", 0.5 * ih)
            sources.append("intrinsics")
    if not k:
        got = focal_from_exif(width, height, exif_focal_35mm, 0.0)
        if got is None:
            raise SynthgenError(f"{photo}: no intrinsics: give intrinsics (fx, fy, cx, cy or a field of view) in "
                                f"{os.path.basename(files[-1])}, a kitti or cityscapes file, or use a photo whose "
                                "EXIF has its 35 mm equivalent focal length")
        k = {"fx": got[0], "fy": got[0], "cx": 0.5 * width, "cy": 0.5 * height}
        sources.append(got[1])
        assumptions.append("intrinsics from EXIF: principal point at the image centre, no distortion")
    if scale_from is not None and (abs(scale_from[0] - width) > 0.5 or abs(scale_from[1] - height) > 0.5):
        sx, sy = width / scale_from[0], height / scale_from[1]
        if abs(sx / sy - 1.0) > 0.01:
            r.error("intrinsics", f"image_size {scale_from[0]:g} x {scale_from[1]:g} and the photo's {width} x "
                                  f"{height} differ in aspect ratio (a crop, not a resize: give its intrinsics)")
        k = {"fx": k["fx"] * sx, "fy": k["fy"] * sy, "cx": (k["cx"] + 0.5) * sx - 0.5, "cy": (k["cy"] + 0.5) * sy - 0.5}
    distortion = tuple(float(v) for v in (r.get("distortion") or (0.0,) * 5))
    # -- ground ------------------------------------------------------------------------------
    g = r.get("ground") or {}
    height_m = g.get("camera_height") if g.get("camera_height") is not None else extra.get("camera_height")
    pitch = roll = None
    if g.get("from_depth"):
        if r.get("depth") is None:
            r.error("ground", "from_depth needs the photo's depth map (depth)")
        d = dict(r.get("depth"))
        d["file"] = r.path("depth", d["file"], "file")
        probe = PhotoSetup(photo=photo, calibration=Calibration(width=int(width), height=int(height), fx=float(k["fx"]),
                                                                fy=float(k["fy"]), cx=float(k["cx"]), cy=float(k["cy"]),
                                                                camera_height=1.0), depth=d)
        z = read_depth(probe, int(width), int(height))
        try:
            normal, offset, inliers = fit_ground_plane(z, k, list(r.get("region") or []))
        except SynthgenError as e:
            r.error("ground", str(e))
        height_m, pitch, roll = ground_from_plane(normal, offset)
        sources.append(f"ground plane fitted to the depth map ({inliers} points)")
    elif g.get("plane") is not None:
        height_m, pitch, roll = ground_from_plane(g["plane"]["normal"], g["plane"]["offset"])
        sources.append("ground plane")
    elif g.get("horizon") is not None:
        hz = g["horizon"]
        pitch, roll = ground_from_horizon(hz if isinstance(hz, float) else [tuple(p) for p in hz],
                                          k["fx"], k["fy"], k["cx"], k["cy"])
        assumptions.append("ground from the horizon: flat and level out to the horizon" +
                           ("" if not isinstance(hz, float) else ", no camera roll"))
        sources.append("horizon")
    else:
        pitch = g.get("pitch") if g.get("pitch") is not None else extra.get("pitch")
        roll = g.get("roll") if g.get("roll") is not None else extra.get("roll", 0.0)
    if height_m is None or pitch is None:
        r.error("ground", "the ground is not given: ground.camera_height with pitch (and roll) or a horizon, "
                          "or ground.plane, or a cityscapes file")
    cal = Calibration(width=int(width), height=int(height), fx=float(k["fx"]), fy=float(k["fy"]), cx=float(k["cx"]),
                      cy=float(k["cy"]), camera_height=float(height_m), pitch=float(pitch), roll=float(roll or 0.0),
                      distortion=distortion, source=", ".join(sources), assumptions=assumptions)
    try:
        cal.camera()
    except SynthgenError as e:
        r.error("distortion" if "distortion" in r.values and "distortion" in str(e) else "intrinsics", str(e))
    setup = PhotoSetup(photo=os.path.abspath(photo), calibration=cal, files=list(files))
    for key, (value, ctx, loc) in r.values.items():
        setup.where[key] = (ctx.source, loc.line, loc.column)
        for sub in getattr(value, "given", ()):
            sl = value.locs.get(sub, loc)
            setup.where[f"{key}.{sub}"] = (ctx.source, sl.line, sl.column)
    # -- placement -----------------------------------------------------------------------------
    setup.regions = list(r.get("region") or [])
    rd = r.get("road_direction")
    setup.road_direction = float(rd if rd is not None else extra.get("road_direction", 0.0))
    # -- sun, depth, environment -------------------------------------------------------------------
    sun = r.get("sun")
    if sun is not None and sun.get("overcast"):
        setup.overcast = True
    elif sun is not None and sun.get("azimuth") is None and sun.get("shadow") is None:
        r.error("sun", "give the sun's azimuth and elevation, a marked shadow, or overcast: true")
    elif sun is not None:
        if sun.get("shadow") is not None:
            sh = sun["shadow"]
            try:
                setup.sun = sun_from_shadow(cal, sh["base"], sh["tip"], sh.get("top"), sh.get("height"))
            except SynthgenError as e:
                r.error("sun", str(e))
            setup.sun_source = "marked shadow"
        else:
            setup.sun = (float(sun["azimuth"]), float(sun["elevation"]))
            setup.sun_source = "given"
    if r.get("depth") is not None:
        d = dict(r.get("depth"))
        d["file"] = r.path("depth", d["file"], "file")
        if d["kind"] == "disparity" and d.get("baseline") is None:
            r.error("depth", "a disparity map needs the stereo baseline (depth.baseline, metres)")
        setup.depth = d
    if r.get("occluders") is not None:
        setup.occluders = r.path("occluders", r.get("occluders"))
    if r.get("envmap") is not None:
        e = r.get("envmap")
        setup.envmap = (r.path("envmap", e["file"], "file"), None if e["rotation"] is None else float(e["rotation"]))
    # -- real labels -----------------------------------------------------------------------------
    objs: List[RealObject] = []
    # A label file's errors name the calibration file (and key) that lists it, then the label
    # file's own place: the user sees which calibration brought the file in.
    for i, lab in enumerate(r.get("labels") or []):
        path = r.path("labels", lab["file"], f"[{i}].file")
        setup.files.append(path)
        ctx, loc = r.loc("labels", f"[{i}].file")
        with ctx.core(loc):
            lf = load_labels(path, lab["format"], photo, (width, height), lab.get("classes"), lab.get("names"),
                             lab.get("class"))
            for o in lf.objects:
                _check_box(o, o.source)
        setup.label_files.append(lf)
        objs += lf.objects
    for key, ignore in (("objects", False), ("ignore", True)):
        for i, o in enumerate(r.get(key) or []):
            poly = o.get("polygon")
            box = list(o["box"]) if o.get("box") is not None else box_of(poly)
            objs.append(RealObject(o["class"], box, poly, ignore, f"{key}[{i}]"))
            ctx, loc = r.loc(key, f"[{i}]")
            with ctx.core(loc):
                _check_box(objs[-1])
    setup.objects = objs
    setup.labelled = any(key in r.values for key in ("labels", "objects"))
    setup.licence = r.get("licence") or ""
    setup.source = r.get("source") or ""
    return setup
