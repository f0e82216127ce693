// Crash-safe file replacement: a reader sees either the old file or the whole
// new one, never a half-written file, even if the process or machine dies.
#pragma once

#include <filesystem>
#include <string_view>

namespace mmpm::io {

// Writes `bytes` to PATH.tmp, fsyncs it, renames it over PATH (atomic on
// POSIX) and fsyncs the directory so the rename itself survives a crash.
// Throws std::runtime_error naming the file and the system error; on failure
// the .tmp file is removed and PATH is left as it was.
void write_file_atomic(const std::filesystem::path& path, std::string_view bytes);

// Forces an existing file's contents to stable storage.
void fsync_file(const std::filesystem::path& path);

// Forces a directory's entries (creations, renames, removals) to stable storage.
void fsync_directory(const std::filesystem::path& directory);

}  // namespace mmpm::io
