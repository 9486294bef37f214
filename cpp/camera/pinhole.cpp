// Camera "pinhole": the declared parameters of PinholeCamera (camera/camera.h), from which
// scene files, scenarios and the docs take the camera's vocabulary.
#include "camera/camera.h"
#include "core/error.h"
#include "core/plugin.h"

namespace sg {

namespace {

PluginInfo info() {
  return PluginInfo("camera", "pinhole",
                    "A pinhole camera in the OpenCV convention (x right, y down, z forward): a vertical field of "
                    "view (principal point at the image centre) or intrinsics fx, fy, cx, cy in pixels.")
      .add(param::integer("width", 640, "image width in pixels").in(1, 65536))
      .add(param::integer("height", 480, "image height in pixels").in(1, 65536))
      .add(param::real("fov_y", 45.0, "vertical field of view in degrees (principal point at the image centre)")
               .above(0)
               .below(180))
      .add(param::real("fx", "focal length in pixels along x (OpenCV K; instead of fov_y)").above(0))
      .add(param::real("fy", "focal length in pixels along y").above(0).default_is("fx"))
      .add(param::real("cx", "principal point x in pixels").default_is("width / 2"))
      .add(param::real("cy", "principal point y in pixels").default_is("height / 2"))
      .add(param::real("k1", 0.0, "radial distortion coefficient k1 (OpenCV model; rays go through the distorted lens)"))
      .add(param::real("k2", 0.0, "radial distortion coefficient k2"))
      .add(param::real("p1", 0.0, "tangential distortion coefficient p1"))
      .add(param::real("p2", 0.0, "tangential distortion coefficient p2"))
      .add(param::real("k3", 0.0, "radial distortion coefficient k3"))
      .add(param::matrix4("world_from_camera", "camera-to-world pose (row-major 4x4; default: the identity)"))
      .exclusive_of({"fov_y"}, {"fx", "fy", "cx", "cy"})
      .requires_all("fy", {"fx"})
      .requires_all("cx", {"fx"})
      .requires_all("cy", {"fx"});
}

std::shared_ptr<PinholeCamera> create(const Params& p, const PluginContext&) {
  Transform wfc;
  if (p.has("world_from_camera")) {
    std::vector<float> m = p.get_floats("world_from_camera");
    wfc = Transform::from_row_major(m.data(), "world_from_camera");
  }
  uint32_t w = uint32_t(p.get_int("width")), h = uint32_t(p.get_int("height"));
  std::shared_ptr<PinholeCamera> c;
  if (!p.has("fx")) {
    c = std::make_shared<PinholeCamera>(PinholeCamera::from_fov(p.get_float("fov_y"), w, h, wfc));
  } else {
    c = std::make_shared<PinholeCamera>();
    c->fx = p.get_float("fx");
    c->fy = p.get_float_or("fy", c->fx);
    c->cx = p.get_float_or("cx", 0.5f * float(w));
    c->cy = p.get_float_or("cy", 0.5f * float(h));
    c->width = w;
    c->height = h;
    c->world_from_camera = wfc;
  }
  c->k1 = p.get_float("k1");
  c->k2 = p.get_float("k2");
  c->p1 = p.get_float("p1");
  c->p2 = p.get_float("p2");
  c->k3 = p.get_float("k3");
  c->validate();
  return c;
}

}  // namespace

SG_REGISTER_PLUGIN(PinholeCamera, info(), create)

PinholeCamera PinholeCamera::from_params(const ParamSet& params, const std::string& context) {
  return *Registry::instance().create<PinholeCamera>("camera", "pinhole", params, PluginContext{}, context);
}

}  // namespace sg
