"""The labels of a photo's real objects (synthgen.background.label_files and .labels): every
reader (labelme, COCO, YOLO, KITTI, CSV, Pascal VOC), the errors that keep real cars from
vanishing from the labels (a classes mapping that misses the file's classes, a mapping to a class
the scenario does not have, YOLO files in pixels), bounded reading of malformed files, and real
boxes a crop cuts to a sliver becoming ignore regions."""
from __future__ import annotations

import json
import os
import re

import numpy as np
import OpenImageIO as oiio
import pytest

import synthgen as sg
from synthgen.background.calibration import Calibration
from synthgen.background.label_files import RealObject, label_images, read_label_file
from synthgen.background.labels import check_classes, load_labels, read_labels
from synthgen.background.photos import Photo
from synthgen.background.photoset import PhotoSet
from synthgen.background.sidecar import PhotoSetup, read_photo_setup
from synthgen.frame.photo import real_object_records
from synthgen.schema.errors import SceneFileError

REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
SHARED = os.path.abspath(os.path.join(REPO, "..", "shared"))

KITTI = ("Car 0.00 0 -1.5 10 20 60 70 1.5 1.6 3.9 1 1.6 12 -1.5\n"
         "Car 0.00 0 -1.5 80 20 120 60 1.5 1.6 3.9 1 1.6 12 -1.5\n"
         "Pedestrian 0.00 0 -1.5 130 20 140 60 1.7 0.6 0.8 1 1.6 12 -1.5\n"
         "DontCare -1 -1 -10 150 20 190 40 -1 -1 -1 -1000 -1000 -1000 -10\n")


def test_a_mapping_that_misses_the_files_classes_is_refused(tmp_path):
    """KITTI's 'Car' with classes {car: car}: every car would vanish; refused, naming the file,
    the classes found in it and the mapping. A class mapped to null is dropped deliberately, and
    an ignore region (DontCare) the mapping does not name stays one."""
    k = tmp_path / "000001.txt"
    k.write_text(KITTI)
    with pytest.raises(sg.SynthgenError) as e:
        load_labels(str(k), "kitti", "000001.png", (200, 100), {"car": "car", "Pedestrian": None})
    msg = str(e.value)
    assert msg.startswith(f"{k}: 000001.png: the class 'Car' of its objects is not in the labels' classes mapping")
    assert "classes found in it: Car (2), Pedestrian (1), DontCare (1)" in msg
    assert "classes: {car: car, Pedestrian: null}" in msg and "'Car' is not 'car': class names are case-sensitive" in msg
    # Not listed at all: refused too (a KITTI file also has vans, trucks, cyclists...).
    with pytest.raises(sg.SynthgenError, match=r"the class 'Pedestrian' of its objects is not in the labels' classes"):
        load_labels(str(k), "kitti", "000001.png", (200, 100), {"Car": "car"})
    lf = load_labels(str(k), "kitti", "000001.png", (200, 100), {"Car": "car", "Pedestrian": None})
    assert [(o.cls, o.ignore, list(o.box)) for o in lf.objects] == [
        ("car", False, [10, 20, 60, 70]), ("car", False, [80, 20, 120, 60]), ("DontCare", True, [150, 20, 190, 40])]
    assert lf.found == {"Car": 2, "Pedestrian": 1, "DontCare": 1}
    # labelme, COCO and YOLO: their labels, category names and names[index] are the classes.
    (tmp_path / "a.json").write_text(json.dumps({"shapes": [
        {"label": "Car", "points": [[10, 20], [60, 50]], "shape_type": "rectangle"}]}))
    with pytest.raises(sg.SynthgenError, match=r"a.json: a.jpg: the class 'Car' .* \(classes found in it: Car \(1\); "
                                               r"classes: \{car: car\}\)"):
        read_labels(str(tmp_path / "a.json"), "labelme", "a.jpg", (200, 100), {"car": "car"})
    (tmp_path / "y.txt").write_text("1 0.5 0.5 0.2 0.4\n")
    with pytest.raises(sg.SynthgenError, match=r"y.txt: a.jpg: the class 'truck' .* \(classes found in it: truck \(1\)"):
        read_labels(str(tmp_path / "y.txt"), "yolo", "a.jpg", (200, 100), {"car": "car"}, names=["car", "truck"])


def test_the_mapping_error_reaches_the_calibration(tmp_path):
    """read_photo_setup (synthgen calibrate, validate and run read calibrations through it) reports
    the mapping's error at the calibration's labels entry."""
    photo = tmp_path / "000001.png"
    oiio.ImageBuf(oiio.ImageSpec(200, 100, 3, oiio.UINT8)).write(str(photo))
    (tmp_path / "000001.txt").write_text(KITTI)
    (tmp_path / "calibration.yaml").write_text(
        "intrinsics: {fov_x: 60}\nground: {camera_height: 1.4, horizon: 40}\n"
        "labels: [{file: '{stem}.txt', format: kitti, classes: {car: car}}]\n")
    with pytest.raises(SceneFileError, match=r"calibration.yaml:3:\d+: labels\[0\]\.file: .*000001.txt: 000001.png: the "
                                             r"classes 'Car', 'Pedestrian' of its objects are not in the labels' "
                                             r"classes mapping \(classes found in it: Car \(2\), Pedestrian \(1\), "
                                             r"DontCare \(1\); classes: \{car: car\}\)"):
        read_photo_setup(str(photo), 200, 100)


def test_classes_the_scenario_does_not_have_are_refused(tmp_path):
    """A mapping to a class the scenario lacks (even one this photo's file does not use), or a
    file read without a mapping whose names are not the scenario's, or a calibration object of
    another class: refused at validation (PhotoSet.check) and, should one get through, by the
    frame's real-object records instead of being left out of the labels."""
    k = tmp_path / "k.txt"
    k.write_text(KITTI)
    lf = load_labels(str(k), "kitti", "k.png", (200, 100), {"Car": "car", "Pedestrian": None, "Van": "van"})
    with pytest.raises(sg.SynthgenError) as e:
        check_classes([lf], lf.objects, ["car", "truck"], "k.png")
    assert str(e.value) == (f"{k}: k.png: 'van' is not a class of the scenario (car, truck): its real objects would be "
                            "left out of the labels (classes found in it: Car (2), Pedestrian (1), DontCare (1); "
                            "classes: {Car: car, Pedestrian: null, Van: van}). Map the file's classes to the "
                            "scenario's, or to null to drop their objects deliberately")
    check_classes([lf], lf.objects, ["car", "van"], "k.png")  # every class known: no error
    raw = load_labels(str(k), "kitti", "k.png", (200, 100))
    with pytest.raises(sg.SynthgenError, match=r"'Car', 'Pedestrian' are not a class of the scenario \(car\).*no "
                                               r"classes mapping.*\); 'Car' is not 'car': class names are "
                                               r"case-sensitive\. Map"):
        check_classes([raw], raw.objects, ["car"], "k.png")
    mine = [RealObject("lorry", [0, 0, 5, 5], source="objects[0]")]
    with pytest.raises(sg.SynthgenError, match=r"k.png: the calibration's objects\[0\]: class 'lorry' is not a class "
                                               r"of the scenario \(car\)"):
        check_classes([], mine, ["car"], "k.png")
    # The frame's records refuse what validation missed.
    ps, _ = _photo_set(tmp_path, [RealObject("lorry", [10, 10, 190, 90], source="objects[0]")])
    fp = ps.frame(0, (100, 100), np.random.default_rng(0), 1.0)
    with pytest.raises(sg.SynthgenError, match=r"objects\[0\]: real object of class 'lorry', not a class of the scenario"):
        real_object_records(fp, np.zeros((100, 100), np.int32), ["car"])
    with pytest.raises(sg.SynthgenError, match=r"objects\[0\]: class 'lorry' is not a class of the scenario"):
        ps.check(["car"])


@pytest.mark.parametrize("labels, error", [
    ("{file: '{stem}.txt', format: kitti, classes: {car: car, Pedestrian: null}}",
     r"calibration.yaml:3:\d+: labels\[0\]\.file: .*000001.txt: 000001.png: the class 'Car' of its objects is not in the "
     r"labels' classes mapping \(classes found in it: Car \(2\), Pedestrian \(1\), DontCare \(1\); classes: "
     r"\{car: car, Pedestrian: null\}\); 'Car' is not 'car'"),
    ("{file: '{stem}.txt', format: kitti, classes: {Car: vehicle, Pedestrian: null}}",
     r"aug.yaml:\d+:\d+: background: cannot use this photo: .*000001.txt: 000001.png: 'vehicle' is not a class of the "
     r"scenario \(car\)"),
    ("{file: '{stem}.txt', format: kitti}", r"000001.txt: 000001.png: 'Car', 'Pedestrian' are not a class of the "
                                            r"scenario \(car\)"),
    ("{file: '{stem}.txt', format: kitti, classes: {Car: car, Pedestrian: null}}", None),
])
def test_validate_refuses_labels_that_would_vanish(tmp_path, capsys, labels, error):
    """synthgen validate on a scenario whose photo's KITTI labels would lose their cars."""
    from synthgen.cli import main

    d = tmp_path / "photos"
    d.mkdir()
    oiio.ImageBuf(oiio.ImageSpec(200, 100, 3, oiio.UINT8)).write(str(d / "000001.png"))
    (d / "000001.txt").write_text(KITTI)
    (d / "calibration.yaml").write_text("intrinsics: {fov_x: 60}\nground: {camera_height: 1.4, horizon: 40}\n"
                                        f"labels: [{labels}]\n")
    (tmp_path / "aug.yaml").write_text("count: 1\nresolution: [40, 20]\nbackground: {photos: [photos]}\nobjects:\n"
                                       "  - {class: car, primitive: box, size: [4, 1.5, 1.8]}\n")
    code = main(["validate", str(tmp_path / "aug.yaml")])
    err = capsys.readouterr().err
    if error is None:
        assert code == 0, err
    else:
        assert code != 0 and re.search(error, err), err


def test_calibrate_prints_the_classes_and_checks_them_against_given_ones(tmp_path, capsys):
    """synthgen calibrate prints each labels file's classes and mapping; with --classes it refuses
    a mapping to another class as validate does."""
    from synthgen.cli import main

    photo = tmp_path / "000001.png"
    oiio.ImageBuf(oiio.ImageSpec(200, 100, 3, oiio.UINT8)).write(str(photo))
    (tmp_path / "000001.txt").write_text(KITTI)
    (tmp_path / "000001.png.yaml").write_text(
        "intrinsics: {fov_x: 60}\nground: {camera_height: 1.4, horizon: 40}\n"
        "labels: [{file: 000001.txt, format: kitti, classes: {Car: car, Pedestrian: person}}]\n")
    out = str(tmp_path / "preview.png")
    assert main(["calibrate", str(photo), "-o", out, "--classes", "car"]) != 0
    assert (f"{tmp_path}/000001.txt: 000001.png: 'person' is not a class of the scenario (car): its real objects would "
            "be left out of the labels (classes found in it: Car (2), Pedestrian (1), DontCare (1); classes: {Car: car, "
            "Pedestrian: person})") in capsys.readouterr().err
    assert main(["calibrate", str(photo), "-o", out, "--classes", "car,person"]) == 0
    assert (f"  labels {tmp_path}/000001.txt (kitti): classes found in it: Car (2), Pedestrian (1), DontCare (1); "
            "classes: {Car: car, Pedestrian: person}\n  real objects: 3 labelled, 1 ignore regions") in \
        capsys.readouterr().out


def test_yolo_values_outside_0_1_are_refused(tmp_path):
    """A YOLO file in pixel coordinates is refused (its boxes would land far outside the photo)."""
    y = tmp_path / "a.txt"
    y.write_text("0 0.5 0.5 0.2 0.4\n0 67.7 211.7 105.2 49.4\n")
    with pytest.raises(sg.SynthgenError) as e:
        read_labels(str(y), "yolo", "a.jpg", (676, 380), names=["car"])
    assert str(e.value) == (f"{y}:2: YOLO's cx cy w h are fractions of the image's width and height, in [0, 1] (w and "
                            "h above 0), got '0 67.7 211.7 105.2 49.4' (pixel coordinates? divide x and w by the width "
                            "676, y and h by the height 380)")
    y.write_text("0 0.5 0.5 0 0.4\n")
    with pytest.raises(sg.SynthgenError, match=r"a.txt:1: YOLO's cx cy w h are fractions"):
        read_labels(str(y), "yolo", "a.jpg", (676, 380), names=["car"])
    y.write_text("0 0.5 0.5 1.0 0.4\n")
    assert list(read_labels(str(y), "yolo", "a.jpg", (200, 100), names=["car"])[0].box) == pytest.approx(
        [0, 30, 200, 70])
    # Without names (a training set's reader) the index is the class.
    assert read_label_file(str(y), "yolo", "a.jpg", (200, 100))[0].cls == "0"


def test_csv_labels(tmp_path):
    """image,x0,y0,x1,y1[,class], header optional: rows matched to the photo by file name, else by
    stem; the images a file covers; classless rows take the labels entry's class."""
    c = tmp_path / "boxes.csv"
    c.write_text("image_id,xmin,ymin,xmax,ymax\nimg/a.jpg,1.5,2,30,40\nb.jpg,5,6,7,8\r\n\nimg/a.jpg,10,20,30,40\n")
    assert label_images(str(c), "csv") == ["img/a.jpg", "b.jpg"]
    objs = read_label_file(str(c), "csv", "/photos/a.jpg", (100, 50), default_class="car")
    assert [(o.cls, o.box, o.source) for o in objs] == [("car", [1.5, 2, 30, 40], f"{c}:2"),
                                                        ("car", [10, 20, 30, 40], f"{c}:5")]
    assert [o.box for o in read_label_file(str(c), "csv", "b.png", default_class="car")] == [[5, 6, 7, 8]]  # stem
    # A file parsed once for many photos is parsed again when it changes.
    c.write_text("b.jpg,5,6,70,80\n")
    assert [o.box for o in read_label_file(str(c), "csv", "b.jpg", default_class="car")] == [[5, 6, 70, 80]]
    c.write_text("image_id,xmin,ymin,xmax,ymax\nimg/a.jpg,1.5,2,30,40\nb.jpg,5,6,7,8\r\n\nimg/a.jpg,10,20,30,40\n")
    with pytest.raises(sg.SynthgenError, match=r"boxes.csv:2: the row has no class .*the labels entry's 'class'"):
        read_label_file(str(c), "csv", "a.jpg")
    with pytest.raises(sg.SynthgenError, match=r"boxes.csv: no row for image 'z.jpg' \(the file has boxes of 2 images: "
                                               r"img/a.jpg, b.jpg\); a photo without real objects declares 'objects: "
                                               r"\[\]' instead"):
        read_label_file(str(c), "csv", "z.jpg", default_class="car")
    (tmp_path / "two.csv").write_text("train/a.jpg,1,2,3,4\nval/a.jpg,5,6,7,8\n")
    with pytest.raises(sg.SynthgenError, match=r"two.csv: rows of several images match 'a.jpg': train/a.jpg, val/a.jpg"):
        read_label_file(str(tmp_path / "two.csv"), "csv", "a.jpg", default_class="car")
    c2 = tmp_path / "classes.csv"
    c2.write_text("a.jpg,1,2,3,4,Car\na.jpg,5,6,7,8,van\n")
    lf = load_labels(str(c2), "csv", "a.jpg", (10, 10), {"Car": "car", "van": None})
    assert [(o.cls, o.box) for o in lf.objects] == [("car", [1, 2, 3, 4])] and lf.found == {"Car": 1, "van": 1}


@pytest.mark.parametrize("text, error", [
    ("a.jpg,1,2,3\n", r"bad.csv:1: expected image,x0,y0,x1,y1\[,class\], got 4 columns: 'a.jpg,1,2,3'"),
    ("a.jpg,1,2,3,4\na.jpg,1,x,3,4\n", r"bad.csv:2: expected an image name and four finite numbers x0,y0,x1,y1, got "
                                       r"'a.jpg,1,x,3,4'"),
    ("a.jpg,1,2,3,nan\n", r"bad.csv:1: expected an image name and four finite numbers"),
    ("a.jpg,30,2,3,4\n", r"bad.csv:1: x1 must be greater than x0 and y1 than y0 \(corners of a box\), got "
                         r"'a.jpg,30,2,3,4'"),
    ("image,x,y,w,h\na.jpg,1,2,3,4\n", r"bad.csv:1: the header 'image,x,y,w,h' is not image,x0,y0,x1,y1\[,class\] .*"
                                       r"corners, not a width and height"),
    ('a.jpg,1,2,3,4\n"b.jpg,1,2,3,4\n', r"bad.csv:\d+: (not CSV|expected image)"),
])
def test_malformed_csv_is_an_error_naming_the_line(tmp_path, text, error):
    c = tmp_path / "bad.csv"
    c.write_text(text)
    with pytest.raises(sg.SynthgenError, match=error):
        read_label_file(str(c), "csv", "a.jpg", default_class="car")


def test_a_huge_label_file_is_refused_before_it_is_read(tmp_path):
    from synthgen.background import label_files as labels

    c = tmp_path / "huge.csv"
    with open(c, "wb") as f:
        f.truncate(labels._MAX_CSV_BYTES + 1)
    with pytest.raises(sg.SynthgenError, match=r"huge.csv: a CSV label file of \d+ bytes is larger than"):
        read_label_file(str(c), "csv", "a.jpg")
    c.write_text("a.jpg,1,2,3,4\n" * (labels._MAX_OBJECTS + 1) + "b.jpg,1,2,3,4\n")
    with pytest.raises(sg.SynthgenError, match=rf"huge.csv: {labels._MAX_OBJECTS + 1} boxes for image 'a.jpg', more "
                                               rf"than the {labels._MAX_OBJECTS} one image can have"):
        read_label_file(str(c), "csv", "a.jpg", default_class="car")
    assert len(read_label_file(str(c), "csv", "b.jpg", default_class="car")) == 1
    v = tmp_path / "huge.xml"
    with open(v, "wb") as f:
        f.truncate(labels._MAX_VOC_BYTES + 1)
    with pytest.raises(sg.SynthgenError, match=r"huge.xml: a Pascal VOC file of \d+ bytes is larger than"):
        read_label_file(str(v), "voc", "a.jpg")


VOC = """<?xml version="1.0"?>
<annotation>
  <folder>VOC2007</folder>
  <filename>000005.jpg</filename>
  <size><width>200</width><height>100</height><depth>3</depth></size>
  <object>
    <name>car</name><truncated>0</truncated><difficult>0</difficult>
    <bndbox><xmin>11</xmin><ymin>21</ymin><xmax>60</xmax><ymax>70.5</ymax></bndbox>
  </object>
  <object>
    <name>car</name><difficult>1</difficult>
    <bndbox><xmin>100</xmin><ymin>30</ymin><xmax>120</xmax><ymax>40</ymax></bndbox>
  </object>
</annotation>
"""


def test_pascal_voc_labels(tmp_path):
    """VOC's 1-based inclusive pixel indices become continuous corners (xmin - 1, xmax);
    difficult objects are ignore regions; the file's image name and size are checked."""
    v = tmp_path / "000005.xml"
    v.write_text(VOC)
    objs = read_label_file(str(v), "voc", "/x/000005.png", (200, 100))
    assert [(o.cls, o.box, o.ignore, o.source) for o in objs] == [
        ("car", [10, 20, 60, 70.5], False, f"{v}:6"), ("car", [99, 29, 120, 40], True, f"{v}:10")]
    assert label_images(str(v), "voc") == ["000005.jpg"]
    with pytest.raises(sg.SynthgenError, match=r"000005.xml: its labels are for a 200 x 100 image, the photo is 100 x 50"):
        read_label_file(str(v), "voc", "000005.jpg", (100, 50))
    with pytest.raises(sg.SynthgenError, match=r"000005.xml:4: its labels are for image '000005.jpg', the photo is "
                                               r"'000006.jpg'"):
        read_label_file(str(v), "voc", "000006.jpg", (200, 100))


@pytest.mark.parametrize("text, error", [
    ('<?xml version="1.0"?>\n<!DOCTYPE lolz [\n <!ENTITY lol "lol">\n <!ENTITY lol2 "&lol;&lol;&lol;&lol;">\n]>\n'
     "<annotation><object><name>&lol2;</name></object></annotation>\n",
     r"bomb.xml:2: a Pascal VOC file with a DTD or entity declarations is refused"),
    ('<?xml version="1.0"?>\n<!DOCTYPE a SYSTEM "file:///etc/passwd">\n<annotation/>\n',
     r"bomb.xml:2: a Pascal VOC file with a DTD or entity declarations is refused"),
    ("<annotation>\n<object><name>car</name>\n<bndbox><xmin>1</xmin></bndbox></object>\n</annotation>\n",
     r"bomb.xml:3: bndbox: ymin must be a finite number"),
    ("<annotation>\n<object><name>car</name>\n<bndbox><xmin>9</xmin><ymin>1</ymin><xmax>2</xmax><ymax>5</ymax>"
     "</bndbox></object>\n</annotation>\n", r"bomb.xml:3: bndbox: xmax must be at least xmin"),
    ("<annotation>\n<object>\n<bndbox/></object>\n</annotation>\n",
     r"bomb.xml:2: an <object> needs a <name> and a <bndbox>"),
    ("<annotation>\n<object><name>car</name>\n</annotation>\n", r"bomb.xml:3: not XML \(mismatched tag\)"),
    ("<a>" * 40 + "</a>" * 40, r"bomb.xml:1: elements nested deeper than 32"),
    ("<root/>", r"bomb.xml:1: not a Pascal VOC file \(its root is <root>, not <annotation>\)"),
])
def test_malformed_or_hostile_voc_is_an_error_naming_the_line(tmp_path, text, error):
    v = tmp_path / "bomb.xml"
    v.write_text(text)
    with pytest.raises(sg.SynthgenError, match=error):
        read_label_file(str(v), "voc", "bomb.jpg", (200, 100))


def _photo_set(tmp_path, objects, width=200, height=100):
    """A PhotoSet of one photo (width x height, black) whose calibration has ``objects``."""
    path = str(tmp_path / "road.png")
    open(path, "wb").close()
    ps = PhotoSet({"photos": [path], "unlabelled_ok": False}, str(tmp_path), 1)
    cal = Calibration(width=width, height=height, fx=100.0, fy=100.0, cx=width / 2, cy=height / 2,
                      camera_height=1.4, pitch=5.0, roll=0.0)
    ps._photos[path] = Photo(path, np.zeros((height, width, 3), np.float32), "0" * 64)
    ps._setups[path] = PhotoSetup(path, cal, objects=objects, labelled=True)
    return ps, path


def test_slivers_a_crop_leaves_of_real_boxes_are_ignore_regions(tmp_path, monkeypatch):
    """The crop [50, 150) x [0, 100) of a 200 x 100 photo: a real box cut to under 4 px wide or
    high, or to under 25 % of its area, is an ignore region in the frame (written as one), never
    an object and never left out; what is left of the others is an object."""
    boxes = {"kept 75%": [40, 10, 80, 50],          # 30 x 40 of 40 x 40 left
             "3 px wide": [45, 10, 53, 50],          # 3 of 8 px wide left (37.5 % of the area)
             "25% left": [20, 10, 60, 90],          # 10 of 40 px: exactly 25 %
             "24.4% left": [19, 10, 60, 90],        # 10 of 41 px
             "4 px high": [120, 40, 140, 44],       # inside the crop
             "3.5 px high": [120, 60, 140, 63.5],   # inside the crop, too thin
             "outside": [0, 0, 30, 30]}             # not in the frame
    objects = [RealObject(name, box, None, False, name) for name, box in boxes.items()]
    objects.append(RealObject("crowd", [45, 60, 53, 70], None, True, "ignore cut"))
    ps, _ = _photo_set(tmp_path, objects)
    monkeypatch.setattr(PhotoSet, "_crop", staticmethod(lambda *a: (50, 0)))
    fp = ps.frame(0, (100, 100), np.random.default_rng(0), 1.0)
    assert fp.crop == (50, 0, 100, 100)
    got = {o.source: (o.ignore, [float(v) for v in o.box]) for o in fp.objects}
    assert got == {"kept 75%": (False, [0, 10, 30, 50]), "3 px wide": (True, [0, 10, 3, 50]),
                   "25% left": (False, [0, 10, 10, 90]), "24.4% left": (True, [0, 10, 10, 90]),
                   "4 px high": (False, [70, 40, 90, 44]), "3.5 px high": (True, [70, 60, 90, 63.5]),
                   "ignore cut": (True, [0, 60, 3, 70])}
    recs = {r["from"]: r for r in real_object_records(fp, np.zeros((100, 100), np.int32),
                                                      [o.cls for o in objects])}
    assert set(recs) == set(got)
    for src, (ignore, box) in got.items():
        r = recs[src]
        assert (r["ignore"], r["bbox"]) == (ignore, box)
        cls = next(o.cls for o in objects if o.source == src)
        # An ignore region: class None, and what it was.
        assert (r["class"], r.get("what")) == ((None, cls) if ignore else (cls, None))


@pytest.mark.skipif(not os.path.isdir(os.path.join(SHARED, "realdata", "cars_highway")),
                    reason="../shared/realdata is not here")
def test_the_highway_boxes_csv_reads():
    """../shared/realdata/cars_highway/boxes.csv (image_id,xmin,ymin,xmax,ymax) through the CSV
    reader: every image it names, each image's rows, boxes inside the 676 x 380 frames."""
    path = os.path.join(SHARED, "realdata", "cars_highway", "boxes.csv")
    with open(path) as f:
        rows = [line.strip().split(",") for line in f.read().splitlines()[1:] if line.strip()]
    images = label_images(path, "csv")
    assert images == list(dict.fromkeys(r[0] for r in rows))
    assert all(os.path.isfile(os.path.join(SHARED, "realdata", "cars_highway", "images", im)) for im in images)
    total = 0
    for im in images:
        objs = read_label_file(path, "csv", im, (676, 380), default_class="car")
        assert objs and all(o.cls == "car" and 0 <= o.box[0] < o.box[2] <= 676 and 0 <= o.box[1] < o.box[3] <= 380
                            for o in objs)
        assert [o.box for o in objs] == [[float(v) for v in r[1:5]] for r in rows if r[0] == im]
        total += len(objs)
    assert total == len(rows)


def test_a_labelme_object_that_cannot_be_read_is_an_error_not_dropped(tmp_path):
    """A polygon of 2 points, a rectangle of 3 and a shape type the reader does not know (labelme's
    'mask') each mark an object: an error naming the shape, never a label left out. Points and
    lines mark no object and are skipped."""
    f = tmp_path / "a.json"
    for shape, words in ((
            {"label": "car", "points": [[1, 2], [30, 40]], "shape_type": "polygon"}, "a polygon needs at least 3 points"),
            ({"label": "car", "points": [[1, 2], [30, 40], [5, 6]], "shape_type": "rectangle"}, "a rectangle needs 2"),
            ({"label": "car", "points": [[1, 2], [30, 40]], "shape_type": "mask"}, "shape_type 'mask' is not read")):
        f.write_text(json.dumps({"shapes": [shape]}))
        with pytest.raises(sg.SynthgenError, match=r"a.json: shapes\[0\]: " + words):
            read_labels(str(f), "labelme", "a.jpg", (200, 100), {"car": "car"})
    f.write_text(json.dumps({"shapes": [{"label": "pole", "points": [[1, 2]], "shape_type": "point"},
                                        {"label": "lane", "points": [[1, 2], [9, 9]], "shape_type": "line"},
                                        {"label": "car", "points": [[1, 2], [30, 40]], "shape_type": "rectangle"}]}))
    objs = read_labels(str(f), "labelme", "a.jpg", (200, 100), {"car": "car", "pole": None, "lane": None})
    assert [(o.cls, list(o.box)) for o in objs] == [("car", [1.0, 2.0, 30.0, 40.0])]


def test_openalpr_plate_labels(tmp_path):
    """OpenALPR's benchmark files (file<TAB>x<TAB>y<TAB>w<TAB>h<TAB>PLATE_TEXT: top-left corner
    and size in pixels): class 'plate', box [x, y, x + w, y + h]; a line naming another image, a
    malformed line and an empty box are errors naming the line."""
    f = tmp_path / "eu7.txt"
    f.write_text("eu7.jpg\t396\t340\t203\t46\tM5XSX\neu7.jpg\t10.5\t20\t30\t8\tAB 123\n")
    assert label_images(str(f), "openalpr") == ["eu7.jpg"]
    objs = read_label_file(str(f), "openalpr", "/photos/eu7.jpg", (800, 600))
    assert [(o.cls, o.box, o.ignore, o.source) for o in objs] == [
        ("plate", [396.0, 340.0, 599.0, 386.0], False, f"{f}:1"), ("plate", [10.5, 20.0, 40.5, 28.0], False, f"{f}:2")]
    lf = load_labels(str(f), "openalpr", "eu7.jpg", (800, 600), {"plate": "licence_plate"})
    assert [o.cls for o in lf.objects] == ["licence_plate"] * 2
    for text, error in (("eu8.jpg\t1\t2\t3\t4\tX\n", r"eu7.txt:1: the plate is for image 'eu8.jpg', the photo is "
                                                     r"'eu7.jpg' \(an OpenALPR file holds the plates of one image\)"),
                        ("eu7.jpg 1 2 3 4 X\n", r"eu7.txt:1: expected an OpenALPR line 'file<TAB>x<TAB>y<TAB>width"),
                        ("\neu7.jpg\t1\t2\tx\t4\tX\n", r"eu7.txt:2: expected an OpenALPR line"),
                        ("eu7.jpg\t1\t2\t0\t4\tX\n", r"eu7.txt:1: the plate's width and height \(4th and 5th fields\) "
                                                     r"must be above 0, got 'eu7.jpg\t1\t2\t0\t4\tX'")):
        f.write_text(text)
        with pytest.raises(sg.SynthgenError, match=error):
            read_label_file(str(f), "openalpr", "eu7.jpg")


def test_a_whole_label_set_reads_in_one_pass(tmp_path):
    """read_label_set: every image of a COCO or CSV file with the objects read_label_file gives
    it; a COCO annotation of no image and two images of one file name are errors, not labels
    left out."""
    from synthgen.background.label_files import read_label_set

    c = tmp_path / "set.json"
    d = {"images": [{"id": 1, "file_name": "a.jpg", "width": 60, "height": 40}, {"id": 2, "file_name": "b.jpg"}],
         "annotations": [{"image_id": 2, "category_id": 1, "bbox": [1, 2, 3, 4]},
                         {"image_id": 1, "category_id": 1, "bbox": [5, 6, 7, 8], "iscrowd": 1}],
         "categories": [{"id": 1, "name": "car"}]}
    c.write_text(json.dumps(d))
    got = read_label_set(str(c), "coco")
    assert [(li.image, li.size, li.where) for li in got] == [("a.jpg", (60, 40), f"{c}: images[0]"),
                                                             ("b.jpg", None, f"{c}: images[1]")]
    for li in got:
        assert [o.meta() for o in li.objects] == [o.meta() for o in read_label_file(str(c), "coco", li.image)]
    c.write_text(json.dumps({**d, "annotations": d["annotations"] + [{"image_id": 9, "category_id": 1,
                                                                      "bbox": [1, 2, 3, 4]}]}))
    with pytest.raises(sg.SynthgenError, match=r"set.json: annotations\[2\]: image_id 9 is no image's"):
        read_label_set(str(c), "coco")
    c.write_text(json.dumps({**d, "images": d["images"] + [{"id": 3, "file_name": "a.jpg"}]}))
    with pytest.raises(sg.SynthgenError, match=r"set.json: images\[2\]: file_name 'a.jpg' is images\[0\]'s too"):
        read_label_set(str(c), "coco")
    v = tmp_path / "boxes.csv"
    v.write_text("b.jpg,1,2,3,4,car\na.jpg,5,6,7,8\nb.jpg,9,10,11,12,van\n")
    got = read_label_set(str(v), "csv", default_class="truck")
    assert [(li.image, [(o.cls, o.box) for o in li.objects], li.where) for li in got] == [
        ("b.jpg", [("car", [1, 2, 3, 4]), ("van", [9, 10, 11, 12])], f"{v}:1"), ("a.jpg", [("truck", [5, 6, 7, 8])],
                                                                                 f"{v}:2")]
    with pytest.raises(sg.SynthgenError, match=r"'kitti' is not a multi-image label format"):
        read_label_set(str(v), "kitti")
