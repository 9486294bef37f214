// Bindings of geometry queries: surface_distances (geometry/accel.h).
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include "bindings/convert.h"
#include "core/error.h"
#include "geometry/accel.h"

namespace sg::bindings {

void bind_geometry(py::module_& m) {
  m.def(
      "surface_distances",
      [](py::array_t<float, py::array::c_style | py::array::forcecast> positions,
         py::array_t<int64_t, py::array::c_style | py::array::forcecast> indices,
         py::array_t<float, py::array::c_style | py::array::forcecast> points, bool return_triangles) -> py::object {
        auto shape_ok = [](const py::array& a, const char* what) {
          if (a.ndim() != 2 || a.shape(1) != 3)
            throw Error(std::string("surface_distances: ") + what + " must be an (n, 3) array");
        };
        shape_ok(positions, "positions");
        shape_ok(indices, "indices");
        shape_ok(points, "points");
        TriangleMesh mesh;
        mesh.name = "surface_distances";
        const float* p = positions.data();
        for (py::ssize_t i = 0; i < positions.shape(0); ++i)
          mesh.positions.emplace_back(p[3 * i], p[3 * i + 1], p[3 * i + 2]);
        const int64_t* t = indices.data();
        for (py::ssize_t i = 0; i < 3 * indices.shape(0); ++i) {
          if (t[i] < 0 || t[i] >= positions.shape(0))
            throw Error("surface_distances: index " + std::to_string(t[i]) + " out of range");
          mesh.indices.push_back(uint32_t(t[i]));
        }
        std::vector<Vec3f> q;
        const float* x = points.data();
        for (py::ssize_t i = 0; i < points.shape(0); ++i) q.emplace_back(x[3 * i], x[3 * i + 1], x[3 * i + 2]);
        std::vector<float> d;
        std::vector<uint32_t> tri;
        {
          py::gil_scoped_release release;
          d = surface_distances(mesh, q, return_triangles ? &tri : nullptr);
        }
        py::array_t<float> out(py::ssize_t(d.size()));
        std::copy(d.begin(), d.end(), out.mutable_data());
        if (!return_triangles) return std::move(out);
        py::array_t<int64_t> closest(py::ssize_t(tri.size()));
        std::copy(tri.begin(), tri.end(), closest.mutable_data());
        return py::make_tuple(out, closest);
      },
      py::arg("positions"), py::arg("indices"), py::arg("points"), py::arg("return_triangles") = false,
      "Distance (float32) from each point (n x 3) to the closest point of the triangle mesh\n"
      "(positions m x 3, indices k x 3): exact, by Embree point queries. Measures the geometric\n"
      "error of a level of detail (synthgen.scene.lod). With return_triangles: (distances, index of\n"
      "each point's closest triangle).");
}

}  // namespace sg::bindings
