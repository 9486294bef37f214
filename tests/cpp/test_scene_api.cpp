// The integration API (api/scene.h, api/scene_xml.cpp): incremental commits, id
// stability, save/load round trips that render bit-identically, and error handling.
#include <gtest/gtest.h>

#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <set>
#include <string>
#include <vector>

#include "api/scene.h"
#include "mesh_checks.h"
#include "core/error.h"
#include "core/params.h"
#include "core/sha256.h"

using namespace sg;
using sgtest::box;

namespace {

TriangleMesh quad(float half, float z) {
  TriangleMesh m;
  m.name = "quad";
  m.positions = {{-half, -half, z}, {half, -half, z}, {half, half, z}, {-half, half, z}};
  m.normals = {{0, 0, 1}, {0, 0, 1}, {0, 0, 1}, {0, 0, 1}};
  m.uvs = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
  m.indices = {0, 1, 2, 0, 2, 3};
  return m;
}

TriangleMesh tetra() {
  TriangleMesh m;
  m.name = "tetra";
  m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  m.indices = {0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3};
  return m;
}

ParamSet diffuse_params(double a) {
  ParamSet p;
  p.set("albedo", a);
  return p;
}

PinholeCamera test_camera(uint32_t w = 48, uint32_t h = 36) {
  return PinholeCamera::from_fov(50.f, w, h,
                                 PinholeCamera::look_at(Vec3f(0.f, -8.f, 4.f), Vec3f(0.f, 0.f, 0.5f),
                                                        Vec3f(0.f, 0.f, 1.f)));
}

/// Instance label (film.instance_id) at the pixel where `p` projects.
uint32_t label_at(const Scene& s, const Film& f, const Vec3f& p) {
  float u, v;
  EXPECT_TRUE(s.camera().project(p, &u, &v));
  int x = int(std::floor(u)), y = int(std::floor(v));
  EXPECT_TRUE(x >= 0 && y >= 0 && x < int(f.width) && y < int(f.height)) << "point projects outside the image";
  return f.instance_id[size_t(y) * f.width + size_t(x)];
}

RenderSettings quick_settings() {
  RenderSettings r;
  r.spp = 1;
  r.max_depth = 2;
  r.seed = 3;
  return r;
}

std::string temp_dir() {
  auto dir = std::filesystem::temp_directory_path() /
             ("synthgen_test_scene_api_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  return dir.string();
}

}  // namespace

TEST(scene_api, commit_rebuilds_only_edited_meshes) {
  Scene s;
  uint32_t m_ground = s.add_mesh(quad(5.f, 0.f)), m_box = s.add_mesh(box(Vec3f(-0.5f), Vec3f(0.5f))),
           m_tet = s.add_mesh(tetra());
  uint32_t grey = s.add_material("diffuse", diffuse_params(0.5)), red = s.add_material("diffuse", diffuse_params(0.9));
  uint32_t i_ground = s.add_instance(m_ground, Transform(), 1, std::nullopt, grey);
  uint32_t i_box = s.add_instance(m_box, Transform::translate(Vec3f(-1.5f, 0.f, 0.5f)), 2, 20u, grey);
  uint32_t i_tet = s.add_instance(m_tet, Transform::translate(Vec3f(1.5f, 0.f, 0.f)), 3, 30u);
  (void)i_ground;
  s.set_camera(test_camera());
  s.commit();
  EXPECT_EQ(s.commit_stats().mesh_bvh_builds, 3u);
  EXPECT_EQ(s.commit_stats().mesh_bvh_builds_last_commit, 3u);
  EXPECT_FALSE(s.has_pending_edits());
  Film f;
  s.render(quick_settings(), &f);
  EXPECT_EQ(label_at(s, f, Vec3f(-1.5f, 0.f, 0.5f)), 20u);

  // Move an instance: top level only, and the box really moved.
  s.set_instance_transform(i_box, Transform::translate(Vec3f(-1.5f, 1.5f, 0.5f)));
  EXPECT_TRUE(s.has_pending_edits());
  s.commit();
  EXPECT_EQ(s.commit_stats().mesh_bvh_builds_last_commit, 0u);
  s.render(quick_settings(), &f);
  EXPECT_EQ(label_at(s, f, Vec3f(-1.5f, 1.5f, 0.5f)), 20u);
  EXPECT_NE(label_at(s, f, Vec3f(-1.5f, -0.45f, 0.55f)), 20u) << "the box is still at its old place";

  // Change an instance material.
  s.set_instance_material(i_box, red);
  s.commit();
  EXPECT_EQ(s.commit_stats().mesh_bvh_builds_last_commit, 0u);
  s.render(quick_settings(), &f);
  {
    float u, v;
    s.camera().project(Vec3f(-1.5f, 1.5f, 0.5f), &u, &v);
    EXPECT_FLOAT_EQ(f.albedo[3 * (size_t(v) * f.width + size_t(u))], 0.9f);
  }

  // A new instance of an existing mesh.
  uint32_t i_box2 = s.add_instance(m_box, Transform::translate(Vec3f(0.f, -2.f, 0.5f)), 2, 21u, red);
  s.commit();
  EXPECT_EQ(s.commit_stats().mesh_bvh_builds_last_commit, 0u);
  s.render(quick_settings(), &f);
  EXPECT_EQ(label_at(s, f, Vec3f(0.f, -2.f, 0.5f)), 21u);

  // Update a material.
  s.update_material(red, "diffuse", diffuse_params(0.25));
  s.commit();
  EXPECT_EQ(s.commit_stats().mesh_bvh_builds_last_commit, 0u);
  s.render(quick_settings(), &f);
  {
    float u, v;
    s.camera().project(Vec3f(0.f, -2.f, 0.5f), &u, &v);
    EXPECT_FLOAT_EQ(f.albedo[3 * (size_t(v) * f.width + size_t(u))], 0.25f);
  }

  // Change labels.
  s.set_instance_labels(i_box2, 7, 77);
  EXPECT_TRUE(s.has_pending_edits());
  s.commit();
  EXPECT_EQ(s.commit_stats().mesh_bvh_builds_last_commit, 0u);
  s.render(quick_settings(), &f);
  EXPECT_EQ(label_at(s, f, Vec3f(0.f, -2.f, 0.5f)), 77u);

  // Removing an instance: no mesh build either.
  s.remove_instance(i_tet);
  s.commit();
  EXPECT_EQ(s.commit_stats().mesh_bvh_builds_last_commit, 0u);
  EXPECT_EQ(s.commit_stats().mesh_bvh_builds, 3u);

  // Editing one mesh rebuilds exactly that mesh; both of its instances follow.
  s.update_mesh(m_box, box(Vec3f(-0.5f, -0.5f, -0.5f), Vec3f(0.5f, 0.5f, 1.5f)));
  s.commit();
  EXPECT_EQ(s.commit_stats().mesh_bvh_builds_last_commit, 1u);
  EXPECT_EQ(s.commit_stats().mesh_bvh_builds, 4u);
  s.render(quick_settings(), &f);
  EXPECT_EQ(label_at(s, f, Vec3f(0.f, -2.5f, 1.8f)), 77u) << "second instance does not see the edited mesh";

  // Nothing pending: a commit builds nothing.
  EXPECT_FALSE(s.has_pending_edits());
  s.commit();
  EXPECT_EQ(s.commit_stats().mesh_bvh_builds_last_commit, 0u);
}

namespace {

/// A scene with every kind of object: meshes with normals, uvs and per-triangle
/// materials, a texture, diffuse and emissive materials, instances with and without
/// material overrides, and point, sun and environment lights.
std::unique_ptr<Scene> rich_scene(uint32_t* removed_instance, std::vector<uint32_t>* kept_instances) {
  auto s = std::make_unique<Scene>();
  ParamSet tex;
  tex.set("value", std::vector<double>{0.8, 0.3, 0.2});
  uint32_t t = s->add_texture("constant", tex);
  ParamSet textured;
  textured.set("albedo", TextureRef{t});
  uint32_t m_tex = s->add_material("diffuse", textured);
  uint32_t m_grey = s->add_material("diffuse", diffuse_params(0.6));
  ParamSet lamp;
  lamp.set("radiance", std::vector<double>{4.0, 3.5, 3.0});
  uint32_t m_lamp = s->add_material("emissive", lamp);

  TriangleMesh ground = quad(6.f, 0.f);
  ground.material_ids = {int32_t(m_tex), int32_t(m_grey)};
  uint32_t me_ground = s->add_mesh(std::move(ground));
  uint32_t me_box = s->add_mesh(box(Vec3f(-0.5f), Vec3f(0.5f)));
  uint32_t me_unused = s->add_mesh(tetra());
  uint32_t me_tet = s->add_mesh(tetra());
  TriangleMesh light_quad = quad(0.7f, 0.f);
  for (auto& n : light_quad.normals) n = Vec3f(0.f, 0.f, -1.f);  // faces down
  uint32_t me_light = s->add_mesh(std::move(light_quad));

  kept_instances->push_back(s->add_instance(me_ground, Transform(), 1));
  kept_instances->push_back(s->add_instance(me_box, Transform::translate(Vec3f(-1.2f, 0.3f, 0.5f)), 2, 12u, m_grey));
  *removed_instance = s->add_instance(me_box, Transform::translate(Vec3f(0.f, 0.f, 0.5f)), 2, 13u, m_grey);
  float rot[16] = {0.f, -1.5f, 0.f, 1.4f, 1.5f, 0.f, 0.f, -0.6f, 0.f, 0.f, 1.5f, 0.f, 0, 0, 0, 1};
  kept_instances->push_back(s->add_instance(me_tet, Transform::from_row_major(rot), 3, 14u, m_tex));
  kept_instances->push_back(s->add_instance(me_light, Transform::translate(Vec3f(0.5f, 0.f, 3.5f)), 4, 15u, m_lamp));
  ParamSet sun;
  sun.set("direction", std::vector<double>{0.4, -0.6, 1.0});
  sun.set("irradiance", 2.0);
  uint32_t l_sun = s->add_light("sun", sun);
  ParamSet point;
  point.set("position", std::vector<double>{2.0, -2.0, 2.5});
  point.set("intensity", 5.0);
  uint32_t l_removed = s->add_light("point", point);
  ParamSet env;
  env.set("radiance", std::vector<double>{0.1, 0.15, 0.3});
  s->add_light("environment", env);
  (void)l_sun;
  s->remove_light(l_removed);
  s->remove_mesh(me_unused);
  s->set_camera(test_camera(40, 30));
  s->remove_instance(*removed_instance);
  return s;
}

}  // namespace

TEST(scene_api, save_load_renders_bit_identically_and_keeps_ids) {
  uint32_t removed;
  std::vector<uint32_t> kept;
  auto a = rich_scene(&removed, &kept);
  std::string path = temp_dir() + "/scene.xml";
  a->save(path);
  std::unique_ptr<Scene> b = Scene::load(path);

  // Ids: the removed instance stays a hole, the others address the same objects.
  ASSERT_EQ(b->instances().size(), a->instances().size());
  EXPECT_FALSE(b->instances()[removed].has_value());
  for (uint32_t id : kept) {
    ASSERT_TRUE(b->instances()[id].has_value()) << "instance " << id;
    const auto &ea = *a->instances()[id], &eb = *b->instances()[id];
    EXPECT_EQ(eb.mesh_id, ea.mesh_id);
    EXPECT_EQ(eb.class_id, ea.class_id);
    EXPECT_EQ(eb.instance_id, ea.instance_id);
    EXPECT_EQ(eb.material_id, ea.material_id);
    EXPECT_EQ(eb.world_from_object.m, ea.world_from_object.m);
    EXPECT_EQ(b->mesh(eb.mesh_id).positions.size(), a->mesh(ea.mesh_id).positions.size());
  }
  ASSERT_EQ(b->meshes().size(), a->meshes().size());
  for (size_t i = 0; i < a->meshes().size(); ++i) {
    ASSERT_EQ(b->meshes()[i].has_value(), a->meshes()[i].has_value()) << "mesh " << i;
    if (!a->meshes()[i]) continue;
    const TriangleMesh &ma = *a->meshes()[i]->mesh, &mb = *b->meshes()[i]->mesh;
    EXPECT_EQ(mb.indices, ma.indices);
    EXPECT_EQ(mb.material_ids, ma.material_ids);
    ASSERT_EQ(mb.positions.size(), ma.positions.size());
    for (size_t k = 0; k < ma.positions.size(); ++k) EXPECT_EQ(mb.positions[k], ma.positions[k]);
  }
  ASSERT_EQ(b->lights().size(), a->lights().size());
  for (size_t i = 0; i < a->lights().size(); ++i) {
    ASSERT_EQ(b->lights()[i].has_value(), a->lights()[i].has_value()) << "light " << i;
    if (a->lights()[i]) {
      EXPECT_EQ(b->lights()[i]->type, a->lights()[i]->type);
    }
  }
  ASSERT_EQ(b->materials().size(), a->materials().size());
  for (size_t i = 0; i < a->materials().size(); ++i) EXPECT_EQ(b->materials()[i]->type, a->materials()[i]->type);
  // New ids continue after the highest slot: removed ids are never reused.
  EXPECT_EQ(b->add_instance(b->instances()[kept[1]]->mesh_id, Transform::translate(Vec3f(50.f, 50.f, 50.f))), uint32_t(a->instances().size()));
  b->remove_instance(uint32_t(a->instances().size()));

  RenderSettings rs;
  rs.spp = 8;
  rs.max_depth = 6;
  rs.seed = 42;
  Film fa, fb;
  a->render(rs, &fa);
  b->render(rs, &fb);
  ASSERT_EQ(fa.rgb.size(), fb.rgb.size());
  EXPECT_TRUE(fa.rgb == fb.rgb) << "rgb differs after save/load";
  EXPECT_TRUE(fa.depth == fb.depth) << "depth differs after save/load";
  EXPECT_TRUE(fa.instance_id == fb.instance_id) << "instance ids differ after save/load";
  EXPECT_TRUE(fa.class_id == fb.class_id);
  EXPECT_TRUE(fa.normal == fb.normal);
  EXPECT_TRUE(fa.albedo == fb.albedo);
  EXPECT_TRUE(fa.alpha == fb.alpha);
  // The render is not trivially empty: the lit scene and several labels are visible.
  double sum = 0.0;
  for (float v : fa.rgb) sum += v;
  EXPECT_GT(sum, 0.0);
  std::vector<uint32_t> seen;
  for (uint32_t id : fa.instance_id)
    if (std::find(seen.begin(), seen.end(), id) == seen.end()) seen.push_back(id);
  EXPECT_GE(seen.size(), 4u) << "expected background and at least three instances in view";
  EXPECT_EQ(std::find(seen.begin(), seen.end(), 13u), seen.end()) << "the removed instance is visible";

  std::filesystem::remove_all(std::filesystem::path(path).parent_path());
}

TEST(scene_api, render_is_deterministic_across_thread_counts) {
  uint32_t removed;
  std::vector<uint32_t> kept;
  auto s = rich_scene(&removed, &kept);
  RenderSettings r1;
  r1.spp = 4;
  r1.seed = 9;
  r1.threads = 1;
  RenderSettings r2 = r1;
  r2.threads = 2;
  r2.tile_size = 7;
  Film f1, f2;
  s->render(r1, &f1);
  s->render(r2, &f2);
  EXPECT_TRUE(f1.rgb == f2.rgb);
  RenderSettings r3 = r1;
  r3.seed = 10;
  Film f3;
  s->render(r3, &f3);
  EXPECT_FALSE(f1.rgb == f3.rgb) << "the seed has no effect";
}

TEST(scene_api, errors) {
  Scene s;
  Film f;
  s.set_camera(test_camera());
  EXPECT_THROW(s.render(quick_settings(), &f), Error) << "empty scene must not render";
  uint32_t m = s.add_mesh(tetra());
  uint32_t mat = s.add_material("diffuse", diffuse_params(0.5));
  uint32_t inst = s.add_instance(m, Transform());
  EXPECT_THROW(s.set_instance_transform(99, Transform()), Error);
  EXPECT_THROW(s.set_instance_labels(99, 1, 1), Error);
  EXPECT_THROW(s.set_instance_material(99, mat), Error);
  EXPECT_THROW(s.set_instance_material(inst, 99), Error);
  EXPECT_THROW(s.remove_instance(99), Error);
  EXPECT_THROW(s.add_instance(99, Transform()), Error);
  EXPECT_THROW(s.add_instance(m, Transform(), 0, std::nullopt, 5), Error);
  EXPECT_THROW(s.update_mesh(99, tetra()), Error);
  EXPECT_THROW(s.remove_mesh(99), Error);
  EXPECT_THROW(s.mesh(99), Error);
  EXPECT_THROW(s.update_material(99, "diffuse", ParamSet{}), Error);
  EXPECT_THROW(s.update_light(0, "point", ParamSet{}), Error);
  EXPECT_THROW(s.remove_light(0), Error);
  EXPECT_THROW(s.remove_mesh(m), Error) << "a mesh in use by an instance cannot be removed";
  // Removed ids stay invalid.
  s.remove_instance(inst);
  EXPECT_THROW(s.remove_instance(inst), Error);
  EXPECT_THROW(s.set_instance_transform(inst, Transform()), Error);
  EXPECT_THROW(s.render(quick_settings(), &f), Error) << "scene without instances must not render";
  // Bad meshes.
  TriangleMesh bad = tetra();
  bad.indices.push_back(17);
  bad.indices.push_back(0);
  bad.indices.push_back(1);
  EXPECT_THROW(s.add_mesh(bad), Error);
  TriangleMesh degenerate = tetra();
  degenerate.positions[3] = degenerate.positions[0];
  EXPECT_THROW(s.add_mesh(degenerate), Error);
  // Camera.
  PinholeCamera c = test_camera();
  c.fx = 0.f;
  EXPECT_THROW(c.validate(), Error);
  EXPECT_THROW(s.set_camera(c), Error);
  c = test_camera();
  c.fy = std::nanf("");
  EXPECT_THROW(c.validate(), Error);
  c = test_camera();
  c.width = 0;
  EXPECT_THROW(c.validate(), Error);
  EXPECT_NO_THROW(test_camera().validate());
  // Render settings.
  s.add_instance(m, Transform());
  RenderSettings zero = quick_settings();
  zero.spp = 0;
  EXPECT_THROW(s.render(zero, &f), Error);
  // No camera.
  Scene no_cam;
  no_cam.add_instance(no_cam.add_mesh(tetra()), Transform());
  EXPECT_THROW(no_cam.render(quick_settings(), &f), Error);
  // Loading a missing file names the file.
  try {
    Scene::load("/nonexistent/dir/scene.xml");
    FAIL() << "expected an error";
  } catch (const FileError& e) {
    EXPECT_NE(std::string(e.what()).find("/nonexistent/dir/scene.xml"), std::string::npos) << e.what();
  }
}

TEST(scene_api, instance_material_maps_wrap_each_material_of_one_instance) {
  // Two instances of one two-material quad (triangle 0: material a, triangle 1: b). A map on
  // the second replaces b by c for it alone; the first keeps its materials; labels' albedo
  // shows it, a save/load round trip keeps it, and c cannot be removed while mapped.
  Scene s;
  uint32_t a = s.add_material("diffuse", diffuse_params(0.2));
  uint32_t b = s.add_material("diffuse", diffuse_params(0.4));
  uint32_t c = s.add_material("diffuse", diffuse_params(0.9));
  TriangleMesh q = quad(1.f, 0.f);
  q.material_ids = {int32_t(a), int32_t(b)};
  uint32_t mesh = s.add_mesh(q);
  uint32_t left = s.add_instance(mesh, Transform::translate(Vec3f(-1.2f, 0.f, 0.f)), 1);
  uint32_t right = s.add_instance(mesh, Transform::translate(Vec3f(1.2f, 0.f, 0.f)), 2);
  s.set_instance_material_map(right, {{int32_t(b), int64_t(c)}});
  s.set_camera(PinholeCamera::from_fov(60.f, 64, 32, PinholeCamera::look_at(Vec3f(0, 0, 4), Vec3f(0, 0, 0), Vec3f(0, 1, 0))));
  RenderSettings rs;
  rs.labels_only = true;
  auto albedos = [&](Scene& scene) {
    Film f;
    scene.render(rs, &f);
    std::set<std::pair<uint32_t, int>> seen;  // (instance, albedo x 10)
    for (size_t i = 0; i < f.instance_id.size(); ++i)
      if (f.instance_id[i]) seen.insert({f.instance_id[i], int(std::lround(f.albedo[3 * i] * 10.f))});
    return seen;
  };
  auto seen = albedos(s);
  EXPECT_EQ(seen, (std::set<std::pair<uint32_t, int>>{{left + 1, 2}, {left + 1, 4}, {right + 1, 2}, {right + 1, 9}}));
  EXPECT_THROW(s.remove_material(c), Error);
  std::string path = (std::filesystem::temp_directory_path() / "synthgen_test_material_map.xml").string();
  s.save(path);
  auto t = Scene::load(path);
  EXPECT_EQ(albedos(*t), seen);
  EXPECT_EQ(t->instance_material_map(right), s.instance_material_map(right));
  std::filesystem::remove(path);
  std::filesystem::remove(path + ".bin");
  // An instance material overrides the map; an empty map removes it.
  s.set_instance_material(right, a);
  EXPECT_EQ(albedos(s), (std::set<std::pair<uint32_t, int>>{{left + 1, 2}, {left + 1, 4}, {right + 1, 2}}));
  s.set_instance_material(right, -1);
  s.set_instance_material_map(right, {});
  EXPECT_EQ(albedos(s), (std::set<std::pair<uint32_t, int>>{{left + 1, 2}, {left + 1, 4}, {right + 1, 2}, {right + 1, 4}}));
  EXPECT_THROW(s.set_instance_material_map(right, {{0, 99}}), Error);
  EXPECT_THROW(s.set_instance_material_map(right, {{-2, int64_t(a)}}), Error);
}

TEST(scene_api, journal_replays_bit_identically_from_mid_life) {
  // A journal begun on a scene with holes (a removed instance), then edits of every kind that
  // a dataset frame makes: the replay renders bit-identically, with the same ids.
  uint32_t removed;
  std::vector<uint32_t> kept;
  auto a = rich_scene(&removed, &kept);
  RenderSettings rs;
  rs.spp = 8;
  rs.max_depth = 6;
  rs.seed = 7;
  Film before;
  a->render(rs, &before);
  a->begin_journal();
  const size_t state_ops = a->journal_size();
  EXPECT_GT(state_ops, 5u);
  uint32_t mesh = a->add_mesh(tetra());
  uint32_t mat = a->add_material("diffuse", diffuse_params(0.7));
  uint32_t inst = a->add_instance(mesh, Transform::translate(Vec3f(1.f, 0.f, 0.5f)), 9, 99, mat);
  a->set_instance_visible(kept[0], false);
  a->set_instance_transform(kept[1], Transform::translate(Vec3f(-0.5f, 0.2f, 0.f)));
  a->update_material(mat, "diffuse", diffuse_params(0.3));
  a->commit();
  a->remove_instance(inst);
  a->remove_material(mat);
  uint32_t again = a->add_instance(mesh, Transform::translate(Vec3f(0.f, 1.f, 0.5f)), 4);
  Film fa;
  a->render(rs, &fa);
  std::string path = temp_dir() + "/scene.journal";
  a->save_journal(path);
  ParamSet render;
  std::unique_ptr<Scene> b = Scene::replay(path, &render);
  EXPECT_EQ(b->instances().size(), a->instances().size());
  EXPECT_TRUE(b->instances()[again].has_value());
  EXPECT_FALSE(b->instances()[inst].has_value());
  EXPECT_FALSE(b->instances()[removed].has_value());
  RenderSettings rb = RenderSettings::from_params([&] {
    ParamSet p;
    for (const auto& [k, v] : render.values())
      if (k != "labels_only") p.set(k, v);
    return p;
  }());
  EXPECT_EQ(rb.spp, rs.spp);
  EXPECT_EQ(rb.seed, rs.seed);
  Film fb;
  b->render(rb, &fb);
  EXPECT_TRUE(fa.rgb == fb.rgb) << "rgb differs after replay";
  EXPECT_TRUE(fa.depth == fb.depth);
  EXPECT_TRUE(fa.instance_id == fb.instance_id);
  EXPECT_FALSE(fa.rgb == before.rgb) << "the edits changed the image";
}

namespace {

/// The process's peak resident memory, bytes.
uint64_t peak_rss() {
  struct rusage ru {};
  getrusage(RUSAGE_SELF, &ru);
  return uint64_t(ru.ru_maxrss) * 1024;
}

void write_text(const std::string& path, const std::string& text) {
  std::ofstream(path, std::ios::binary) << text;
}

/// The message of the sg::Error that `f` throws ("" when it throws none).
template <class F>
std::string error_of(F f) {
  try {
    f();
  } catch (const Error& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST(scene_api, a_hostile_slot_id_fails_before_the_loader_allocates_its_slots) {
  // Ids of removed objects stay empty slots, so a file may name an id above its entries; one
  // naming id 2^24 - 1 with a single light made both loaders allocate 2^24 slots (~1.6 GB of
  // std::optional<LightEntry>, every one touched). Now holes are bounded by the file's content.
  const std::string dir = temp_dir();
  const std::string light = "<param name=\"position\" type=\"floats\" value=\"0 1 0\"/>";
  write_text(dir + "/hostile.xml.bin", "");
  write_text(dir + "/hostile.xml", "<synthgen_scene version=\"1\" bin=\"hostile.xml.bin\"><slots meshes=\"0\" "
                                   "textures=\"0\" materials=\"0\" instances=\"0\" lights=\"16777216\"/>"
                                   "<light id=\"16777215\" type=\"point\">" + light + "</light></synthgen_scene>");
  write_text(dir + "/hostile.journal.bin", "");
  write_text(dir + "/hostile.journal", "<synthgen_journal version=\"1\" bin=\"hostile.journal.bin\">"
                                       "<op kind=\"add_light\" id=\"16777215\" type=\"point\">" + light +
                                       "</op></synthgen_journal>");
  const uint64_t before = peak_rss();
  std::string e = error_of([&] { Scene::load(dir + "/hostile.xml"); });
  EXPECT_NE(e.find("light id 16777215 is out of range: the file has 1 lights"), std::string::npos) << e;
  e = error_of([&] { Scene::replay(dir + "/hostile.journal"); });
  EXPECT_NE(e.find("operation 0 (add_light 16777215): id 16777215 is out of range: the file has 1 lights"),
            std::string::npos) << e;
  EXPECT_LT(peak_rss() - before, uint64_t(64) << 20) << "the loaders' peak memory grew by this much";
  // Ids above the file's own slot counts are inconsistent: named, not padded.
  write_text(dir + "/ids.xml.bin", "");
  write_text(dir + "/ids.xml", "<synthgen_scene version=\"1\" bin=\"ids.xml.bin\"><slots meshes=\"0\" "
                               "textures=\"0\" materials=\"0\" instances=\"0\" lights=\"1\"/>"
                               "<light id=\"3\" type=\"point\">" + light + "</light></synthgen_scene>");
  e = error_of([&] { Scene::load(dir + "/ids.xml"); });
  EXPECT_NE(e.find("light id 3 is not below the file's slot count of lights (1)"), std::string::npos) << e;
  // Holes within the bound load, with their ids.
  Scene s;
  for (int i = 0; i < 3; ++i) s.add_light("point", ParamSet());
  s.remove_light(0);
  s.remove_light(1);
  s.save(dir + "/holes.xml");
  auto loaded = Scene::load(dir + "/holes.xml");
  ASSERT_EQ(loaded->lights().size(), 3u);
  EXPECT_TRUE(loaded->lights()[2].has_value());
  EXPECT_FALSE(loaded->lights()[0].has_value());
}

TEST(scene_api, journal_sha256_gives_the_digests_of_fips_180_4) {
  // The content hash by which journals record files (core/sha256.h): the standard's examples,
  // fed in pieces that straddle its 64-byte blocks.
  auto digest = [](const std::string& s, size_t piece) {
    Sha256 h;
    for (size_t i = 0; i < s.size(); i += piece) h.update(s.data() + i, std::min(piece, s.size() - i));
    return h.hex();
  };
  EXPECT_EQ(digest("", 1), "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855");
  EXPECT_EQ(digest("abc", 1), "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
  EXPECT_EQ(digest("abcdbcdecdefdefgefghfghighijhijkijkljklmklmnlmnomnopnopq", 7),
            "248d6a61d20638b8e5c026930c3e6039a33ce45964ff2167f6ecedd419db06c1");
  EXPECT_EQ(digest(std::string(1000000, 'a'), 4099), "cdc76e5c9914fb9281a1c7e284d73e67f1809a48a497200e046d39ccc7112cd0");
  EXPECT_TRUE(Sha256::is_hex_digest(digest("abc", 3)));
  EXPECT_FALSE(Sha256::is_hex_digest("../../etc/passwd"));
  EXPECT_FALSE(Sha256::is_hex_digest(std::string(64, 'A')));
}
