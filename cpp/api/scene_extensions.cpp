// The integration API's side of user extensions (ext/extension.h): shapes in the mesh
// library, and the failures extensions record during renders.
#include "api/scene.h"
#include "core/error.h"
#include "ext/extension.h"

namespace sg {

uint32_t Scene::add_shape(const std::string& type, const ParamSet& params) {
  uint32_t id = uint32_t(m_meshes.size());
  auto shape = Registry::instance().create<ExtensionShape>("shape", type, params, PluginContext{},
                                                            "shape " + std::to_string(id));
  TriangleMesh mesh;
  mesh.name = type;
  mesh.shape = shape;
  MeshEntry e;
  e.bounds = shape->bounds();
  e.mesh = std::make_shared<TriangleMesh>(std::move(mesh));
  e.shape_type = type;
  e.shape_params = params;
  m_meshes.emplace_back(std::move(e));
  if (JournalOp* o = journal_op(JournalOp::Kind::AddShape, id)) {
    o->type = type;
    o->params = params;
  }
  return id;
}

void Scene::check_extension_failures() const {
  // NOTE: a user extension's non-finite output is replaced by 0 where it happens (inside the
  // render loop nothing can throw); the render then fails, never returning damaged pixels.
  for (size_t i = 0; i < m_textures.size(); ++i)
    if (m_textures[i]) {
      std::string f = m_textures[i]->object->failure();
      if (!f.empty()) throw Error("render: texture " + std::to_string(i) + ": " + f);
    }
  for (size_t i = 0; i < m_meshes.size(); ++i)
    if (m_meshes[i] && m_meshes[i]->mesh->shape) {
      std::string f = m_meshes[i]->mesh->shape->failure();
      if (!f.empty()) throw Error("render: mesh " + std::to_string(i) + ": " + f);
    }
}

}  // namespace sg
