// pybind11 bindings: synthgen._core. Names mirror the C++ API (snake_case).
#include <array>
#include <map>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "api/scene.h"
#include "core/error.h"
#include "core/plugin.h"
#include "bindings/convert.h"
#include "io/image_io.h"
#include "io/vdb_io.h"

namespace py = pybind11;
using namespace sg;

namespace sg::bindings {

ParamSet params_from_dict(const py::dict& d, const std::string& context) {
  ParamSet ps;
  for (auto item : d) {
    std::string key = py::str(item.first);
    py::handle v = item.second;
    if (py::isinstance<py::bool_>(v)) ps.set(key, v.cast<bool>());
    else if (py::isinstance<TextureRef>(v)) ps.set(key, v.cast<TextureRef>());
    else if (py::isinstance<py::int_>(v)) ps.set(key, v.cast<int64_t>());
    else if (py::isinstance<py::float_>(v)) ps.set(key, v.cast<double>());
    else if (py::isinstance<py::str>(v)) ps.set(key, v.cast<std::string>());
    else if (py::isinstance<py::array>(v) || py::isinstance<py::list>(v) || py::isinstance<py::tuple>(v)) {
      std::vector<double> out;
      try {
        auto arr = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(v);
        if (!arr || arr.ndim() > 1) throw py::value_error("");
        if (arr.ndim() == 0) {
          ps.set(key, double(*arr.data()));
          continue;
        }
        out.assign(arr.data(), arr.data() + arr.size());
      } catch (const py::error_already_set&) {
        throw Error(context + ": parameter '" + key + "' must be a flat list of numbers");
      } catch (const py::value_error&) {
        throw Error(context + ": parameter '" + key + "' must be a flat list of numbers");
      }
      ps.set(key, out);
    } else if (py::hasattr(v, "__float__")) {
      ps.set(key, v.attr("__float__")().cast<double>());
    } else {
      throw Error(context + ": parameter '" + key + "' has unsupported type " +
                  std::string(py::str(v.get_type().attr("__name__"))));
    }
  }
  return ps;
}

}  // namespace sg::bindings

using namespace sg::bindings;

namespace {

template <class T>
py::array_t<float, py::array::c_style> as_float_array(const py::object& o, size_t cols, const char* what) {
  auto a = py::array_t<float, py::array::c_style | py::array::forcecast>::ensure(o);
  if (!a || a.ndim() != 2 || size_t(a.shape(1)) != cols)
    throw Error(std::string(what) + ": expected an array of shape (N, " + std::to_string(cols) + ")");
  return a;
}

TriangleMesh mesh_from_arrays(const py::object& positions, const py::object& indices, const py::object& normals,
                              const py::object& uvs, const py::object& material_ids, const std::string& name) {
  TriangleMesh m;
  m.name = name;
  auto p = as_float_array<float>(positions, 3, "positions");
  m.positions.resize(size_t(p.shape(0)));
  std::memcpy(static_cast<void*>(m.positions.data()), p.data(), m.positions.size() * sizeof(Vec3f));
  auto idx_any = py::array::ensure(indices);
  if (!idx_any || idx_any.ndim() != 2 || idx_any.shape(1) != 3)
    throw Error("indices: expected an integer array of shape (M, 3)");
  if (!py::isinstance<py::array_t<int64_t>>(idx_any) && !py::isinstance<py::array_t<int32_t>>(idx_any) &&
      !py::isinstance<py::array_t<uint32_t>>(idx_any) && !py::isinstance<py::array_t<uint64_t>>(idx_any))
    throw Error("indices: expected an integer array of shape (M, 3)");
  auto idx = py::array_t<int64_t, py::array::c_style | py::array::forcecast>::ensure(idx_any);
  m.indices.resize(size_t(idx.size()));
  for (size_t i = 0; i < m.indices.size(); ++i) {
    int64_t v = idx.data()[i];
    if (v < 0 || v > int64_t(UINT32_MAX)) throw Error("indices: triangle " + std::to_string(i / 3) + " has index " + std::to_string(v) + " out of range");
    m.indices[i] = uint32_t(v);
  }
  if (!normals.is_none()) {
    auto n = as_float_array<float>(normals, 3, "normals");
    m.normals.resize(size_t(n.shape(0)));
    std::memcpy(static_cast<void*>(m.normals.data()), n.data(), m.normals.size() * sizeof(Vec3f));
  }
  if (!uvs.is_none()) {
    auto u = as_float_array<float>(uvs, 2, "uvs");
    m.uvs.resize(size_t(u.shape(0)));
    std::memcpy(static_cast<void*>(m.uvs.data()), u.data(), m.uvs.size() * sizeof(Vec2f));
  }
  if (!material_ids.is_none()) {
    auto ids = py::array_t<int64_t, py::array::c_style | py::array::forcecast>::ensure(material_ids);
    if (!ids || ids.ndim() != 1) throw Error("material_ids: expected a 1-D integer array");
    m.material_ids.resize(size_t(ids.size()));
    for (size_t i = 0; i < m.material_ids.size(); ++i) m.material_ids[i] = int32_t(ids.data()[i]);
  }
  return m;
}

py::object value_to_py(const ParamSet::Value& v) {
  return std::visit([](const auto& x) -> py::object {
    using T = std::decay_t<decltype(x)>;
    if constexpr (std::is_same_v<T, TextureRef>) return py::cast(x);
    else if constexpr (std::is_same_v<T, std::vector<double>>) return py::cast(x);
    else return py::cast(x);
  }, v);
}

/// A bound of an integer parameter as a Python int. NOTE: bounds at or beyond 2^63 / 2^64
/// (as doubles) stand for the int64 / uint64 maxima.
py::object int_bound(double b) {
  if (b >= 18446744073709551615.0) return py::int_(py::reinterpret_steal<py::object>(PyLong_FromUnsignedLongLong(UINT64_MAX)));
  if (b >= 9223372036854775807.0) return py::int_(INT64_MAX);
  if (b <= -9223372036854775807.0) return py::int_(INT64_MIN);
  return py::int_(int64_t(b));
}

py::dict plugin_info_to_dict(const PluginInfo& info) {
  py::dict d;
  d["kind"] = info.kind;
  d["name"] = info.name;
  d["doc"] = info.doc;
  d["file"] = info.file;
  py::list params;
  for (const auto& p : info.params) {
    py::dict q;
    q["name"] = p.name;
    q["type"] = param_type_name(p.type);
    q["default"] = p.has_default ? value_to_py(p.default_value) : py::none();
    q["has_default"] = p.has_default;
    q["default_doc"] = p.default_doc;
    q["required"] = p.required;
    bool is_int = p.type == ParamType::Int;
    q["min"] = std::isfinite(p.lo) ? (is_int ? int_bound(p.lo) : py::object(py::float_(p.lo))) : py::none();
    q["max"] = std::isfinite(p.hi) ? (is_int ? int_bound(p.hi) : py::object(py::float_(p.hi))) : py::none();
    q["min_open"] = p.lo_open;
    q["max_open"] = p.hi_open;
    q["choices"] = p.choices;
    q["aliases"] = p.aliases;
    q["size"] = p.size;
    q["doc"] = p.doc;
    params.append(q);
  }
  d["params"] = params;
  py::list exclusive;
  for (const auto& [a, b] : info.exclusive) exclusive.append(py::make_tuple(a, b));
  d["exclusive"] = exclusive;
  py::list requires;
  for (const auto& [k, o] : info.requires) requires.append(py::make_tuple(k, o));
  d["requires"] = requires;
  d["one_of"] = info.one_of;
  return d;
}

/// Default of a render setting, from its declaration (integrator/path_tracer.cpp).
template <class T>
T render_default(const char* name) {
  const ParamDecl* d = Registry::instance().info("render", "path_tracer").find(name);
  if (!d || !d->has_default) throw Error(std::string("render setting '") + name + "' has no declared default");
  if (auto b = std::get_if<bool>(&d->default_value)) return T(*b);
  if (auto r = std::get_if<double>(&d->default_value)) return T(*r);
  return T(std::get<int64_t>(d->default_value));
}

}  // namespace

PYBIND11_MODULE(_core, m) {
  m.doc() = "synthgen native core: Embree-based path tracer with exact label outputs.";
  m.attr("__version__") = SYNTHGEN_VERSION;
  m.def("load_image_plugin", &load_image_plugin,
        "Loads the OpenImageIO plugin now rather than at the first image read or write (a one-time cost\n"
        "of about 0.2 s: OpenImageIO and its format libraries). Worker processes and benchmarks call it\n"
        "at start-up. Raises SynthgenError when the plugin cannot be loaded.");

  bind_images(m);

  static py::exception<Error> base_exc(m, "SynthgenError", PyExc_ValueError);
  static py::exception<FileError> file_exc(m, "FileError", base_exc.ptr());
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const FileError& e) {
      file_exc(e.what());
    } catch (const Error& e) {
      base_exc(e.what());
    }
  });

  m.def("vdb_supported", &vdb_supported, "Whether this build reads and writes OpenVDB (.vdb) files.");
  m.def(
      "write_vdb_grid",
      [](const std::string& path, const std::string& name,
         py::array_t<float, py::array::c_style | py::array::forcecast> a, std::array<float, 3> lo,
         std::array<float, 3> hi) {
        if (a.ndim() != 3)
          throw Error("write_vdb_grid: expected a 3D array (z, y, x), got " + std::to_string(a.ndim()) + "D");
        DenseGrid g;
        g.nz = int(a.shape(0));
        g.ny = int(a.shape(1));
        g.nx = int(a.shape(2));
        g.lo = Vec3f(lo[0], lo[1], lo[2]);
        g.hi = Vec3f(hi[0], hi[1], hi[2]);
        g.values.assign(a.data(), a.data() + a.size());
        write_vdb_grid(path, name, g);
      },
      py::arg("path"), py::arg("grid_name"), py::arg("density"), py::arg("bounds_min"), py::arg("bounds_max"),
      "Writes a density array (z, y, x: x fastest) as the float grid `grid_name` of a new .vdb file\n"
      "over the world box [bounds_min, bounds_max] (for the 'grid' medium; non-zero voxels active).");
  bind_geometry(m);
  m.def("plugin_kinds", []() { return Registry::instance().kinds(); },
        "Plugin kinds of the registry: camera, light, material, render, texture.");
  m.def("plugin_names", [](const std::string& kind) { return Registry::instance().names(kind); }, py::arg("kind"),
        "Names of the plugins of a kind, sorted (e.g. plugin_names('material')).");
  m.def("plugin_info", [](const std::string& kind, const std::string& name) {
          return plugin_info_to_dict(Registry::instance().info(kind, name));
        }, py::arg("kind"), py::arg("name"),
        "The declaration of a plugin: {kind, name, doc, file, params: [{name, type, default, has_default,\n"
        "default_doc, required, min, max, min_open, max_open, choices, aliases, size, doc}], exclusive:\n"
        "[(keys, keys)], requires: [(key, keys)], one_of: [keys]}. Every parameter's type, default, range\n"
        "and doc is declared once, in the plugin's C++ file; schemas and docs are generated from this.");

  py::class_<TextureRef>(m, "TextureRef", "Reference to a texture id, usable as a material parameter.")
      .def(py::init([](uint32_t id) { return TextureRef{id}; }), py::arg("id"))
      .def_readonly("id", &TextureRef::id)
      .def("__repr__", [](const TextureRef& t) { return "TextureRef(" + std::to_string(t.id) + ")"; });

  bind_camera(m);
  bind_render_result(m);
  bind_denoise(m);

  py::class_<Scene> scene_class(m, "Scene", R"doc(Integration API: typed libraries with stable integer ids.

Edits accumulate; commit() applies only what changed (only new or edited meshes get
a BVH build). render() commits pending edits first.)doc");
  bind_extensions(m, scene_class);
  bind_journal(scene_class);
  bind_queries(scene_class);
  scene_class
      .def(py::init<>())
      .def("add_mesh",
           [](Scene& s, const py::object& positions, const py::object& indices, const py::object& normals,
              const py::object& uvs, const py::object& material_ids, const std::string& name) {
             return s.add_mesh(mesh_from_arrays(positions, indices, normals, uvs, material_ids, name));
           },
           py::arg("positions"), py::arg("indices"), py::arg("normals") = py::none(), py::arg("uvs") = py::none(),
           py::arg("material_ids") = py::none(), py::arg("name") = "")
      .def("update_mesh",
           [](Scene& s, uint32_t id, const py::object& positions, const py::object& indices, const py::object& normals,
              const py::object& uvs, const py::object& material_ids, const std::string& name) {
             s.update_mesh(id, mesh_from_arrays(positions, indices, normals, uvs, material_ids, name));
           },
           py::arg("mesh_id"), py::arg("positions"), py::arg("indices"), py::arg("normals") = py::none(),
           py::arg("uvs") = py::none(), py::arg("material_ids") = py::none(), py::arg("name") = "")
      .def("remove_mesh", &Scene::remove_mesh, py::arg("mesh_id"))
      .def("mesh_arrays",
           [](const Scene& s, uint32_t id) {
             const TriangleMesh& m = s.mesh(id);
             py::dict d;
             py::array_t<float> p({py::ssize_t(m.positions.size()), py::ssize_t(3)});
             std::memcpy(p.mutable_data(), m.positions.data(), m.positions.size() * sizeof(Vec3f));
             py::array_t<uint32_t> i({py::ssize_t(m.triangle_count()), py::ssize_t(3)});
             std::memcpy(i.mutable_data(), m.indices.data(), m.indices.size() * sizeof(uint32_t));
             d["positions"] = p;
             d["indices"] = i;
             d["material_ids"] = py::array_t<int32_t>(py::ssize_t(m.material_ids.size()), m.material_ids.data());
             d["has_normals"] = !m.normals.empty();
             d["has_uvs"] = !m.uvs.empty();
             if (!m.normals.empty()) {
               py::array_t<float> n({py::ssize_t(m.normals.size()), py::ssize_t(3)});
               std::memcpy(n.mutable_data(), m.normals.data(), m.normals.size() * sizeof(Vec3f));
               d["normals"] = n;
             }
             if (!m.uvs.empty()) {
               py::array_t<float> t({py::ssize_t(m.uvs.size()), py::ssize_t(2)});
               std::memcpy(t.mutable_data(), m.uvs.data(), m.uvs.size() * sizeof(Vec2f));
               d["uvs"] = t;
             }
             return d;
           },
           py::arg("mesh_id"),
           "Copies of a mesh's positions, indices and material ids (and its normals and uvs when it has them).")
      .def("load_mesh_file",
           [](Scene& s, const std::string& path) {
             ImportResult r = s.load_mesh_file(path);
             py::dict d;
             d["mesh_id"] = r.mesh_id;
             d["material_ids"] = r.material_ids;
             // Names as the file spells them; bytes that are not UTF-8 (old MTL files) replaced.
             py::list names;
             for (const std::string& n : r.material_names)
               names.append(py::reinterpret_steal<py::str>(PyUnicode_DecodeUTF8(n.data(), py::ssize_t(n.size()), "replace")));
             d["material_names"] = names;
             d["texture_ids"] = r.texture_ids;
             d["removed_degenerate"] = r.removed_degenerate;
             return d;
           },
           py::arg("path"), "Imports OBJ/PLY/glTF/GLB (node transforms applied, materials created).")
      .def("add_texture",
           [](Scene& s, const std::string& type, const py::dict& params) {
             return s.add_texture(type, params_from_dict(params, "texture '" + type + "'"));
           },
           py::arg("type"), py::arg("params") = py::dict())
      .def("add_image_texture",
           [](Scene& s, const py::array& pixels, const py::dict& params) {
             auto img = std::make_shared<ImageData>();
             bool integer = false;
             float range = 1.f;
             if (py::isinstance<py::array_t<uint8_t>>(pixels)) integer = true, range = 255.f;
             else if (py::isinstance<py::array_t<uint16_t>>(pixels)) integer = true, range = 65535.f;
             else if (!py::isinstance<py::array_t<float>>(pixels) && !py::isinstance<py::array_t<double>>(pixels))
               throw Error("add_image_texture: pixels must be a float32, float64, uint8 or uint16 array, got " +
                           std::string(py::str(pixels.dtype())));
             if (pixels.ndim() != 2 && pixels.ndim() != 3)
               throw Error("add_image_texture: pixels must be an H x W or H x W x C array");
             auto a = py::array_t<float, py::array::c_style | py::array::forcecast>::ensure(pixels);
             img->height = int(a.shape(0));
             img->width = int(a.shape(1));
             img->channels = a.ndim() == 3 ? int(a.shape(2)) : 1;
             img->pixels.assign(a.data(), a.data() + a.size());
             if (integer)
               for (float& v : img->pixels) v /= range;
             return s.add_image_texture(std::move(img), integer,
                                        params_from_dict(params, "texture '" + std::string("image") + "'"));
           },
           py::arg("pixels"), py::arg("params") = py::dict(),
           "Texture 'image' of pixels in memory (H x W or H x W x C, C <= 4; float32/float64 linear values, or\n"
           "uint8/uint16 sRGB-encoded ones, decoded like 8/16-bit files when colorspace is auto) instead\n"
           "of a file: generated plates, signs, decals. `params` are the image plugin's without\n"
           "'file'. Identical pixels share one mip pyramid; the image is saved with the scene.")
      .def("texture_values",
           [](const Scene& s, uint32_t id, py::array_t<float, py::array::c_style | py::array::forcecast> points,
              std::array<float, 3> lo, std::array<float, 3> hi, float world_footprint, py::object uvs) {
             if (id >= s.textures().size() || !s.textures()[id]) throw Error("texture " + std::to_string(id) + " does not exist");
             const Texture& t = *s.textures()[id]->object;
             if (points.ndim() != 2 || points.shape(1) != 3) throw Error("texture_values: points must be N x 3");
             const size_t n = size_t(points.shape(0));
             py::array_t<float, py::array::c_style | py::array::forcecast> uv_arr;
             const bool has_uv = !uvs.is_none();
             if (has_uv) {
               uv_arr = py::array_t<float, py::array::c_style | py::array::forcecast>::ensure(uvs);
               if (!uv_arr || uv_arr.ndim() != 2 || uv_arr.shape(1) != 2 || size_t(uv_arr.shape(0)) != n)
                 throw Error("texture_values: uvs must be N x 2 like points");
             }
             py::array_t<float> out(std::vector<py::ssize_t>{py::ssize_t(n), py::ssize_t(3)});
             auto P = points.unchecked<2>();
             auto O = out.mutable_unchecked<2>();
             for (size_t i = 0; i < n; ++i) {
               TexturePoint q;
               q.p_world = q.p_object = Vec3f(P(i, 0), P(i, 1), P(i, 2));
               q.object_lo = Vec3f(lo[0], lo[1], lo[2]);
               q.object_hi = Vec3f(hi[0], hi[1], hi[2]);
               q.world_footprint = world_footprint;
               if (has_uv) q.uv = Vec2f(uv_arr.at(i, 0), uv_arr.at(i, 1));
               Color c = t.eval_point(q);
               O(i, 0) = c.x;
               O(i, 1) = c.y;
               O(i, 2) = c.z;
             }
             std::string failure = t.failure();  // a user extension's non-finite value
             if (!failure.empty()) throw Error("texture " + std::to_string(id) + ": " + failure);
             return out;
           },
           py::arg("texture"), py::arg("points"), py::arg("object_lo") = std::array<float, 3>{0.f, 0.f, 0.f},
           py::arg("object_hi") = std::array<float, 3>{1.f, 1.f, 1.f}, py::arg("world_footprint") = 0.f,
           py::arg("uvs") = py::none(),
           "Values of texture `texture` at N points (N x 3, used as world and object positions; uvs N x 2\n"
           "optional), for an object with bounds [object_lo, object_hi] and a footprint width in world\n"
           "units: for inspecting and calibrating procedural textures. Returns N x 3 float32.")
      .def("material_info",
           [](const Scene& s, uint32_t id) {
             const auto& ms = s.materials();
             if (id >= ms.size() || !ms[id]) throw Error("material_info: material " + std::to_string(id) + " does not exist");
             py::dict params;
             for (const auto& [k, v] : ms[id]->params.values())
               std::visit([&, key = k](const auto& x) {
                 using T = std::decay_t<decltype(x)>;
                 if constexpr (std::is_same_v<T, TextureRef>) params[py::str(key)] = py::make_tuple("texture", x.id);
                 else params[py::str(key)] = x;
               }, v);
             py::dict d;
             d["type"] = ms[id]->type;
             d["params"] = params;
             return d;
           },
           py::arg("material_id"),
           "The type and parameters of a material (texture references as ('texture', id)).")
      .def("add_material",
           [](Scene& s, const std::string& type, const py::dict& params) {
             return s.add_material(type, params_from_dict(params, "material '" + type + "'"));
           },
           py::arg("type"), py::arg("params") = py::dict())
      .def("update_material",
           [](Scene& s, uint32_t id, const std::string& type, const py::dict& params) {
             s.update_material(id, type, params_from_dict(params, "material '" + type + "'"));
           },
           py::arg("material_id"), py::arg("type"), py::arg("params") = py::dict())
      .def("add_instance",
           [](Scene& s, uint32_t mesh_id, const py::object& wfo, uint32_t class_id, std::optional<uint32_t> instance_id,
              int64_t material_id) {
             return s.add_instance(mesh_id, transform_from_py(wfo, "world_from_object"), class_id, instance_id, material_id);
           },
           py::arg("mesh_id"), py::arg("world_from_object") = py::none(), py::arg("class_id") = 0,
           py::arg("instance_id") = py::none(), py::arg("material_id") = -1)
      .def("set_instance_transform",
           [](Scene& s, uint32_t id, const py::object& wfo) {
             s.set_instance_transform(id, transform_from_py(wfo, "world_from_object"));
           },
           py::arg("instance"), py::arg("world_from_object"))
      .def("set_instance_labels", &Scene::set_instance_labels, py::arg("instance"), py::arg("class_id"), py::arg("instance_id"))
      .def("set_instance_material", &Scene::set_instance_material, py::arg("instance"), py::arg("material_id"))
      .def("set_instance_material_map",
           [](Scene& s, uint32_t id, const std::map<int32_t, int64_t>& map) {
             s.set_instance_material_map(id, std::vector<std::pair<int32_t, int64_t>>(map.begin(), map.end()));
           },
           py::arg("instance"), py::arg("material_map"),
           "Replaces, for this instance only, the materials of its mesh's triangles: {mesh material id:\n"
           "material id} (-1: triangles without a material); e.g. wear wrapping each material of a\n"
           "multi-material model. An instance material (set_instance_material) takes precedence; {}\n"
           "removes the map.")
      .def("instance_material_map",
           [](const Scene& s, uint32_t id) {
             std::map<int32_t, int64_t> m;
             for (const auto& kv : s.instance_material_map(id)) m[kv.first] = kv.second;
             return m;
           },
           py::arg("instance"))
      .def("set_instance_mesh", &Scene::set_instance_mesh, py::arg("instance"), py::arg("mesh_id"),
           "Points an instance at another mesh (no BVH build, only the top level).")
      .def("remove_instance", &Scene::remove_instance, py::arg("instance"))
      .def("set_instance_visible", &Scene::set_instance_visible, py::arg("instance"), py::arg("visible"),
           "Hides (or shows again) an instance for every ray and for light sampling, keeping its BVH:\n"
           "toggling costs a top-level rebuild only.")
      .def("instance_visible", &Scene::instance_visible, py::arg("instance"))
      .def("set_instance_catcher", &Scene::set_instance_catcher, py::arg("instance"), py::arg("catcher"),
           "Makes an instance a shadow catcher: a stand-in of a photo's world (ground, proxy geometry) into\n"
           "which the other instances are inserted. A scene with catchers renders differentially\n"
           "(RenderResult.differential); give catchers labels 0.")
      .def("instance_catcher", &Scene::instance_catcher, py::arg("instance"))
      .def("instance_count", &Scene::instance_count)
      .def("texture_count", &Scene::texture_count, "Live (not removed) textures.")
      .def("material_count", &Scene::material_count, "Live (not removed) materials.")
      .def("set_medium",
           [](Scene& s, const std::string& type, const py::dict& params) {
             s.set_medium(type, params_from_dict(params, "medium '" + type + "'"));
           },
           py::arg("type"), py::arg("params") = py::dict(),
           "Fills the scene with a participating medium (fog, haze: medium plugins), replacing any.")
      .def("clear_medium", &Scene::clear_medium, "Removes the scene's medium.")
      .def("camera_transmittance",
           [](const Scene& s, const py::object& distance) {
             auto a = py::array_t<float, py::array::c_style | py::array::forcecast>::ensure(distance);
             if (!a || a.ndim() != 2) throw Error("camera_transmittance: distance must be an H x W array");
             std::vector<float> d(a.data(), a.data() + a.size());
             std::vector<float> t = s.camera_transmittance(d);
             py::array_t<float> out({a.shape(0), a.shape(1)});
             std::copy(t.begin(), t.end(), out.mutable_data());
             return out;
           },
           py::arg("distance"),
           "Per pixel, the medium's transmittance along the pixel-centre camera ray up to `distance`\n"
           "(RenderResult.distance; inf: the whole ray); all 1 without a medium.")
      .def("medium_type",
           [](const Scene& s) -> py::object {
             return s.medium() ? py::object(py::str(s.medium()->type)) : py::object(py::none());
           },
           "The type of the scene's medium, or None.")
      .def("add_light",
           [](Scene& s, const std::string& type, const py::dict& params) {
             return s.add_light(type, params_from_dict(params, "light '" + type + "'"));
           },
           py::arg("type"), py::arg("params") = py::dict())
      .def("update_light",
           [](Scene& s, uint32_t id, const std::string& type, const py::dict& params) {
             s.update_light(id, type, params_from_dict(params, "light '" + type + "'"));
           },
           py::arg("light_id"), py::arg("type"), py::arg("params") = py::dict())
      .def("remove_light", &Scene::remove_light, py::arg("light_id"))
      .def("remove_texture", &Scene::remove_texture, py::arg("texture_id"),
           "Removes a texture; refused while a texture or material refers to it.")
      .def("remove_material", &Scene::remove_material, py::arg("material_id"),
           "Removes a material; refused while an instance, a mesh's triangles or another material use it.")
      .def("set_camera", &Scene::set_camera, py::arg("camera"))
      // A copy: a reference would silently follow later set_camera() calls.
      .def_property_readonly("camera", [](const Scene& s) { return PinholeCamera(s.camera()); },
                             "A copy of the current camera.")
      .def("commit", &Scene::commit, py::call_guard<py::gil_scoped_release>())
      .def("has_pending_edits", &Scene::has_pending_edits)
      .def_property_readonly("commit_stats", [](const Scene& s) {
        py::dict d;
        d["mesh_bvh_builds"] = s.commit_stats().mesh_bvh_builds;
        d["mesh_bvh_builds_last_commit"] = s.commit_stats().mesh_bvh_builds_last_commit;
        d["top_level_builds"] = s.commit_stats().top_level_builds;
        d["commits"] = s.commit_stats().commits;
        d["alpha_tested_meshes"] = s.commit_stats().alpha_tested_meshes;  // cut-out meshes
        d["image_loads"] = s.image_cache().loads();            // image files decoded
        d["image_cache_hits"] = s.image_cache().hits();        // image textures that shared one
        d["mip_files_written"] = s.image_cache().mip_files_written();  // tiled copies made
        d["mip_files_opened"] = s.image_cache().mip_files_opened();    // files read lazily
        return d;
      })
      .def("render",
           [](Scene& s, uint32_t spp, uint32_t max_depth, uint32_t rr_depth, uint64_t seed, uint32_t threads,
              uint32_t tile_size, bool texture_filtering, float exposure, float clamp_indirect, float noise_threshold,
              float target_psnr, uint32_t min_spp, uint32_t max_spp, bool denoise, uint32_t max_medium_depth,
              bool next_event, bool labels_only, bool texture_lod, uint32_t texture_lod_margin,
              float texture_budget_mib) {
             RenderSettings rs;
             rs.spp = spp;
             rs.max_depth = max_depth;
             rs.rr_depth = rr_depth;
             rs.seed = seed;
             rs.threads = threads;
             rs.tile_size = tile_size;
             rs.texture_filtering = texture_filtering;
             rs.exposure = exposure;
             rs.clamp_indirect = clamp_indirect;
             rs.noise_threshold = noise_threshold;
             rs.target_psnr = target_psnr;
             rs.min_spp = min_spp;
             rs.max_spp = max_spp;
             rs.denoise = denoise;
             rs.max_medium_depth = max_medium_depth;
             rs.next_event = next_event;
             rs.labels_only = labels_only;
             rs.texture_lod = texture_lod;
             rs.texture_lod_margin = texture_lod_margin;
             rs.texture_budget_mib = texture_budget_mib;
             auto film = std::make_shared<Film>();
             {
               py::gil_scoped_release release;
               s.render(rs, film.get());
             }
             return film;
           },
           py::arg("spp") = render_default<uint32_t>("spp"), py::arg("max_depth") = render_default<uint32_t>("max_depth"),
           py::arg("rr_depth") = render_default<uint32_t>("rr_depth"), py::arg("seed") = render_default<uint64_t>("seed"),
           py::arg("threads") = render_default<uint32_t>("threads"),
           py::arg("tile_size") = render_default<uint32_t>("tile_size"),
           py::arg("texture_filtering") = render_default<bool>("texture_filtering"),
           py::arg("exposure") = render_default<float>("exposure"),
           py::arg("clamp_indirect") = render_default<float>("clamp_indirect"),
           py::arg("noise_threshold") = render_default<float>("noise_threshold"),
           py::arg("target_psnr") = render_default<float>("target_psnr"),
           py::arg("min_spp") = render_default<uint32_t>("min_spp"),
           py::arg("max_spp") = render_default<uint32_t>("max_spp"),
           py::arg("denoise") = render_default<bool>("denoise"),
           py::arg("max_medium_depth") = render_default<uint32_t>("max_medium_depth"),
           py::arg("next_event") = render_default<bool>("next_event"), py::arg("labels_only") = false,
           py::arg("texture_lod") = render_default<bool>("texture_lod"),
           py::arg("texture_lod_margin") = render_default<uint32_t>("texture_lod_margin"),
           py::arg("texture_budget_mib") = render_default<float>("texture_budget_mib"),
           "Path-traces the scene; releases the GIL. Returns a RenderResult. With labels_only, only the\n"
           "label outputs are computed (one pixel-centre ray per pixel; rgb stays 0, alpha is the\n"
           "centre ray's coverage).")
      .def("estimate_texture_resolution",
           [](Scene& s, uint32_t max_depth, uint32_t max_rays_per_pixel, uint32_t threads) {
             TextureEstimateSettings es;
             es.max_depth = max_depth;
             es.max_rays_per_pixel = std::max<uint32_t>(max_rays_per_pixel, 1);
             es.threads = threads;
             std::vector<TextureResolution> res;
             TextureEstimate raw;
             {
               py::gil_scoped_release release;
               res = s.estimate_texture_resolution(es, &raw);
             }
             return texture_estimate_to_py(res, raw);
           },
           py::arg("max_depth") = 4, py::arg("max_rays_per_pixel") = 16, py::arg("threads") = 0,
           "The texture resolution estimate for the current camera (docs/texture_lod.md): one camera ray\n"
           "per pixel with ray differentials, followed through sharp reflections and refractions up to\n"
           "max_depth bounces; per image texture the coarsest mip level that keeps at least one texel per\n"
           "pixel in at least one axis, and the memory of its pyramid before and after. Returns\n"
           "{'textures': [one dict per image texture], 'camera_rays', 'bounce_rays'}; commits first.")
      .def("set_texture_levels",
           [](Scene& s, const std::map<uint32_t, int>& levels) {
             std::vector<std::pair<uint32_t, int>> v(levels.begin(), levels.end());
             py::gil_scoped_release release;
             s.set_texture_levels(v);
           },
           py::arg("levels"),
           "Makes mip levels `level` and coarser of each texture's pyramid resident ({texture id: level};\n"
           "textures sharing a pyramid get the finest level any asks for; clamped to [0, tail]), freeing\n"
           "finer levels where they can be read back (docs/texture_lod.md). Textures not listed keep\n"
           "their levels; a render makes every level of a pyramid nobody chose for resident first.")
      .def("set_mip_cache_dir", &Scene::set_mip_cache_dir, py::arg("directory"),
           "Keeps tiled mip-mapped copies of image files in this directory (written once, read lazily:\n"
           "only the levels set_texture_levels asks for); '' turns it off.")
      .def("save", &Scene::save, py::arg("path"), "Writes the scene (XML + '.bin' sidecar) for replay.")
      .def_static("load", &Scene::load, py::arg("path"), "Replays a scene written by save().");
}
