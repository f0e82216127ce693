#include "io/checkpoint.hpp"

#include <array>
#include <fstream>
#include <iterator>
#include <set>

#include "io/atomic_file.hpp"

namespace mmpm::io {

namespace {

constexpr std::string_view magic = "MMPMCKP1";
constexpr std::size_t word = 8;

void put_u64(std::string& out, std::uint64_t value) {
  for (std::size_t i = 0; i < word; ++i) {
    out.push_back(static_cast<char>((value >> (8 * i)) & 0xffu));
  }
}

[[noreturn]] void corrupt(const std::filesystem::path& file, const std::string& why) {
  throw std::runtime_error("checkpoint " + file.string() + ": corrupt (" + why + ")");
}

// Walks the file's bytes; every read is bounds-checked so a damaged length
// field reports truncation instead of reading past the end.
class Reader {
 public:
  Reader(std::string_view bytes, const std::filesystem::path& file) : bytes_(bytes), file_(file) {}

  std::string_view take(std::uint64_t n, const char* what) {
    if (n > bytes_.size() - position_) {
      corrupt(file_, std::string("truncated in ") + what + " at byte " + std::to_string(position_));
    }
    const std::string_view out = bytes_.substr(position_, static_cast<std::size_t>(n));
    position_ += static_cast<std::size_t>(n);
    return out;
  }

  std::uint64_t u64(const char* what) {
    const std::string_view raw = take(word, what);
    std::uint64_t value = 0;
    for (std::size_t i = 0; i < word; ++i) {
      value |= std::uint64_t{static_cast<unsigned char>(raw[i])} << (8 * i);
    }
    return value;
  }

  std::size_t position() const { return position_; }

 private:
  std::string_view bytes_;
  const std::filesystem::path& file_;
  std::size_t position_ = 0;
};

}  // namespace

std::uint64_t fnv1a64(std::string_view bytes) {
  std::uint64_t hash = 14695981039346656037ull;
  for (const char c : bytes) {
    hash ^= static_cast<unsigned char>(c);
    hash *= 1099511628211ull;
  }
  return hash;
}

Blob make_string_blob(std::string name, std::string_view text) {
  return Blob{std::move(name), std::vector<unsigned char>(text.begin(), text.end())};
}

std::string read_string_blob(const Blob& blob) {
  return std::string(blob.bytes.begin(), blob.bytes.end());
}

void write_checkpoint(const std::filesystem::path& file, const std::vector<Blob>& blobs) {
  std::set<std::string_view> names;
  std::size_t size = magic.size() + 2 * word;
  for (const Blob& blob : blobs) {
    if (!names.insert(blob.name).second) {
      throw std::invalid_argument("checkpoint " + file.string() + ": duplicate blob name '" +
                                  blob.name + "'");
    }
    size += 2 * word + blob.name.size() + blob.bytes.size();
  }
  std::string out;
  out.reserve(size);
  out.append(magic);
  put_u64(out, blobs.size());
  for (const Blob& blob : blobs) {
    put_u64(out, blob.name.size());
    out.append(blob.name);
    put_u64(out, blob.bytes.size());
    out.append(reinterpret_cast<const char*>(blob.bytes.data()), blob.bytes.size());
  }
  put_u64(out, fnv1a64(out));
  write_file_atomic(file, out);
}

std::vector<Blob> read_checkpoint(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw std::runtime_error("checkpoint " + file.string() + ": cannot open");
  const std::string bytes{std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  if (in.bad()) throw std::runtime_error("checkpoint " + file.string() + ": cannot read");

  Reader reader(bytes, file);
  if (reader.take(magic.size(), "the header") != magic) {
    corrupt(file, "not an mmpm checkpoint: bad magic");
  }
  const std::uint64_t count = reader.u64("the blob count");
  std::vector<Blob> blobs;
  for (std::uint64_t i = 0; i < count; ++i) {
    Blob blob;
    blob.name = std::string(reader.take(reader.u64("a blob name length"), "a blob name"));
    const std::string_view payload = reader.take(reader.u64("a blob length"), "a blob's bytes");
    blob.bytes.assign(payload.begin(), payload.end());
    blobs.push_back(std::move(blob));
  }
  const std::size_t covered = reader.position();
  if (reader.u64("the checksum") != fnv1a64(std::string_view(bytes).substr(0, covered))) {
    corrupt(file, "checksum mismatch");
  }
  if (reader.position() != bytes.size()) {
    corrupt(file,
            std::to_string(bytes.size() - reader.position()) + " stray bytes after the checksum");
  }
  return blobs;
}

const Blob* find_optional_blob(const std::vector<Blob>& blobs, std::string_view name) {
  for (const Blob& blob : blobs) {
    if (blob.name == name) return &blob;
  }
  return nullptr;
}

const Blob& find_blob(const std::vector<Blob>& blobs, std::string_view name) {
  if (const Blob* blob = find_optional_blob(blobs, name)) return *blob;
  throw std::runtime_error("checkpoint: no blob named '" + std::string(name) + "'");
}

}  // namespace mmpm::io
