"""The training and scoring sets of synthgen.evaluate (synthgen.evaluate.datasets): synthgen
datasets (a real render over a photo: synthetic objects, a photo's real object and its class-less
ignore region; a hand-made COCO file for the occlusion rule and split files), every real label
format read into samples with exact boxes, format detection, class mapping and dropping, the
errors that keep labels from vanishing, ground truth for scoring, and the real sets in
../shared."""
from __future__ import annotations

import json
import os

import numpy as np
import OpenImageIO as oiio
import pytest

import synthgen as sg
from synthgen.evaluate import datasets as D
from synthgen.evaluate.score import Detections, score

REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
SHARED = os.path.abspath(os.path.join(REPO, "..", "shared"))
REAL = os.path.join(SHARED, "realdata")


def _image(path, w, h, orientation=None):
    spec = oiio.ImageSpec(w, h, 3, oiio.UINT8)
    if orientation:
        spec.attribute("Orientation", orientation)
    b = oiio.ImageBuf(spec)
    b.set_pixels(oiio.ROI(), np.full((h, w, 3), 90, np.uint8))
    os.makedirs(os.path.dirname(str(path)), exist_ok=True)
    assert b.write(str(path)), b.geterror()
    return str(path)


def _boxes(s):
    return [(list(map(float, b)), c, bool(i)) for b, c, i in zip(s.boxes, s.classes, s.ignore)]


# ---------------------------------------------------------------------------------------
# synthgen datasets

W, H = 96, 64
CALIBRATION = """intrinsics: {fx: 85.0, cx: 48.0, cy: 30.0}
ground: {camera_height: 1.6, pitch: 6.0}
sun: {azimuth: 230.0, elevation: 35.0}
objects:
  - {class: box, box: [5, 35, 20, 50]}
ignore:
  - {box: [75, 32, 95, 40]}
"""
SCENARIO = f"""seed: 5
count: 1
resolution: [{W}, {H}]
background:
  photos: [photos]
  ground_albedo: 0.15
objects:
  - {{class: box, primitive: box, size: [1.6, 1.2, 1.6], material: {{type: diffuse, albedo: [0.7, 0.1, 0.1]}}}}
  - {{class: ball, primitive: box, size: [0.8, 0.8, 0.8], material: {{type: diffuse, albedo: [0.1, 0.7, 0.1]}}}}
render: {{spp: 4}}
"""


@pytest.fixture(scope="module")
def rendered(tmp_path_factory):
    """One frame over a flat photo with a labelled real box and a class-less ignore region."""
    from synthgen.cli import main

    d = tmp_path_factory.mktemp("ds")
    (d / "photos").mkdir()
    spec = oiio.ImageSpec(W, H, 3, oiio.FLOAT)
    b = oiio.ImageBuf(spec)
    b.set_pixels(oiio.ROI(), np.full((H, W, 3), 0.08, np.float32))
    assert b.write(str(d / "photos" / "street.exr"))
    (d / "photos" / "calibration.yaml").write_text(CALIBRATION)
    (d / "aug.yaml").write_text(SCENARIO)
    out = str(d / "out")
    assert main(["run", str(d / "aug.yaml"), "-o", out, "--no-progress"]) == 0
    return out


def test_a_rendered_dataset_reads_as_the_writer_wrote_it(rendered):
    """The inserted objects are positives with the tight box of their instance mask; the photo's
    real object (source: real) a positive at its labelled box; its class-less ignore region,
    written once per category, one ignore region of class ''."""
    s = D.read_synthgen(rendered)
    assert len(s) == 1 and s[0].source == "synthetic" and s[0].size == (W, H)
    assert s[0].image == os.path.join(rendered, "images", "000000.png")
    inst = np.asarray(oiio.ImageBuf(os.path.join(rendered, "instance", "000000.png")).get_pixels(oiio.UINT16))[..., 0]
    meta = json.load(open(os.path.join(rendered, "meta", "000000.json")))
    names = {o["instance_id"]: o["class"] for o in meta["objects"] if o.get("visible_pixels")}
    assert len(names) == 2
    expected = []
    for i, cls in names.items():
        ys, xs = np.nonzero(inst == i)
        expected.append(([float(xs.min()), float(ys.min()), float(xs.max() + 1), float(ys.max() + 1)], cls, False))
    got = _boxes(s[0])
    assert sorted(got[:2]) == sorted(expected)
    assert got[2:] == [([5.0, 35.0, 20.0, 50.0], "box", False), ([75.0, 32.0, 95.0, 40.0], "", True)]
    assert (s.kept, s.ignored, s.hidden, dict(s.dropped)) == ({"box": 2, "ball": 1}, 1, 0, {})
    assert s.summary() == f"{rendered}: 1 images, 3 boxes (ball 1, box 2), 1 ignore regions"
    # As ground truth: the class-less region is a crowd region of every class.
    gt = D.ground_truth(s)[s[0].image]
    assert gt.crowd.tolist() == [False, False, False, True] and not gt.ignore.any()
    # Only balls trained: the boxes are dropped (counted), the class-less region stays.
    b = D.read_synthgen(rendered, classes=["ball"])
    assert [c for c in b[0].classes] == ["ball", ""] and dict(b.dropped) == {"box": 2}
    # The split file that holds the frame reads the same frame.
    split = next(os.path.join(rendered, "splits", f) for f in os.listdir(os.path.join(rendered, "splits"))
                 if f.endswith(".txt") and open(os.path.join(rendered, "splits", f)).read().strip())
    assert _boxes(D.read_synthgen(split)[0]) == got


def _coco_dataset(tmp_path, anns, cats=("car", "truck")):
    root = tmp_path / "ds"
    _image(root / "images" / "000000.png", 100, 50)
    _image(root / "images" / "000001.png", 100, 50)
    (root / "splits").mkdir()
    (root / "splits" / "val.txt").write_text("images/000001.png\n")
    d = {"images": [{"id": 0, "file_name": "images/000000.png", "width": 100, "height": 50},
                    {"id": 1, "file_name": "images/000001.png", "width": 100, "height": 50}],
         "annotations": anns, "categories": [{"id": i + 1, "name": n} for i, n in enumerate(cats)]}
    (root / "annotations").mkdir()
    (root / "annotations" / "coco.json").write_text(json.dumps(d))
    return str(root)


def test_objects_hidden_more_than_the_limit_are_ignore_regions(tmp_path):
    """occlusion 0.75 > MAX_OCCLUSION (0.7): an ignore region of its class; 0.7 stays a positive;
    a crowd region of one category stays that category's; mapping and max_occlusion apply."""
    root = _coco_dataset(tmp_path, [
        {"id": 1, "image_id": 0, "category_id": 1, "bbox": [10, 5, 20, 10], "iscrowd": 0, "occlusion": 0.7,
         "source": "synthetic"},
        {"id": 2, "image_id": 0, "category_id": 2, "bbox": [40, 5, 20, 10], "iscrowd": 0, "occlusion": 0.75,
         "source": "synthetic"},
        {"id": 3, "image_id": 0, "category_id": 2, "bbox": [1, 2, 3, 4], "iscrowd": 1, "source": "real"},
        {"id": 4, "image_id": 1, "category_id": 1, "bbox": [0.5, 1.5, 2, 3], "iscrowd": 0, "source": "real",
         "visible_fraction": 0.5}])
    assert D.MAX_OCCLUSION == 0.7
    s = D.read_synthgen(root)
    assert _boxes(s[0]) == [([10, 5, 30, 15], "car", False), ([40, 5, 60, 15], "truck", True),
                            ([1, 2, 4, 6], "truck", True)]
    assert _boxes(s[1]) == [([0.5, 1.5, 2.5, 4.5], "car", False)]
    assert (s.hidden, s.ignored, dict(s.kept)) == (1, 2, {"car": 2})
    assert D.class_names(s) == ["car"]
    s = D.read_synthgen(root, max_occlusion=0.8, mapping={"truck": "car"})
    assert _boxes(s[0])[1] == ([40, 5, 60, 15], "car", False) and s.hidden == 0
    # The ignore region of a class is matched as a box when scored.
    gt = D.ground_truth(s)[s[0].image]
    assert gt.ignore.tolist() == [False, False, True] and not gt.crowd.any()
    # A split file: its frames only.
    v = D.read_synthgen(os.path.join(root, "splits", "val.txt"))
    assert [x.image for x in v] == [os.path.join(root, "images", "000001.png")]


@pytest.mark.parametrize("change, error", [
    (lambda d: d["annotations"].append({"image_id": 7, "category_id": 1, "bbox": [1, 2, 3, 4]}),
     r"coco.json: annotations\[1\]: image_id is no image's"),
    (lambda d: d["annotations"].append({"image_id": 0, "category_id": 9, "bbox": [1, 2, 3, 4]}),
     r"coco.json: annotations\[1\]: category_id 9 is not in categories"),
    (lambda d: d["annotations"].append({"image_id": 0, "category_id": 1, "bbox": [1, 2, 3]}),
     r"coco.json: annotations\[1\]: bbox must be \[x, y, width, height\]"),
    (lambda d: d["images"].append({"id": 2, "file_name": "images/gone.png"}),
     r"coco.json: images\[2\]: its image .*images/gone.png is missing"),
])
def test_a_broken_synthgen_dataset_is_an_error_naming_the_place(tmp_path, change, error):
    root = _coco_dataset(tmp_path, [{"id": 1, "image_id": 0, "category_id": 1, "bbox": [1, 2, 3, 4]}])
    p = os.path.join(root, "annotations", "coco.json")
    d = json.load(open(p))
    change(d)
    open(p, "w").write(json.dumps(d))
    with pytest.raises(sg.SynthgenError, match=error):
        D.read_synthgen(root)


def test_a_folder_without_a_coco_file_is_not_a_synthgen_dataset(tmp_path):
    with pytest.raises(sg.SynthgenError, match=r"not a synthgen dataset: no annotations/coco.json"):
        D.read_synthgen(str(tmp_path))


# ---------------------------------------------------------------------------------------
# real label sets

KITTI = ("Car 0.00 0 -1.5 10 20 60 70 1.5 1.6 3.9 1 1.6 12 -1.5\n"
         "Van 0.00 0 -1.5 80 20 120 60 1.5 1.6 3.9 1 1.6 12 -1.5\n"
         "Pedestrian 0.00 0 -1.5 130 20 140 60 1.7 0.6 0.8 1 1.6 12 -1.5\n"
         "DontCare -1 -1 -10 150 20 190 40 -1 -1 -1 -1000 -1000 -1000 -10\n")


def test_kitti_folder_with_mapping_and_dropped_classes(tmp_path):
    """KITTI's training layout (image_2/, label_2/): Car and Van mapped to car, Pedestrian
    dropped and counted, DontCare an ignore region of every class; an empty file, no objects."""
    _image(tmp_path / "image_2" / "000000.png", 200, 100)
    _image(tmp_path / "image_2" / "000001.png", 200, 100)
    (tmp_path / "label_2").mkdir()
    (tmp_path / "label_2" / "000000.txt").write_text(KITTI)
    (tmp_path / "label_2" / "000001.txt").write_text("")
    s = D.read_real(str(tmp_path), classes=["car"], mapping={"Car": "car", "Van": "car"})
    assert [x.image for x in s] == [str(tmp_path / "image_2" / f"00000{i}.png") for i in (0, 1)]
    assert _boxes(s[0]) == [([10, 20, 60, 70], "car", False), ([80, 20, 120, 60], "car", False),
                            ([150, 20, 190, 40], "", True)]
    assert s[1].boxes.shape == (0, 4) and s[0].source == "real"
    assert s[0].where == str(tmp_path / "label_2" / "000000.txt")
    assert s.summary() == f"{tmp_path}: 2 images, 2 boxes (car 2), 1 ignore regions; dropped (class not trained): " \
                          "Pedestrian 1"
    # Without classes every class is kept, as the file names it.
    assert D.read_real(str(tmp_path))[0].classes == ["Car", "Van", "Pedestrian", ""]
    # 'car' asked, only 'Car' written: an error, not an empty set.
    with pytest.raises(sg.SynthgenError, match=r"no box of the classes car \(classes found: Car \(1\), Van \(1\), "
                                               r"Pedestrian \(1\); mapping none\); 'Car' is not 'car'"):
        D.read_real(str(tmp_path), classes=["car"])


def test_yolo_folder_takes_image_sizes_from_headers(tmp_path):
    """images/ + labels/ + classes.txt: fractions of each image's own size (its header; EXIF
    orientation 6 swaps width and height)."""
    _image(tmp_path / "images" / "a.png", 200, 100)
    _image(tmp_path / "images" / "b.jpg", 40, 80, orientation=6)
    (tmp_path / "labels").mkdir()
    (tmp_path / "labels" / "a.txt").write_text("1 0.5 0.5 0.2 0.4\n0 0.25 0.75 0.5 0.5\n")
    (tmp_path / "labels" / "b.txt").write_text("0 0.5 0.5 0.5 0.5\n")
    with pytest.raises(sg.SynthgenError, match=r"a.txt: YOLO labels need their class names"):
        D.read_real(str(tmp_path))
    # A mapping of the class indices names them too.
    s = D.read_real(str(tmp_path), mapping={"0": "car", "1": None})
    assert [x.classes for x in s] == [["car"], ["car"]] and dict(s.dropped) == {"1": 1}
    (tmp_path / "labels" / "classes.txt").write_text("car\ntruck\n")
    s = D.read_real(str(tmp_path))
    assert _boxes(s[0]) == [([80, 30, 120, 70], "truck", False), ([0, 50, 100, 100], "car", False)]
    assert s[0].size == (200, 100) and s[1].size == (80, 40)
    assert _boxes(s[1]) == [([20, 10, 60, 30], "car", False)]
    assert D.read_real(str(tmp_path), names=["x", "y"])[0].classes == ["y", "x"]
    assert D.read_real(str(tmp_path / "labels" / "a.txt"))[0].classes == ["truck", "car"]  # one file


def test_voc_labelme_and_openalpr_folders(tmp_path):
    """Per-image files beside their images: VOC (1-based inclusive: xmin - 1; difficult is an
    ignore region of its class), labelme (a polygon's box), OpenALPR (class plate)."""
    voc = tmp_path / "voc"
    _image(voc / "JPEGImages" / "a.jpg", 60, 40)
    (voc / "Annotations").mkdir()
    (voc / "Annotations" / "a.xml").write_text(
        "<annotation><filename>a.jpg</filename><size><width>60</width><height>40</height></size>"
        "<object><name>car</name><bndbox><xmin>1</xmin><ymin>2</ymin><xmax>30</xmax><ymax>20</ymax></bndbox></object>"
        "<object><name>car</name><difficult>1</difficult><bndbox><xmin>41</xmin><ymin>5</ymin><xmax>50</xmax>"
        "<ymax>9</ymax></bndbox></object></annotation>")
    assert _boxes(D.read_real(str(voc))[0]) == [([0, 1, 30, 20], "car", False), ([40, 4, 50, 9], "car", True)]
    lm = tmp_path / "lm"
    _image(lm / "a.png", 60, 40)
    (lm / "a.json").write_text(json.dumps({"shapes": [
        {"label": "car", "points": [[3, 4], [20, 5], [10, 17.5]], "shape_type": "polygon"}]}))
    assert _boxes(D.read_real(str(lm))[0]) == [([3, 4, 20, 17.5], "car", False)]
    alpr = tmp_path / "alpr"
    _image(alpr / "eu1.jpg", 60, 40)
    (alpr / "eu1.txt").write_text("eu1.jpg\t10\t20\t30\t8\tAB123\n")
    s = D.read_real(str(alpr))
    assert _boxes(s[0]) == [([10, 20, 40, 28], "plate", False)] and s.kept == {"plate": 1}


def test_coco_and_csv_files_of_many_images(tmp_path):
    """A COCO file in annotations/ (images beside that folder, crowd regions ignore regions of
    their class) and a CSV file (images in its images/; a folder holding only it reads it)."""
    _image(tmp_path / "images" / "a.jpg", 60, 40)
    _image(tmp_path / "images" / "b.jpg", 60, 40)
    (tmp_path / "annotations").mkdir()
    (tmp_path / "annotations" / "instances.json").write_text(json.dumps({
        "images": [{"id": 3, "file_name": "a.jpg", "width": 60, "height": 40}, {"id": 4, "file_name": "b.jpg"}],
        "annotations": [{"image_id": 4, "category_id": 1, "bbox": [1, 2, 3, 4]},
                        {"image_id": 3, "category_id": 2, "bbox": [5, 6, 7, 8], "iscrowd": 1},
                        {"image_id": 4, "category_id": 2, "bbox": [0.5, 0, 10, 10]}],
        "categories": [{"id": 1, "name": "car"}, {"id": 2, "name": "person"}]}))
    s = D.read_real(str(tmp_path / "annotations" / "instances.json"))
    assert [x.image for x in s] == [str(tmp_path / "images" / n) for n in ("a.jpg", "b.jpg")]
    assert _boxes(s[0]) == [([5, 6, 12, 14], "person", True)] and s[0].size == (60, 40) and s[1].size is None
    assert _boxes(s[1]) == [([1, 2, 4, 6], "car", False), ([0.5, 0, 10.5, 10], "person", False)]
    assert s[1].where == f"{tmp_path / 'annotations' / 'instances.json'}: images[1]"
    s = D.read_real(str(tmp_path / "annotations" / "instances.json"), classes=["car"])
    assert [x.classes for x in s] == [[], ["car"]] and dict(s.dropped) == {"person": 2}
    c = tmp_path / "csv"
    c.mkdir()
    os.symlink(tmp_path / "images", c / "images")
    (c / "boxes.csv").write_text("image_id,xmin,ymin,xmax,ymax\nb.jpg,1,2,3,4\na.jpg,5,6,7,8\nb.jpg,9,10,11,12\n")
    with pytest.raises(sg.SynthgenError, match=r"boxes.csv:2: the row has no class .*--default-class NAME; default_class in Python"):
        D.read_real(str(c))
    s = D.read_real(str(c), default_class="car")
    assert [(os.path.basename(x.image), x.boxes.tolist(), x.where) for x in s] == [
        ("b.jpg", [[1, 2, 3, 4], [9, 10, 11, 12]], f"{c / 'boxes.csv'}:2"), ("a.jpg", [[5, 6, 7, 8]], f"{c / 'boxes.csv'}:3")]


def test_format_detection(tmp_path):
    """.txt files by their lines; extensions; what cannot be told apart is an error."""
    t = tmp_path / "x.txt"
    for text, fmt in (("0 0.5 0.5 0.2 0.2\n", "yolo"), (KITTI, "kitti"), ("a.jpg\t1\t2\t3\t4\tAB\n", "openalpr"),
                      ("\n", None)):
        t.write_text(text)
        assert D.detect_format(str(t)) == fmt
    t.write_text("0 0.5 0.5 0.2 0.2\n" + KITTI)
    with pytest.raises(sg.SynthgenError, match=r"x.txt: line 1 reads as yolo, line 2 as kitti: give the format"):
        D.detect_format(str(t))
    t.write_text("0 0.1 0.1 0.2 0.1 0.2 0.3 0.3\n")
    with pytest.raises(sg.SynthgenError, match=r"x.txt:1: 8 numbers, not YOLO's 'class cx cy w h'"):
        D.detect_format(str(t))
    t.write_text("hello world\n")
    with pytest.raises(sg.SynthgenError, match=r"x.txt:1: not a YOLO .*, KITTI .* or OpenALPR .* line: 'hello world'"):
        D.detect_format(str(t))
    j = tmp_path / "x.json"
    j.write_text("{}")
    with pytest.raises(sg.SynthgenError, match=r"x.json: a JSON file that is neither COCO"):
        D.detect_format(str(j))
    # A folder of two kinds of label files, or of .txt files of two formats.
    _image(tmp_path / "f" / "a.png", 20, 10)
    _image(tmp_path / "f" / "b.png", 20, 10)
    (tmp_path / "f" / "a.txt").write_text(KITTI)
    (tmp_path / "f" / "b.xml").write_text("<annotation/>")
    with pytest.raises(sg.SynthgenError, match=r"f: label files of several kinds \(1 .txt, 1 .xml\): give the format"):
        D.read_real(str(tmp_path / "f"))
    (tmp_path / "f" / "b.xml").unlink()
    (tmp_path / "f" / "b.txt").write_text("0 0.5 0.5 0.2 0.2\n")
    with pytest.raises(sg.SynthgenError, match=r"f: a.txt reads as kitti, b.txt as yolo: give the format"):
        D.read_real(str(tmp_path / "f"))


def test_missing_and_unlabelled_images_are_errors(tmp_path):
    _image(tmp_path / "a.png", 20, 10)
    (tmp_path / "a.txt").write_text(KITTI)
    (tmp_path / "b.txt").write_text(KITTI)
    with pytest.raises(sg.SynthgenError, match=r"b.txt: its image b.\* is not found \(looked in "):
        D.read_real(str(tmp_path))
    (tmp_path / "b.txt").unlink()
    _image(tmp_path / "images" / "c.png", 20, 10)
    _image(tmp_path / "images" / "d.png", 20, 10)
    with pytest.raises(sg.SynthgenError, match=r"images: 2 images without a label file \(c.png, d.png\): write an "
                                               r"empty label file for an image without objects"):
        D.read_real(str(tmp_path))
    (tmp_path / "boxes.csv").write_text("a.png,1,2,3,4,car\nz.png,1,2,3,4,car\n")
    with pytest.raises(sg.SynthgenError, match=r"boxes.csv:2: its image 'z.png' is not found"):
        D.read_real(str(tmp_path / "boxes.csv"))
    with pytest.raises(sg.SynthgenError, match=r"holds both a file of many images' labels \(boxes.csv\) and per-image"):
        D.read_real(str(tmp_path))
    with pytest.raises(sg.SynthgenError, match=r"nowhere: label file or folder not found"):
        D.read_real(str(tmp_path / "nowhere"))


def test_negatives_and_ground_truth(tmp_path):
    """Images without objects; an image given twice is refused by ground_truth; a detection on a
    class-less ignore region is neither a true nor a false positive."""
    _image(tmp_path / "neg" / "b.png", 20, 10)
    _image(tmp_path / "neg" / "a.jpg", 20, 10)
    n = D.read_negatives(str(tmp_path / "neg"))
    assert [(os.path.basename(s.image), s.source, s.boxes.shape) for s in n] == [("a.jpg", "negative", (0, 4)),
                                                                                 ("b.png", "negative", (0, 4))]
    with pytest.raises(sg.SynthgenError, match=r"b.png is .*a.jpg's too|is .*'s too"):
        D.ground_truth(list(n) + [n[0]])
    s = D.Sample("x.png", np.array([[0, 0, 30, 30], [40, 0, 80, 40.0]]), ["car", ""], np.array([False, True]), "real")
    gt = D.ground_truth([s])
    # The second detection lies inside the region (IoU 1 as a crowd region: area over its own).
    dets = {"x.png": Detections([[0, 0, 30, 30], [42, 1, 70, 30]], [0.8, 0.9], ["car", "car"])}
    r = score(gt, dets, bootstrap=0).row("car")
    assert r.ap50 == pytest.approx(1.0) and (r.n_gt, r.n_ignored) == (1, 1)
    # Without the region the higher-scored detection is a false positive: precision 1/2 at recall 1.
    bare = D.ground_truth([D.Sample("x.png", s.boxes[:1], ["car"], np.array([False]), "real")])
    assert score(bare, dets, bootstrap=0).row("car").ap50 == pytest.approx(0.5)


@pytest.mark.skipif(not os.path.isdir(os.path.join(REAL, "cars_highway")), reason="../shared/realdata is not here")
def test_the_shared_real_sets_read():
    """boxes.csv: 216 images, 350 cars (its rows, counted here); the EU plates: 54 photos with
    one plate each; the car-free frames: 152 negatives."""
    path = os.path.join(REAL, "cars_highway", "boxes.csv")
    rows = [ln.split(",") for ln in open(path).read().splitlines()[1:] if ln.strip()]
    s = D.read_real(os.path.join(REAL, "cars_highway"), default_class="car")
    assert (len(s), sum(len(x.classes) for x in s)) == (len({r[0] for r in rows}), len(rows)) == (216, 350)
    assert s.summary() == f"{path}: 216 images, 350 boxes (car 350), 0 ignore regions"
    assert all(os.path.isfile(x.image) for x in s)
    first = [r for r in rows if r[0] == os.path.basename(s[0].image)]
    assert s[0].boxes.tolist() == [[float(v) for v in r[1:5]] for r in first]
    eu = D.read_real(os.path.join(REAL, "plates_openalpr", "eu"), classes=["plate"])
    assert len(eu) == 54 and all(x.classes == ["plate"] for x in eu)
    line = open(os.path.join(REAL, "plates_openalpr", "eu", "eu1.txt")).read().split("\t")
    x, y, w, h = (float(v) for v in line[1:5])
    assert next(e for e in eu if e.image.endswith("/eu1.jpg")).boxes.tolist() == [[x, y, x + w, y + h]]
    assert len(D.read_negatives(os.path.join(REAL, "cars_highway", "negatives"))) == 152
