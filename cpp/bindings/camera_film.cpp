// Python bindings of the camera (PinholeCamera) and of a render's outputs (RenderResult: the
// Film's buffers as numpy views, no copies).
#include <array>
#include <cmath>

#include <pybind11/stl.h>

#include "bindings/convert.h"
#include "camera/camera.h"

namespace sg::bindings {

namespace {

py::dict stats_to_dict(const RenderStats& s) {
  py::dict d;
  d["wall_time_s"] = s.wall_time_s;
  d["samples_per_s"] = s.samples_per_s;
  d["rays_per_s"] = s.rays_per_s;
  d["samples"] = s.samples;
  d["rays"] = s.rays;
  d["nan_samples"] = s.nan_samples;
  d["mesh_bvh_builds"] = s.mesh_bvh_builds;
  d["mesh_bvh_builds_last_commit"] = s.mesh_bvh_builds_last_commit;
  d["top_level_builds"] = s.top_level_builds;
  d["alpha_test_calls"] = s.alpha_test_calls;
  d["threads"] = s.threads;
  d["estimated_psnr_db"] = s.estimated_psnr_db;
  d["denoise_time_s"] = s.denoise_time_s;
  d["texture_lod_time_s"] = s.texture_lod_time_s;
  d["texture_baked_bytes"] = s.texture_baked_bytes;
  d["texture_bytes_full"] = s.texture_bytes_full;
  d["texture_bytes_resident"] = s.texture_bytes_resident;
  return d;
}

/// A getter of one of the Film's differential buffers (None when the render was not differential).
auto differential_buffer(std::vector<float> Film::*buffer, py::ssize_t channels) {
  return [buffer, channels](std::shared_ptr<Film> f) -> py::object {
    if (!f->differential) return py::none();
    std::vector<py::ssize_t> shape{f->height, f->width};
    if (channels > 1) shape.push_back(channels);
    return wrap(f, (*f).*buffer, shape);
  };
}

}  // namespace

void bind_camera(py::module_& m) {
  py::class_<PinholeCamera>(m, "PinholeCamera", R"doc(Pinhole camera in the OpenCV convention.

Camera space: x right, y down, z forward. A camera-space point (X, Y, Z) projects to
u = fx X/Z + cx, v = fy Y/Z + cy and lands in pixel (floor(u), floor(v)); pixel (i, j)
has its centre at (i + 0.5, j + 0.5). world_from_camera maps camera to world space.)doc")
      .def(py::init([](float fx, float fy, float cx, float cy, uint32_t width, uint32_t height,
                       const py::object& world_from_camera, const std::array<float, 5>& distortion) {
             PinholeCamera c;
             c.fx = fx;
             c.fy = fy;
             c.cx = cx;
             c.cy = cy;
             c.width = width;
             c.height = height;
             c.world_from_camera = transform_from_py(world_from_camera, "world_from_camera");
             c.k1 = distortion[0];
             c.k2 = distortion[1];
             c.p1 = distortion[2];
             c.p2 = distortion[3];
             c.k3 = distortion[4];
             c.validate();
             return c;
           }),
           py::arg("fx"), py::arg("fy"), py::arg("cx"), py::arg("cy"), py::arg("width"), py::arg("height"),
           py::arg("world_from_camera") = py::none(), py::arg("distortion") = std::array<float, 5>{0, 0, 0, 0, 0},
           "distortion: OpenCV's (k1, k2, p1, p2, k3); camera rays go through the distorted lens.")
      .def_static("from_params",
                  [](const py::dict& params) { return PinholeCamera::from_params(params_from_dict(params, "camera"), "camera"); },
                  py::arg("params"),
                  "The camera of plugin 'pinhole' from its declared parameters (width, height, fov_y or fx, fy,\n"
                  "cx, cy, world_from_camera as 16 numbers); see plugin_info('camera', 'pinhole').")
      .def_readonly("fx", &PinholeCamera::fx)
      .def_readonly("fy", &PinholeCamera::fy)
      .def_readonly("cx", &PinholeCamera::cx)
      .def_readonly("cy", &PinholeCamera::cy)
      .def_property_readonly("distortion",
                             [](const PinholeCamera& c) { return std::array<float, 5>{c.k1, c.k2, c.p1, c.p2, c.k3}; },
                             "OpenCV distortion coefficients (k1, k2, p1, p2, k3).")
      .def("distort",
           [](const PinholeCamera& c, float x, float y) {
             Vec2f d = c.distort({x, y});
             return py::make_tuple(d.x, d.y);
           },
           py::arg("x"), py::arg("y"), "The distorted normalized point of normalized point (x, y) = (X/Z, Y/Z).")
      .def("undistort",
           [](const PinholeCamera& c, float x, float y) -> py::object {
             Vec2f u;
             if (!c.undistort({x, y}, &u)) return py::none();
             return py::make_tuple(u.x, u.y);
           },
           py::arg("x"), py::arg("y"), "The normalized point that distorts to (x, y), or None (no convergence).")
      .def_readonly("width", &PinholeCamera::width)
      .def_readonly("height", &PinholeCamera::height)
      .def_property_readonly("world_from_camera", [](const PinholeCamera& c) { return transform_to_py(c.world_from_camera); })
      .def_property_readonly("K", [](const PinholeCamera& c) {
        py::array_t<double> k({3, 3});
        double* d = k.mutable_data();
        double v[9] = {c.fx, 0, c.cx, 0, c.fy, c.cy, 0, 0, 1};
        std::copy(v, v + 9, d);
        return k;
      }, "3x3 intrinsic matrix.")
      .def_static("from_fov",
                  [](float vfov, uint32_t w, uint32_t h, const py::object& wfc) {
                    return PinholeCamera::from_fov(vfov, w, h, transform_from_py(wfc, "world_from_camera"));
                  },
                  py::arg("vfov_degrees"), py::arg("width"), py::arg("height"), py::arg("world_from_camera") = py::none(),
                  "Intrinsics from a vertical field of view (degrees); principal point at the image centre.")
      .def_static("look_at",
                  [](std::array<float, 3> eye, std::array<float, 3> target, std::array<float, 3> up) {
                    return transform_to_py(PinholeCamera::look_at({eye[0], eye[1], eye[2]}, {target[0], target[1], target[2]},
                                                                  {up[0], up[1], up[2]}));
                  },
                  py::arg("eye"), py::arg("target"), py::arg("up") = std::array<float, 3>{0.f, 1.f, 0.f},
                  "world_from_camera (4x4) for a camera at eye looking at target; image y points along -up.")
      .def("project",
           [](const PinholeCamera& c, std::array<float, 3> p) -> py::object {
             float u, v;
             if (!c.project({p[0], p[1], p[2]}, &u, &v)) return py::none();
             return py::make_tuple(u, v);
           },
           py::arg("point"), "Continuous image coordinates (u, v) of a world point, or None behind the camera.")
      .def("project_points",
           [](const PinholeCamera& c, py::array_t<double, py::array::c_style | py::array::forcecast> points) {
             if (points.ndim() != 2 || points.shape(1) != 3)
               throw Error("project_points: expected an N x 3 array of world points");
             const py::ssize_t n = points.shape(0);
             py::array_t<double> out({n, py::ssize_t(2)});
             auto p = points.unchecked<2>();
             auto o = out.mutable_unchecked<2>();
             for (py::ssize_t i = 0; i < n; ++i) {
               // NOTE: the points rounded to float as project() takes them, so both agree exactly.
               float u, v;
               const bool seen = c.project({float(p(i, 0)), float(p(i, 1)), float(p(i, 2))}, &u, &v);
               o(i, 0) = seen ? double(u) : std::nan("");
               o(i, 1) = seen ? double(v) : std::nan("");
             }
             return out;
           },
           py::arg("points"),
           "project() of each row of an N x 3 array of world points: N x 2 (u, v), NaN where behind the camera.")
      .def("generate_ray",
           [](const PinholeCamera& c, float u, float v) {
             Ray r = c.generate_ray(u, v);
             return py::make_tuple(std::array<float, 3>{r.o.x, r.o.y, r.o.z}, std::array<float, 3>{r.d.x, r.d.y, r.d.z});
           },
           py::arg("u"), py::arg("v"), "(origin, unit direction) of the ray through image position (u, v).");
}

void bind_render_result(py::module_& m) {
  py::class_<Film, std::shared_ptr<Film>>(m, "RenderResult",
                                          "Outputs of Scene.render as numpy arrays (views of the render's buffers).")
      .def_property_readonly(
          "rgb", [](std::shared_ptr<Film> f) { return wrap(f, f->rgb, {f->height, f->width, 3}); },
          "H x W x 3 float32 linear radiance (scene-referred, not display-encoded: srgb8() or\n"
          "synthgen.outputs.files.write_srgb_png for viewing; write_exr keeps it linear).")
      .def_property_readonly(
          "alpha", [](std::shared_ptr<Film> f) { return wrap(f, f->alpha, {f->height, f->width}); },
          "H x W float32 coverage: the fraction of a pixel's samples whose camera ray hit a surface.")
      .def_property_readonly(
          "depth", [](std::shared_ptr<Film> f) { return wrap(f, f->depth, {f->height, f->width}); },
          "H x W float32 camera-space z of the first hit at the pixel centre, metres (+inf: background).")
      .def_property_readonly(
          "distance", [](std::shared_ptr<Film> f) { return wrap(f, f->distance, {f->height, f->width}); },
          "H x W float32 distance along the pixel-centre ray to the first hit, metres (+inf: background).")
      .def_property_readonly(
          "normal", [](std::shared_ptr<Film> f) { return wrap(f, f->normal, {f->height, f->width, 3}); },
          "H x W x 3 float32 world-space shading normal of the first hit (0 on background).")
      .def_property_readonly(
          "albedo", [](std::shared_ptr<Film> f) { return wrap(f, f->albedo, {f->height, f->width, 3}); },
          "H x W x 3 float32 albedo of the first hit (linear; 0 on background).")
      .def_property_readonly(
          "instance_id", [](std::shared_ptr<Film> f) { return wrap(f, f->instance_id, {f->height, f->width}); },
          "H x W uint32 instance id of the first hit at the pixel centre (0: background).")
      .def_property_readonly(
          "class_id", [](std::shared_ptr<Film> f) { return wrap(f, f->class_id, {f->height, f->width}); },
          "H x W uint32 class id of the first hit at the pixel centre (0: background).")
      .def_property_readonly(
          "rgb_even", [](std::shared_ptr<Film> f) { return wrap(f, f->rgb_even, {f->height, f->width, 3}); },
          "H x W x 3 float32: the mean of each pixel's even-numbered samples (with rgb_odd, two independent\n"
          "half-sample estimates whose difference measures rgb's noise: synthgen.post.noise).")
      .def_property_readonly(
          "rgb_odd", [](std::shared_ptr<Film> f) { return wrap(f, f->rgb_odd, {f->height, f->width, 3}); },
          "H x W x 3 float32: the mean of each pixel's odd-numbered samples.")
      .def_property_readonly(
          "variance", [](std::shared_ptr<Film> f) { return wrap(f, f->variance, {f->height, f->width, 3}); },
          "H x W x 3 float32: the variance of rgb's per-pixel mean (the samples' unbiased variance / their\n"
          "number; 0 with fewer than two samples).")
      .def_property_readonly(
          "albedo_even", [](std::shared_ptr<Film> f) { return wrap(f, f->albedo_even, {f->height, f->width, 3}); },
          "H x W x 3 float32: the denoiser's albedo feature, mean over the even-numbered samples of the albedo\n"
          "at each sample's first vertex that is not a mirror or glass (escaped samples: 1).")
      .def_property_readonly(
          "albedo_odd", [](std::shared_ptr<Film> f) { return wrap(f, f->albedo_odd, {f->height, f->width, 3}); },
          "H x W x 3 float32: albedo_even over the odd-numbered samples.")
      .def_property_readonly(
          "normal_even", [](std::shared_ptr<Film> f) { return wrap(f, f->normal_even, {f->height, f->width, 3}); },
          "H x W x 3 float32: the denoiser's normal feature (shading normal at that vertex, escaped samples 0),\n"
          "mean over the even-numbered samples.")
      .def_property_readonly(
          "normal_odd", [](std::shared_ptr<Film> f) { return wrap(f, f->normal_odd, {f->height, f->width, 3}); },
          "H x W x 3 float32: normal_even over the odd-numbered samples.")
      .def_property_readonly(
          "depth_even", [](std::shared_ptr<Film> f) { return wrap(f, f->depth_even, {f->height, f->width}); },
          "H x W float32: the denoiser's depth feature (path length to that vertex in metres; escaped samples\n"
          "a finite distance beyond the scene), mean over the even-numbered samples.")
      .def_property_readonly(
          "depth_odd", [](std::shared_ptr<Film> f) { return wrap(f, f->depth_odd, {f->height, f->width}); },
          "H x W float32: depth_even over the odd-numbered samples.")
      .def_property_readonly(
          "rgb_noisy",
          [](std::shared_ptr<Film> f) -> py::object {
            if (f->rgb_noisy.empty()) return py::none();
            return wrap(f, f->rgb_noisy, {f->height, f->width, 3});
          },
          "H x W x 3 float32: rgb before denoising when the render denoised (render(..., denoise=True): rgb is\n"
          "then the denoised image); None otherwise.")
      .def_property_readonly(
          "sample_count", [](std::shared_ptr<Film> f) { return wrap(f, f->sample_count, {f->height, f->width}); },
          "H x W uint32: the samples each pixel got (spp; with adaptive sampling, its own count).")
      .def_property_readonly("differential", [](std::shared_ptr<Film> f) { return f->differential; },
                             "True when the scene had catchers: the five buffers below are filled (else None).")
      .def_property_readonly(
          "synthetic_rgb",
          differential_buffer(&Film::synthetic_rgb, 3),
          "H x W x 3 float32: radiance of the samples whose camera ray first hit an inserted (non-catcher)\n"
          "object, divided by all the pixel's samples (premultiplied by synthetic_alpha).")
      .def_property_readonly(
          "synthetic_alpha",
          differential_buffer(&Film::synthetic_alpha, 1),
          "H x W float32: the fraction of samples whose camera ray first hit an inserted object.")
      .def_property_readonly(
          "catcher_with",
          differential_buffer(&Film::catcher_with, 3),
          "H x W x 3 float32: radiance of the other samples (catchers, background) with the objects.")
      .def_property_readonly(
          "catcher_without",
          differential_buffer(&Film::catcher_without, 3),
          "H x W x 3 float32: the same samples' radiance without the inserted objects (same random\n"
          "numbers: equal to catcher_with bit for bit where the objects have no influence).")
      .def_property_readonly(
          "behind_synthetic",
          differential_buffer(&Film::behind_synthetic, 3),
          "H x W x 3 float32: the synthetic samples' radiance without the objects (what they hide).")
      .def_property_readonly(
          "stats", [](std::shared_ptr<Film> f) { return stats_to_dict(f->stats); },
          "Render statistics: timings, rays, samples, BVH builds of the last commit, ...");
}

}  // namespace sg::bindings
