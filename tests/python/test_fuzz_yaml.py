"""fuzz/fuzz_yaml.py: the YAML validation fuzzer replays its regression corpus cleanly, runs,
and tells a crash (a bug) from a refusal (a clear error naming the file)."""
import importlib.util
import os
from pathlib import Path

import pytest

import synthgen as sg

ROOT = Path(__file__).resolve().parents[2]


def _fuzz_yaml():
    spec = importlib.util.spec_from_file_location("fuzz_yaml", ROOT / "fuzz" / "fuzz_yaml.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_regression_corpus_replays_without_crashes(capsys):
    fy = _fuzz_yaml()
    assert fy.main(["--replay", str(ROOT / "fuzz" / "corpus" / "fuzz_yaml"), "--memory-mb", "0"]) == 0
    out = capsys.readouterr().out
    n = len([f for f in os.listdir(ROOT / "fuzz" / "corpus" / "fuzz_yaml") if not f.endswith(".txt")])
    assert f"replayed {n} input(s), 0 crash(es)" in out


def test_yaml_the_fuzzer_found_is_refused_with_location(tmp_path):
    """What the first fuzzing runs found, now errors naming file, line and column."""
    from synthgen.scenario import load_scenario
    from synthgen.schema import parse_yaml

    base = (ROOT / "scenarios" / "default.yaml").read_bytes()
    p = tmp_path / "s.yaml"
    p.write_bytes(b"seed: 1\ncount: 2 \xef\x28\n" + base)
    with pytest.raises(sg.SynthgenError, match=rf"^{p}:2:10: the scenario is not UTF-8 text \(byte 0xef at offset 17"):
        load_scenario(p)
    with pytest.raises(sg.SynthgenError, match=r"^x.yaml:2:4: invalid YAML: character U\+001D is not allowed"):
        parse_yaml("a: 1\nb: \x1d\n", "x.yaml")
    deep = "a: " + "[" * 65 + "]" * 65 + "\n"
    with pytest.raises(sg.SynthgenError, match=r"^x.yaml:1:\d+: the document nests more than 64 levels"):
        parse_yaml(deep, "x.yaml")
    assert parse_yaml("a: " + "[" * 63 + "]" * 63 + "\n", "x.yaml")["a"] is not None  # 64 levels with the top


def test_the_fuzzer_finds_what_it_should(tmp_path, monkeypatch):
    """A planted bug (an exception that is not a SynthgenError) and an error that does not
    name the file are crashes; a named refusal is not."""
    fy = _fuzz_yaml()
    target = fy.Target(timeout=5)
    try:
        target.run("scenario", b"count: [\n")  # refused with file:line: fine
        import synthgen.scenario as scn

        def planted(path):
            raise KeyError("bug")

        monkeypatch.setattr(scn, "load_scenario", planted)
        with pytest.raises(fy.Crash, match="exception"):
            target.run("scenario", b"count: 1\n")

        def unnamed(path):
            raise sg.SynthgenError("something is wrong")

        monkeypatch.setattr(scn, "load_scenario", unnamed)
        with pytest.raises(fy.Crash, match="unnamed-error"):
            target.run("scenario", b"count: 1\n")
    finally:
        target.close()


def test_a_short_fuzzing_run_is_clean(tmp_path, capsys):
    fy = _fuzz_yaml()
    rc = fy.main(["--seconds", "60", "--runs", "40", "--seed", "7", "--memory-mb", "0",
                  "--corpus", str(tmp_path / "corpus"), "--crashes", str(tmp_path / "crashes")])
    out = capsys.readouterr().out
    assert "fuzz_yaml: executions=40 crashes=0" in out, out
    assert rc == 0


@pytest.mark.parametrize("text, where, what", [
    ("a: !!float ior\n", "1:4", "cannot read float value 'ior'"),
    ("b:\n  !!int width: 640\n", "2:3", "cannot read int value 'width'"),
    ("c: !!bool maybe\n", "1:4", "cannot read bool value 'maybe'"),
    ("d: !!timestamp 2020-13-45\n", "1:4", "cannot read timestamp value"),
])
def test_tagged_values_that_cannot_be_read_are_located(text, where, what):
    """Found by fuzz_yaml: PyYAML's scalar constructors raised plain ValueError / KeyError."""
    from synthgen.schema import parse_yaml

    with pytest.raises(sg.SynthgenError, match=rf"^x.yaml:{where}: invalid YAML: {what}"):
        parse_yaml(text, "x.yaml")
