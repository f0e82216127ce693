// Checkpoints for `mmpm run --restart`: a list of named binary blobs in one
// file, written atomically and guarded by a checksum so that a torn or
// damaged file is refused instead of silently restarting from garbage.
//
// Layout (all integers 64-bit little-endian):
//   "MMPMCKP1"  count  { name_length name byte_length bytes } * count  fnv1a64
// where fnv1a64 is the 64-bit FNV-1a hash of every byte before it.
// Blob payloads are raw host-order bytes: a checkpoint is for restarting on
// the same kind of machine, not an exchange format.
#pragma once

#include <cstdint>
#include <cstring>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <string_view>
#include <type_traits>
#include <utility>
#include <vector>

namespace mmpm::io {

struct Blob {
  std::string name;
  std::vector<unsigned char> bytes;
};

// Element types that can travel as raw bytes. bool is excluded because
// std::vector<bool> has no contiguous storage to copy.
template <class T>
concept BlobElement = std::is_trivially_copyable_v<T> && !std::is_same_v<T, bool>;

template <BlobElement T>
Blob make_blob(std::string name, const std::vector<T>& values) {
  Blob blob{std::move(name), std::vector<unsigned char>(values.size() * sizeof(T))};
  if (!values.empty()) std::memcpy(blob.bytes.data(), values.data(), blob.bytes.size());
  return blob;
}

// Throws std::runtime_error if the blob's size is not a whole number of T.
template <BlobElement T>
void read_blob(const Blob& blob, std::vector<T>& values) {
  if (blob.bytes.size() % sizeof(T) != 0) {
    throw std::runtime_error(
        "checkpoint blob '" + blob.name + "': " + std::to_string(blob.bytes.size()) +
        " bytes is not a whole number of " + std::to_string(sizeof(T)) + "-byte elements");
  }
  values.resize(blob.bytes.size() / sizeof(T));
  if (!values.empty()) std::memcpy(values.data(), blob.bytes.data(), blob.bytes.size());
}

template <BlobElement T>
Blob make_scalar_blob(std::string name, const T& value) {
  Blob blob{std::move(name), std::vector<unsigned char>(sizeof(T))};
  std::memcpy(blob.bytes.data(), &value, sizeof(T));
  return blob;
}

// Throws std::runtime_error unless the blob holds exactly one T.
template <BlobElement T>
T read_scalar_blob(const Blob& blob) {
  if (blob.bytes.size() != sizeof(T)) {
    throw std::runtime_error("checkpoint blob '" + blob.name + "': holds " +
                             std::to_string(blob.bytes.size()) + " bytes, expected " +
                             std::to_string(sizeof(T)));
  }
  T value;
  std::memcpy(&value, blob.bytes.data(), sizeof(T));
  return value;
}

Blob make_string_blob(std::string name, std::string_view text);
std::string read_string_blob(const Blob& blob);

// Throws std::invalid_argument on duplicate blob names (find_blob could not
// tell them apart) and std::runtime_error if the file cannot be written.
void write_checkpoint(const std::filesystem::path& file, const std::vector<Blob>& blobs);

// Throws std::runtime_error("checkpoint FILE: corrupt (...)") on a wrong
// magic, a checksum mismatch or a truncated file, and
// std::runtime_error("checkpoint FILE: cannot open ...") if it is unreadable.
std::vector<Blob> read_checkpoint(const std::filesystem::path& file);

// Throws std::runtime_error("checkpoint: no blob named 'NAME'") if absent.
const Blob& find_blob(const std::vector<Blob>& blobs, std::string_view name);

// The blob named NAME, or nullptr: for blobs that older checkpoints lack.
const Blob* find_optional_blob(const std::vector<Blob>& blobs, std::string_view name);

// 64-bit FNV-1a; exposed for tests.
std::uint64_t fnv1a64(std::string_view bytes);

}  // namespace mmpm::io
