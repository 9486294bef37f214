"""Projective texture mapping ("projector" texture): a projector coinciding with the camera
reproduces the projected image in the albedo output; outside its frustum the mask is 0."""
from __future__ import annotations

import numpy as np
import OpenImageIO as oiio

import synthgen as sg
from synthgen import primitives as P

W, H = 80, 60


def write_image(path, img):
    out = oiio.ImageOutput.create(path)
    assert out.open(path, oiio.ImageSpec(img.shape[1], img.shape[0], 3, oiio.FLOAT))
    out.write_image(np.ascontiguousarray(img, np.float32))
    out.close()


def smooth_image():
    y, x = np.mgrid[0:H, 0:W].astype(np.float32)
    r = 0.5 + 0.4 * np.sin(x / W * 2 * np.pi)
    g = 0.2 + 0.7 * y / H
    b = 0.5 + 0.4 * np.cos((x + y) / (W + H) * 3 * np.pi)
    return np.stack([r, g, b], axis=-1)


def render(tmp_path, projector_params, mesh="box"):
    path = str(tmp_path / "proj.exr")
    write_image(path, smooth_image())
    s = sg.Scene()
    m = P.box((2.0, 2.0, 2.0)) if mesh == "box" else P.uv_sphere(1.2, 64, 32)
    mid = s.add_mesh(m["positions"], m["indices"], normals=m["normals"])  # no uvs: projection only
    img = s.add_texture("image", {"filename": path, "colorspace": "linear", "wrap": "clamp"})
    pr = s.add_texture("projector", dict(projector_params, texture=sg.TextureRef(img)))
    mat = s.add_material("diffuse", {"albedo": sg.TextureRef(pr)})
    s.add_instance(mid, P.rotate([0, 1, 0], 35), class_id=1, material_id=mat)
    s.add_light("environment", {"radiance": 1.0})
    wfc = sg.PinholeCamera.look_at((0.4, 1.0, -4.0), (0.0, 0.0, 0.0), (0.0, 1.0, 0.0))
    cam = sg.PinholeCamera.from_fov(45.0, W, H, wfc)
    s.set_camera(cam)
    return s.render(spp=1, labels_only=True), cam, wfc


def test_projector_at_the_camera_reproduces_the_image(tmp_path):
    wfc = sg.PinholeCamera.look_at((0.4, 1.0, -4.0), (0.0, 0.0, 0.0), (0.0, 1.0, 0.0))
    K = sg.PinholeCamera.from_fov(45.0, W, H, wfc).K
    params = {"world_from_projector": np.asarray(wfc, np.float64).ravel().tolist(), "fx": float(K[0][0]),
              "fy": float(K[1][1]), "cx": float(K[0][2]), "cy": float(K[1][2]), "width": float(W), "height": float(H)}
    for mesh in ("box", "sphere"):
        r, cam, _ = render(tmp_path, params, mesh)
        hit = r.instance_id > 0
        assert hit.sum() > 0.2 * W * H
        err = np.abs(np.asarray(r.albedo) - smooth_image())[hit]
        print(f"\n[projector {mesh}] mean |albedo - image| = {err.mean():.4f}, max = {err.max():.4f} over {hit.sum()} px")
        assert err.mean() < 0.01 and np.percentile(err, 99) < 0.05


def test_mask_is_zero_outside_the_frustum(tmp_path):
    # A narrow projector from another position, looking at the object: mask output.
    params = {"position": [-2.0, 2.0, -3.0], "look_at": [0.0, 0.0, 0.0], "fov": 15.0, "width": 1.0, "height": 1.0,
              "output": "mask"}
    r, cam, wfc = render(tmp_path, params)
    hit = r.instance_id > 0
    mask = np.asarray(r.albedo)[..., 0]
    # Expected: project each pixel-centre hit point into the projector (reconstructed from depth).
    K = np.asarray(cam.K, np.float64)
    y, x = np.mgrid[0:H, 0:W].astype(np.float64) + 0.5
    z = np.asarray(r.depth, np.float64)
    z = np.where(np.isfinite(z), z, 1.0)  # background pixels (inf depth) are excluded below
    pc = np.stack([(x - K[0, 2]) / K[0, 0] * z, (y - K[1, 2]) / K[1, 1] * z, z, np.ones_like(z)], -1)
    pw = pc @ np.asarray(wfc, np.float64).T
    wfp = np.asarray(sg.PinholeCamera.look_at((-2.0, 2.0, -3.0), (0.0, 0.0, 0.0), (0.0, 1.0, 0.0)), np.float64)
    pp = pw @ np.linalg.inv(wfp).T
    f = 0.5 / np.tan(np.radians(7.5))
    u, v = f * pp[..., 0] / pp[..., 2] + 0.5, f * pp[..., 1] / pp[..., 2] + 0.5
    inside = (pp[..., 2] > 0) & (u >= 0) & (u <= 1) & (v >= 0) & (v <= 1)
    # Away from the frustum's border (float round-off of the reconstruction), exact agreement.
    margin = (np.minimum.reduce([u, 1 - u, v, 1 - v]) > 0.01) | ~inside
    sel = hit & margin
    assert np.all(mask[sel & inside] == 1.0) and np.all(mask[sel & ~inside] == 0.0)
    assert (hit & inside).sum() > 50 and (hit & ~inside).sum() > 50, "both sides of the frustum are visible"


def test_decal_occlusion_keeps_hidden_surfaces_clean(tmp_path):
    """A small box in front of a big one, as seen from the projector: with the occlusion test
    the big box stays clean in the small box's "shadow"; without it the decal covers it all."""
    from synthgen import wear

    path = str(tmp_path / "white.exr")
    write_image(path, np.ones((8, 8, 3), np.float32))

    def render(occlusion):
        s = sg.Scene()
        b = P.box((1.0, 1.0, 1.0))
        m = s.add_mesh(b["positions"], b["indices"], normals=b["normals"])
        base = s.add_material("diffuse", {"albedo": 0.1})
        s.set_camera(sg.PinholeCamera.from_fov(45.0, 64, 64,
                                               sg.PinholeCamera.look_at((2.5, 0.5, -5.0), (0.0, 0.0, 1.5), (0, 1, 0))))
        small = s.add_instance(m, P.translate([0.0, 0.0, 0.0]) @ P.scale(0.6), class_id=1, material_id=base)
        big = s.add_instance(m, P.translate([0.0, 0.0, 3.0]) @ P.scale(2.5), class_id=2, material_id=base)
        mat = wear.decal(s, base, path, position=[0.0, 0.0, -4.0], look_at=[0.0, 0.0, 3.0], fov=30.0,
                         occlusion=occlusion)
        s.set_instance_material(small, mat)
        s.set_instance_material(big, mat)
        s.add_light("environment", {"radiance": 1.0})
        r = s.render(spp=1, labels_only=True)
        alb = np.asarray(r.albedo)[..., 0]
        return alb[r.class_id == 1], alb[r.class_id == 2]

    s_occ, b_occ = render(True)
    s_all, b_all = render(False)
    assert (s_occ > 0.9).mean() > 0.2 and (s_all > 0.9).mean() > 0.2, "the small box carries the decal"
    assert (b_all > 0.9).mean() > 0.5, "without occlusion the decal covers the big box's face"
    assert (b_all > 0.9).mean() - (b_occ > 0.9).mean() > 0.03, "with occlusion the shadowed part stays clean"


def test_facing_keeps_the_projection_off_faces_turned_away(tmp_path):
    """With `facing`, a wide projector's mask is 1 exactly on the visible faces whose normal
    points towards the projector (a box: the faces turned away stay 0, inside the frustum)."""
    eye = np.array([-3.0, 2.5, -3.0])
    params = {"position": eye.tolist(), "look_at": [0.0, 0.0, 0.0], "fov": 80.0, "output": "mask"}
    r_all, cam, wfc = render(tmp_path, params)
    r_face, _, _ = render(tmp_path, dict(params, facing=True))
    hit = r_all.instance_id > 0
    K = np.asarray(cam.K, np.float64)
    y, x = np.mgrid[0:H, 0:W].astype(np.float64) + 0.5
    z = np.where(np.isfinite(np.asarray(r_all.depth, np.float64)), np.asarray(r_all.depth, np.float64), 1.0)
    pc = np.stack([(x - K[0, 2]) / K[0, 0] * z, (y - K[1, 2]) / K[1, 1] * z, z, np.ones_like(z)], -1)
    pw = (pc @ np.asarray(wfc, np.float64).T)[..., :3]
    n = np.asarray(r_all.normal, np.float64)
    towards = np.einsum("ijk,ijk->ij", n, eye - pw) > 0
    m_all, m_face = np.asarray(r_all.albedo)[..., 0], np.asarray(r_face.albedo)[..., 0]
    assert np.all(m_all[hit] == 1.0), "the frustum covers the whole box"
    assert np.all(m_face[hit & towards] == 1.0) and np.all(m_face[hit & ~towards] == 0.0)
    assert (hit & towards).sum() > 100 and (hit & ~towards).sum() > 100, "both kinds of faces are visible"
