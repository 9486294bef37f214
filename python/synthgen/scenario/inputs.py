"""Every input of a scenario, loaded once before anything renders.

:func:`check_inputs` reads each file a scenario names -- meshes (through the same importer
as the frames), images, environment maps, assets (fetched and checksummed) and the fonts of
generated signs and plates -- and creates every material and light whose parameters are
constants, so a broken file or an impossible combination of parameters is reported once, by
``FILE:LINE:COLUMN: key.path: reason``, instead of failing every frame of a run.

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

from .._core import Scene, SynthgenError
from ..schema import distributions as D
from ..schema.errors import Loc, SceneFileError, ValidationContext
from ..schema.fields import InputPath, Validated
from ..schema.plugins import given_params
from .load import Scenario

__all__ = ["check_inputs", "EVALUATION_TIMEOUT"]

#: Seconds an extension's first evaluation (a texture's creation) may take in the checks.
EVALUATION_TIMEOUT = 60.0


def _options(v: Any) -> List[Any]:
    return list(v.options) if isinstance(v, D.Choice) else [v]


def _constant(tree: Any) -> bool:
    return not D.has_distribution(tree)


class _Checker:
    def __init__(self, sc: Scenario):
        self.ctx = ValidationContext(sc.source, sc.base_dir)
        self.scene = Scene()
        self.seen: Dict[Tuple[str, str], None] = {}
        self.fonts = False
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

    def once(self, kind: str, path: str, loc: Loc, load: Callable[[], Any]) -> None:
        if (kind, path) in self.seen:
            return
        self.seen[(kind, path)] = None
        try:
            load()
        except (SynthgenError, OSError) as e:
            self.fail(loc, f"cannot use this {kind}", e)

    def mesh(self, path: str, loc: Loc) -> None:
        self.once("mesh", path, loc, lambda: self.scene.load_mesh_file(path))

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
        from ..frame.resources import realize  # (synthgen.frame imports this package)

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
        for o in objects:
            if o.get("mesh") is not None:
                self.mesh(str(o["mesh"]), o.locs["mesh"])
            if o.get("asset") is not None:
                self.asset(o["asset"], "mesh", o.locs["asset"])
            if o.get("material") is not None:
                self.plugin("material", o["material"], o.locs["material"])
            if o.get("sign") is not None or o.get("plate") is not None:
                self.fonts = True
            for d in o.get("decals") or []:
                if d.get("image") is not None:
                    self.image(str(d["image"]), d.locs["image"])
                else:
                    self.fonts = True

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


def check_inputs(sc: Scenario, timeout: Optional[float] = EVALUATION_TIMEOUT) -> Dict[str, int]:
    """Loads every input of ``sc`` once; SceneFileError at the YAML entry of the first
    that cannot be used. Returns counts of what was checked. A scenario with extensions is
    checked in a child process; ``timeout``: seconds each first evaluation of an extension may
    take there (None or 0: no limit)."""
    if sc.spec["extensions"]:
        return _check_isolated(sc, float(timeout or 0.0))
    return _check(sc)


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

        conn.send(("ok", _check(sc, note)))
    except SceneFileError as e:
        conn.send(("error", e.source, e.line, e.column, e.key_path, e.reason))
    except Exception as e:  # noqa: BLE001 -- reported by the parent
        conn.send(("error", None, None, None, "", f"{type(e).__name__}: {e}"))
    conn.close()


def _check_isolated(sc: Scenario, timeout: float) -> Dict[str, int]:
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


def _check(sc: Scenario, note: Optional[Callable[[Optional[Loc], str], None]] = None) -> Dict[str, int]:
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
    _check_weather(sc, spec, ps)
    if c.fonts:
        c.check_fonts(spec.locs.get("objects", spec.loc))
    kinds: Dict[str, int] = {}
    for kind, _ in c.seen:
        kinds[kind] = kinds.get(kind, 0) + 1
    return kinds


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
