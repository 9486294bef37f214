// The files a change journal names, recorded by content (api/scene_journal.cpp writes and
// replays journals through these two functions).
//
// Files a journal names (parameters declared as paths: image textures, environment maps, grid
// media, ...) are recorded by content, so that a journal replays after they are gone (a run's
// temporary photo dome) or elsewhere: each as a <resource param= path= sha256= size=> child of
// its operation, the file's bytes embedded in the sidecar when it has at most k_embed_max
// bytes, else copied at write time into the resource store ($SYNTHGEN_CACHE/resources,
// default ~/.cache/synthgen/resources) as SHA256.EXT. A replay uses the embedded bytes (written
// to the store, where the plugin reads them) or the store's copy, else the file at its
// recorded path if its content still has the recorded sha256; anything else is an error
// naming the parameter, the recorded path, the sha256 and where it looked.
#pragma once

#include <cstdint>
#include <fstream>
#include <map>
#include <string>
#include <vector>

#include <pugixml.hpp>

#include "core/params.h"

namespace sg {

/// The <resource> children of `n`: one for each given parameter that the plugin (kind, type)
/// declares as a path (`skip`: a parameter that names no file, such as an in-memory image's
/// key). `embedded`: sha256 -> sidecar offset of the files embedded so far (each once).
void write_resources(pugi::xml_node n, const char* kind, const std::string& type, const ParamSet& params,
                     std::ofstream& bin, std::map<std::string, uint64_t>* embedded, const char* skip = nullptr);

/// `params` with each parameter that a <resource> child of `n` names replaced by a file with
/// the recorded content; throws sg::Error naming what is missing.
ParamSet resolve_resources(pugi::xml_node n, ParamSet params, const std::vector<char>& bin);

}  // namespace sg
