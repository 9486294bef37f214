"""Every input of a scenario, loaded once before anything renders.

:func:`check_inputs` reads each file a scenario names -- meshes (through the same importer
as the frames), images, environment maps, assets (fetched and checksummed) and the fonts of
generated signs and plates -- and creates every material and light whose parameters are
constants, so a broken file or an impossible combination of parameters is reported once, by
``FILE:LINE:COLUMN: key.path: reason``, instead of failing every frame of a run.

Every model an object entry can draw (each option of a ``choice`` of assets) is checked against
every randomizer applied to the entry, by the run's own test (``Randomizer.needs``): paint needs
a paint material, plates plate mounts, lamps lamps; a library entry's material roles must name
materials of its model.

A scenario with C extensions is checked in a child process (:func:`check_inputs`): creating a
texture evaluates the extension's code (its average over 512 points), and a crash there (a
segfault) would kill ``synthgen validate`` and every ``run``, a loop would hang them. A crash, or
an extension's first evaluation longer than ``timeout`` seconds, becomes a SceneFileError at the
entry that uses it, naming the extension's texture and file.
"""
from __future__ import annotations

import os
import signal
import time
from typing import Any, Callable, Dict, List, Optional, Tuple

import numpy as np

from .._core import Scene, SynthgenError
from ..schema import distributions as D
from ..schema.errors import Loc, SceneFileError, ValidationContext
from ..schema.fields import InputPath, Validated
from ..schema.plugins import given_params, realize
from .load import Scenario

__all__ = ["check_inputs", "EVALUATION_TIMEOUT"]

#: Seconds an extension's first evaluation (a texture's creation) may take in the checks.
EVALUATION_TIMEOUT = 60.0


def _options(v: Any) -> List[Any]:
    return list(v.options) if isinstance(v, D.Choice) else [v]


def _drawable(v: Any) -> List[Any]:
    """Every value ``v`` can take as far as choices go: the options of a choice (of choices),
    those of weight 0 left out; any other value is itself."""
    if isinstance(v, D.Choice):
        return [x for o, p in zip(v.options, v.p) if p > 0 for x in _drawable(o)]
    return [v]


def _least(v: Any) -> Optional[np.ndarray]:
    """The smallest value (per component) a number or vector can take, or None when a
    distribution has no lower bound above 0."""
    if isinstance(v, D.Choice):
        opts = [_least(o) for o in _drawable(v)]
        if not opts or any(o is None for o in opts):
            return None
        return np.min(np.broadcast_arrays(*opts), axis=0)
    if isinstance(v, D.Broadcast):
        return _least(v.inner)
    if isinstance(v, (D.Uniform, D.IntUniform, D.LogUniform)):
        return np.asarray(v.lo, np.float64)
    if isinstance(v, D.Normal):
        return None if v.lo is None else np.asarray(v.lo, np.float64)
    if isinstance(v, D.Distribution):
        return None
    return np.asarray(v, np.float64)


def _constant(tree: Any) -> bool:
    return not D.has_distribution(tree)


class _Checker:
    def __init__(self, sc: Scenario):
        self.ctx = ValidationContext(sc.source, sc.base_dir)
        self.scene = Scene()
        self.seen: Dict[Tuple[str, str], Any] = {}   # (kind, path) -> what loading it returned
        self.fonts = False
        self.asset_paths: Dict[str, str] = {}   # asset id -> its cached file
        #: Called as note(loc, what) before extension code runs, note(None, "") after (the
        #: isolated check reports it to the parent, which then knows whom to blame).
        self.note: Optional[Callable[[Optional[Loc], str], None]] = None
        self.extension_textures: Dict[str, str] = {}
        if sc.spec["extensions"]:
            from .._core import loaded_extension_libraries

            for lib in loaded_extension_libraries():  # a name loaded twice: the latest wins
                self.extension_textures.update({t: lib["source"] for t in lib["textures"]})

    def extensions_in(self, tree: Any) -> List[str]:
        """The extension textures ``tree`` creates: "texture 'NAME' of the extension FILE"."""
        found: List[str] = []

        def walk(v: Any) -> None:
            if isinstance(v, dict):
                t = v.get("type")
                if isinstance(t, str) and t in self.extension_textures:
                    found.append(f"texture '{t}' of the extension {self.extension_textures[t]}")
                for x in v.values():
                    walk(x)
            elif isinstance(v, (list, tuple)):
                for x in v:
                    walk(x)

        if self.extension_textures:
            walk(tree)
        return sorted(set(found))

    def fail(self, loc: Loc, what: str, e: Exception) -> None:
        raise SceneFileError(self.ctx.source, loc.line, loc.column, loc.path, f"{what}: {e}") from None

    def once(self, kind: str, path: str, loc: Loc, load: Callable[[], Any]) -> Any:
        if (kind, path) in self.seen:
            return self.seen[(kind, path)]
        self.seen[(kind, path)] = None
        try:
            self.seen[(kind, path)] = load()
        except (SynthgenError, OSError) as e:
            self.fail(loc, f"cannot use this {kind}", e)
        return self.seen[(kind, path)]

    def mesh(self, path: str, loc: Loc) -> Any:
        return self.once("mesh", path, loc, lambda: self.scene.load_mesh_file(path))

    def image(self, path: str, loc: Loc) -> None:
        self.once("image", path, loc, lambda: self.scene.add_texture("image", {"file": path}))

    def envmap(self, path: str, loc: Loc) -> None:
        self.once("environment map", path, loc, lambda: self.scene.add_light("envmap", {"file": path}))

    def asset(self, asset_id: Any, kind: str, loc: Loc) -> None:
        from ..scene import assets

        for a in _options(asset_id):
            if a is None:
                continue
            try:
                path = assets.resolve(a)
            except (SynthgenError, OSError) as e:
                self.fail(loc, f"cannot fetch asset '{a}'", e)
            self.asset_paths[a] = path
            (self.mesh if kind == "mesh" else self.envmap)(path, loc)

    def texture_files(self, tree: Any, loc: Loc) -> None:
        """Loads the image files of every inline texture in ``tree`` (any option of any
        distribution)."""
        from ..schema.plugins import TextureSpec

        if isinstance(tree, D.Choice):
            for o in tree.options:
                self.texture_files(o, loc)
        elif isinstance(tree, TextureSpec):
            rec = tree["texture"]
            rloc = getattr(rec, "loc", loc)
            for f in _options(rec.get("file")) if isinstance(rec, dict) else []:
                if isinstance(f, InputPath):
                    self.image(str(f), getattr(rec, "locs", {}).get("file", rloc))
            self.texture_files(dict(rec), rloc)
        elif isinstance(tree, dict):
            for k, v in tree.items():
                self.texture_files(v, getattr(tree, "locs", {}).get(k, loc))
        elif isinstance(tree, (list, tuple)):
            for v in tree:
                self.texture_files(v, loc)

    def plugin(self, kind: str, rec: Any, loc: Loc) -> None:
        """Creates a material or light whose parameters are all constants."""
        self.texture_files(rec, loc)
        for option in _options(rec):
            if not isinstance(option, Validated) or not _constant(option):
                continue
            ext = self.extensions_in(option)
            if ext and self.note is not None:
                self.note(option.loc, " and ".join(ext))
            self.create(kind, option, loc)
            if ext and self.note is not None:
                self.note(None, "")

    def create(self, kind: str, option: Validated, loc: Loc) -> None:
        """Creates a material or light (``option``: constant parameters) and its inline textures."""
        try:  # inline textures are created here: their errors are this plugin's
            params = realize(self.scene, given_params(option))
        except SynthgenError as e:
            self.fail(option.loc, f"this {kind} cannot be created", e)
        if kind == "light":
            if option.get("type") == "envmap":
                if option.get("file") is not None:
                    self.envmap(str(option["file"]), option.locs.get("file", loc))
                if option.get("asset") is not None:
                    self.asset(option["asset"], "hdr", option.locs.get("asset", loc))
                return
        try:
            if kind == "material":
                self.scene.add_material(str(option["type"]), params)
            else:
                self.scene.add_light(str(option["type"]), params)
        except SynthgenError as e:
            self.fail(option.loc, f"this {kind} cannot be created", e)

    def lights(self, lights: Any, loc: Loc) -> None:
        for setup in _options(lights):
            for i, li in enumerate(setup):
                self.plugin("light", li, li.loc if isinstance(li, Validated) else loc)
                if isinstance(li, Validated) and not _constant(li) and li.get("type") == "envmap":
                    for f in _options(li.get("file")):
                        if isinstance(f, InputPath):
                            self.envmap(str(f), li.locs.get("file", li.loc))
                    if li.get("asset") is not None:
                        self.asset(li["asset"], "hdr", li.locs.get("asset", li.loc))

    def objects(self, objects: List[Validated]) -> None:
        for i, o in enumerate(objects):
            if o.get("mesh") is not None:
                self.mesh(str(o["mesh"]), o.locs["mesh"])
            if o.get("asset") is not None:
                self.asset(o["asset"], "mesh", o.locs["asset"])
            self.model_parts(i, o)
            if o.get("material") is not None:
                self.plugin("material", o["material"], o.locs["material"])
            if o.get("sign") is not None or o.get("plate") is not None:
                self.fonts = True
            for d in o.get("decals") or []:
                if d.get("image") is not None:
                    self.image(str(d["image"]), d.locs["image"])
                else:
                    self.fonts = True

    def model_parts(self, i: int, o: Validated) -> None:
        """Each model entry ``o`` can draw against each randomizer applied to it, by the run's
        test (Randomizer.needs); an asset's material roles against its model's materials."""
        from ..randomize import ModelParts, randomizers
        from .schema import SHAPE_KEYS

        applied = [r for r in randomizers() if any(v is not None for v in _drawable(o.get(r.key)))]
        kind = next((k for k in SHAPE_KEYS if o.get(k) is not None), None)
        if kind is None:
            return
        loc = o.locs.get(kind, o.loc)
        replaced = any(v is not None for v in _drawable(o.get("material")))
        # (what, its parts, its parts were its own materials kept)
        models: List[Tuple[str, ModelParts, ModelParts]] = []
        if kind == "asset":
            from ..scene import assets
            from ..scene.vehicles import material_roles

            for a in _drawable(o["asset"]):
                if a is None:
                    continue
                entry = assets.entry(a)
                loaded = self.seen.get(("mesh", self.asset_paths.get(a, ""))) or {}
                try:
                    roles = material_roles(a, entry, loaded.get("material_names", []), loaded.get("material_ids", []))
                except SynthgenError as e:
                    raise SceneFileError(self.ctx.source, loc.line, loc.column, loc.path, str(e)) from None
                models.append((f"asset '{a}'", ModelParts.of_entry(entry, roles, replaced),
                               ModelParts.of_entry(entry, roles, False)))
        else:
            what = f"{kind} '{o[kind]}'" if kind in ("primitive", "mesh") else f"a {kind}"
            models.append((what, ModelParts(), ModelParts()))
        for what, parts, own in models:
            for r in applied:
                why = r.needs(parts)
                if why:
                    if not r.needs(own):
                        why = f"objects[{i}].material replaces the model's own materials, which {r.key} needs"
                    raise SceneFileError(self.ctx.source, loc.line, loc.column, loc.path,
                                         f"{what} cannot take objects[{i}].{r.key}: {why}")

    def footprints(self, objects: List[Validated]) -> List[Tuple[str, float, float]]:
        """(what, length, width in metres) of the smallest object of each entry that stands on the
        ground by itself (no rests_on, no pixel_height, a primitive, mesh or asset: not a sign or a
        plate on its post), from its smallest size and scale; entries whose size has no lower bound
        are left out."""
        from ..scene.vehicles import AXES as AXIS_VECTORS

        out = []
        for i, o in enumerate(objects):
            if o.get("rests_on") is not None or o.get("pixel_height") is not None:
                continue
            size, scale = _least(o["size"]), _least(o["scale"])
            if size is None or scale is None:
                continue
            size = np.broadcast_to(size, (3,)) * float(scale)
            if o.get("primitive") is not None:
                for p in _drawable(o["primitive"]):
                    dims = np.full(3, size[0]) if p == "sphere" else size
                    out.append((f"objects[{i}] (a {p})", float(dims[0]), float(dims[2])))
                continue
            paths: List[Tuple[str, str, float, Dict[str, Any]]] = []
            if o.get("mesh") is not None:
                paths.append((f"mesh '{o['mesh']}'", str(o["mesh"]), 1.0, {}))
            elif o.get("asset") is not None:
                from ..scene import assets

                for a in _drawable(o["asset"]):
                    if a is not None and a in self.asset_paths:
                        e = assets.entry(a)
                        paths.append((f"asset '{a}'", self.asset_paths[a], float(e.get("scale", 1.0)), e))
            for what, path, unit, entry in paths:
                loaded = self.seen.get(("mesh", path))
                if not loaded:
                    continue
                pos = np.asarray(self.scene.mesh_arrays(loaded["mesh_id"])["positions"], np.float64)
                ext = (pos.max(axis=0) - pos.min(axis=0)) * unit if len(pos) else np.zeros(3)
                fi = int(np.argmax(np.abs(AXIS_VECTORS[o.get("forward") or entry.get("forward", "+x")])))
                ui = int(np.argmax(np.abs(AXIS_VECTORS[o.get("up") or entry.get("up", "+y")])))
                out.append((f"objects[{i}] ({what})", float(ext[fi] * size[0]), float(ext[3 - fi - ui] * size[2])))
        return out

    def check_fonts(self, loc: Loc) -> None:
        from ..scene import raster

        for name in ("DejaVuSans-Bold", "DejaVuSans"):
            try:
                path = raster.font_path(name)
            except (SynthgenError, OSError) as e:
                self.fail(loc, "the fonts of generated signs and plates", e)
            if not os.path.isfile(path):
                self.fail(loc, "the fonts of generated signs and plates",
                          SynthgenError(f"{path} not found (Debian package fonts-dejavu-core)"))


def check_inputs(sc: Scenario, warnings: Optional[List[str]] = None,
                 timeout: Optional[float] = EVALUATION_TIMEOUT) -> Dict[str, int]:
    """Loads every input of ``sc`` once; SceneFileError at the YAML entry of the first
    that cannot be used. Returns counts of what was checked; ``warnings`` (a list) receives
    what is suspicious but would not fail (a photo's geometry). A scenario with extensions is
    checked in a child process; ``timeout``: seconds each first evaluation of an extension may
    take there (None or 0: no limit)."""
    if sc.spec["extensions"]:
        return _check_isolated(sc, float(timeout or 0.0), warnings)
    return _check(sc, warnings=warnings)


def _check_child(conn: Any, sc: Scenario) -> None:
    """The isolated check (a spawned process): sends ("note", line, column, key path, what)
    before extension code runs and ("note", None, ...) after, then ("ok", counts) or ("error",
    ...)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C: the parent kills this process
    from ..scene.extensions import load_extension

    try:
        for path in sc.spec["extensions"]:  # consented to when the scenario was loaded
            load_extension(path)

        def note(loc: Optional[Loc], what: str) -> None:
            conn.send(("note", None, None, "", "") if loc is None else ("note", loc.line, loc.column, loc.path, what))

        found: List[str] = []
        counts = _check(sc, note, found)
        conn.send(("ok", counts, found))
    except SceneFileError as e:
        conn.send(("error", e.source, e.line, e.column, e.key_path, e.reason))
    except Exception as e:  # noqa: BLE001 -- reported by the parent
        conn.send(("error", None, None, None, "", f"{type(e).__name__}: {e}"))
    conn.close()


def _check_isolated(sc: Scenario, timeout: float, warnings: Optional[List[str]] = None) -> Dict[str, int]:
    """:func:`_check` in a child process; its death, or an extension's evaluation longer than
    ``timeout`` seconds, becomes a SceneFileError at the entry whose extension code ran."""
    import multiprocessing as mp

    from ..scene.extensions import exit_description

    ctx = mp.get_context("spawn")  # NOTE: no fork of a process with render threads
    receive, send = ctx.Pipe(duplex=False)
    proc = ctx.Process(target=_check_child, args=(send, sc))
    note: Tuple[Any, ...] = (None, None, "", "")
    since = 0.0
    try:
        proc.start()
        send.close()
        while True:
            wait = max(0.0, since + timeout - time.monotonic()) if timeout and note[3] else None
            if not receive.poll(wait):
                proc.kill()
                proc.join()
                raise SceneFileError(sc.source, note[0], note[1], note[2],
                                     f"the {note[3]} did not finish its first evaluation (creating the texture: its "
                                     f"average over 512 points) within {timeout:g} s (a loop?); its process was "
                                     "killed")
            try:
                msg = receive.recv()
            except EOFError:
                proc.join()
                how = exit_description(proc.exitcode)
                if proc.exitcode is not None and proc.exitcode > 0:  # Python's own exit, its traceback on stderr
                    raise SynthgenError(f"{sc.source}: the process checking the scenario (it has extensions) ended"
                                        f"{how} before it reported, with the error printed above (a script needs "
                                        "multiprocessing's `if __name__ == \"__main__\":` guard: the process is "
                                        "spawned)") from None
                if not note[3]:
                    raise SynthgenError(f"{sc.source}: the check of the scenario's inputs crashed its process{how} "
                                        "outside any extension's code") from None
                raise SceneFileError(sc.source, note[0], note[1], note[2],
                                     f"the {note[3]} crashed its process{how} in its first evaluation (creating "
                                     "the texture: its average over 512 points); every frame would fail "
                                     "alike") from None
            if msg[0] == "note":
                note, since = msg[1:], time.monotonic()
                continue
            proc.join()
            if msg[0] == "ok":
                if warnings is not None:
                    warnings.extend(msg[2])
                return msg[1]
            if msg[1] is None:
                raise SynthgenError(f"{sc.source}: {msg[5]}")
            raise SceneFileError(*msg[1:])
    except BaseException:
        if proc.is_alive():
            proc.kill()
            proc.join()
        raise
    finally:
        receive.close()


def _check(sc: Scenario, note: Optional[Callable[[Optional[Loc], str], None]] = None,
           warnings: Optional[List[str]] = None) -> Dict[str, int]:
    c = _Checker(sc)
    c.note = note
    spec = sc.spec
    c.lights(spec["lights"], spec.locs.get("lights", spec.loc))
    ground = spec["ground"]
    if ground["enabled"]:
        c.plugin("material", ground["material"], ground.locs.get("material", ground.loc))
    c.objects(spec["objects"])
    ps = None
    if spec.get("background") is not None:
        from ..background.photoset import PhotoSet

        bg = spec["background"]
        loc = spec.locs.get("background", spec.loc)
        if spec["render"]["denoise"]:
            rl = spec["render"].locs.get("denoise", spec["render"].loc)
            raise SceneFileError(sc.source, rl.line, rl.column, rl.path,
                                 "not available with photo backgrounds yet: their composite is "
                                 "built from the differential buffers, which the denoiser does not filter")
        try:
            ps = PhotoSet(bg, sc.base_dir, sc.seed)
            ps.check_count(int(spec["count"]))
            c.seen.update({("photo", p): None for p in ps.paths[:ps.check(list(sc.class_names))]})
        except SceneFileError:
            raise
        except (SynthgenError, OSError) as e:
            c.fail(loc, "cannot use this photo", e)
        _check_photo_geometry(c, ps, bg, spec["objects"], warnings)
    _check_weather(sc, spec, ps)
    if c.fonts:
        c.check_fonts(spec.locs.get("objects", spec.loc))
    kinds: Dict[str, int] = {}
    for kind, _ in c.seen:
        kinds[kind] = kinds.get(kind, 0) + 1
    return kinds


def _check_photo_geometry(c: _Checker, photos: Any, bg: Validated, objects: List[Validated],
                          warnings: Optional[List[str]]) -> None:
    """Each photo's geometry against the background's distances and the entries' smallest
    footprints (synthgen.background.geometry): an error (nothing could be placed) is raised at
    its calibration file's key, warnings go to ``warnings``."""
    from ..background.geometry import geometry_findings

    feet = c.footprints(objects)
    seen: Dict[Any, Any] = {}  # photos of one size sharing a calibration have the same geometry: checked once
    for i, path in enumerate(photos.paths):
        setup = photos.setup(i)
        cal = setup.calibration
        key = (repr(cal.meta()), tuple(np.asarray(p, np.float64).tobytes() for p in setup.regions),
               tuple(sorted(setup.where.items())))
        if key in seen:
            continue
        seen[key] = None
        for f in geometry_findings(setup, float(bg["min_distance"]), float(bg["max_distance"]), feet):
            if f.error and f.line:
                raise SceneFileError(f.file, f.line, f.column, f.key, f"{f.message} (photo {os.path.basename(path)})")
            if f.error:
                raise SynthgenError(f"{f} (photo {os.path.basename(path)})")
            if warnings is not None:
                warnings.append(f"{f} (photo {os.path.basename(path)})")


def _check_weather(sc: Scenario, spec: Validated, photos: Any = None) -> None:
    """Each weather condition's demands on the scenario (and its photos), reported at its key."""
    from ..randomize import weather

    w = spec["weather"]
    for c in weather.conditions():
        if w.get(c.key) is None:
            continue
        wl = w.locs.get(c.key, w.loc)

        def fail(message: str, wl: Loc = wl) -> None:
            raise SceneFileError(sc.source, wl.line, wl.column, wl.path, message)

        c.check(w[c.key], spec, fail, photos)
