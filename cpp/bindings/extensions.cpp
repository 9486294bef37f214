// Bindings of user extensions (ext/extension.h): loading compiled libraries, the loaded ones,
// and Scene.add_shape. Compiling is Python's (synthgen.scene.extensions).
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include "api/scene.h"
#include "bindings/convert.h"
#include "ext/extension.h"

namespace sg::bindings {

namespace {

py::dict library_to_py(const ExtensionLibrary& lib) {
  py::dict d;
  d["library"] = lib.library;
  d["source"] = lib.source;
  d["textures"] = lib.textures;
  d["shapes"] = lib.shapes;
  return d;
}

}  // namespace

void bind_extensions(py::module_& m, py::class_<Scene>& scene) {
  m.attr("EXTENSION_ABI_VERSION") = SG_EXT_ABI_VERSION;
  m.def(
      "load_extension_library",
      [](const std::string& library, const std::string& source) {
        return library_to_py(load_extension_library(library, source));
      },
      py::arg("library"), py::arg("source"),
      R"doc(Loads a compiled extension library (built from `source`, named in errors) and registers its
textures and shapes as plugins. Runs the library's code: see synthgen.scene.extensions, which
compiles and calls this only when extensions are allowed. Returns {'library', 'source',
'textures', 'shapes'}.)doc");
  m.def(
      "loaded_extension_libraries",
      []() {
        py::list out;
        for (const ExtensionLibrary& lib : loaded_extension_libraries()) out.append(library_to_py(lib));
        return out;
      },
      "The extension libraries loaded in this process, in loading order.");
  scene.def(
      "add_shape",
      [](Scene& s, const std::string& type, const py::dict& params) {
        return s.add_shape(type, params_from_dict(params, "shape '" + type + "'"));
      },
      py::arg("type"), py::arg("params") = py::dict(),
      R"doc(Adds a user shape (a "shape" plugin of a loaded extension) to the mesh library; returns its
mesh id, instanced with add_instance like a mesh.)doc");
}

}  // namespace sg::bindings
