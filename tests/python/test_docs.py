"""Documentation generated from code stays in sync with it."""
import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def _run(tool: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, str(ROOT / "tools" / tool), "--check"], capture_output=True, text=True)


def test_generated_docs_are_current():
    """The scene-file and scenario references, the plugin table, the registries and the
    layout tables of docs/architecture.md and README.md (tools/gen_docs.py)."""
    r = _run("gen_docs.py")
    assert r.returncode == 0, r.stderr


def test_python_api_reference_is_current():
    r = _run("gen_api_doc.py")
    assert r.returncode == 0, r.stderr


def test_layout_tables_cover_the_tree():
    sys.path.insert(0, str(ROOT / "tools"))
    try:
        import gen_docs
    finally:
        sys.path.pop(0)
    cpp = sorted(d for d in os.listdir(ROOT / "cpp") if (ROOT / "cpp" / d).is_dir())
    assert sorted(gen_docs.CPP_FOLDERS) == cpp, "describe every cpp/ folder in tools/gen_docs.py CPP_FOLDERS"
    readme = (ROOT / "README.md").read_text()
    arch = (ROOT / "docs" / "architecture.md").read_text()
    pkg = ROOT / "python" / "synthgen"
    for d in sorted(p.name for p in pkg.iterdir() if (p / "__init__.py").exists()):
        assert f"`python/synthgen/{d}/`" in readme, d
        for m in sorted(f.stem for f in (pkg / d).glob("*.py") if f.stem != "__init__"):
            assert f"`{d}/{m}.py`" in arch, f"{d}/{m}.py"
    # No Python module outside the subpackages but the package's own entry points.
    assert sorted(f.name for f in pkg.glob("*.py")) == ["__init__.py", "__main__.py"]


def test_readme_starts_with_the_two_setup_commands():
    lines = [l.strip() for l in (ROOT / "README.md").read_text().splitlines() if l.strip()]
    code = lines[lines.index("```sh") + 1:lines.index("```sh") + 3]
    assert code[0].startswith("make demo") and code[1].startswith("make test")


def test_no_python_source_file_is_too_long():
    """The package reads by stage: no module over ~600 lines."""
    long = {}
    for f in (ROOT / "python" / "synthgen").rglob("*.py"):
        n = len(f.read_text().splitlines())
        if n > 620:
            long[str(f.relative_to(ROOT))] = n
    assert not long, long
