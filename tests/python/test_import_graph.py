"""The import graph of the Python code: no circles, and each stage imports only the stages
below it (docs/architecture.md, "Layout").

Every ``.py`` file under python/synthgen, bench/ and tools/ is parsed with ``ast`` (no module is
imported); every ``import`` and ``from ... import`` statement counts, those inside functions
(lazy imports) included. A statement is resolved to the files it runs:

* ``from P import name`` is the file of the module ``P.name`` when there is one, else the file
  of ``P`` (a package's ``__init__.py`` when the name is taken from it: ``from . import
  register``, ``from ..scenario import Scenario``); the native module ``synthgen._core`` is no
  file and below everything;
* ``import a.b.c`` is the file of ``a.b.c``;
* in a script of bench/ or tools/, a top-level name is the script of that name in the same
  folder (the scripts put their folder on ``sys.path``); names found nowhere (the standard
  library, numpy, tests/python helpers) are outside the graph.

Plugin registries that import their modules by computed name (``importlib.import_module`` in
``discover()``) are not statements and are not in the graph.
"""
from __future__ import annotations

import ast
import os
from collections import defaultdict
from typing import Dict, List, Optional, Set, Tuple

import pytest

REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))

#: The stages of the Python package, bottom to top (docs/architecture.md): a file imports only
#: files of its own stage or of stages before it. ``synthgen`` is the package's own
#: ``__init__.py`` and ``__main__.py`` (the public facade); ``scripts`` are bench/ and tools/.
LAYERS = ["schema", "scene", "background", "post", "outputs", "randomize", "scenario", "frame", "run",
          "evaluate", "bench", "cli", "synthgen", "scripts"]

#: Modules of the package that are not Python files (the native core): below every stage.
NATIVE = {"synthgen._core"}

Edge = Tuple[str, str]


def _imports(tree: ast.Module):
    """The import statements of a file, those in functions, classes and blocks included (imports
    are statements: expressions need no visit)."""
    stack: List[ast.AST] = list(tree.body)
    while stack:
        node = stack.pop()
        if isinstance(node, (ast.Import, ast.ImportFrom)):
            yield node
            continue
        for name in ("body", "orelse", "finalbody", "handlers", "cases"):
            block = getattr(node, name, None)
            if isinstance(block, list):
                stack.extend(block)


class Graph:
    """Files (paths relative to the root) and the imports between them, with the names taken."""

    def __init__(self, root: str, trees: Tuple[str, ...] = ("python/synthgen", "bench", "tools"),
                 package_root: str = "python"):
        self.root = root
        self.package_root = package_root
        self.files: List[str] = []
        for tree in trees:
            for d, dirs, fs in os.walk(os.path.join(root, tree)):
                dirs[:] = sorted(x for x in dirs if x != "__pycache__")
                self.files += [os.path.relpath(os.path.join(d, f), root).replace(os.sep, "/")
                               for f in sorted(fs) if f.endswith(".py")]
        self.modules: Dict[str, str] = {}
        for f in self.files:
            m = self.module_of(f)
            if m:
                self.modules[m] = f
        self.trees: Dict[str, ast.Module] = {}
        for f in self.files:
            with open(os.path.join(root, f), encoding="utf-8") as fh:
                self.trees[f] = ast.parse(fh.read(), f)
        self.edges: Dict[Edge, Set[str]] = defaultdict(set)
        #: Imports of the package (relative, or absolute ``synthgen...``) that name no file.
        self.unresolved: List[str] = []
        for f in self.files:
            self._scan(f)

    def module_of(self, f: str) -> Optional[str]:
        prefix = self.package_root + "/"
        if not f.startswith(prefix):
            return None
        parts = f[len(prefix):-3].split("/")
        return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)

    def _script_file(self, folder: str, module: str) -> Optional[str]:
        """The file of ``module`` (dotted) among the scripts of ``folder``: a script, or a
        module or package of a folder of scripts (bench/sim2real/)."""
        path = f"{folder}/{module.replace('.', '/')}"
        for cand in (path + ".py", path + "/__init__.py"):
            if cand in self.trees:
                return cand
        return None

    def _file(self, module: str, f: str) -> Optional[str]:
        if module in self.modules:
            return self.modules[module]
        if self.module_of(f) is None:  # a script: its folder's scripts (and their packages)
            found = self._script_file(os.path.dirname(f), module)
            if found is not None:
                return found
            script = f"{os.path.dirname(f)}/{module.split('.')[0]}.py"
            if script in self.trees:
                return script
        return None

    def _add(self, f: str, target: Optional[str], name: str, what: str, ours: bool) -> None:
        if target is not None:
            if target != f:
                self.edges[(f, target)].add(name)
        elif ours:
            self.unresolved.append(f"{f}:{what}")

    def _scan(self, f: str) -> None:
        me = self.module_of(f)
        package = None if me is None else (me if f.endswith("__init__.py") else me.rpartition(".")[0])
        top = "synthgen"
        for node in _imports(self.trees[f]):
            if isinstance(node, ast.Import):
                for a in node.names:
                    if a.name in NATIVE:
                        continue
                    ours = a.name.split(".")[0] == top
                    self._add(f, self._file(a.name, f), a.name, f"import {a.name}", ours)
            elif isinstance(node, ast.ImportFrom):
                if node.level and me is None:  # relative, in a package of scripts (bench/sim2real/)
                    folder = os.path.dirname(f)
                    for _ in range(node.level - 1):
                        folder = os.path.dirname(folder)
                    what = f"from {'.' * node.level}{node.module or ''} import"
                    for a in node.names:
                        sub = f"{node.module}.{a.name}" if node.module else a.name
                        target = self._script_file(folder, sub)
                        if target is None and node.module:
                            target = self._script_file(folder, node.module)
                        self._add(f, target, a.name, f"{what} {a.name}", True)
                    continue
                if node.level:
                    base = (package or "").split(".")
                    base = base[:len(base) - node.level + 1]
                    module = ".".join(base + ([node.module] if node.module else []))
                    ours = True
                else:
                    module = node.module or ""
                    ours = module.split(".")[0] == top
                what = f"from {'.' * node.level}{node.module or ''} import"
                for a in node.names:
                    sub = f"{module}.{a.name}"
                    if sub in self.modules:
                        self._add(f, self.modules[sub], a.name, f"{what} {a.name}", ours)
                        continue
                    if module in NATIVE or sub in NATIVE:
                        continue
                    if me is None and self._script_file(os.path.dirname(f), sub):  # a script package's module
                        self._add(f, self._script_file(os.path.dirname(f), sub), a.name, f"{what} {a.name}", ours)
                        continue
                    self._add(f, self._file(module, f), a.name, f"{what} {a.name}", ours)

    def cycles(self) -> List[List[str]]:
        """The strongly connected components of more than one file (Tarjan), each sorted."""
        adj: Dict[str, List[str]] = defaultdict(list)
        for a, b in sorted(self.edges):
            adj[a].append(b)
        index: Dict[str, int] = {}
        low: Dict[str, int] = {}
        stack: List[str] = []
        on: Set[str] = set()
        out: List[List[str]] = []

        def visit(v: str) -> None:
            index[v] = low[v] = len(index)
            stack.append(v)
            on.add(v)
            for w in adj[v]:
                if w not in index:
                    visit(w)
                    low[v] = min(low[v], low[w])
                elif w in on:
                    low[v] = min(low[v], index[w])
            if low[v] == index[v]:
                comp = []
                while True:
                    w = stack.pop()
                    on.discard(w)
                    comp.append(w)
                    if w == v:
                        break
                if len(comp) > 1:
                    out.append(sorted(comp))

        for v in self.files:
            if v not in index:
                visit(v)
        return out

    def circle(self, files: List[str]) -> List[str]:
        """A shortest circle through the first of ``files`` (a strongly connected component),
        as the files in import order, the first repeated at the end (breadth-first search)."""
        inside = set(files)
        start = files[0]
        parent: Dict[str, str] = {}
        queue = [start]
        for v in queue:
            for (a, b) in sorted(self.edges):
                if a != v or b not in inside:
                    continue
                if b == start:
                    path = [v]
                    while path[-1] != start:
                        path.append(parent[path[-1]])
                    return [start] + path[::-1][1:] + [start] if len(path) > 1 else [start, start]
                if b not in parent:
                    parent[b] = v
                    queue.append(b)
        return []

    def describe(self, files: List[str]) -> str:
        """A circle among ``files`` (each import with the names it takes), then every import
        among them: 'a -> b: names' lines."""
        path = self.circle(files)
        s = set(files)
        hops = [f"  {a} -> {b}: {', '.join(sorted(self.edges[(a, b)]))}" for a, b in zip(path, path[1:])]
        rest = [f"    {a} -> {b}: {', '.join(sorted(n))}" for (a, b), n in sorted(self.edges.items())
                if a in s and b in s]
        return "\n".join(hops + ["  (all imports among these files:)"] + rest)


def layer(f: str) -> str:
    if not f.startswith("python/synthgen/"):
        return "scripts"
    parts = f[len("python/synthgen/"):].split("/")
    return "synthgen" if len(parts) == 1 else parts[0]


def upward(graph: Graph) -> List[str]:
    """Imports of a stage above the importing file's (or of a stage LAYERS does not know)."""
    out = []
    for (a, b), names in sorted(graph.edges.items()):
        la, lb = layer(a), layer(b)
        if la == lb:
            continue
        if la not in LAYERS or lb not in LAYERS or LAYERS.index(lb) > LAYERS.index(la):
            out.append(f"  {a} ({la}) -> {b} ({lb}): {', '.join(sorted(names))}")
    return out


@pytest.fixture(scope="module")
def graph() -> Graph:
    return Graph(REPO)


def test_the_graph_sees_the_package(graph):
    """Every import of the package's own modules resolves to a file, so none is missed; and the
    graph holds the imports known to be there (a resolver that found nothing would pass the
    tests below)."""
    assert not graph.unresolved, "imports that name no file:\n" + "\n".join(graph.unresolved)
    assert len(graph.files) > 100
    task_frame = ("python/synthgen/run/task.py", "python/synthgen/frame/__init__.py")
    assert {"FrameRenderer"} <= graph.edges.get(task_frame, set())
    assert graph.edges.get(("python/synthgen/frame/renderer.py", "python/synthgen/randomize/__init__.py"), set())
    assert graph.edges.get(("bench/scaling.py", "bench/dataset_throughput.py"), set())
    assert graph.edges.get(("bench/sim2real/data.py", "bench/sim2real/road_regions.py"), set())   # from . import
    assert graph.edges.get(("bench/sim2real.py", "bench/sim2real/data.py"), set())   # the script and its package


def test_no_import_circles(graph):
    cycles = graph.cycles()
    assert not cycles, "import circles:\n" + "\n\n".join(graph.describe(c) for c in cycles)


def test_stages_import_only_stages_below(graph):
    assert {layer(f) for f in graph.files} <= set(LAYERS)
    bad = upward(graph)
    assert not bad, f"imports running back up (order {' < '.join(LAYERS)}):\n" + "\n".join(bad)


def test_the_checks_find_circles_and_upward_imports(tmp_path):
    """The checks themselves, on a small package: a circle through a package's __init__
    (``from . import x`` of a name it binds), a lazy import inside a function, a native
    module taken from the package (no file, no edge) and a script importing its neighbour."""
    files = {
        "python/synthgen/__init__.py": "from ._core import Scene\n",
        "python/synthgen/schema/__init__.py": "from .a import A\n",
        "python/synthgen/schema/a.py": "from . import helper\nA = 1\n",
        "python/synthgen/schema/helper.py": "from .. import _core\n",
        "python/synthgen/schema/b.py": "def f():\n    from ..scene.c import C\n",
        "python/synthgen/scene/__init__.py": "",
        "python/synthgen/scene/c.py": "from ..schema import A\nC = A\n",
        "bench/x.py": "import y\nimport numpy\n",
        "bench/y.py": "import synthgen\n",
    }
    for rel, text in files.items():
        os.makedirs(os.path.dirname(tmp_path / rel), exist_ok=True)
        (tmp_path / rel).write_text(text)
    g = Graph(str(tmp_path))
    assert not g.unresolved
    assert g.edges.get(("python/synthgen/schema/a.py", "python/synthgen/schema/helper.py"), set()) == {"helper"}
    assert ("python/synthgen/schema/helper.py", "python/synthgen/__init__.py") not in g.edges
    assert g.edges.get(("bench/x.py", "bench/y.py"), set()) == {"y"}
    assert g.edges.get(("bench/y.py", "python/synthgen/__init__.py"), set()) == {"synthgen"}
    assert g.cycles() == []
    up = upward(g)
    assert len(up) == 1 and "schema/b.py (schema) -> python/synthgen/scene/c.py (scene): C" in up[0]
    # A circle: the package's __init__ imports a module that takes a name from the __init__.
    (tmp_path / "python/synthgen/schema/a.py").write_text("from . import helper, B\nA = 1\n")
    (tmp_path / "python/synthgen/schema/__init__.py").write_text("from .a import A\nB = 2\n")
    g = Graph(str(tmp_path))
    assert g.cycles() == [["python/synthgen/schema/__init__.py", "python/synthgen/schema/a.py"]]
    assert g.circle(g.cycles()[0]) == ["python/synthgen/schema/__init__.py", "python/synthgen/schema/a.py",
                                       "python/synthgen/schema/__init__.py"]
    assert "schema/a.py -> python/synthgen/schema/__init__.py: B" in g.describe(g.cycles()[0])
