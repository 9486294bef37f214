"""Triplanar (box) mapping of an image onto a model without uvs."""
from __future__ import annotations

import numpy as np
import OpenImageIO as oiio

import synthgen as sg
from synthgen import primitives as P

W, H = 96, 96


def checker(path, n=64, checks=4):
    i, j = np.mgrid[0:n, 0:n]
    c = ((i // (n // checks) + j // (n // checks)) % 2).astype(np.float32)
    img = np.repeat((0.1 + 0.8 * c)[..., None], 3, axis=2)
    out = oiio.ImageOutput.create(path)
    assert out.open(path, oiio.ImageSpec(n, n, 3, oiio.FLOAT))
    out.write_image(img)
    out.close()


def test_triplanar_projects_the_image_on_each_face(tmp_path):
    path = str(tmp_path / "checker.exr")
    checker(path)
    s = sg.Scene()
    b = P.box((1.0, 1.0, 1.0))
    mesh = s.add_mesh(b["positions"], b["indices"], normals=b["normals"])  # no uvs
    img = s.add_texture("image", {"filename": path, "colorspace": "linear", "wrap": "repeat"})
    tri = s.add_texture("triplanar", {"texture": sg.TextureRef(img), "scale": 1.0, "sharpness": 64})
    s.add_instance(mesh, None, class_id=1, material_id=s.add_material("diffuse", {"albedo": sg.TextureRef(tri)}))
    s.add_light("environment", {"radiance": 1.0})
    wfc = np.asarray(sg.PinholeCamera.look_at((2.0, 1.6, -2.4), (0.0, 0.0, 0.0), (0.0, 1.0, 0.0)), np.float64)
    cam = sg.PinholeCamera.from_fov(40.0, W, H, wfc)
    s.set_camera(cam)
    r = s.render(spp=1, labels_only=True, texture_filtering=False)
    hit = r.instance_id > 0
    K = np.asarray(cam.K, np.float64)
    y, x = np.mgrid[0:H, 0:W].astype(np.float64) + 0.5
    z = np.where(np.isfinite(r.depth), r.depth, 1.0)
    pc = np.stack([(x - K[0, 2]) / K[0, 0] * z, (y - K[1, 2]) / K[1, 1] * z, z, np.ones_like(z)], -1)
    p = (pc @ wfc.T)[..., :3]
    face = np.argmax(np.abs(p), axis=-1)  # the axis the point's face is normal to
    # Projected coordinates: x face -> (z, y), y face -> (x, z), z face -> (x, y); checks 0.25 wide.
    u = np.choose(face, [p[..., 2], p[..., 0], p[..., 0]])
    v = np.choose(face, [p[..., 1], p[..., 2], p[..., 1]])
    # Image t = 1 - v (rows down); the check parity is the same either way for 4 checks per unit.
    parity = ((np.floor(u * 4) + np.floor((1 - v) * 4)) % 2).astype(int)
    expect = np.where(parity == 1, 0.9, 0.1)
    frac_u, frac_v = (u * 4) % 1, (v * 4) % 1
    inside = hit & (np.minimum(frac_u, 1 - frac_u) > 0.15) & (np.minimum(frac_v, 1 - frac_v) > 0.15)
    got = np.asarray(r.albedo)[..., 0]
    assert inside.sum() > 300
    agree = np.abs(got[inside] - expect[inside]) < 0.1
    assert agree.mean() > 0.97, f"{agree.mean():.3f} of the pixels show the projected check"
    # Every visible face shows both check colours.
    for f in range(3):
        sel = inside & (face == f)
        if sel.sum() > 30:
            assert (got[sel] < 0.3).any() and (got[sel] > 0.7).any()
