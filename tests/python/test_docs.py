"""Documentation generated from code stays in sync with it."""
import os
import re
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


def _tables(text: str):
    """Markdown tables as lists of rows (lists of cells), with the line of their header."""
    lines = text.split("\n")
    tables, i = [], 0
    while i < len(lines):
        if lines[i].startswith("|") and i + 1 < len(lines) and set(lines[i + 1].replace("|", "").strip()) <= set("-: "):
            start, rows = i, []
            while i < len(lines) and lines[i].startswith("|"):
                rows.append([c.strip() for c in re.split(r"(?<!\\)\|", lines[i].strip()[1:-1])])
                i += 1
            tables.append((start + 1, rows))
        else:
            i += 1
    return tables


def test_markdown_tables_are_whole():
    """No table is cut by a blank line (rows after it render as text), every row has the
    header's cells, and every example in scenarios/ is described in its README."""
    docs = [ROOT / "README.md", ROOT / "scenarios" / "README.md"] + sorted((ROOT / "docs").glob("*.md"))
    for path in docs:
        text = path.read_text()
        lines = text.split("\n")
        for i in range(1, len(lines) - 1):
            assert not (lines[i] == "" and lines[i - 1].startswith("|") and lines[i + 1].startswith("|")), \
                f"{path}:{i + 1}: a blank line cuts a table"
        for line, rows in _tables(text):
            header = rows[0]
            for r in rows[1:]:
                assert len(r) == len(header), f"{path}:{line}: row {r[:1]} has {len(r)} cells"
    readme = (ROOT / "scenarios" / "README.md").read_text()
    described = {r[0].strip("`") for _, rows in _tables(readme) for r in rows[2:]}
    examples = {p.name for p in (ROOT / "scenarios").glob("*.yaml")}
    assert examples <= described, f"not described in scenarios/README.md: {sorted(examples - described)}"


def test_generated_references_describe_every_key():
    """Every key of the scenario and scene-file references says what it is, and declared
    defaults read as declared (0.8, not float32's 0.800000011920929)."""
    for name in ("scenarios.md", "scene_file.md"):
        text = (ROOT / "docs" / name).read_text()
        block = text[text.index("<!-- BEGIN GENERATED"):text.index("<!-- END GENERATED")]
        lines = [ln for ln in block.split("\n") if re.match(r"^\s*[A-Za-z_]\w*: ", ln)]
        assert len(lines) > 100, name
        empty = [ln.strip() for ln in lines if ln.rstrip().endswith(" -") or " - " not in ln]
        assert not empty, f"{name}: keys without a description: {empty[:5]}"
        noisy = re.findall(r"\d\.\d{9,}", block)
        assert not noisy, f"{name}: float32 noise in defaults: {noisy[:3]}"


def test_readme_quick_start_runs_and_says_what_rgb_is(tmp_path, monkeypatch):
    """The README's Python quick start runs as written (at 4 spp), writes the files it names,
    and RenderResult.rgb is linear radiance: srgb8() is its sRGB encoding."""
    import numpy as np

    import synthgen as sg
    from synthgen.outputs.files import to_srgb8

    text = (ROOT / "README.md").read_text()
    code = text.split("## Quick start (Python)", 1)[1].split("```python", 1)[1].split("```", 1)[0]
    code = code.replace("spp=64", "spp=4")
    monkeypatch.chdir(tmp_path)
    env: dict = {}
    exec(compile(code, "README.md", "exec"), env)
    out = env["out"]
    assert (tmp_path / "sphere.png").exists() and (tmp_path / "sphere.exr").exists()
    assert out.rgb.dtype == np.float32 and "linear" in sg.RenderResult.rgb.__doc__
    assert np.array_equal(out.srgb8(), to_srgb8(out.rgb))
    back = sg.read_image(str(tmp_path / "sphere.png"))  # sRGB-decoded: the linear values again
    assert np.abs(back - np.clip(out.rgb, 0, 1)).max() < 0.01
