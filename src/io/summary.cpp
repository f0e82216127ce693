#include "io/summary.hpp"

#include <fstream>
#include <sstream>
#include <stdexcept>

#include "io/atomic_file.hpp"

namespace mmpm::io {

void write_summary(const std::filesystem::path& file, const nlohmann::json& j) {
  write_file_atomic(file, j.dump(2, ' ', false, nlohmann::json::error_handler_t::replace) + "\n");
}

nlohmann::json read_summary(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw std::runtime_error("summary " + file.string() + ": cannot open");
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) throw std::runtime_error("summary " + file.string() + ": cannot read");
  try {
    return nlohmann::json::parse(text.str());
  } catch (const nlohmann::json::parse_error& e) {
    throw std::runtime_error("summary " + file.string() + ": not valid JSON: " + e.what());
  }
}

}  // namespace mmpm::io
