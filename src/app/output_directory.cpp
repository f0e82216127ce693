#include "app/output_directory.hpp"

#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <system_error>

#include "scene/error.hpp"

namespace mmpm {

namespace fs = std::filesystem;

void prepare_output_directory(const fs::path& dir, const std::string& source) {
  const auto fail = [&](const std::string& reason) {
    throw InputError(source + " " + dir.string() + ": cannot write the output directory (" +
                     reason + "); expected a directory this user can create and write");
  };
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) fail(ec.message());
  if (!fs::is_directory(dir, ec)) fail("it exists and is not a directory");
  // Permissions alone do not say it (root ignores them, /proc refuses
  // root): try the operation the run will do.
  const fs::path probe = dir / (".mmpm-write-probe-" + std::to_string(::getpid()));
  std::FILE* f = std::fopen(probe.c_str(), "wb");
  if (!f) fail(std::strerror(errno));
  std::fclose(f);
  fs::remove(probe, ec);
}

}  // namespace mmpm
