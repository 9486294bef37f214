"""Writes the seed corpora of the fuzz targets into fuzz/corpus/<target>/seed-*.

    .venv/bin/python tools/make_fuzz_seeds.py

Small inputs of our own making (a scene saved by Scene.save, models written here, images
written through OpenImageIO, plugin parameter bytes), so nothing of a third party is
committed; bench/fuzz.sh adds Debian's assimp-testmodels and the scenarios/ files to a
working corpus when it runs. Inputs that once crashed a target go next to the seeds as
crash-* files and are replayed by `make test`.
"""
from __future__ import annotations

import os
import sys
import tempfile

import numpy as np

import synthgen as sg
from synthgen import primitives as P
from synthgen.outputs.files import write_exr, write_srgb_png

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), ".."))
CORPUS = os.path.join(ROOT, "fuzz", "corpus")


def put(target: str, name: str, data: bytes) -> None:
    d = os.path.join(CORPUS, target)
    os.makedirs(d, exist_ok=True)
    with open(os.path.join(d, "seed-" + name), "wb") as f:
        f.write(data)


def scene_xml(tmp: str) -> None:
    s = sg.Scene()
    box = s.add_mesh(**P.box((1, 1, 1)))
    tex = s.add_image_texture(np.linspace(0, 1, 12, dtype=np.float32).reshape(2, 2, 3), {"wrap": "clamp"})
    a = s.add_material("diffuse", {"albedo": sg.TextureRef(tex)})
    b = s.add_material("conductor", {"metal": "gold", "roughness": 0.2})
    m = s.add_material("mix", {"material_a": a, "material_b": b, "weight": 0.3})
    i = s.add_instance(box, P.translate([0, 0.5, 0]), class_id=1, material_id=m)
    s.add_instance(box, P.translate([2, 0.5, 0]), class_id=2)
    s.set_instance_material_map(i, {-1: a})
    s.add_light("sun", {"elevation": 40, "azimuth": 10})
    s.set_camera(sg.PinholeCamera.from_fov(40, 32, 24, sg.PinholeCamera.look_at([0, 2, -5], [0, 0.5, 0])))
    path = os.path.join(tmp, "scene.xml")  # the name fuzz_scene_xml writes (the sidecar is "scene.xml.bin")
    s.save(path)
    xml = open(path, "rb").read()
    binary = open(path + ".bin", "rb").read()
    put("fuzz_scene_xml", "scene", xml + b"\0BIN\0" + binary)
    put("fuzz_scene_xml", "xml-only", xml)


def journal(tmp: str) -> None:
    """A change journal (Scene.save_journal) with every kind of edit, for fuzz_journal."""
    s = sg.Scene()
    s.begin_journal()
    box = s.add_mesh(**P.box((1, 1, 1)))
    tex = s.add_image_texture(np.linspace(0, 1, 12, dtype=np.float32).reshape(2, 2, 3), {"wrap": "clamp"})
    a = s.add_material("diffuse", {"albedo": sg.TextureRef(tex)})
    b = s.add_material("conductor", {"metal": "gold", "roughness": 0.2})
    i = s.add_instance(box, P.translate([0, 0.5, 0]), class_id=1, material_id=a)
    j = s.add_instance(box, P.translate([2, 0.5, 0]), class_id=2)
    s.set_instance_material_map(i, {-1: b})
    light = s.add_light("sun", {"elevation": 40, "azimuth": 10})
    s.set_camera(sg.PinholeCamera.from_fov(40, 32, 24, sg.PinholeCamera.look_at([0, 2, -5], [0, 0.5, 0])))
    s.commit()
    s.set_instance_visible(j, False)
    s.set_instance_transform(i, P.translate([0, 0.6, 0]))
    s.update_material(b, "conductor", {"metal": "copper"})
    s.remove_light(light)
    s.set_medium("homogeneous", {"visibility": 300.0})
    s.commit()
    path = os.path.join(tmp, "journal.xml")  # the name fuzz_journal writes (the sidecar is "journal.xml.bin")
    s.save_journal(path)
    xml = open(path, "rb").read()
    binary = open(path + ".bin", "rb").read()
    put("fuzz_journal", "journal", xml + b"\0BIN\0" + binary)
    put("fuzz_journal", "xml-only", xml)


def meshes() -> None:
    obj = b"mtllib none.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nvn 0 0 1\nvt 0 0\nvt 1 0\nvt 0 1\nusemtl a\nf 1/1/1 2/2/1 3/3/1\nf 2 4 3\n"
    put("fuzz_mesh_import", "tri.obj", bytes([0]) + obj)
    ply = (b"ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
           b"element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n")
    put("fuzz_mesh_import", "tri.ply", bytes([1]) + ply)
    import base64
    import json
    import struct

    buf = struct.pack("<9f", 0, 0, 0, 1, 0, 0, 0, 1, 0) + struct.pack("<3H", 0, 1, 2) + b"\0\0"
    gltf = {"asset": {"version": "2.0"}, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}],
            "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
            "buffers": [{"byteLength": len(buf), "uri": "data:application/octet-stream;base64,"
                         + base64.b64encode(buf).decode()}],
            "bufferViews": [{"buffer": 0, "byteOffset": 0, "byteLength": 36}, {"buffer": 0, "byteOffset": 36,
                                                                                 "byteLength": 6}],
            "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                           "min": [0, 0, 0], "max": [1, 1, 0]},
                          {"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"}]}
    text = json.dumps(gltf).encode()
    put("fuzz_mesh_import", "tri.gltf", bytes([2]) + text)
    gjson = json.dumps(dict(gltf, buffers=[{"byteLength": len(buf)}])).encode()
    gjson += b" " * (-len(gjson) % 4)
    glb = struct.pack("<4sII", b"glTF", 2, 12 + 8 + len(gjson) + 8 + len(buf))
    glb += struct.pack("<I4s", len(gjson), b"JSON") + gjson + struct.pack("<I4s", len(buf), b"BIN\0") + buf
    put("fuzz_mesh_import", "tri.glb", bytes([3]) + glb)


def images(tmp: str) -> None:
    img = (np.indices((6, 5)).sum(0)[..., None] * np.array([0.1, 0.05, 0.02])).astype(np.float32)
    for i, (ext, write) in enumerate([("png", write_srgb_png), ("exr", write_exr)]):
        path = os.path.join(tmp, "i." + ext)
        write(path, np.clip(img, 0, 1))
        hint = {"png": 0, "exr": 2}[ext]
        put("fuzz_image", "img." + ext, bytes([hint]) + open(path, "rb").read())
    import OpenImageIO as oiio

    for ext, hint in (("jpg", 1), ("hdr", 3), ("tga", 4), ("bmp", 5)):
        path = os.path.join(tmp, "i." + ext)
        out = oiio.ImageOutput.create(path)
        out.open(path, oiio.ImageSpec(5, 6, 3, oiio.UINT8 if ext != "hdr" else oiio.FLOAT))
        out.write_image(np.clip(img, 0, 1) if ext == "hdr" else (np.clip(img, 0, 1) * 255).astype(np.uint8))
        out.close()
        put("fuzz_image", "img." + ext, bytes([hint]) + open(path, "rb").read())


def photos(tmp: str) -> None:
    """fuzz_photo: small photos, whole, truncated and corrupted (first byte: 0 jpg, 1 png, 2 exr)."""
    import OpenImageIO as oiio

    rng = np.random.default_rng(3)
    img = (rng.random((24, 32, 3)) * 0.8 + 0.1).astype(np.float32)
    for ext, hint in (("jpg", 0), ("png", 1), ("exr", 2)):
        path = os.path.join(tmp, "p." + ext)
        out = oiio.ImageOutput.create(path)
        spec = oiio.ImageSpec(32, 24, 3, oiio.HALF if ext == "exr" else oiio.UINT8)
        out.open(path, spec)
        out.write_image(img if ext == "exr" else (img * 255).astype(np.uint8))
        out.close()
        whole = open(path, "rb").read()
        put("fuzz_photo", f"{ext}-whole", bytes([hint]) + whole)
        for keep in (len(whole) // 4, len(whole) // 2, len(whole) - 40):
            put("fuzz_photo", f"{ext}-cut-{keep}", bytes([hint]) + whole[:keep])
        middle = bytearray(whole)
        for i in range(len(whole) // 2, len(whole) // 2 + 16):
            middle[i] ^= 0x5A
        put("fuzz_photo", f"{ext}-corrupt", bytes([hint]) + bytes(middle))
        if ext == "jpg":  # libjpeg's harmless "extraneous bytes before marker", then cut
            end = 4 + int.from_bytes(whole[4:6], "big")
            padded = whole[:end] + b"\x00\x01\x02" + whole[end:]
            put("fuzz_photo", "jpg-extraneous", bytes([hint]) + padded)
            put("fuzz_photo", "jpg-extraneous-cut", bytes([hint]) + padded[:-40])


def params() -> None:
    rng = np.random.default_rng(7)
    for i in range(24):
        put("fuzz_plugin_params", f"random-{i:02d}", rng.integers(0, 256, 64, dtype=np.uint8).tobytes())


def main() -> int:
    with tempfile.TemporaryDirectory() as tmp:
        scene_xml(tmp)
        journal(tmp)
        meshes()
        images(tmp)
        photos(tmp)
        params()
    print(f"wrote seeds under {os.path.relpath(CORPUS, ROOT)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
