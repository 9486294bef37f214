"""Bad input raises a clear Python exception (synthgen.SynthgenError, or its subclass FileError
for files; both are ValueError subclasses), never a crash or a silent success."""
from __future__ import annotations

import os
import subprocess
import sys
import textwrap

import numpy as np
import pytest

import synthgen as sg
from synthgen import primitives as P

ASSIMP_MODELS = "/usr/share/assimp/models"


def tri(**over):
    d = dict(positions=np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], dtype=np.float32),
             indices=np.array([[0, 1, 2]], dtype=np.uint32))
    d.update(over)
    return d


@pytest.fixture
def scene():
    return sg.Scene()


def test_exception_hierarchy():
    assert issubclass(sg.SynthgenError, ValueError)
    assert issubclass(sg.FileError, sg.SynthgenError)


# Files ---------------------------------------------------------------------------------------

def test_missing_file_names_the_file(scene, tmp_path):
    path = str(tmp_path / "does_not_exist.obj")
    with pytest.raises(sg.FileError, match="does_not_exist.obj"):
        scene.load_mesh_file(path)


def test_directory_instead_of_file(scene, tmp_path):
    with pytest.raises(sg.FileError, match=str(tmp_path.name)):
        scene.load_mesh_file(str(tmp_path))


def test_garbage_obj(scene, tmp_path):
    path = tmp_path / "garbage.obj"
    path.write_bytes(bytes(np.random.default_rng(0).integers(0, 256, 4096, dtype=np.uint8)))
    with pytest.raises(sg.FileError, match="garbage.obj"):
        scene.load_mesh_file(str(path))


def test_obj_with_bad_face_index(scene, tmp_path):
    path = tmp_path / "badface.obj"
    path.write_text("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n")
    with pytest.raises(sg.FileError, match="badface.obj"):
        scene.load_mesh_file(str(path))


@pytest.mark.parametrize("axis", [0, 1, 2])
@pytest.mark.parametrize("token", ["nan", "NaN", "inf", "-inf"])
def test_obj_with_non_finite_vertex(scene, tmp_path, token, axis):
    coords = ["5", "0", "2"]
    coords[axis] = token
    path = tmp_path / "nonfinite.obj"
    path.write_text(f"v 0 0 0\nv 1 0 0\nv 0 1 0\nv {' '.join(coords)}\nv 6 0 2\nv 5 1 2\nf 1 2 3\nf 4 5 6\n")
    with pytest.raises(sg.FileError, match="nonfinite.obj") as e:
        scene.load_mesh_file(str(path))
    assert "non-finite" in str(e.value)


def test_obj_with_only_degenerate_triangles(scene, tmp_path):
    path = tmp_path / "flat.obj"
    path.write_text("v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n")
    with pytest.raises(sg.FileError, match="flat.obj"):
        scene.load_mesh_file(str(path))


def test_obj_with_missing_texture_names_both(scene, tmp_path):
    (tmp_path / "m.mtl").write_text("newmtl a\nKd 1 1 1\nmap_Kd nothere.png\n")
    path = tmp_path / "tex.obj"
    path.write_text("mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl a\nf 1 2 3\n")
    with pytest.raises(sg.FileError, match="tex.obj") as e:
        scene.load_mesh_file(str(path))
    assert "nothere.png" in str(e.value)


def test_failed_load_leaves_scene_usable(scene, tmp_path):
    bad = tmp_path / "bad.obj"
    bad.write_text("this is not an obj file\n")
    with pytest.raises(sg.FileError):
        scene.load_mesh_file(str(bad))
    good = tmp_path / "good.obj"
    good.write_text("v 0 0 2\nv 1 0 2\nv 0 1 2\nf 1 2 3\n")
    mid = scene.load_mesh_file(str(good))["mesh_id"]
    scene.add_instance(mid)
    scene.set_camera(sg.PinholeCamera(fx=10, fy=10, cx=4, cy=4, width=8, height=8))
    assert scene.render(spp=1).instance_id.max() == 1


def test_missing_image_texture(scene, tmp_path):
    with pytest.raises(sg.FileError, match="nope.png"):
        scene.add_texture("image", {"filename": str(tmp_path / "nope.png")})


# Arrays --------------------------------------------------------------------------------------

@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
def test_non_finite_vertex_array(scene, bad):
    p = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, bad]], dtype=np.float32)
    with pytest.raises(sg.SynthgenError, match="vertex 3"):
        scene.add_mesh(positions=p, indices=np.array([[0, 1, 2], [1, 3, 2]]))


def test_non_finite_normal_and_uv(scene):
    with pytest.raises(sg.SynthgenError, match="normal 1"):
        scene.add_mesh(**tri(normals=np.array([[0, 0, 1], [np.nan, 0, 1], [0, 0, 1]], dtype=np.float32)))
    with pytest.raises(sg.SynthgenError, match="normal 2"):
        scene.add_mesh(**tri(normals=np.array([[0, 0, 1], [0, 0, 1], [0, 0, 0]], dtype=np.float32)))
    with pytest.raises(sg.SynthgenError, match="uv 0"):
        scene.add_mesh(**tri(uvs=np.array([[np.inf, 0], [0, 0], [0, 1]], dtype=np.float32)))


@pytest.mark.parametrize("indices", [
    [[0, 1, 1]],                       # repeated vertex
    [[0, 1, 2], [0, 1, 3]],            # collinear vertices (3 lies on the line 0-1)
])
def test_degenerate_triangles(scene, indices):
    p = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [2, 0, 0]], dtype=np.float32)
    with pytest.raises(sg.SynthgenError, match="degenerate"):
        scene.add_mesh(positions=p, indices=np.array(indices))


@pytest.mark.parametrize("indices", [[[0, 1, 3]], [[0, 1, -1]], [[0, 1, 2**32]]])
def test_indices_out_of_range(scene, indices):
    with pytest.raises(sg.SynthgenError, match="out of range|references vertex"):
        scene.add_mesh(**tri(indices=np.array(indices, dtype=np.int64)))


@pytest.mark.parametrize("over, what", [
    (dict(positions=np.zeros((3, 2), np.float32)), "positions"),
    (dict(positions=np.zeros(9, np.float32)), "positions"),
    (dict(indices=np.array([[0, 1, 2, 0]])), "indices"),
    (dict(indices=np.array([0, 1, 2])), "indices"),
    (dict(indices=np.array([[0.0, 1.0, 2.0]])), "indices"),
    (dict(normals=np.zeros((3, 2), np.float32)), "normals"),
    (dict(normals=np.array([[0, 0, 1]] * 2, np.float32)), "normals"),
    (dict(uvs=np.zeros((3, 3), np.float32)), "uvs"),
    (dict(uvs=np.zeros((4, 2), np.float32)), "uvs"),
    (dict(material_ids=np.array([0, 0])), "material_ids"),
    (dict(positions=np.zeros((0, 3), np.float32), indices=np.zeros((0, 3), np.uint32)), "no vertices"),
    (dict(indices=np.zeros((0, 3), np.uint32)), "no triangles"),
    (dict(positions=[["a", "b", "c"]] * 3), "positions"),
])
def test_wrong_array_shapes(scene, over, what):
    with pytest.raises(sg.SynthgenError) as e:
        scene.add_mesh(**tri(**over))
    assert what in str(e.value)


def test_update_mesh_validates_and_keeps_old_mesh(scene):
    mid = scene.add_mesh(**tri())
    with pytest.raises(sg.SynthgenError, match="degenerate"):
        scene.update_mesh(mid, positions=np.zeros((3, 3), np.float32), indices=np.array([[0, 1, 2]]))
    np.testing.assert_array_equal(scene.mesh_arrays(mid)["positions"], tri()["positions"])


# Scene and camera ----------------------------------------------------------------------------

def test_empty_scene_render(scene):
    scene.set_camera(sg.PinholeCamera(fx=10, fy=10, cx=4, cy=4, width=8, height=8))
    with pytest.raises(sg.SynthgenError, match="empty"):
        scene.render(spp=1)


def test_render_without_camera(scene):
    scene.add_instance(scene.add_mesh(**tri()))
    with pytest.raises(sg.SynthgenError, match="camera"):
        scene.render(spp=1)


@pytest.mark.parametrize("kw", [dict(fx=0), dict(fy=0), dict(fx=-100), dict(fy=float("nan")),
                                dict(fx=float("inf")), dict(cx=float("nan")), dict(width=0), dict(height=0)])
def test_bad_camera_intrinsics(kw):
    args = dict(fx=100.0, fy=100.0, cx=32.0, cy=24.0, width=64, height=48)
    args.update(kw)
    with pytest.raises(sg.SynthgenError, match="camera"):
        sg.PinholeCamera(**args)


@pytest.mark.parametrize("vfov", [0.0, -10.0, 180.0, float("nan")])
def test_bad_field_of_view(vfov):
    with pytest.raises(sg.SynthgenError, match="field of view"):
        sg.PinholeCamera.from_fov(vfov, 64, 48)


def test_bad_look_at():
    with pytest.raises(sg.SynthgenError, match="coincide"):
        sg.PinholeCamera.look_at([1, 2, 3], [1, 2, 3])
    with pytest.raises(sg.SynthgenError, match="parallel"):
        sg.PinholeCamera.look_at([0, 0, 0], [0, 5, 0], [0, 1, 0])


@pytest.mark.parametrize("kw, what", [(dict(spp=0), "spp"), (dict(max_depth=0), "max_depth"),
                                      (dict(tile_size=0), "tile_size")])
def test_bad_render_settings(scene, kw, what):
    scene.add_instance(scene.add_mesh(**tri()))
    scene.set_camera(sg.PinholeCamera(fx=10, fy=10, cx=4, cy=4, width=8, height=8))
    with pytest.raises(sg.SynthgenError, match=what):
        scene.render(**kw)


# Materials, textures, lights -----------------------------------------------------------------

def test_unknown_material_type_did_you_mean(scene):
    with pytest.raises(sg.SynthgenError, match="did you mean 'diffuse'"):
        scene.add_material("difuse", {"albedo": 0.5})
    with pytest.raises(sg.SynthgenError, match="did you mean 'emissive'"):
        scene.add_material("emisive", {})


def test_unknown_material_parameter_did_you_mean(scene):
    with pytest.raises(sg.SynthgenError, match="unknown parameter 'albdo'.*did you mean 'albedo'"):
        scene.add_material("diffuse", {"albdo": [0.5, 0.5, 0.5]})
    with pytest.raises(sg.SynthgenError, match="did you mean 'radiance'"):
        scene.add_material("emissive", {"radience": 2.0})


@pytest.mark.parametrize("params, what", [
    ({"albedo": [0.5, 0.5]}, "albedo"),
    ({"albedo": "red"}, "albedo"),
    ({"albedo": [1.5, 0.2, 0.2]}, "albedo"),
    ({"albedo": [-0.1, 0.2, 0.2]}, "albedo"),
    ({"albedo": float("nan")}, "albedo"),
    ({"albedo": [[0.1, 0.2, 0.3]]}, "albedo"),
    ({"albedo": object()}, "albedo"),
])
def test_bad_material_parameter_values(scene, params, what):
    with pytest.raises(sg.SynthgenError, match=what):
        scene.add_material("diffuse", params)


def test_unknown_light_and_texture_types(scene):
    with pytest.raises(sg.SynthgenError, match="did you mean 'sun'"):
        scene.add_light("sunn", {})
    with pytest.raises(sg.SynthgenError, match="did you mean 'image'"):
        scene.add_texture("imag", {})
    with pytest.raises(sg.SynthgenError, match="unknown parameter 'irradiance_'"):
        scene.add_light("sun", {"irradiance_": 1.0})


def test_texture_ref_to_missing_texture(scene):
    with pytest.raises(sg.SynthgenError, match="texture 5 does not exist"):
        scene.add_material("diffuse", {"albedo": sg.TextureRef(5)})


# Transforms and ids --------------------------------------------------------------------------

@pytest.mark.parametrize("matrix, what", [
    (P.scale([1.0, 0.0, 1.0]), "singular"),
    (np.zeros((4, 4), np.float32), "singular|last row"),
    (np.array([[1, 2, 3, 0], [2, 4, 6, 0], [0, 0, 1, 0], [0, 0, 0, 1]], np.float32), "singular"),
    (np.diag([1, 1, 1, 2]).astype(np.float32), "last row"),
    (np.full((4, 4), np.nan, np.float32), "non-finite"),
    (np.eye(3, dtype=np.float32), "4x4"),
])
def test_bad_instance_transform(scene, matrix, what):
    mid = scene.add_mesh(**tri())
    with pytest.raises(sg.SynthgenError, match=what):
        scene.add_instance(mid, matrix)
    inst = scene.add_instance(mid)
    with pytest.raises(sg.SynthgenError, match=what):
        scene.set_instance_transform(inst, matrix)


def test_singular_camera_pose():
    with pytest.raises(sg.SynthgenError, match="singular"):
        sg.PinholeCamera(fx=10, fy=10, cx=4, cy=4, width=8, height=8, world_from_camera=P.scale(0.0))


def test_nonexistent_ids(scene):
    mid = scene.add_mesh(**tri())
    mat = scene.add_material("diffuse", {})
    inst = scene.add_instance(mid, material_id=mat)
    with pytest.raises(sg.SynthgenError, match="mesh 7 does not exist"):
        scene.add_instance(7)
    with pytest.raises(sg.SynthgenError, match="material 9 does not exist"):
        scene.add_instance(mid, material_id=9)
    with pytest.raises(sg.SynthgenError, match="material 9 does not exist"):
        scene.set_instance_material(inst, 9)
    with pytest.raises(sg.SynthgenError, match="material 9 does not exist"):
        scene.add_mesh(**tri(material_ids=np.array([9])))
    with pytest.raises(sg.SynthgenError, match="material 4 does not exist"):
        scene.update_material(4, "diffuse", {})
    with pytest.raises(sg.SynthgenError, match="instance 3 does not exist"):
        scene.set_instance_transform(3, np.eye(4))
    with pytest.raises(sg.SynthgenError, match="instance 3 does not exist"):
        scene.set_instance_labels(3, 1, 1)
    with pytest.raises(sg.SynthgenError, match="instance 3 does not exist"):
        scene.remove_instance(3)
    with pytest.raises(sg.SynthgenError, match="mesh 2 does not exist"):
        scene.update_mesh(2, **tri())
    with pytest.raises(sg.SynthgenError, match="mesh 2 does not exist"):
        scene.mesh_arrays(2)
    with pytest.raises(sg.SynthgenError, match="light 0 does not exist"):
        scene.update_light(0, "sun", {})
    with pytest.raises(sg.SynthgenError, match="light 0 does not exist"):
        scene.remove_light(0)
    with pytest.raises(sg.SynthgenError, match="still used by instance"):
        scene.remove_mesh(mid)
    scene.remove_instance(inst)
    with pytest.raises(sg.SynthgenError, match=f"instance {inst} does not exist"):
        scene.remove_instance(inst)  # removed handles stay invalid


def test_scene_load_of_missing_and_malformed_file(tmp_path):
    with pytest.raises(sg.FileError, match="missing.xml"):
        sg.Scene.load(str(tmp_path / "missing.xml"))
    bad = tmp_path / "bad.xml"
    bad.write_text("<synthgen_scene><mesh id='0' ")
    with pytest.raises(sg.FileError, match="bad.xml"):
        sg.Scene.load(str(bad))


# Robustness over assimp's collection of unusual and malformed files ----------------------------

_LOADER = textwrap.dedent("""
    import sys, numpy as np, synthgen as sg
    cam = sg.PinholeCamera.from_fov(60, 16, 16, sg.PinholeCamera.look_at([2.0, 1.5, 3.0], [0, 0, 0]))
    for path in sys.argv[1:]:
        print("START", path, flush=True)
        s = sg.Scene()
        try:
            r = s.load_mesh_file(path)
        except sg.SynthgenError as e:
            print("ERROR", type(e).__name__, str(e).replace("\\n", " "), flush=True)
            continue
        # A loaded mesh must be valid and renderable.
        m = s.mesh_arrays(r["mesh_id"])
        assert len(m["indices"]) > 0 and np.isfinite(m["positions"]).all()
        assert m["indices"].max() < len(m["positions"])
        s.add_instance(r["mesh_id"])
        s.set_camera(cam)
        img = s.render(spp=1, max_depth=2, threads=1)
        assert np.isfinite(img.rgb).all()
        print("LOADED", len(m["indices"]), "triangles", len(r["material_ids"]), "materials",
              len(r["texture_ids"]), "textures", flush=True)
""")


def _assimp_test_files():
    out = []
    for root, _, files in os.walk(ASSIMP_MODELS):
        for f in files:
            if f.lower().endswith((".obj", ".ply", ".gltf", ".glb")):
                out.append(os.path.join(root, f))
    return sorted(out)


@pytest.mark.skipif(not os.path.isdir(ASSIMP_MODELS),
                    reason=f"{ASSIMP_MODELS} not found: install the Debian package assimp-testmodels")
def test_assimp_testmodels_load_or_raise():
    """Every OBJ/PLY/glTF/GLB of assimp-testmodels either loads (and renders) or raises
    SynthgenError. The loads run in a child process so that a crash is reported with the
    file that caused it instead of killing pytest."""
    files = _assimp_test_files()
    assert len(files) > 50
    p = subprocess.run([sys.executable, "-c", _LOADER, *files], capture_output=True, text=True, timeout=300)
    lines = p.stdout.splitlines()
    started = [ln[6:] for ln in lines if ln.startswith("START ")]
    if p.returncode != 0:
        culprit = started[-1] if started else "?"
        pytest.fail(f"loader exited with {p.returncode} while processing {culprit}:\n{p.stderr[-3000:]}")
    results = [ln for ln in lines if ln.startswith(("LOADED", "ERROR"))]
    assert started == files and len(results) == len(files)
    loaded = sum(r.startswith("LOADED") for r in results)
    errors = [r for r in results if r.startswith("ERROR")]
    print(f"\n[assimp-testmodels] {len(files)} files: {loaded} loaded, {len(errors)} raised SynthgenError")
    # FileError messages name the file they are about.
    for f, r in zip(files, results):
        if r.startswith("ERROR FileError"):
            assert f in r, r
    # The collection contains both kinds; a loader that rejected (or accepted) everything is wrong.
    assert loaded > len(files) // 3 and len(errors) > 10
