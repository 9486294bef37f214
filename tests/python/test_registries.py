"""Every extension point is one file that registers itself: each registry lists every module
of its package (a file of that kind that does not register fails here), under the module's
own name, and nothing else. The C++ plugins: tests/cpp/test_registry.cpp."""
import importlib

from synthgen import cli, outputs, post, randomize


def _modules_of(entries, attr="module"):
    return {getattr(e, attr) for e in entries}


def test_output_formats_are_registered():
    mods = {f"synthgen.outputs.{m}" for m in outputs.format_modules()}
    kinds = outputs.kinds(include_always=True)
    assert _modules_of(kinds) == mods, "every outputs/ module but the infrastructure registers an output kind"
    names = [k.name for k in kinds]
    assert len(names) == len(set(names))
    # The scenario's `outputs:` vocabulary is the registry's.
    from synthgen.scenario.schema import SCENARIO_SCHEMA

    assert SCENARIO_SCHEMA.fields["outputs"].item.choices == outputs.kind_names()
    for k in kinds:
        assert k.name in importlib.import_module(k.module).__doc__, f"{k.module} documents kind {k.name}"


def test_randomizers_are_registered_and_shape_the_objects_schema():
    mods = {f"synthgen.randomize.{m}" for m in randomize.randomizer_modules()}
    rs = randomize.randomizers()
    assert {type(r).__module__ for r in rs} == mods
    for r in rs:
        assert type(r).__module__.rsplit(".", 1)[1] == r.key, "file name = randomizer key"
    from synthgen.scenario.schema import OBJECT, SHAPE_KEYS

    assert [k for k in OBJECT.fields if k in {r.key for r in rs}] == [r.key for r in rs]
    assert set(SHAPE_KEYS) >= {r.key for r in rs if r.shape}
    orders = [r.apply_order for r in rs]
    assert len(set(orders)) == len(orders), "apply orders are distinct (a defined order)"


def test_post_steps_are_registered():
    mods = {f"synthgen.post.{m}" for m in post.step_modules()}
    steps = post.steps()
    assert {s.module for s in steps} == mods
    for s in steps:
        assert s.module.rsplit(".", 1)[1] == s.name, "file name = step name"
    from synthgen.scenario.schema import POST_STEP

    assert POST_STEP.fields["type"].choices == [s.name for s in steps]


def test_commands_are_registered():
    mods = {f"synthgen.cli.{m}" for m in cli.command_modules()}
    cmds = cli.commands()
    assert {c.module for c in cmds} == mods
    for c in cmds:
        assert c.module.rsplit(".", 1)[1] == c.name, "file name = command name"
    parser = cli.build_parser()
    sub = next(a for a in parser._actions if a.dest == "command")
    assert list(sub.choices) == [c.name for c in cmds]
