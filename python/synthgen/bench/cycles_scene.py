"""Builds and renders a synthgen scene description with Blender Cycles (runs inside Blender).

Usage (``synthgen bench`` and bench/vs_cycles.py write the description and call this file;
bench/cycles_scene.py runs it too):

    blender -b --factory-startup --python-exit-code 1 -P python/synthgen/bench/cycles_scene.py -- scene.json

The argument after ``--`` is the path of a JSON scene description, or the JSON text itself.
It is the same description from which vs_cycles.py builds the synthgen scene:

    {"output": "out.exr", "width": W, "height": H, "spp": N, "max_depth": D, "threads": T, "seed": S,
     "camera": {"fx", "fy", "cx", "cy", "world_from_camera": 4x4 rows},      # OpenCV convention
     "meshes": [{"name", "positions": [[x, y, z]...], "indices": [[a, b, c]...], "normals": [...] or null}],
     "materials": [{"type": synthgen material plugin, "params": {...}}],
     "instances": [{"mesh": i, "material": j, "world_from_object": 4x4 rows}],
     "lights": [{"type": synthgen light plugin, "params": {...}}]}

Conversions (each checked numerically by `vs_cycles.py --check`):

* World coordinates are used as they are (Cycles has no preferred up axis; only the equirect
  lookup of an environment map depends on it, and that is converted in the world shader).
* Camera: Blender cameras look down local -Z with +Y up, so world_from_blender_camera =
  world_from_camera @ diag(1, -1, -1, 1). Focal length and sensor are given in pixels
  (sensor_fit HORIZONTAL, sensor_width = W, lens = fx; or VERTICAL for portrait images);
  the principal point becomes shift_x = (W/2 - cx) / max(W, H), shift_y = (cy - H/2) / max(W, H).
* max_depth (synthgen: ray segments from the camera, 2 = direct lighting) -> Cycles
  max_bounces = max_depth - 2 (Cycles: 0 = direct lighting only; the ray leaving the last
  bounce still collects emission, like synthgen's last segment).
* Lights: sun irradiance E [W/m^2] -> sun strength E; point intensity I [W/sr] -> point power
  P = 4 pi I [W], radius 0; constant environment radiance -> world Background colour.
* Materials: diffuse -> Diffuse BSDF; emissive -> Emission (masked to the front face unless
  two_sided) plus a Diffuse BSDF for its albedo; conductor / dielectric / coated -> Principled
  BSDF or Glass BSDF approximations (different models: see docs/benchmarks.md).

Keys starting with "_" in plugin parameters are hints for this script (ignored by synthgen):
`_blender_roughness`, `_blender_mapping` (3x3 world -> Blender equirect lookup direction),
`_blender_interpolation`. `cycles_max_bounces` at the top level overrides the bounce mapping.

Optional top-level render keys (default: off): `adaptive_sampling` (Cycles' own adaptive
sampling, `spp` is then the maximum), `adaptive_threshold` (0: Cycles' automatic value),
`adaptive_min_samples` (0: automatic), `time_limit` (seconds; 0: none).

Prints one line ``CYCLES_RESULT {json}`` with the timings (render_s = bpy.ops.render.render).
"""
import json
import math
import os
import sys
import time

try:  # importable outside Blender (the package's documentation and tests list every module)
    import bpy
    from mathutils import Matrix, Vector
except ImportError:  # pragma: no cover - only Blender runs this script
    bpy = Matrix = Vector = None


def _argv_spec():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    if not argv:
        raise SystemExit("cycles_scene.py: expected a scene description (JSON file or text) after --")
    arg = argv[0]
    if arg.lstrip().startswith("{"):
        return json.loads(arg)
    with open(arg) as f:
        return json.load(f)


def _rgb(v, default=(1.0, 1.0, 1.0)):
    if v is None:
        return list(default)
    if isinstance(v, (int, float)):
        return [float(v)] * 3
    v = [float(x) for x in v]
    if len(v) != 3:
        raise ValueError(f"expected an RGB triple, got {v}")
    return v


def _scaled(params, key, default):
    """Colour parameter times the plugin's `strength` (synthgen's convention for lights and emitters)."""
    c = _rgb(params.get(key, default), (default,) * 3 if isinstance(default, (int, float)) else default)
    s = float(params.get("strength", 1.0))
    return [x * s for x in c]


def _colour_and_energy(c):
    """Blender lights take a colour (kept within [0, 1]) and a scalar energy."""
    m = max(c)
    if m <= 0:
        return (0.0, 0.0, 0.0), 0.0
    return tuple(x / m for x in c), m


# ---------------------------------------------------------------------------------------------
# Materials


def _new_material(name):
    mat = bpy.data.materials.new(name)
    mat.use_nodes = True
    nt = mat.node_tree
    for n in list(nt.nodes):
        nt.nodes.remove(n)
    out = nt.nodes.new("ShaderNodeOutputMaterial")
    out.target = "CYCLES"
    return mat, nt, out


def _fresnel_f0_conductor(eta, k):
    return [((n - 1) ** 2 + kk ** 2) / ((n + 1) ** 2 + kk ** 2) for n, kk in zip(eta, k)]


# Complex IORs (eta, k) in linear sRGB of synthgen's conductor `metal` presets
# (cpp/material/conductor.cpp); "none" is synthgen's ideal mirror (Fresnel 1).
CONDUCTOR_PRESETS = {
    "aluminium": ([1.6575, 0.8804, 0.5212], [9.2239, 6.2695, 4.8370]),
    "aluminum": ([1.6575, 0.8804, 0.5212], [9.2239, 6.2695, 4.8370]),
    "chrome": ([4.3697, 2.9167, 1.6547], [5.2064, 4.2314, 3.7549]),
    "chromium": ([4.3697, 2.9167, 1.6547], [5.2064, 4.2314, 3.7549]),
    "copper": ([0.2004, 0.9240, 1.1022], [3.9129, 2.4528, 2.1422]),
    "gold": ([0.1431, 0.3750, 1.4425], [3.9832, 2.3857, 1.6032]),
    "iron": ([2.9114, 2.9497, 2.5845], [3.0893, 2.9318, 2.7670]),
    "silver": ([0.1553, 0.1167, 0.1384], [4.8283, 3.1222, 2.1470]),
    "none": ([1.0, 1.0, 1.0], [1e6, 1e6, 1e6]),
}


def _shader_for(m, nt, materials, depth=0):
    """Returns the output socket of the shader built for synthgen material description m."""
    t, p = m["type"], m.get("params", {})
    nodes, links = nt.nodes, nt.links
    if t == "diffuse":
        d = nodes.new("ShaderNodeBsdfDiffuse")
        d.inputs["Color"].default_value = (*_rgb(p.get("albedo", 0.5)), 1.0)
        d.inputs["Roughness"].default_value = 0.0  # Lambertian
        return d.outputs["BSDF"]
    if t == "emissive":
        e = nodes.new("ShaderNodeEmission")
        e.inputs["Color"].default_value = (*_scaled(p, "radiance", 1.0), 1.0)
        e.inputs["Strength"].default_value = 1.0  # Cycles: radiance = colour x strength
        sock = e.outputs["Emission"]
        if not p.get("two_sided", False):
            # synthgen emits from the front face only; Cycles emission is two-sided.
            geo = nodes.new("ShaderNodeNewGeometry")
            inv = nodes.new("ShaderNodeMath")
            inv.operation = "SUBTRACT"
            inv.inputs[0].default_value = 1.0
            links.new(geo.outputs["Backfacing"], inv.inputs[1])
            links.new(inv.outputs[0], e.inputs["Strength"])
        albedo = _rgb(p.get("albedo", 0.0), (0.0, 0.0, 0.0))
        if max(albedo) > 0:
            d = nodes.new("ShaderNodeBsdfDiffuse")
            d.inputs["Color"].default_value = (*albedo, 1.0)
            d.inputs["Roughness"].default_value = 0.0
            add = nodes.new("ShaderNodeAddShader")
            links.new(sock, add.inputs[0])
            links.new(d.outputs["BSDF"], add.inputs[1])
            sock = add.outputs[0]
        return sock
    if t == "conductor":
        # Principled metallic: Schlick-style Fresnel from the normal-incidence reflectance F0.
        if "eta" not in p:
            key = str(p.get("metal", "aluminium")).lower()
            eta, k = CONDUCTOR_PRESETS[key]
        else:
            eta, k = _rgb(p.get("eta", 0.2)), _rgb(p.get("k", 3.9))
        f0 = _fresnel_f0_conductor(eta, k)
        if "specular_tint" in p:
            f0 = [a * b for a, b in zip(f0, _rgb(p["specular_tint"]))]
        b = nodes.new("ShaderNodeBsdfPrincipled")
        b.distribution = "GGX"
        b.inputs["Base Color"].default_value = (*f0, 1.0)
        b.inputs["Metallic"].default_value = 1.0
        r, aniso = _principled_roughness(p), float(p.get("anisotropy", 0.0))
        if "roughness_u" in p or "roughness_v" in p:
            # synthgen: alpha_x = ru^2, alpha_y = rv^2. Principled: alpha = r^2, aspect = sqrt(1 - 0.9 a),
            # alpha_x = alpha / aspect, alpha_y = alpha * aspect (the same convention as synthgen's
            # roughness + anisotropy); a < 0 swaps the axes, a 90 degree tangent rotation in Blender.
            ax, ay = float(p.get("roughness_u", 0.3)) ** 2, float(p.get("roughness_v", 0.3)) ** 2
            r = (ax * ay) ** 0.25
            aspect2 = min(ax, ay) / max(ax, ay) if max(ax, ay) > 0 else 1.0
            aniso = (1.0 - aspect2) / 0.9 * (1.0 if ay <= ax else -1.0)
        b.inputs["Roughness"].default_value = r
        b.inputs["Anisotropic"].default_value = abs(aniso)
        b.inputs["Anisotropic Rotation"].default_value = 0.25 if aniso < 0 else 0.0
        return b.outputs["BSDF"]
    if t == "dielectric":
        if p.get("thin", False):
            raise NotImplementedError("dielectric thin=true (thin sheet) has no Cycles 3.4 equivalent")
        g = nodes.new("ShaderNodeBsdfGlass")
        r = _principled_roughness(p)
        g.distribution = "SHARP" if r == 0.0 else "GGX"
        g.inputs["Color"].default_value = (*_rgb(p.get("transmittance", 1.0)), 1.0)
        g.inputs["Roughness"].default_value = r
        g.inputs["IOR"].default_value = float(p.get("ior", 1.5)) / float(p.get("exterior_ior", 1.0))
        return g.outputs["BSDF"]
    if t == "coated":
        # Principled (metallic 0): Lambertian base + GGX specular with F0 from the coating's IOR.
        ior = float(p.get("ior", 1.5))
        f0 = ((ior - 1) / (ior + 1)) ** 2
        b = nodes.new("ShaderNodeBsdfPrincipled")
        b.distribution = "GGX"
        b.inputs["Base Color"].default_value = (*_rgb(p.get("albedo", 0.5)), 1.0)
        b.inputs["Metallic"].default_value = 0.0
        b.inputs["Specular"].default_value = f0 / 0.08 * float(p.get("specular", 1.0))
        b.inputs["Roughness"].default_value = _principled_roughness(p)
        b.inputs["IOR"].default_value = ior
        return b.outputs["BSDF"]
    if t == "mix":
        if depth > 8:
            raise ValueError("mix materials nested too deeply")
        a_id, b_id = _mix_children(p)
        mix = nodes.new("ShaderNodeMixShader")
        mix.inputs["Fac"].default_value = float(p.get("weight", p.get("factor", 0.5)))
        links.new(_shader_for(materials[a_id], nt, materials, depth + 1), mix.inputs[1])
        links.new(_shader_for(materials[b_id], nt, materials, depth + 1), mix.inputs[2])
        return mix.outputs["Shader"]
    raise NotImplementedError(f"material type {t!r} has no Cycles equivalent in cycles_scene.py")


def _mix_children(p):
    for a, b in (("a", "b"), ("material_a", "material_b"), ("first", "second")):
        if a in p and b in p:
            return int(p[a]), int(p[b])
    if "materials" in p:
        return int(p["materials"][0]), int(p["materials"][1])
    raise ValueError(f"mix: cannot find the two child materials in {sorted(p)}")


def _principled_roughness(p):
    """Blender roughness r gives GGX alpha = r^2, as synthgen's `roughness` does; vs_cycles.py
    may pass an explicit `_blender_roughness` next to the synthgen parameters."""
    if "_blender_roughness" in p:
        return float(p["_blender_roughness"])
    return float(p.get("roughness", 0.0))


def build_material(i, m, materials):
    mat, nt, out = _new_material(f"mat{i}_{m['type']}")
    sock = _shader_for(m, nt, materials)
    nt.links.new(sock, out.inputs["Surface"])
    return mat


# ---------------------------------------------------------------------------------------------
# Lights and world


def _world_nodes(scene):
    world = bpy.data.worlds.new("World")
    scene.world = world
    world.use_nodes = True
    nt = world.node_tree
    for n in list(nt.nodes):
        nt.nodes.remove(n)
    out = nt.nodes.new("ShaderNodeOutputWorld")
    out.target = "CYCLES"
    return world, nt, out


def build_lights(scene, lights):
    world_shaders = []  # output sockets of background shaders, summed
    world, nt, out = _world_nodes(scene)
    for i, light in enumerate(lights):
        t, p = light["type"], light.get("params", {})
        if t == "point":
            data = bpy.data.lights.new(f"point{i}", "POINT")
            colour, intensity = _colour_and_energy(_scaled(p, "intensity", 1.0))
            data.color = colour
            data.energy = 4.0 * math.pi * intensity  # P = 4 pi I
            data.shadow_soft_size = 0.0
            obj = bpy.data.objects.new(f"point{i}", data)
            obj.location = Vector(_rgb(p.get("position", 0.0)))
            scene.collection.objects.link(obj)
        elif t == "sun":
            data = bpy.data.lights.new(f"sun{i}", "SUN")
            colour, e = _colour_and_energy(_scaled(p, "irradiance", 1.0))
            data.color = colour
            data.energy = e  # W/m^2 on a surface facing the sun
            data.angle = math.radians(float(p.get("angular_diameter", 0.53)))
            obj = bpy.data.objects.new(f"sun{i}", data)
            d = Vector(_rgb(p.get("direction", (0.0, 0.0, 1.0)))).normalized()
            # The sun shines along its local -Z: local +Z must point towards the sun.
            obj.rotation_mode = "QUATERNION"
            obj.rotation_quaternion = d.to_track_quat("Z", "Y")
            scene.collection.objects.link(obj)
        elif t == "environment":
            bg = nt.nodes.new("ShaderNodeBackground")
            bg.inputs["Color"].default_value = (*_scaled(p, "radiance", 1.0), 1.0)
            bg.inputs["Strength"].default_value = 1.0
            world_shaders.append(bg.outputs["Background"])
        elif t == "envmap":
            world_shaders.append(_envmap_shader(nt, p))
        else:
            raise NotImplementedError(f"light type {t!r} has no Cycles equivalent in cycles_scene.py")
    if not world_shaders:
        bg = nt.nodes.new("ShaderNodeBackground")
        bg.inputs["Color"].default_value = (0.0, 0.0, 0.0, 1.0)
        bg.inputs["Strength"].default_value = 0.0
        world_shaders.append(bg.outputs["Background"])
    sock = world_shaders[0]
    for s in world_shaders[1:]:
        add = nt.nodes.new("ShaderNodeAddShader")
        nt.links.new(sock, add.inputs[0])
        nt.links.new(s, add.inputs[1])
        sock = add.outputs[0]
    nt.links.new(sock, out.inputs["Surface"])
    # Importance-sample the world (Cycles "Multiple Importance" world, automatic map resolution).
    world.cycles.sampling_method = "AUTOMATIC"


def _envmap_shader(nt, p):
    """Equirectangular map. The description gives `_blender_mapping`: a 3x3 matrix M such that
    the Blender direction used for the lookup is M @ d for a world direction d (vs_cycles.py
    derives it from the synthgen plugin's convention and `rotation`)."""
    nodes, links = nt.nodes, nt.links
    coord = nodes.new("ShaderNodeTexCoord")
    tex = nodes.new("ShaderNodeTexEnvironment")
    tex.image = bpy.data.images.load(os.path.abspath(p["filename"]))
    tex.image.colorspace_settings.name = "Linear"
    tex.interpolation = p.get("_blender_interpolation", "Linear")
    tex.projection = "EQUIRECTANGULAR"
    M = p.get("_blender_mapping", [[1, 0, 0], [0, 1, 0], [0, 0, 1]])
    # Vector = (row0 . d, row1 . d, row2 . d) with dot-product nodes.
    comb = nodes.new("ShaderNodeCombineXYZ")
    for axis, row in zip("XYZ", M):
        dot = nodes.new("ShaderNodeVectorMath")
        dot.operation = "DOT_PRODUCT"
        dot.inputs[1].default_value = tuple(float(x) for x in row)
        links.new(coord.outputs["Generated"], dot.inputs[0])
        links.new(dot.outputs["Value"], comb.inputs[axis])
    links.new(comb.outputs["Vector"], tex.inputs["Vector"])
    bg = nodes.new("ShaderNodeBackground")
    links.new(tex.outputs["Color"], bg.inputs["Color"])
    bg.inputs["Strength"].default_value = float(p.get("strength", 1.0))
    sock = bg.outputs["Background"]
    if not p.get("visible", True):
        # Camera rays see black; every other ray sees the map.
        lp = nodes.new("ShaderNodeLightPath")
        black = nodes.new("ShaderNodeBackground")
        black.inputs["Color"].default_value = (0.0, 0.0, 0.0, 1.0)
        mix = nodes.new("ShaderNodeMixShader")
        links.new(lp.outputs["Is Camera Ray"], mix.inputs["Fac"])
        links.new(sock, mix.inputs[1])
        links.new(black.outputs["Background"], mix.inputs[2])
        sock = mix.outputs["Shader"]
    return sock


# ---------------------------------------------------------------------------------------------
# Geometry and camera


def build_meshes(meshes):
    out = []
    for i, m in enumerate(meshes):
        me = bpy.data.meshes.new(m.get("name") or f"mesh{i}")
        pos = [tuple(v) for v in m["positions"]]
        tris = [tuple(int(x) for x in t) for t in m["indices"]]
        me.from_pydata(pos, [], tris)
        if m.get("normals"):
            for poly in me.polygons:
                poly.use_smooth = True
            me.use_auto_smooth = True  # Blender 3.x: needed for custom split normals
            me.normals_split_custom_set_from_vertices([tuple(n) for n in m["normals"]])
        me.update()
        out.append(me)
    return out


def build_camera(scene, spec):
    c = spec["camera"]
    W, H = int(spec["width"]), int(spec["height"])
    fx, fy, cx, cy = (float(c[k]) for k in ("fx", "fy", "cx", "cy"))
    if abs(fx - fy) > 1e-6 * fx:
        raise NotImplementedError("cycles_scene.py: fx != fy (non-square pixels) is not converted")
    cam = bpy.data.cameras.new("camera")
    cam.type = "PERSP"
    cam.lens_unit = "MILLIMETERS"
    if W >= H:
        cam.sensor_fit = "HORIZONTAL"
        cam.sensor_width = float(W)
    else:
        cam.sensor_fit = "VERTICAL"
        cam.sensor_height = float(H)
    cam.lens = fx  # focal length in pixels with a sensor measured in pixels
    S = float(max(W, H))
    cam.shift_x = (0.5 * W - cx) / S
    cam.shift_y = (cy - 0.5 * H) / S
    cam.clip_start = float(c.get("clip_start", 1e-4))
    cam.clip_end = float(c.get("clip_end", 1e7))
    obj = bpy.data.objects.new("camera", cam)
    wfc = Matrix([list(map(float, r)) for r in c["world_from_camera"]])
    obj.matrix_world = wfc @ Matrix.Diagonal((1.0, -1.0, -1.0, 1.0))
    scene.collection.objects.link(obj)
    scene.camera = obj


def configure(scene, spec):
    scene.render.engine = "CYCLES"
    cy = scene.cycles
    cy.device = "CPU"
    cy.samples = int(spec["spp"])
    cy.use_adaptive_sampling = bool(spec.get("adaptive_sampling", False))
    cy.adaptive_threshold = float(spec.get("adaptive_threshold", 0.0))
    cy.adaptive_min_samples = int(spec.get("adaptive_min_samples", 0))
    cy.time_limit = float(spec.get("time_limit", 0.0))
    cy.use_denoising = False
    cy.seed = int(spec.get("seed", 0))
    bounces = max(0, int(spec["max_depth"]) - 2)
    if "cycles_max_bounces" in spec:  # override, used by `vs_cycles.py --check` to test the mapping
        bounces = int(spec["cycles_max_bounces"])
    cy.max_bounces = bounces
    cy.diffuse_bounces = bounces
    cy.glossy_bounces = bounces
    cy.transmission_bounces = bounces
    cy.volume_bounces = 0
    cy.transparent_max_bounces = bounces
    cy.sample_clamp_direct = 0.0
    cy.sample_clamp_indirect = 0.0
    cy.blur_glossy = 0.0  # "Filter Glossy" off: no roughness regularisation
    cy.caustics_reflective = True
    cy.caustics_refractive = True
    cy.light_sampling_threshold = 0.0  # no probabilistic culling of light samples
    cy.pixel_filter_type = "BOX"
    cy.filter_width = 1.0
    cy.use_animated_seed = False
    r = scene.render
    r.resolution_x = int(spec["width"])
    r.resolution_y = int(spec["height"])
    r.resolution_percentage = 100
    r.pixel_aspect_x = r.pixel_aspect_y = 1.0
    r.film_transparent = False
    r.threads_mode = "FIXED"
    r.threads = int(spec.get("threads", 2))
    r.use_persistent_data = False
    scene.view_settings.view_transform = "Standard"
    scene.view_settings.look = "None"
    scene.view_settings.exposure = 0.0
    scene.view_settings.gamma = 1.0
    scene.display_settings.display_device = "sRGB"
    s = r.image_settings
    s.file_format = "OPEN_EXR"
    s.color_mode = "RGBA"
    s.color_depth = "32"
    s.exr_codec = "ZIP"


def main():
    t_start = time.perf_counter()
    spec = _argv_spec()
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene = bpy.context.scene
    configure(scene, spec)
    meshes = build_meshes(spec["meshes"])
    materials = [build_material(i, m, spec["materials"]) for i, m in enumerate(spec["materials"])]
    for i, inst in enumerate(spec["instances"]):
        obj = bpy.data.objects.new(f"inst{i}", meshes[inst["mesh"]])
        obj.matrix_world = Matrix([list(map(float, r)) for r in inst["world_from_object"]])
        # No shadow-terminator fixes (Cycles moves shadow-ray origins off smooth low-poly
        # surfaces by default; synthgen shades the mesh as it is).
        obj.cycles.shadow_terminator_geometry_offset = 0.0
        obj.cycles.shadow_terminator_offset = 0.0
        scene.collection.objects.link(obj)
        if inst.get("material", -1) >= 0:
            if len(obj.data.materials) == 0:
                obj.data.materials.append(None)
            obj.material_slots[0].link = "OBJECT"
            obj.material_slots[0].material = materials[inst["material"]]
    build_lights(scene, spec["lights"])
    build_camera(scene, spec)
    t_built = time.perf_counter()
    bpy.ops.render.render(write_still=False)
    t_rendered = time.perf_counter()
    out = os.path.abspath(spec["output"])
    bpy.data.images["Render Result"].save_render(filepath=out, scene=scene)
    t_saved = time.perf_counter()
    print("CYCLES_RESULT " + json.dumps({
        "build_s": t_built - t_start, "render_s": t_rendered - t_built, "save_s": t_saved - t_rendered,
        "output": out, "blender": bpy.app.version_string, "max_bounces": scene.cycles.max_bounces,
        "threads": scene.render.threads, "sampling_pattern": scene.cycles.sampling_pattern,
        "adaptive_sampling": scene.cycles.use_adaptive_sampling, "adaptive_threshold": scene.cycles.adaptive_threshold,
        "time_limit": scene.cycles.time_limit}), flush=True)


if __name__ == "__main__":
    main()
