// summary.json: the run's headline numbers, the file scripts read (SCENE.md).
#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>

namespace mmpm::io {

// Pretty-printed with a 2-space indent and a final newline, written
// atomically so a script never reads half a summary.
void write_summary(const std::filesystem::path& file, const nlohmann::json& j);

// Throws std::runtime_error("summary FILE: ...") if the file cannot be read
// or is not JSON.
nlohmann::json read_summary(const std::filesystem::path& file);

}  // namespace mmpm::io
