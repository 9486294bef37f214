"""``synthgen verify``: a dataset's labels agree with its masks.

Every frame with metadata must be complete (all its files present and decodable); for each,
each COCO annotation decodes to exactly the pixels of its instance
in ``instance/*.png``, bbox and area are the mask's, the semantic mask holds its category
there, every visible instance is labelled once, and the YOLO and KITTI files hold the same
boxes and classes.
"""
from __future__ import annotations

import os
from typing import Any, Dict, List

import numpy as np

from .._core import SynthgenError
from .coco import mask_bbox, rle_decode
from .kitti import parse_kitti
from .meta import frame_status, read_meta
from .registry import frame_name
from .yolo import parse_yolo

__all__ = ["verify_dataset"]


def _read_u16(path: str) -> np.ndarray:
    import OpenImageIO as oiio

    buf = oiio.ImageBuf(path)
    px = None if buf.has_error else buf.get_pixels(oiio.UINT16)
    if px is None or buf.has_error or np.asarray(px).ndim != 3:
        raise SynthgenError(f"{path}: unreadable image: {buf.geterror() or 'no pixels'}")
    return np.asarray(px)[..., 0].astype(np.int64)


def _readable(path: str) -> None:
    import OpenImageIO as oiio

    buf = oiio.ImageBuf(path)
    if buf.has_error or not buf.read():
        raise SynthgenError(f"{path}: unreadable image: {buf.geterror() or 'no pixels'}")


def verify_dataset(out_dir: str) -> Dict[str, Any]:
    """Checks that the labels of a dataset agree with its masks: for every complete frame,
    each COCO annotation decodes to exactly the pixels of its instance in instance/*.png,
    bbox and area are the mask's, the semantic mask holds its category there, every visible
    instance is labelled once, and the YOLO and KITTI files hold the same boxes and classes.
    Returns counts (``annotations`` = ``inserted`` + ``real``: the rendered objects and a photo's
    labelled real ones, ``source: real``, as ``synthgen inspect`` counts them); raises
    SynthgenError naming the first disagreement."""
    import json

    def fail(msg: str) -> None:
        raise SynthgenError(f"{out_dir}: {msg}")

    frames, broken = frame_status(out_dir)
    for k, reason in broken.items():
        fail(f"frame {k} is incomplete: {reason}")
    if not frames:
        fail("no complete frame (no meta/NNNNNN.json)")
    coco_path = os.path.join(out_dir, "annotations", "coco.json")
    try:
        with open(coco_path, encoding="utf-8") as f:
            coco = json.load(f)
        names = [c["name"] for c in coco["categories"]]
        by_image: Dict[int, List[Dict[str, Any]]] = {}
        for a in coco["annotations"]:
            by_image.setdefault(a["image_id"], []).append(a)
        image_ids = sorted(im["id"] for im in coco["images"])
    except (OSError, ValueError, KeyError, TypeError) as e:
        fail(f"{coco_path}: missing or unreadable ({type(e).__name__}: {e})")
    for k in frames:
        meta = read_meta(os.path.join(out_dir, "meta", frame_name(k) + ".json"))
        if "instance" not in meta["files"]:
            fail(f"frame {k}: no instance mask (the `instance` output is needed to verify labels)")
        for kind, rel in meta["files"].items():  # every file of the frame decodes
            path = os.path.join(out_dir, rel)
            if rel.endswith((".png", ".exr")):
                _read_u16(path) if kind in ("instance", "semantic", "depth16") else _readable(path)
    if image_ids != frames:
        fail("annotations/coco.json does not list exactly the complete frames")
    n_inserted = n_real = 0
    for k in frames:
        name = frame_name(k)
        ids = _read_u16(os.path.join(out_dir, "instance", name + ".png"))
        h, w = ids.shape
        sem_path = os.path.join(out_dir, "semantic", name + ".png")
        sem = _read_u16(sem_path) if os.path.isfile(sem_path) else None
        meta = read_meta(os.path.join(out_dir, "meta", name + ".json"))
        all_anns = by_image.get(k, [])
        anns = sorted((a for a in all_anns if a.get("source") != "real"), key=lambda a: a["instance_id"])
        real = [a for a in all_anns if a.get("source") == "real" and not a["iscrowd"]]
        meta_real = [o for o in meta.get("real_objects", []) if not o["ignore"]]
        if [(a["category_id"], a["bbox"]) for a in real] != \
                [(o["class_id"], [o["bbox"][0], o["bbox"][1], o["bbox"][2] - o["bbox"][0], o["bbox"][3] - o["bbox"][1]])
                 for o in meta_real]:
            fail(f"frame {k}: COCO's real objects differ from the frame's meta")
        present = sorted(int(i) for i in np.unique(ids) if i != 0)
        if [a["instance_id"] for a in anns] != present:
            fail(f"frame {k}: COCO labels instances {[a['instance_id'] for a in anns]}, mask shows {present}")
        yolo_path = os.path.join(out_dir, "labels", name + ".txt")
        kitti_path = os.path.join(out_dir, "kitti", name + ".txt")
        yolo = parse_yolo(open(yolo_path).read(), w, h) if os.path.isfile(yolo_path) else None
        kitti = parse_kitti(open(kitti_path).read()) if os.path.isfile(kitti_path) else None
        if kitti is not None:
            kitti = [kt for kt in kitti if kt["type"] != "DontCare"]
        for lst, what in ((yolo, "YOLO"), (kitti, "KITTI")):
            if lst is not None and len(lst) != len(anns) + len(real):
                fail(f"frame {k}: {what} has {len(lst)} objects, COCO {len(anns) + len(real)}")
        for j, a in enumerate(real):  # after the inserted objects, in the same order everywhere
            jj = len(anns) + j
            if yolo is not None and (yolo[jj][0] != a["category_id"] - 1 or
                                     np.max(np.abs(np.subtract(yolo[jj][1], a["bbox"]))) > 1e-3 * max(w, h)):
                fail(f"frame {k}: YOLO line {jj + 1} differs from COCO's real object {j}")
            if kitti is not None and np.max(np.abs(np.subtract(kitti[jj]["bbox"], a["bbox"]))) > 0.01:
                fail(f"frame {k}: KITTI line {jj + 1} differs from COCO's real object {j}")
            n_real += 1
        for j, a in enumerate(anns):
            m = ids == a["instance_id"]
            if not np.array_equal(rle_decode(a["segmentation"]), m):
                fail(f"frame {k}: the RLE of instance {a['instance_id']} is not its mask")
            if a["area"] != int(m.sum()) or a["bbox"] != mask_bbox(m):
                fail(f"frame {k}: area/bbox of instance {a['instance_id']} differ from its mask")
            if sem is not None and set(np.unique(sem[m]).tolist()) != {a["category_id"]}:
                fail(f"frame {k}: semantic mask disagrees with category of instance {a['instance_id']}")
            if yolo is not None:
                c, box = yolo[j]
                if c != a["category_id"] - 1 or np.max(np.abs(np.subtract(box, a["bbox"]))) > 1e-3 * max(w, h):
                    fail(f"frame {k}: YOLO line {j + 1} differs from COCO annotation {a['id']}")
            if kitti is not None:
                kt = kitti[j]
                if kt["type"] != names[a["category_id"] - 1].replace(" ", "_") or \
                        np.max(np.abs(np.subtract(kt["bbox"], a["bbox"]))) > 0.01:
                    fail(f"frame {k}: KITTI line {j + 1} differs from COCO annotation {a['id']}")
            n_inserted += 1
    return {"frames": len(frames), "annotations": n_inserted + n_real, "inserted": n_inserted, "real": n_real,
            "categories": names}
