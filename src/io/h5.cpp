#include "io/h5.hpp"

#include <mutex>
#include <numeric>
#include <stdexcept>
#include <utility>

namespace mmpm::io::h5 {

namespace {

// HDF5 closes the files still open when the process exits (an atexit
// handler). A file whose write failed (a full disk) stays open, since its
// close fails too, and the handler's second close crashed the process after
// its error message (SIGSEGV in H5F__close_cb, HDF5 1.10.8). Every file is
// closed by its owner (Id), so the handler has nothing else to do; it is
// switched off before the library starts, which is the only time it can be.
[[maybe_unused]] const bool kNoExitHandler = [] {
  H5dont_atexit();
  return true;
}();

// Sweeps run several scenes in threads of one process. The Debian build is
// thread-safe, but a serial non-thread-safe build is common elsewhere; one
// process-wide lock around every call makes both safe at no measurable cost
// (output is a small share of a run). Recursive because wrappers call each
// other. The guard also switches off HDF5's stderr printing for the calling
// thread: thread-safe builds keep that setting per thread.
std::recursive_mutex& library_mutex() {
  static std::recursive_mutex mutex;
  return mutex;
}

class Guard {
 public:
  Guard() : lock_(library_mutex()) {
    thread_local bool quiet = false;
    if (!quiet) {
      H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
      quiet = true;
    }
  }

 private:
  std::unique_lock<std::recursive_mutex> lock_;
};

struct StackText {
  std::string outer;  // what the API function said
  std::string inner;  // the deepest cause (often the errno text)
};

// A failed system call's description spans lines and lists the buffer,
// offset and time; its "error message = '...'" is the part a user needs.
std::string system_error_text(const std::string& desc) {
  const std::string key = "error message = '";
  const std::size_t at = desc.find(key);
  if (at == std::string::npos) return desc;
  const std::size_t from = at + key.size(), to = desc.find('\'', from);
  return to == std::string::npos ? desc : desc.substr(from, to - from);
}

herr_t collect(unsigned n, const H5E_error2_t* err, void* data) {
  auto* text = static_cast<StackText*>(data);
  std::string desc = system_error_text(err->desc != nullptr ? err->desc : "");
  for (char& c : desc)
    if (c == '\n') c = ' ';
  if (n == 0) text->outer = desc;
  text->inner = desc;
  return 0;
}

// Checks an identifier-returning call.
hid_t check_id(hid_t id, const std::string& what) {
  if (id < 0) raise(what);
  return id;
}

void check(herr_t status, const std::string& what) {
  if (status < 0) raise(what);
}

std::string quoted(const std::string& name) {
  return "'" + name + "'";
}

// A name this layer creates must be one link, not a path: it keeps the
// wrappers' meaning obvious and HDF5's "." and ".." out of the way.
void check_link_name(const std::string& name) {
  if (name.empty() || name == "." || name == ".." || name.find('/') != std::string::npos) {
    throw std::invalid_argument("HDF5 link name " + quoted(name) +
                                " must be one non-empty component without '/'");
  }
}

Id make_space(const std::vector<hsize_t>& shape, std::size_t values) {
  if (shape.empty()) throw std::invalid_argument("HDF5 dataset shape must have a rank >= 1");
  const hsize_t n = std::accumulate(shape.begin(), shape.end(), hsize_t{1},
                                    [](hsize_t a, hsize_t b) { return a * b; });
  if (n != values) {
    throw std::invalid_argument("HDF5 dataset: shape holds " + std::to_string(n) + " values but " +
                                std::to_string(values) + " were given");
  }
  return Id(check_id(H5Screate_simple(static_cast<int>(shape.size()), shape.data(), nullptr),
                     "cannot create a dataspace"),
            H5Sclose);
}

Id string_type() {
  Id type(check_id(H5Tcopy(H5T_C_S1), "cannot copy the string type"), H5Tclose);
  check(H5Tset_size(type.get(), H5T_VARIABLE), "cannot make a variable-length string type");
  check(H5Tset_cset(type.get(), H5T_CSET_UTF8), "cannot set the UTF-8 character set");
  return type;
}

hssize_t element_count(hid_t space, const std::string& what) {
  const hssize_t n = H5Sget_simple_extent_npoints(space);
  if (n < 0) raise(what);
  return n;
}

template <class T>
T read_number_attribute(hid_t object, const std::string& name, hid_t memory_type) {
  Attribute attribute = Attribute::open(object, name);
  Id space(check_id(H5Aget_space(attribute.id()), "attribute " + quoted(name)), H5Sclose);
  if (element_count(space.get(), "attribute " + quoted(name)) != 1) {
    throw std::runtime_error("attribute " + quoted(name) + " is not a single value");
  }
  T value{};
  check(H5Aread(attribute.id(), memory_type, &value), "cannot read attribute " + quoted(name));
  return value;
}

template <class T>
std::vector<T> read_all(hid_t dataset, hid_t memory_type) {
  Id space(check_id(H5Dget_space(dataset), "cannot get a dataset's dataspace"), H5Sclose);
  std::vector<T> values(static_cast<std::size_t>(element_count(space.get(), "dataset size")));
  if (!values.empty()) {
    check(H5Dread(dataset, memory_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, values.data()),
          "cannot read a dataset");
  }
  return values;
}

template <class T>
Dataset write_all(hid_t group, const std::string& name, std::span<const T> values,
                  const std::vector<hsize_t>& shape, hid_t file_type, hid_t memory_type) {
  check_link_name(name);
  Id space = make_space(shape, values.size());
  Dataset dataset(Id(check_id(H5Dcreate2(group, name.c_str(), file_type, space.get(), H5P_DEFAULT,
                                         H5P_DEFAULT, H5P_DEFAULT),
                              "cannot create dataset " + quoted(name)),
                     H5Dclose));
  if (!values.empty()) {  // HDF5 rejects a null buffer even for zero elements
    check(H5Dwrite(dataset.id(), memory_type, H5S_ALL, H5S_ALL, H5P_DEFAULT, values.data()),
          "cannot write dataset " + quoted(name));
  }
  return dataset;
}

}  // namespace

void raise(const std::string& what) {
  Guard guard;
  StackText text;
  H5Ewalk2(H5E_DEFAULT, H5E_WALK_DOWNWARD, collect, &text);
  H5Eclear2(H5E_DEFAULT);
  std::string message = what;
  if (!text.outer.empty()) message += ": " + text.outer;
  if (!text.inner.empty() && text.inner != text.outer) message += " (" + text.inner + ")";
  throw std::runtime_error(message);
}

// ---- Id ----

Id::Id(Id&& other) noexcept
    : id_(std::exchange(other.id_, H5I_INVALID_HID)),
      closer_(std::exchange(other.closer_, nullptr)) {}

Id& Id::operator=(Id&& other) noexcept {
  if (this != &other) {
    Id old(std::move(*this));  // released by its destructor
    id_ = std::exchange(other.id_, H5I_INVALID_HID);
    closer_ = std::exchange(other.closer_, nullptr);
  }
  return *this;
}

Id::~Id() {
  if (valid() && closer_ != nullptr) {
    Guard guard;
    closer_(id_);
    H5Eclear2(H5E_DEFAULT);  // a failed release has no one to report to
  }
}

void Id::close(const std::string& what) {
  if (!valid()) return;
  Guard guard;
  // The identifier counts as released even when HDF5 reports a failure:
  // closing it again could only fail again.
  const hid_t id = std::exchange(id_, H5I_INVALID_HID);
  if (closer_ != nullptr) check(closer_(id), what);
}

// ---- Attribute ----

Attribute Attribute::open(hid_t object, const std::string& name) {
  Guard guard;
  return Attribute(Id(
      check_id(H5Aopen(object, name.c_str(), H5P_DEFAULT), "cannot open attribute " + quoted(name)),
      H5Aclose));
}

Attribute Attribute::create(hid_t object, const std::string& name, hid_t file_type, hid_t space) {
  Guard guard;
  if (name.empty()) throw std::invalid_argument("HDF5 attribute name must not be empty");
  const htri_t exists = H5Aexists(object, name.c_str());
  if (exists < 0) raise("cannot look up attribute " + quoted(name));
  if (exists > 0)
    check(H5Adelete(object, name.c_str()), "cannot replace attribute " + quoted(name));
  return Attribute(
      Id(check_id(H5Acreate2(object, name.c_str(), file_type, space, H5P_DEFAULT, H5P_DEFAULT),
                  "cannot create attribute " + quoted(name)),
         H5Aclose));
}

// ---- Object ----

bool Object::has_attribute(const std::string& name) const {
  Guard guard;
  const htri_t exists = H5Aexists(id(), name.c_str());
  if (exists < 0) raise("cannot look up attribute " + quoted(name));
  return exists > 0;
}

void Object::set_string_attribute(const std::string& name, std::string_view value) {
  Guard guard;
  Id type = string_type();
  Id space(check_id(H5Screate(H5S_SCALAR), "cannot create a scalar dataspace"), H5Sclose);
  Attribute attribute = Attribute::create(id(), name, type.get(), space.get());
  const std::string text(value);
  const char* pointer = text.c_str();
  check(H5Awrite(attribute.id(), type.get(), &pointer), "cannot write attribute " + quoted(name));
}

void Object::set_double_attribute(const std::string& name, double value) {
  Guard guard;
  Id space(check_id(H5Screate(H5S_SCALAR), "cannot create a scalar dataspace"), H5Sclose);
  Attribute attribute = Attribute::create(id(), name, H5T_IEEE_F64LE, space.get());
  check(H5Awrite(attribute.id(), H5T_NATIVE_DOUBLE, &value),
        "cannot write attribute " + quoted(name));
}

void Object::set_int_attribute(const std::string& name, std::int64_t value) {
  Guard guard;
  Id space(check_id(H5Screate(H5S_SCALAR), "cannot create a scalar dataspace"), H5Sclose);
  Attribute attribute = Attribute::create(id(), name, H5T_STD_I64LE, space.get());
  check(H5Awrite(attribute.id(), H5T_NATIVE_INT64, &value),
        "cannot write attribute " + quoted(name));
}

std::string Object::string_attribute(const std::string& name) const {
  Guard guard;
  Attribute attribute = Attribute::open(id(), name);
  Id file_type(check_id(H5Aget_type(attribute.id()), "attribute " + quoted(name)), H5Tclose);
  if (H5Tget_class(file_type.get()) != H5T_STRING) {
    throw std::runtime_error("attribute " + quoted(name) + " is not a string");
  }
  const htri_t variable = H5Tis_variable_str(file_type.get());
  if (variable < 0) raise("attribute " + quoted(name));
  if (variable > 0) {
    Id type = string_type();
    char* pointer = nullptr;
    check(H5Aread(attribute.id(), type.get(), &pointer), "cannot read attribute " + quoted(name));
    std::string text = pointer != nullptr ? pointer : "";
    H5free_memory(pointer);
    return text;
  }
  // Fixed-length strings (as other tools may write them): trailing NULs are padding.
  const std::size_t size = H5Tget_size(file_type.get());
  std::string text(size, '\0');
  check(H5Aread(attribute.id(), file_type.get(), text.data()),
        "cannot read attribute " + quoted(name));
  text.erase(text.find_last_not_of('\0') + 1);
  return text;
}

double Object::double_attribute(const std::string& name) const {
  Guard guard;
  return read_number_attribute<double>(id(), name, H5T_NATIVE_DOUBLE);
}

std::int64_t Object::int_attribute(const std::string& name) const {
  Guard guard;
  return read_number_attribute<std::int64_t>(id(), name, H5T_NATIVE_INT64);
}

// ---- Dataset ----

std::vector<hsize_t> Dataset::shape() const {
  Guard guard;
  Id space(check_id(H5Dget_space(id()), "cannot get a dataset's dataspace"), H5Sclose);
  const int rank = H5Sget_simple_extent_ndims(space.get());
  if (rank < 0) raise("cannot get a dataset's rank");
  std::vector<hsize_t> dims(static_cast<std::size_t>(rank));
  if (rank > 0 && H5Sget_simple_extent_dims(space.get(), dims.data(), nullptr) < 0) {
    raise("cannot get a dataset's shape");
  }
  return dims;
}

std::vector<double> Dataset::read_doubles() const {
  Guard guard;
  return read_all<double>(id(), H5T_NATIVE_DOUBLE);
}

std::vector<std::int64_t> Dataset::read_ints() const {
  Guard guard;
  return read_all<std::int64_t>(id(), H5T_NATIVE_INT64);
}

// ---- Group ----

Group Group::create_group(const std::string& name) {
  Guard guard;
  check_link_name(name);
  return Group(Id(check_id(H5Gcreate2(id(), name.c_str(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT),
                           "cannot create group " + quoted(name)),
                  H5Gclose));
}

Group Group::open_group(const std::string& name) const {
  Guard guard;
  return Group(
      Id(check_id(H5Gopen2(id(), name.c_str(), H5P_DEFAULT), "cannot open group " + quoted(name)),
         H5Gclose));
}

Group Group::require_group(const std::string& name) {
  Guard guard;
  return contains(name) ? open_group(name) : create_group(name);
}

bool Group::contains(const std::string& name) const {
  Guard guard;
  check_link_name(name);
  const htri_t exists = H5Lexists(id(), name.c_str(), H5P_DEFAULT);
  if (exists < 0) raise("cannot look up " + quoted(name));
  return exists > 0;
}

void Group::remove(const std::string& name) {
  Guard guard;
  check_link_name(name);
  check(H5Ldelete(id(), name.c_str(), H5P_DEFAULT), "cannot delete " + quoted(name));
}

std::vector<std::string> Group::children() const {
  Guard guard;
  H5G_info_t info{};
  check(H5Gget_info(id(), &info), "cannot list a group");
  std::vector<std::string> names;
  names.reserve(info.nlinks);
  for (hsize_t i = 0; i < info.nlinks; ++i) {
    const ssize_t length =
        H5Lget_name_by_idx(id(), ".", H5_INDEX_NAME, H5_ITER_INC, i, nullptr, 0, H5P_DEFAULT);
    if (length < 0) raise("cannot list a group");
    std::string name(static_cast<std::size_t>(length) + 1, '\0');
    if (H5Lget_name_by_idx(id(), ".", H5_INDEX_NAME, H5_ITER_INC, i, name.data(), name.size(),
                           H5P_DEFAULT) < 0) {
      raise("cannot list a group");
    }
    name.resize(static_cast<std::size_t>(length));
    names.push_back(std::move(name));
  }
  return names;
}

Dataset Group::write_doubles(const std::string& name, std::span<const double> values,
                             const std::vector<hsize_t>& shape) {
  Guard guard;
  return write_all<double>(id(), name, values, shape, H5T_IEEE_F64LE, H5T_NATIVE_DOUBLE);
}

Dataset Group::write_ints(const std::string& name, std::span<const std::int64_t> values,
                          const std::vector<hsize_t>& shape) {
  Guard guard;
  return write_all<std::int64_t>(id(), name, values, shape, H5T_STD_I64LE, H5T_NATIVE_INT64);
}

Dataset Group::open_dataset(const std::string& name) const {
  Guard guard;
  return Dataset(
      Id(check_id(H5Dopen2(id(), name.c_str(), H5P_DEFAULT), "cannot open dataset " + quoted(name)),
         H5Dclose));
}

// ---- File ----

namespace {

// Lock the file against a second writer where the file system allows it, and
// carry on without a lock where it does not (some network file systems).
Id access_properties() {
  Id fapl(check_id(H5Pcreate(H5P_FILE_ACCESS), "cannot create file access properties"), H5Pclose);
  check(H5Pset_file_locking(fapl.get(), true, true), "cannot set file locking");
  return fapl;
}

}  // namespace

File File::create(const std::filesystem::path& path) {
  Guard guard;
  Id fapl = access_properties();
  const std::string name = path.string();
  return File(Id(check_id(H5Fcreate(name.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, fapl.get()),
                          "cannot create HDF5 file " + quoted(name)),
                 H5Fclose),
              path);
}

File File::open(const std::filesystem::path& path, Mode mode) {
  Guard guard;
  Id fapl = access_properties();
  const std::string name = path.string();
  const unsigned flags = mode == Mode::read_write ? H5F_ACC_RDWR : H5F_ACC_RDONLY;
  return File(Id(check_id(H5Fopen(name.c_str(), flags, fapl.get()),
                          "cannot open HDF5 file " + quoted(name)),
                 H5Fclose),
              path);
}

Group File::root() const {
  Guard guard;
  return Group(Id(check_id(H5Gopen2(id_.get(), "/", H5P_DEFAULT),
                           "cannot open the root group of " + quoted(path_.string())),
                  H5Gclose));
}

void File::flush() {
  Guard guard;
  check(H5Fflush(id_.get(), H5F_SCOPE_GLOBAL), "cannot flush " + quoted(path_.string()));
}

void File::close() {
  id_.close("cannot close HDF5 file " + quoted(path_.string()));
}

}  // namespace mmpm::io::h5
