// The plugin registry (core/plugin.h): every plugin file is registered under its file
// name, declarations are consistent, and the checks and defaults of the declarations are
// what factories see.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <map>
#include <set>

#include "api/scene.h"
#include "camera/camera.h"
#include "core/plugin.h"
#include "integrator/path_tracer.h"
#include "texture/image_cache.h"

using namespace sg;
namespace fs = std::filesystem;

namespace {

const fs::path k_cpp = fs::path(SYNTHGEN_SOURCE_DIR) / "cpp";

// Source files of a plugin folder that are not plugins, with the reason. Every other .cpp
// file of the folder must register exactly the plugin named like the file.
const std::map<std::string, std::string> k_not_plugins = {
    {"material/material.cpp", "the Material interface and create_material"},
    {"texture/texture.cpp", "the Texture interface and create_texture"},
    {"texture/image_cache.cpp", "decoded images shared by image textures"},
    {"texture/mipmap.cpp", "mip-map pyramids and filtered lookups"},
    {"texture/footprint.cpp", "footprints of texture lookups, recorded for the texture resolution estimate"},
    {"texture/baked.cpp", "procedural textures baked on demand (bake: auto)"},
    {"light/light.cpp", "the Light interface and create_light"},
    {"medium/tracking.cpp", "majorant grids and tracking shared by the heterogeneous media"},
    {"light/area.cpp", "area lights are made by the scene from emissive materials"},
    {"medium/medium.cpp", "the Medium interface and create_medium"},
    {"camera/camera.cpp", "PinholeCamera itself; its plugin declaration is camera/pinhole.cpp"},
};

std::string error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST(registry, every_plugin_file_is_registered_under_its_name) {
  const Registry& r = Registry::instance();
  const std::map<std::string, std::string> folders = {
      {"material", "material"}, {"texture", "texture"}, {"light", "light"}, {"camera", "camera"}, {"medium", "medium"}};
  for (const auto& [kind, folder] : folders) {
    std::set<std::string> files;
    for (const auto& entry : fs::directory_iterator(k_cpp / folder)) {
      if (entry.path().extension() != ".cpp") continue;
      std::string rel = folder + "/" + entry.path().filename().string();
      if (k_not_plugins.count(rel)) continue;
      files.insert(entry.path().stem().string());
    }
    std::vector<std::string> names = r.names(kind);
    std::set<std::string> registered(names.begin(), names.end());
    EXPECT_EQ(files, registered) << "cpp/" << folder << ": every plugin file must register (SG_REGISTER_PLUGIN) "
                                 << "the plugin named like the file, and nothing else";
    for (const auto& n : names)
      EXPECT_EQ(r.info(kind, n).file, "cpp/" + folder + "/" + n + ".cpp") << kind << " " << n;
  }
  // The render settings are declared by the path tracer.
  EXPECT_EQ(r.info("render", "path_tracer").file, "cpp/integrator/path_tracer.cpp");
  EXPECT_EQ(r.kinds(), (std::vector<std::string>{"camera", "light", "material", "medium", "render", "texture"}));
}

TEST(registry, declarations_are_consistent) {
  const Registry& r = Registry::instance();
  for (const auto& kind : r.kinds())
    for (const auto& name : r.names(kind)) {
      const PluginInfo& info = r.info(kind, name);
      std::string what = info.label();
      EXPECT_FALSE(info.doc.empty()) << what;
      std::set<std::string> keys;
      for (const auto& p : info.params) {
        EXPECT_TRUE(keys.insert(p.name).second) << what << ": '" << p.name << "' declared twice";
        for (const auto& a : p.aliases) EXPECT_TRUE(keys.insert(a).second) << what << ": alias '" << a << "'";
        EXPECT_FALSE(p.doc.empty()) << what << ": '" << p.name << "' has no doc";
        EXPECT_FALSE(p.required && p.has_default) << what << ": '" << p.name << "' is required and has a default";
        // A declared default passes the declaration's own checks.
        if (p.has_default) {
          EXPECT_NO_THROW(check_param_value(p, p.default_value)) << what << ": default of '" << p.name << "'";
        }
      }
      auto declared = [&](const std::string& k) { return info.find(k) != nullptr; };
      for (const auto& [a, b] : info.exclusive)
        for (const auto& k : a) EXPECT_TRUE(declared(k)) << what << ": exclusive names '" << k << "'";
      for (const auto& [k, others] : info.requires) {
        EXPECT_TRUE(declared(k)) << what << ": requires names '" << k << "'";
        for (const auto& o : others) EXPECT_TRUE(declared(o)) << what << ": requires names '" << o << "'";
      }
      for (const auto& g : info.one_of)
        for (const auto& k : g) EXPECT_TRUE(declared(k)) << what << ": one_of names '" << k << "'";
    }
}

TEST(registry, checks_come_from_the_declaration) {
  const PluginInfo& diffuse = Registry::instance().info("material", "diffuse");
  auto params = [](std::initializer_list<std::pair<const char*, ParamSet::Value>> kv) {
    ParamSet p;
    for (const auto& [k, v] : kv) p.set(k, v);
    return p;
  };
  std::string e = error_of([&] { Params(diffuse, params({{"albdo", 0.5}})); });
  EXPECT_NE(e.find("unknown parameter 'albdo' (did you mean 'albedo'?)"), std::string::npos) << e;
  EXPECT_NE(e.find("accepted parameters: albedo, alpha, alpha_cutoff, bump_map, bump_scale"), std::string::npos) << e;
  e = error_of([&] { Params(diffuse, params({{"alpha_cutoff", 1.5}})); });
  EXPECT_NE(e.find("parameter 'alpha_cutoff': must lie in [0, 1], got 1.5"), std::string::npos) << e;
  e = error_of([&] { Params(diffuse, params({{"albedo", std::vector<double>{0.5, 2.0, 0.5}}})); });
  EXPECT_NE(e.find("parameter 'albedo': components must lie in [0, 1], got 2"), std::string::npos) << e;
  e = error_of([&] { Params(diffuse, params({{"albedo", std::string("red")}})); });
  EXPECT_NE(e.find("parameter 'albedo': expected a colour"), std::string::npos) << e;
  e = error_of([&] { Params(diffuse, params({{"bump_map", 1.0}})); });
  EXPECT_NE(e.find("expected a texture reference"), std::string::npos) << e;
  e = error_of([&] { Params(diffuse, params({{"bump_scale", std::nan("")}})); });
  EXPECT_NE(e.find("not finite"), std::string::npos) << e;

  const PluginInfo& conductor = Registry::instance().info("material", "conductor");
  e = error_of([&] { Params(conductor, params({{"metal", std::string("gld")}})); });
  EXPECT_NE(e.find("unknown value 'gld' (did you mean 'gold'?)"), std::string::npos) << e;
  e = error_of([&] { Params(conductor, params({{"metal", std::string("gold")}, {"eta", 1.0}, {"k", 1.0}})); });
  EXPECT_NE(e.find("parameters 'metal' and 'eta' cannot be combined"), std::string::npos) << e;
  e = error_of([&] { Params(conductor, params({{"eta", 1.0}})); });
  EXPECT_NE(e.find("parameter 'eta' requires 'k'"), std::string::npos) << e;

  const PluginInfo& projector = Registry::instance().info("texture", "projector");
  e = error_of([&] { Params(projector, params({{"texture", TextureRef{0}}})); });
  EXPECT_NE(e.find("give exactly one of 'world_from_projector' or 'position'"), std::string::npos) << e;
  e = error_of([&] { Params(projector, params({})); });
  EXPECT_NE(e.find("parameter 'texture' is required"), std::string::npos) << e;

  // Aliases: "filename" is "file"; both at once are an error.
  const PluginInfo& image = Registry::instance().info("texture", "image");
  Params aliased(image, params({{"filename", std::string("a.png")}}));
  EXPECT_TRUE(aliased.has("file"));
  EXPECT_EQ(aliased.get_string("file"), "a.png");
  e = error_of([&] { Params(image, params({{"file", std::string("a.png")}, {"filename", std::string("b.png")}})); });
  EXPECT_NE(e.find("given twice"), std::string::npos) << e;
}

TEST(registry, factories_see_declared_defaults) {
  const PluginInfo& coated = Registry::instance().info("material", "coated");
  Params p(coated, ParamSet());
  EXPECT_FALSE(p.has("ior"));
  EXPECT_EQ(p.get_float("ior"), 1.5f);
  EXPECT_EQ(p.get_float("roughness"), 0.f);
  EXPECT_EQ(p.get_color("albedo"), Color(0.5f));
  // Reading an undeclared parameter is a bug of the plugin, reported as such.
  std::string e = error_of([&] { p.get_float("roughnes"); });
  EXPECT_NE(e.find("undeclared parameter 'roughnes'"), std::string::npos) << e;
  // A parameter without a default must be given (or read with its dynamic default).
  const PluginInfo& spot = Registry::instance().info("light", "spot");
  Params s(spot, ParamSet());
  e = error_of([&] { s.get_float("falloff_start"); });
  EXPECT_NE(e.find("min(25, cone_angle)"), std::string::npos) << e;
  EXPECT_EQ(s.get_float_or("falloff_start", 7.f), 7.f);

  // The render settings: RenderSettings' own member defaults equal the declared ones.
  RenderSettings declared = RenderSettings::from_params(ParamSet());
  RenderSettings plain;
  EXPECT_EQ(declared.spp, plain.spp);
  EXPECT_EQ(declared.max_depth, plain.max_depth);
  EXPECT_EQ(declared.rr_depth, plain.rr_depth);
  EXPECT_EQ(declared.seed, plain.seed);
  EXPECT_EQ(declared.threads, plain.threads);
  EXPECT_EQ(declared.tile_size, plain.tile_size);
  EXPECT_EQ(declared.texture_filtering, plain.texture_filtering);
}

TEST(registry, camera_plugin_matches_from_fov_and_intrinsics) {
  ParamSet p;
  p.set("width", int64_t(320));
  p.set("height", int64_t(200));
  p.set("fov_y", 50.0);
  PinholeCamera a = PinholeCamera::from_params(p);
  PinholeCamera b = PinholeCamera::from_fov(50.f, 320, 200, Transform());
  EXPECT_EQ(a.fx, b.fx);
  EXPECT_EQ(a.fy, b.fy);
  EXPECT_EQ(a.cx, b.cx);
  EXPECT_EQ(a.cy, b.cy);
  ParamSet q;
  q.set("fx", 400.0);
  q.set("cx", 100.0);
  PinholeCamera c = PinholeCamera::from_params(q);
  EXPECT_EQ(c.fy, 400.f);  // fy defaults to fx
  EXPECT_EQ(c.cx, 100.f);
  EXPECT_EQ(c.cy, 240.f);  // height / 2 of the default 640 x 480
  ParamSet r;
  r.set("fov_y", 40.0);
  r.set("fx", 400.0);
  std::string e = error_of([&] { PinholeCamera::from_params(r); });
  EXPECT_NE(e.find("'fov_y' and 'fx' cannot be combined"), std::string::npos) << e;
}

TEST(registry, in_memory_images_share_a_pyramid_and_replay) {
  Scene s;
  auto px = std::make_shared<ImageData>();
  px->width = 3;
  px->height = 2;
  px->channels = 1;
  px->pixels = {0.f, 0.25f, 0.5f, 0.75f, 1.f, 0.125f};
  ParamSet linear;
  linear.set("colorspace", std::string("linear"));
  uint32_t a = s.add_image_texture(px, false, linear);
  auto copy = std::make_shared<ImageData>(*px);
  uint32_t b = s.add_image_texture(copy, false, linear);
  EXPECT_EQ(s.image_cache().hits(), 1u) << "identical pixels share one pyramid";
  EXPECT_EQ(s.image_cache().loads(), 0u) << "no file is read";
  const Texture& ta = *s.textures()[a]->object;
  EXPECT_NEAR(ta.eval(Vec2f(0.5f / 3.f, 1.f - 0.25f), 0.f).x, 0.f, 1e-6f);
  EXPECT_NEAR(ta.eval(Vec2f(2.5f / 3.f, 1.f - 0.75f), 0.f).x, 0.125f, 1e-6f);
  // 8-bit sources decode as sRGB under colorspace auto, like 8-bit files.
  auto bytes = std::make_shared<ImageData>(*px);
  uint32_t c = s.add_image_texture(bytes, true, ParamSet());
  float v = s.textures()[c]->object->eval(Vec2f(2.5f / 3.f, 1.f - 0.25f), 0.f).x;  // value 0.5
  EXPECT_NEAR(v, 0.21404f, 1e-4f);
  // Saved with the scene and replayed.
  fs::path dir = fs::temp_directory_path() / "synthgen_test_memory_image";
  fs::create_directories(dir);
  s.save((dir / "s.xml").string());
  auto t = Scene::load((dir / "s.xml").string());
  for (uint32_t id : {a, b, c})
    for (float u : {0.1f, 0.5f, 0.9f})
      EXPECT_EQ(t->textures()[id]->object->eval(Vec2f(u, 0.3f), 0.f), s.textures()[id]->object->eval(Vec2f(u, 0.3f), 0.f));
  fs::remove_all(dir);
  ParamSet with_file;
  with_file.set("filename", std::string("x.png"));
  EXPECT_NE(error_of([&] { s.add_image_texture(px, false, with_file); }).find("no 'file'"), std::string::npos);
}
