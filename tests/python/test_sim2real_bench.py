"""bench/sim2real.py's machinery (not its figures): the test/dev split keeps every training frame
200 frames from every test frame, K-frame draws are contiguous blocks, the staging for the
accelerator rewrites every path into one folder, the accelerator's runner trains with a
stand-in for synthgen's compiled core (the machine has none), and the report prints every key
of issue 34 even where an experiment has no model yet."""
from __future__ import annotations

import dataclasses
import glob
import importlib.util
import io
import json
import os
import subprocess
import sys
from contextlib import redirect_stdout

import numpy as np
import pytest

REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
BENCH = os.path.join(REPO, "bench")
HIGHWAY = os.path.abspath(os.path.join(REPO, "..", "shared", "realdata", "cars_highway"))
sys.path.insert(0, BENCH)

from sim2real import splits, stage  # noqa: E402

needs_shared = pytest.mark.skipif(not os.path.isdir(HIGHWAY), reason="../shared/realdata is not here")


def _bench():
    spec = importlib.util.spec_from_file_location("sim2real_bench", os.path.join(BENCH, "sim2real.py"))
    m = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(m)
    return m


@needs_shared
def test_split_keeps_training_frames_away_from_the_test_blocks():
    labelled = sorted(glob.glob(os.path.join(HIGHWAY, "images", "*.jpg")))
    negatives = sorted(glob.glob(os.path.join(HIGHWAY, "negatives", "*.jpg")))
    s = splits.split(labelled, negatives)
    n = splits.frame_number
    test = [n(p) for p in s["test"]]
    assert test and all(splits.in_blocks(t, splits.TEST_BLOCKS) for t in test)
    for key in ("dev", "backgrounds", "recipe_train", "recipe_val"):
        assert s[key], key
        assert min(abs(n(p) - t) for p in s[key] for t in test) >= splits.GAP, key
    assert min(abs(n(a) - n(b)) for a in s["recipe_train"] for b in s["recipe_val"]) >= splits.GAP
    # every frame is in exactly one of test, dev, backgrounds, unused
    parts = s["test"] + s["dev"] + s["backgrounds"] + s["unused"]
    assert sorted(parts) == sorted(labelled + negatives)


def test_contiguous_draws():
    b = _bench()

    class S:
        def __init__(self, k):
            self.image = f"/x/vid_4_{k}.jpg"

    dev = [S(k) for k in range(0, 2000, 20)]   # 100 frames
    rng = np.random.default_rng(0)
    pick = b.contiguous_draw(dev, 25, rng)
    assert len(pick) == 25 and len({p.image for p in pick}) == 25
    order = [p.image for p in sorted(dev, key=lambda s: splits.frame_number(s.image))]
    idx = sorted(order.index(p.image) for p in pick)
    blocks = [idx[i:i + 5] for i in range(0, 25, 5)]
    assert all(bl == list(range(bl[0], bl[0] + 5)) and bl[0] % 5 == 0 for bl in blocks)
    assert [p.image for p in b.contiguous_draw(dev, 25, np.random.default_rng(0))] == [p.image for p in pick]


def _tiny_images(tmp_path, n=2):
    from PIL import Image

    paths = []
    for i in range(n):
        a = np.zeros((64, 96, 3), np.uint8)
        a[10:40, 20:60] = (200, 50, 50)
        p = tmp_path / f"img{i}.png"
        Image.fromarray(a).save(p)
        paths.append(str(p))
    return paths


def test_stage_rewrites_every_path(tmp_path):
    imgs = _tiny_images(tmp_path)
    jobs = [{"name": "a", "classes": ["car"], "mix": None, "options": {"steps": 1, "batch": 1},
             "pools": {"synthetic": [[p, [[20, 10, 60, 40]], ["car"], [False]] for p in imgs]}}]
    out = str(tmp_path / ".device")
    stage.stage(jobs, out)
    staged = json.load(open(os.path.join(out, "jobs.json")))["jobs"]
    from PIL import Image

    for r, src in zip(staged[0]["pools"]["synthetic"], imgs):
        assert not os.path.isabs(r[0]) and os.path.isfile(os.path.join(out, "data", r[0]))
        # the PNG render travels as a JPEG of stage.JPEG_QUALITY, the same picture
        with Image.open(os.path.join(out, "data", r[0])) as im:
            assert im.format == "JPEG" and r[0].endswith(".jpg")
            got = np.asarray(im.convert("RGB"), np.float64)
        assert np.abs(got - np.asarray(Image.open(src), np.float64)).mean() < 3.0
    assert os.path.isfile(os.path.join(out, "code", "bench", "sim2real", "remote.py"))
    assert os.path.isfile(os.path.join(out, "code", "python", "synthgen", "evaluate", "train.py"))
    old = stage.LIMIT
    stage.LIMIT = 10
    try:
        with pytest.raises(SystemExit, match="stage fewer jobs"):
            stage.stage(jobs, out)
    finally:
        stage.LIMIT = old


def test_stage_split_packs_jobs_into_parts_under_the_limit(tmp_path):
    imgs = _tiny_images(tmp_path, 3)

    def job(name, paths):
        return {"name": name, "classes": ["car"], "mix": None, "options": {"steps": 1, "batch": 1},
                "pools": {"synthetic": [[p, [[20, 10, 60, 40]], ["car"], [False]] for p in paths]}}

    jobs = [job("a", imgs[:2]), job("b", imgs[1:3]), job("c", imgs[1:2])]
    out = str(tmp_path / ".device")
    probe = stage._Folder(str(tmp_path / "probe"), stage.JPEG_QUALITY)
    base = probe.size
    probe.add(jobs[0])
    one = probe.size - base                       # job a: two images and its row
    old = stage.LIMIT
    stage.LIMIT = base + one + one // 3           # room for a, not for a and b's one new image
    try:
        parts = stage.stage(jobs, out, split=True)
    finally:
        stage.LIMIT = old
    assert parts == [os.path.join(out, "part0"), os.path.join(out, "part1")]
    names = []
    for p in parts:
        staged = json.load(open(os.path.join(p, "jobs.json")))["jobs"]
        names += [j["name"] for j in staged]
        used = {r[0] for j in staged for r in j["pools"]["synthetic"]}
        have = {os.path.relpath(os.path.join(dp, f), os.path.join(p, "data"))
                for dp, _, fs in os.walk(os.path.join(p, "data")) for f in fs}
        assert used == have                       # every file a job reads, and no other (the undo removed its file)
        assert os.path.isfile(os.path.join(p, "code", "bench", "sim2real", "remote.py"))
        assert sum(os.path.getsize(os.path.join(dp, f)) for dp, _, fs in os.walk(p) for f in fs) <= \
            base + one + one // 3
    assert names == ["a", "b", "c"]               # in order; c shares part1 with b
    stage.LIMIT = 10
    try:
        with pytest.raises(SystemExit, match="job a alone is"):
            stage.stage(jobs, out, split=True)
    finally:
        stage.LIMIT = old


def test_remote_trains_with_the_core_stand_in(tmp_path):
    pytest.importorskip("torch")
    imgs = _tiny_images(tmp_path)
    jobs = {"jobs": [{"name": "tiny", "classes": ["car"], "mix": None,
                      "options": {"steps": 2, "batch": 1, "size": [64, 96], "warmup": 1},
                      "pools": {"synthetic": [[os.path.basename(p), [[20, 10, 60, 40]], ["car"], [False]]
                                              for p in imgs]},
                      "test": [[os.path.basename(imgs[0]), [[20, 10, 60, 40]], ["car"], [False]]]}]}
    jf = tmp_path / "jobs.json"
    jf.write_text(json.dumps(jobs))
    out = tmp_path / "out"
    out.mkdir()
    probe = ("import sys; sys.argv[0] = ''; sys.path.insert(0, %r); from sim2real import remote; "
             "remote._import_evaluate(); import synthgen._core as c; print(hasattr(c, 'read_image_info'))" % BENCH)
    env = dict(os.environ, SYNTHGEN_REMOTE_STANDIN="1")
    r = subprocess.run([sys.executable, "-c", probe], env=env, capture_output=True, text=True)
    assert r.stdout.strip() == "False", r.stderr      # the stand-in, not the compiled core
    r = subprocess.run([sys.executable, os.path.join(BENCH, "sim2real", "remote.py"), str(jf), "--root", str(tmp_path),
                        "--out", str(out), "--device", "cpu", "--workers", "0"], env=env, capture_output=True,
                       text=True)
    assert r.returncode == 0, r.stderr
    res = json.load(open(out / "results.json"))
    assert res["tiny"]["manifest"]["pools"]["synthetic"]["samples"] == 2
    assert "car/all" in res["tiny"]["scores"]
    assert os.path.isfile(out / "tiny.model")


def test_remote_parallel_merges_results_and_packs_models(tmp_path):
    """Two processes, three jobs: every job's result in results.json, the per-process files
    gone, the models moved into tar files under the size asked for, each model once; a job's
    weights do not depend on the number of processes (its batches depend on its seed alone)."""
    pytest.importorskip("torch")
    import tarfile

    imgs = _tiny_images(tmp_path)
    rows = [[os.path.basename(p), [[20, 10, 60, 40]], ["car"], [False]] for p in imgs]
    jobs = {"jobs": [{"name": f"j{i}", "classes": ["car"], "mix": None,
                      "options": {"steps": 2, "batch": 1, "size": [64, 96], "warmup": 1, "seed": i},
                      "pools": {"synthetic": rows}} for i in range(3)]}
    jf = tmp_path / "jobs.json"
    jf.write_text(json.dumps(jobs))
    env = dict(os.environ, SYNTHGEN_REMOTE_STANDIN="1")
    outs = {}
    for parallel in (1, 2):
        out = tmp_path / f"out{parallel}"
        out.mkdir()
        r = subprocess.run([sys.executable, os.path.join(BENCH, "sim2real", "remote.py"), str(jf), "--root",
                            str(tmp_path), "--out", str(out), "--device", "cpu", "--workers", "0", "--parallel",
                            str(parallel), "--pack", "3"], env=env, capture_output=True, text=True)
        assert r.returncode == 0, r.stderr
        assert sorted(json.load(open(out / "results.json"))) == ["j0", "j1", "j2"]
        assert sorted(os.listdir(out))[-1] == "results.json" and not list(out.glob("results_*"))
        members = {}
        for t in sorted(out.glob("models_*.tar")):
            assert os.path.getsize(t) <= 3 * 2**20
            with tarfile.open(t) as tf:
                for m in tf.getmembers():
                    assert m.name not in members
                    members[m.name] = tf.extractfile(m).read()
        assert sorted(members) == ["j0.model", "j1.model", "j2.model"]
        assert not list(out.glob("*.model")) and len(list(out.glob("models_*.tar"))) == 2
        outs[parallel] = members
    import io as _io

    import torch

    for name in outs[1]:
        a = torch.load(_io.BytesIO(outs[1][name]), map_location="cpu")
        b = torch.load(_io.BytesIO(outs[2][name]), map_location="cpu")
        sa, sb = a["state_dict"], b["state_dict"]
        for k in sa:
            if hasattr(sa[k], "shape"):
                assert torch.equal(sa[k], sb[k]), (name, k)


@needs_shared
def test_report_prints_every_key_of_the_issue(tmp_path):
    b = _bench()
    buf = io.StringIO()
    with redirect_stdout(buf):
        b.report("small", str(tmp_path), {}, 1.0)
    keys = {line.split("=")[0] for line in buf.getvalue().splitlines()}
    want = {"sim2real_car_ap50", "sim2real_car_ap50_pure", "paste_control_ap50", "real_trained_ap50",
            "augment_gain_ap50_at_10", "augment_gain_ap50_at_25", "augment_gain_ap50_at_50",
            "augment_gain_ap50_all_dev", "sim2real_plate_ap50", "sim2real_plate_ap50_us"}
    want |= {f"ablation_{n}_ap50" for n in ["no_wear", "no_shadow_catcher", "no_camera_match", "no_denoise",
                                            "plain_light", "one_paint", "one_car", "spp4", "spp16", "spp64"]}
    want |= {f"ablation_{n}_render_cpu_s" for n in ["base", "spp4", "spp64"]}
    want |= {f"ablation_{n}_{k}" for n in ["no_wear", "spp64"] for k in ("delta", "delta_ci", "effect")}
    assert want <= keys, sorted(want - keys)


@needs_shared
def test_unknown_group_is_refused_before_any_render(tmp_path):
    r = subprocess.run([sys.executable, os.path.join(BENCH, "sim2real.py"), "--budget", "small", "--phase", "render",
                        "--groups", "car,cars", "--cache", str(tmp_path / "cache")], capture_output=True, text=True,
                       env=dict(os.environ, PYTHONPATH=os.path.join(REPO, "python")))
    assert r.returncode == 2 and "unknown group(s) ['cars']" in r.stderr, r.stderr
    assert not os.path.exists(tmp_path / "cache" / "inserted")


def test_unpack_extracts_models_and_refuses_other_members(tmp_path):
    import tarfile

    b = _bench()
    (tmp_path / "a.model").write_bytes(b"A")
    with tarfile.open(tmp_path / "models_0.tar", "w") as tf:
        tf.add(tmp_path / "a.model", arcname="a.model")
    (tmp_path / "a.model").unlink()
    b.unpack(str(tmp_path))
    assert (tmp_path / "a.model").read_bytes() == b"A"
    with tarfile.open(tmp_path / "models_1.tar", "w") as tf:
        tf.add(tmp_path / "a.model", arcname="../evil.model")
    with pytest.raises(SystemExit, match="not a model file"):
        b.unpack(str(tmp_path))
    assert not (tmp_path.parent / "evil.model").exists()


def test_pack_numbers_new_tars_after_existing_ones(tmp_path):
    from sim2real import remote

    (tmp_path / "a.model").write_bytes(b"A" * 100)
    assert [os.path.basename(t) for t in remote.pack(str(tmp_path), 1)] == ["models_0.tar"]
    (tmp_path / "b.model").write_bytes(b"B" * 100)
    assert [os.path.basename(t) for t in remote.pack(str(tmp_path), 1)] == ["models_1.tar"]
    import tarfile

    with tarfile.open(tmp_path / "models_0.tar") as tf:
        assert tf.getnames() == ["a.model"]


def _row(ap50, boot):
    from types import SimpleNamespace

    return SimpleNamespace(ap50=ap50, ap50_boot=np.asarray(boot, float))


def test_ablation_table_pairs_the_bootstrap_and_needs_seeds_apart(tmp_path):
    from sim2real import ablations

    rng = np.random.default_rng(0)
    noise = rng.normal(0, 0.02, 400)        # the shared resamples: the same images in every model's draw b
    rows = {"ablation_base_s0": _row(0.50, 0.50 + noise), "ablation_base_s1": _row(0.54, 0.54 + noise),
            # paired: every resample 0.1 lower, seeds below the reference's range -> lower
            "ablation_worse_s0": _row(0.41, 0.41 + noise), "ablation_worse_s1": _row(0.43, 0.43 + noise),
            # the seeds overlap the reference's -> no effect, however tight the interval
            "ablation_same_s0": _row(0.49, 0.49 + noise), "ablation_same_s1": _row(0.52, 0.52 + noise),
            # seeds apart but the unpaired noise swamps it -> no effect
            "ablation_noisy_s0": _row(0.56, 0.56 + rng.normal(0, 0.3, 400)),
            "ablation_noisy_s1": _row(0.57, 0.57 + rng.normal(0, 0.3, 400)),
            "ablation_better_s0": _row(0.60, 0.60 + noise)}
    costs = {"ablation_base_s0": {"frames": 10, "cpu_s": 30.0}, "ablation_base_s1": {"frames": 30, "cpu_s": 50.0}}
    t = {a.name: a for a in ablations.table(rows, costs, ["base", "worse", "same", "noisy", "better", "missing",
                                                          "spp16"], [0, 1], aliases={"spp16": "base"})}
    assert t.pop("spp16") == dataclasses.replace(t["base"], name="spp16")
    assert t["base"].effect == "reference" and t["base"].ap50 == pytest.approx(0.52)
    assert t["base"].cpu_s == pytest.approx(2.0)               # (30 + 50) / (10 + 30) frames
    lo, hi = t["base"].ap50_ci
    assert lo < 0.52 < hi and hi - lo == pytest.approx(np.percentile(noise, 97.5) - np.percentile(noise, 2.5))
    w = t["worse"]
    assert w.effect == "lower" and w.delta == pytest.approx(-0.10)
    assert w.delta_ci == pytest.approx((-0.10, -0.10))        # paired: the shared noise cancels exactly
    assert t["same"].effect == "no effect" and t["same"].delta_ci[1] < 0
    assert t["noisy"].effect == "no effect" and t["noisy"].delta_ci[0] < 0 < t["noisy"].delta_ci[1]
    assert t["better"].effect == "higher" and t["better"].seeds == [0.60]
    assert t["missing"].effect == "not measured" and np.isnan(t["missing"].ap50) and np.isnan(t["missing"].cpu_s)
    md = ablations.markdown(list(t.values()), {"worse": "a knob off"})
    assert "| `worse` | a knob off | 0.420 [" in md and "| -0.100 [-0.100, -0.100] | lower | nan |" in md
    assert md.count("\n") == 2 + 6
    assert ablations.figure(ablations.table(rows, {}, ["base", "worse"], [0, 1]), str(tmp_path / "a.png")) is None
    assert not os.path.exists(tmp_path / "a.png")               # no render cost: no point to draw
    costs.update({"ablation_worse_s0": {"frames": 5, "cpu_s": 50.0}})
    png = ablations.figure(ablations.table(rows, costs, ["base", "worse"], [0, 1]), str(tmp_path / "a.png"))
    from PIL import Image

    with Image.open(png) as im:
        assert im.size == (768, 528)
