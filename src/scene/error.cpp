#include "scene/error.hpp"

namespace mmpm {

std::string located(const std::string& file, int line, const std::string& key,
                    const std::string& message) {
  // Appended piece by piece: `"literal" + std::string` trips GCC 12's false
  // -Wrestrict positive at -O3 (GCC bug 105329).
  std::string out;
  if (!file.empty()) {
    out += file;
    if (line > 0) {
      out += ':';
      out += std::to_string(line);
    }
    out += ": ";
  }
  if (!key.empty()) {
    out += "key '";
    out += key;
    out += "': ";
  }
  out += message;
  return out;
}

}  // namespace mmpm
