"""Readers of the label files users have: labelme JSON, COCO JSON, YOLO txt, KITTI label txt,
CSV (``image,x0,y0,x1,y1[,class]``), Pascal VOC XML and OpenALPR's plate ``.txt``
(``file<TAB>x<TAB>y<TAB>w<TAB>h<TAB>PLATE_TEXT``, class ``plate``). :func:`read_label_file` reads the objects
of one image with the file's own class names (the calibration's ``classes`` mapping is applied by
:mod:`.labels`), :func:`label_images` lists the images a file names (every image of a COCO or CSV
file): one module for a photo's real labels and for whole labelled sets.

An object is a :class:`RealObject`: a box (pixels, x0 y0 x1 y1, continuous coordinates), maybe a
polygon, a class name, ``ignore`` (COCO ``iscrowd``, KITTI ``DontCare``, VOC ``difficult``) and
where it came from. Every error names the file, the line or index, and the reason; files are read
with a size limit, XML without DTDs or entity declarations, and CSV rows compactly."""
from __future__ import annotations

import csv
import io
import json
import math
import os
from collections import OrderedDict
from dataclasses import dataclass
from typing import Any, Dict, List, Optional, Sequence, Tuple

import numpy as np

from .._core import SynthgenError
from .formats import MAX_CALIB_BYTES

__all__ = ["RealObject", "read_label_file", "label_images", "read_label_set", "LabelledImage", "LABEL_FORMATS",
           "MULTI_IMAGE_FORMATS", "OPENALPR_CLASS", "box_of"]

LABEL_FORMATS = ("labelme", "coco", "yolo", "kitti", "csv", "voc", "openalpr")
#: Formats of one file for many images (the others have a file per image).
MULTI_IMAGE_FORMATS = ("coco", "csv")
#: The class of an OpenALPR file's boxes (the file names none: every line is a licence plate).
OPENALPR_CLASS = "plate"
_MAX_LABEL_BYTES = 64 * MAX_CALIB_BYTES
#: A VOC file describes one image: a few kilobytes.
_MAX_VOC_BYTES = 4 * MAX_CALIB_BYTES
#: A CSV file of boxes of many images: 16 MiB is about 300000 rows (about 1.2 million short ones).
_MAX_CSV_BYTES = 16 * MAX_CALIB_BYTES
#: More boxes than this for one image are refused (a CSV file of one image's boxes).
_MAX_OBJECTS = 20000
#: Element nesting deeper than this is no VOC file.
_MAX_XML_DEPTH = 32


@dataclass
class RealObject:
    cls: str                              #: class name (mapped to the scenario's)
    box: Sequence[float]                  #: x0, y0, x1, y1 in photo pixels
    polygon: Optional[np.ndarray] = None  #: N x 2 photo pixels, or None (the box)
    ignore: bool = False                  #: an ignore region (crowd, DontCare, difficult)
    source: str = ""                      #: file (and line / index) it came from

    def meta(self) -> Dict[str, Any]:
        d = {"class": self.cls, "box": [float(v) for v in self.box], "ignore": self.ignore, "source": self.source}
        if self.polygon is not None:
            d["polygon"] = np.asarray(self.polygon, float).round(2).tolist()
        return d


def box_of(points: np.ndarray) -> List[float]:
    p = np.asarray(points, np.float64)
    return [float(p[:, 0].min()), float(p[:, 1].min()), float(p[:, 0].max()), float(p[:, 1].max())]


def _read(path: str, what: str, limit: int = _MAX_LABEL_BYTES) -> str:
    if not os.path.isfile(path):
        raise SynthgenError(f"{path}: {what} not found")
    if os.path.getsize(path) > limit:
        raise SynthgenError(f"{path}: a {what} of {os.path.getsize(path)} bytes is larger than the {limit} bytes "
                            "one can be")
    try:
        with open(path, "r", encoding="utf-8-sig") as f:
            return f.read()
    except (OSError, UnicodeDecodeError) as e:
        raise SynthgenError(f"{path}: cannot read the {what} ({e})") from None


#: Parsed multi-image files (COCO, CSV), so that the photos of a folder sharing one file parse it
#: once: (path, format) -> ((inode, size, mtime), parsed). Parsed data is never modified. A COCO
#: file's parsed JSON takes about ten times its size: only small ones are kept (CSV rows are compact).
_PARSED: "OrderedDict[Tuple[str, str], Tuple[Tuple[int, int, int], Any]]" = OrderedDict()
_MAX_KEPT_JSON_BYTES = 8 * MAX_CALIB_BYTES


def _cached(path: str, fmt: str, parse) -> Any:
    key = (os.path.abspath(path), fmt)
    try:
        st = os.stat(path)
        stamp = (st.st_ino, st.st_size, st.st_mtime_ns)
        if fmt == "coco" and st.st_size > _MAX_KEPT_JSON_BYTES:
            stamp = None
    except OSError:
        stamp = None
    hit = _PARSED.get(key)
    if stamp is not None and hit is not None and hit[0] == stamp:
        _PARSED.move_to_end(key)
        return hit[1]
    value = parse()
    if stamp is not None:
        _PARSED[key] = (stamp, value)
        while len(_PARSED) > 4:
            _PARSED.popitem(last=False)
    return value


def _json(path: str, what: str) -> Any:
    try:
        return json.loads(_read(path, what))
    except json.JSONDecodeError as e:
        raise SynthgenError(f"{path}:{e.lineno}: not JSON ({e.msg})") from None


def _finite_points(pts: Any, where: str) -> np.ndarray:
    try:
        p = np.asarray(pts, np.float64)
    except (TypeError, ValueError):
        raise SynthgenError(f"{where}: points must be [[x, y], ...] numbers") from None
    if p.ndim != 2 or p.shape[1] != 2 or len(p) < 1 or not np.all(np.isfinite(p)):
        raise SynthgenError(f"{where}: points must be [[x, y], ...] finite numbers")
    return p


def _file_name(image: str) -> str:
    """The file name of an image path written on any system (``dir\\a.jpg`` too)."""
    return str(image).replace("\\", "/").rsplit("/", 1)[-1]


def _same_image(written: str, image: str) -> bool:
    """Whether a label file's image name is ``image``: by file name, else (one or the other
    without an extension, or another one) by stem."""
    a, b = _file_name(written), _file_name(image)
    return a == b or os.path.splitext(a)[0] == os.path.splitext(b)[0]


def _labelme(path: str, photo: str, size) -> List[RealObject]:
    d = _json(path, "labelme file")
    if not isinstance(d, dict) or not isinstance(d.get("shapes"), list):
        raise SynthgenError(f"{path}: not a labelme file (no 'shapes' list)")
    _check_size(path, d.get("imageWidth"), d.get("imageHeight"), size)
    out = []
    for i, s in enumerate(d["shapes"]):
        where = f"{path}: shapes[{i}]"
        if not isinstance(s, dict) or not isinstance(s.get("label"), str):
            raise SynthgenError(f"{where}: a shape needs a 'label' and 'points'")
        p = _finite_points(s.get("points"), where)
        kind = s.get("shape_type") or "polygon"
        if kind == "rectangle" and len(p) == 2:
            box, poly = box_of(p), None
        elif kind == "circle" and len(p) == 2:
            r = float(np.hypot(*(p[1] - p[0])))
            box, poly = [p[0, 0] - r, p[0, 1] - r, p[0, 0] + r, p[0, 1] + r], None
        elif kind in ("polygon", "linestrip") and len(p) >= 3:
            box, poly = box_of(p), p
        elif kind in ("point", "points", "line") or (kind == "linestrip" and len(p) < 3):
            continue  # points and lines mark no object
        elif kind in ("polygon", "rectangle", "circle"):  # an object that cannot be read: never dropped
            need = "at least 3 points" if kind == "polygon" else "2 points"
            raise SynthgenError(f"{where}: a {kind} needs {need}, got {len(p)} (label '{s['label']}')")
        else:
            raise SynthgenError(f"{where}: shape_type '{kind}' is not read (polygon, rectangle, circle; point, "
                                f"line and linestrip mark no object): convert it to a polygon (label '{s['label']}')")
        out.append(RealObject(s["label"], box, poly, False, where))
    return out


def _coco_file(path: str) -> Dict[str, Any]:
    d = _json(path, "COCO file")
    if not isinstance(d, dict) or not all(isinstance(d.get(k), list) for k in ("images", "annotations", "categories")):
        raise SynthgenError(f"{path}: not a COCO file (needs images, annotations and categories lists)")
    return d


def _coco(path: str, photo: str, size) -> List[RealObject]:
    d = _cached(path, "coco", lambda: _coco_file(path))
    name = _file_name(photo)
    image = next((im for im in d["images"] if isinstance(im, dict)
                  and _file_name(str(im.get("file_name", ""))) == name), None)
    if image is None:
        raise SynthgenError(f"{path}: no image with file_name '{name}'")
    _check_size(path, image.get("width"), image.get("height"), size)
    cats = {c.get("id"): str(c.get("name")) for c in d["categories"] if isinstance(c, dict)}
    return [_coco_object(path, i, a, cats) for i, a in enumerate(d["annotations"])
            if isinstance(a, dict) and a.get("image_id") == image.get("id")]


def _coco_object(path: str, i: int, a: Dict[str, Any], cats: Dict[Any, str]) -> RealObject:
    where = f"{path}: annotations[{i}]"
    bb = a.get("bbox")
    if (not isinstance(bb, list) or len(bb) != 4 or
            not all(isinstance(v, (int, float)) and math.isfinite(v) for v in bb)):
        raise SynthgenError(f"{where}: bbox must be [x, y, width, height]")
    if a.get("category_id") not in cats:
        raise SynthgenError(f"{where}: category_id {a.get('category_id')!r} is not in categories")
    poly = None
    seg = a.get("segmentation")
    if isinstance(seg, list) and seg and isinstance(seg[0], list) and len(seg[0]) >= 6:
        poly = _finite_points(np.asarray(seg[0], float).reshape(-1, 2), where)
    x, y, w, h = (float(v) for v in bb)
    return RealObject(cats[a["category_id"]], [x, y, x + w, y + h], poly, bool(a.get("iscrowd", 0)), where)


def _yolo(path: str, photo: str, size, names: Optional[Sequence[str]]) -> List[RealObject]:
    if size is None:
        raise SynthgenError(f"{path}: YOLO labels are fractions of the image's size: it must be known")
    w, h = size
    out = []
    for n, line in enumerate(_read(path, "YOLO label file").splitlines(), 1):
        if not line.strip():
            continue
        parts = line.split()
        try:
            c = int(parts[0])
            v = [float(x) for x in parts[1:5]]
        except (ValueError, IndexError):
            raise SynthgenError(f"{path}:{n}: expected 'class cx cy w h', got '{line.strip()[:60]}'") from None
        if len(v) != 4 or not all(math.isfinite(x) for x in v) or c < 0 or (names and c >= len(names)):
            span = f" with class in 0..{len(names) - 1}" if names else ""
            raise SynthgenError(f"{path}:{n}: expected 'class cx cy w h'{span}, got '{line.strip()[:60]}'")
        if not all(0.0 <= x <= 1.0 for x in v) or v[2] <= 0.0 or v[3] <= 0.0:
            raise SynthgenError(
                f"{path}:{n}: YOLO's cx cy w h are fractions of the image's width and height, in [0, 1] (w and h "
                f"above 0), got '{line.strip()[:60]}' (pixel coordinates? divide x and w by the width {w}, "
                f"y and h by the height {h})")
        cx, cy, bw, bh = v
        out.append(RealObject(str(names[c]) if names else str(c),
                              [(cx - bw / 2) * w, (cy - bh / 2) * h, (cx + bw / 2) * w, (cy + bh / 2) * h],
                              None, False, f"{path}:{n}"))
    return out


def _kitti(path: str, photo: str, size) -> List[RealObject]:
    out = []
    for n, line in enumerate(_read(path, "KITTI label file").splitlines(), 1):
        parts = line.split()
        if not parts:
            continue
        try:
            box = [float(x) for x in parts[4:8]]
        except ValueError:
            box = []
        if len(box) != 4 or not all(math.isfinite(x) for x in box):
            raise SynthgenError(f"{path}:{n}: expected a KITTI label line (type truncated occluded alpha "
                                f"x0 y0 x1 y1 ...), got '{line.strip()[:60]}'")
        out.append(RealObject(parts[0], box, None, parts[0] == "DontCare", f"{path}:{n}"))
    return out


#: Header names a CSV file's four box columns may have (any case), all meaning x0, y0, x1, y1.
_CSV_BOX_HEADERS = (("x0", "y0", "x1", "y1"), ("xmin", "ymin", "xmax", "ymax"), ("x_min", "y_min", "x_max", "y_max"),
                    ("x1", "y1", "x2", "y2"), ("left", "top", "right", "bottom"))


def _number(s: str) -> Optional[float]:
    try:
        v = float(s)
    except ValueError:
        return None
    return v if math.isfinite(v) else None


@dataclass
class _CsvTable:
    """A CSV label file's rows, compactly (a row costs 52 bytes, not a few hundred)."""

    images: List[str]      #: distinct image names as written, in order of first appearance
    classes: List[str]     #: distinct class names
    line: np.ndarray       #: per row: its line in the file
    image: np.ndarray      #: per row: index into images
    cls: np.ndarray        #: per row: index into classes, -1 for none
    box: np.ndarray        #: per row: x0, y0, x1, y1


def _csv_file(path: str) -> _CsvTable:
    from array import array

    text = _read(path, "CSV label file", _MAX_CSV_BYTES)
    reader = csv.reader(io.StringIO(text, newline=""))
    images: Dict[str, int] = {}
    classes: Dict[str, int] = {}
    line, image, cls, box = array("q"), array("i"), array("i"), array("d")
    first = True
    try:
        for row in reader:
            n = reader.line_num
            row = [c.strip() for c in row]
            if not any(row):
                continue
            if first and len(row) >= 2 and _number(row[1]) is None:
                first = False
                names = tuple(c.lower() for c in row[1:5])
                if len(row) not in (5, 6) or names not in _CSV_BOX_HEADERS:
                    raise SynthgenError(
                        f"{path}:{n}: the header '{','.join(row)[:80]}' is not image,x0,y0,x1,y1[,class] (box "
                        f"columns named {' or '.join(','.join(h) for h in _CSV_BOX_HEADERS)}: corners, not a "
                        "width and height)")
                continue
            first = False
            if len(row) not in (5, 6):
                raise SynthgenError(f"{path}:{n}: expected image,x0,y0,x1,y1[,class], got {len(row)} columns: "
                                    f"'{','.join(row)[:80]}'")
            v = [_number(c) for c in row[1:5]]
            if not row[0] or any(x is None for x in v):
                raise SynthgenError(f"{path}:{n}: expected an image name and four finite numbers x0,y0,x1,y1, got "
                                    f"'{','.join(row)[:80]}'")
            if not (v[2] > v[0] and v[3] > v[1]):
                raise SynthgenError(f"{path}:{n}: x1 must be greater than x0 and y1 than y0 (corners of a box), got "
                                    f"'{','.join(row)[:80]}'")
            line.append(n)
            image.append(images.setdefault(row[0], len(images)))
            cls.append(classes.setdefault(row[5], len(classes)) if len(row) == 6 and row[5] else -1)
            box.extend(v)
    except csv.Error as e:
        raise SynthgenError(f"{path}:{reader.line_num}: not CSV ({e})") from None
    return _CsvTable(list(images), list(classes), np.frombuffer(line, np.int64), np.frombuffer(image, np.int32),
                     np.frombuffer(cls, np.int32), np.frombuffer(box, np.float64).reshape(-1, 4))


def _csv(path: str, photo: str, size, default_class: Optional[str]) -> List[RealObject]:
    t: _CsvTable = _cached(path, "csv", lambda: _csv_file(path))
    name = _file_name(photo)
    mine = [i for i, im in enumerate(t.images) if _file_name(im) == name] or \
        [i for i, im in enumerate(t.images) if _same_image(im, name)]
    if len(mine) > 1:
        raise SynthgenError(f"{path}: rows of several images match '{name}': "
                            f"{', '.join(t.images[i] for i in mine[:5])}{', ...' if len(mine) > 5 else ''}")
    if not mine:
        raise SynthgenError(f"{path}: no row for image '{name}' (the file has boxes of {len(t.images)} images: "
                            f"{', '.join(t.images[:3])}{', ...' if len(t.images) > 3 else ''}); a photo without real "
                            "objects declares 'objects: []' instead")
    rows = np.flatnonzero(t.image == mine[0])
    if len(rows) > _MAX_OBJECTS:
        raise SynthgenError(f"{path}: {len(rows)} boxes for image '{t.images[mine[0]]}', more than the "
                            f"{_MAX_OBJECTS} one image can have")
    return _csv_objects(path, t, rows, default_class)


def _csv_objects(path: str, t: _CsvTable, rows: np.ndarray, default_class: Optional[str]) -> List[RealObject]:
    out = []
    for r in rows.tolist():
        c = int(t.cls[r])
        if c < 0 and default_class is None:
            raise SynthgenError(f"{path}:{t.line[r]}: the row has no class (image,x0,y0,x1,y1,class): give the class "
                                "of the file's boxes (the labels entry's 'class')")
        out.append(RealObject(t.classes[c] if c >= 0 else str(default_class), t.box[r].tolist(), None, False,
                              f"{path}:{t.line[r]}"))
    return out


class _Element:
    """An XML element with the line it starts on."""

    __slots__ = ("tag", "line", "children", "text")

    def __init__(self, tag: str, line: int):
        self.tag, self.line, self.children, self.text = tag, line, [], ""

    def find(self, tag: str) -> Optional["_Element"]:
        return next((c for c in self.children if c.tag == tag), None)

    def findall(self, tag: str) -> List["_Element"]:
        return [c for c in self.children if c.tag == tag]


def _xml(path: str, what: str) -> _Element:
    """The root of a small XML file: expat with DTDs (and so entity declarations: no entity
    expansion bombs, no external entities) refused, nesting bounded."""
    from xml.parsers import expat

    text = _read(path, what, _MAX_VOC_BYTES)
    p = expat.ParserCreate()
    p.SetParamEntityParsing(expat.XML_PARAM_ENTITY_PARSING_NEVER)
    stack: List[_Element] = []
    root: List[_Element] = []

    def refuse(*_a):
        raise SynthgenError(f"{path}:{p.CurrentLineNumber}: a {what} with a DTD or entity declarations is refused")

    def start(tag, _attrs):
        if len(stack) >= _MAX_XML_DEPTH:
            raise SynthgenError(f"{path}:{p.CurrentLineNumber}: elements nested deeper than {_MAX_XML_DEPTH}")
        e = _Element(tag, p.CurrentLineNumber)
        (stack[-1].children if stack else root).append(e)
        stack.append(e)

    def end(_tag):
        stack.pop()

    def chars(data):
        if stack and len(stack[-1].text) < 4096:
            stack[-1].text += data

    p.StartDoctypeDeclHandler = refuse
    p.EntityDeclHandler = refuse
    p.UnparsedEntityDeclHandler = refuse
    p.ExternalEntityRefHandler = refuse
    p.StartElementHandler, p.EndElementHandler, p.CharacterDataHandler = start, end, chars
    try:
        p.Parse(text, True)
    except expat.ExpatError as e:
        raise SynthgenError(f"{path}:{e.lineno}: not XML ({expat.ErrorString(e.code)})") from None
    return root[0]


def _voc(path: str, photo: str, size) -> List[RealObject]:
    root = _xml(path, "Pascal VOC file")
    if root.tag != "annotation":
        raise SynthgenError(f"{path}:{root.line}: not a Pascal VOC file (its root is <{root.tag}>, not <annotation>)")
    fn = root.find("filename")
    if fn is not None and fn.text.strip() and not _same_image(fn.text.strip(), photo):
        raise SynthgenError(f"{path}:{fn.line}: its labels are for image '{fn.text.strip()}', the photo is "
                            f"'{_file_name(photo)}'")
    sz = root.find("size")
    if sz is not None:
        dims = [sz.find(k) for k in ("width", "height")]
        if all(d is not None for d in dims):
            try:
                w, h = (int(d.text.strip()) for d in dims)
            except ValueError:
                raise SynthgenError(f"{path}:{sz.line}: size: width and height must be whole numbers") from None
            if w > 0 and h > 0:  # some tools write 0 x 0
                _check_size(path, w, h, size)
    out = []
    for ob in root.findall("object"):
        where = f"{path}:{ob.line}"
        name, bb = ob.find("name"), ob.find("bndbox")
        if name is None or not name.text.strip() or bb is None:
            raise SynthgenError(f"{where}: an <object> needs a <name> and a <bndbox>")
        v = []
        for k in ("xmin", "ymin", "xmax", "ymax"):
            e = bb.find(k)
            x = None if e is None else _number(e.text.strip())
            if x is None:
                raise SynthgenError(f"{path}:{(e or bb).line}: bndbox: {k} must be a finite number")
            v.append(x)
        if not (v[2] >= v[0] and v[3] >= v[1]):
            raise SynthgenError(f"{path}:{bb.line}: bndbox: xmax must be at least xmin and ymax at least ymin, got "
                                f"{v}")
        diff = ob.find("difficult")
        difficult = diff is not None and diff.text.strip() not in ("", "0")
        # NOTE: VOC's coordinates are 1-based pixel indices, inclusive (xmin 1, xmax W: the whole
        # width), as the devkit and detectron2 read them: corners xmin - 1 and xmax.
        out.append(RealObject(name.text.strip(), [v[0] - 1.0, v[1] - 1.0, v[2], v[3]], None, difficult, where))
    return out


def _openalpr_lines(path: str) -> List[Tuple[int, str, List[float], str]]:
    """(line, image, [x, y, w, h], plate text) of each line of an OpenALPR benchmark file."""
    out = []
    for n, line in enumerate(_read(path, "OpenALPR label file").splitlines(), 1):
        if not line.strip():
            continue
        parts = line.rstrip("\r\n").split("\t")
        v = [_number(c.strip()) for c in parts[1:5]]
        if len(parts) < 5 or not parts[0].strip() or any(x is None for x in v):
            raise SynthgenError(f"{path}:{n}: expected an OpenALPR line 'file<TAB>x<TAB>y<TAB>width<TAB>height"
                                f"<TAB>PLATE_TEXT' (pixels, tab-separated), got '{line.strip()[:60]}'")
        if not (v[2] > 0 and v[3] > 0):
            raise SynthgenError(f"{path}:{n}: the plate's width and height (4th and 5th fields) must be above 0, got "
                                f"'{line.strip()[:60]}'")
        out.append((n, parts[0].strip(), v, "\t".join(parts[5:]).strip()))
    return out


def _openalpr(path: str, photo: str, size) -> List[RealObject]:
    out = []
    for n, image, (x, y, w, h), _text in _openalpr_lines(path):
        if not _same_image(image, photo):
            raise SynthgenError(f"{path}:{n}: the plate is for image '{image}', the photo is '{_file_name(photo)}' "
                                "(an OpenALPR file holds the plates of one image)")
        # NOTE: x, y are the plate's top-left corner and w, h its size in pixels: the box is
        # [x, x + w] x [y, y + h] in continuous coordinates, as COCO's [x, y, w, h].
        out.append(RealObject(OPENALPR_CLASS, [x, y, x + w, y + h], None, False, f"{path}:{n}"))
    return out


def _check_size(path: str, w: Any, h: Any, size) -> None:
    if isinstance(w, int) and isinstance(h, int) and size is not None and (w, h) != tuple(size):
        raise SynthgenError(f"{path}: its labels are for a {w} x {h} image, the photo is {size[0]} x {size[1]}")


def read_label_file(path: str, fmt: str, image: str, size: Optional[Sequence[int]] = None,
                    names: Optional[Sequence[str]] = None, default_class: Optional[str] = None) -> List[RealObject]:
    """The objects of image ``image`` (a path or file name; its ``size`` = (width, height) when
    known: YOLO needs it, the others check it where the file states one) in label file ``path`` of
    format ``fmt``, with the file's own class names: KITTI's type column, COCO's category names,
    labelme's labels, VOC's names, a CSV's class column (``default_class`` for rows without one),
    YOLO's ``names[index]`` (the index itself without ``names``). Multi-image files (COCO, CSV)
    find the image's rows by file name (CSV: else by stem); an image a COCO or CSV file does not
    name is an error. Ignore regions (``ignore``): COCO ``iscrowd``, KITTI ``DontCare``, VOC
    ``difficult``. OpenALPR files (class ``plate``) are per image too: a line naming another image is an
    error."""
    if fmt not in LABEL_FORMATS:
        raise SynthgenError(f"{path}: label format '{fmt}' is not one of {', '.join(LABEL_FORMATS)}")
    if fmt == "openalpr":
        return _openalpr(path, image, size)
    if fmt == "labelme":
        return _labelme(path, image, size)
    if fmt == "coco":
        return _coco(path, image, size)
    if fmt == "yolo":
        return _yolo(path, image, size, names)
    if fmt == "kitti":
        return _kitti(path, image, size)
    if fmt == "csv":
        return _csv(path, image, size, default_class)
    return _voc(path, image, size)


def label_images(path: str, fmt: str) -> List[str]:
    """The images label file ``path`` names, as written there: every image of a COCO file and
    every image of a CSV file (in order of first appearance), labelme's ``imagePath``, VOC's
    ``filename``, the images an OpenALPR file's lines name (in order of first appearance); none
    for YOLO and KITTI (a file per image, named after it)."""
    if fmt not in LABEL_FORMATS:
        raise SynthgenError(f"{path}: label format '{fmt}' is not one of {', '.join(LABEL_FORMATS)}")
    if fmt == "coco":
        return [str(im.get("file_name", "")) for im in _cached(path, "coco", lambda: _coco_file(path))["images"]
                if isinstance(im, dict)]
    if fmt == "csv":
        return list(_cached(path, "csv", lambda: _csv_file(path)).images)
    if fmt == "labelme":
        d = _json(path, "labelme file")
        return [str(d["imagePath"])] if isinstance(d, dict) and d.get("imagePath") else []
    if fmt == "openalpr":
        return list(OrderedDict.fromkeys(ln[1] for ln in _openalpr_lines(path)))
    if fmt == "voc":
        fn = _xml(path, "Pascal VOC file").find("filename")
        return [fn.text.strip()] if fn is not None and fn.text.strip() else []
    return []


@dataclass
class LabelledImage:
    """One image of a multi-image label file, with its objects (:func:`read_label_set`)."""

    image: str                              #: the image's name as the file writes it
    objects: List[RealObject]               #: its objects, the file's class names
    size: Optional[Tuple[int, int]] = None  #: (width, height) where the file states it
    where: str = ""                         #: the file and the image's index or first line


def read_label_set(path: str, fmt: str, default_class: Optional[str] = None) -> List[LabelledImage]:
    """Every image of a multi-image label file (COCO, CSV) with its objects, the file parsed
    once and its rows grouped in one pass (not :func:`read_label_file` per image, which scans the
    whole file each time): the same objects, class names and errors as :func:`read_label_file`,
    in the order of the file's images (COCO: ``images``; CSV: first appearance). Nothing is left
    out unsaid: a COCO annotation whose ``image_id`` is no image's, or two COCO images of one
    ``file_name``, is an error."""
    if fmt not in MULTI_IMAGE_FORMATS:
        raise SynthgenError(f"{path}: '{fmt}' is not a multi-image label format ({', '.join(MULTI_IMAGE_FORMATS)}): "
                            "read its files one image at a time (read_label_file)")
    if fmt == "csv":
        t: _CsvTable = _cached(path, "csv", lambda: _csv_file(path))
        order = np.argsort(t.image, kind="stable")
        starts = np.searchsorted(t.image[order], np.arange(len(t.images) + 1))
        out = []
        for k, name in enumerate(t.images):
            rows = order[starts[k]:starts[k + 1]]
            if len(rows) > _MAX_OBJECTS:
                raise SynthgenError(f"{path}: {len(rows)} boxes for image '{name}', more than the {_MAX_OBJECTS} one "
                                    "image can have")
            out.append(LabelledImage(name, _csv_objects(path, t, rows, default_class), None,
                                     f"{path}:{int(t.line[rows[0]])}"))
        return out
    d = _cached(path, "coco", lambda: _coco_file(path))
    cats = {c.get("id"): str(c.get("name")) for c in d["categories"] if isinstance(c, dict)}
    by_id: Dict[Any, int] = {}
    names: Dict[str, int] = {}
    for k, im in enumerate(d["images"]):
        if not isinstance(im, dict) or not isinstance(im.get("file_name"), str) or not im["file_name"] or \
                isinstance(im.get("id"), (dict, list)) or im.get("id") is None:
            raise SynthgenError(f"{path}: images[{k}]: an image needs an 'id' and a 'file_name'")
        if im["id"] in by_id:
            raise SynthgenError(f"{path}: images[{k}]: id {im['id']!r} is images[{by_id[im['id']]}]'s too")
        if im["file_name"] in names:
            raise SynthgenError(f"{path}: images[{k}]: file_name '{im['file_name']}' is images[{names[im['file_name']]}]'s "
                                "too")
        by_id[im["id"]] = k
        names[im["file_name"]] = k
    objects: List[List[RealObject]] = [[] for _ in d["images"]]
    for i, a in enumerate(d["annotations"]):
        k = by_id.get(a.get("image_id")) if isinstance(a, dict) and not isinstance(a.get("image_id"), (dict, list)) \
            else None
        if k is None:
            raise SynthgenError(f"{path}: annotations[{i}]: image_id "
                                f"{a.get('image_id') if isinstance(a, dict) else None!r} is no image's (its label "
                                "would belong to no image)")
        objects[k].append(_coco_object(path, i, a, cats))
    out = []
    for k, im in enumerate(d["images"]):
        w, h = im.get("width"), im.get("height")
        size = (w, h) if isinstance(w, int) and isinstance(h, int) and not isinstance(w, bool) and w > 0 and h > 0 \
            else None
        out.append(LabelledImage(im["file_name"], objects[k], size, f"{path}: images[{k}]"))
    return out
