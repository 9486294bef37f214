// Bindings of the scene's queries: Scene.instance_coverage (api/scene_queries.cpp) and what a scene
// holds (Scene.instances, Scene.lights).
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <memory>

#include "api/scene.h"
#include "bindings/convert.h"

namespace sg::bindings {

void bind_queries(py::class_<Scene>& scene) {
  scene.def(
      "instance_coverage",
      [](Scene& s, const PinholeCamera& camera, const std::vector<uint32_t>& instances, uint32_t threads,
         bool first_hit) {
        auto bits = std::make_unique<std::vector<uint64_t>>();
        {
          py::gil_scoped_release release;
          *bits = s.instance_coverage(camera, instances, threads, first_hit);
        }
        const py::ssize_t words = py::ssize_t((instances.size() + 63) / 64);
        std::vector<py::ssize_t> shape{py::ssize_t(camera.height), py::ssize_t(camera.width), words};
        if (bits->empty()) return py::array_t<uint64_t>(shape);
        auto* owned = bits.release();
        py::capsule cap(owned, [](void* p) { delete static_cast<std::vector<uint64_t>*>(p); });
        return py::array_t<uint64_t>(shape, owned->data(), cap);
      },
      py::arg("camera"), py::arg("instances"), py::arg("threads") = 0, py::arg("first_hit") = false,
      "Amodal masks of many instances from one camera ray per pixel: an H x W x ceil(n / 64) uint64 array\n"
      "(H, W: the camera's, which need not be the scene's) whose bit i % 64 of word i // 64 is set where the\n"
      "ray through the pixel centre hits instances[i] anywhere along it -- exactly the pixels a label-only\n"
      "render of that instance alone (every other one hidden) gives its id: cut-outs are respected, a hidden\n"
      "listed instance covers nothing, instances not listed are ignored. With first_hit, only where\n"
      "instances[i] is the ray's first hit among all shown instances: its visible mask, where a label-only\n"
      "render shows its id. Rays are traced only where a listed instance's bounds project. Commits pending\n"
      "edits first; releases the GIL; deterministic whatever the thread count (0: all).")
      .def("instances",
           [](const Scene& s) {
             py::list out;
             const auto& all = s.instances();
             for (size_t i = 0; i < all.size(); ++i) {
               if (!all[i]) continue;
               py::dict d;
               d["id"] = i;
               d["mesh"] = all[i]->mesh_id;
               d["class_id"] = all[i]->class_id;
               d["instance_id"] = all[i]->instance_id;
               d["material"] = all[i]->material_id;
               d["visible"] = all[i]->visible;
               d["catcher"] = all[i]->catcher;
               out.append(d);
             }
             return out;
           },
           "The live instances, by id: [{'id', 'mesh', 'class_id', 'instance_id', 'material' (-1: the\n"
           "mesh's), 'visible', 'catcher'}] (what a replayed journal holds).")
      .def("lights",
           [](const Scene& s) {
             py::list out;
             const auto& all = s.lights();
             for (size_t i = 0; i < all.size(); ++i) {
               if (!all[i]) continue;
               py::dict d;
               d["id"] = i;
               d["type"] = all[i]->type;
               out.append(d);
             }
             return out;
           },
           "The live lights added with add_light, by id: [{'id', 'type'}] (emissive materials' area\n"
           "lights are not among them).");
}

}  // namespace sg::bindings
