"""The asset manifest (assets_manifest/*.yaml) and the cache (synthgen.scene.assets)."""
import hashlib
import os
import shutil
import subprocess
from pathlib import Path

import pytest
import yaml

from synthgen.scene import assets

ROOT = Path(__file__).resolve().parents[2]


def _sha(p) -> str:
    return hashlib.sha256(Path(p).read_bytes()).hexdigest()


def test_every_manifest_file_validates_and_ids_are_unique():
    m = assets.load_manifest()
    assert len(m) >= 40
    kinds = {e["kind"] for e in m.values()}
    assert {"hdr", "mesh", "photo", "svg"} <= kinds
    for e in m.values():
        assert e["licence"] and len(e["sha256"]) == 64
    # The real data named in ../shared/README.md is listed.
    for i in ("hdr/courtyard", "mesh/sumo-car-normal-citrus", "photo/dlib-mmod-cars-test-image", "svg/josm-stop"):
        assert i in m


def test_checksums_match_the_files_present_here():
    checked = 0
    for e in assets.load_manifest().values():
        p = e["source"].get("path")
        if p is None:
            continue
        local = p if os.path.isabs(p) else str(ROOT / p)
        if os.path.isfile(local):
            assert _sha(local) == e["sha256"], f"checksum mismatch: {local}"
            checked += 1
    assert checked >= 9, "too few manifest files present (blender-data missing?)"


def test_fetch_local_and_installed_deb_into_the_cache(tmp_path):
    cache = str(tmp_path / "cache")
    ids = ["test/kenney/vehicle-truck-red.glb", "hdr/courtyard"]
    if not (ROOT / "../shared/assets/kenney").exists():
        pytest.skip("../shared is absent")
    got = assets.fetch(ids, cache=cache)
    m = assets.load_manifest()
    for i in ids:
        assert got[i].startswith(cache) and _sha(got[i]) == m[i]["sha256"]
    # Idempotent: a second fetch verifies and keeps the files.
    assert assets.fetch(ids, cache=cache) == got


def test_companion_files_land_next_to_the_main_file(tmp_path):
    if not (ROOT / "../shared/assets/kenney").exists():
        pytest.skip("../shared is absent")
    p = assets.resolve("mesh/kenney-vehicle-truck-red", cache=str(tmp_path))
    assert os.path.isfile(os.path.join(os.path.dirname(p), "Textures", "colormap.png"))


def test_unknown_id_suggests_close_ones(tmp_path):
    with pytest.raises(assets.AssetError, match="did you mean 'hdr/courtyard'"):
        assets.fetch(["hdr/courtyrd"], cache=str(tmp_path))


def test_bad_checksum_and_bad_manifest_are_errors(tmp_path):
    f = tmp_path / "x.bin"
    f.write_bytes(b"hello")
    mdir = tmp_path / "manifest"
    mdir.mkdir()
    (mdir / "a.yaml").write_text(yaml.safe_dump({"assets": [
        {"id": "x", "kind": "data", "licence": "CC0-1.0", "sha256": "0" * 64, "source": {"path": str(f)}}]}))
    m = assets.load_manifest(str(mdir))
    with pytest.raises(assets.AssetError, match="checksum mismatch"):
        assets.fetch(["x"], manifest=m, cache=str(tmp_path / "c"))
    (mdir / "a.yaml").write_text(yaml.safe_dump({"assets": [
        {"id": "x", "kind": "data", "licence": "CC0-1.0", "sha265": "0" * 64, "source": {"path": str(f)}}]}))
    with pytest.raises(assets.AssetError, match="did you mean 'sha256'"):
        assets.load_manifest(str(mdir))


def test_fetch_from_a_debian_package_without_installing(tmp_path):
    # libdlib19.1 is not installed: the photo comes from `apt-get download` + `dpkg -x`.
    if shutil.which("apt-get") is None:
        pytest.skip("apt-get not available")
    probe = subprocess.run(["apt-get", "download", "--print-uris", "libdlib19.1"], capture_output=True, text=True)
    if probe.returncode != 0 or "http" not in probe.stdout:
        pytest.skip("no Debian package source reachable")
    p = assets.resolve("photo/dlib-mmod-cars-test-image", cache=str(tmp_path))
    assert _sha(p) == assets.entry("photo/dlib-mmod-cars-test-image")["sha256"]
