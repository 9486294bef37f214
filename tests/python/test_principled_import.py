"""glTF metallic-roughness and OBJ/MTL materials import as "principled" (cpp/io/mesh_io.cpp,
cpp/api/scene_import.cpp): Khronos' BoxTextured sample, and small glTF / OBJ files written
here whose factors are known, checked through Scene.material_info and renders."""
from __future__ import annotations

import json
import math
import os
import struct
import zlib

import numpy as np
import pytest

import synthgen as sg

ASSIMP_GLTF2 = "/usr/share/assimp/models/glTF2"
BOX_GLB = os.path.join(ASSIMP_GLTF2, "BoxTextured-glTF-Binary", "BoxTextured.glb")
BOX_GLTF = os.path.join(ASSIMP_GLTF2, "BoxTextured-glTF", "BoxTextured.gltf")
needs_box = pytest.mark.skipif(not os.path.isfile(BOX_GLB), reason="assimp-testmodels not installed")


def png_bytes(pixels: np.ndarray) -> bytes:
    """8-bit RGBA PNG (PNG spec: IHDR, one IDAT of filter-0 scanlines, IEND)."""
    h, w, _ = pixels.shape
    raw = b"".join(b"\x00" + pixels[y].astype(np.uint8).tobytes() for y in range(h))

    def chunk(tag, data):
        return struct.pack(">I", len(data)) + tag + data + struct.pack(">I", zlib.crc32(tag + data) & 0xFFFFFFFF)

    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 6, 0, 0, 0))
            + chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b""))


def write_quad_gltf(directory, material: dict, images: dict | None = None, name="quad.gltf") -> str:
    """A 2 x 2 quad in the z = 3 plane facing -z (towards a camera at the origin), with uvs,
    one material, and PNG images (name -> RGBA array) written next to it."""
    pos = np.array([[-1, -1, 3], [1, -1, 3], [1, 1, 3], [-1, 1, 3]], np.float32)
    nrm = np.tile(np.array([0, 0, -1], np.float32), (4, 1))
    uv = np.array([[0, 1], [1, 1], [1, 0], [0, 0]], np.float32)
    idx = np.array([0, 2, 1, 0, 3, 2], np.uint16)
    blob = pos.tobytes() + nrm.tobytes() + uv.tobytes() + idx.tobytes()
    (directory / "quad.bin").write_bytes(blob)
    views = [{"buffer": 0, "byteOffset": 0, "byteLength": 48}, {"buffer": 0, "byteOffset": 48, "byteLength": 48},
             {"buffer": 0, "byteOffset": 96, "byteLength": 32}, {"buffer": 0, "byteOffset": 128, "byteLength": 12}]
    doc = {
        "asset": {"version": "2.0"},
        "scene": 0, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2},
                                    "indices": 3, "material": 0}]}],
        "buffers": [{"uri": "quad.bin", "byteLength": len(blob)}],
        "bufferViews": views,
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3", "min": [-1, -1, 3], "max": [1, 1, 3]},
            {"bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC3"},
            {"bufferView": 2, "componentType": 5126, "count": 4, "type": "VEC2"},
            {"bufferView": 3, "componentType": 5123, "count": 6, "type": "SCALAR"}],
        "materials": [material],
    }
    if images:
        doc["images"] = [{"uri": n} for n in images]
        doc["textures"] = [{"source": i} for i in range(len(images))]
        for n, px in images.items():
            (directory / n).write_bytes(png_bytes(px))
    path = directory / name
    path.write_text(json.dumps(doc))
    return str(path)


def quad_scene(path):
    s = sg.Scene()
    res = s.load_mesh_file(path)
    s.add_instance(res["mesh_id"], instance_id=1)
    # f = 30: the quad (2 x 2 at distance 3) covers the central 20 x 20 pixels of 40 x 40.
    s.set_camera(sg.PinholeCamera(fx=30, fy=30, cx=20, cy=20, width=40, height=40))
    return s, res


def principled_of(s, res):
    infos = [s.material_info(m) for m in res["material_ids"]]
    assert all(i["type"] == "principled" for i in infos)
    return infos


@needs_box
@pytest.mark.parametrize("path", [BOX_GLB, BOX_GLTF])
def test_box_textured_imports_as_principled_with_its_texture(path):
    s = sg.Scene()
    res = s.load_mesh_file(path)
    infos = principled_of(s, res)
    # The file's material (assimp may add a default one): base colour texture, metallic 0
    # (metallicFactor 0 in the file), roughness 1 (glTF default), opaque.
    textured = [i["params"] for i in infos if isinstance(i["params"]["base_color"], tuple)]
    assert len(textured) == 1 and len(res["texture_ids"]) == 1
    p = textured[0]
    assert p["base_color"] == ("texture", res["texture_ids"][0])
    assert p["metallic"] == 0.0 and p["roughness"] == 1.0 and p["alpha_mode"] == "opaque"
    s.add_instance(res["mesh_id"], instance_id=1)
    s.set_camera(sg.PinholeCamera.from_fov(40, 64, 64, sg.PinholeCamera.look_at([1.5, 1.2, 2.0], [0, 0, 0])))
    r = s.render(spp=1, max_depth=1)
    albedo = r.albedo[r.instance_id == 1]
    assert len(albedo) > 500
    # The Cesium logo texture: many distinct albedo values.
    assert len(np.unique(albedo, axis=0)) > 20


def test_gltf_factors_and_textures_map_to_principled_parameters(tmp_path):
    px = np.full((4, 4, 4), 255, np.uint8)
    mat = {
        "pbrMetallicRoughness": {"baseColorFactor": [0.2, 0.4, 0.6, 0.5], "metallicFactor": 0.3,
                                 "roughnessFactor": 0.7, "metallicRoughnessTexture": {"index": 0}},
        "normalTexture": {"index": 1, "scale": 0.8},
        "emissiveFactor": [1.0, 0.5, 0.25],
        "alphaMode": "MASK", "alphaCutoff": 0.3,
    }
    path = write_quad_gltf(tmp_path, mat, {"mr.png": px, "normal.png": px})
    s = sg.Scene()
    res = s.load_mesh_file(path)
    p = [i["params"] for i in principled_of(s, res) if i["params"].get("alpha_mode") == "mask"][0]
    assert p["base_color"] == pytest.approx([0.2, 0.4, 0.6])
    assert p["metallic"] == pytest.approx(0.3) and p["roughness"] == pytest.approx(0.7)
    assert p["metallic_roughness"][0] == "texture" and p["normal_map"][0] == "texture"
    assert p["metallic_roughness"] != p["normal_map"]
    assert p["normal_scale"] == pytest.approx(0.8)
    assert p["emission"] == pytest.approx([1.0, 0.5, 0.25])
    assert p["alpha_cutoff"] == pytest.approx(0.3) and p["alpha_factor"] == pytest.approx(0.5)
    assert len(res["texture_ids"]) == 2


def test_gltf_khr_transmission_clearcoat_ior(tmp_path):
    mat = {"pbrMetallicRoughness": {"baseColorFactor": [1, 1, 1, 1], "metallicFactor": 0.0},
           "extensions": {"KHR_materials_transmission": {"transmissionFactor": 0.9},
                          "KHR_materials_clearcoat": {"clearcoatFactor": 0.6, "clearcoatRoughnessFactor": 0.2},
                          "KHR_materials_ior": {"ior": 1.33}}}
    path = write_quad_gltf(tmp_path, mat)
    doc = json.loads(open(path).read())
    doc["extensionsUsed"] = ["KHR_materials_transmission", "KHR_materials_clearcoat", "KHR_materials_ior"]
    open(path, "w").write(json.dumps(doc))
    s = sg.Scene()
    res = s.load_mesh_file(path)
    p = principled_of(s, res)[0]["params"]
    assert p["transmission"] == pytest.approx(0.9) and p["ior"] == pytest.approx(1.33)
    assert p["clearcoat"] == pytest.approx(0.6) and p["clearcoat_roughness"] == pytest.approx(0.2)


def test_gltf_metal_albedo_is_base_colour_and_emission_renders(tmp_path):
    mat = {"pbrMetallicRoughness": {"baseColorFactor": [0.9, 0.6, 0.3, 1.0], "metallicFactor": 1.0,
                                    "roughnessFactor": 0.4},
           "emissiveFactor": [1.0, 0.5, 0.25]}
    s, _ = quad_scene(write_quad_gltf(tmp_path, mat))
    r = s.render(spp=4, max_depth=1)
    centre = (slice(12, 28), slice(12, 28))
    assert np.all(r.instance_id[centre] == 1)
    np.testing.assert_allclose(r.albedo[centre], np.broadcast_to(np.float32([0.9, 0.6, 0.3]), (16, 16, 3)), atol=1e-6)
    # max_depth 1: only emission is seen (no lights), from the front face.
    np.testing.assert_allclose(r.rgb[centre], np.broadcast_to(np.float32([1.0, 0.5, 0.25]), (16, 16, 3)), atol=1e-5)


@pytest.mark.parametrize("alpha, mode, visible", [(0.2, "MASK", False), (0.8, "MASK", True), (0.2, "OPAQUE", True),
                                                  (0.4, "BLEND", False), (0.6, "BLEND", True)])
def test_gltf_alpha_mode_cuts_out(tmp_path, alpha, mode, visible):
    mat = {"pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.5, 0.5, alpha]}, "alphaMode": mode}
    s, _ = quad_scene(write_quad_gltf(tmp_path, mat))
    r = s.render(spp=1, max_depth=1)
    assert np.all(r.instance_id[12:28, 12:28] == (1 if visible else 0))


def test_gltf_base_texture_alpha_channel_cuts_out(tmp_path):
    # Left half of the texture transparent (alpha 0), right half opaque; MASK at 0.5.
    px = np.full((8, 8, 4), 200, np.uint8)
    px[:, :4, 3] = 0
    px[:, 4:, 3] = 255
    mat = {"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}, "alphaMode": "MASK"}
    s, _ = quad_scene(write_quad_gltf(tmp_path, mat, {"rgba.png": px}))
    r = s.render(spp=1, max_depth=1)
    # u = 0 at x = -1 (left of the image, the camera looks along +z with x right).
    assert np.all(r.instance_id[12:28, 11:19] == 0)
    assert np.all(r.instance_id[12:28, 21:29] == 1)


def test_obj_mtl_specular_shininess_and_opacity(tmp_path):
    (tmp_path / "m.mtl").write_text("newmtl shiny\nKd 0.5 0.25 0.1\nKs 0.5 0.5 0.5\nNs 98\nd 0.3\n\n"
                                    "newmtl matte\nKd 0.2 0.2 0.2\nKs 0 0 0\n")
    (tmp_path / "m.obj").write_text("mtllib m.mtl\nv -1 -1 3\nv 1 -1 3\nv 0 1 3\nv 0 1 4\n"
                                    "usemtl shiny\nf 1 2 3\nusemtl matte\nf 1 2 4\n")
    s = sg.Scene()
    res = s.load_mesh_file(str(tmp_path / "m.obj"))
    infos = [s.material_info(m) for m in res["material_ids"]]
    shiny = next(i["params"] for i in infos if i["type"] == "principled")
    # A purely Lambertian MTL material (Ks = 0, opaque) imports as the exact "diffuse".
    diffuse = [[round(c, 3) for c in i["params"]["albedo"]] for i in infos if i["type"] == "diffuse"]
    assert [0.2, 0.2, 0.2] in diffuse
    assert [round(c, 3) for c in shiny["base_color"]] == [0.5, 0.25, 0.1]
    # roughness = sqrt(2 / (Ns + 2)) (Walter et al. 2007's Phong-Beckmann relation).
    assert shiny["roughness"] == pytest.approx(math.sqrt(2 / 100))
    assert shiny["specular"] == pytest.approx(1.0)  # F0 = min(lum(Ks), 0.08) = 0.08
    assert shiny["alpha_mode"] == "blend" and shiny["alpha_factor"] == pytest.approx(0.3)
    assert sum(i["type"] == "principled" for i in infos) == 1


@pytest.mark.parametrize("ext, emits", [(".ac", False), (".obj", True)])
def test_ac3d_emis_is_not_a_light(tmp_path, ext, emits):
    """AC3D's "emis" (OpenGL fixed-function emission: TORCS gives every car 0.2) is not read
    as emission -- it made whole car bodies glow -- while an OBJ's Ke still is."""
    if ext == ".ac":
        (tmp_path / "m.ac").write_text(
            "AC3Db\nMATERIAL \"body\" rgb 0.8 0.8 0.8 amb 1 1 1 emis 0.2 0.2 0.2 spec 0.5 0.5 0.5 shi 50 trans 0\n"
            "OBJECT world\nkids 1\nOBJECT poly\nname \"tri\"\nnumvert 3\n-1 -1 3\n1 -1 3\n0 1 3\nnumsurf 1\nSURF 0x10\n"
            "mat 0\nrefs 3\n0 0 0\n1 0 0\n2 0 0\nkids 0\n")
    else:
        (tmp_path / "m.mtl").write_text("newmtl body\nKd 0.8 0.8 0.8\nKe 0.2 0.2 0.2\n")
        (tmp_path / "m.obj").write_text("mtllib m.mtl\nv -1 -1 3\nv 1 -1 3\nv 0 1 3\nusemtl body\nf 1 2 3\n")
    s = sg.Scene()
    res = s.load_mesh_file(str(tmp_path / f"m{ext}"))
    infos = [s.material_info(m) for m in res["material_ids"]]
    glows = any(i["type"] == "emissive" or any(k.startswith("emission") and v not in (0, 0.0, [0.0, 0.0, 0.0])
                                               for k, v in i["params"].items()) for i in infos)
    assert glows == emits, infos
