"""Regenerates the parts of the docs that come from the code.

    .venv/bin/python tools/gen_docs.py          # rewrite the generated blocks
    .venv/bin/python tools/gen_docs.py --check  # exit 1 (naming the stale blocks) if any differs

A generated block sits between ``<!-- BEGIN GENERATED: NAME -->`` and
``<!-- END GENERATED: NAME -->`` in a Markdown file:

- ``docs/scene_file.md`` ``scene-file-reference`` and ``docs/scenarios.md``
  ``scenario-reference``: every key of the two formats (``synthgen schema [--scenario]``),
  whose plugin parts come from the C++ declarations;
- ``docs/architecture.md`` ``plugins``: the table of every C++ plugin and its parameters;
  ``registries``: output kinds, object randomizers, post-processing steps and commands;
  ``python-layout``: the Python package, a line per module;
- ``README.md`` ``layout``: the layout of the repository.

tests/python/test_docs.py runs the check, so no generated text can drift from the code.
"""
from __future__ import annotations

import importlib
import pkgutil
import re
import sys
from pathlib import Path
from typing import Callable, Dict, List

import synthgen
from synthgen import cli, outputs, post, randomize
from synthgen.background.sidecar import CALIBRATION_SCHEMA
from synthgen.scenario import SCENARIO_SCHEMA
from synthgen.scenario.schema import format_scenario_schema
from synthgen.schema.plugins import plugin_info, plugin_names
from synthgen.schema.reference import format_schema
from synthgen.scene.scene_file import SCENE_SCHEMA

ROOT = Path(__file__).resolve().parents[1]

#: The C++ folders (one concern each) and what they hold. A test checks that this lists
#: exactly the folders of cpp/.
CPP_FOLDERS = {
    "core": "math (Vec3f, Frame, Transform), rng (counter-based sampler), sampling, noise, params, the "
            "plugin registry (`plugin.h`: parameters declared once) and `isolate.h` (untrusted files read in "
            "another process)",
    "geometry": "TriangleMesh (validation) and Accel -- the only files including Embree",
    "material": "the Material interface and one file per material plugin",
    "texture": "the Texture interface, one file per texture plugin; mip maps, the image cache",
    "light": "the Light interface, one file per light plugin; area lights (from emissive materials)",
    "camera": "PinholeCamera (OpenCV convention) and its plugin declaration (`pinhole.cpp`)",
    "medium": "the Medium interface and Henyey-Greenstein phase function, one file per medium plugin (fog, haze)",
    "integrator": "the committed render scene, interactions, ray cones, the path tracer, its paths through media "
                  "(`volume.h`) and its settings",
    "film": "radiance and label buffers, render statistics; the denoiser (`denoise.cpp`)",
    "io": "each third-party API in one file: OpenImageIO (a lazily loaded plugin), assimp",
    "ext": "user extensions: loading compiled C libraries (`dlopen`, the ABI of "
           "`python/synthgen/include/synthgen_ext.h`), their textures and shapes as run-time plugins",
    "api": "Scene, the integration API; its XML persistence (`scene_xml.cpp`, pugixml) and file import",
    "bindings": "the pybind11 module `synthgen._core`",
    "reader": "`synthgen-reader`, the executable that decodes one untrusted file (mesh, image) with time and "
              "memory limits",
}

#: Top-level folders of the repository besides cpp/ and python/.
OTHER_FOLDERS = {
    "scenarios/": "example scenarios and scene files, each described in `scenarios/README.md`",
    "tests/cpp, tests/python": "GoogleTest and pytest suites",
    "bench/": "scripts that print benchmark figures (never timed tests)",
    "docs/": "`architecture.md` (design, plugins, how to add things), `python_api.md`, `scene_file.md`, "
             "`scenarios.md`, `augmented_photos.md`, `wear.md`, `vehicles.md`, `quality.md`, `denoise.md`, "
             "`benchmarks.md`, `failure_modes.md`, `weather.md`, `texture_lod.md`, `geometry_lod.md`, `extensions.md` "
             "(C extensions, the change journal), `cluster.md` (runs on a Dask cluster), `evaluate.md` (scoring "
             "detectors on real photos)",
    "assets_manifest/": "which assets exist, where they come from, licences, checksums",
    "fuzz/": "libFuzzer targets of every loader, their seed and regression corpora (`corpus/`), the YAML "
             "mutation fuzzer (`fuzz_yaml.py`); `bench/fuzz.sh` runs them",
    "tools/": "generators of the docs (`gen_docs.py`, `gen_api_doc.py`), `dataset_hash.py`, `make_fuzz_seeds.py`",
}


def _first_sentence(doc: str) -> str:
    text = " ".join((doc or "").strip().split("\n\n")[0].split())
    text = re.sub(r":\w+:`", "`", text).replace("``", "`")  # reST roles and literals -> Markdown
    m = re.match(r"(.+?\.)(\s|$)", text)
    return (m.group(1) if m else text).replace("|", "\\|")


def _python_packages() -> List[str]:
    return sorted(m.name for m in pkgutil.iter_modules(synthgen.__path__) if m.ispkg)


def _fmt(v) -> str:
    if isinstance(v, bool):
        return str(v).lower()
    if isinstance(v, float):
        return f"{v:g}"
    if isinstance(v, list):
        if v and all(x == v[0] for x in v) and len(v) == 3:
            return _fmt(v[0])
        return "[" + ", ".join(_fmt(x) for x in v) + "]"
    return str(v)


def _range(p) -> str:
    lo, hi = p["min"], p["max"]
    if lo is None and hi is None:
        return ""
    if lo is not None and hi is not None:
        return f" {'(' if p['min_open'] else '['}{_fmt(lo)}, {_fmt(hi)}{')' if p['max_open'] else ']'}"
    if lo is not None:
        return f" {'>' if p['min_open'] else '>='} {_fmt(lo)}"
    return f" {'<' if p['max_open'] else '<='} {_fmt(hi)}"


def _param(p) -> str:
    if p["required"]:
        d = "required"
    elif p["has_default"]:
        d = _fmt(p["default"])
    else:
        d = p["default_doc"] or "optional"
    choices = f" {'/'.join(p['choices'])}" if p["choices"] else ""
    return f"`{p['name']}` {p['type']}{choices}{_range(p)} ({d})"


def plugins_table() -> str:
    rows = ["| kind | name | file | parameters (type, range, default) |", "|---|---|---|---|"]
    for kind in synthgen.plugin_kinds():
        for name in plugin_names(kind):
            i = plugin_info(kind, name)
            params = "; ".join(_param(p) for p in i["params"]) or "none"
            rows.append(f"| {kind} | `{name}` | `{i['file']}` | {i['doc'].replace('|', '/')} {params} |")
    return "\n".join(rows)


def registries_table() -> str:
    rows = ["| registry | entry | module | what |", "|---|---|---|---|"]
    for k in outputs.kinds(include_always=True):
        rows.append(f"| output kind | `{k.name}` | `{k.module}` | {k.doc} |")
    for r in randomize.randomizers():
        rows.append(f"| object randomizer | `{r.key}` | `{type(r).__module__}` | "
                    f"{_first_sentence(sys.modules[type(r).__module__].__doc__)} |")
    for s in post.steps():
        rows.append(f"| post-processing step | `{s.name}` | `{s.module}` | {s.doc} |")
    for c in cli.commands():
        rows.append(f"| command | `synthgen {c.name}` | `{c.module}` | {c.help} |")
    return "\n".join(rows)


def python_layout() -> str:
    rows = ["| module | what |", "|---|---|"]
    for pkg in _python_packages():
        mod = importlib.import_module(f"synthgen.{pkg}")
        rows.append(f"| **`synthgen.{pkg}`** | {_first_sentence(mod.__doc__)} |")
        for m in sorted(pkgutil.iter_modules(mod.__path__), key=lambda m: m.name):
            sub = importlib.import_module(f"synthgen.{pkg}.{m.name}")
            rows.append(f"| `{pkg}/{m.name}{'/' if m.ispkg else '.py'}` | {_first_sentence(sub.__doc__)} |")
    return "\n".join(rows)


def repo_layout() -> str:
    rows = ["| path | what |", "|---|---|"]
    for folder, what in CPP_FOLDERS.items():
        rows.append(f"| `cpp/{folder}/` | {what} |")
    for pkg in _python_packages():
        mod = importlib.import_module(f"synthgen.{pkg}")
        rows.append(f"| `python/synthgen/{pkg}/` | {_first_sentence(mod.__doc__)} |")
    for folder, what in OTHER_FOLDERS.items():
        rows.append(f"| `{folder}` | {what} |")
    return "\n".join(rows)


def _code(text: str) -> str:
    return "```\n" + text.rstrip() + "\n```"


#: file -> {block name: generator}
BLOCKS: Dict[str, Dict[str, Callable[[], str]]] = {
    "docs/scene_file.md": {"scene-file-reference": lambda: _code(format_schema(SCENE_SCHEMA))},
    "docs/scenarios.md": {"scenario-reference": lambda: _code(format_scenario_schema())},
    "docs/augmented_photos.md": {"calibration-reference": lambda: _code(format_schema(CALIBRATION_SCHEMA))},
    "docs/architecture.md": {"plugins": plugins_table, "registries": registries_table, "python-layout": python_layout},
    "README.md": {"layout": repo_layout},
}


def regenerate(text: str, blocks: Dict[str, Callable[[], str]], path: str) -> str:
    for name, make in blocks.items():
        begin, end = f"<!-- BEGIN GENERATED: {name} -->", f"<!-- END GENERATED: {name} -->"
        pattern = re.compile(re.escape(begin) + r".*?" + re.escape(end), re.S)
        if not pattern.search(text):
            raise SystemExit(f"{path}: no generated block '{name}'")
        body = make()
        text = pattern.sub(lambda m: begin + "\n" + body + "\n" + end, text)
    return text


def main(argv: List[str]) -> int:
    stale = []
    for rel, blocks in BLOCKS.items():
        path = ROOT / rel
        old = path.read_text()
        new = regenerate(old, blocks, rel)
        if new != old:
            stale.append(rel)
            if "--check" not in argv:
                path.write_text(new)
                print(f"wrote {rel}")
    if "--check" in argv and stale:
        print("stale generated docs (run tools/gen_docs.py): " + ", ".join(stale), file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
