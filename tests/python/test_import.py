"""Mesh file import: glTF/GLB node transforms, base-colour textures resolved next to the file,
OBJ + MTL diffuse colours. Expectations are derived from the files themselves (the GLB's JSON
chunk and binary buffer, parsed here with json/numpy; the texture read with OpenImageIO)."""
from __future__ import annotations

import json
import os
import shutil
import struct

import numpy as np
import pytest

import synthgen as sg

REPO = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
KENNEY = os.path.abspath(os.path.join(REPO, "..", "shared", "assets", "kenney"))
TRUCK = os.path.join(KENNEY, "vehicle-truck-red.glb")
ASSIMP_GLTF2 = "/usr/share/assimp/models/glTF2"

needs_kenney = pytest.mark.skipif(
    not os.path.isfile(TRUCK),
    reason=f"shared test data not found: {TRUCK} (expected <repo>/../shared, see ../shared/README.md)")


# GLB parsing (glTF 2.0 binary container) ----------------------------------------------------

def read_glb(path: str):
    with open(path, "rb") as f:
        data = f.read()
    magic, version, length = struct.unpack_from("<4sII", data, 0)
    assert magic == b"glTF" and version == 2 and length == len(data)
    doc, bin_chunk, off = None, b"", 12
    while off < length:
        clen, ctype = struct.unpack_from("<I4s", data, off)
        chunk = data[off + 8:off + 8 + clen]
        if ctype == b"JSON":
            doc = json.loads(chunk)
        elif ctype == b"BIN\x00":
            bin_chunk = chunk
        off += 8 + clen
    return doc, bin_chunk


_COMPONENTS = {5120: np.int8, 5121: np.uint8, 5122: np.int16, 5123: np.uint16, 5125: np.uint32, 5126: np.float32}
_WIDTH = {"SCALAR": 1, "VEC2": 2, "VEC3": 3, "VEC4": 4, "MAT4": 16}


def accessor(doc, bin_chunk, index) -> np.ndarray:
    a = doc["accessors"][index]
    view = doc["bufferViews"][a["bufferView"]]
    dtype = np.dtype(_COMPONENTS[a["componentType"]])
    width = _WIDTH[a["type"]]
    start = view.get("byteOffset", 0) + a.get("byteOffset", 0)
    stride = view.get("byteStride", dtype.itemsize * width)
    rows = [np.frombuffer(bin_chunk, dtype, width, start + i * stride) for i in range(a["count"])]
    return np.array(rows).reshape(a["count"], width)


def _quat_matrix(q):
    x, y, z, w = q
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def node_matrix(node) -> np.ndarray:
    if "matrix" in node:
        return np.asarray(node["matrix"], dtype=np.float64).reshape(4, 4).T  # column-major
    m = np.eye(4)
    m[:3, :3] = _quat_matrix(node.get("rotation", [0, 0, 0, 1])) @ np.diag(node.get("scale", [1, 1, 1]))
    m[:3, 3] = node.get("translation", [0, 0, 0])
    return m


def world_mesh_nodes(doc):
    """(world matrix, mesh index) for every mesh node of the default scene."""
    out = []

    def visit(i, parent):
        node = doc["nodes"][i]
        world = parent @ node_matrix(node)
        if "mesh" in node:
            out.append((world, node["mesh"]))
        for c in node.get("children", []):
            visit(c, world)

    for root in doc["scenes"][doc.get("scene", 0)]["nodes"]:
        visit(root, np.eye(4))
    return out


def expected_bounds(doc):
    """World bounds from the POSITION accessors' min/max transformed by the node matrices."""
    lo, hi = np.full(3, np.inf), np.full(3, -np.inf)
    for world, mesh in world_mesh_nodes(doc):
        for prim in doc["meshes"][mesh]["primitives"]:
            a = doc["accessors"][prim["attributes"]["POSITION"]]
            corners = np.array([[x, y, z, 1.0] for x in (a["min"][0], a["max"][0])
                                for y in (a["min"][1], a["max"][1]) for z in (a["min"][2], a["max"][2])])
            p = (world @ corners.T).T[:, :3]
            lo, hi = np.minimum(lo, p.min(0)), np.maximum(hi, p.max(0))
    return lo, hi


def read_texture_linear(path: str) -> np.ndarray:
    import OpenImageIO as oiio

    buf = oiio.ImageBuf(path)
    px = buf.get_pixels(oiio.FLOAT)[:, :, :3].astype(np.float64)
    return np.where(px <= 0.04045, px / 12.92, ((px + 0.055) / 1.055) ** 2.4)


def texels_under_uvs(doc, bin_chunk, tex_h, tex_w, flip_v=False) -> np.ndarray:
    """Mask of the texels that the triangles' UV footprints (their UV bounding boxes, dilated by
    one texel for bilinear filtering) can sample. glTF's UV origin is the top-left of the image."""
    mask = np.zeros((tex_h, tex_w), dtype=bool)
    for _, mesh in world_mesh_nodes(doc):
        for prim in doc["meshes"][mesh]["primitives"]:
            uv = accessor(doc, bin_chunk, prim["attributes"]["TEXCOORD_0"]).astype(np.float64)
            if flip_v:
                uv[:, 1] = 1.0 - uv[:, 1]
            idx = accessor(doc, bin_chunk, prim["indices"]).reshape(-1, 3).astype(np.int64)
            t = uv[idx]  # triangles x 3 x 2
            lo, hi = t.min(axis=1), t.max(axis=1)
            for (u0, v0), (u1, v1) in zip(lo, hi):
                c0, c1 = int(np.floor(u0 * tex_w - 0.5)) - 1, int(np.ceil(u1 * tex_w - 0.5)) + 1
                r0, r1 = int(np.floor(v0 * tex_h - 0.5)) - 1, int(np.ceil(v1 * tex_h - 0.5)) + 1
                mask[max(r0, 0):min(r1, tex_h - 1) + 1, max(c0, 0):min(c1, tex_w - 1) + 1] = True
    return mask


def nearest_colour_distance(colours: np.ndarray, palette: np.ndarray) -> np.ndarray:
    palette = np.unique(np.round(palette, 6), axis=0)
    out = np.empty(len(colours))
    for i in range(0, len(colours), 512):
        c = colours[i:i + 512]
        out[i:i + 512] = np.sqrt(((c[:, None, :] - palette[None, :, :]) ** 2).sum(-1)).min(1)
    return out


# Kenney truck (GLB with node transforms and an external texture) -------------------------------

@pytest.fixture(scope="module")
def truck():
    s = sg.Scene()
    res = s.load_mesh_file(TRUCK)
    return s, res


@needs_kenney
def test_glb_node_transforms_are_applied(truck):
    s, res = truck
    doc, _ = read_glb(TRUCK)
    lo, hi = expected_bounds(doc)
    pos = s.mesh_arrays(res["mesh_id"])["positions"]
    np.testing.assert_allclose(pos.min(0), lo, atol=1e-4)
    np.testing.assert_allclose(pos.max(0), hi, atol=1e-4)
    # Sanity of the expectation itself: the nodes do move the meshes (ignoring them would give
    # different bounds), so the comparison above tests the node transforms.
    lo0 = np.min([doc["accessors"][p["attributes"]["POSITION"]]["min"] for m in doc["meshes"]
                  for p in m["primitives"]], axis=0)
    assert np.abs(lo0 - lo).max() > 0.1


@needs_kenney
def test_glb_triangle_count_matches_file(truck):
    s, res = truck
    doc, _ = read_glb(TRUCK)
    n_file = sum(doc["accessors"][p["indices"]]["count"] // 3 for _, m in world_mesh_nodes(doc)
                 for p in doc["meshes"][m]["primitives"])
    m = s.mesh_arrays(res["mesh_id"])
    assert len(m["indices"]) + res["removed_degenerate"] == n_file
    assert len(m["material_ids"]) == len(m["indices"]) and set(m["material_ids"]) <= set(res["material_ids"])
    assert m["has_uvs"] and m["has_normals"]


@needs_kenney
def test_glb_texture_resolved_and_sampled(truck):
    s, res = truck
    doc, bin_chunk = read_glb(TRUCK)
    # assimp may add its default material next to the file's own
    assert len(res["texture_ids"]) == 1 and len(res["material_ids"]) >= len(doc["materials"])
    tex_path = os.path.join(KENNEY, doc["images"][0]["uri"])
    assert os.path.isfile(tex_path)
    inst = s.add_instance(res["mesh_id"], instance_id=1)
    s.set_camera(sg.PinholeCamera.from_fov(35, 128, 96, sg.PinholeCamera.look_at([3.5, 2.5, 4.0], [0, 0.6, 0])))
    r = s.render(spp=1, max_depth=1)
    mask = r.instance_id == 1
    assert mask.sum() > 2000
    albedo = r.albedo[mask].astype(np.float64)
    # Textured: many distinct albedo values.
    assert len(np.unique(albedo, axis=0)) > 20 and albedo.std(axis=0).max() > 0.05

    # The albedo comes from the texels under the mesh's UVs in colormap.png (sRGB decoded).
    tex = read_texture_linear(tex_path)
    allowed = texels_under_uvs(doc, bin_chunk, *tex.shape[:2])
    d = nearest_colour_distance(albedo, tex[allowed])
    frac = float(np.mean(d < 0.02))
    # The criterion discriminates: with the UV convention flipped, the same pixels do not match.
    d_flip = nearest_colour_distance(albedo, tex[texels_under_uvs(doc, bin_chunk, *tex.shape[:2], flip_v=True)])
    frac_flip = float(np.mean(d_flip < 0.02))
    print(f"\n[truck] {mask.sum()} px, {frac:.1%} match texels under the UVs (V flipped: {frac_flip:.1%})")
    assert frac > 0.95
    assert frac_flip < 0.8
    s.remove_instance(inst)


@needs_kenney
def test_glb_texture_is_resolved_relative_to_the_file(tmp_path, monkeypatch):
    # Next to the file in another directory, loaded from an unrelated working directory.
    d = tmp_path / "copy"
    d.mkdir()
    shutil.copy(TRUCK, d / "truck.glb")
    shutil.copytree(os.path.join(KENNEY, "Textures"), d / "Textures")
    monkeypatch.chdir(tmp_path)
    res = sg.Scene().load_mesh_file(str(d / "truck.glb"))
    assert len(res["texture_ids"]) == 1
    # Without the texture next to it: a FileError naming the file and the missing texture.
    lone = tmp_path / "lone"
    lone.mkdir()
    shutil.copy(TRUCK, lone / "truck.glb")
    with pytest.raises(sg.FileError, match="truck.glb") as e:
        sg.Scene().load_mesh_file(str(lone / "truck.glb"))
    assert "colormap.png" in str(e.value)


# Embedded textures (a valid Khronos sample model shipped by assimp-testmodels) ----------------

@pytest.mark.skipif(not os.path.isdir(ASSIMP_GLTF2),
                    reason=f"{ASSIMP_GLTF2} not found: install the Debian package assimp-testmodels")
@pytest.mark.parametrize("path", ["BoxTextured-glTF-Binary/BoxTextured.glb", "BoxTextured-glTF-Embedded/BoxTextured.gltf"])
def test_gltf_with_embedded_png_texture_loads(path):
    """Khronos' BoxTextured sample with its PNG inside the file (GLB buffer view / data URI):
    the texture must be decoded and sampled, like the external-file variant."""
    s = sg.Scene()
    res = s.load_mesh_file(os.path.join(ASSIMP_GLTF2, path))
    assert len(res["texture_ids"]) == 1
    s.add_instance(res["mesh_id"], instance_id=1)
    s.set_camera(sg.PinholeCamera.from_fov(40, 64, 64, sg.PinholeCamera.look_at([1.5, 1.2, 2.0], [0, 0, 0])))
    r = s.render(spp=1, max_depth=1)
    albedo = r.albedo[r.instance_id == 1]
    assert len(albedo) > 500 and len(np.unique(albedo, axis=0)) > 10


# OBJ + MTL -------------------------------------------------------------------------------------

def test_obj_mtl_diffuse_colours_become_albedo(tmp_path):
    kd = {"red": (0.8, 0.1, 0.2), "green": (0.1, 0.6, 0.3), "blue": (0.05, 0.15, 0.7)}
    (tmp_path / "quads.mtl").write_text("".join(f"newmtl {n}\nKd {r} {g} {b}\n\n" for n, (r, g, b) in kd.items()))
    # Three unit quads side by side in the z = 3 plane, facing -z (towards a camera at the origin).
    lines = ["mtllib quads.mtl"]
    for k in range(3):
        x0 = -1.5 + k
        lines += [f"v {x0} -0.5 3", f"v {x0} 0.5 3", f"v {x0 + 1} 0.5 3", f"v {x0 + 1} -0.5 3"]
    for k, name in enumerate(kd):
        b = 4 * k + 1
        lines += [f"usemtl {name}", f"f {b} {b + 1} {b + 2} {b + 3}"]
    (tmp_path / "quads.obj").write_text("\n".join(lines) + "\n")

    s = sg.Scene()
    res = s.load_mesh_file(str(tmp_path / "quads.obj"))
    assert len(res["material_ids"]) >= 3 and res["texture_ids"] == []
    s.add_instance(res["mesh_id"], instance_id=1)
    # f = 120: the quads fill the 120 x 40 image, quad k covers columns [40 k, 40 k + 40).
    s.set_camera(sg.PinholeCamera(fx=120, fy=120, cx=60, cy=20, width=120, height=40))
    r = s.render(spp=1, max_depth=1)
    assert np.all(r.instance_id[1:39, 1:119] == 1)
    for k, c in enumerate(kd.values()):
        block = r.albedo[1:39, 40 * k + 1:40 * k + 39]
        np.testing.assert_allclose(block, np.broadcast_to(np.float32(c), block.shape), rtol=0, atol=1e-6)


def test_obj_without_mtl_gets_default_material(tmp_path):
    (tmp_path / "t.obj").write_text("v -1 -1 3\nv 1 -1 3\nv 0 1 3\nf 1 2 3\n")
    s = sg.Scene()
    res = s.load_mesh_file(str(tmp_path / "t.obj"))
    s.add_instance(res["mesh_id"], instance_id=1)
    s.set_camera(sg.PinholeCamera(fx=20, fy=20, cx=16, cy=16, width=32, height=32))
    r = s.render(spp=1, max_depth=1)
    a = r.albedo[r.instance_id == 1]
    assert len(a) > 50
    # One uniform grey-ish albedo (assimp's default material or synthgen's default).
    assert np.all(a == a[0]) and np.all((a[0] > 0) & (a[0] <= 1))
