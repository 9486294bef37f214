"""Image and procedural textures in scenario materials: inline textures ({texture: {type:
NAME, ...}}) wherever a plugin takes a texture, parameters that may be distributions, nested
textures, image files checked before rendering, per-frame textures released."""
import numpy as np
import pytest

import synthgen as sg
from synthgen import scenario
from synthgen.frame.renderer import FrameRenderer
from synthgen.outputs.files import write_exr, write_srgb_png


def _scenario(tmp_path, objects, ground="", count=1):
    p = tmp_path / "s.yaml"
    p.write_text(f"""seed: 1
count: {count}
resolution: [96, 72]
camera: {{fov_y: 40, pose: {{type: orbit, distance: 4, elevation: 25}}}}
render: {{spp: 1, max_depth: 1}}
{ground}
objects:
{objects}
""")
    return scenario.load_scenario(p)


def test_an_image_texture_gives_its_colours(tmp_path):
    write_exr(str(tmp_path / "flat.exr"), np.tile(np.float32([0.2, 0.4, 0.6]), (4, 4, 1)))
    write_srgb_png(str(tmp_path / "grey.png"), np.full((4, 4, 3), 0.5, np.float32))
    sc = _scenario(tmp_path, "  - {class: box, primitive: box, material: {type: diffuse, albedo: {texture: "
                             "{type: image, file: flat.exr}}}}",
                   ground="ground: {material: {type: diffuse, albedo: {texture: {type: image, file: grey.png}}}}")
    arrays, meta, _ = FrameRenderer(sc).render(0)
    cls, alb = np.asarray(arrays["class_id"]), np.asarray(arrays["albedo"])
    assert np.allclose(alb[cls == 1], [0.2, 0.4, 0.6], atol=1e-3)
    hit = np.isfinite(np.asarray(arrays["depth"]))
    assert np.allclose(alb[hit & (cls == 0)], 0.5, atol=4e-3), "the PNG's sRGB 0.5 decodes to linear 0.5 here"


def test_procedural_textures_with_distributions_and_nesting(tmp_path):
    write_srgb_png(str(tmp_path / "road.png"), np.random.default_rng(0).random((32, 32, 3)).astype(np.float32))
    objects = """  - {class: box, primitive: box, material: {type: diffuse, albedo: {texture: {type: noise, scale: {uniform: [2, 6]}, seed: {int: [0, 100]}}}}}
  - {class: ball, primitive: sphere, material: {type: principled, base_color: {choice: [{texture: {type: triplanar, texture: {texture: {type: image, file: road.png}}}}, [0.8, 0.1, 0.1]]}, roughness: {texture: {type: noise}}}}"""
    sc = _scenario(tmp_path, objects, count=6)
    fr = FrameRenderer(sc)
    counts = []
    textured = 0
    for k in range(sc.count):
        arrays, meta, _ = fr.render(k)
        cls, alb = np.asarray(arrays["class_id"]), np.asarray(arrays["albedo"])
        assert alb[cls == 1].std(axis=0).max() > 0.01, "noise varies over the box"
        ball = alb[cls == 2]
        textured += ball.std(axis=0).max() > 0.01
        counts.append((fr.scene.texture_count(), fr.scene.material_count()))
    assert 0 < textured < sc.count, "the choice takes both options"
    assert max(c[0] for c in counts) <= 6, f"per-frame textures are released: {counts}"
    assert "objects[0]#0.material.albedo.texture.scale" in meta["sampled"]


@pytest.mark.parametrize("material, message", [
    ("{type: diffuse, albedo: {texture: {type: imag, file: x.png}}}",
     r"albedo.texture.type: unknown value 'imag' \(did you mean 'image'\?\)"),
    ("{type: diffuse, albedo: {texture: {type: noise}, scale: 2}}",
     r"albedo.scale: an inline texture is \{texture: \{...\}\} alone; unexpected key 'scale'"),
    ("{type: diffuse, albedo: {texture: {type: image, file: missing.png}}}",
     r"albedo.texture.file: file not found"),
    ("{type: diffuse, bump_map: 0.5}", r"bump_map: expected an inline texture"),
])
def test_texture_mistakes_are_located(tmp_path, material, message):
    with pytest.raises(sg.SynthgenError, match=message):
        _scenario(tmp_path, f"  - {{class: box, primitive: box, material: {material}}}")


def test_a_corrupt_image_is_refused_before_rendering(tmp_path):
    from synthgen.scenario import check_inputs

    (tmp_path / "bad.png").write_bytes(b"\x89PNG\r\n\x1a\n" + b"x" * 40)
    sc = _scenario(tmp_path, "  - {class: box, primitive: box, material: {type: diffuse, albedo: {choice: "
                             "[{texture: {type: image, file: bad.png}}, 0.5]}}}")
    with pytest.raises(sg.SynthgenError, match=r"s.yaml:\d+:\d+: .*texture.file: cannot use this image: .*bad.png"):
        check_inputs(sc)
