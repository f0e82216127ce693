// io/: run file, XDMF, summary, checkpoints, atomic writes.
// The run file is read back with the raw HDF5 C API, not io/h5.hpp, so a bug
// in the wrappers cannot hide itself.
#include <gtest/gtest.h>
#include <hdf5.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <csignal>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "io/atomic_file.hpp"
#include "io/checkpoint.hpp"
#include "io/h5.hpp"
#include "io/run_writer.hpp"
#include "io/summary.hpp"
#include "io/xdmf.hpp"

namespace fs = std::filesystem;
using namespace mmpm::io;

namespace {

// A fresh directory per test, removed afterwards.
class ScratchDir {
 public:
  ScratchDir() {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    path_ = fs::temp_directory_path() / ("mmpm_io_" + std::string(info->test_suite_name()) + "_" +
                                         info->name() + "_" + std::to_string(::getpid()));
    fs::remove_all(path_);
    fs::create_directories(path_);
  }
  ~ScratchDir() {
    std::error_code ignored;
    fs::remove_all(path_, ignored);
  }
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
};

std::string slurp(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void spit(const fs::path& file, const std::string& bytes) {
  std::ofstream out(file, std::ios::binary | std::ios::trunc);
  out << bytes;
}

bool any_tmp_file(const fs::path& dir) {
  for (const auto& entry : fs::directory_iterator(dir)) {
    if (entry.path().extension() == ".tmp") return true;
  }
  return false;
}

// ---- raw HDF5 readers for checking ----

struct RawFile {
  explicit RawFile(const fs::path& path) {
    H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
    id = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  }
  ~RawFile() {
    if (id >= 0) H5Fclose(id);
  }
  bool exists(const std::string& path) const {
    // H5Lexists needs every intermediate group to exist: walk down.
    std::string prefix;
    std::istringstream parts(path);
    std::string part;
    while (std::getline(parts, part, '/')) {
      if (part.empty()) continue;
      prefix += "/" + part;
      if (H5Lexists(id, prefix.c_str(), H5P_DEFAULT) <= 0) return false;
    }
    return true;
  }
  std::vector<double> doubles(const std::string& path,
                              std::vector<hsize_t>* shape = nullptr) const {
    const hid_t ds = H5Dopen2(id, path.c_str(), H5P_DEFAULT);
    EXPECT_GE(ds, 0) << path;
    if (ds < 0) return {};
    const hid_t type = H5Dget_type(ds);
    EXPECT_EQ(H5Tget_class(type), H5T_FLOAT) << path;
    EXPECT_EQ(H5Tget_size(type), 8u) << path << " is not double precision";
    H5Tclose(type);
    const hid_t space = H5Dget_space(ds);
    const int rank = H5Sget_simple_extent_ndims(space);
    std::vector<hsize_t> dims(static_cast<std::size_t>(rank));
    H5Sget_simple_extent_dims(space, dims.data(), nullptr);
    std::vector<double> values(static_cast<std::size_t>(H5Sget_simple_extent_npoints(space)));
    if (!values.empty()) {
      EXPECT_GE(H5Dread(ds, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, values.data()), 0);
    }
    H5Sclose(space);
    H5Dclose(ds);
    if (shape != nullptr) *shape = dims;
    return values;
  }
  template <class T>
  T number_attribute(const std::string& object, const std::string& name, hid_t type) const {
    T value{};
    const hid_t a = H5Aopen_by_name(id, object.c_str(), name.c_str(), H5P_DEFAULT, H5P_DEFAULT);
    EXPECT_GE(a, 0) << object << " @" << name;
    if (a < 0) return value;
    EXPECT_GE(H5Aread(a, type, &value), 0);
    H5Aclose(a);
    return value;
  }
  std::string string_attribute(const std::string& object, const std::string& name) const {
    const hid_t a = H5Aopen_by_name(id, object.c_str(), name.c_str(), H5P_DEFAULT, H5P_DEFAULT);
    EXPECT_GE(a, 0) << object << " @" << name;
    if (a < 0) return {};
    const hid_t type = H5Tcopy(H5T_C_S1);
    H5Tset_size(type, H5T_VARIABLE);
    H5Tset_cset(type, H5T_CSET_UTF8);
    char* text = nullptr;
    EXPECT_GE(H5Aread(a, type, &text), 0);
    std::string out = text != nullptr ? text : "";
    H5free_memory(text);
    H5Tclose(type);
    H5Aclose(a);
    return out;
  }
  std::vector<std::string> children(const std::string& group) const {
    std::vector<std::string> names;
    const hid_t g = H5Gopen2(id, group.c_str(), H5P_DEFAULT);
    if (g < 0) return names;
    H5G_info_t info{};
    H5Gget_info(g, &info);
    for (hsize_t i = 0; i < info.nlinks; ++i) {
      char name[256] = {};
      H5Lget_name_by_idx(g, ".", H5_INDEX_NAME, H5_ITER_INC, i, name, sizeof name, H5P_DEFAULT);
      names.emplace_back(name);
    }
    H5Gclose(g);
    return names;
  }
  hid_t id = -1;
};

// ---- a small synthetic run ----

std::vector<double> ramp(std::size_t n, double start, double step) {
  std::vector<double> v(n);
  for (std::size_t i = 0; i < n; ++i) v[i] = start + step * static_cast<double>(i);
  return v;
}

// Snapshot with recognisable values: every number depends on the step and
// the field, so a mix-up between snapshots or fields shows.
Snapshot make_snapshot(int dimension, long step, double time, std::size_t count) {
  const double s = static_cast<double>(step);
  const int stress = dimension == 2 ? 4 : 6;
  Snapshot snap{step, time, dimension, count, ramp(count * dimension, 0.5 + s, 0.25), {}, {}};
  snap.fields.push_back({"displacement", dimension, ramp(count * dimension, s * 1e-3, 1e-4)});
  snap.fields.push_back({"velocity", dimension, ramp(count * dimension, -s, 0.1)});
  snap.fields.push_back({"stress", stress, ramp(count * stress, 100.0 + s, -1.5)});
  snap.fields.push_back({"material", 1, ramp(count, 0.0, 1.0)});
  return snap;
}

void expect_snapshot_in(const RawFile& file, const Snapshot& snap) {
  char name[32];
  std::snprintf(name, sizeof name, "/particles/step_%010ld", snap.step);
  const std::string group = name;
  ASSERT_TRUE(file.exists(group)) << group;
  EXPECT_EQ(file.number_attribute<std::int64_t>(group, "step", H5T_NATIVE_INT64), snap.step);
  EXPECT_EQ(file.number_attribute<double>(group, "time", H5T_NATIVE_DOUBLE), snap.time);
  std::vector<hsize_t> shape;
  EXPECT_EQ(file.doubles(group + "/position", &shape), snap.position);
  EXPECT_EQ(shape, (std::vector<hsize_t>{snap.count, static_cast<hsize_t>(snap.dimension)}));
  for (const ParticleField& f : snap.fields) {
    EXPECT_EQ(file.doubles(group + "/" + f.name, &shape), f.values) << f.name;
    EXPECT_EQ(shape, (std::vector<hsize_t>{snap.count, static_cast<hsize_t>(f.components)}))
        << f.name;
  }
  std::vector<std::string> expected{"position"};
  for (const ParticleField& f : snap.fields) expected.push_back(f.name);
  std::sort(expected.begin(), expected.end());
  EXPECT_EQ(file.children(group), expected) << "a snapshot group holds exactly its datasets";
}

// Every piece of text between an occurrence of `open` and the next `close`.
// (Plain scanning rather than std::regex, whose GCC 12 headers trip
// -Wmaybe-uninitialized in some optimised and sanitizer builds.)
std::vector<std::string> between(const std::string& text, const std::string& open,
                                 const std::string& close) {
  std::vector<std::string> out;
  for (std::size_t at = text.find(open); at != std::string::npos; at = text.find(open, at)) {
    at += open.size();
    const std::size_t end = text.find(close, at);
    if (end == std::string::npos) break;
    out.push_back(text.substr(at, end - at));
    at = end + close.size();
  }
  return out;
}

void write_and_check_run(int dimension) {
  ScratchDir scratch;
  const fs::path dir = scratch.path() / "nested" / "out";  // created by the writer
  const std::size_t count = 7;
  const std::vector<Snapshot> snaps{make_snapshot(dimension, 0, 0.0, count),
                                    make_snapshot(dimension, 40, 0.1 + 0.2, count)};
  const std::vector<std::string> names{"time", "kinetic", "strain"};
  const std::vector<std::vector<double>> columns{ramp(5, 0.0, 0.01), ramp(5, 1.0, 2.0),
                                                 ramp(5, -3.0, 0.5)};
  const std::string scene = "[simulation]\ndimension = " + std::to_string(dimension) + "\n";
  {
    RunWriter writer(dir);
    writer.set_attribute("scene", scene);
    writer.set_attribute("build", "g++ 12, double");
    for (const Snapshot& s : snaps) writer.write_snapshot(s);
    writer.sync();  // as before a checkpoint
    EXPECT_TRUE(fs::exists(dir / "run.h5.partial"));
    EXPECT_FALSE(fs::exists(dir / "run.h5"));
    writer.write_series(names, columns);
    writer.finish();
  }
  EXPECT_FALSE(fs::exists(dir / "run.h5.partial"));
  ASSERT_TRUE(fs::exists(dir / "run.h5"));
  ASSERT_TRUE(fs::exists(dir / "run.xdmf"));
  EXPECT_FALSE(any_tmp_file(dir));

  const RawFile file(dir / "run.h5");
  ASSERT_GE(file.id, 0);
  EXPECT_EQ(file.string_attribute("/", "scene"), scene);
  EXPECT_EQ(file.string_attribute("/", "build"), "g++ 12, double");
  for (const Snapshot& s : snaps) expect_snapshot_in(file, s);
  EXPECT_EQ(file.children("/particles"),
            (std::vector<std::string>{"step_0000000000", "step_0000000040"}));
  for (std::size_t i = 0; i < names.size(); ++i) {
    EXPECT_EQ(file.doubles("/series/" + names[i]), columns[i]) << names[i];
  }
  EXPECT_EQ(file.string_attribute("/series", "columns"), "time,kinetic,strain");

  // run.xdmf: one grid per snapshot, exact times, and every dataset it
  // names exists in run.h5 with the dimensions it claims.
  const std::string xdmf = slurp(dir / "run.xdmf");
  EXPECT_NE(xdmf.find("CollectionType=\"Temporal\""), std::string::npos);
  const std::vector<std::string> times = between(xdmf, "<Time Value=\"", "\"/>");
  ASSERT_EQ(times.size(), snaps.size());
  for (std::size_t i = 0; i < snaps.size(); ++i) EXPECT_EQ(std::stod(times[i]), snaps[i].time);
  EXPECT_EQ(between(xdmf, "TopologyType=\"", "\""),
            std::vector<std::string>(snaps.size(), "Polyvertex"));
  EXPECT_EQ(between(xdmf, "GeometryType=\"", "\""),
            std::vector<std::string>(snaps.size(), dimension == 2 ? "XY" : "XYZ"));

  std::set<std::string> referenced;
  const std::vector<std::string> items = between(xdmf, "<DataItem Dimensions=\"", "</DataItem>");
  EXPECT_EQ(items.size(), snaps.size() * 6);  // topology, geometry, 4 fields
  for (const std::string& item : items) {
    const std::string claimed = item.substr(0, item.find('"'));
    const std::size_t file_at = item.find(">run.h5:");
    ASSERT_NE(file_at, std::string::npos) << item;
    const std::string path = item.substr(file_at + 8);
    referenced.insert(path);
    ASSERT_TRUE(file.exists(path)) << path;
    std::vector<hsize_t> shape;
    if (path.find("vertices") != std::string::npos) continue;  // integer dataset
    file.doubles(path, &shape);
    std::string dims;
    for (const hsize_t d : shape) dims += (dims.empty() ? "" : " ") + std::to_string(d);
    EXPECT_EQ(claimed, dims) << path;
  }
  for (const Snapshot& s : snaps) {
    char name[32];
    std::snprintf(name, sizeof name, "step_%010ld", s.step);
    const std::string group = std::string("/particles/") + name;
    EXPECT_EQ(referenced.count(group + "/position"), 1u);
    EXPECT_EQ(referenced.count(group + "/stress"), 1u);
    EXPECT_EQ(referenced.count(group + "/material"), 1u);
    // ParaView needs 3-component vectors: 2D ones go through a padded copy.
    const std::string velocity =
        dimension == 2 ? std::string("/xdmf/") + name + "/velocity" : group + "/velocity";
    EXPECT_EQ(referenced.count(velocity), 1u) << velocity;
    if (dimension == 2) {
      const std::vector<double> padded = file.doubles(velocity);
      const std::vector<double>& original = s.fields[1].values;
      ASSERT_EQ(padded.size(), count * 3);
      for (std::size_t p = 0; p < count; ++p) {
        EXPECT_EQ(padded[3 * p], original[2 * p]);
        EXPECT_EQ(padded[3 * p + 1], original[2 * p + 1]);
        EXPECT_EQ(padded[3 * p + 2], 0.0);
      }
    }
  }
  const auto kinds = [&](const std::string& field) {
    return between(xdmf, "Name=\"" + field + "\" AttributeType=\"", "\"");
  };
  EXPECT_EQ(kinds("velocity"), std::vector<std::string>(snaps.size(), "Vector"));
  EXPECT_EQ(kinds("displacement"), std::vector<std::string>(snaps.size(), "Vector"));
  EXPECT_EQ(kinds("material"), std::vector<std::string>(snaps.size(), "Scalar"));
  EXPECT_EQ(kinds("stress"), std::vector<std::string>(snaps.size(), "Matrix"));
}

// The snapshot files of a run's partial directory, each checked to hold
// its own snapshot, as the step names.
std::vector<std::string> steps_in(const fs::path& partial) {
  std::set<std::string> names;
  for (const auto& entry : fs::directory_iterator(partial)) {
    const std::string stem = entry.path().stem().string();
    EXPECT_EQ(entry.path().extension(), ".h5") << entry.path();
    const RawFile file(entry.path());
    EXPECT_GE(file.id, 0) << entry.path();
    EXPECT_EQ(file.children("/particles"), std::vector<std::string>{stem}) << entry.path();
    names.insert(stem);
  }
  return {names.begin(), names.end()};
}

}  // namespace

// ---------------------------------------------------------------- atomic file

TEST(IoAtomicFile, WritesAndReplacesLeavingNoTmp) {
  ScratchDir scratch;
  const fs::path file = scratch.path() / "a.txt";
  write_file_atomic(file, "first");
  EXPECT_EQ(slurp(file), "first");
  write_file_atomic(file, std::string("second\0with nul", 15));
  EXPECT_EQ(slurp(file), std::string("second\0with nul", 15));
  write_file_atomic(file, "");
  EXPECT_EQ(slurp(file), "");
  EXPECT_FALSE(fs::exists(scratch.path() / "a.txt.tmp"));
  EXPECT_FALSE(any_tmp_file(scratch.path()));
}

TEST(IoAtomicFile, FailureThrowsAndLeavesTargetAndNoTmp) {
  ScratchDir scratch;
  EXPECT_THROW(write_file_atomic(scratch.path() / "missing" / "a.txt", "x"), std::runtime_error);
  // Renaming a file over a non-empty directory fails after the .tmp exists.
  const fs::path target = scratch.path() / "target";
  fs::create_directories(target / "inside");
  try {
    write_file_atomic(target, "x");
    ADD_FAILURE() << "expected an exception";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find(target.string()), std::string::npos) << e.what();
  }
  EXPECT_TRUE(fs::is_directory(target / "inside"));
  EXPECT_FALSE(any_tmp_file(scratch.path()));
}

// ---------------------------------------------------------------- summary

TEST(IoSummary, RoundTripPrettyTwoSpaces) {
  ScratchDir scratch;
  const fs::path file = scratch.path() / "summary.json";
  const nlohmann::json j = {{"scene", "two-layer"},
                            {"steps", 4210},
                            {"dt", 9.5e-5},
                            {"stages_s", {{"sort", 0.1}, {"p2g", 0.6}}}};
  write_summary(file, j);
  EXPECT_EQ(read_summary(file), j);
  const std::string text = slurp(file);
  EXPECT_NE(text.find("\n  \"scene\": \"two-layer\""), std::string::npos) << text;
  EXPECT_NE(text.find("\n    \"p2g\": 0.6"), std::string::npos) << text;
  EXPECT_EQ(text.back(), '\n');
  EXPECT_FALSE(any_tmp_file(scratch.path()));
}

TEST(IoSummary, UnreadableOrInvalidThrowsNamingTheFile) {
  ScratchDir scratch;
  const fs::path file = scratch.path() / "summary.json";
  EXPECT_THROW(read_summary(file), std::runtime_error);
  spit(file, "{\"scene\": ");
  try {
    read_summary(file);
    ADD_FAILURE() << "expected an exception";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("summary " + file.string()), std::string::npos);
  }
}

// ---------------------------------------------------------------- checkpoint

namespace {

struct Pod {
  int a;
  double b;
};

std::vector<Blob> sample_blobs() {
  return {make_blob("x", std::vector<double>{1.0, -2.5, 3.25e-300}),
          make_blob("ids", std::vector<std::int64_t>{7, -1, 1LL << 40}),
          make_blob("pods", std::vector<Pod>{{1, 0.5}, {2, -0.25}}),
          make_blob("empty", std::vector<float>{}),
          make_scalar_blob("step", 123456789L),
          make_scalar_blob("time", 0.375),
          make_string_blob("scene", "[grid]\ncells = [4, 4]\n")};
}

void expect_corrupt(const fs::path& file, const std::string& why) {
  try {
    read_checkpoint(file);
    ADD_FAILURE() << why << ": accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("checkpoint " + file.string() + ": corrupt"),
              std::string::npos)
        << why << ": " << e.what();
  }
}

}  // namespace

TEST(IoCheckpoint, RoundTrip) {
  ScratchDir scratch;
  const fs::path file = scratch.path() / "checkpoint.bin";
  write_checkpoint(file, sample_blobs());
  EXPECT_FALSE(any_tmp_file(scratch.path()));
  const std::vector<Blob> blobs = read_checkpoint(file);
  ASSERT_EQ(blobs.size(), 7u);

  std::vector<double> x;
  read_blob(find_blob(blobs, "x"), x);
  EXPECT_EQ(x, (std::vector<double>{1.0, -2.5, 3.25e-300}));
  std::vector<std::int64_t> ids;
  read_blob(find_blob(blobs, "ids"), ids);
  EXPECT_EQ(ids, (std::vector<std::int64_t>{7, -1, 1LL << 40}));
  std::vector<Pod> pods;
  read_blob(find_blob(blobs, "pods"), pods);
  ASSERT_EQ(pods.size(), 2u);
  EXPECT_EQ(pods[1].a, 2);
  EXPECT_EQ(pods[1].b, -0.25);
  std::vector<float> empty{1.0f};
  read_blob(find_blob(blobs, "empty"), empty);
  EXPECT_TRUE(empty.empty());
  EXPECT_EQ(read_scalar_blob<long>(find_blob(blobs, "step")), 123456789L);
  EXPECT_EQ(read_scalar_blob<double>(find_blob(blobs, "time")), 0.375);
  EXPECT_EQ(read_string_blob(find_blob(blobs, "scene")), "[grid]\ncells = [4, 4]\n");
  EXPECT_EQ(blobs[0].name, "x");  // order kept
  EXPECT_EQ(blobs[6].name, "scene");
}

TEST(IoCheckpoint, FormatIsMagicCountBlobsChecksum) {
  ScratchDir scratch;
  const fs::path file = scratch.path() / "c.bin";
  write_checkpoint(file, {make_string_blob("ab", "xyz")});
  const std::string bytes = slurp(file);
  std::string expected = "MMPMCKP1";
  const auto u64 = [&](std::uint64_t v) {
    for (int i = 0; i < 8; ++i) expected.push_back(static_cast<char>((v >> (8 * i)) & 0xff));
  };
  u64(1);
  u64(2);
  expected += "ab";
  u64(3);
  expected += "xyz";
  u64(fnv1a64(expected));
  EXPECT_EQ(bytes, expected);
  // Published FNV-1a 64 test vectors.
  EXPECT_EQ(fnv1a64(""), 0xcbf29ce484222325ull);
  EXPECT_EQ(fnv1a64("a"), 0xaf63dc4c8601ec8cull);
  EXPECT_EQ(fnv1a64("foobar"), 0x85944171f73967e8ull);
}

TEST(IoCheckpoint, TruncatedIsRejectedAtEveryLength) {
  ScratchDir scratch;
  const fs::path good = scratch.path() / "good.bin";
  write_checkpoint(good, sample_blobs());
  const std::string bytes = slurp(good);
  const fs::path bad = scratch.path() / "bad.bin";
  for (std::size_t length = 0; length < bytes.size(); ++length) {
    spit(bad, bytes.substr(0, length));
    expect_corrupt(bad, "truncated to " + std::to_string(length));
  }
  spit(bad, bytes + "x");
  expect_corrupt(bad, "trailing byte");
}

TEST(IoCheckpoint, AnyFlippedBitIsRejected) {
  ScratchDir scratch;
  const fs::path good = scratch.path() / "good.bin";
  write_checkpoint(good, sample_blobs());
  const std::string bytes = slurp(good);
  const fs::path bad = scratch.path() / "bad.bin";
  for (std::size_t i = 0; i < bytes.size(); ++i) {
    std::string flipped = bytes;
    flipped[i] = static_cast<char>(flipped[i] ^ (1 << (i % 8)));
    spit(bad, flipped);
    expect_corrupt(bad, "bit flipped in byte " + std::to_string(i));
  }
}

TEST(IoCheckpoint, MissingFileDuplicateNamesAndMissingBlob) {
  ScratchDir scratch;
  EXPECT_THROW(read_checkpoint(scratch.path() / "none.bin"), std::runtime_error);
  EXPECT_THROW(write_checkpoint(scratch.path() / "dup.bin",
                                {make_scalar_blob("a", 1), make_scalar_blob("a", 2)}),
               std::invalid_argument);
  EXPECT_FALSE(fs::exists(scratch.path() / "dup.bin"));
  const std::vector<Blob> blobs = sample_blobs();
  try {
    find_blob(blobs, "nope");
    ADD_FAILURE() << "expected an exception";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("'nope'"), std::string::npos);
  }
  std::vector<double> wrong;
  EXPECT_THROW(read_blob(find_blob(blobs, "scene"), wrong), std::runtime_error);  // 21 bytes
  EXPECT_THROW(read_scalar_blob<int>(find_blob(blobs, "time")), std::runtime_error);
}

// ---------------------------------------------------------------- h5 wrappers

TEST(IoH5, FailuresThrowWithHdf5MessageAndPrintNothing) {
  ScratchDir scratch;
  const fs::path missing = scratch.path() / "missing.h5";
  ::testing::internal::CaptureStderr();
  try {
    h5::File::open(missing, h5::File::Mode::read_only);
    ADD_FAILURE() << "expected an exception";
  } catch (const std::runtime_error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(missing.string()), std::string::npos) << what;
    EXPECT_NE(what.find("unable to open file"), std::string::npos) << what;  // HDF5's words
  }
  h5::File file = h5::File::create(scratch.path() / "a.h5");
  h5::Group root = file.root();
  EXPECT_THROW(root.open_group("absent"), std::runtime_error);
  EXPECT_THROW(root.string_attribute("absent"), std::runtime_error);
  EXPECT_THROW(root.write_doubles("bad", std::vector<double>{1, 2, 3}, {2, 2}),
               std::invalid_argument);
  root.write_doubles("d", std::vector<double>{1, 2}, {2});
  EXPECT_THROW(root.write_doubles("d", std::vector<double>{1, 2}, {2}), std::runtime_error);
  EXPECT_EQ(::testing::internal::GetCapturedStderr(), "");
}

TEST(IoH5, AttributesDatasetsAndGroupsRoundTrip) {
  ScratchDir scratch;
  const fs::path path = scratch.path() / "a.h5";
  const std::string long_text(200000, 'x');  // beyond the 64 KiB compact-attribute limit
  {
    h5::File file = h5::File::create(path);
    h5::Group root = file.root();
    root.set_string_attribute("long", long_text);
    root.set_string_attribute("utf8", "σ_xx in MPa");
    root.set_string_attribute("utf8", "replaced");
    root.set_double_attribute("x", 0.1);
    root.set_int_attribute("n", -42);
    h5::Group g = root.create_group("g");
    g.write_doubles("empty", std::vector<double>{}, {0, 3});
    g.write_ints("ids", std::vector<std::int64_t>{3, 1, 2}, {3});
    root.create_group("b");
    file.close();
  }
  h5::File file = h5::File::open(path, h5::File::Mode::read_only);
  const h5::Group root = file.root();
  EXPECT_EQ(root.string_attribute("long"), long_text);
  EXPECT_EQ(root.string_attribute("utf8"), "replaced");
  EXPECT_EQ(root.double_attribute("x"), 0.1);
  EXPECT_EQ(root.int_attribute("n"), -42);
  EXPECT_TRUE(root.has_attribute("n"));
  EXPECT_FALSE(root.has_attribute("m"));
  EXPECT_EQ(root.children(), (std::vector<std::string>{"b", "g"}));
  const h5::Group g = root.open_group("g");
  EXPECT_EQ(g.open_dataset("empty").shape(), (std::vector<hsize_t>{0, 3}));
  EXPECT_TRUE(g.open_dataset("empty").read_doubles().empty());
  EXPECT_EQ(g.open_dataset("ids").read_ints(), (std::vector<std::int64_t>{3, 1, 2}));
}

// ---------------------------------------------------------------- xdmf

TEST(IoXdmf, AttributeKinds) {
  EXPECT_EQ(attribute_kind(1, 2), AttributeKind::scalar);
  EXPECT_EQ(attribute_kind(2, 2), AttributeKind::vector);
  EXPECT_EQ(attribute_kind(3, 3), AttributeKind::vector);
  EXPECT_EQ(attribute_kind(3, 2), AttributeKind::matrix);  // 2D stress xx yy xy
  EXPECT_EQ(attribute_kind(4, 2), AttributeKind::matrix);
  EXPECT_EQ(attribute_kind(6, 3), AttributeKind::matrix);  // Voigt order is not Tensor6's
  EXPECT_EQ(attribute_kind(9, 3), AttributeKind::tensor);
}

TEST(IoXdmf, EmptyRunIsAValidDocument) {
  const std::string doc = xdmf_document("run.h5", {});
  EXPECT_NE(doc.find("<Grid Name=\"particles\" GridType=\"Collection\""), std::string::npos);
  EXPECT_NE(doc.find("</Xdmf>"), std::string::npos);
}

// ---------------------------------------------------------------- run writer

TEST(IoRunWriter, Writes2DRun) {
  write_and_check_run(2);
}

TEST(IoRunWriter, Writes3DRun) {
  write_and_check_run(3);
}

TEST(IoRunWriter, AbandonLeavesNothing) {
  ScratchDir scratch;
  const fs::path dir = scratch.path() / "out";
  RunWriter writer(dir);
  writer.write_snapshot(make_snapshot(2, 0, 0.0, 3));
  writer.abandon();
  EXPECT_TRUE(fs::is_empty(dir));
  writer.abandon();  // idempotent
  EXPECT_THROW(writer.write_snapshot(make_snapshot(2, 1, 0.1, 3)), std::logic_error);
}

TEST(IoRunWriter, NewRunRemovesAnEarlierRunsResults) {
  ScratchDir scratch;
  spit(scratch.path() / "run.h5", "old");
  spit(scratch.path() / "run.xdmf", "old");
  RunWriter writer(scratch.path());
  EXPECT_FALSE(fs::exists(scratch.path() / "run.h5"));
  EXPECT_FALSE(fs::exists(scratch.path() / "run.xdmf"));
  writer.abandon();
}

TEST(IoRunWriter, DestructorLeavesPartialForRestart) {
  ScratchDir scratch;
  { RunWriter(scratch.path()).write_snapshot(make_snapshot(3, 5, 0.5, 4)); }
  EXPECT_TRUE(fs::exists(scratch.path() / "run.h5.partial"));
  EXPECT_FALSE(fs::exists(scratch.path() / "run.h5"));
  EXPECT_EQ(steps_in(scratch.path() / "run.h5.partial"),
            (std::vector<std::string>{"step_0000000005"}));
}

TEST(IoRunWriter, ReopenDeletesLaterSnapshotsAndEndsLikeAnUninterruptedRun) {
  ScratchDir scratch;
  const fs::path dir = scratch.path();
  {
    RunWriter writer(dir);
    writer.set_attribute("scene", "s");
    for (long step : {0L, 10L, 20L, 30L}) {
      writer.write_snapshot(make_snapshot(2, step, 0.01 * step, 5));
    }
    writer.write_series({"time"}, {{0.0, 0.1}});
  }  // "killed" after step 30, last checkpoint at step 10
  RunWriter writer = RunWriter::reopen(dir, 10);
  EXPECT_EQ(steps_in(dir / "run.h5.partial"),
            (std::vector<std::string>{"step_0000000000", "step_0000000010"}));
  writer.set_attribute("scene", "s");  // attributes live in memory: a restart sets them again
  Snapshot redo = make_snapshot(2, 20, 0.2, 5);
  redo.position[0] = -99.0;  // the restarted run's own data must win
  writer.write_snapshot(redo);
  writer.write_series({"time"}, {{0.0, 0.1, 0.2}});
  writer.finish();

  const RawFile file(dir / "run.h5");
  EXPECT_EQ(file.children("/particles"),
            (std::vector<std::string>{"step_0000000000", "step_0000000010", "step_0000000020"}));
  expect_snapshot_in(file, make_snapshot(2, 10, 0.1, 5));
  expect_snapshot_in(file, redo);
  EXPECT_EQ(file.doubles("/series/time"), (std::vector<double>{0.0, 0.1, 0.2}));
  EXPECT_EQ(file.string_attribute("/", "scene"), "s");
  EXPECT_EQ(file.children("/xdmf"), (std::vector<std::string>{"step_0000000000", "step_0000000010",
                                                              "step_0000000020", "vertices_5"}));
  const std::string xdmf = slurp(dir / "run.xdmf");
  EXPECT_EQ(between(xdmf, "<Time Value=\"", "\"/>"), (std::vector<std::string>{"0", "0.1", "0.2"}));
}

// In a forked child that is to die as a killed run does: a writer never
// destroyed, with the snapshots of steps 0 and 7 written.
RunWriter& leaked_writer_with_steps_0_and_7(const fs::path& dir) {
  auto* writer = new RunWriter(dir);  // leaked on purpose: no destructor runs
  writer->write_snapshot(make_snapshot(2, 0, 0.0 / 10, 6));
  writer->write_snapshot(make_snapshot(2, 7, 7.0 / 10, 6));
  return *writer;
}

// The restart of such a run from a checkpoint at step 7: it keeps steps 0
// and 7, writes 14 and ends with all three.
void expect_restart_from_step_7(const fs::path& dir) {
  RunWriter writer = RunWriter::reopen(dir, 7);
  EXPECT_EQ(steps_in(dir / "run.h5.partial"),
            (std::vector<std::string>{"step_0000000000", "step_0000000007"}));
  writer.write_snapshot(make_snapshot(2, 14, 14.0 / 10, 6));
  writer.finish();
  const RawFile file(dir / "run.h5");
  for (long step : {0L, 7L, 14L})
    expect_snapshot_in(file, make_snapshot(2, step, static_cast<double>(step) / 10, 6));
}

TEST(IoRunWriter, ReopenAfterTheWritingProcessWasKilled) {
  ScratchDir scratch;
  const fs::path dir = scratch.path();
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    // The child writes two snapshots and dies without closing anything.
    try {
      leaked_writer_with_steps_0_and_7(dir);
    } catch (...) {
      ::_exit(3);
    }
    ::_exit(0);
  }
  int status = 0;
  ASSERT_EQ(::waitpid(child, &status, 0), child);
  ASSERT_TRUE(WIFEXITED(status));
  ASSERT_EQ(WEXITSTATUS(status), 0);
  expect_restart_from_step_7(dir);
}

// What a kill in the middle of a write leaves: a snapshot's .tmp file cut
// short and a half-assembled run.h5 in the partial directory. A restart
// from the checkpoint at step 20 drops both and keeps every snapshot the
// run had finished.
TEST(IoRunWriter, ReopenDropsWhatAKilledWriteLeft) {
  ScratchDir scratch;
  const fs::path dir = scratch.path();
  {
    RunWriter writer(dir);
    for (long step : {0L, 10L, 20L}) writer.write_snapshot(make_snapshot(2, step, 0.01 * step, 5));
  }
  const fs::path partial = dir / "run.h5.partial";
  fs::copy_file(partial / "step_0000000020.h5", partial / "step_0000000030.h5.tmp");
  fs::resize_file(partial / "step_0000000030.h5.tmp", 700);
  fs::copy_file(partial / "step_0000000020.h5", partial / "run.h5");
  fs::resize_file(partial / "run.h5", 900);

  RunWriter writer = RunWriter::reopen(dir, 20);
  EXPECT_EQ(steps_in(partial),
            (std::vector<std::string>{"step_0000000000", "step_0000000010", "step_0000000020"}));
  writer.write_snapshot(make_snapshot(2, 30, 0.01 * 30, 5));
  writer.finish();
  const RawFile file(dir / "run.h5");
  for (long step : {0L, 10L, 20L, 30L})
    expect_snapshot_in(file, make_snapshot(2, step, 0.01 * step, 5));
  EXPECT_FALSE(fs::exists(partial));
}

// A process killed for real while it writes a large snapshot (the parent
// sends SIGKILL as soon as the snapshot's file appears; its write takes
// ~0.1 s): the snapshots before it stay readable and the run goes on from
// the checkpoint that followed them. One HDF5 file written in place lost
// them all, once in many runs (Restart.KilledFloatRunContinuesBitwise,
// 2026-11-30: "unable to get link name (free block size is zero?)").
TEST(IoRunWriter, ReopenAfterAKillDuringASnapshotWrite) {
  ScratchDir scratch;
  const fs::path dir = scratch.path();
  const fs::path big = dir / "run.h5.partial" / "step_0000000014.h5.tmp";
  const Snapshot large = make_snapshot(2, 14, 14.0 / 10, 1'500'000);  // 132 MB of values
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    try {
      RunWriter& writer = leaked_writer_with_steps_0_and_7(dir);
      for (;;) writer.write_snapshot(large);  // until killed
    } catch (...) {
      ::_exit(3);
    }
  }
  const auto t0 = std::chrono::steady_clock::now();
  while (!fs::exists(big) && std::chrono::steady_clock::now() - t0 < std::chrono::seconds(60))
    std::this_thread::sleep_for(std::chrono::microseconds(200));
  std::this_thread::sleep_for(std::chrono::milliseconds(20));  // into the write
  ASSERT_EQ(::kill(child, SIGKILL), 0);
  int status = 0;
  ASSERT_EQ(::waitpid(child, &status, 0), child);
  ASSERT_TRUE(WIFSIGNALED(status)) << "the writer ended by itself, status " << status;
  EXPECT_TRUE(fs::exists(big)) << "the kill fell between two writes, not in one";
  expect_restart_from_step_7(dir);
}

// A snapshot write that fails (a full disk; here a file size limit with
// SIGXFSZ ignored, so the write fails with EFBIG as with ENOSPC) throws one
// message naming the file and the reason, and leaves no file of that step:
// the snapshots before it and a restart from them are untouched. Run in a
// child process, whose limit the test runner does not share.
TEST(IoRunWriter, FailedSnapshotWriteLeavesNoFile) {
  ScratchDir scratch;
  const fs::path dir = scratch.path();
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    ::signal(SIGXFSZ, SIG_IGN);
    const rlimit limit{200 * 1024, 200 * 1024};
    if (::setrlimit(RLIMIT_FSIZE, &limit) != 0) ::_exit(10);
    RunWriter* writer = nullptr;
    try {
      writer = new RunWriter(dir);  // leaked on purpose, as by a killed run
      writer->write_snapshot(make_snapshot(2, 0, 0.0, 6));
    } catch (...) {
      ::_exit(11);
    }
    try {
      writer->write_snapshot(make_snapshot(2, 5, 0.5, 20'000));  // 2.6 MB of values
      ::_exit(12);                                               // the limit did not bite
    } catch (const std::runtime_error& e) {
      const std::string what = e.what();
      const bool named = what.find((dir / "run.h5.partial" / "step_0000000005.h5.tmp").string()) !=
                         std::string::npos;
      ::_exit(!named ? 13 : what.find("File too large") == std::string::npos ? 14 : 0);
    }
  }
  int status = 0;
  ASSERT_EQ(::waitpid(child, &status, 0), child);
  ASSERT_TRUE(WIFEXITED(status)) << status;
  ASSERT_EQ(WEXITSTATUS(status), 0) << "10: setrlimit, 11: the small write failed, 12: no failure, "
                                       "13: the message lacks the file, 14: lacks the reason";
  EXPECT_EQ(steps_in(dir / "run.h5.partial"), std::vector<std::string>{"step_0000000000"});
  RunWriter writer = RunWriter::reopen(dir, 0);
  writer.write_snapshot(make_snapshot(2, 5, 0.5, 6));
  writer.finish();
  const RawFile file(dir / "run.h5");
  expect_snapshot_in(file, make_snapshot(2, 0, 0.0, 6));
  expect_snapshot_in(file, make_snapshot(2, 5, 0.5, 6));
}

// A snapshot file damaged under a running writer: finish() names that
// file (not run.h5, which it was writing), publishes nothing and leaves
// the partial for a restart.
TEST(IoRunWriter, FinishNamesTheDamagedSnapshotFile) {
  ScratchDir scratch;
  const fs::path dir = scratch.path();
  RunWriter writer(dir);
  writer.write_snapshot(make_snapshot(2, 0, 0.0, 5));
  writer.write_snapshot(make_snapshot(2, 5, 0.5, 5));
  const fs::path damaged = dir / "run.h5.partial" / "step_0000000005.h5";
  fs::resize_file(damaged, 600);
  try {
    writer.finish();
    ADD_FAILURE() << "finish() accepted a damaged snapshot";
  } catch (const std::runtime_error& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find(damaged.string()), std::string::npos) << what;
    EXPECT_EQ(what.find("run.h5.partial/run.h5"), std::string::npos) << what;
  }
  EXPECT_FALSE(fs::exists(dir / "run.h5"));
  EXPECT_FALSE(fs::exists(dir / "run.xdmf"));
  EXPECT_FALSE(fs::exists(dir / "run.h5.partial" / "run.h5"));
  EXPECT_TRUE(fs::exists(dir / "run.h5.partial" / "step_0000000000.h5"));
}

// A snapshot the restart keeps that is damaged, or the checkpoint's last
// one missing: refused at once, naming the file.
TEST(IoRunWriter, ReopenRefusesDamagedOrMissingSnapshots) {
  ScratchDir scratch;
  const fs::path dir = scratch.path();
  const fs::path partial = dir / "run.h5.partial";
  const auto write_run = [&] {
    RunWriter writer(dir);
    for (long step : {0L, 10L, 20L}) writer.write_snapshot(make_snapshot(2, step, 0.01 * step, 5));
  };
  const auto refused_naming = [&](long last_step, const fs::path& file) {
    try {
      RunWriter::reopen(dir, last_step);
      ADD_FAILURE() << "reopen accepted a partial without a readable " << file;
    } catch (const std::runtime_error& e) {
      EXPECT_NE(std::string(e.what()).find(file.string()), std::string::npos) << e.what();
    }
  };
  write_run();
  fs::resize_file(partial / "step_0000000010.h5", 600);
  refused_naming(20, partial / "step_0000000010.h5");
  write_run();
  fs::remove(partial / "step_0000000010.h5");
  refused_naming(10, partial / "step_0000000010.h5");
  write_run();
  fs::remove_all(partial);
  std::ofstream(partial) << "an older mmpm's partial file";
  refused_naming(10, partial);
}

TEST(IoRunWriter, ReopenWithoutPartialThrows) {
  ScratchDir scratch;
  EXPECT_THROW(RunWriter::reopen(scratch.path(), 0), std::runtime_error);
}

TEST(IoRunWriter, RewritingAStepReplacesIt) {
  ScratchDir scratch;
  RunWriter writer(scratch.path());
  writer.write_snapshot(make_snapshot(2, 3, 0.3, 4));
  Snapshot again = make_snapshot(2, 3, 0.3, 2);
  again.fields.pop_back();
  writer.write_snapshot(again);
  writer.finish();
  const RawFile file(scratch.path() / "run.h5");
  expect_snapshot_in(file, again);
  EXPECT_EQ(file.children("/xdmf"), (std::vector<std::string>{"step_0000000003", "vertices_2"}));
}

TEST(IoRunWriter, RejectsInconsistentInput) {
  ScratchDir scratch;
  RunWriter writer(scratch.path());
  Snapshot s = make_snapshot(2, 0, 0.0, 4);
  s.position.pop_back();
  EXPECT_THROW(writer.write_snapshot(s), std::invalid_argument);
  s = make_snapshot(2, 0, 0.0, 4);
  s.fields[0].values.push_back(1.0);
  EXPECT_THROW(writer.write_snapshot(s), std::invalid_argument);
  s = make_snapshot(2, 0, 0.0, 4);
  s.fields[0].name = "a/b";
  EXPECT_THROW(writer.write_snapshot(s), std::invalid_argument);
  s = make_snapshot(2, 0, 0.0, 4);
  s.fields[0].name = "position";
  EXPECT_THROW(writer.write_snapshot(s), std::invalid_argument);
  s = make_snapshot(2, 0, 0.0, 4);
  s.dimension = 1;
  EXPECT_THROW(writer.write_snapshot(s), std::invalid_argument);
  s = make_snapshot(2, -1, 0.0, 4);
  EXPECT_THROW(writer.write_snapshot(s), std::invalid_argument);
  EXPECT_THROW(writer.write_series({"a", "b"}, {{1.0}}), std::invalid_argument);
  EXPECT_THROW(writer.write_series({"a", "b"}, {{1.0}, {1.0, 2.0}}), std::invalid_argument);
  EXPECT_THROW(writer.write_series({"a", "a"}, {{1.0}, {2.0}}), std::invalid_argument);
  EXPECT_THROW(writer.write_series({"a,b"}, {{1.0}}), std::invalid_argument);
  writer.finish();
  EXPECT_TRUE(RawFile(scratch.path() / "run.h5").children("/particles").empty())
      << "nothing half-written";
}

// Sweeps run scenes in threads of one process: runs written side by side
// must not disturb each other, and HDF5 must stay quiet in every thread.
TEST(IoRunWriter, ConcurrentRunsInThreads) {
  ScratchDir scratch;
  ::testing::internal::CaptureStderr();
  std::vector<std::thread> threads;
  for (int t = 0; t < 4; ++t) {
    threads.emplace_back([t, &scratch] {
      const fs::path dir = scratch.path() / ("run" + std::to_string(t));
      RunWriter writer(dir);
      for (long step = 0; step < 20; ++step) {
        writer.write_snapshot(make_snapshot(2 + t % 2, step + 100 * t, 0.5 * step, 50 + t));
      }
      writer.finish();
      try {
        h5::File::open(dir / "absent.h5", h5::File::Mode::read_only);
      } catch (const std::runtime_error&) {
      }
    });
  }
  for (std::thread& thread : threads) thread.join();
  EXPECT_EQ(::testing::internal::GetCapturedStderr(), "");
  for (int t = 0; t < 4; ++t) {
    const RawFile file(scratch.path() / ("run" + std::to_string(t)) / "run.h5");
    ASSERT_GE(file.id, 0);
    EXPECT_EQ(file.children("/particles").size(), 20u);
    expect_snapshot_in(file, make_snapshot(2 + t % 2, 19 + 100 * t, 0.5 * 19, 50 + t));
  }
}

TEST(IoRunWriter, EmptyParticleSetAndNoSnapshots) {
  ScratchDir scratch;
  {
    RunWriter writer(scratch.path() / "a");
    writer.write_snapshot(Snapshot{0, 0.0, 3, 0, {}, {{"velocity", 3, {}}}, {}});
    writer.finish();
  }
  EXPECT_TRUE(fs::exists(scratch.path() / "a" / "run.xdmf"));
  {
    RunWriter writer(scratch.path() / "b");
    writer.finish();
  }
  EXPECT_TRUE(fs::exists(scratch.path() / "b" / "run.h5"));
  EXPECT_TRUE(fs::exists(scratch.path() / "b" / "run.xdmf"));
}
