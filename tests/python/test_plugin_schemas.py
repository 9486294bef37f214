"""Plugin parameters are declared once, in C++: the scene-file schema, the scenario schema,
the bindings and the command line take them from the registry (synthgen.plugin_info), and
agree with it key for key."""
import inspect
import math

import pytest

import synthgen
from synthgen import cli
from synthgen.scenario import schema as scenario_schema
from synthgen.schema import fields as F
from synthgen.schema.plugins import InlineTexture, _short
from synthgen.schema.random import Random
from synthgen.scene import scene_file

KINDS = {"material": scene_file.MATERIAL, "texture": scene_file.TEXTURE, "light": scene_file.LIGHT}


def _default(p):
    """The declared default as the schemas hold it: float32 values as their shortest decimal
    (0.8f is 0.8, not 0.800000011920929; the renderer gets the same float32)."""
    if p["required"] or not p["has_default"]:
        return None
    d = p["default"]
    return tuple(_short(float(x)) for x in d) if isinstance(d, list) else _short(d)


def _field_default(f):
    d = f.default
    return None if d is F.REQUIRED else d


def _range_of(f):
    """(min, max, min_open, max_open) of a numeric field, of a vector's elements, of a colour."""
    if isinstance(f, InlineTexture):
        f = f.constant
    if isinstance(f, Random):
        f = f.inner
    for attr in ("element", "color", "number"):
        if hasattr(f, attr):
            f = getattr(f, attr)
            if isinstance(f, F.Vector):
                f = f.element
    if isinstance(f, F.Number):
        return f.min, f.max, f.min_open, f.max_open
    return None


def _check_variant(kind, name, rec, scenario):
    info = synthgen.plugin_info(kind, name)
    # In scenarios texture parameters are inline textures (or their constant form); materials
    # (mix) have no form.
    declared = [p for p in info["params"] if not (scenario and p["type"] == "material")]
    assert list(rec.fields) == [p["name"] for p in declared], (kind, name)
    for p in declared:
        f = rec.fields[p["name"]]
        if scenario:
            assert isinstance(f, (Random, InlineTexture)), (kind, name, p["name"], "every scenario leaf may be a "
                                                                                   "distribution")
            assert isinstance(f, InlineTexture) == (p["type"] in ("texture", "float_texture", "color_texture"))
            if isinstance(f, InlineTexture):
                if f.constant is None:
                    assert p["type"] == "texture" and f.default is None
                    continue
                f = f.constant
        inner = f.inner if isinstance(f, Random) else f
        assert _field_default(inner) == _default(p), (kind, name, p["name"])
        if isinstance(inner, F.Choice):
            assert inner.choices == p["choices"], (kind, name, p["name"])
        r = _range_of(f)
        if p["min"] is not None or p["max"] is not None:
            assert r is not None, (kind, name, p["name"])
            assert (r[0], r[1]) == (p["min"], p["max"]), (kind, name, p["name"], r)
            if isinstance(inner, (F.Number, F.Vector)):
                assert (r[2], r[3]) == (p["min_open"], p["max_open"]), (kind, name, p["name"])
        for a in p["aliases"]:
            assert rec.aliases[a] == p["name"]
    assert [tuple(map(list, e)) for e in rec.exclusive] == [tuple(e) for e in info["exclusive"]
                                                          if all(k in rec.fields for g in e for k in g)]


@pytest.mark.parametrize("kind", sorted(KINDS))
def test_scene_file_records_are_the_declarations(kind):
    rec = KINDS[kind]
    assert rec.fields["type"].choices == synthgen.plugin_names(kind)
    assert sorted(rec.variants) == synthgen.plugin_names(kind)
    for name, v in rec.variants.items():
        _check_variant(kind, name, v, scenario=False)


@pytest.mark.parametrize("kind, rec", [("material", scenario_schema.MATERIAL), ("light", scenario_schema.LIGHT)])
def test_scenario_records_are_the_declarations_with_distributions(kind, rec):
    # Every plugin but those that need a reference to another object (mix).
    usable = [n for n in synthgen.plugin_names(kind)
              if not any(p["required"] and p["type"] == "material"
                         for p in synthgen.plugin_info(kind, n)["params"])]
    assert sorted(rec.variants) == usable
    for name, v in rec.variants.items():
        fields = {k: f for k, f in v.fields.items() if k != "asset"}  # the envmap's scenario extension
        _check_variant(kind, name, F.Record(fields, exclusive=v.exclusive, aliases=v.aliases), scenario=True)


def test_camera_and_render_settings_are_the_declarations():
    _check_variant("camera", "pinhole", F.Record({k: f for k, f in scene_file.CAMERA.fields.items() if k != "look_at"},
                                                 exclusive=scene_file.CAMERA.exclusive), scenario=False)
    _check_variant("render", "path_tracer", scene_file.RENDER, scenario=False)
    cam = scenario_schema.CAMERA
    for k in ("fov_y", "fx", "fy", "cx", "cy"):
        p = next(p for p in synthgen.plugin_info("camera", "pinhole")["params"] if p["name"] == k)
        assert _field_default(cam.fields[k].inner) == _default(p)


def test_one_default_per_render_setting():
    """C++ (RenderSettings from its declaration), the bindings (Scene.render's keyword
    defaults), scene files, scenarios and the command line's help agree."""
    declared = {p["name"]: p["default"] for p in synthgen.plugin_info("render", "path_tracer")["params"]}
    sig = synthgen.Scene.render.__doc__.splitlines()[0]
    for k, v in declared.items():
        assert f"{k}: {type(v).__name__} = {v}" in sig, (k, sig)
    assert scene_file.validate_render_settings({}) == declared
    rs = scenario_schema.RENDER.validate({}, F.Loc(), F.ValidationContext())
    # Scenarios add host policy the path tracer does not see (levels of detail of models).
    host = {"geometry_lod": 0.5, "geometry_lod_iou": 0.98}
    assert dict(rs) == dict({k: declared[k] for k in scenario_schema.RENDER_KEYS}, **host)
    assert not set(host) & set(declared)
    help_text = cli.build_parser()._subparsers._group_actions[0].choices["render"].format_help()
    assert f"else {declared['spp']})" in " ".join(help_text.split())


def test_no_plugin_vocabulary_is_written_in_python():
    """The records of scene files and scenarios are generated: a plugin parameter added in
    C++ appears in both without touching Python."""
    import synthgen.schema.plugins as gen

    for rec in (scene_file.MATERIAL, scene_file.LIGHT, scene_file.TEXTURE, scenario_schema.MATERIAL):
        for name, v in rec.variants.items():
            assert v.doc == synthgen.plugin_info(rec.fields["type"].doc.split()[0], name)["doc"]
    src = inspect.getsource(scene_file) + inspect.getsource(scenario_schema)
    for word in ("turbidity", "clearcoat", "roughness_u", "angular_diameter"):
        assert word not in src, word
    assert gen.plugin_record  # the generator


def test_aliases_and_combinations_reach_yaml(tmp_path):
    from synthgen import SceneFileError

    base = {"camera": {"width": 8, "height": 8, "look_at": {"eye": [0, 0, -3], "target": [0, 0, 0]}},
            "objects": [{"primitive": "box", "class_id": 1, "material": "m"}]}
    bad = dict(base, materials={"m": {"type": "conductor", "metal": "gold", "eta": 1.0, "k": 1.0}})
    with pytest.raises(SceneFileError, match="'eta' cannot be combined with 'metal'"):
        synthgen.build_scene(bad)
    img = tmp_path / "t.exr"
    from synthgen.outputs.files import write_exr
    import numpy as np

    write_exr(str(img), np.full((2, 2, 3), 0.25, np.float32))
    for key in ("file", "filename"):
        ok = dict(base, textures={"t": {"type": "image", key: str(img)}},
                  materials={"m": {"type": "diffuse", "albedo": {"texture": "t"}}})
        synthgen.build_scene(ok)
    both = dict(base, textures={"t": {"type": "image", "file": str(img), "filename": str(img)}})
    with pytest.raises(SceneFileError, match="same key"):
        synthgen.build_scene(both)

