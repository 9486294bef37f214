"""Scene.add_image_texture: images from memory (generated plates, signs, decals, shadow
maps) render exactly like the same pixels read from a file, without any file."""
import numpy as np
import pytest

import synthgen as sg
from synthgen import primitives as P
from synthgen.outputs.files import write_exr


def _plane_scene(material_from_texture):
    s = sg.Scene()
    pl = P.plane(2.0, 2.0)
    mesh = s.add_mesh(pl["positions"], pl["indices"], normals=pl["normals"], uvs=pl["uvs"])
    tex = material_from_texture(s)
    mat = s.add_material("diffuse", {"albedo": sg.TextureRef(tex)})
    s.add_instance(mesh, class_id=1, material_id=mat)
    s.add_light("environment", {"radiance": 1.0})
    s.set_camera(sg.PinholeCamera.from_fov(50.0, 48, 36, sg.PinholeCamera.look_at([0, 1.6, -1.2], [0, 0, 0])))
    return s


def test_memory_image_renders_like_its_file(tmp_path):
    img = np.random.default_rng(4).random((33, 47, 3)).astype(np.float32) * 0.9
    path = str(tmp_path / "img.exr")
    write_exr(path, img)
    a = _plane_scene(lambda s: s.add_texture("image", {"file": path, "wrap": "mirror"})).render(spp=4, seed=3)
    b = _plane_scene(lambda s: s.add_image_texture(img, {"wrap": "mirror"})).render(spp=4, seed=3)
    np.testing.assert_array_equal(a.rgb, b.rgb)
    np.testing.assert_array_equal(a.albedo, b.albedo)


def test_integer_pixels_decode_like_8_bit_files(tmp_path):
    import OpenImageIO as oiio

    img = (np.random.default_rng(5).random((16, 16, 3)) * 255).astype(np.uint8)
    path = str(tmp_path / "img.png")
    out = oiio.ImageOutput.create(path)
    out.open(path, oiio.ImageSpec(16, 16, 3, oiio.UINT8))
    out.write_image(img)
    out.close()
    a = _plane_scene(lambda s: s.add_texture("image", {"file": path})).render(spp=1, labels_only=True)
    b = _plane_scene(lambda s: s.add_image_texture(img)).render(spp=1, labels_only=True)
    np.testing.assert_allclose(a.albedo, b.albedo, atol=1e-6)


def test_identical_pixels_share_one_pyramid_and_bad_arrays_are_refused():
    s = sg.Scene()
    img = np.full((4, 4), 0.5, np.float32)
    s.add_image_texture(img)
    s.add_image_texture(img.copy())
    assert s.commit_stats["image_cache_hits"] == 1 and s.commit_stats["image_loads"] == 0
    with pytest.raises(sg.SynthgenError, match="not finite"):
        s.add_image_texture(np.full((2, 2), np.nan, np.float32))
    with pytest.raises(sg.SynthgenError, match="1 to 4 channels"):
        s.add_image_texture(np.zeros((2, 2, 5), np.float32))
    with pytest.raises(sg.SynthgenError, match="float32, float64, uint8 or uint16"):
        s.add_image_texture(np.zeros((2, 2), np.int32))
    with pytest.raises(sg.SynthgenError, match="no 'file'"):
        s.add_image_texture(img, {"file": "x.png"})
    with pytest.raises(sg.SynthgenError, match="did you mean 'wrap'"):
        s.add_image_texture(img, {"wrp": "clamp"})
