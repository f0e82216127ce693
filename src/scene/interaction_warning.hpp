// The head of a scene warning about one [[interaction]]'s key, shared by
// the start warnings (solver/time_step.cpp, solver/contact_gap.cpp,
// app/start_warnings.cpp): "FILE:LINE: warning: key 'interaction[I].KEY': "
// (the scene's file when the interaction has none, no line when 0).
#pragma once

#include <cstddef>
#include <string>

#include "scene/scene.hpp"

namespace mmpm {

inline std::string interaction_warning(const Scene& scene, std::size_t index,
                                       const std::string& key) {
  const InteractionSpec& it = scene.interactions[index];
  std::string out = it.where.file.empty() ? scene.source_file : it.where.file;
  if (it.where.line > 0) {
    out += ':';
    out += std::to_string(it.where.line);
  }
  out += ": warning: key 'interaction[";
  out += std::to_string(index);
  out += "].";
  out += key;
  out += "': ";
  return out;
}

}  // namespace mmpm
