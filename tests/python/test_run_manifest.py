"""A run never mixes datasets: rendering into a directory made by another run is refused,
naming what differs (run_manifest.json), and only complete frames (every file present,
metadata readable) count as done."""
import glob
import hashlib
import os
import shutil

import pytest

from synthgen import SynthgenError
from synthgen import run as runner
from synthgen.outputs.verify import verify_dataset
from synthgen.run.manifest import ManifestMismatch

HERE = os.path.dirname(os.path.abspath(__file__))
TINY = os.path.join(HERE, "scenarios", "tiny.yaml")


def variant(tmp_path, name, *replace, extra=""):
    with open(TINY) as f:
        text = f.read()
    for a, b in replace:
        assert a in text, a
        text = text.replace(a, b)
    path = tmp_path / name
    path.write_text(text + extra)
    return str(path)


def files(d):
    out = {}
    for p in sorted(glob.glob(os.path.join(d, "**", "*"), recursive=True)):
        if os.path.isfile(p) and os.path.basename(p) not in ("run_summary.json", "dataset.yaml"):
            out[os.path.relpath(p, d)] = hashlib.sha256(open(p, "rb").read()).hexdigest()
    return out


@pytest.fixture(scope="module")
def first_two(tmp_path_factory):
    d = tmp_path_factory.mktemp("m")
    out = str(d / "ds")
    runner.run(variant(d, "a.yaml"), out, count=2, progress=False)
    return d, out


@pytest.mark.parametrize("change, words", [
    ((("seed: 11", "seed: 12"),), ["seed: 11 -> 12"]),
    ((("  - class: ball", "  - class: bal"),), ["class_names", "ball"]),
    ((("outputs: [rgb, rgb_exr,", "outputs: [rgb,"),), ["outputs"]),
    ((("resolution: [64, 48]", "resolution: [64, 40]"),), ["resolution"]),
])
def test_resume_refuses_another_scenario(first_two, tmp_path, change, words):
    d, out = first_two
    work = str(tmp_path / "ds")
    shutil.copytree(out, work)
    before = files(work)
    with pytest.raises(ManifestMismatch) as e:
        runner.run(variant(tmp_path, "b.yaml", *change), work, count=4, resume=True, progress=False)
    for w in words:
        assert w in str(e.value), str(e.value)
    assert files(work) == before, "nothing was written"


def test_comments_and_the_frame_count_do_not_change_the_run(first_two, tmp_path):
    d, out = first_two
    work = str(tmp_path / "ds")
    shutil.copytree(out, work)
    s = runner.run(variant(tmp_path, "c.yaml", ("# A small", "# Still a small"), extra="# more frames later\n"),
                   work, count=3, resume=True, progress=False)
    assert s["skipped"] == 2 and s["rendered"] == 1 and not s["failures"]


def test_an_input_file_that_changed_is_named(tmp_path):
    from synthgen.outputs.files import write_exr
    import numpy as np

    img = str(tmp_path / "sticker.exr")
    write_exr(img, np.full((4, 4, 3), 0.5, np.float32))
    scen = variant(tmp_path, "d.yaml", ("    material: {choice:", f"    decals: [{{image: {img}}}]\n    material: {{choice:"))
    out = str(tmp_path / "ds")
    runner.run(scen, out, count=1, progress=False)
    write_exr(img, np.full((4, 4, 3), 0.7, np.float32))  # same name, other pixels
    with pytest.raises(ManifestMismatch, match="sticker.exr"):
        runner.run(scen, out, count=2, resume=True, progress=False)


def test_frames_without_a_manifest_are_refused(first_two, tmp_path):
    d, out = first_two
    work = str(tmp_path / "ds")
    shutil.copytree(out, work)
    os.unlink(os.path.join(work, "run_manifest.json"))
    with pytest.raises(ManifestMismatch, match="no run_manifest.json"):
        runner.run(variant(tmp_path, "a.yaml"), work, count=3, resume=True, progress=False)


def test_incomplete_frames_are_rendered_again_and_fail_verification(first_two, tmp_path):
    d, out = first_two
    reference = files(out)
    work = str(tmp_path / "ds")
    shutil.copytree(out, work)
    os.unlink(os.path.join(work, "images", "000001.png"))                     # a lost image
    with pytest.raises(SynthgenError, match=r"frame 1 is incomplete.*images/000001.png"):
        verify_dataset(work)
    with open(os.path.join(work, "meta", "000000.json"), "w") as f:          # a corrupt meta file
        f.write('{"frame": 0, "files": {')
    with pytest.raises(SynthgenError, match=r"meta/000000.json: unreadable frame metadata"):
        verify_dataset(work)
    s = runner.run(variant(tmp_path, "a.yaml"), work, count=2, resume=True, progress=False)
    assert s["rendered"] == 2 and s["skipped"] == 0
    reasons = {f["frame"]: f["reason"] for f in s["incomplete"]}
    assert "000000.json" in reasons[0] and "images/000001.png" in reasons[1]
    assert "rendered again" in s.text()
    assert files(work) == reference, "the repaired frames equal the originals"
    assert verify_dataset(work)["frames"] == 2
