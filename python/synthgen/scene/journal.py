"""The change journal of a :class:`synthgen.Scene` (api/journal.h): every edit recorded as it
happens, so that a scene can be saved as it was at a failure and replayed elsewhere.

``scene.begin_journal()`` starts recording (the journal begins with the scene as it is);
``scene.save_journal(path)`` writes it (XML in the scene file's vocabulary, arrays and the
sources of the extensions the scene uses in ``path.bin``); :func:`replay` (``Scene.replay``)
applies it to a fresh scene, which renders bit-identically; ``synthgen replay JOURNAL``
re-renders it in a fresh process: what a user sends with a bug report. Files the journal
names (image textures, environment maps such as a photo frame's temporary dome, grid media) are
recorded by sha256: embedded when at most 1 MiB, else copied into ``$SYNTHGEN_CACHE/resources``
when it is written; a replay that finds neither them nor an unchanged file at the recorded path
raises naming the parameter, the path, the sha256 and where it looked (docs/extensions.md).
"""
from __future__ import annotations

import hashlib
import os
from typing import Any, Dict, Tuple

from .._core import Scene, SynthgenError
from . import extensions

__all__ = ["replay", "journal_extensions"]


def journal_extensions(path: str):
    """The extensions a journal needs: ``[{'source', 'sha256', 'text'}]`` (sources embedded)."""
    return list(Scene.journal_extensions(os.fspath(path)))


def replay(path: str, allow_extensions: bool = False) -> Tuple[Scene, Dict[str, Any]]:
    """A fresh scene with the journal ``path`` applied, and the keyword arguments of the last
    render it recorded (``{}`` when none). The extensions the journal embeds are compiled and
    loaded only with ``allow_extensions`` (extensions run with your rights)."""
    path = os.fspath(path)
    exts = journal_extensions(path)
    if exts and not allow_extensions:
        names = ", ".join(os.path.basename(e["source"]) for e in exts)
        raise SynthgenError(f"{path}: the journal needs the C extensions {names} (their sources are embedded); "
                            "extensions run with your rights: replay with --allow-extensions (or "
                            "allow_extensions=True)")
    for e in exts:
        text = bytes(e["text"])
        if hashlib.sha256(text).hexdigest() != e["sha256"]:
            raise SynthgenError(f"{path}: the embedded source of {e['source']} does not match its sha256")
        # The journal's copy, under the original file name (compile errors name it).
        d = os.path.join(extensions.cache_dir(), "journal", e["sha256"][:16])
        os.makedirs(d, exist_ok=True)
        copy = os.path.join(d, os.path.basename(e["source"]) or "extension.c")
        if not os.path.isfile(copy):
            with open(copy + ".tmp", "wb") as f:
                f.write(text)
            os.replace(copy + ".tmp", copy)
        extensions.load_extension(copy)
    scene, recorded = Scene._replay(path)
    settings = dict(recorded)
    if settings.get("seed", 0) < 0:
        settings["seed"] += 1 << 64  # a 64-bit unsigned seed, kept in a signed parameter
    return scene, settings


def _scene_replay(path: str, allow_extensions: bool = False) -> Scene:
    """A fresh scene with the journal ``path`` applied (see :mod:`synthgen.scene.journal`);
    it renders bit-identically to the scene that recorded it."""
    return replay(path, allow_extensions)[0]


Scene.replay = staticmethod(_scene_replay)  # type: ignore[attr-defined]
