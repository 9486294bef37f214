"""Scene file loading: validation messages with file:line:column, key paths and
suggestions; building (transforms, camera, references, relative paths); the demo YAML;
the Cornell box scenario against the independent Ignis reference."""
from __future__ import annotations

import math
import textwrap
from pathlib import Path

import numpy as np
import OpenImageIO as oiio
import pytest
import yaml

import synthgen
from synthgen import schema as sf
from synthgen.scene import scene_file
from synthgen import SceneFileError, build_scene, load_scene

REPO = Path(__file__).resolve().parents[2]
SHARED = REPO.parent / "shared"
CBOX = SHARED / "assets" / "ignis-cbox"

CAMERA = "camera: {width: 32, height: 24, fov_y: 40, look_at: {eye: [0, 0, -5], target: [0, 0, 0]}}\n"


def write(tmp_path: Path, text: str, name: str = "scene.yaml") -> Path:
    p = tmp_path / name
    p.write_text(textwrap.dedent(text))
    return p


def error_of(path: Path) -> SceneFileError:
    with pytest.raises(SceneFileError) as info:
        load_scene(path)
    return info.value


# ---------------------------------------------------------------------------------------
# Error messages


def test_error_type_hierarchy():
    assert issubclass(SceneFileError, synthgen.SynthgenError)
    assert issubclass(SceneFileError, ValueError)
    assert synthgen.SceneFileError is SceneFileError


def test_misspelt_key_names_file_line_and_suggestion(tmp_path):
    p = write(tmp_path, CAMERA + textwrap.dedent("""\
        materials:
          red: {type: diffuse, albedo: [0.8, 0.1, 0.1]}
        objects:
          - primitive: sphere
            class_id: 1
            materal: red
        """))
    e = error_of(p)
    assert (e.line, e.column) == (7, 5)
    assert e.key_path == "objects[0].materal"
    msg = str(e)
    assert msg.startswith(f"{p}:7:5: objects[0].materal: unknown key 'materal'")
    assert "did you mean 'material'?" in msg
    assert "allowed keys:" in msg and "class_id" in msg


def test_misspelt_top_level_key(tmp_path):
    p = write(tmp_path, CAMERA + "objetcs:\n  - {primitive: box, class_id: 1}\n")
    e = error_of(p)
    assert e.line == 2 and e.key_path == "objetcs"
    assert "did you mean 'objects'?" in str(e)


def test_no_suggestion_for_unrelated_key(tmp_path):
    p = write(tmp_path, CAMERA + "objects:\n  - {primitive: box, class_id: 1, zzqx: 3}\n")
    e = error_of(p)
    assert "unknown key 'zzqx'" in str(e) and "did you mean" not in str(e)


def test_bad_value_type_names_key_path_and_range(tmp_path):
    p = write(tmp_path, CAMERA + "objects: [{primitive: box, class_id: 1}]\nrender:\n  spp: many\n")
    e = error_of(p)
    assert (e.line, e.key_path) == (4, "render.spp")
    assert "expected an integer in [1, 1048576], got 'many' (string)" in str(e)


def test_out_of_range_component_names_index_and_range(tmp_path):
    p = write(tmp_path, CAMERA + textwrap.dedent("""\
        materials:
          red: {type: diffuse, albedo: [0.8, 1.2, 0.1]}
        objects: [{primitive: box, class_id: 1, material: red}]
        """))
    e = error_of(p)
    assert e.line == 3 and e.key_path == "materials.red.albedo[1]"
    assert "value 1.2 is out of range; allowed: number in [0, 1]" in str(e)


@pytest.mark.parametrize("snippet, path, fragment", [
    ("objects: [{primitive: box, class_id: 70000}]", "objects[0].class_id", "[0, 65535]"),
    ("objects: [{primitive: box, class_id: 1, instance_id: 0}]", "objects[0].instance_id", "[1, 65535]"),
    ("objects: [{primitive: box, class_id: true}]", "objects[0].class_id", "got true (boolean)"),
    ("objects: [{primitive: sphere, radius: -1, class_id: 1}]", "objects[0].radius", "allowed: number > 0"),
    ("objects: [{primitive: box, class_id: 1, scale: [1, 0, 1]}]", "objects[0].scale[1]", "allowed: number > 0"),
    ("objects: [{primitive: box, class_id: 1, translate: [1, 2]}]", "objects[0].translate",
     "expected a list of 3 numbers, got a list of 2 items"),
    ("objects: [{primitive: box, class_id: 1}]\nlights: [{type: sun, angular_diameter: 90}]",
     "lights[0].angular_diameter", "in [0, 90)"),
    ("objects: [{primitive: box, class_id: 1}]\nrender: {seed: -1}", "render.seed", "integer in [0, "),
    ("objects: [{primitive: box, class_id: 1}]\nrender: {spp: .inf}", "render.spp", "expected an integer"),
    ("objects: []", "objects", "expected at least 1 item, got 0"),
])
def test_bad_values(tmp_path, snippet, path, fragment):
    e = error_of(write(tmp_path, CAMERA + snippet + "\n"))
    assert e.key_path == path
    assert fragment in str(e)
    assert e.line is not None and e.line >= 2


def test_unknown_choice_suggests_and_lists_values(tmp_path):
    e = error_of(write(tmp_path, CAMERA + "objects: [{primitive: spere, class_id: 1}]\n"))
    assert e.key_path == "objects[0].primitive" and e.line == 2
    assert "unknown value 'spere' (did you mean 'sphere'?); allowed values: sphere, box, cylinder, cone, plane, ground" in str(e)


def test_key_of_other_variant_is_explained(tmp_path):
    e = error_of(write(tmp_path, CAMERA + "objects: [{primitive: box, radius: 2, class_id: 1}]\n"))
    assert e.key_path == "objects[0].radius"
    assert "not allowed with primitive 'box' (only with sphere, cylinder, cone, ground)" in str(e)


def test_missing_required_key_points_at_the_entry(tmp_path):
    p = write(tmp_path, CAMERA + "objects:\n  - primitive: box\n    size: 2\n")
    e = error_of(p)
    assert (e.line, e.column) == (3, 5) and e.key_path == "objects[0]"
    assert "missing required key 'class_id'" in str(e)


def test_missing_light_type_lists_types(tmp_path):
    e = error_of(write(tmp_path, CAMERA + "objects: [{primitive: box, class_id: 1}]\nlights: [{irradiance: 3}]\n"))
    assert e.key_path == "lights[0]" and "missing required key 'type'" in str(e)
    assert "environment, envmap, headlamp, point, sky, spot, sun, twilight" in str(e)


def test_exclusive_and_one_of_groups(tmp_path):
    e = error_of(write(tmp_path, "camera: {width: 8, height: 8, fov_y: 40, fx: 5, fy: 5,\n"
                                 "  look_at: {eye: [0, 0, -5], target: [0, 0, 0]}}\n"
                                 "objects: [{primitive: box, class_id: 1}]\n"))
    assert e.key_path == "camera.fx" and "'fx' cannot be combined with 'fov_y'" in str(e)
    e = error_of(write(tmp_path, "camera: {width: 8, height: 8, fov_y: 40}\n"
                                 "objects: [{primitive: box, class_id: 1}]\n"))
    assert e.key_path == "camera" and "'look_at' or 'world_from_camera'" in str(e)
    e = error_of(write(tmp_path, CAMERA + "objects:\n  - {primitive: box, class_id: 1, translate: [0, 1, 0],\n"
                                          "     world_from_object: [[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]]}\n"))
    assert e.key_path == "objects[0].world_from_object" and e.line == 4
    assert "cannot be combined with 'translate'" in str(e)
    e = error_of(write(tmp_path, CAMERA + "objects: [{mesh: {file: x.obj}, primitive: box, class_id: 1}]\n"))
    assert "give exactly one of 'mesh' or 'primitive'" in str(e)


def test_matrix_checks(tmp_path):
    e = error_of(write(tmp_path, CAMERA + "objects:\n  - {primitive: box, class_id: 1,\n"
                                          "     world_from_object: [[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,1,1]]}\n"))
    assert e.key_path == "objects[0].world_from_object" and "last row must be [0, 0, 0, 1]" in str(e)
    e = error_of(write(tmp_path, CAMERA + "objects:\n  - {primitive: box, class_id: 1,\n"
                                          "     world_from_object: [[1,0,0,0],[0,0,0,0],[0,0,1,0],[0,0,0,1]]}\n"))
    assert "singular" in str(e)


def test_unknown_material_and_texture_names(tmp_path):
    e = error_of(write(tmp_path, CAMERA + "materials: {red: {type: diffuse}}\n"
                                          "objects: [{primitive: box, class_id: 1, material: rde}]\n"))
    assert e.key_path == "objects[0].material" and e.line == 3
    assert "unknown material 'rde' (did you mean 'red'?); materials defined: red" in str(e)
    e = error_of(write(tmp_path, CAMERA + "materials:\n  red: {type: diffuse, albedo: {texture: wod}}\n"
                                          "objects: [{primitive: box, class_id: 1, material: red}]\n"))
    assert e.key_path == "materials.red.albedo.texture" and e.line == 3
    assert "unknown texture 'wod'" in str(e)


def test_yaml_syntax_error_has_line(tmp_path):
    e = error_of(write(tmp_path, CAMERA + "objects: [{primitive: box, class_id: 1}\nlights: []\n"))
    assert e.line == 3 and "invalid YAML" in str(e)


def test_duplicate_key_is_an_error(tmp_path):
    e = error_of(write(tmp_path, CAMERA + "objects: [{primitive: box, class_id: 1}]\n"
                                          "objects: [{primitive: box, class_id: 2}]\n"))
    assert e.line == 3 and "duplicate key 'objects' (first defined on line 2)" in str(e)


def test_unsafe_tags_are_rejected(tmp_path):
    e = error_of(write(tmp_path, "camera: !!python/object/apply:os.system ['echo hacked']\n"))
    assert e.line == 1 and "could not determine a constructor" in str(e)


def test_empty_and_missing_files(tmp_path):
    e = error_of(write(tmp_path, "# nothing\n"))
    assert "empty" in str(e) and str(tmp_path) in str(e)
    e = error_of(tmp_path / "absent.yaml")
    assert "cannot read the scene file" in str(e) and "absent.yaml" in str(e)
    e = error_of(write(tmp_path, "- 1\n- 2\n"))
    assert "expected a mapping" in str(e) and e.line == 1


def test_missing_mesh_file_names_resolved_path(tmp_path):
    e = error_of(write(tmp_path, CAMERA + "objects:\n  - mesh: {file: meshes/nope.obj}\n    class_id: 1\n"))
    assert e.key_path == "objects[0].mesh.file" and e.line == 3
    assert str(tmp_path / "meshes" / "nope.obj") in str(e) and "relative paths are resolved against" in str(e)


def test_core_errors_are_relocated(tmp_path):
    (tmp_path / "bad.obj").write_text("v 1 2\nf 1 2 3\n")
    p = write(tmp_path, CAMERA + "objects:\n  - {primitive: box, class_id: 1}\n"
                                 "  - mesh: {file: bad.obj}\n    class_id: 2\n")
    e = error_of(p)
    assert (e.line, e.key_path) == (4, "objects[1].mesh")
    assert "bad.obj" in str(e)
    assert isinstance(e.__cause__, synthgen.FileError)

    p = write(tmp_path, CAMERA + "objects: [{primitive: box, class_id: 1}]\n"
                                 "lights:\n  - {type: point}\n  - {type: sun, direction: [0, 0, 0]}\n")
    e = error_of(p)
    assert (e.line, e.key_path) == (5, "lights[1]")
    assert "'direction'" in str(e) and "non-zero" in str(e)
    assert isinstance(e.__cause__, synthgen.SynthgenError)

    p = write(tmp_path, "camera: {width: 8, height: 8, fov_y: 40,\n"
                        "  look_at: {eye: [0, 0, -5], target: [0, 0, 0], up: [0, 0, 1]}}\n"
                        "objects: [{primitive: box, class_id: 1}]\n")
    e = error_of(p)
    assert e.key_path == "camera.look_at" and e.line == 2 and "parallel" in str(e)


def test_build_scene_from_dict_names_source_and_path():
    data = {"camera": {"width": 8, "height": 8, "fov_y": 40,
                       "look_at": {"eye": [0, 0, -5], "target": [0, 0, 0]}},
            "objects": [{"primitive": "box", "class_id": 1, "colour": 3}]}
    with pytest.raises(SceneFileError) as info:
        build_scene(data, "my-generator")
    e = info.value
    assert e.line is None and e.key_path == "objects[0].colour"
    assert str(e).startswith("my-generator: objects[0].colour: unknown key 'colour'")


# ---------------------------------------------------------------------------------------
# Building


def test_yaml12_floats_and_defaults(tmp_path):
    p = write(tmp_path, CAMERA + "objects: [{primitive: sphere, radius: 5e-1, class_id: 1}]\n"
                                 "lights: [{type: point, position: [0, 0, -3], intensity: 1.0e1}]\n")
    scene, settings, meta = load_scene(p)
    assert settings == {"spp": 16, "max_depth": 8, "rr_depth": 5, "seed": 0, "threads": 0, "tile_size": 16,
                        "texture_filtering": True, "exposure": 1.0, "clamp_indirect": 0.0, "noise_threshold": 0.0,
                        "target_psnr": 0.0, "min_spp": 0, "max_spp": 0, "denoise": False, "max_medium_depth": 64,
                        "next_event": True, "texture_lod": False, "texture_lod_margin": 0, "texture_budget_mib": 256.0}
    assert meta["objects"][0]["instance_id"] == 1 and meta["objects"][0]["class_id"] == 1
    assert meta["lights"] == [{"name": None, "type": "point", "id": 0}]


def test_transforms(tmp_path):
    p = write(tmp_path, CAMERA + textwrap.dedent("""\
        objects:
          - {primitive: box, class_id: 1, translate: [1, 2, 3], rotate: {axis: [0, 0, 2], angle: 90}, scale: 2}
          - {primitive: box, class_id: 1, rotate: {euler: [90, 0, 90]}}
          - {primitive: box, class_id: 1, rotate: {euler: [90, 0, 90], order: zyx}}
          - {primitive: box, class_id: 1, world_from_object: [1,0,0,5, 0,1,0,6, 0,0,1,7, 0,0,0,1]}
        """))
    _, _, meta = load_scene(p)
    m = [np.array(o["world_from_object"]) for o in meta["objects"]]
    np.testing.assert_allclose(m[0], [[0, -2, 0, 1], [2, 0, 0, 2], [0, 0, 2, 3], [0, 0, 0, 1]], atol=1e-12)
    rx = np.array([[1, 0, 0], [0, 0, -1], [0, 1, 0]])
    rz = np.array([[0, -1, 0], [1, 0, 0], [0, 0, 1]])
    np.testing.assert_allclose(m[1][:3, :3], rz @ rx, atol=1e-12)  # x first, then z
    np.testing.assert_allclose(m[2][:3, :3], rx @ rz, atol=1e-12)  # z first, then x
    np.testing.assert_allclose(m[3][:3, 3], [5, 6, 7])


def test_camera_forms(tmp_path):
    p = write(tmp_path, "camera:\n  {width: 40, height: 30, fx: 50, fy: 60,\n"
                        "   world_from_camera: [[1,0,0,1],[0,1,0,2],[0,0,1,3],[0,0,0,1]]}\n"
                        "objects: [{primitive: box, class_id: 1}]\n")
    scene, _, _ = load_scene(p)
    cam = scene.camera
    np.testing.assert_allclose(cam.K, [[50, 0, 20], [0, 60, 15], [0, 0, 1]])
    np.testing.assert_allclose(cam.world_from_camera[:3, 3], [1, 2, 3])
    p = write(tmp_path, CAMERA + "objects: [{primitive: box, class_id: 1}]\n")
    cam = load_scene(p)[0].camera
    f = 0.5 * 24 / math.tan(math.radians(20))
    np.testing.assert_allclose(cam.K, [[f, 0, 16], [0, f, 12], [0, 0, 1]], rtol=1e-6)
    np.testing.assert_allclose(cam.world_from_camera,
                               synthgen.PinholeCamera.look_at([0, 0, -5], [0, 0, 0], [0, 1, 0]), atol=1e-7)


def test_render_labels_land_where_the_camera_projects(tmp_path):
    """End to end: an object placed by the YAML appears at the pixel where the camera
    projects its centre, with the YAML's labels; the background keeps label 0."""
    p = write(tmp_path, textwrap.dedent("""\
        camera: {width: 32, height: 24, fx: 30, fy: 30, cx: 16, cy: 12,
                 look_at: {eye: [0, 0, -6], target: [0, 0, 0]}}
        materials: {m: {type: diffuse, albedo: 0.7}}
        objects:
          - {name: a, primitive: sphere, radius: 0.5, translate: [1.5, 1, 0], class_id: 4, instance_id: 40, material: m}
          - {name: b, primitive: box, size: 0.8, translate: [-1.5, -1, 0], class_id: 5}
        lights: [{type: environment, radiance: 1}]
        render: {spp: 1}
        """))
    scene, settings, meta = load_scene(p)
    result = scene.render(**settings)
    for obj, centre in zip(meta["objects"], ([1.5, 1, 0], [-1.5, -1, 0])):
        u, v = scene.camera.project(centre)
        assert result.instance_id[int(v), int(u)] == obj["instance_id"]
        assert result.class_id[int(v), int(u)] == obj["class_id"]
    assert meta["objects"][0]["instance_id"] == 40 and meta["objects"][1]["instance_id"] == 2
    assert result.instance_id[0, 16] == 0 and np.isinf(result.depth[0, 16])
    # the sphere's camera-space depth at its centre pixel is about 6 - radius
    u, v = scene.camera.project([1.5, 1, 0])
    assert abs(result.depth[int(v), int(u)] - 5.5) < 0.1


def test_relative_paths_resolve_against_the_yaml_directory(tmp_path, monkeypatch):
    sub = tmp_path / "scenes"
    (sub / "assets").mkdir(parents=True)
    (sub / "assets" / "tri.obj").write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    tex = np.zeros((4, 4, 3), np.uint8)
    tex[..., 0] = 255
    out = oiio.ImageOutput.create(str(sub / "assets" / "red.png"))
    out.open(str(sub / "assets" / "red.png"), oiio.ImageSpec(4, 4, 3, oiio.UINT8))
    out.write_image(tex)
    out.close()
    write(sub, CAMERA + textwrap.dedent("""\
        textures: {red: {type: image, file: assets/red.png, colorspace: srgb}}
        materials: {tex: {type: diffuse, albedo: {texture: red}}}
        objects: [{mesh: {file: assets/tri.obj}, class_id: 1, material: tex}]
        """))
    monkeypatch.chdir(tmp_path)  # not the YAML's directory
    scene, _, meta = load_scene(Path("scenes") / "scene.yaml")
    assert meta["textures"] == {"red": 0} and meta["materials"] == {"tex": 0}
    assert meta["objects"][0]["mesh"] == str(sub / "assets" / "tri.obj")


def test_meshes_are_shared_between_instances(tmp_path):
    p = write(tmp_path, CAMERA + textwrap.dedent("""\
        objects:
          - {primitive: sphere, radius: 1, class_id: 1}
          - {primitive: sphere, radius: 2, class_id: 1}
          - {primitive: box, size: [1, 2, 3], class_id: 2}
          - {primitive: box, size: 4, class_id: 2}
        """))
    _, _, meta = load_scene(p)
    ids = [o["mesh_id"] for o in meta["objects"]]
    assert ids[0] == ids[1] and ids[2] == ids[3] and ids[0] != ids[2]


def test_format_schema_documents_every_section():
    text = scene_file.format_schema()
    for key in ("camera:", "fov_y:", "objects:", "primitive:", "[primitive: sphere]", "lights:",
                "angular_diameter: number in [0, 90) (default 0.53)", "render:", "spp:"):
        assert key in text


# ---------------------------------------------------------------------------------------
# The extension point for random distributions (documented in the module docstring)


class Uniform:
    def __init__(self, lo, hi):
        self.lo, self.hi = lo, hi


class RandomizingContext(sf.ValidationContext):
    def number(self, field, value, loc):
        if isinstance(value, dict) and list(value) == ["uniform"]:
            bounds = value["uniform"]
            lo, hi = (field.check(v, loc.key("uniform", value).index(i, bounds), self) for i, v in enumerate(bounds))
            return Uniform(lo, hi)
        return super().number(field, value, loc)


def test_distribution_extension_point(tmp_path):
    p = write(tmp_path, CAMERA + textwrap.dedent("""\
        materials:
          red: {type: diffuse, albedo: [{uniform: [0.2, 0.8]}, 0.1, 0.1]}
        objects:
          - {primitive: sphere, radius: {uniform: [0.5, 1.0]}, class_id: 1, material: red}
        """))
    data = sf.read_yaml(p)
    ctx = RandomizingContext(str(p), str(tmp_path))
    spec = scene_file.SCENE_SCHEMA.validate(data, sf.Loc.root(data), ctx)
    assert isinstance(spec["objects"][0]["radius"], Uniform)
    rng = np.random.default_rng(1)
    frame = sf.map_values(spec, lambda v: float(rng.uniform(v.lo, v.hi)) if isinstance(v, Uniform) else v)
    assert 0.5 <= frame["objects"][0]["radius"] <= 1.0
    assert frame["objects"][0].locs["radius"].line == 5
    scene, settings, meta = scene_file.build_validated(frame, ctx)
    assert meta["materials"] == {"red": 0}
    # distribution bounds are checked against the slot's range, at their own position
    p = write(tmp_path, CAMERA + "materials:\n  red: {type: diffuse, albedo: {uniform: [0.2, 1.5]}}\n"
                                 "objects: [{primitive: box, class_id: 1}]\n")
    data = sf.read_yaml(p)
    with pytest.raises(SceneFileError) as info:
        scene_file.SCENE_SCHEMA.validate(data, sf.Loc.root(data), RandomizingContext(str(p)))
    assert info.value.key_path == "materials.red.albedo.uniform[1]" and info.value.line == 3
    assert "allowed: number in [0, 1]" in str(info.value)
    # the plain context rejects them
    with pytest.raises(SceneFileError, match="or {texture: NAME}, got a mapping with key\\(s\\) 'uniform'"):
        load_scene(p)


# ---------------------------------------------------------------------------------------
# Scenarios


def _plain(x):
    if isinstance(x, dict):
        return {k: _plain(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_plain(v) for v in x]
    return float(x) if isinstance(x, (int, float)) and not isinstance(x, bool) else x


def test_demo_yaml_is_the_builtin_demo():
    from synthgen.scene.demo import DEMO_SCENE

    data = yaml.safe_load((REPO / "scenarios" / "demo_scene.yaml").read_text())
    assert _plain(data) == _plain(DEMO_SCENE)
    scene, settings, meta = load_scene(REPO / "scenarios" / "demo_scene.yaml")
    assert settings["spp"] == 64 and (scene.camera.width, scene.camera.height) == (640, 480)
    assert sorted({o["class_id"] for o in meta["objects"]}) == [1, 2, 3]
    assert len({o["instance_id"] for o in meta["objects"]}) == len(meta["objects"])


@pytest.mark.skipif(not CBOX.is_dir(), reason=f"needs the shared assets directory {CBOX} (absent)")
def test_cornell_box_matches_the_ignis_reference():
    scene, settings, meta = load_scene(REPO / "scenarios" / "cornell_box.yaml")
    assert settings["max_depth"] == 6 and (scene.camera.width, scene.camera.height) == (256, 256)
    result = scene.render(**{**settings, "spp": 8})
    ref = oiio.ImageBuf(str(CBOX / "references" / "ref-cbox-d6-4096.exr")).get_pixels(oiio.FLOAT)[..., :3]
    img = np.asarray(result.rgb)
    np.testing.assert_allclose(img.mean(axis=(0, 1)), [0.21174, 0.10294, 0.02580], rtol=0.03)

    def blocks(x):
        return x.reshape(16, 16, 16, 16, 3).mean(axis=(1, 3))

    # 16x16-pixel block means agree (a mirrored or misplaced camera would not)
    err = np.abs(blocks(img) - blocks(ref)).mean() / ref.mean()
    assert err < 0.03, err
    assert np.abs(blocks(img[:, ::-1]) - blocks(ref)).mean() / ref.mean() > 0.1
    # labels: the luminaire (class 3) is visible near the top centre
    assert 3 in np.unique(result.class_id[:40, 100:156])


# ---------------------------------------------------------------------------------------
# Python-side use


def test_texture_reference_typo_is_explained(tmp_path):
    e = error_of(write(tmp_path, CAMERA + "materials:\n  m: {type: diffuse, albedo: {textur: wood}}\n"
                                          "objects: [{primitive: box, class_id: 1}]\n"))
    assert e.key_path == "materials.m.albedo" and e.line == 3
    assert "or {texture: NAME}, got a mapping with key(s) 'textur' (did you mean 'texture'?)" in str(e)


def test_build_scene_accepts_numpy_values():
    data = {"camera": {"width": np.int64(16), "height": 12, "fov_y": np.float32(40), "world_from_camera": np.eye(4)},
            "materials": {"m": {"type": "emissive", "radiance": np.array([1.0, 2.0, 3.0]), "two_sided": np.bool_(True)}},
            "objects": [{"primitive": "box", "class_id": np.uint16(3), "translate": np.array([0, 0, 5.0]),
                         "material": "m"}]}
    scene, settings, meta = build_scene(data)
    assert meta["objects"][0]["class_id"] == 3 and scene.camera.width == 16
    assert meta["source"] == "<scene>"


def test_load_scene_meta_records_source_and_hash(tmp_path):
    import hashlib

    p = write(tmp_path, CAMERA + "description: two boxes\nobjects: [{primitive: box, class_id: 1, name: a}]\n")
    _, _, meta = load_scene(p)
    assert meta["source"] == str(p) and meta["description"] == "two boxes"
    assert meta["source_sha256"] == hashlib.sha256(p.read_bytes()).hexdigest()
    assert meta["objects"][0]["name"] == "a" and meta["objects"][0]["primitive"] == "box"


def test_schema_can_be_extended(tmp_path):
    schema = scene_file.SCENE_SCHEMA.extend({"frames": sf.Integer(1, min=1, doc="number of frames")})
    p = write(tmp_path, CAMERA + "objects: [{primitive: box, class_id: 1}]\nframes: 0\n")
    data = sf.read_yaml(p)
    with pytest.raises(SceneFileError) as info:
        schema.validate(data, sf.Loc.root(data), sf.ValidationContext(str(p)))
    assert info.value.key_path == "frames" and info.value.line == 3 and ">= 1" in str(info.value)
    assert "frames" not in scene_file.SCENE_SCHEMA.fields  # the original is untouched
    data["frames"] = 3
    spec = schema.validate(data, sf.Loc.root(data), sf.ValidationContext(str(p)))
    assert spec["frames"] == 3 and spec["render"]["spp"] == 16
