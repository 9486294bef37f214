// Bindings of the change journal (api/journal.h): recording, saving, replaying. Loading the
// extensions a journal notes before replaying is Python's (synthgen.scene.journal).
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "api/scene.h"
#include "bindings/convert.h"

namespace sg::bindings {

namespace {

py::dict params_to_py(const ParamSet& ps) {
  py::dict d;
  for (const auto& [k, v] : ps.values())
    std::visit([&, key = k](const auto& x) {
      using T = std::decay_t<decltype(x)>;
      if constexpr (std::is_same_v<T, TextureRef>) d[py::str(key)] = py::make_tuple("texture", x.id);
      else d[py::str(key)] = x;
    }, v);
  return d;
}

}  // namespace

void bind_journal(py::class_<Scene>& scene) {
  scene
      .def("begin_journal", &Scene::begin_journal,
           "Starts recording edits (dropping earlier ones): the journal begins with the scene as it is, then every "
           "edit through this API as it succeeds, commits and renders included (api/journal.h).")
      .def("end_journal", &Scene::end_journal, "Stops recording and drops the journal.")
      .def_property_readonly("journaling", &Scene::journaling)
      .def_property_readonly("journal_size", &Scene::journal_size, "operations recorded so far")
      .def("save_journal", &Scene::save_journal, py::arg("path"),
           "Writes the journal: XML in the scene file's vocabulary plus a binary sidecar PATH.bin (arrays, pixels, "
           "the extensions' sources, the files it names of at most 1 MiB; larger ones are copied into "
           "$SYNTHGEN_CACHE/resources, named by sha256). Scene.replay(PATH) renders bit-identically.")
      .def("note_extension", &Scene::note_extension, py::arg("source"), py::arg("sha256"), py::arg("text"),
           "Records that an extension was loaded for this scene (its source is embedded in saved journals).")
      .def("set_journal_autosave", &Scene::set_journal_autosave, py::arg("path"),
           "render() first writes the journal to PATH ('' = off): a process dying inside the render leaves it.")
      .def_static(
          "_replay",
          [](const std::string& path) {
            ParamSet render;
            std::unique_ptr<Scene> s;
            {
              py::gil_scoped_release release;
              s = Scene::replay(path, &render);
            }
            return py::make_tuple(py::cast(std::move(s)), params_to_py(render));
          },
          py::arg("path"), "(scene, settings of the last render recorded): see synthgen.scene.journal.replay.")
      .def_static(
          "journal_extensions",
          [](const std::string& path) {
            py::list out;
            for (const JournalExtension& e : Scene::journal_extensions(path)) {
              py::dict d;
              d["source"] = e.source;
              d["sha256"] = e.sha256;
              d["text"] = py::bytes(e.text);
              out.append(d);
            }
            return out;
          },
          py::arg("path"), "The extensions a journal notes: [{'source', 'sha256', 'text' (bytes)}].");
}

}  // namespace sg::bindings
