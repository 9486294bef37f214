// Conversions shared by the binding files (module.cpp, camera_film.cpp, images.cpp, ...): Python
// dicts to plugin parameters, 4x4 matrices both ways, and film buffers as numpy views; and the
// bind_* functions of the other binding files.
#pragma once

#include <algorithm>
#include <memory>
#include <string>
#include <vector>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include "core/error.h"
#include "core/math.h"
#include "core/params.h"
#include "film/film.h"

namespace sg {
struct TextureResolution;
struct TextureEstimate;
class Scene;
}  // namespace sg

namespace sg::bindings {

namespace py = pybind11;

/// Plugin parameters from a Python dict (numbers, strings, sequences, TextureRef); errors name
/// `context`.
ParamSet params_from_dict(const py::dict& d, const std::string& context);

inline Transform transform_from_py(const py::object& o, const char* what) {
  if (o.is_none()) return Transform();
  auto a = py::array_t<float, py::array::c_style | py::array::forcecast>::ensure(o);
  if (!a) throw Error(std::string(what) + ": expected a 4x4 matrix");
  if (!((a.ndim() == 2 && a.shape(0) == 4 && a.shape(1) == 4) || (a.ndim() == 1 && a.shape(0) == 16)))
    throw Error(std::string(what) + ": expected a 4x4 matrix");
  return Transform::from_row_major(a.data(), what);
}

inline py::array_t<float> transform_to_py(const Transform& t) {
  py::array_t<float> a({4, 4});
  std::copy(t.m.begin(), t.m.end(), a.mutable_data());
  return a;
}

// Wraps a vector owned by `owner` as a numpy array without copying; a buffer the render left
// empty (Film::allocate's labels_only) as zeros of that shape.
template <class T>
py::array wrap(std::shared_ptr<Film> owner, std::vector<T>& v, std::vector<py::ssize_t> shape) {
  if (v.empty()) {
    py::array_t<T> zeros(shape);
    std::fill(zeros.mutable_data(), zeros.mutable_data() + zeros.size(), T(0));
    return std::move(zeros);
  }
  auto* holder = new std::shared_ptr<Film>(owner);
  py::capsule cap(holder, [](void* p) { delete static_cast<std::shared_ptr<Film>*>(p); });
  return py::array_t<T>(shape, v.data(), cap);
}

void bind_images(py::module_& m);         ///< read_image, read_image_info (images.cpp)
void bind_camera(py::module_& m);         ///< PinholeCamera (camera_film.cpp)
void bind_render_result(py::module_& m);  ///< RenderResult: the Film's buffers (camera_film.cpp)
void bind_denoise(py::module_& m);        ///< denoise (denoise.cpp)
void bind_geometry(py::module_& m);       ///< surface_distances (geometry.cpp)
/// load_extension_library, loaded_extension_libraries, Scene.add_shape (extensions.cpp).
void bind_extensions(py::module_& m, py::class_<Scene>& scene);
/// Scene's change journal: begin_journal, save_journal, _replay, ... (journal.cpp).
void bind_journal(py::class_<Scene>& scene);
/// Scene.instance_coverage: amodal masks from one ray per pixel (queries.cpp).
void bind_queries(py::class_<Scene>& scene);
/// Scene::estimate_texture_resolution's rows as {'textures', 'camera_rays', 'bounce_rays'} (texture_lod.cpp).
py::dict texture_estimate_to_py(const std::vector<TextureResolution>& res, const TextureEstimate& raw);

}  // namespace sg::bindings
