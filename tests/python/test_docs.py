"""Documentation generated from code stays in sync with it."""
from pathlib import Path

from synthgen import scene_file

ROOT = Path(__file__).resolve().parents[2]


def test_scene_file_reference_matches_the_validator():
    doc = (ROOT / "docs" / "scene_file.md").read_text()
    block = doc.split("```\n", 2)[1].rsplit("```", 1)[0]
    assert block.strip() == scene_file.format_schema().strip(), (
        "docs/scene_file.md is stale: regenerate it from `synthgen schema`")


def test_scenario_reference_matches_the_validator():
    from synthgen.scenario import SCENARIO_SCHEMA

    doc = (ROOT / "docs" / "scenarios.md").read_text()
    block = doc.split("## Reference", 1)[1].split("```\n", 2)[1].rsplit("```", 1)[0]
    assert block.strip() == scene_file.format_schema(SCENARIO_SCHEMA).strip(), (
        "docs/scenarios.md is stale: regenerate its reference from `synthgen schema --scenario`")


def test_readme_starts_with_the_two_setup_commands():
    lines = [l.strip() for l in (ROOT / "README.md").read_text().splitlines() if l.strip()]
    code = lines[lines.index("```sh") + 1:lines.index("```sh") + 3]
    assert code[0].startswith("make demo") and code[1].startswith("make test")


def test_python_api_reference_is_current():
    import subprocess
    import sys

    r = subprocess.run([sys.executable, str(ROOT / "tools" / "gen_api_doc.py"), "--check"],
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
