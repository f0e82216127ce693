// Small RAII wrappers over the HDF5 C API: file, group, dataset, attribute.
//
// Why not the HDF5 C++ API: the C API is the stable, documented one, and the
// few calls the run file needs fit in a page. Every failure becomes a
// std::runtime_error carrying HDF5's own message; the library's habit of
// printing its error stack to stderr is switched off (per thread, because the
// Debian build is thread-safe and keeps that setting per thread).
#pragma once

#include <hdf5.h>

#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace mmpm::io::h5 {

// Throws std::runtime_error("WHAT: <message from HDF5's error stack>").
[[noreturn]] void raise(const std::string& what);

// One owned HDF5 identifier and the function that releases it. Move-only.
class Id {
 public:
  using Closer = herr_t (*)(hid_t);
  Id() = default;
  Id(hid_t id, Closer closer) : id_(id), closer_(closer) {}
  Id(const Id&) = delete;
  Id& operator=(const Id&) = delete;
  Id(Id&& other) noexcept;
  Id& operator=(Id&& other) noexcept;
  ~Id();  // releases quietly: destructors must not throw

  hid_t get() const { return id_; }
  bool valid() const { return id_ >= 0; }
  // Releases now and throws std::runtime_error("WHAT: ...") if HDF5 reports a failure.
  void close(const std::string& what = "cannot close an HDF5 object");

 private:
  hid_t id_ = H5I_INVALID_HID;
  Closer closer_ = nullptr;
};

// An attribute opened or created on some object.
class Attribute {
 public:
  static Attribute open(hid_t object, const std::string& name);
  // Replaces an existing attribute of that name (HDF5 cannot resize one).
  static Attribute create(hid_t object, const std::string& name, hid_t file_type, hid_t space);
  hid_t id() const { return id_.get(); }

 private:
  explicit Attribute(Id id) : id_(std::move(id)) {}
  Id id_;
};

// Anything that carries attributes (groups, datasets, the root of a file).
class Object {
 public:
  hid_t id() const { return id_.get(); }
  bool valid() const { return id_.valid(); }
  void close() { id_.close(); }

  bool has_attribute(const std::string& name) const;
  // Strings are variable-length UTF-8: h5py returns them as str, and their
  // text lives in the global heap, so a long scene text is not bound by the
  // 64 KiB object-header limit of compact attributes.
  void set_string_attribute(const std::string& name, std::string_view value);
  void set_double_attribute(const std::string& name, double value);
  void set_int_attribute(const std::string& name, std::int64_t value);
  std::string string_attribute(const std::string& name) const;
  double double_attribute(const std::string& name) const;
  std::int64_t int_attribute(const std::string& name) const;

 protected:
  Object() = default;
  explicit Object(Id id) : id_(std::move(id)) {}
  Id id_;
};

class Dataset : public Object {
 public:
  explicit Dataset(Id id) : Object(std::move(id)) {}
  std::vector<hsize_t> shape() const;
  std::vector<double> read_doubles() const;
  std::vector<std::int64_t> read_ints() const;
};

class Group : public Object {
 public:
  explicit Group(Id id) : Object(std::move(id)) {}

  Group create_group(const std::string& name);
  Group open_group(const std::string& name) const;
  Group require_group(const std::string& name);  // open, or create when absent
  bool contains(const std::string& name) const;  // a direct child link of that name
  void remove(const std::string& name);          // unlink a child (group or dataset)
  std::vector<std::string> children() const;     // link names in name order

  // Contiguous datasets in the file's native little-endian layout; `shape`'s
  // product must equal values.size(). Zero-sized datasets are allowed.
  Dataset write_doubles(const std::string& name, std::span<const double> values,
                        const std::vector<hsize_t>& shape);
  Dataset write_ints(const std::string& name, std::span<const std::int64_t> values,
                     const std::vector<hsize_t>& shape);
  Dataset open_dataset(const std::string& name) const;
};

class File {
 public:
  enum class Mode { read_only, read_write };
  static File create(const std::filesystem::path& path);  // truncates
  static File open(const std::filesystem::path& path, Mode mode);

  Group root() const;
  void flush();  // pushes every buffered change to the operating system
  void close();  // throws if HDF5 cannot close the file cleanly
  bool valid() const { return id_.valid(); }
  const std::filesystem::path& path() const { return path_; }

 private:
  File(Id id, std::filesystem::path path) : id_(std::move(id)), path_(std::move(path)) {}
  Id id_;
  std::filesystem::path path_;
};

}  // namespace mmpm::io::h5
