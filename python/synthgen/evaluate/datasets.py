"""The images a detector trains and is scored on, with their boxes: synthgen datasets, users' real
label sets and folders of images without objects, read into :class:`Sample` records.

- :func:`read_synthgen`: a synthgen dataset (its folder: ``annotations/coco.json``; a COCO file
  of one, e.g. ``annotations/coco_train.json``; or a split file, ``splits/train.txt``). Its
  objects (``source: synthetic``) and a photo frame's labelled real ones (``source: real``) are
  positives alike; ``iscrowd`` regions are ignore regions, and one written for every category
  (a photo's class-less ignore region) is one region of class ``""``; an object hidden more
  than ``max_occlusion`` (COCO ``occlusion``: 1 - visible / amodal pixels inside the image) is
  an ignore region of its class (:data:`MAX_OCCLUSION`).
- :func:`read_real`: a COCO or CSV file naming many images, or a folder of images with a label
  file per image (KITTI, YOLO, VOC, labelme, OpenALPR), all through
  :mod:`synthgen.background.label_files`; the format from ``fmt`` or detected (extension, and
  for ``.txt`` the lines: YOLO, KITTI or OpenALPR); ignore regions are COCO ``iscrowd``,
  KITTI ``DontCare`` (class ``""``) and VOC ``difficult``.
- :func:`read_negatives`: a folder (or glob) of images without objects.
- :func:`ground_truth` / :func:`class_names`: the samples as :mod:`.score` ground truth, and
  their classes.

Classes: ``mapping`` renames the file's classes first (``{"Car": "car", "Van": "car"}``; a name
mapped to None is dropped deliberately), then boxes of a class not in ``classes`` (when given)
are dropped; both are counted (:class:`Samples` ``dropped``, :meth:`Samples.summary`), and a
set whose every positive would be dropped is an error naming the classes found. Nothing else
is left out: an image a label file names but that is missing, an image of a per-image folder
without a label file, a label file without its image, two images of one name, are errors
naming the file. Boxes are x0 y0 x1 y1 in pixels (continuous coordinates) of the image as
synthgen reads it. No image is decoded: YOLO's fractions take the size from the file's header
(EXIF orientation applied). Pure numpy (no PyTorch)."""
from __future__ import annotations

import json
import os
from collections import Counter, OrderedDict
from dataclasses import dataclass
from typing import Any, Dict, Iterable, List, Mapping, Optional, Sequence, Tuple

import numpy as np

from .._core import SynthgenError
from ..background import label_files as lf
from ..background.photos import PHOTO_EXTENSIONS, expand_photos
from . import score

__all__ = ["Sample", "Samples", "MAX_OCCLUSION", "read_synthgen", "read_real", "read_negatives", "ground_truth",
           "class_names", "detect_format", "image_size"]

#: A synthetic object hidden more than this (COCO ``occlusion``) becomes an ignore region.
#: NOTE: 0.7 (at least 30% of its pixels visible to stay a positive). Its COCO box is the tight
#: box of its *visible* pixels: at 30% and more that is a recognisable part of the object (a
#: whole front, rear or side half), which real label sets box as the object (KITTI labels
#: "partly occluded" cars); below it is a fragment (a wheel arch, a strip of roof) that no real
#: set boxes, and neither a positive (teaching fragments as cars) nor background (teaching the
#: detector to miss hidden cars) is right: neither hit nor miss.
MAX_OCCLUSION = 0.7

#: Largest synthgen COCO file read (it is parsed whole: about ten times its size in memory).
MAX_COCO_BYTES = 1 << 30

#: Folder names where a per-image label set keeps its label files and its images.
_LABEL_DIRS = ("labels", "label_2", "Annotations")
_IMAGE_DIRS = ("images", "image_2", "JPEGImages")
#: Files of a per-image label folder that are not label files.
_NOT_LABELS = ("classes.txt", "readme.txt", "license.txt", "labels.txt")
_PER_IMAGE_EXT = {".txt": None, ".xml": "voc", ".json": "labelme"}


@dataclass
class Sample:
    """One image and its boxes."""

    image: str                 #: absolute path of the image file
    boxes: np.ndarray          #: N x 4 float64, x0 y0 x1 y1 in pixels (continuous coordinates)
    classes: List[str]         #: N class names after mapping ("" for an ignore region of every class)
    ignore: np.ndarray         #: N bool: ignore regions (crowd, DontCare, difficult, too hidden)
    source: str                #: "synthetic" (a synthgen frame), "real" (a real labelled image), "negative"
    size: Optional[Tuple[int, int]] = None   #: (width, height) when the label file states it
    where: str = ""            #: "file[:line/index]" for messages


class Samples(list):
    """A list of :class:`Sample` with what reading them counted: ``kept`` (class -> positive
    boxes), ``ignored`` (ignore regions), ``hidden`` (objects hidden more than ``max_occlusion``,
    among the ignore regions), ``dropped`` (the file's class name -> boxes left out by
    ``mapping`` / ``classes``)."""

    def __init__(self, samples: Iterable[Sample] = (), what: str = "", kept: Optional[Counter] = None,
                 ignored: int = 0, hidden: int = 0, dropped: Optional[Counter] = None):
        super().__init__(samples)
        self.what = what
        self.kept = kept if kept is not None else Counter()
        self.ignored, self.hidden = ignored, hidden
        self.dropped = dropped if dropped is not None else Counter()

    def summary(self) -> str:
        """One line: ``WHAT: N images, M boxes (car M), K ignore regions[; dropped ...]``."""
        per = ", ".join(f"{c} {n}" for c, n in sorted(self.kept.items()))
        s = (f"{self.what}: {len(self)} images, {sum(self.kept.values())} boxes" + (f" ({per})" if per else "") +
             f", {self.ignored} ignore regions")
        if self.hidden:
            s += f" ({self.hidden} objects hidden more than the occlusion limit)"
        if self.dropped:
            s += "; dropped (class not trained): " + ", ".join(f"{c} {n}" for c, n in sorted(self.dropped.items()))
        return s


class _Classes:
    """``mapping`` then ``classes``, counting what each keeps and drops."""

    def __init__(self, classes: Optional[Sequence[str]], mapping: Optional[Mapping[str, Optional[str]]]):
        self.classes = None if classes is None else [str(c) for c in classes]
        self.mapping = dict(mapping or {})
        self.kept: Counter = Counter()
        self.dropped: Counter = Counter()
        self.found: Counter = Counter()
        self.ignored = 0

    def map(self, name: str, ignore: bool) -> Optional[str]:
        """The class a box of the file's class ``name`` gets ("" for a class-less ignore
        region), or None when it is dropped."""
        if ignore and name == "":
            self.ignored += 1
            return ""
        self.found[name] += 1
        c = self.mapping.get(name, name)
        if c is None or (self.classes is not None and c not in self.classes):
            self.dropped[name] += 1
            return None
        if ignore:
            self.ignored += 1
        else:
            self.kept[c] += 1
        return str(c)

    def check(self, what: str) -> None:
        """Refuses a set whose every positive was dropped (``car`` asked, ``Car`` written)."""
        if self.dropped and not self.kept and self.classes is not None:
            found = ", ".join(f"{c} ({n})" for c, n in self.found.items())
            known = [k for k in self.classes]
            hints = [f"'{c}' is not '{k}'" for c in self.found for k in known if k != c and k.lower() == c.lower()][:3]
            raise SynthgenError(
                f"{what}: no box of the classes {', '.join(self.classes)} (classes found: {found}; mapping "
                f"{self.mapping or 'none'}){'; ' + ', '.join(hints) + ': class names are case-sensitive' if hints else ''}"
                ": map the file's classes to the trained ones")

    def samples(self, out: List[Sample], what: str, hidden: int = 0) -> Samples:
        self.check(what)
        return Samples(out, what, self.kept, self.ignored, hidden, self.dropped)


def _sample(objs: Sequence[Tuple[Sequence[float], str, bool, str]], image: str, source: str, size, where: str,
            cm: _Classes) -> Sample:
    """A sample of objects (box, file class, ignore, where), classes mapped."""
    boxes, classes, ignore = [], [], []
    for box, cls, ig, src in objs:
        b = [float(v) for v in box]
        if len(b) != 4 or not np.all(np.isfinite(b)) or b[2] < b[0] or b[3] < b[1]:
            raise SynthgenError(f"{src}: the box {b} is not x0 y0 x1 y1 with x1 >= x0 and y1 >= y0")
        c = cm.map(cls, ig)
        if c is None:
            continue
        boxes.append(b)
        classes.append(c)
        ignore.append(bool(ig))
    return Sample(os.path.abspath(image), np.asarray(boxes, np.float64).reshape(-1, 4), classes,
                  np.asarray(ignore, bool), source, None if size is None else (int(size[0]), int(size[1])), where)


# ---------------------------------------------------------------------------------------
# synthgen datasets


def _synthgen_files(path: str) -> Tuple[str, str, Optional[List[str]]]:
    """(COCO file, dataset root its file names are relative to, the split file's images or None)."""
    if os.path.isdir(path):
        coco = os.path.join(path, "annotations", "coco.json")
        if not os.path.isfile(coco):
            raise SynthgenError(f"{path}: not a synthgen dataset: no annotations/coco.json (`synthgen run` writes it "
                                "when the run ends; a real label set is read by --real)")
        return coco, path, None
    if not os.path.isfile(path):
        raise SynthgenError(f"{path}: not found")
    here = os.path.dirname(os.path.abspath(path))
    if path.lower().endswith(".json"):
        root = os.path.dirname(here) if os.path.basename(here) == "annotations" else here
        return path, root, None
    if path.lower().endswith(".txt"):
        if os.path.basename(here) != "splits":
            raise SynthgenError(f"{path}: a split file of a synthgen dataset is DATASET/splits/NAME.txt")
        root = os.path.dirname(here)
        names = [ln.strip() for ln in lf._read(path, "split file").splitlines() if ln.strip()]
        return os.path.join(root, "annotations", "coco.json"), root, names
    raise SynthgenError(f"{path}: not a synthgen dataset (its folder, a COCO .json or a splits/*.txt file)")


def read_synthgen(path: str, *, classes: Optional[Sequence[str]] = None,
                  mapping: Optional[Mapping[str, Optional[str]]] = None, max_occlusion: float = MAX_OCCLUSION,
                  what: str = "") -> Samples:
    """The frames of a synthgen dataset (see the module docstring), each a ``synthetic`` sample
    with its image's size, in the COCO file's order; ``what`` names the set in messages (default:
    the path)."""
    what = what or path
    if not 0.0 <= max_occlusion <= 1.0:
        raise SynthgenError(f"{what}: max_occlusion must be in [0, 1], got {max_occlusion}")
    coco, root, split = _synthgen_files(path)
    if not os.path.isfile(coco):
        raise SynthgenError(f"{coco}: not found (the split file {path}'s dataset has no COCO annotations)")
    d = lf._read(coco, "synthgen COCO file", MAX_COCO_BYTES)
    try:
        d = json.loads(d)
    except json.JSONDecodeError as e:
        raise SynthgenError(f"{coco}:{e.lineno}: not JSON ({e.msg})") from None
    if not isinstance(d, dict) or not all(isinstance(d.get(k), list) for k in ("images", "annotations", "categories")):
        raise SynthgenError(f"{coco}: not a COCO file (needs images, annotations and categories lists)")
    cats = {c.get("id"): str(c.get("name")) for c in d["categories"] if isinstance(c, dict)}
    by_id: Dict[Any, int] = {}
    for k, im in enumerate(d["images"]):
        if not isinstance(im, dict) or not isinstance(im.get("file_name"), str) or im.get("id") is None \
                or isinstance(im.get("id"), (list, dict)):
            raise SynthgenError(f"{coco}: images[{k}]: an image needs an 'id' and a 'file_name'")
        if im["id"] in by_id:
            raise SynthgenError(f"{coco}: images[{k}]: id {im['id']!r} is images[{by_id[im['id']]}]'s too")
        by_id[im["id"]] = k
    anns: List[List[Tuple[int, Dict[str, Any]]]] = [[] for _ in d["images"]]
    for i, a in enumerate(d["annotations"]):
        k = by_id.get(a.get("image_id")) if isinstance(a, dict) and not isinstance(a.get("image_id"), (list, dict)) \
            else None
        if k is None:
            raise SynthgenError(f"{coco}: annotations[{i}]: image_id is no image's (its label would belong to no image)")
        anns[k].append((i, a))
    keep = range(len(d["images"]))
    if split is not None:
        index = {im["file_name"]: k for k, im in enumerate(d["images"])}
        missing = [n for n in split if n not in index]
        if missing:
            raise SynthgenError(f"{path}: {len(missing)} images of the split are not in {coco}: "
                                f"{', '.join(missing[:3])}{', ...' if len(missing) > 3 else ''}")
        keep = [index[n] for n in OrderedDict.fromkeys(split)]
    cm = _Classes(classes, mapping)
    hidden = 0
    out = []
    all_cats = set(cats)
    for k in keep:
        im = d["images"][k]
        image = os.path.join(root, im["file_name"])
        where = f"{coco}: images[{k}]"
        if not os.path.isfile(image):
            raise SynthgenError(f"{where}: its image {image} is missing")
        objs = []
        regions: "OrderedDict[Tuple, List[int]]" = OrderedDict()  # crowd regions by box: their categories
        for i, a in anns[k]:
            o = lf._coco_object(coco, i, a, cats)
            if o.ignore:
                regions.setdefault((tuple(o.box), a.get("source")), []).append(i)
                continue
            occ = a.get("occlusion")
            too_hidden = isinstance(occ, (int, float)) and not isinstance(occ, bool) and occ > max_occlusion
            hidden += too_hidden
            objs.append((o.box, o.cls, too_hidden, o.source))
        for (box, _src), idx in regions.items():
            ids = {d["annotations"][i]["category_id"] for i in idx}
            # NOTE: synthgen writes a class-less ignore region once per category (COCO's crowd
            # regions are per category): all of them at one box are one region of every class.
            if len(all_cats) > 1 and ids == all_cats:
                objs.append((list(box), "", True, f"{coco}: annotations[{idx[0]}]"))
            else:
                objs.extend((list(box), cats[d["annotations"][i]["category_id"]], True, f"{coco}: annotations[{i}]")
                            for i in idx)
        w, h = im.get("width"), im.get("height")
        size = (w, h) if isinstance(w, int) and isinstance(h, int) else None
        out.append(_sample(objs, image, "synthetic", size, where, cm))
    return cm.samples(out, what, hidden)


# ---------------------------------------------------------------------------------------
# real label sets


def image_size(path: str) -> Tuple[int, int]:
    """(width, height) of an image as synthgen reads it (EXIF orientation applied), from its
    header: no pixel is decoded."""
    import OpenImageIO as oiio

    inp = oiio.ImageInput.open(path)
    if inp is None:
        raise SynthgenError(f"{path}: cannot read the image's header ({oiio.geterror() or 'unknown format'})")
    try:
        spec = inp.spec()
        w, h, orient = spec.width, spec.height, spec.get_int_attribute("Orientation", 1)
    finally:
        inp.close()
    return (h, w) if orient in (5, 6, 7, 8) else (w, h)


def _txt_format(path: str) -> Optional[str]:
    """yolo, kitti or openalpr by a .txt file's lines; None for an empty file."""
    seen = OrderedDict()
    for n, line in enumerate(lf._read(path, "label file").splitlines(), 1):
        if not line.strip():
            continue
        tabs = line.rstrip("\r\n").split("\t")
        parts = line.split()
        if len(tabs) >= 5 and tabs[0].strip().lower().endswith(PHOTO_EXTENSIONS) and \
                all(lf._number(c.strip()) is not None for c in tabs[1:5]):
            kind = "openalpr"
        elif parts and all(lf._number(c) is not None for c in parts):
            if len(parts) != 5:
                raise SynthgenError(f"{path}:{n}: {len(parts)} numbers, not YOLO's 'class cx cy w h' (YOLO polygons "
                                    "or scores are not read): convert the file to boxes")
            kind = "yolo"
        elif len(parts) in (15, 16) and lf._number(parts[0]) is None and \
                all(lf._number(c) is not None for c in parts[1:]):
            kind = "kitti"
        else:
            raise SynthgenError(f"{path}:{n}: not a YOLO ('class cx cy w h'), KITTI ('type truncated occluded alpha "
                                f"x0 y0 x1 y1 h w l x y z rotation_y') or OpenALPR ('file<TAB>x<TAB>y<TAB>w<TAB>h<TAB>"
                                f"TEXT') line: '{line.strip()[:60]}' (give the format)")
        seen.setdefault(kind, n)
    if len(seen) > 1:
        (a, na), (b, nb) = list(seen.items())[:2]
        raise SynthgenError(f"{path}: line {na} reads as {a}, line {nb} as {b}: give the format")
    return next(iter(seen), None)


def detect_format(path: str) -> Optional[str]:
    """The label format of file ``path`` by its extension and content (``.txt``: its lines);
    None for an empty ``.txt`` file (no objects in any format)."""
    ext = os.path.splitext(path)[1].lower()
    if ext == ".csv":
        return "csv"
    if ext == ".xml":
        return "voc"
    if ext == ".json":
        d = lf._json(path, "label file")
        if isinstance(d, dict) and all(isinstance(d.get(k), list) for k in ("images", "annotations", "categories")):
            return "coco"
        if isinstance(d, dict) and isinstance(d.get("shapes"), list):
            return "labelme"
        raise SynthgenError(f"{path}: a JSON file that is neither COCO (images, annotations, categories) nor labelme "
                            "(shapes)")
    if ext == ".txt":
        return _txt_format(path)
    raise SynthgenError(f"{path}: no label format has the extension '{ext}' (COCO .json, CSV .csv, VOC .xml, labelme "
                        ".json, YOLO / KITTI / OpenALPR .txt)")


def _yolo_names(dirs: Sequence[str]) -> Optional[List[str]]:
    """YOLO class names from classes.txt, else a dataset.yaml / data.yaml ``names``."""
    for d in dirs:
        p = os.path.join(d, "classes.txt")
        if os.path.isfile(p):
            return [ln.strip() for ln in lf._read(p, "YOLO classes file").splitlines() if ln.strip()]
    for d in dirs:
        for n in ("dataset.yaml", "data.yaml"):
            p = os.path.join(d, n)
            if os.path.isfile(p):
                import yaml

                try:
                    names = (yaml.safe_load(lf._read(p, "YOLO dataset file")) or {}).get("names")
                except (yaml.YAMLError, AttributeError) as e:
                    raise SynthgenError(f"{p}: not a YOLO dataset file with 'names' ({e})") from None
                if isinstance(names, dict):
                    try:
                        names = [names[i] for i in range(len(names))]
                    except KeyError:
                        raise SynthgenError(f"{p}: names: indices must be 0..{len(names) - 1}") from None
                if not isinstance(names, list):
                    raise SynthgenError(f"{p}: names: expected a list of class names")
                return [str(x) for x in names]
    return None


def _find_image(name: str, dirs: Sequence[str]) -> Optional[str]:
    for d in dirs:
        for p in (os.path.join(d, name), os.path.join(d, lf._file_name(name))):
            if os.path.isfile(p):
                return p
    return None


def _images_by_stem(dirs: Sequence[str]) -> Dict[str, List[str]]:
    out: Dict[str, List[str]] = {}
    for d in dirs:
        for f in sorted(os.listdir(d)):
            p = os.path.join(d, f)
            if f.lower().endswith(PHOTO_EXTENSIONS) and os.path.isfile(p):
                out.setdefault(os.path.splitext(f)[0], []).append(p)
    return out


def _existing(dirs: Iterable[str]) -> List[str]:
    return list(OrderedDict((os.path.abspath(d), None) for d in dirs if os.path.isdir(d)))


def read_real(path: str, fmt: Optional[str] = None, *, images: Optional[str] = None,
              classes: Optional[Sequence[str]] = None, mapping: Optional[Mapping[str, Optional[str]]] = None,
              default_class: Optional[str] = None, names: Optional[Sequence[str]] = None) -> Samples:
    """A real labelled set (``real`` samples): a COCO or CSV file naming many images (images
    found in ``images``, else beside the file, in its ``images/``, or, for a file in
    ``annotations/``, beside that folder); a folder holding one such file and no per-image label
    files; or a folder of per-image label files (in it or in its ``labels/``, ``label_2/`` or
    ``Annotations/``), each named after its image (in ``images``, else beside the label files,
    in the folder, or its ``images/``, ``image_2/``, ``JPEGImages/``), an empty ``.txt`` for an
    image without objects; or one per-image label file. ``fmt``: one of
    :data:`synthgen.background.label_files.LABEL_FORMATS` or None (detected). ``names``: YOLO's
    class names (else ``classes.txt``, ``dataset.yaml`` / ``data.yaml`` there); ``default_class``:
    a CSV file's class when it has no class column."""
    if fmt is not None and fmt not in lf.LABEL_FORMATS:
        raise SynthgenError(f"{path}: label format '{fmt}' is not one of {', '.join(lf.LABEL_FORMATS)}")
    if images is not None and not os.path.isdir(images):
        raise SynthgenError(f"{images}: the images folder is not found")
    cm = _Classes(classes, mapping)
    if os.path.isdir(path):
        return _read_folder(path, fmt, images, cm, default_class, names)
    if not os.path.isfile(path):
        raise SynthgenError(f"{path}: label file or folder not found")
    f = fmt or detect_format(path)
    here = os.path.dirname(os.path.abspath(path))
    if f == "csv" and default_class is None:
        t = lf._cached(path, "csv", lambda: lf._csv_file(path))
        if (t.cls < 0).any():
            raise SynthgenError(f"{path}:{int(t.line[np.argmax(t.cls < 0)])}: the row has no class "
                                "(image,x0,y0,x1,y1,class): give the class of the file's boxes (synthgen evaluate --default-class NAME; default_class in Python)")
    if f in lf.MULTI_IMAGE_FORMATS:
        dirs = [images] if images else _existing(
            [here, os.path.join(here, "images")] +
            ([os.path.dirname(here), os.path.join(os.path.dirname(here), "images")]
             if os.path.basename(here) == "annotations" else []))
        out = []
        seen: Dict[str, str] = {}
        for li in lf.read_label_set(path, f, default_class):
            image = _find_image(li.image, dirs)
            if image is None:
                raise SynthgenError(f"{li.where}: its image '{li.image}' is not found (looked in "
                                    f"{', '.join(dirs)}; give the images' folder)")
            if os.path.abspath(image) in seen:
                raise SynthgenError(f"{li.where}: its image {image} is {seen[os.path.abspath(image)]}'s too")
            seen[os.path.abspath(image)] = li.where
            out.append(_sample([(o.box, o.cls, o.ignore, o.source)
                                for o in li.objects], image, "real", li.size, li.where, cm))
        return cm.samples(out, path)
    dirs = [images] if images else _existing([here, os.path.join(here, "images"),
                                              os.path.join(os.path.dirname(here), "images")])
    if f == "yolo" and names is None:
        names = _yolo_names(_existing([here, os.path.dirname(here)]))
    return cm.samples(_per_image([path], f, dirs, cm, names, default_class, check_all=False), path)


def _read_folder(path: str, fmt: Optional[str], images: Optional[str], cm: _Classes, default_class: Optional[str],
                 names: Optional[Sequence[str]]) -> Samples:
    label_dir = next((os.path.join(path, d) for d in _LABEL_DIRS if os.path.isdir(os.path.join(path, d))), path)
    files = sorted(os.path.join(label_dir, f) for f in os.listdir(label_dir)
                   if os.path.splitext(f)[1].lower() in _PER_IMAGE_EXT and f.lower() not in _NOT_LABELS
                   and os.path.isfile(os.path.join(label_dir, f)))
    want = {"voc": ".xml", "labelme": ".json", "yolo": ".txt", "kitti": ".txt", "openalpr": ".txt"}.get(fmt or "")
    if want:  # the format given: its files only
        files = [p for p in files if p.lower().endswith(want)]
    multi: List[str] = []
    if label_dir == path:
        multi = sorted(os.path.join(path, f) for f in os.listdir(path) if f.lower().endswith(".csv")) + \
            [p for p in files if p.lower().endswith(".json") and detect_format(p) == "coco"]
        files = [p for p in files if p not in multi]
    if fmt in lf.MULTI_IMAGE_FORMATS or (multi and not files):
        cands = [p for p in multi if fmt is None or detect_format(p) == fmt]
        if len(cands) != 1:
            raise SynthgenError(f"{path}: {'several' if cands else 'no'} {fmt or 'COCO or CSV'} label files "
                                f"({', '.join(os.path.basename(p) for p in cands) or 'none'}): give the file")
        return read_real(cands[0], fmt, images=images, classes=cm.classes, mapping=cm.mapping,
                         default_class=default_class, names=names)
    if not files:
        raise SynthgenError(f"{path}: no label files (a COCO .json or a .csv naming the images, or a label file per "
                            f"image: .txt, .xml, .json, in the folder or its {'/, '.join(_LABEL_DIRS[:-1])}/ or "
                            f"{_LABEL_DIRS[-1]}/)")
    if multi:
        raise SynthgenError(f"{path}: holds both a file of many images' labels ({os.path.basename(multi[0])}) and "
                            f"per-image label files ({os.path.basename(files[0])}, ...): give the one to read")
    f = fmt
    if f is None:
        exts = Counter(os.path.splitext(p)[1].lower() for p in files)
        if len(exts) > 1:
            raise SynthgenError(f"{label_dir}: label files of several kinds "
                                f"({', '.join(f'{n} {e}' for e, n in exts.items())}): give the format")
        ext = next(iter(exts))
        f = _PER_IMAGE_EXT[ext]
        if f is None:  # .txt: by the lines, every file the same
            kinds: "OrderedDict[str, str]" = OrderedDict()
            for p in files:
                k = _txt_format(p)
                if k is not None:
                    kinds.setdefault(k, p)
            if len(kinds) > 1:
                (a, pa), (b, pb) = list(kinds.items())[:2]
                raise SynthgenError(f"{label_dir}: {os.path.basename(pa)} reads as {a}, {os.path.basename(pb)} as "
                                    f"{b}: give the format")
            if not kinds:
                raise SynthgenError(f"{label_dir}: every .txt label file is empty: give the format")
            f = next(iter(kinds))
    dirs = [images] if images else _existing(
        [label_dir, path] + [os.path.join(path, d) for d in _IMAGE_DIRS])
    if f == "yolo" and names is None:
        names = _yolo_names(_existing([label_dir, path]))
    return cm.samples(_per_image(files, f, dirs, cm, names, default_class, check_all=True), path)


def _per_image(files: Sequence[str], fmt: str, dirs: Sequence[str], cm: _Classes, names: Optional[Sequence[str]],
               default_class: Optional[str], check_all: bool) -> List[Sample]:
    """Samples of per-image label files, each named after its image in ``dirs``."""
    if fmt in lf.MULTI_IMAGE_FORMATS:
        raise SynthgenError(f"{files[0]}: a {fmt} file is read whole, not as one image's labels")
    if fmt == "yolo" and names is None and not cm.mapping:
        raise SynthgenError(f"{files[0]}: YOLO labels need their class names: names=, a classes.txt (a name a line) "
                            "or a dataset.yaml / data.yaml 'names' beside them, or a mapping of the class indices "
                            "({'0': 'car'})")
    stems = _images_by_stem(dirs)
    out = []
    used = set()
    for p in files:
        stem = os.path.splitext(os.path.basename(p))[0]
        found = stems.get(stem, [])
        if not found:
            raise SynthgenError(f"{p}: its image {stem}.* is not found (looked in {', '.join(dirs)}; give the "
                                "images' folder)")
        if len(found) > 1:
            raise SynthgenError(f"{p}: several images are named {stem}: {', '.join(found[:3])}")
        image = found[0]
        used.add(image)
        size = image_size(image) if fmt == "yolo" else None
        objs = lf.read_label_file(p, fmt, image, size, names, default_class)
        out.append(_sample([(o.box, "" if o.ignore and o.cls == "DontCare" else o.cls, o.ignore, o.source)
                            for o in objs], image, "real", size, p, cm))
    if check_all:
        unlabelled = [ps[0] for s, ps in stems.items() if ps[0] not in used]
        if unlabelled:
            raise SynthgenError(f"{os.path.dirname(unlabelled[0])}: {len(unlabelled)} images without a label file "
                                f"({', '.join(os.path.basename(u) for u in sorted(unlabelled)[:3])}"
                                f"{', ...' if len(unlabelled) > 3 else ''}): write an empty label file for an image "
                                "without objects, or keep unlabelled images elsewhere")
    return out


def read_negatives(path: str) -> Samples:
    """Images without objects (a folder or a glob of images; every detection on them is a false
    positive): ``negative`` samples without boxes, sorted by path."""
    files = expand_photos([path], os.getcwd())
    return Samples([Sample(f, np.zeros((0, 4)), [], np.zeros(0, bool), "negative", None, f) for f in files], path)


# ---------------------------------------------------------------------------------------
# scoring


def ground_truth(samples: Iterable[Sample]) -> Dict[str, score.GroundTruth]:
    """The samples as :mod:`.score` ground truth, keyed by image path: a class-less ignore region
    is a crowd region of every class, one of a class an ``ignore`` box (matched as a box). An
    image given twice is an error (its boxes would count twice)."""
    out: Dict[str, score.GroundTruth] = {}
    where: Dict[str, str] = {}
    for s in samples:
        if s.image in out:
            raise SynthgenError(f"{s.where}: the image {s.image} is {where[s.image]}'s too (its boxes would count "
                                "twice)")
        ig = np.asarray(s.ignore, bool)
        blank = np.array([c == "" for c in s.classes], bool).reshape(-1)
        out[s.image] = score.GroundTruth(s.boxes, list(s.classes), crowd=ig & blank, ignore=ig & ~blank)
        where[s.image] = s.where
    return out


def class_names(samples: Iterable[Sample]) -> List[str]:
    """The classes of the samples' positive boxes, sorted."""
    return sorted({c for s in samples for c, ig in zip(s.classes, s.ignore) if not ig and c})
