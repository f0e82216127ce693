// Where a run or a sweep writes: made and proved writable before the first
// step, so that a bad --out is bad input (one message, exit 2) and not an
// error from the file system after the run has started.
#pragma once

#include <filesystem>
#include <string>

namespace mmpm {

// Creates `dir` (and its parents) and writes and removes a probe file in
// it. Throws InputError naming `source` (the option or key that chose the
// directory) and the file system's reason.
void prepare_output_directory(const std::filesystem::path& dir, const std::string& source);

}  // namespace mmpm
