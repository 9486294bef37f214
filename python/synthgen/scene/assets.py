"""Asset manifest and cache: ``assets_manifest/*.yaml`` -> verified local files.

Each manifest entry has ``id``, ``kind`` (mesh, hdr, texture, photo, svg, image, data),
``licence``, ``sha256``, a ``source`` and optionally ``class`` (a class name for meshes),
``scale`` (factor to metres), ``description`` and ``companions`` (files that must sit next
to the main one, e.g. an OBJ's MTL, each with ``path`` and ``sha256``); vehicles also
``ride_height`` and ``wheels`` (built by :mod:`synthgen.scene.vehicles` for bodies that come
without them); ``lods`` lists coarser versions of a model (levels of detail, files of the same
source, each with ``path``, ``sha256`` and ``error``: the largest distance between its surface
and the main file's, in mesh units, :mod:`synthgen.scene.lod`), fetched with it; ``optional: true`` marks a large asset that tests use only when it is
already in the cache. Sources:

* ``{path: P}``: a local file (relative paths are relative to the repository root);
* ``{deb: PACKAGE, path: P}``: a file of a Debian package, taken from the installed system
  when present with the right checksum, else extracted with ``apt-get download`` +
  ``dpkg -x`` (no installation, no root needed);
* ``{url: U}``: downloaded with urllib;
* ``{npm: PACKAGE, path: P}``: a file of an npm package (``npm pack``).

:func:`fetch` copies assets into the cache (``$SYNTHGEN_CACHE`` or ``~/.cache/synthgen``),
``<cache>/<id>/<file name>``, verifying every checksum; :func:`resolve` returns the cached
path of one id, fetching it first if needed. Unknown ids raise with "did you mean".
"""
from __future__ import annotations

import difflib
import glob
import hashlib
import os
import shutil
import subprocess
import tempfile
import urllib.request
from typing import Any, Dict, Iterable, List, Optional

import yaml

from .._core import SynthgenError

__all__ = ["AssetError", "manifest_dir", "load_manifest", "cache_dir", "fetch", "resolve", "lods", "KINDS"]

KINDS = ("mesh", "hdr", "texture", "photo", "svg", "image", "data")
#: Axes a model may declare as its forward and up directions (``forward: "+z"``).
AXES = ("+x", "-x", "+y", "-y", "+z", "-z")
_REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", "..", ".."))


class AssetError(SynthgenError):
    """A manifest problem, an unknown asset id, or a failed fetch / checksum."""


def manifest_dir() -> str:
    """``$SYNTHGEN_MANIFEST`` or the repository's ``assets_manifest``."""
    return os.environ.get("SYNTHGEN_MANIFEST", os.path.join(_REPO, "assets_manifest"))


def cache_dir() -> str:
    return os.environ.get("SYNTHGEN_CACHE", os.path.join(os.path.expanduser("~"), ".cache", "synthgen"))


def file_sha256(path: str) -> str:
    """The sha256 of a file's content (hex), read in 1 MiB blocks."""
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def load_manifest(directory: Optional[str] = None) -> Dict[str, Dict[str, Any]]:
    """Every entry of ``directory/*.yaml`` by id, validated (required keys, kinds, unique ids)."""
    directory = directory or manifest_dir()
    out: Dict[str, Dict[str, Any]] = {}
    files = sorted(glob.glob(os.path.join(directory, "*.yaml")))
    if not files:
        raise AssetError(f"no manifest files (*.yaml) in {directory}")
    for path in files:
        with open(path, encoding="utf-8") as f:
            data = yaml.safe_load(f)
        if not isinstance(data, dict) or not isinstance(data.get("assets"), list):
            raise AssetError(f"{path}: expected a mapping with an 'assets' list")
        for i, e in enumerate(data["assets"]):
            where = f"{path}: assets[{i}]"
            if not isinstance(e, dict):
                raise AssetError(f"{where}: expected a mapping")
            allowed = {"id", "kind", "licence", "sha256", "source", "class", "scale", "description", "companions",
                       "forward", "up", "optional", "ride_height", "wheels", "plates", "lamps", "materials",
                       "lods"}
            for k in e:
                if k not in allowed:
                    m = difflib.get_close_matches(str(k), allowed, n=1)
                    raise AssetError(f"{where}: unknown key '{k}'" + (f" (did you mean '{m[0]}'?)" if m else ""))
            for k in ("id", "kind", "licence", "sha256", "source"):
                if k not in e:
                    raise AssetError(f"{where}: missing key '{k}'")
            if e["kind"] not in KINDS:
                raise AssetError(f"{where} ({e['id']}): kind '{e['kind']}' is not one of {', '.join(KINDS)}")
            src = e["source"]
            if not isinstance(src, dict) or not any(k in src for k in ("path", "deb", "url", "npm")):
                raise AssetError(f"{where} ({e['id']}): source needs one of path, deb, url, npm")
            if ("deb" in src or "npm" in src) and "path" not in src:
                raise AssetError(f"{where} ({e['id']}): a deb or npm source needs the 'path' inside the package")
            if not (isinstance(e["sha256"], str) and len(e["sha256"]) == 64):
                raise AssetError(f"{where} ({e['id']}): sha256 must be 64 hex digits")
            for k in ("forward", "up"):
                if k in e and e[k] not in AXES:
                    raise AssetError(f"{where} ({e['id']}): {k} must be one of {', '.join(AXES)}, got {e[k]!r}")
            if "forward" in e and "up" in e and e["forward"][1] == e["up"][1]:
                raise AssetError(f"{where} ({e['id']}): forward and up must be different axes")
            if "wheels" in e:
                _check_wheels(e["wheels"], f"{where} ({e['id']}): wheels")
            if "plates" in e:
                _check_plates(e["plates"], f"{where} ({e['id']}): plates")
            if "lamps" in e:
                _check_lamps(e["lamps"], f"{where} ({e['id']}): lamps")
            if "lods" in e:
                _check_lods(e["lods"], f"{where} ({e['id']}): lods")
            if "materials" in e:
                from .vehicle_parts import ROLES

                if not isinstance(e["materials"], dict) or not all(v in ROLES for v in e["materials"].values()):
                    raise AssetError(f"{where} ({e['id']}): materials: expected {{material name: role}}, the roles "
                                     f"being {', '.join(ROLES)}")
            if e["id"] in out:
                raise AssetError(f"{where}: duplicate id '{e['id']}'")
            out[e["id"]] = dict(e, manifest=path)
    return out


def _check_lods(lods: Any, where: str) -> None:
    if not isinstance(lods, list) or not lods:
        raise AssetError(f"{where}: expected a list of {{path, sha256, error}}")
    for i, lod in enumerate(lods):
        w = f"{where}[{i}]"
        if not isinstance(lod, dict) or set(lod) != {"path", "sha256", "error"}:
            raise AssetError(f"{w}: expected exactly the keys path, sha256, error")
        if not (isinstance(lod["sha256"], str) and len(lod["sha256"]) == 64):
            raise AssetError(f"{w}: sha256 must be 64 hex digits")
        err = lod["error"]
        if isinstance(err, bool) or not isinstance(err, (int, float)) or not err > 0 or err != err:
            raise AssetError(f"{w}: error must be a positive number (mesh units), got {err!r}")


def _check_wheels(w: Any, where: str) -> None:
    """A vehicle's wheels: axles (positions along forward, m), track (m, one or per axle), radius,
    width and optionally rim_radius (m), all positive but the axles."""
    if not isinstance(w, dict):
        raise AssetError(f"{where}: expected a mapping")
    for k in w:
        if k not in ("axles", "track", "radius", "width", "rim_radius"):
            m = difflib.get_close_matches(str(k), ["axles", "track", "radius", "width", "rim_radius"], n=1)
            raise AssetError(f"{where}: unknown key '{k}'" + (f" (did you mean '{m[0]}'?)" if m else ""))
    for k in ("axles", "track", "radius", "width"):
        if k not in w:
            raise AssetError(f"{where}: missing key '{k}'")
    axles = w["axles"]
    if not (isinstance(axles, list) and axles and all(isinstance(a, (int, float)) for a in axles)):
        raise AssetError(f"{where}.axles: expected a list of numbers (metres along forward)")
    track = w["track"] if isinstance(w["track"], list) else [w["track"]]
    if len(track) not in (1, len(axles)) or not all(isinstance(t, (int, float)) and t > 0 for t in track):
        raise AssetError(f"{where}.track: expected a positive number or one per axle")
    for k in ("radius", "width", "rim_radius"):
        if k in w and not (isinstance(w[k], (int, float)) and w[k] > 0):
            raise AssetError(f"{where}.{k}: expected a positive number (metres)")
    if w.get("rim_radius", 0) >= w["radius"]:
        raise AssetError(f"{where}.rim_radius: must be less than radius")


def _check_plates(p: Any, where: str) -> None:
    """A vehicle's plate mounts: front and / or rear, each {height (m, > 0), offset (m)}."""
    if not isinstance(p, dict) or not p:
        raise AssetError(f"{where}: expected a mapping with front and / or rear")
    for name, spec in p.items():
        if name not in ("front", "rear"):
            raise AssetError(f"{where}: unknown plate '{name}' (front or rear)")
        if not isinstance(spec, dict) or "height" not in spec:
            raise AssetError(f"{where}.{name}: expected {{height: metres above the ground, offset: metres}}")
        for k, v in spec.items():
            if k not in ("height", "offset"):
                raise AssetError(f"{where}.{name}: unknown key '{k}' (height, offset)")
            if not isinstance(v, (int, float)) or (k == "height" and v <= 0):
                raise AssetError(f"{where}.{name}.{k}: expected a number (metres{', > 0' if k == 'height' else ''})")


def _check_lamps(p: Any, where: str) -> None:
    """A vehicle's lamps: {kind: {height (m, > 0), offset (m, >= 0), size ([w, h] m, > 0)}}."""
    from .vehicle_parts import LAMP_KINDS

    if not isinstance(p, dict) or not p:
        raise AssetError(f"{where}: expected a mapping {{kind: {{height, offset, size}}}}")
    for kind, spec in p.items():
        if kind not in LAMP_KINDS:
            m = difflib.get_close_matches(str(kind), list(LAMP_KINDS), n=1)
            raise AssetError(f"{where}: unknown lamp '{kind}' ({', '.join(LAMP_KINDS)})"
                             + (f" (did you mean '{m[0]}'?)" if m else ""))
        if not isinstance(spec, dict) or "height" not in spec:
            raise AssetError(f"{where}.{kind}: expected {{height: metres above the ground, offset: metres from "
                             f"the centre line, size: [width, height] metres}}")
        for k, v in spec.items():
            if k not in ("height", "offset", "size"):
                raise AssetError(f"{where}.{kind}: unknown key '{k}' (height, offset, size)")
            if k == "size":
                if not (isinstance(v, list) and len(v) == 2 and all(isinstance(x, (int, float)) and x > 0 for x in v)):
                    raise AssetError(f"{where}.{kind}.size: expected [width, height], metres > 0")
            elif not isinstance(v, (int, float)) or v < 0 or (k == "height" and v == 0):
                raise AssetError(f"{where}.{kind}.{k}: expected a number (metres, {'> 0' if k == 'height' else '>= 0'})")


def _lookup(manifest: Dict[str, Dict[str, Any]], asset_id: str) -> Dict[str, Any]:
    if asset_id not in manifest:
        m = difflib.get_close_matches(asset_id, list(manifest), n=3, cutoff=0.5)
        hint = f" (did you mean {', '.join(repr(x) for x in m)}?)" if m else ""
        raise AssetError(f"unknown asset id '{asset_id}'{hint}; `synthgen assets list` shows them all")
    return manifest[asset_id]


def _local_path(p: str) -> str:
    return p if os.path.isabs(p) else os.path.normpath(os.path.join(_REPO, p))


def _deb_extract(package: str, workdir: str) -> str:
    """Extracts a Debian package (downloaded, not installed) into workdir/root."""
    try:
        subprocess.run(["apt-get", "download", package], cwd=workdir, check=True, capture_output=True, text=True)
    except FileNotFoundError as e:
        raise AssetError(f"apt-get is not available to download package '{package}'") from e
    except subprocess.CalledProcessError as e:
        raise AssetError(f"apt-get download {package} failed: {e.stderr.strip()}") from e
    debs = glob.glob(os.path.join(workdir, f"{package}_*.deb"))
    if not debs:
        raise AssetError(f"apt-get download {package} produced no .deb")
    root = os.path.join(workdir, "root")
    subprocess.run(["dpkg", "-x", debs[0], root], check=True, capture_output=True)
    return root


_DEB_ROOTS: Dict[str, Any] = {}


def _deb_root(package: str) -> str:
    """A package extracted once per process (several assets of one big package, e.g. the
    vehicles of torcs-data, 333 MB, are not downloaded once each); removed at exit."""
    if package not in _DEB_ROOTS:
        import atexit

        tmp = tempfile.TemporaryDirectory(prefix="synthgen-deb-")
        atexit.register(tmp.cleanup)
        _DEB_ROOTS[package] = (tmp, _deb_extract(package, tmp.name))
    return _DEB_ROOTS[package][1]


def _copy_verified(src: str, dst: str, sha: str, what: str) -> None:
    if not os.path.isfile(src):
        raise AssetError(f"{what}: source file not found: {src}")
    got = file_sha256(src)
    if got != sha:
        raise AssetError(f"{what}: checksum mismatch for {src}: expected {sha}, got {got}")
    os.makedirs(os.path.dirname(dst), exist_ok=True)
    tmp = dst + ".part"
    shutil.copyfile(src, tmp)
    os.replace(tmp, dst)


def _cached(entry: Dict[str, Any], cache: str) -> str:
    return os.path.join(cache, entry["id"], os.path.basename(entry["source"].get("path") or entry["source"]["url"]))


def _fetch_one(entry: Dict[str, Any], cache: str) -> str:
    dst = _cached(entry, cache)
    files = [(entry["source"].get("path"), dst, entry["sha256"])]
    for c in list(entry.get("companions") or []) + list(entry.get("lods") or []):
        rel = os.path.relpath(c["path"], os.path.dirname(entry["source"].get("path") or ""))
        files.append((c["path"], os.path.join(os.path.dirname(dst), rel), c["sha256"]))
    if all(os.path.isfile(d) and file_sha256(d) == s for _, d, s in files):
        return dst
    src = entry["source"]
    what = f"asset '{entry['id']}'"
    if "deb" in src:
        # Installed on this system with the right content: no download needed.
        if all(os.path.isfile(p) and file_sha256(p) == s for p, _, s in files):
            for p, d, s in files:
                _copy_verified(p, d, s, what)
            return dst
        root = _deb_root(src["deb"])
        for p, d, s in files:
            _copy_verified(os.path.join(root, p.lstrip("/")), d, s, what)
        return dst
    if "url" in src:
        with tempfile.TemporaryDirectory(prefix="synthgen-url-") as tmp:
            t = os.path.join(tmp, "download")
            try:
                urllib.request.urlretrieve(src["url"], t)
            except OSError as e:
                raise AssetError(f"{what}: download of {src['url']} failed: {e}") from e
            _copy_verified(t, dst, entry["sha256"], what)
        return dst
    if "npm" in src:
        with tempfile.TemporaryDirectory(prefix="synthgen-npm-") as tmp:
            try:
                r = subprocess.run(["npm", "pack", src["npm"]], cwd=tmp, check=True, capture_output=True, text=True)
            except FileNotFoundError as e:
                raise AssetError(f"{what}: npm is not installed (needed for package '{src['npm']}')") from e
            except subprocess.CalledProcessError as e:
                raise AssetError(f"{what}: npm pack {src['npm']} failed: {e.stderr.strip()}") from e
            tgz = os.path.join(tmp, r.stdout.strip().splitlines()[-1])
            shutil.unpack_archive(tgz, os.path.join(tmp, "x"))
            for p, d, s in files:
                _copy_verified(os.path.join(tmp, "x", "package", p), d, s, what)
        return dst
    for p, d, s in files:
        _copy_verified(_local_path(p), d, s, what)
    return dst


def fetch(ids: Optional[Iterable[str]] = None, manifest: Optional[Dict[str, Dict[str, Any]]] = None,
          cache: Optional[str] = None) -> Dict[str, str]:
    """Fetches ``ids`` (default: all) into the cache; returns {id: cached path}."""
    manifest = manifest if manifest is not None else load_manifest()
    cache = cache or cache_dir()
    wanted = list(ids) if ids else list(manifest)
    entries = [_lookup(manifest, i) for i in wanted]  # all ids checked before any download
    return {e["id"]: _fetch_one(e, cache) for e in entries}


def resolve(asset_id: str, manifest: Optional[Dict[str, Dict[str, Any]]] = None,
            cache: Optional[str] = None) -> str:
    """The cached path of one asset, fetched first when missing."""
    return fetch([asset_id], manifest, cache)[asset_id]


def lods(asset_id: str, manifest: Optional[Dict[str, Dict[str, Any]]] = None,
         cache: Optional[str] = None) -> List[Dict[str, Any]]:
    """The levels of detail of a model, finest first: ``{"path": cached file, "error": mesh
    units}``, the main file being level 0 (error 0); fetched with the model when missing."""
    e = entry(asset_id, manifest)
    main = resolve(asset_id, manifest, cache)
    base = os.path.dirname(e["source"].get("path") or "")
    out = [{"path": main, "error": 0.0}]
    for lod in e.get("lods") or []:
        out.append({"path": os.path.join(os.path.dirname(main), os.path.relpath(lod["path"], base)),
                    "error": float(lod["error"])})
    return out


def entry(asset_id: str, manifest: Optional[Dict[str, Dict[str, Any]]] = None) -> Dict[str, Any]:
    return _lookup(manifest if manifest is not None else load_manifest(), asset_id)


def list_assets(manifest: Optional[Dict[str, Dict[str, Any]]] = None) -> List[str]:
    m = manifest if manifest is not None else load_manifest()
    return [f"{i:40s} {e['kind']:6s} {e.get('class', ''):12s} {e['licence']}" for i, e in sorted(m.items())]
