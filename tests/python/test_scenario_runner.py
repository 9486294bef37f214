"""Scenario runner: determinism across workers and resumes, crash safety, labels that agree
with the masks, Dask. Uses tests/python/scenarios/tiny.yaml (64 x 48, 4 spp)."""
from __future__ import annotations

import glob
import hashlib
import json
import os
import random
import signal
import subprocess
import sys
import time

import numpy as np
import OpenImageIO as oiio
import pytest

from synthgen.outputs import coco as C, kitti as K, yolo as Y
from synthgen import outputs, run as runner
from synthgen.frame import FrameRenderer
from synthgen.outputs.meta import completed_frames
from synthgen.outputs.verify import verify_dataset

HERE = os.path.dirname(__file__)
TINY = os.path.join(HERE, "scenarios", "tiny.yaml")
REPO = os.path.abspath(os.path.join(HERE, "..", ".."))
# Files that legitimately differ between runs: timings and absolute paths.
VOLATILE = {"run_summary.json", "dataset.yaml"}


def hashes(out_dir: str) -> dict:
    out = {}
    for p in sorted(glob.glob(os.path.join(out_dir, "**", "*"), recursive=True)):
        if os.path.isfile(p) and os.path.basename(p) not in VOLATILE:
            with open(p, "rb") as f:
                out[os.path.relpath(p, out_dir)] = hashlib.sha256(f.read()).hexdigest()
    return out


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    out = str(tmp_path_factory.mktemp("ref") / "ds")
    s = runner.run(TINY, out, workers=1, progress=False)
    assert s["rendered"] == 6 and not s["failures"], s.text()
    return out


def read_ids(path: str) -> np.ndarray:
    buf = oiio.ImageBuf(path)
    return np.asarray(buf.get_pixels(oiio.UINT16))[..., 0].astype(np.int64)


def test_layout_and_every_frame_present(reference):
    h = hashes(reference)
    for sub, ext in (("images", "png"), ("images", "exr"), ("depth", "exr"), ("depth16", "png"), ("instance", "png"),
                     ("semantic", "png"), ("labels", "txt"), ("kitti", "txt"), ("meta", "json")):
        assert sorted(k for k in h if k.startswith(sub + "/") and k.endswith(ext)) == \
               [f"{sub}/{k:06d}.{ext}" for k in range(6)], sub
    assert "annotations/coco.json" in h
    assert not glob.glob(os.path.join(reference, "**", ".*tmp*"), recursive=True)


def test_same_frames_with_two_workers_and_in_two_halves_with_resume(reference, tmp_path):
    ref = hashes(reference)
    two = str(tmp_path / "two")
    runner.run(TINY, two, workers=2, progress=False)
    assert hashes(two) == ref, "2 workers differ from 1"
    halves = str(tmp_path / "halves")
    runner.run(TINY, halves, count=3, progress=False)
    s = runner.run(TINY, halves, resume=True, progress=False)
    assert s["skipped"] == 3 and s["rendered"] == 3
    assert hashes(halves) == ref, "a resumed run differs"
    alone = str(tmp_path / "alone")
    runner.run(TINY, alone, only=[4], progress=False)
    h = hashes(alone)
    for k in ("images/000004.png", "depth/000004.exr", "instance/000004.png", "meta/000004.json"):
        assert h[k] == ref[k], f"frame 4 rendered alone differs in {k}"


def test_workers_get_the_validated_scenario_not_its_path(reference, tmp_path):
    """A task carries the validated scenario: a scenario that exists only in memory renders
    the same frame, file for file, as the run that read it from disk."""
    from synthgen.scenario import parse_scenario
    from synthgen.schema.yaml_io import parse_yaml

    with open(TINY, encoding="utf-8") as f:
        text = f.read()
    sc = parse_scenario(parse_yaml(text, "<memory>"), "<memory>", os.path.dirname(TINY), text)
    out = str(tmp_path / "mem")
    r = runner.render_task(sc, out, 2)
    assert r["ok"], r.get("traceback")
    ref = hashes(reference)
    mine = hashes(out)
    assert mine and all(mine[k] == ref[k] for k in mine), [k for k in mine if mine[k] != ref[k]]


def test_output_directory_is_not_overwritten_without_resume(reference):
    with pytest.raises(ValueError, match="--resume"):
        runner.run(TINY, reference, progress=False)


def test_labels_agree_with_masks(reference):
    with open(os.path.join(reference, "annotations", "coco.json")) as f:
        coco = json.load(f)
    assert [c["name"] for c in coco["categories"]] == ["box", "ball"]
    assert [a["id"] for a in coco["annotations"]] == list(range(1, len(coco["annotations"]) + 1))
    assert len(coco["images"]) == 6
    n_checked = 0
    for k in range(6):
        ids = read_ids(os.path.join(reference, "instance", f"{k:06d}.png"))
        sem = read_ids(os.path.join(reference, "semantic", f"{k:06d}.png"))
        with open(os.path.join(reference, "meta", f"{k:06d}.json")) as f:
            meta = json.load(f)
        anns = [a for a in coco["annotations"] if a["image_id"] == k]
        yolo = Y.parse_yolo(open(os.path.join(reference, "labels", f"{k:06d}.txt")).read(), 64, 48)
        kitti = K.parse_kitti(open(os.path.join(reference, "kitti", f"{k:06d}.txt")).read())
        present = sorted(set(np.unique(ids)) - {0})
        # Every visible object is labelled exactly once, nothing else is.
        assert sorted(a["instance_id"] for a in anns) == present
        assert len(yolo) == len(kitti) == len(present)
        for a, (cls, ybox), kt in zip(sorted(anns, key=lambda a: a["instance_id"]), yolo, kitti):
            m = ids == a["instance_id"]
            np.testing.assert_array_equal(C.rle_decode(a["segmentation"]), m)
            assert a["area"] == m.sum() and a["bbox"] == C.mask_bbox(m)
            assert set(np.unique(sem[m])) == {a["category_id"]}
            obj = next(o for o in meta["objects"] if o["instance_id"] == a["instance_id"])
            assert obj["class_id"] == a["category_id"] and obj["visible_pixels"] == m.sum()
            assert 0.0 <= a["occlusion"] <= 1.0 and 0.0 <= a["truncation"] <= 1.0
            assert obj["amodal_pixels"] >= obj["visible_pixels"]
            assert cls == a["category_id"] - 1
            np.testing.assert_allclose(ybox, a["bbox"], atol=0.01)
            np.testing.assert_allclose(kt["bbox"], a["bbox"], atol=0.01)
            n_checked += 1
        # Depth is metres along the camera axis where something was hit, 16-bit mm copy agrees.
        d = np.asarray(oiio.ImageBuf(os.path.join(reference, "depth", f"{k:06d}.exr")).get_pixels(oiio.FLOAT))[..., 0]
        d16 = read_ids(os.path.join(reference, "depth16", f"{k:06d}.png"))
        fin = np.isfinite(d)
        assert np.all(np.abs(d16[fin] - np.round(d[fin] * 1000)) <= 0) and np.all(d16[~fin] == 0)
        # The seed and the sampled parameters are recorded.
        assert meta["frame"] == k and meta["scenario_seed"] == 11 and meta["sampled"]
    assert n_checked >= 6


def test_killed_runs_resume_to_the_same_dataset(tmp_path):
    # A slower variant of tiny.yaml (64 spp, 12 frames) so that kills land mid-run.
    slow = str(tmp_path / "slow.yaml")
    with open(TINY) as f, open(slow, "w") as g:
        g.write(f.read().replace("render: {spp: 4,", "render: {spp: 96,").replace("count: 6", "count: 12"))
    ref_dir = str(tmp_path / "ref")
    runner.run(slow, ref_dir, progress=False)
    out = str(tmp_path / "killed")
    env = dict(os.environ, PYTHONPATH=os.path.join(REPO, "python"))
    cmd = [sys.executable, "-m", "synthgen", "run", slow, "-o", out, "--no-progress", "--resume"]
    rng = random.Random(4)
    interrupted = 0
    for attempt in range(4):
        p = subprocess.Popen(cmd, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                             start_new_session=True)
        time.sleep(rng.uniform(0.6, 1.2))
        os.killpg(p.pid, signal.SIGKILL)
        p.wait()
        done = completed_frames(out) if os.path.isdir(out) else []
        interrupted += len(done) < 12
    assert interrupted >= 2, "the kills did not interrupt the run: make the scenario slower"
    r = subprocess.run(cmd, env=env, capture_output=True, text=True)
    assert r.returncode == 0, r.stdout + r.stderr
    assert not glob.glob(os.path.join(out, "**", ".*tmp*"), recursive=True), "temporary files left"
    assert completed_frames(out) == list(range(12))
    assert hashes(out) == hashes(ref_dir)


def test_dask_local_cluster_equals_local_run(reference, tmp_path):
    distributed = pytest.importorskip("distributed")
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1",
                                  dashboard_address=None) as cluster, distributed.Client(cluster) as client:
        out = str(tmp_path / "dask")
        s = runner.run(TINY, out, count=4, scheduler=client, progress=False)
        assert s["rendered"] == 4 and not s["failures"], s.text()
        # Two workers on this machine share its cores (a worker alone on a remote node would get
        # 0: all of that node's cores, which the client cannot count).
        from synthgen.run.executors import DaskExecutor

        assert DaskExecutor(client).default_threads() == max(1, (os.cpu_count() or 1) // 2)
    ref = hashes(reference)
    for k, v in hashes(out).items():
        if k.startswith(("annotations/", "splits/")):
            continue  # dataset-level: assembled from 4 frames here, 6 in the reference
        assert ref[k] == v, k


def test_worker_scene_stays_bounded_over_many_frames():
    from synthgen import scenario

    fr = FrameRenderer(scenario.load_scenario(TINY))
    for k in range(40):
        fr.render(k)
    stats = fr.scene.commit_stats
    # Ground + at most 2 boxes + 2 balls; one BVH per shape (ground, box, sphere), never rebuilt.
    assert fr.scene.instance_count() <= 5
    assert stats["mesh_bvh_builds"] == 3, stats
    # The same frame from a worker that rendered 40 other frames equals a fresh worker's.
    fresh = FrameRenderer(scenario.load_scenario(TINY))
    a, m, _ = fr.render(17)
    b, n, _ = fresh.render(17)
    for key in a:
        np.testing.assert_array_equal(a[key], b[key])
    assert m == n


def test_verify_dataset_accepts_a_run_and_catches_a_wrong_label(reference, tmp_path):
    r = verify_dataset(reference)
    assert r["frames"] == 6 and r["annotations"] >= 6
    import shutil

    bad = str(tmp_path / "bad")
    shutil.copytree(reference, bad)
    path = os.path.join(bad, "labels", "000002.txt")
    lines = open(path).read().splitlines()
    f = lines[0].split()
    f[1] = f"{float(f[1]) + 0.1:.6f}"  # shift one YOLO box
    open(path, "w").write("\n".join([" ".join(f)] + lines[1:]) + "\n")
    with pytest.raises(ValueError, match="YOLO line 1"):
        verify_dataset(bad)


def test_write_frame_is_a_pure_writer(tmp_path):
    """arrays + metadata -> files, no rendering: every file reflects exactly its input."""
    h, w = 12, 16
    ids = np.zeros((h, w), np.uint32)
    ids[2:5, 3:9] = 1          # object 1, class 1
    ids[6:12, 10:16] = 2       # object 2, class 2, touching the image border
    cls = np.where(ids == 1, 1, np.where(ids == 2, 2, 0)).astype(np.uint32)
    depth = np.full((h, w), np.inf, np.float32)
    depth[ids > 0] = 2.5
    rgb = np.random.default_rng(0).random((h, w, 3)).astype(np.float32)
    objs = []
    for k, c in ((1, "car"), (2, "sign")):
        m = ids == k
        objs.append({"index": k - 1, "instance_id": k, "class": c, "class_id": k, "kind": k - 1,
                     "visible_pixels": int(m.sum()), "amodal_pixels": int(m.sum()) + 4, "occlusion": 0.1,
                     "visible_fraction": 0.9, "truncation": 0.0 if k == 1 else 0.5, "bbox": C.mask_bbox(m),
                     "dimensions_hwl": [1, 2, 3], "location_camera": [0, 1, 10], "rotation_y": 0.0, "alpha": 0.0})
    objs.append({"index": 2, "instance_id": 3, "class": "car", "class_id": 1, "kind": 0, "dropped": "no spot"})
    meta = {"frame": 7, "image_size": [w, h], "objects": objs}
    files = outputs.write_frame(str(tmp_path), 7, {"rgb": rgb, "depth": depth, "instance_id": ids, "class_id": cls},
                               meta, ["rgb", "rgb_exr", "depth", "depth16", "instance", "semantic", "coco", "yolo",
                                      "kitti"])
    assert sorted(files) == ["depth", "depth16", "instance", "kitti", "meta", "rgb", "rgb_exr", "semantic", "yolo"]
    np.testing.assert_array_equal(read_ids(files["instance"]), ids)
    np.testing.assert_array_equal(read_ids(files["semantic"]), cls)
    d16 = read_ids(files["depth16"])
    assert set(np.unique(d16[ids > 0])) == {2500} and np.all(d16[ids == 0] == 0)
    exr = np.asarray(oiio.ImageBuf(files["rgb_exr"]).get_pixels(oiio.FLOAT))
    np.testing.assert_array_equal(exr, rgb)
    yolo = Y.parse_yolo(open(files["yolo"]).read(), w, h)
    assert [c for c, _ in yolo] == [0, 1] and yolo[1][1] == pytest.approx([10, 6, 6, 6])
    kitti = K.parse_kitti(open(files["kitti"]).read())
    assert [k["type"] for k in kitti] == ["car", "sign"] and kitti[1]["truncated"] == 0.5
    with open(files["meta"]) as f:
        written = json.load(f)
    anns = written["coco"]["annotations"]
    assert [a["instance_id"] for a in anns] == [1, 2], "the dropped object is not labelled"
    np.testing.assert_array_equal(C.rle_decode(anns[1]["segmentation"]), ids == 2)
    assert written["coco"]["image"] == {"id": 7, "file_name": "images/000007.png", "width": w, "height": h}


def test_ctrl_c_stops_cleanly_and_keeps_completed_frames(tmp_path):
    slow = str(tmp_path / "slow.yaml")
    with open(TINY) as f, open(slow, "w") as g:
        # Many frames: the interrupt comes before the run ends, however fast the machine.
        g.write(f.read().replace("render: {spp: 4,", "render: {spp: 128,").replace("count: 6", "count: 1000"))
    out = str(tmp_path / "ds")
    env = dict(os.environ, PYTHONPATH=os.path.join(REPO, "python"))
    # A test run started in the background by a shell inherits SIGINT ignored (POSIX), and Python
    # then installs no KeyboardInterrupt handler: the child gets the default disposition back.
    p = subprocess.Popen([sys.executable, "-m", "synthgen", "run", slow, "-o", out, "--no-progress"], env=env,
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                         preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    deadline = time.time() + 60
    while time.time() < deadline and len(completed_frames(out) if os.path.isdir(out) else []) < 2:
        time.sleep(0.1)
    p.send_signal(signal.SIGINT)
    stdout, stderr = p.communicate(timeout=60)
    assert p.returncode == 130, stdout + stderr
    assert "interrupted" in stdout + stderr
    done = completed_frames(out)
    assert 2 <= len(done) < 1000
    assert not glob.glob(os.path.join(out, "**", ".*tmp*"), recursive=True)
    with open(os.path.join(out, "annotations", "coco.json")) as f:
        assert len(json.load(f)["images"]) == len(done), "coco.json covers the completed frames"


def small_road_signs(tmp_path, resolution, render):
    """scenarios/road_signs.yaml at a small `resolution` ("[w, h]") and `render` settings."""
    small = str(tmp_path / "signs.yaml")
    with open(os.path.join(REPO, "scenarios", "road_signs.yaml")) as f, open(small, "w") as g:
        g.write(f.read().replace("resolution: [640, 480]", f"resolution: {resolution}")
                .replace("render: {spp: 32, max_depth: 6}", f"render: {render}")
                .replace("min_pixels: 150", "min_pixels: 4"))
    return small


def test_road_signs_with_plates_and_wear(tmp_path):
    """A small version of scenarios/road_signs.yaml: signs and plates with wear render, their
    labels agree with the masks, plate texts are valid registrations and recorded, and a frame
    rendered alone equals the same frame rendered after others (per-frame textures and
    materials are created and removed without changing results)."""
    from synthgen.scene import plates

    small = small_road_signs(tmp_path, "[96, 72]", "{spp: 2, max_depth: 3}")
    out = str(tmp_path / "ds")
    s = runner.run(small, out, count=4, progress=False)
    assert s["rendered"] == 4 and not s["failures"], s.text()
    verify_dataset(out)
    n_plates = n_signs = 0
    for k in range(4):
        with open(os.path.join(out, "meta", f"{k:06d}.json")) as f:
            meta = json.load(f)
        for o in meta["objects"]:
            if o.get("plate"):
                assert plates.is_valid_registration(o["plate"]["country"], o["plate"]["text"])
                n_plates += 1
            if o.get("sign"):
                n_signs += 1
    assert n_plates >= 4 and n_signs >= 2
    alone = str(tmp_path / "alone")
    runner.run(small, alone, only=[3], progress=False)
    a, b = hashes(out), hashes(alone)
    for key in ("images/000003.png", "instance/000003.png", "meta/000003.json"):
        assert a[key] == b[key], key


def test_decals_from_scenarios(tmp_path):
    """objects[].decals: a pictogram and a plate projected onto boxes (object space); recorded
    in meta, the labels still agree with the masks, and the decal shows in the albedo."""
    scen = str(tmp_path / "decals.yaml")
    with open(TINY) as f, open(scen, "w") as g:
        text = f.read().replace("    material: {type: coated, albedo: {hsv: {color: [0.6, 0.2, 0.1], h: 0.3, s: 0.2, v: 0.2}}}",
                                "    material: {type: diffuse, albedo: 0.05}\n"
                                "    decals:\n"
                                "      - {pictogram: {family: stop}, size: 0.8}\n"
                                "      - {plate: {country: de}, size: 0.9, height: 0.2}\n"
                                "      - {plate: {country: ru}, size: 0.9, height: 0.8}\n"
                                "      - {image: stripe.png, size: 0.5, height: 0.5}")
        assert "decals" in text
        g.write(text)
    # A 3:1 image file: its decal keeps that aspect on the object.
    stripe = np.zeros((20, 60, 3), np.float32)
    stripe[:, ::10] = 1.0
    oiio.ImageBuf(stripe).write(str(tmp_path / "stripe.png"))
    out = str(tmp_path / "ds")
    s = runner.run(scen, out, count=3, progress=False)
    assert s["rendered"] == 3 and not s["failures"], s.text()
    verify_dataset(out)
    kinds = []
    for k in range(3):
        with open(os.path.join(out, "meta", f"{k:06d}.json")) as f:
            meta = json.load(f)
        for o in meta["objects"]:
            if o["class"] == "box" and not o.get("dropped"):
                kinds.append([d["kind"] for d in o.get("decals", [])])
                aspects = [d["size"][0] / d["size"][1] for d in o["decals"]]
                assert aspects == pytest.approx([1.0, 520 / 110, 520 / 112, 3.0], rel=1e-4)
    assert kinds and all(k == ["pictogram", "plate", "plate", "image"] for k in kinds)
    # The boxes are nearly black (albedo 0.05); the decals make parts of them bright.
    bright = 0
    for k in range(3):
        img = np.asarray(oiio.ImageBuf(os.path.join(out, "images", f"{k:06d}.png")).get_pixels(oiio.FLOAT))
        sem = read_ids(os.path.join(out, "semantic", f"{k:06d}.png"))
        box = sem == 1
        bright += int((img[..., :3].mean(axis=-1)[box] > 0.5).sum())
    assert bright > 10, "no decal visible on the boxes"


def test_every_wear_parameter_from_yaml(tmp_path):
    """Every preset parameter is reachable from a scenario, also as a distribution: the
    values drawn reach synthgen.wear (recorded in meta) and the frames render."""
    scen = str(tmp_path / "worn.yaml")
    with open(TINY) as f, open(scen, "w") as g:
        text = f.read().replace(
            "    material: {type: coated, albedo: {hsv: {color: [0.6, 0.2, 0.1], h: 0.3, s: 0.2, v: 0.2}}}",
            "    material: {type: diffuse, albedo: 0.5}\n"
            "    wear:\n"
            "      rust: {amount: 0.4, roughness: {uniform: [0.3, 0.6]}, bump: 0.001,\n"
            "             colors: [{position: 0.8, color: [0.5, 0.2, 0.05]},\n"
            "                      {position: 0.0, color: {hsv: {color: [0.1, 0.05, 0.02], v: 0.1}}}]}\n"
            "      dirt: {amount: 0.3, color: [0.2, 0.15, 0.1], roughness: 0.9, ao_radius: 0.1, stochastic: false}\n"
            "      scratches: {density: 10, direction: {choice: [x, z]}, elongation: {uniform: [4, 12]},\n"
            "                  metal: copper, roughness: 0.3, depth: 0.001}\n"
            "      ice: {amount: 0.2, bump: 0.002, top_bias: 1.0}")
        assert "scratches" in text
        g.write(text)
    out = str(tmp_path / "ds")
    s = runner.run(scen, out, count=2, progress=False)
    assert s["rendered"] == 2 and not s["failures"], s.text()
    verify_dataset(out)
    seen = 0
    for k in range(2):
        with open(os.path.join(out, "meta", f"{k:06d}.json")) as f:
            meta = json.load(f)
        for o in meta["objects"]:
            if o["class"] != "box":
                continue
            w = o["wear"]
            assert set(w) == {"rust", "dirt", "scratches", "ice"}
            assert 0.3 <= w["rust"]["roughness"] <= 0.6 and w["rust"]["bump"] == 0.001
            assert [c[0] for c in w["rust"]["colors"]] == [0.0, 0.8], "ramp stops sorted by position"
            assert w["dirt"]["color"] == [0.2, 0.15, 0.1] and w["dirt"]["roughness"] == 0.9
            assert w["dirt"]["stochastic"] is False and w["rust"]["stochastic"] is True
            sc = w["scratches"]
            assert sc["direction"] in ("x", "z") and 4 <= sc["elongation"] <= 12
            assert sc["metal"] == "copper" and sc["depth"] == 0.001
            assert w["ice"]["bump"] == 0.002
            seen += 1
    assert seen >= 2


def test_generated_images_do_not_accumulate(tmp_path, monkeypatch):
    """Plates, signs and wear are generated per frame, in memory (Scene.add_image_texture): no
    file is written for them, and a long batch keeps only the current frame's textures and
    materials in the worker's scene (unique plates would otherwise grow it without bound)."""
    import tempfile

    from synthgen import scenario

    made = []
    real = tempfile.mkdtemp
    monkeypatch.setattr(tempfile, "mkdtemp", lambda *a, **k: made.append(real(*a, **k)) or made[-1])
    small = small_road_signs(tmp_path, "[48, 36]", "{spp: 1, max_depth: 2}")
    fr = FrameRenderer(scenario.load_scenario(small))
    textures, materials = [], []
    for k in range(8):
        _, meta, _ = fr.render(k)
        textures.append(fr.scene.texture_count())
        materials.append(fr.scene.material_count())
    assert made == []
    # Bounded: the frame's own generated resources only (not growing with the frame count).
    assert max(textures) <= 80 and max(materials) <= 60, (textures, materials)
    assert textures[-1] <= 2 * min(textures[2:]) + 40, textures
