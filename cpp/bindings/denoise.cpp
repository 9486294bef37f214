// Python binding of the denoiser (film/denoise.h): synthgen._core.denoise.
#include <array>
#include <string>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include "bindings/convert.h"
#include "film/denoise.h"

namespace sg::bindings {

namespace {

using FloatArray = py::array_t<float, py::array::c_style | py::array::forcecast>;

/// A C-contiguous float32 array of shape (h, w, channels) ((h, w) for one channel).
FloatArray image_arg(const py::object& o, const char* name, py::ssize_t h, py::ssize_t w, int channels) {
  FloatArray a = FloatArray::ensure(o);
  if (!a) throw Error(std::string("denoise: ") + name + " is not a float array");
  const bool ok = channels == 1 ? (a.ndim() == 2 && a.shape(0) == h && a.shape(1) == w)
                                : (a.ndim() == 3 && a.shape(0) == h && a.shape(1) == w && a.shape(2) == channels);
  if (!ok) {
    std::string got = "(";
    for (py::ssize_t i = 0; i < a.ndim(); ++i) got += (i ? ", " : "") + std::to_string(a.shape(i));
    got += a.ndim() == 1 ? ",)" : ")";
    std::string want = "(" + std::to_string(h) + ", " + std::to_string(w) +
                       (channels == 1 ? std::string(")") : ", " + std::to_string(channels) + ")");
    throw Error(std::string("denoise: ") + name + " has shape " + got + ", expected " + want);
  }
  return a;
}

}  // namespace

void bind_denoise(py::module_& m) {
  const DenoiseSettings d;
  m.def(
      "denoise",
      [](const py::object& rgb_even, const py::object& rgb_odd, const py::object& albedo_even,
         const py::object& albedo_odd, const py::object& normal_even, const py::object& normal_odd,
         const py::object& depth_even, const py::object& depth_odd, const py::object& variance, int radius,
         int patch_radius, float k, int feature_radius, int selection_radius, float albedo_floor, float ridge,
         float firefly_ratio, bool second_pass, float distance_floor, float normal_weight) {
        FloatArray first = FloatArray::ensure(rgb_even);
        if (!first || first.ndim() != 3 || first.shape(2) != 3 || first.shape(0) == 0 || first.shape(1) == 0)
          throw Error("denoise: rgb_even must be a non-empty H x W x 3 float array");
        const py::ssize_t h = first.shape(0), w = first.shape(1);
        std::array<FloatArray, 9> a = {
            image_arg(rgb_even, "rgb_even", h, w, 3),       image_arg(rgb_odd, "rgb_odd", h, w, 3),
            image_arg(albedo_even, "albedo_even", h, w, 3), image_arg(albedo_odd, "albedo_odd", h, w, 3),
            image_arg(normal_even, "normal_even", h, w, 3), image_arg(normal_odd, "normal_odd", h, w, 3),
            image_arg(depth_even, "depth_even", h, w, 1),   image_arg(depth_odd, "depth_odd", h, w, 1),
            variance.is_none() ? FloatArray() : image_arg(variance, "variance", h, w, 3)};
        DenoiseInput in;
        in.width = uint32_t(w);
        in.height = uint32_t(h);
        // The same Python object twice is one buffer: the denoiser then skips prefiltering it.
        auto pair = [&](const float* (&dst)[2], size_t i, const py::object& o0, const py::object& o1) {
          dst[0] = a[i].data();
          dst[1] = o0.is(o1) ? a[i].data() : a[i + 1].data();
        };
        in.rgb[0] = a[0].data();
        in.rgb[1] = a[1].data();
        pair(in.albedo, 2, albedo_even, albedo_odd);
        pair(in.normal, 4, normal_even, normal_odd);
        pair(in.depth, 6, depth_even, depth_odd);
        in.variance = variance.is_none() ? nullptr : a[8].data();
        DenoiseSettings s;
        s.radius = radius;
        s.patch_radius = patch_radius;
        s.k = k;
        s.feature_radius = feature_radius;
        s.selection_radius = selection_radius;
        s.albedo_floor = albedo_floor;
        s.ridge = ridge;
        s.firefly_ratio = firefly_ratio;
        s.second_pass = second_pass;
        s.distance_floor = distance_floor;
        s.normal_weight = normal_weight;
        py::array_t<float> out({h, w, py::ssize_t(3)});
        float* dst = out.mutable_data();
        {
          py::gil_scoped_release release;
          denoise(in, s, dst);
        }
        return out;
      },
      py::arg("rgb_even"), py::arg("rgb_odd"), py::arg("albedo_even"), py::arg("albedo_odd"), py::arg("normal_even"),
      py::arg("normal_odd"), py::arg("depth_even"), py::arg("depth_odd"), py::arg("variance") = py::none(),
      py::arg("radius") = d.radius, py::arg("patch_radius") = d.patch_radius, py::arg("k") = d.k,
      py::arg("feature_radius") = d.feature_radius, py::arg("selection_radius") = d.selection_radius,
      py::arg("albedo_floor") = d.albedo_floor, py::arg("ridge") = d.ridge, py::arg("firefly_ratio") = d.firefly_ratio,
      py::arg("second_pass") = d.second_pass, py::arg("distance_floor") = d.distance_floor,
      py::arg("normal_weight") = d.normal_weight,
      "Denoises a render from its two half-sample images (H x W x 3 float32 each) and its features\n"
      "(albedo and normal H x W x 3, depth H x W; each as two halves -- the same array twice when the\n"
      "render has only pixel-centre features); returns H x W x 3 float32 linear radiance.\n"
      "A reduced NFOR (Bitterli et al. 2016): per-pixel first-order regression on position, depth,\n"
      "normal and albedo with NL-means weights from the other half, two bandwidths (k, k/2) blended\n"
      "by their error estimated from the halves, albedo demodulation. Optional `variance`: the\n"
      "variance of the mean (RenderResult.variance); without it the halves' difference is used.\n"
      "Settings: radius (window half-size), patch_radius, k, feature_radius (feature prefilter),\n"
      "selection_radius, albedo_floor (0: no demodulation), ridge, firefly_ratio (0: off), second_pass,\n"
      "distance_floor (relative variance floor of the weights), normal_weight (bilateral normal term).\n"
      "Deterministic for any number of threads. Raises SynthgenError on bad shapes or settings.\n"
      "Use synthgen.post.denoise.denoise.");
}

}  // namespace sg::bindings
