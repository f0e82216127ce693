// The head of a scene warning about one [[interaction]]'s key, shared by
// the start warnings (solver/time_step.cpp, solver/contact_gap.cpp,
// app/start_warnings.cpp): "FILE:LINE: warning: key 'interaction[I].KEY': "
// (the scene's file when the interaction has none, no line when 0).
#pragma once

#include <cstddef>
#include <string>

#include "scene/scene.hpp"

namespace mmpm {

// "FILE:LINE: warning: " for a key read at `where` (the scene's file when
// it has none, no line when 0: a default the scene does not set).
inline std::string warning_at(const Scene& scene, const Where& where) {
  std::string out = where.file.empty() ? scene.source_file : where.file;
  if (where.line > 0) {
    out += ':';
    out += std::to_string(where.line);
  }
  return out + ": warning: ";
}

inline std::string interaction_warning(const Scene& scene, std::size_t index,
                                       const std::string& key) {
  std::string out = warning_at(scene, scene.interactions[index].where);
  out += "key 'interaction[";
  out += std::to_string(index);
  out += "].";
  out += key;
  out += "': ";
  return out;
}

}  // namespace mmpm
