"""User extensions: procedural textures and geometric primitives as small C functions
(docs/extensions.md), after Hydra Render's extension mechanism (Sanzharov 2023).

An extension is one C file written against ``synthgen_ext.h`` (:func:`header_dir`; ABI
version ``synthgen._core.EXTENSION_ABI_VERSION``). :func:`load_extension` compiles it with the
system C compiler (``cc``, or ``$SYNTHGEN_CC``: ``-O2 -shared -fPIC``) into a cache keyed by
the hash of the source, the header and the compiler (``$SYNTHGEN_CACHE/extensions``, default
``~/.cache/synthgen/extensions``), loads it (a new library first in a child process: a crash
or a loop in its own loading code becomes an ExtensionError), and registers its textures and
shapes as plugins by name: ``scene.add_texture("rust_mask", {...})``, ``scene.add_shape("torus", {...})``.
Arguments are a parameter block built per texture or shape: changing them never recompiles.

**Extensions run with your rights.** Compiling and running user code happens only when asked
for: a Python call (``scene.load_extension(path)`` or :func:`load_extension`), or a scene file or
scenario whose ``allow_extensions: true`` is matched by ``--allow-extensions`` on the command
line. A file from someone else never compiles code silently.
"""
from __future__ import annotations

import hashlib
import os
import shutil
import signal
import subprocess
import sys
import tempfile
from typing import Any, Dict, List, Optional

from .. import _core
from .._core import Scene, SynthgenError

__all__ = ["ExtensionError", "load_extension", "compile_extension", "header_dir", "compiler", "cache_dir",
           "loaded_extensions", "example", "exit_description", "NOT_ALLOWED"]

#: Flags of every compile (the cache key includes them).
_FLAGS = ["-O2", "-shared", "-fPIC", "-std=c11", "-fvisibility=hidden", "-Wall",
          "-Werror=implicit-function-declaration", "-Werror=return-type"]
#: Seconds a compile may take.
_TIMEOUT = 120.0
#: Seconds loading a new library in a child process may take (:func:`_probe`).
_PROBE_TIMEOUT = 60.0

NOT_ALLOWED = ("extensions run with your rights: compiling and running {what} needs 'allow_extensions: true' "
               "in the file and --allow-extensions on the command line")


class ExtensionError(SynthgenError):
    """An extension that does not compile or load (the message names the file and line)."""


def header_dir() -> str:
    """The directory holding ``synthgen_ext.h`` (installed with the package)."""
    return os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "include")


def example(name: str) -> str:
    """The path of an example extension installed with the package (``data/extensions``):
    ``rust`` (the rust preset's textures), ``shapes`` (an analytic sphere, an SDF rounded box
    and torus)."""
    path = os.path.join(os.path.dirname(os.path.dirname(os.path.abspath(__file__))), "data", "extensions",
                        f"{name}.c")
    if not os.path.isfile(path):
        raise ExtensionError(f"no example extension '{name}' (rust, shapes)")
    return path


_COMPILER: Dict[str, Any] = {}


def compiler() -> Dict[str, Any]:
    """The C compiler used: ``{'path', 'version'}`` (``$SYNTHGEN_CC`` or ``cc`` on PATH)."""
    name = os.environ.get("SYNTHGEN_CC", "cc")
    if name in _COMPILER:
        return _COMPILER[name]
    path = shutil.which(name)
    if path is None:
        raise ExtensionError(f"no C compiler '{name}' on PATH: extensions are compiled with it "
                             "(apt-get install gcc, or set SYNTHGEN_CC)")
    try:
        out = subprocess.run([path, "--version"], capture_output=True, text=True, timeout=30.0)
    except (OSError, subprocess.TimeoutExpired) as e:
        raise ExtensionError(f"the C compiler {path} does not run: {e}") from None
    version = (out.stdout or out.stderr).splitlines()[0] if (out.stdout or out.stderr) else "unknown"
    _COMPILER[name] = {"path": os.path.realpath(path), "version": version}
    return _COMPILER[name]


def cache_dir() -> str:
    """Where compiled extensions are kept (``$SYNTHGEN_CACHE/extensions``)."""
    root = os.environ.get("SYNTHGEN_CACHE", os.path.join(os.path.expanduser("~"), ".cache", "synthgen"))
    return os.path.join(root, "extensions")


def _read_source(path: str) -> bytes:
    if not os.path.isfile(path):
        raise ExtensionError(f"{path}: no such extension file")
    size = os.path.getsize(path)
    if size > 4 << 20:
        raise ExtensionError(f"{path}: {size} bytes: an extension source is at most 4 MiB")
    with open(path, "rb") as f:
        return f.read()


def compile_extension(path: str) -> Dict[str, Any]:
    """Compiles the extension ``path`` (or finds it in the cache): ``{'library', 'source',
    'sha256', 'cached'}`` (``sha256`` of the source). Raises :class:`ExtensionError` with the
    compiler's messages (``FILE:LINE:COLUMN: error: ...``) when it does not compile."""
    path = os.path.abspath(os.fspath(path))
    src = _read_source(path)
    cc = compiler()
    with open(os.path.join(header_dir(), "synthgen_ext.h"), "rb") as f:
        header = f.read()
    key = hashlib.sha256()
    for part in (src, header, cc["path"].encode(), cc["version"].encode(), " ".join(_FLAGS).encode()):
        key.update(hashlib.sha256(part).digest())
    digest = key.hexdigest()
    stem = "".join(c if c.isalnum() or c in "_-" else "_" for c in os.path.splitext(os.path.basename(path))[0])
    cache = cache_dir()
    lib = os.path.join(cache, f"{stem}-{digest[:24]}.so")
    info = {"library": lib, "source": path, "sha256": hashlib.sha256(src).hexdigest(), "cached": True}
    if os.path.isfile(lib):
        return info
    os.makedirs(cache, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{stem}-", suffix=".so", dir=cache)
    os.close(fd)
    cmd = [cc["path"], *_FLAGS, "-I", header_dir(), "-o", tmp, path, "-lm"]
    try:
        out = subprocess.run(cmd, capture_output=True, text=True, timeout=_TIMEOUT)
    except subprocess.TimeoutExpired:
        os.unlink(tmp)
        raise ExtensionError(f"{path}: compiling took more than {_TIMEOUT:.0f} s") from None
    if out.returncode != 0:
        os.unlink(tmp)
        msg = (out.stderr or out.stdout).strip()
        raise ExtensionError(f"{path}: the extension does not compile ({os.path.basename(cc['path'])} exit "
                             f"{out.returncode}):\n{msg}")
    # NOTE: the library appears under its final name only once complete (rename is atomic within
    # a file system), so concurrent workers compiling the same source never load a partial file.
    os.replace(tmp, lib)
    info["cached"] = False
    return info


def _probe(info: Dict[str, Any]) -> None:
    """Loads a library in a child process first, once per compiled library (a marker beside it
    then says it loaded): loading runs the extension's own code (``synthgen_extension()``, a
    library's constructors), and a crash or a loop there would take this process down. Raises
    ExtensionError naming the file for a crash or a load longer than ``_PROBE_TIMEOUT``; an
    error the loader reports (ABI version, declarations) is left to the load in this process."""
    lib = info["library"]
    marker = lib + ".loaded"
    if os.path.isfile(marker):
        return
    package_parent = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(p for p in [package_parent, os.environ.get("PYTHONPATH")] if p))
    code = "import sys; from synthgen import _core; _core.load_extension_library(sys.argv[1], sys.argv[2])"
    try:
        out = subprocess.run([sys.executable, "-c", code, lib, info["source"]], capture_output=True, text=True,
                             timeout=_PROBE_TIMEOUT, env=env, stdin=subprocess.DEVNULL)
    except subprocess.TimeoutExpired:  # (the child is killed)
        raise ExtensionError(f"{info['source']}: loading the extension took more than {_PROBE_TIMEOUT:g} s (its "
                             "synthgen_extension() or a constructor in a loop?); its process was killed") from None
    if out.returncode < 0:
        raise ExtensionError(f"{info['source']}: loading the extension crashed its process"
                             f"{exit_description(out.returncode)} (its synthgen_extension() or a constructor of the "
                             "library)")
    if out.returncode == 0:
        fd, tmp = tempfile.mkstemp(prefix=".loaded-", dir=os.path.dirname(lib))
        os.close(fd)
        os.replace(tmp, marker)


def load_extension(path: str, scene: Optional[Scene] = None) -> Dict[str, Any]:
    """Compiles (or finds cached) and loads the extension ``path``; registers its textures
    and shapes as plugins. Returns ``{'library', 'source', 'sha256', 'cached', 'textures',
    'shapes'}``. Calling this is the consent to run the file's code (see the module doc).
    ``scene``: the scene the extension is loaded for (recorded in its journal)."""
    info = compile_extension(path)
    _probe(info)
    try:
        loaded = _core.load_extension_library(info["library"], info["source"])
    except SynthgenError as e:
        raise ExtensionError(str(e)) from None
    info.update(textures=list(loaded["textures"]), shapes=list(loaded["shapes"]))
    from ..schema.plugins import refresh_runtime_plugins

    refresh_runtime_plugins()
    if scene is not None:
        scene.note_extension(info["source"], info["sha256"], _read_source(info["source"]))
    return info


def exit_description(exitcode: Optional[int]) -> str:
    """How a process that ran extension code ended, from its exit code (multiprocessing's:
    negative for a signal): " (killed by SIGSEGV)", " (exit code 3)" or ""."""
    if exitcode is not None and exitcode < 0:
        try:
            return f" (killed by {signal.Signals(-exitcode).name})"
        except ValueError:
            return f" (killed by signal {-exitcode})"
    return f" (exit code {exitcode})" if exitcode is not None else ""


def loaded_extensions() -> List[Dict[str, Any]]:
    """The extension libraries loaded in this process (``synthgen._core.loaded_extension_libraries``)."""
    return list(_core.loaded_extension_libraries())


def _scene_load_extension(self: Scene, path: str) -> Dict[str, Any]:
    """Compiles and loads a C extension (see :mod:`synthgen.scene.extensions`): its textures
    and shapes become plugins (``add_texture``, ``add_shape``). Extensions run with your rights."""
    return load_extension(path, scene=self)


Scene.load_extension = _scene_load_extension  # type: ignore[attr-defined]
