"""Scene files reach the newer plugins: coated and mix materials (references by name,
in any order, cycles rejected), envmap/sky/spot lights, texture uv transforms."""
import os

import numpy as np
import pytest
import yaml

from synthgen import SceneFileError
from synthgen.scene import scene_file

HDR = "/usr/share/blender/datafiles/studiolights/world/forest.exr"


def _scene(materials, lights=None):
    return {
        "camera": {"width": 24, "height": 16, "fov_y": 40, "look_at": {"eye": [0, 2, -5], "target": [0, 0.5, 0]}},
        "materials": materials,
        "objects": [{"primitive": "plane", "size": 10, "class_id": 1, "material": "top"}],
        "lights": lights or [{"type": "environment", "radiance": 1.0}],
        "render": {"spp": 2},
    }


def test_mix_may_refer_to_materials_defined_later():
    data = _scene({"top": {"type": "mix", "material_a": "a", "material_b": "b", "weight": 0.25},
                   "a": {"type": "diffuse", "albedo": 0.2}, "b": {"type": "coated", "albedo": 0.6}})
    scene, settings, meta = scene_file.build_scene(data, "mem.yaml")
    r = scene.render(**settings)
    assert np.allclose(r.albedo[r.class_id == 1], 0.75 * 0.2 + 0.25 * 0.6, atol=1e-6)


def test_material_reference_cycle_is_an_error():
    data = _scene({"top": {"type": "mix", "material_a": "x", "material_b": "top"},
                   "x": {"type": "diffuse"}})
    with pytest.raises(SceneFileError, match="cycle"):
        scene_file.build_scene(data, "mem.yaml")


def test_unknown_material_reference_suggests_a_name():
    data = _scene({"top": {"type": "mix", "material_a": "paint", "material_b": "pain"},
                   "paint": {"type": "diffuse"}})
    with pytest.raises(SceneFileError, match="did you mean 'paint'"):
        scene_file.build_scene(data, "mem.yaml")


def test_spot_and_sky_lights_and_range_errors():
    data = _scene({"top": {"type": "diffuse"}},
                  [{"type": "spot", "position": [0, 3, 0], "intensity": 5, "cone_angle": 30},
                   {"type": "sky", "elevation": 40, "turbidity": 3, "strength": 0.01}])
    scene, settings, _ = scene_file.build_scene(data, "mem.yaml")
    assert scene.render(**settings).stats["nan_samples"] == 0
    data["lights"][1]["turbidity"] = 20
    with pytest.raises(SceneFileError, match=r"lights\[1\]\.turbidity"):
        scene_file.build_scene(data, "mem.yaml")


@pytest.mark.skipif(not os.path.exists(HDR), reason="blender-data (HDR maps) not installed")
def test_envmap_file_is_resolved_relative_to_the_scene_file(tmp_path):
    os.symlink(HDR, tmp_path / "sky.exr")
    data = _scene({"top": {"type": "diffuse"}}, [{"type": "envmap", "file": "sky.exr", "rotation": 90}])
    path = tmp_path / "s.yaml"
    path.write_text(yaml.safe_dump(data))
    scene, settings, _ = scene_file.load_scene(str(path))
    r = scene.render(**settings)
    assert r.rgb.mean() > 0 and r.stats["nan_samples"] == 0
