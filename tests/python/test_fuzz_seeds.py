"""The seeds of the C++ fuzz targets (fuzz/corpus/<target>/seed-*) are valid inputs, so the
fuzzers start from files that reach deep into the loaders (a scene seed whose sidecar name
did not match what the target writes kept fuzz_scene_xml at the first check)."""
import os
from pathlib import Path

import numpy as np
import pytest

import synthgen as sg

CORPUS = Path(__file__).resolve().parents[2] / "fuzz" / "corpus"


def test_scene_xml_seed_loads(tmp_path):
    data = (CORPUS / "fuzz_scene_xml" / "seed-scene").read_bytes()
    xml, binary = data.split(b"\0BIN\0", 1)
    (tmp_path / "scene.xml").write_bytes(xml)  # the names fuzz_scene_xml.cpp writes
    (tmp_path / "scene.xml.bin").write_bytes(binary)
    s = sg.Scene.load(str(tmp_path / "scene.xml"))
    assert s.instance_count() == 2


@pytest.mark.parametrize("name", sorted(p.name for p in (CORPUS / "fuzz_mesh_import").glob("seed-*")))
def test_mesh_seeds_load(tmp_path, name):
    data = (CORPUS / "fuzz_mesh_import" / name).read_bytes()
    ext = ["obj", "ply", "gltf", "glb"][data[0] % 4]  # the first byte picks the format
    path = tmp_path / f"model.{ext}"
    path.write_bytes(data[1:])
    r = sg.Scene().load_mesh_file(str(path))
    assert r["mesh_id"] >= 0


@pytest.mark.parametrize("name", sorted(p.name for p in (CORPUS / "fuzz_image").glob("seed-*")))
def test_image_seeds_load(tmp_path, name):
    data = (CORPUS / "fuzz_image" / name).read_bytes()
    ext = ["png", "jpg", "exr", "hdr", "tga", "bmp"][(data[0] & 0x7F) % 6]
    path = tmp_path / f"image.{ext}"
    path.write_bytes(data[1:])
    assert sg.read_image(str(path)).size > 0


def test_journal_seed_with_an_embedded_file_replays(tmp_path, monkeypatch):
    """seed-resource: a journal whose environment map ("sky.exr", a relative path that exists
    nowhere) is embedded in its sidecar, so that fuzz_journal reaches resolve_resources."""
    monkeypatch.setenv("SYNTHGEN_CACHE", str(tmp_path / "cache"))
    data = (CORPUS / "fuzz_journal" / "seed-resource").read_bytes()
    xml, binary = data.split(b"\0BIN\0", 1)
    (tmp_path / "journal.xml").write_bytes(xml)  # the names fuzz_journal.cpp writes
    (tmp_path / "journal.xml.bin").write_bytes(binary)
    assert not os.path.exists("sky.exr")
    s = sg.Scene.replay(str(tmp_path / "journal.xml"))
    assert np.asarray(s.render(spp=1, seed=1).rgb).max() > 0
