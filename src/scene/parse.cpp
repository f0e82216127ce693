#include "scene/parse.hpp"

#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <climits>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <limits>
#include <optional>
#include <set>
#include <sstream>
#include <toml.hpp>
#include <unordered_map>

#include "scene/cylinder.hpp"
#include "scene/format.hpp"

namespace mmpm {
namespace {

// Values that came from --set carry this prefix plus the key as their file name.
constexpr std::string_view kSetPrefix = "--set ";

using Keys = std::vector<std::string_view>;

// ---------------------------------------------------------------- messages --

struct Place {
  std::string file;
  int line = 0;
};

// Maps a toml value to the file and line a message should name. Values read
// from the scene carry its label and a line; values from --set carry
// "--set KEY" and no line (there is no line a user could look up); values the
// parser made itself (an absent section) are blamed on the file alone.
class Source {
 public:
  explicit Source(std::string label) : label_(std::move(label)) {}
  const std::string& label() const { return label_; }

  Place place(const toml::value& v) const {
    // toml11 (3.7) finds a value's line by counting the newlines from the
    // start of the file on every call, and every [[body]] asks for its
    // line: O(bodies x file size); `mmpm check` of 40 000 disks took 71 s
    // (11.5 s now). Here the line comes from the value's offset in a table
    // of line starts, built once per source text (only the scene file's
    // text is indexed; it lives as long as the parsed tree).
    if (const auto* reg = dynamic_cast<const toml::detail::region*>(toml::detail::get_region(v))) {
      if (reg->name() == label_) return {label_, line_of(*reg)};
      if (reg->name().starts_with(kSetPrefix)) return {reg->name(), 0};
      return {label_, 0};
    }
    const toml::source_location loc = v.location();
    if (loc.file_name() == label_) return {label_, static_cast<int>(loc.line())};
    if (loc.file_name().starts_with(kSetPrefix)) return {loc.file_name(), 0};
    return {label_, 0};
  }

 private:
  int line_of(const toml::detail::region& reg) const {
    const std::vector<char>* text = reg.source().get();
    if (text != indexed_) {
      indexed_ = text;
      line_starts_.assign(1, 0);
      for (std::size_t i = 0; i < text->size(); ++i)
        if ((*text)[i] == '\n') line_starts_.push_back(i + 1);
    }
    const auto offset = static_cast<std::size_t>(reg.first() - reg.begin());
    return static_cast<int>(std::upper_bound(line_starts_.begin(), line_starts_.end(), offset) -
                            line_starts_.begin());
  }

  std::string label_;
  mutable const std::vector<char>* indexed_ = nullptr;  // the text line_starts_ is of
  mutable std::vector<std::size_t> line_starts_;
};

std::string join(const std::string& path, std::string_view key) {
  return path.empty() ? std::string(key) : path + "." + std::string(key);
}

std::string indexed(const std::string& path, std::size_t i) {
  return path + "[" + std::to_string(i) + "]";
}

std::string quote(std::string_view s) {
  return "\"" + std::string(s) + "\"";
}

// "an \"isotropic\"", "a \"box\"": the article that reads right before the word.
std::string a_quoted(std::string_view word) {
  const bool vowel =
      !word.empty() && std::string_view("aeiou").find(word[0]) != std::string_view::npos;
  return (vowel ? "an " : "a ") + quote(word);
}

// Computed coordinates (bounds) in messages: enough digits to see the problem.
std::string short_number(double x) {
  std::ostringstream out;
  out.precision(6);
  out << x;
  return out.str();
}

std::string word_list(const Keys& words, bool quoted) {
  std::string out;
  for (std::size_t i = 0; i < words.size(); ++i) {
    if (i > 0) out += ", ";
    out += quoted ? quote(words[i]) : std::string(words[i]);
  }
  return out;
}

template <class E, std::size_t N>
Keys names_of(const std::array<EnumName<E>, N>& names) {
  Keys out;
  for (const auto& n : names) out.push_back(n.name);
  return out;
}

std::string type_name(const toml::value& v) {
  switch (v.type()) {
    case toml::value_t::boolean:
      return "a boolean";
    case toml::value_t::integer:
      return "an integer";
    case toml::value_t::floating:
      return "a floating-point number";
    case toml::value_t::string:
      return "a string";
    case toml::value_t::array:
      return "an array";
    case toml::value_t::table:
      return "a table";
    case toml::value_t::empty:
      return "nothing";
    default:
      return "a date/time";
  }
}

// toml11 explains a syntax error over several lines with a picture of the
// source; the scene contract is one line, so keep the headline and the hints.
std::string condense_toml_error(const std::string& what) {
  std::istringstream in(what);
  std::string line;
  std::getline(in, line);
  if (line.starts_with("[error] ")) line.erase(0, 8);
  if (line.starts_with("toml::")) {
    const auto colon = line.find(": ");
    if (colon != std::string::npos) line.erase(0, colon + 2);
  }
  // Some messages start with the reader's function ("parse_ml_basic_string:
  // invalid utf8 sequence found"): a name that means nothing to the user.
  if (const auto colon = line.find(": ");
      colon != std::string::npos && line.starts_with("parse_") &&
      line.find_first_not_of("abcdefghijklmnopqrstuvwxyz_") == colon)
    line.erase(0, colon + 2);
  std::string out = line;
  if (!out.empty() && out.back() == '.') out.pop_back();
  std::vector<std::string> hints;
  while (std::getline(in, line)) {
    // Pictures mark the spot with "^--- hint" or "~~~ hint".
    const auto mark = line.find_first_of("^~");
    if (mark == std::string::npos || line.find('|') > mark) continue;
    const auto text = line.find_first_not_of("^~- ", mark);
    if (text == std::string::npos) continue;
    std::string hint = line.substr(text);
    if (std::find(hints.begin(), hints.end(), hint) == hints.end()) hints.push_back(hint);
  }
  for (const std::string& h : hints) out += "; " + h;
  return out;
}

// ------------------------------------------------------- typed value access --

class Table;

// One toml value with its dotted path, able to read itself as the type a key
// needs and to complain about itself in the scene's message format.
class Field {
 public:
  Field(const toml::value& v, std::string path, const Source& src)
      : v_(&v), path_(std::move(path)), src_(&src) {}

  const toml::value& raw() const { return *v_; }
  Where where() const {
    const Place p = src_->place(*v_);
    return Where{p.file, p.line, path_};
  }

  [[noreturn]] void fail(const std::string& what) const {
    const Place p = src_->place(*v_);
    throw InputError(located(p.file, p.line, path_, what));
  }
  [[noreturn]] void wrong_type(std::string_view expected) const {
    fail("expected " + std::string(expected) + ", got " + type_name(*v_));
  }

  // TOML integers are accepted wherever a number is expected.
  double number() const {
    double x = 0;
    if (v_->is_integer()) {
      // An integer past 64 bits reads as the limit (integer_text): taken
      // as a number, 1e20 written 100000000000000000000 became 9.2e18.
      const long long n = v_->as_integer();
      if (n == LLONG_MAX || n == LLONG_MIN)
        fail("expected a number, got the integer " + integer_text(n) +
             "; write it as a float, e.g. 1e20");
      x = static_cast<double>(n);
    } else if (v_->is_floating()) {
      x = v_->as_floating();
    } else {
      wrong_type("a number");
    }
    if (!std::isfinite(x)) fail("expected a finite number, got " + format_number(x));
    return x;
  }
  double positive() const {
    const double x = number();
    if (!(x > 0)) fail("expected a number > 0, got " + format_number(x));
    return x;
  }
  // A material constant or the thickness: they multiply each other and the
  // lengths into masses, moduli and energies, which must stay normal numbers
  // in float as well as in double (FLT_MAX ~3.4e38, FLT_MIN ~1.2e-38). In
  // the scene's units (mm, ms, g, MPa) physical values lie far inside.
  double modulus_like() const {
    const double x = positive();
    if (x < 1e-30 || x > 1e30)
      fail(
          "expected a number from 1e-30 to 1e30 (the products of such constants must stay "
          "representable), got " +
          format_number(x));
    return x;
  }
  double non_negative() const {
    const double x = number();
    if (x < 0) fail("expected a number >= 0, got " + format_number(x));
    return x;
  }
  long long integer() const {
    if (!v_->is_integer()) wrong_type("an integer");
    return v_->as_integer();
  }
  // toml11 reads an integer beyond 64 bits as the nearest 64-bit limit, so a
  // limit in a message stands for "this or beyond".
  static std::string integer_text(long long n) {
    if (n == LLONG_MAX) return std::to_string(n) + " or more (beyond a 64-bit integer)";
    if (n == LLONG_MIN) return std::to_string(n) + " or less (beyond a 64-bit integer)";
    return std::to_string(n);
  }
  int int_at_least(int lowest) const {
    const long long n = integer();
    if (n < lowest)
      fail("expected an integer >= " + std::to_string(lowest) + ", got " + integer_text(n));
    if (n > INT_MAX)
      fail("expected an integer <= " + std::to_string(INT_MAX) + ", got " + integer_text(n));
    return static_cast<int>(n);
  }
  bool boolean() const {
    if (!v_->is_boolean()) wrong_type("a boolean (true or false)");
    return v_->as_boolean();
  }
  std::string string() const {
    if (!v_->is_string()) wrong_type("a string");
    std::string s = v_->as_string().str;
    // Names become directory names, series columns and messages; a control
    // character (a NUL cut the directory name short) has no use in any of them.
    for (const char c : s)
      if (static_cast<unsigned char>(c) < 0x20 || c == 0x7f)
        fail("expected a string without control characters, got one with character code " +
             std::to_string(int(static_cast<unsigned char>(c))));
    return s;
  }
  std::string name() const {
    std::string s = string();
    if (s.empty()) fail("expected a non-empty name");
    return s;
  }

  template <class E, std::size_t N>
  E choice(const std::array<EnumName<E>, N>& names) const {
    const Keys words = names_of(names);
    if (!v_->is_string()) wrong_type("a string, one of " + word_list(words, true));
    const std::string s = v_->as_string().str;
    for (const auto& n : names) {
      if (n.name == s) return n.value;
    }
    fail("expected one of " + word_list(words, true) + ", got " + quote(s));
  }

  // The elements of an array, each named path[i].
  std::vector<Field> elements(std::string_view expected) const {
    if (!v_->is_array()) wrong_type(expected);
    std::vector<Field> out;
    const auto& arr = v_->as_array();
    for (std::size_t i = 0; i < arr.size(); ++i) out.emplace_back(arr[i], indexed(path_, i), *src_);
    return out;
  }

  // Exactly `dim` numbers (one per dimension); the rest of the Vec3 keeps `fill`.
  Vec3 vec(int dim, Vec3 fill = {0, 0, 0}) const {
    const std::string expected =
        "an array of " + std::to_string(dim) + " numbers (one per dimension)";
    const std::vector<Field> items = elements(expected);
    if (items.size() != static_cast<std::size_t>(dim)) {
      fail("expected " + expected + ", got an array of " + std::to_string(items.size()));
    }
    for (std::size_t k = 0; k < items.size(); ++k) {
      const toml::value& e = items[k].raw();
      if (!e.is_integer() && !e.is_floating()) {
        fail("expected " + expected + "; element [" + std::to_string(k) + "] is " + type_name(e));
      }
      fill[k] = items[k].number();
    }
    return fill;
  }

  Table table() const;

 private:
  const toml::value* v_;
  std::string path_;
  const Source* src_;
};

// A toml table with its dotted path: key lookup, required keys, and the
// check that every key present is one the section knows.
class Table {
 public:
  Table(const toml::value& v, std::string path, const Source& src)
      : v_(&v), path_(std::move(path)), src_(&src) {}

  Where where() const {
    const Place p = src_->place(*v_);
    return Where{p.file, p.line, path_};
  }
  Field as_field() const { return Field(*v_, path_, *src_); }
  bool has(std::string_view key) const { return v_->as_table().count(std::string(key)) > 0; }

  std::optional<Field> get(std::string_view key) const {
    const auto& t = v_->as_table();
    const auto it = t.find(std::string(key));
    if (it == t.end()) return std::nullopt;
    return Field(it->second, join(path_, key), *src_);
  }

  // A missing key is reported at the table's own line (its [header]). A
  // table only a --set created (the section is absent from the file) is
  // the file's omission, not the override's: name the file, and the --set.
  Field need(std::string_view key, const std::string& why = "") const {
    if (auto f = get(key)) return *f;
    const std::string what = "missing required key" + (why.empty() ? "" : " (" + why + ")");
    const Place p = src_->place(*v_);
    if (p.file.starts_with(kSetPrefix)) {
      throw InputError(
          located(src_->label(), 0, join(path_, key),
                  what + "; the file has no [" + path_ + "], only '" + p.file + "' made it"));
    }
    fail_key(key, what);
  }

  [[noreturn]] void fail_key(std::string_view key, const std::string& what) const {
    const Place p = src_->place(*v_);
    throw InputError(located(p.file, p.line, join(path_, key), what));
  }

  // Rejects any key outside `allowed`. Of several unknown keys the first in
  // the file is named, so the message does not depend on hash order.
  void only(const Keys& allowed, const std::string& context = "",
            std::string_view noun = "key") const {
    std::optional<Field> first;
    for (const auto& [key, value] : v_->as_table()) {
      if (std::find(allowed.begin(), allowed.end(), key) != allowed.end()) continue;
      Field f(value, join(path_, key), *src_);
      const auto loc = value.location();
      if (!first ||
          std::pair(loc.line(), loc.column()) <
              std::pair(first->raw().location().line(), first->raw().location().column())) {
        first = f;
      }
    }
    if (first) {
      first->fail("unknown " + std::string(noun) + (context.empty() ? "" : " for " + context) +
                  "; allowed " + std::string(noun) + "s: " + word_list(allowed, false));
    }
  }

 private:
  const toml::value* v_;
  std::string path_;
  const Source* src_;
};

Table Field::table() const {
  if (!v_->is_table()) wrong_type("a table");
  return Table(*v_, path_, *src_);
}

// ------------------------------------------------------------- geometry --

struct Bounds {
  Vec3 lo{0, 0, 0};
  Vec3 hi{0, 0, 0};
};

Bounds bounds_of(const std::vector<Vec3>& points, int dim) {
  Bounds b{points.front(), points.front()};
  for (const Vec3& p : points) {
    for (int k = 0; k < dim; ++k) {
      const auto kk = static_cast<std::size_t>(k);
      b.lo[kk] = std::min(b.lo[kk], p[kk]);
      b.hi[kk] = std::max(b.hi[kk], p[kk]);
    }
  }
  return b;
}

// The points that span a body before rotation (box corners, polygon points)
// or its bounds directly for round shapes.
std::vector<Vec3> outline_points(const BodySpec& b) {
  switch (b.shape) {
    case BodyShape::box:
      return {b.min, {b.max[0], b.min[1], b.min[2]}, b.max, {b.min[0], b.max[1], b.max[2]}};
    case BodyShape::polygon:
      return b.points;
    case BodyShape::cylinder: {
      const auto [lo, hi] = cylinder_bounds(b);
      return {lo, hi};
    }
    case BodyShape::disk:
    case BodyShape::sphere: {
      const double r = b.radius;
      const Vec3& c = b.center;
      return {{c[0] - r, c[1] - r, c[2] - r}, {c[0] + r, c[1] + r, c[2] + r}};
    }
  }
  return {};
}

// Bounding box of the body as filled: after `rotate` (2D, about the centre
// of the unrotated bounds) and cut by `clip`. Empty when clip misses it.
std::optional<Bounds> body_bounds(const BodySpec& b, int dim) {
  std::vector<Vec3> pts = outline_points(b);
  Bounds box = bounds_of(pts, dim);
  const bool round = b.shape == BodyShape::disk;
  if (dim == 2 && b.rotate != 0.0 && !round) {
    const double a = b.rotate * std::acos(-1.0) / 180.0;
    const double cx = b.pivot ? (*b.pivot)[0] : 0.5 * (box.lo[0] + box.hi[0]);
    const double cy = b.pivot ? (*b.pivot)[1] : 0.5 * (box.lo[1] + box.hi[1]);
    for (Vec3& p : pts) {
      const double dx = p[0] - cx, dy = p[1] - cy;
      p[0] = cx + std::cos(a) * dx - std::sin(a) * dy;
      p[1] = cy + std::sin(a) * dx + std::cos(a) * dy;
    }
    box = bounds_of(pts, dim);
  }
  if (b.clip) {
    for (std::size_t k = 0; k < static_cast<std::size_t>(dim); ++k) {
      box.lo[k] = std::max(box.lo[k], b.clip->first[k]);
      box.hi[k] = std::min(box.hi[k], b.clip->second[k]);
      if (box.lo[k] >= box.hi[k]) return std::nullopt;
    }
  }
  return box;
}

// Twice the signed area of a polygon (shoelace formula).
double polygon_twice_area(const std::vector<Vec3>& pts) {
  double twice = 0;
  for (std::size_t i = 0; i < pts.size(); ++i) {
    const Vec3& p = pts[i];
    const Vec3& q = pts[(i + 1) % pts.size()];
    twice += p[0] * q[1] - q[0] * p[1];
  }
  return twice;
}

// Area (2D) or volume of a body as filled, at most its clipped bounds'.
double body_measure(const BodySpec& b, int dim, const Bounds& clipped) {
  double shape = 0;
  const double pi = std::acos(-1.0);
  switch (b.shape) {
    case BodyShape::box:
      shape = 1;
      for (std::size_t k = 0; k < static_cast<std::size_t>(dim); ++k) shape *= b.max[k] - b.min[k];
      break;
    case BodyShape::disk:
      shape = pi * b.radius * b.radius;
      break;
    case BodyShape::sphere:
      shape = 4.0 / 3.0 * pi * b.radius * b.radius * b.radius;
      break;
    case BodyShape::cylinder:
      shape = pi * b.radius * b.radius * b.length;
      break;
    case BodyShape::polygon:
      shape = 0.5 * std::abs(polygon_twice_area(b.points));
      break;
  }
  double box = 1;
  for (std::size_t k = 0; k < static_cast<std::size_t>(dim); ++k)
    box *= clipped.hi[k] - clipped.lo[k];
  return std::min(shape, box);
}

// Bytes this process may use (0 when unknown: no check then): the
// machine's RAM, or less under an address-space limit (ulimit -v) or a
// cgroup's memory.max. With RAM alone, `check` of a scene past a 6 GB
// ulimit built its particles until std::bad_alloc.
double usable_memory() {
  const long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGE_SIZE);
  double have = pages > 0 && page > 0 ? double(pages) * double(page) : 0.0;
  auto lower_to = [&](double limit) {
    if (limit > 0) have = have > 0 ? std::min(have, limit) : limit;
  };
  rlimit as{};
  if (getrlimit(RLIMIT_AS, &as) == 0 && as.rlim_cur != RLIM_INFINITY) lower_to(double(as.rlim_cur));
  std::ifstream cgroup("/sys/fs/cgroup/memory.max");
  std::string word;
  if (cgroup >> word && word != "max") {
    char* end = nullptr;
    const double limit = std::strtod(word.c_str(), &end);
    if (end && *end == '\0') lower_to(limit);
  }
  return have;
}

std::string bounds_text(const Bounds& b, int dim) {
  std::string s;
  for (int k = 0; k < dim; ++k) {
    const auto kk = static_cast<std::size_t>(k);
    s += (k > 0 ? " x " : "") + std::string("[") + short_number(b.lo[kk]) + ", " +
         short_number(b.hi[kk]) + "]";
  }
  return s;
}

// Cells of nodes a shape function needs between any particle and the grid edge.
int margin_cells(ShapeKind shape) {
  switch (shape) {
    case ShapeKind::linear:
      return 0;
    case ShapeKind::gimp:
    case ShapeKind::bspline2:
      return 1;
    case ShapeKind::bspline3:
      return 2;
  }
  return 1;
}

// Grid coordinates are compared with a tolerance of a tiny fraction of a cell
// so that values typed in decimal (0.1 * 3) still land on nodes.
constexpr double kNodeTolerance = 1e-9;

std::optional<std::pair<int, bool>> parse_face(const std::string& s, int dim) {
  for (int axis = 0; axis < dim; ++axis) {
    for (const bool max_side : {false, true}) {
      if (s == face_name(axis, max_side)) return std::pair(axis, max_side);
    }
  }
  return std::nullopt;
}

Keys face_names(int dim) {
  static const Keys kAll{"x_min", "x_max", "y_min", "y_max", "z_min", "z_max"};
  return Keys(kAll.begin(), kAll.begin() + 2 * dim);
}

Keys axis_names(int dim) {
  static const Keys kAll{"x", "y", "z"};
  return Keys(kAll.begin(), kAll.begin() + dim);
}

Vec3 normalized(const Field& f, Vec3 v) {
  // Components near the double range's ends are scaled by the largest one
  // first, so that the squares neither overflow nor underflow (ordinary
  // vectors keep the plain division, and their bits).
  const double big = std::max({std::abs(v[0]), std::abs(v[1]), std::abs(v[2])});
  if (!(big > 0)) f.fail("expected a non-zero direction");
  if (big > 1e150 || big < 1e-150)
    for (double& c : v) c /= big;
  const double len = std::sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
  // Leave (nearly) unit vectors alone so a resolved scene reads back bit for bit.
  if (std::abs(len - 1.0) > 1e-14) {
    for (double& c : v) c /= len;
  }
  return v;
}

// ------------------------------------------------------------ the reader --

// Turns the toml tree into a Scene, section by section, in an order where
// every section finds what it refers to already read and checked.
class SceneReader {
 public:
  SceneReader(const Source& src, std::string default_name)
      : src_(src), default_name_(std::move(default_name)) {}

  Scene read(const toml::value& root) {
    const Table top(root, "", src_);
    top.only({"simulation", "grid", "material", "body", "interaction", "boundary", "load", "output",
              "stop"},
             "", "section");
    read_simulation(section(top, "simulation"));
    read_grid(section(top, "grid"));
    for (const Table& t : sections(top, "material")) add_material(t);
    const auto bodies = sections(top, "body");
    for (std::size_t i = 0; i < bodies.size(); ++i) add_body(bodies[i], i);
    if (bodies.empty()) {
      // Nothing to simulate; no line to point at either.
      throw InputError(
          located(src_.label(), 0, "body", "missing: a scene needs at least one [[body]]"));
    }
    if (scene_.simulation.precision == Precision::float32) check_float_range();
    for (const Table& t : sections(top, "interaction")) add_interaction(t);
    // One separation method per scene: the interactions that do not name
    // one take the method another names (else the default, displacement).
    const auto named = std::find(separation_named_.begin(), separation_named_.end(), true);
    if (named != separation_named_.end()) {
      const Separation method =
          scene_.interactions[std::size_t(named - separation_named_.begin())].separation;
      for (InteractionSpec& it : scene_.interactions) it.separation = method;
    }
    const auto boundaries = sections(top, "boundary");
    for (std::size_t i = 0; i < boundaries.size(); ++i) add_boundary(boundaries[i], i);
    for (const Table& t : sections(top, "load")) add_load(t);
    read_output(section(top, "output"));
    if (top.has("stop")) read_stop(section(top, "stop"));
    return std::move(scene_);
  }

 private:
  int dim() const { return scene_.simulation.dimension; }

  // [name]; an absent section reads as an empty table (all defaults).
  Table section(const Table& top, std::string_view name) {
    if (auto f = top.get(name)) {
      if (!f->raw().is_table()) f->wrong_type("a table [" + std::string(name) + "]");
      return f->table();
    }
    return Table(empty_, std::string(name), src_);
  }

  // [[name]] tables, each named name[i].
  std::vector<Table> sections(const Table& top, std::string_view name) const {
    std::vector<Table> out;
    const auto f = top.get(name);
    if (!f) return out;
    const std::string expected = "an array of tables [[" + std::string(name) + "]]";
    for (const Field& e : f->elements(expected)) {
      // The element, not the array: a --set that put a value in the array
      // is blamed on the --set (the element remembers where it came from).
      if (!e.raw().is_table()) e.wrong_type("a table of [[" + std::string(name) + "]]");
      out.push_back(e.table());
    }
    return out;
  }

  const MaterialSpec* find_material(const std::string& name) const {
    for (const MaterialSpec& m : scene_.materials) {
      if (m.name == name) return &m;
    }
    return nullptr;
  }
  // By name through an index: a scan per body made parsing O(bodies^2).
  const BodySpec* find_body(const std::string& name) const {
    const auto it = body_index_.find(name);
    return it == body_index_.end() ? nullptr : &scene_.bodies[it->second];
  }

  // A material name that must be defined; "missing material" otherwise.
  const MaterialSpec& known_material(const Field& f) const {
    const std::string name = f.name();
    if (const MaterialSpec* m = find_material(name)) return *m;
    Keys known;
    for (const MaterialSpec& m : scene_.materials) known.push_back(m.name);
    f.fail("missing material " + quote(name) + ": no [[material]] has this name (defined: " +
           (known.empty() ? std::string("none") : word_list(known, true)) + ")");
  }

  // -------------------------------------------------------- [simulation]
  void read_simulation(const Table& t) {
    t.only({"name",
            "dimension",
            "plane",
            "thickness",
            "end_time",
            "cfl",
            "dt",
            "scheme",
            "flip",
            "xpic_order",
            "precision",
            "default_law",
            "force",
            "sort_every",
            "fuse_constitutive",
            "compensated_positions",
            "fuse_step_tail",
            "mm_fields_share",
            "particle_order",
            "skip_empty_nodes",
            "prefetch_grid",
            "prefetch_particles"});
    SimulationSpec& sim = scene_.simulation;
    const Field d = t.need("dimension");
    const long long dimension = d.integer();
    if (dimension != 2 && dimension != 3)
      d.fail("expected 2 or 3, got " + std::to_string(dimension));
    sim.dimension = static_cast<int>(dimension);
    if (dim() == 3) {
      for (const char* key : {"plane", "thickness"}) {
        if (auto f = t.get(key))
          f->fail("only for dimension = 2 (a 3D scene has no plane or thickness)");
      }
    }
    if (auto f = t.get("plane")) sim.plane = f->choice(kPlaneNames);
    if (auto f = t.get("thickness")) sim.thickness = f->modulus_like();
    sim.end_time = t.need("end_time").positive();
    sim.step_where = Where{src_.label(), 0, "simulation.cfl"};
    if (auto f = t.get("cfl")) {
      sim.cfl = f->positive();
      sim.step_where = f->where();
    }
    if (auto f = t.get("dt")) {
      sim.dt = f->positive();
      sim.step_where = f->where();
    }
    if (auto f = t.get("scheme")) sim.scheme = f->choice(kSchemeNames);
    if (auto f = t.get("flip")) {
      sim.flip = f->number();
      if (sim.flip < 0 || sim.flip > 1)
        f->fail("expected a number in [0, 1], got " + format_number(sim.flip));
    }
    if (auto f = t.get("xpic_order")) {
      sim.xpic_order = f->int_at_least(0);
      if (sim.xpic_order > kMaxXpicOrder)
        f->fail("expected an integer from 0 (off) to " + std::to_string(kMaxXpicOrder) + ", got " +
                std::to_string(sim.xpic_order));
    }
    if (auto f = t.get("precision")) {
      sim.precision = f->choice(kPrecisionNames);
      precision_where_ = f->where();
    }
    if (auto f = t.get("default_law")) {
      sim.default_law = f->choice(kDefaultLawNames);
      sim.default_law_where = f->where();
    }
    if (auto f = t.get("force")) sim.force = f->boolean();
    if (auto f = t.get("sort_every")) sim.sort_every = f->int_at_least(0);
    if (auto f = t.get("fuse_constitutive")) sim.fuse_constitutive = f->boolean();
    if (auto f = t.get("compensated_positions")) sim.compensated_positions = f->boolean();
    if (auto f = t.get("fuse_step_tail")) sim.fuse_step_tail = f->boolean();
    if (auto f = t.get("skip_empty_nodes")) sim.skip_empty_nodes = f->boolean();
    if (auto f = t.get("prefetch_grid")) sim.prefetch_grid = f->boolean();
    if (auto f = t.get("prefetch_particles")) sim.prefetch_particles = f->boolean();
    if (auto f = t.get("particle_order")) sim.particle_order = f->choice(kParticleOrderNames);
    if (auto f = t.get("mm_fields_share")) {
      sim.mm_fields_share = f->number();
      if (sim.mm_fields_share < 0 || sim.mm_fields_share > 1)
        f->fail("expected a number in [0, 1], got " + format_number(sim.mm_fields_share));
    }
    if (auto f = t.get("name")) {
      scene_.name = scene_name_value(*f);
    } else if (!valid_utf8(default_name_)) {
      // The name goes into summary.json and run.h5, which hold UTF-8 text:
      // a file name with other bytes failed the run's last write, after
      // the whole simulation.
      const Where w = t.where();
      throw InputError(located(w.file, w.line, "simulation.name",
                               "the scene's name defaults to the file name, which is not valid "
                               "UTF-8; rename the file or set simulation.name"));
    } else {
      scene_.name = default_name_;
    }
  }

  // Well-formed UTF-8 (the Unicode standard's table 3-7: no overlong forms,
  // no surrogates, nothing above U+10FFFF), as the JSON writer checks it.
  static bool valid_utf8(std::string_view s) {
    auto byte = [&](std::size_t i) { return i < s.size() ? static_cast<unsigned char>(s[i]) : 0u; };
    auto in = [](unsigned b, unsigned lo, unsigned hi) { return b >= lo && b <= hi; };
    for (std::size_t i = 0; i < s.size();) {
      const unsigned c = byte(i);
      std::size_t n = 0;
      unsigned lo = 0x80, hi = 0xBF;  // the range of the second byte
      if (c < 0x80)
        n = 1;
      else if (in(c, 0xC2, 0xDF))
        n = 2;
      else if (in(c, 0xE0, 0xEF))
        n = 3, lo = c == 0xE0 ? 0xA0 : 0x80, hi = c == 0xED ? 0x9F : 0xBF;
      else if (in(c, 0xF0, 0xF4))
        n = 4, lo = c == 0xF0 ? 0x90 : 0x80, hi = c == 0xF4 ? 0x8F : 0xBF;
      else
        return false;
      if (n > 1 && !in(byte(i + 1), lo, hi)) return false;
      for (std::size_t k = 2; k < n; ++k)
        if (!in(byte(i + k), 0x80, 0xBF)) return false;
      i += n;
    }
    return true;
  }

  // The scene name becomes a directory name under results/.
  static std::string scene_name_value(const Field& f) {
    const std::string s = f.name();
    if (s == "." || s == ".." || s.find_first_of("/\\") != std::string::npos) {
      f.fail("expected a name usable as a directory name (no '/' or '\\'), got " + quote(s));
    }
    return s;
  }

  // --------------------------------------------------------------- [grid]
  void read_grid(const Table& t) {
    t.only({"origin", "cell", "cells", "shape", "damping", "tile"});
    GridSpec& g = scene_.grid;
    g.origin = t.need("origin").vec(dim());
    const Field cell = t.need("cell");
    g.cell = cell.vec(dim(), {1, 1, 1});
    for (int k = 0; k < dim(); ++k) {
      if (!(g.cell[static_cast<std::size_t>(k)] > 0)) {
        cell.fail("expected every cell size > 0, got " + format_vector(g.cell, dim()));
      }
    }
    read_cells(t.need("cells"));
    check_grid_memory(t.need("cells"));
    if (auto f = t.get("shape")) g.shape = f->choice(kShapeKindNames);
    if (auto f = t.get("damping")) g.damping = f->non_negative();
    if (auto f = t.get("tile")) {
      // The edge is rounded up to a power of two and a tile's cells are
      // counted in 32-bit keys (kernels/binning.hpp); per-tile buffers grow
      // with the edge^dim cells. 1024 (2D) and 128 (3D) are 32-64 times the
      // defaults and hold 2^20-2^21 cells per tile.
      const int most = dim() == 2 ? 1024 : 128;
      g.tile = f->int_at_least(0);
      if (g.tile > most)
        f->fail("expected an integer from 0 (automatic) to " + std::to_string(most) +
                " (cells per tile edge), got " + std::to_string(g.tile));
    }
  }

  // Sizes a run could never allocate are bad input, said before anything
  // is allocated: a grid of 10^8 x 10^8 cells ended in std::bad_alloc
  // (exit 3), and a body with 10^5 particles per cell and direction in a
  // seeding loop that did not end. The bytes per node and per particle are
  // a little below the peak that `mmpm check` measured (its resident memory
  // at two particle counts, 2026-11-29: 2D 310 B per particle in double,
  // 242 in float, 124 per node and material field in double; 3D 338, 273
  // and 176), one field counted, so a run refused here could not have run.
  // They were the arrays' bare sizes before (12 or 17 reals per particle),
  // which let a scene of 24 GB pass and be killed by the kernel.
  double real_bytes() const {
    return scene_.simulation.precision == Precision::float64 ? 8.0 : 4.0;
  }
  double grid_nodes() const {
    double nodes = 1;
    for (int k = 0; k < dim(); ++k) nodes *= double(scene_.grid.cells[std::size_t(k)]) + 1;
    return nodes;
  }
  double grid_bytes() const { return grid_nodes() * (dim() == 2 ? 15 : 21) * real_bytes(); }
  double particle_bytes() const {
    const bool dbl = scene_.simulation.precision == Precision::float64;
    return dim() == 2 ? (dbl ? 300 : 230) : (dbl ? 330 : 265);
  }
  void check_grid_memory(const Field& f) const {
    const double need = grid_bytes(), have = usable_memory();
    if (have > 0 && need > have)
      f.fail("the grid has " + number_text(grid_nodes()) + " nodes, at least " + gib_text(need) +
             " for its arrays, more than the memory this process may use (" + gib_text(have) +
             "); expected fewer or larger cells");
  }
  void check_particle_memory(const Table& t, const BodySpec& b, const Bounds& clipped) {
    double cell = 1;
    for (int k = 0; k < dim(); ++k) cell *= scene_.grid.cell[std::size_t(k)];
    particles_estimate_ +=
        body_measure(b, dim(), clipped) / cell * std::pow(double(b.particles_per_cell), dim());
    const double need = particles_estimate_ * particle_bytes() + grid_bytes(),
                 have = usable_memory();
    if (have > 0 && need > have) {
      const auto f = t.get("particles_per_cell");
      const std::string why = "the bodies up to this one hold about " +
                              number_text(particles_estimate_) +
                              " particles, with the grid at least " + gib_text(need) +
                              ", more than the memory this process may use (" + gib_text(have) +
                              "); expected fewer particles per cell or smaller bodies";
      if (f) f->fail(why);
      t.need("shape").fail(why);
    }
  }
  static std::string number_text(double x) {
    std::ostringstream os;
    os.precision(3);
    os << x;
    return os.str();
  }
  static std::string gib_text(double bytes) {
    return number_text(bytes / double(1ull << 30)) + " GiB";
  }

  void read_cells(const Field& f) {
    const std::string expected =
        "an array of " + std::to_string(dim()) + " integers >= 1 (cells per direction)";
    const std::vector<Field> items = f.elements(expected);
    if (items.size() != static_cast<std::size_t>(dim())) {
      f.fail("expected " + expected + ", got an array of " + std::to_string(items.size()));
    }
    for (std::size_t k = 0; k < items.size(); ++k) {
      const toml::value& e = items[k].raw();
      if (!e.is_integer())
        f.fail("expected " + expected + "; element [" + std::to_string(k) + "] is " + type_name(e));
      if (e.as_integer() < 1 || e.as_integer() > INT_MAX) {
        f.fail("expected " + expected + "; element [" + std::to_string(k) + "] is " +
               Field::integer_text(e.as_integer()));
      }
      scene_.grid.cells[k] = static_cast<int>(e.as_integer());
    }
  }

  // ---------------------------------------------------------- [[material]]
  static Keys material_keys(MaterialType type) {
    Keys keys{"name", "type", "density"};
    switch (type) {
      case MaterialType::isotropic:
      case MaterialType::neohookean:
        keys.insert(keys.end(), {"E", "nu"});
        break;
      case MaterialType::transverse:
        keys.insert(keys.end(), {"EA", "ET", "GA", "nuA", "nuT", "axis"});
        break;
      case MaterialType::rigid:
        keys.push_back("velocity");
        break;
    }
    return keys;
  }

  void add_material(const Table& t) {
    MaterialSpec m;
    m.where = t.where();
    const Field name = t.need("name");
    m.name = name.name();
    const Field type = t.need("type");
    m.type = type.choice(kMaterialTypeNames);
    // Checked here, not only where the model is built (model/material.cpp),
    // so the message names this key as written (a --set one included).
    if (m.type == MaterialType::neohookean && dim() == 2 &&
        scene_.simulation.plane == Plane::stress)
      type.fail(
          "a neohookean material needs plane = \"strain\" or 3D ([simulation] plane is "
          "\"stress\")");
    t.only(material_keys(m.type), a_quoted(scene_name(m.type)) + " material");
    if (const MaterialSpec* other = find_material(m.name)) {
      name.fail("duplicate material name " + quote(m.name) + " (first defined at line " +
                std::to_string(other->where.line) + ")");
    }
    m.density = t.need("density").modulus_like();
    const std::string why = a_quoted(scene_name(m.type)) + " material needs it";
    switch (m.type) {
      case MaterialType::isotropic:
      case MaterialType::neohookean:
        read_isotropic(t, m, why);
        break;
      case MaterialType::transverse:
        read_transverse(t, m, why);
        break;
      case MaterialType::rigid:
        m.velocity = VelocityTable{{0.0}, {Vec3{0, 0, 0}}};
        if (auto f = t.get("velocity")) m.velocity = rigid_velocity(*f);
        break;
    }
    scene_.materials.push_back(std::move(m));
  }

  static void read_isotropic(const Table& t, MaterialSpec& m, const std::string& why) {
    m.E = t.need("E", why).modulus_like();
    const Field nu = t.need("nu", why);
    m.nu = nu.number();
    // nu -> 0.5 makes the bulk modulus infinite; nu <= -1 makes it negative.
    if (!(m.nu > -1.0 && m.nu < 0.5)) {
      nu.fail("expected a Poisson's ratio with -1 < nu < 0.5, got " + format_number(m.nu));
    }
  }

  void read_transverse(const Table& t, MaterialSpec& m, const std::string& why) const {
    m.EA = t.need("EA", why).modulus_like();
    m.ET = t.need("ET", why).modulus_like();
    m.GA = t.need("GA", why).modulus_like();
    const Field nuA = t.need("nuA", why);
    const Field nuT = t.need("nuT", why);
    m.nuA = nuA.number();
    m.nuT = nuT.number();
    // Compliance with A as axis 1: the normal block [[1/EA, -nuA/EA, -nuA/EA],
    // [., 1/ET, -nuT/ET], [., ., 1/ET]] has eigenvalue (1+nuT)/ET on (0,1,-1)
    // and a 2x2 rest; all positive <=> the two conditions below (the shear
    // terms 1/GA and 2(1+nuT)/ET are then positive too).
    if (!(m.nuT > -1.0 && m.nuT < 1.0)) {
      nuT.fail("expected -1 < nuT < 1 for a positive-definite transverse compliance, got " +
               format_number(m.nuT));
    }
    const double limit = (1.0 - m.nuT) * m.EA / (2.0 * m.ET);
    if (!(m.nuA * m.nuA < limit)) {
      nuA.fail(
          "the transverse compliance is not positive definite: need nuA^2 < (1 - nuT) EA / (2 ET) "
          "= " +
          format_number(limit) + ", got nuA = " + format_number(m.nuA));
    }
    if (auto f = t.get("axis")) m.axis = normalized(*f, f->vec(dim()));
  }

  // Either a constant [vx, vy(, vz)] or { time = [...], velocity = [[...], ...] }.
  VelocityTable rigid_velocity(const Field& f) const {
    if (f.raw().is_array()) return VelocityTable{{0.0}, {f.vec(dim())}};
    if (!f.raw().is_table()) {
      f.wrong_type("an array of " + std::to_string(dim()) +
                   " numbers or a table { time = [...], velocity = [[...], ...] }");
    }
    const Table t = f.table();
    t.only({"time", "velocity"}, "a velocity table");
    const Field time = t.need("time");
    const Field rows = t.need("velocity");
    VelocityTable out;
    for (const Field& e : time.elements("an array of times")) out.time.push_back(e.number());
    if (out.time.empty()) time.fail("expected at least one time");
    for (std::size_t i = 1; i < out.time.size(); ++i) {
      if (!(out.time[i] > out.time[i - 1])) time.fail("expected strictly increasing times");
    }
    for (const Field& e : rows.elements("an array of velocities, one per time"))
      out.velocity.push_back(e.vec(dim()));
    if (out.velocity.size() != out.time.size()) {
      rows.fail("expected one velocity per time (" + std::to_string(out.time.size()) + "), got " +
                std::to_string(out.velocity.size()));
    }
    return out;
  }

  // -------------------------------------------------------------- [[body]]
  static Keys body_keys(BodyShape shape) {
    Keys keys{"name",  "material",           "shape",    "rotate",
              "pivot", "particles_per_cell", "velocity", "clip"};
    switch (shape) {
      case BodyShape::box:
        keys.insert(keys.end(), {"min", "max"});
        break;
      case BodyShape::disk:
      case BodyShape::sphere:
        keys.insert(keys.end(), {"center", "radius"});
        break;
      case BodyShape::cylinder:
        keys.insert(keys.end(), {"center", "radius", "length", "axis"});
        break;
      case BodyShape::polygon:
        keys.push_back("points");
        break;
    }
    return keys;
  }

  void add_body(const Table& t, std::size_t index) {
    BodySpec b;
    b.where = t.where();
    const Field shape = t.need("shape");
    b.shape = shape.choice(kBodyShapeNames);
    check_shape_dimension(shape, b.shape);
    t.only(body_keys(b.shape), a_quoted(scene_name(b.shape)) + " body");
    b.name = "body" + std::to_string(index);
    if (auto f = t.get("name")) {
      b.name = f->name();
      if (const BodySpec* other = find_body(b.name)) {
        f->fail("duplicate body name " + quote(b.name) + " (first defined at line " +
                std::to_string(other->where.line) + ")");
      }
    }
    const MaterialSpec& material = known_material(t.need("material"));
    b.material = material.name;
    read_geometry(t, b);
    if (auto f = t.get("rotate")) {
      if (dim() == 3) f->fail("only for dimension = 2 (rotation about z of a 2D body)");
      b.rotate = f->number();
      // Beyond a turn the angle adds nothing, and far beyond it (1e308) the
      // degrees-to-radians product loses every digit of the angle.
      if (std::abs(b.rotate) > 360.0)
        f->fail("expected degrees from -360 to 360, got " + format_number(b.rotate));
    }
    if (auto f = t.get("pivot")) {
      if (dim() == 3) f->fail("only for dimension = 2 (the centre of `rotate`)");
      b.pivot = f->vec(2);
    }
    if (auto f = t.get("particles_per_cell")) b.particles_per_cell = f->int_at_least(1);
    if (auto f = t.get("velocity")) {
      b.velocity = f->vec(dim());
      if (material.type == MaterialType::rigid && b.velocity != Vec3{0, 0, 0}) {
        f->fail("a body of rigid material " + quote(material.name) +
                " moves with the material's velocity; give it there");
      }
    }
    if (auto f = t.get("clip")) b.clip = read_box(f->table(), "clip box");
    check_inside_grid(t, b);
    check_particle_memory(t, b, *body_bounds(b, dim()));
    body_index_.emplace(b.name, scene_.bodies.size());
    scene_.bodies.push_back(std::move(b));
  }

  void check_shape_dimension(const Field& f, BodyShape shape) const {
    const bool two_d_only = shape == BodyShape::disk || shape == BodyShape::polygon;
    const bool three_d_only = shape == BodyShape::sphere || shape == BodyShape::cylinder;
    if (two_d_only && dim() != 2) {
      f.fail(quote(scene_name(shape)) +
             " is a 2D shape; in 3D use \"box\", \"sphere\" or \"cylinder\"");
    }
    if (three_d_only && dim() != 3) {
      f.fail(quote(scene_name(shape)) +
             " is a 3D shape; in 2D use \"box\", \"disk\" or \"polygon\"");
    }
  }

  void read_geometry(const Table& t, BodySpec& b) const {
    const std::string why = a_quoted(scene_name(b.shape)) + " body needs it";
    switch (b.shape) {
      case BodyShape::box: {
        const auto box = read_box(t, "box", why);
        b.min = box.first;
        b.max = box.second;
        break;
      }
      case BodyShape::cylinder:
        b.length = t.need("length", why).positive();
        if (auto f = t.get("axis")) b.axis = normalized(*f, f->vec(3));
        [[fallthrough]];
      case BodyShape::disk:
      case BodyShape::sphere:
        b.center = t.need("center", why).vec(dim());
        b.radius = t.need("radius", why).positive();
        break;
      case BodyShape::polygon:
        b.points = read_polygon(t.need("points", why));
        break;
    }
  }

  // { min = [...], max = [...] } with max > min in every direction.
  std::pair<Vec3, Vec3> read_box(const Table& t, const std::string& what,
                                 const std::string& why = "") const {
    if (what != "box") t.only({"min", "max"}, "a " + what);
    const Vec3 lo = t.need("min", why).vec(dim());
    const Field max = t.need("max", why);
    const Vec3 hi = max.vec(dim());
    for (std::size_t k = 0; k < static_cast<std::size_t>(dim()); ++k) {
      if (!(hi[k] > lo[k])) {
        max.fail("expected max > min in every direction, got min " + format_vector(lo, dim()) +
                 " and max " + format_vector(hi, dim()));
      }
    }
    return {lo, hi};
  }

  std::vector<Vec3> read_polygon(const Field& f) const {
    std::vector<Vec3> pts;
    for (const Field& e : f.elements("an array of [x, y] points")) pts.push_back(e.vec(2));
    if (pts.size() < 3) f.fail("expected at least 3 points, got " + std::to_string(pts.size()));
    if (polygon_twice_area(pts) == 0.0)
      f.fail(
          "expected a polygon enclosing some area (the points are collinear, or the outline "
          "crosses itself so that its parts' areas cancel)");
    return pts;
  }

  // Particles need every node their shape function touches, so the filled
  // region must keep `margin_cells` cells from the grid edge.
  void check_inside_grid(const Table& t, const BodySpec& b) const {
    const auto box = body_bounds(b, dim());
    if (!box) t.need("clip").fail("the clip box does not overlap the body");
    const GridSpec& g = scene_.grid;
    const int margin = margin_cells(g.shape);
    Bounds whole, usable;
    for (std::size_t k = 0; k < static_cast<std::size_t>(dim()); ++k) {
      whole.lo[k] = g.origin[k];
      whole.hi[k] = g.origin[k] + g.cells[k] * g.cell[k];
      usable.lo[k] = whole.lo[k] + margin * g.cell[k];
      usable.hi[k] = whole.hi[k] - margin * g.cell[k];
    }
    const std::string body = "body " + quote(b.name) + " spans " + bounds_text(*box, dim());
    if (const Side side = crossing(*box, whole); side != Side::none) {
      t.need(blame_key(b, side, usable))
          .fail(body + ", outside the grid " + bounds_text(whole, dim()));
    }
    if (const Side side = crossing(*box, usable); side != Side::none) {
      const std::string cells = std::to_string(margin) + (margin == 1 ? " cell" : " cells");
      t.need(blame_key(b, side, usable))
          .fail(body + ", closer than " + cells +
                " to the grid edge: " + quote(scene_name(g.shape)) + " shape functions need " +
                cells + " of nodes around every particle (usable region " +
                bounds_text(usable, dim()) + ")");
    }
  }

  enum class Side { none, low, high };

  // Whether `box` leaves `region`, and on which side first.
  Side crossing(const Bounds& box, const Bounds& region) const {
    for (std::size_t k = 0; k < static_cast<std::size_t>(dim()); ++k) {
      const double tol = kNodeTolerance * scene_.grid.cell[k];
      if (box.lo[k] < region.lo[k] - tol) return Side::low;
      if (box.hi[k] > region.hi[k] + tol) return Side::high;
    }
    return Side::none;
  }

  // The key a user would edit: `rotate` when only the rotation takes the body
  // out, else the geometry key on the offending side.
  std::string blame_key(const BodySpec& b, Side side, const Bounds& usable) const {
    if (b.rotate != 0.0 && b.shape != BodyShape::disk) {
      BodySpec upright = b;
      upright.rotate = 0.0;
      const auto box = body_bounds(upright, dim());
      if (box && crossing(*box, usable) == Side::none) return "rotate";
    }
    switch (b.shape) {
      case BodyShape::box:
        return side == Side::low ? "min" : "max";
      case BodyShape::polygon:
        return "points";
      default:
        return "center";
    }
  }

  // In float, the products of the constants must stay normal numbers too:
  // each constant within [1e-30, 1e30] (modulus_like) still let density,
  // cell and thickness multiply into a particle mass of 1e58, which
  // overflowed at the first step and was reported as an instability. The
  // scales the kernels hold per particle (mass, momentum, stress times
  // volume, the force it spreads over 1/h) must lie in [1e-30, 1e30]:
  // float's normal range (1.2e-38 to 3.4e38) with 1e8 to spare for the
  // weights, dt and the sums over a node's particles.
  void check_float_range() const {
    const double h = *std::min_element(scene_.grid.cell.begin(), scene_.grid.cell.begin() + dim());
    double cell_volume = dim() == 2 ? scene_.simulation.thickness : 1.0;
    for (int d = 0; d < dim(); ++d) cell_volume *= scene_.grid.cell[std::size_t(d)];
    for (const BodySpec& b : scene_.bodies) {
      const MaterialSpec& m = *find_material(b.material);
      const double volume = cell_volume / std::pow(double(b.particles_per_cell), dim());
      const double mass = m.density * volume;
      const double modulus = std::max({m.E, m.EA, m.ET, m.GA});
      double speed = 0;
      for (int d = 0; d < dim(); ++d) speed = std::max(speed, std::abs(b.velocity[std::size_t(d)]));
      const std::pair<const char*, double> scales[] = {
          {"particle volume (cell volume / particles per cell)", volume},
          {"particle mass (density x particle volume)", mass},
          {"particle momentum (mass x velocity)", mass * speed},
          {"stress x volume (modulus x particle volume)", modulus * volume},
          {"nodal force (modulus x particle volume / cell size)", modulus * volume / h}};
      for (const auto& [what, x] : scales) {
        if (x == 0 || (x >= 1e-30 && x <= 1e30)) continue;
        const Where& w = precision_where_;
        throw InputError(located(
            w.file.empty() ? src_.label() : w.file, w.line,
            w.key.empty() ? "simulation.precision" : w.key,
            "precision = \"float\": body " + quote(b.name) + "'s " + what + " is " +
                format_number(x) +
                ", outside [1e-30, 1e30], the range float holds with room for the kernels' "
                "products and sums (its normal numbers: 1.2e-38 to 3.4e38); use precision = "
                "\"double\", or units that bring it inside"));
      }
    }
  }

  // ------------------------------------------------------- [[interaction]]
  void add_interaction(const Table& t) {
    t.only({"materials", "law", "friction", "Dn", "Dt", "traction_law", "Dn_compression", "normal",
            "normal_vector", "center", "axis", "separation", "contact_offset", "min_volume",
            "force_limit", "integration", "area"});
    InteractionSpec in;
    in.where = t.where();
    const Field mats = t.need("materials");
    const auto pair = interaction_pair(mats);
    in.materials = {pair.first->name, pair.second->name};
    if (auto f = t.get("law")) in.law = f->choice(kLawNames);
    // No default coefficient: a Coulomb law left at 0 would be the
    // frictionless one under another name.
    if (auto f = in.law == Law::friction
                     ? std::optional(t.need("friction", "law = \"friction\" needs its coefficient"))
                     : t.get("friction"))
      in.friction = f->non_negative();
    const bool interface = in.law == Law::interface;
    const std::string why = "law = \"interface\" needs Dn and Dt";
    if (auto f = interface ? std::optional(t.need("Dn", why)) : t.get("Dn")) in.Dn = stiffness(*f);
    if (auto f = interface ? std::optional(t.need("Dt", why)) : t.get("Dt")) in.Dt = stiffness(*f);
    if (auto f = t.get("traction_law")) in.traction_law = f->choice(kTractionLawNames);
    if (auto f = t.get("Dn_compression")) in.Dn_compression = stiffness(*f);
    read_normal(t, in, *pair.first, *pair.second);
    const auto separation = t.get("separation");
    if (separation) in.separation = separation->choice(kSeparationNames);
    // One method per scene (mx holds one kind of data, solver/field_plan.cpp),
    // checked here so the message names this interaction's key as written.
    for (std::size_t k = 0; separation && k < scene_.interactions.size(); ++k) {
      const InteractionSpec& other = scene_.interactions[k];
      if (!separation_named_[k] || other.separation == in.separation) continue;
      separation->fail(
          "every interaction of a scene must use the same separation method; interaction[" +
          std::to_string(k) + "]" +
          (other.where.line > 0 ? " (line " + std::to_string(other.where.line) + ")" : "") +
          " names " + quote(scene_name(other.separation)) + ", this one " +
          quote(scene_name(in.separation)));
    }
    separation_named_.push_back(separation.has_value());
    if (auto f = t.get("contact_offset")) {
      if (in.separation != Separation::position)
        f->fail("contact_offset applies to separation = \"position\" only");
      in.contact_offset = f->number();
      if (!(in.contact_offset > 0 && in.contact_offset <= 2)) {
        f->fail("expected a fraction of the cell size in (0, 2], got " +
                format_number(in.contact_offset));
      }
    }
    if (auto f = t.get("min_volume")) {
      in.min_volume = f->number();
      if (in.min_volume < 0 || in.min_volume >= 1) {
        f->fail("expected a fraction of the cell volume in [0, 1), got " +
                format_number(in.min_volume));
      }
    }
    if (auto f = t.get("force_limit")) in.force_limit = f->boolean();
    if (auto f = t.get("integration")) in.integration = f->choice(kIntegrationNames);
    // (P-20) counts every row of interface nodes in full, and the B-splines put
    // an interface in two or three rows: their default reads the interface's
    // share of each node from the domain gradients (docs/multimaterial.md §7.2).
    const ShapeKind shape = scene_.grid.shape;
    if (shape == ShapeKind::bspline2 || shape == ShapeKind::bspline3)
      in.area = ContactArea::gradient;
    if (auto f = t.get("area")) {
      if (!interface)
        f->fail("area applies to law = \"interface\" only (the contact area of P-20)");
      in.area = f->choice(kContactAreaNames);
    }
    scene_.interactions.push_back(std::move(in));
  }

  // Two different, defined materials not yet paired by an earlier interaction.
  std::pair<const MaterialSpec*, const MaterialSpec*> interaction_pair(const Field& f) const {
    const std::vector<Field> names = f.elements("an array of two material names");
    if (names.size() != 2)
      f.fail("expected an array of two material names, got " + std::to_string(names.size()));
    const MaterialSpec& a = known_material(names[0]);
    const MaterialSpec& b = known_material(names[1]);
    if (a.name == b.name)
      f.fail("expected two different materials, got " + quote(a.name) + " twice");
    if (a.type == MaterialType::rigid && b.type == MaterialType::rigid) {
      f.fail("both materials are rigid; an interaction needs at least one deformable material");
    }
    for (const InteractionSpec& other : scene_.interactions) {
      const std::set<std::string> seen{other.materials[0], other.materials[1]};
      if (seen == std::set<std::string>{a.name, b.name}) {
        f.fail("the pair " + quote(a.name) + ", " + quote(b.name) +
               " already has an interaction (line " + std::to_string(other.where.line) + ")");
      }
    }
    return {&a, &b};
  }

  // MPa/mm >= 0, or "perfect" (infinitely stiff: that direction sticks).
  static double stiffness(const Field& f) {
    const toml::value& v = f.raw();
    const std::string expected = "a number >= 0 (MPa/mm) or \"perfect\"";
    if (v.is_string()) {
      if (v.as_string().str == "perfect") return std::numeric_limits<double>::infinity();
      f.fail("expected " + expected + ", got " + quote(v.as_string().str));
    }
    if (!v.is_integer() && !v.is_floating()) f.wrong_type(expected);
    if (v.is_floating() && std::isinf(v.as_floating()) && v.as_floating() > 0) {
      return std::numeric_limits<double>::infinity();
    }
    const double x = f.number();
    if (x < 0) f.fail("expected " + expected + ", got " + format_number(x));
    return x;
  }

  void read_normal(const Table& t, InteractionSpec& in, const MaterialSpec& a,
                   const MaterialSpec& b) const {
    const auto method = t.get("normal");
    if (method) in.normal = method->choice(kNormalMethodNames);
    const bool specified = in.normal == NormalMethod::specified;
    const bool radial = in.normal == NormalMethod::radial;
    if (auto f = specified
                     ? std::optional(t.need("normal_vector", "normal = \"specified\" needs it"))
                     : t.get("normal_vector")) {
      in.normal_vector = normalized(*f, f->vec(dim()));
    }
    if (auto f = radial ? std::optional(t.need("center", "normal = \"radial\" needs it"))
                        : t.get("center")) {
      in.center = f->vec(dim());
    }
    // A cylindrical inclusion in 3D (a fibre): the radial normal about the
    // line through `center` along `axis`, n ∝ (x − c) − ((x − c)·a) a.
    if (auto f = t.get("axis")) {
      if (!radial) f->fail("axis applies to normal = \"radial\" only");
      if (dim() != 3)
        f->fail(
            "axis applies in 3D only (in 2D the radial normal is already about the out-of-plane "
            "axis through center)");
      in.radial_axis = normalized(*f, f->vec(3));
    }
    if (in.normal == NormalMethod::rigid && a.type != MaterialType::rigid &&
        b.type != MaterialType::rigid) {
      method->fail("normal = \"rigid\" needs one of the two materials to be rigid; " +
                   quote(a.name) + " and " + quote(b.name) + " are not");
    }
  }

  // ---------------------------------------------------------- [[boundary]]
  void add_boundary(const Table& t, std::size_t index) {
    t.only({"where", "fix", "displacement", "ramp"});
    BoundarySpec bc;
    bc.where = t.where();
    read_boundary_where(t.need("where"), bc, index);
    read_fix(t.need("fix"), bc);
    if (auto f = t.get("ramp")) bc.ramp = f->non_negative();
    if (auto f = t.get("displacement")) {
      bc.has_displacement = true;
      bc.displacement = f->vec(dim());
      bool moves = false;
      for (std::size_t k = 0; k < static_cast<std::size_t>(dim()); ++k) {
        if (bc.displacement[k] == 0.0) continue;
        if (!bc.fix[k]) {
          f->fail("expected 0 for the free component " + std::string(1, "xyz"[k]) +
                  " (only fixed components are prescribed)");
        }
        moves = true;
      }
      // The nodes move at displacement / ramp; a zero ramp would be an infinite velocity.
      if (moves && bc.ramp == 0.0) {
        (t.get("ramp") ? *t.get("ramp") : *f)
            .fail("a non-zero displacement needs ramp > 0 (the time to reach it)");
      }
    }
    // Each boundary reports its reaction in series columns named after its
    // label; a second boundary on the same face (another component fixed)
    // gets "_2", "_3", ... so the columns stay distinct.
    const std::string label = bc.label;
    for (int k = 2; labelled(bc.label); ++k) bc.label = label + "_" + std::to_string(k);
    scene_.boundaries.push_back(std::move(bc));
  }
  bool labelled(const std::string& label) const {
    return std::any_of(scene_.boundaries.begin(), scene_.boundaries.end(),
                       [&](const BoundarySpec& b) { return b.label == label; });
  }

  void read_boundary_where(const Field& f, BoundarySpec& bc, std::size_t index) const {
    const std::string expected = "a grid face (" + word_list(face_names(dim()), true) +
                                 "), a plane { x = ... } or a box { min = [...], max = [...] }";
    if (f.raw().is_string()) {
      const std::string s = f.string();
      const auto face = parse_face(s, dim());
      if (!face) f.fail("expected " + expected + ", got " + quote(s));
      bc.kind = BoundaryWhere::face;
      bc.face_axis = face->first;
      bc.face_max = face->second;
      bc.label = s;
      return;
    }
    if (!f.raw().is_table()) f.wrong_type(expected);
    const Table t = f.table();
    if (t.has("min") || t.has("max")) {
      const auto box = read_box(t, "boundary box");
      bc.kind = BoundaryWhere::box;
      bc.box_min = box.first;
      bc.box_max = box.second;
      check_box_has_nodes(f, bc);
      bc.label = "box" + std::to_string(index);
    } else {
      read_plane(t, bc);
    }
  }

  void read_plane(const Table& t, BoundarySpec& bc) const {
    const Keys axes = axis_names(dim());
    t.only(axes, "a boundary plane");
    std::optional<Field> coord;
    for (std::size_t k = 0; k < axes.size(); ++k) {
      if (auto f = t.get(axes[k])) {
        if (coord)
          t.as_field().fail("expected exactly one coordinate in a plane, e.g. { x = 1.0 }");
        coord = f;
        bc.plane_axis = static_cast<int>(k);
      }
    }
    if (!coord) t.as_field().fail("expected exactly one coordinate in a plane, e.g. { x = 1.0 }");
    bc.kind = BoundaryWhere::plane;
    bc.plane_value = coord->number();
    const auto k = static_cast<std::size_t>(bc.plane_axis);
    const GridSpec& g = scene_.grid;
    const double i = (bc.plane_value - g.origin[k]) / g.cell[k];
    const double nearest = std::round(i);
    if (std::abs(i - nearest) > 1e-6 || nearest < 0 || nearest > g.cells[k]) {
      coord->fail("expected a coordinate on a grid node line (origin + i * cell, i = 0.." +
                  std::to_string(g.cells[k]) + "), got " + format_number(bc.plane_value));
    }
    bc.label = "plane_" + std::string(axes[k]) + "=" + format_number(bc.plane_value);
  }

  void check_box_has_nodes(const Field& f, const BoundarySpec& bc) const {
    const GridSpec& g = scene_.grid;
    for (std::size_t k = 0; k < static_cast<std::size_t>(dim()); ++k) {
      const double first =
          std::max(0.0, std::ceil((bc.box_min[k] - g.origin[k]) / g.cell[k] - 1e-6));
      const double last = std::min<double>(
          g.cells[k], std::floor((bc.box_max[k] - g.origin[k]) / g.cell[k] + 1e-6));
      if (first > last) f.fail("the box contains no grid node");
    }
  }

  void read_fix(const Field& f, BoundarySpec& bc) const {
    const Keys axes = axis_names(dim());
    const std::string expected = "an array of components from " + word_list(axes, true);
    const std::vector<Field> items = f.elements(expected);
    if (items.empty()) f.fail("expected " + expected + ", got an empty array");
    for (const Field& e : items) {
      if (!e.raw().is_string())
        f.fail("expected " + expected + "; an entry is " + type_name(e.raw()));
      const std::string c = e.raw().as_string().str;
      const auto it = std::find(axes.begin(), axes.end(), c);
      if (it == axes.end()) f.fail("expected " + expected + ", got " + quote(c));
      const auto k = static_cast<std::size_t>(it - axes.begin());
      if (bc.fix[k]) f.fail("component " + quote(c) + " is listed twice");
      bc.fix[k] = true;
    }
  }

  // -------------------------------------------------------------- [[load]]
  void add_load(const Table& t) {
    LoadSpec l;
    l.where = t.where();
    if (auto f = t.get("kind")) l.kind = f->choice(kLoadKindNames);
    if (l.kind == LoadKind::traction) {
      t.only({"kind", "where", "traction", "ramp"}, "a \"traction\" load");
      read_load_where(t.need("where").table(), l);
      l.traction = t.need("traction").vec(dim());
    } else {
      t.only({"kind", "acceleration", "ramp"}, "a \"gravity\" load");
      l.acceleration = t.need("acceleration").vec(dim());
    }
    if (auto f = t.get("ramp")) l.ramp = f->non_negative();
    scene_.loads.push_back(std::move(l));
  }

  void read_load_where(const Table& t, LoadSpec& l) const {
    t.only({"body", "face"}, "a traction's where");
    const Field body = t.need("body");
    l.body = body.name();
    const BodySpec* b = find_body(l.body);
    if (!b) body.fail("no [[body]] is named " + quote(l.body));
    if (find_material(b->material)->type == MaterialType::rigid) {
      body.fail("body " + quote(l.body) + " is rigid; tractions cannot move it");
    }
    const Field face = t.need("face");
    const std::string s = face.string();
    const auto parsed = parse_face(s, dim());
    if (!parsed)
      face.fail("expected a face of the body, one of " + word_list(face_names(dim()), true) +
                ", got " + quote(s));
    l.face_axis = parsed->first;
    l.face_max = parsed->second;
  }

  // ------------------------------------------------------ [output], [stop]
  void read_output(const Table& t) {
    t.only({"every", "fields", "grid_fields", "series", "checkpoint_minutes", "directory"});
    OutputSpec& o = scene_.output;
    if (auto f = t.get("every")) {
      o.every = f->non_negative();
      // The driver counts snapshot times k * every in a long; a ratio past
      // 1e12 is a typo, not a request (a snapshot per step needs only
      // every <= dt).
      if (o.every > 0 && scene_.simulation.end_time / o.every > 1e12)
        f->fail("expected 0 (the last state only) or at least end_time * 1e-12 = " +
                format_number(scene_.simulation.end_time * 1e-12) + ", got " +
                format_number(o.every) +
                " (every <= dt already writes every step; or is "
                "simulation.end_time = " +
                format_number(scene_.simulation.end_time) + " the typo?)");
    }
    if (auto f = t.get("fields")) {
      o.fields = output_fields(*f);
      // F is kept only for finite-strain materials (the H columns); said
      // here, where `check` sees it too, not when the first snapshot fails.
      const bool finite =
          std::any_of(scene_.materials.begin(), scene_.materials.end(),
                      [](const MaterialSpec& m) { return m.type == MaterialType::neohookean; });
      if (!finite &&
          std::find(o.fields.begin(), o.fields.end(), "deformation_gradient") != o.fields.end())
        f->fail(
            "field \"deformation_gradient\" needs a finite-strain (\"neohookean\") material; "
            "this scene has none (the small-strain types keep no F)");
    }
    if (auto f = t.get("grid_fields")) o.grid_fields = names_from(*f, kGridFieldNames);
    if (auto f = t.get("series")) o.series = f->int_at_least(1);
    if (auto f = t.get("checkpoint_minutes")) o.checkpoint_minutes = f->non_negative();
    o.directory = "results/" + scene_.name;
    if (auto f = t.get("directory")) {
      o.directory = f->name();
      o.directory_where = f->where();
    }
  }

  static std::vector<std::string> output_fields(const Field& f) {
    return names_from(f, kOutputFieldNames);
  }

  // An array of distinct names, each from `names`.
  template <std::size_t N>
  static std::vector<std::string> names_from(const Field& f,
                                             const std::array<std::string_view, N>& names) {
    const Keys allowed(names.begin(), names.end());
    const std::string expected = "an array of field names from " + word_list(allowed, true);
    std::vector<std::string> out;
    for (const Field& e : f.elements(expected)) {
      if (!e.raw().is_string())
        f.fail("expected " + expected + "; an entry is " + type_name(e.raw()));
      const std::string name = e.raw().as_string().str;
      if (std::find(allowed.begin(), allowed.end(), name) == allowed.end()) {
        f.fail("expected " + expected + ", got " + quote(name));
      }
      if (std::find(out.begin(), out.end(), name) != out.end())
        f.fail("field " + quote(name) + " is listed twice");
      out.push_back(name);
    }
    return out;
  }

  void read_stop(const Table& t) {
    t.only({"enabled", "kinetic_ratio", "hold_steps"});
    StopSpec& s = scene_.stop;
    s.enabled = true;
    if (auto f = t.get("enabled")) s.enabled = f->boolean();
    if (auto f = t.get("kinetic_ratio")) s.kinetic_ratio = f->positive();
    if (auto f = t.get("hold_steps")) s.hold_steps = f->int_at_least(1);
  }

  const Source& src_;
  std::string default_name_;
  Where precision_where_;          // simulation.precision as written (float range messages)
  double particles_estimate_ = 0;  // check_particle_memory, summed over the bodies
  std::unordered_map<std::string, std::size_t> body_index_;  // name -> scene_.bodies index
  const toml::value empty_ = toml::table{};
  Scene scene_;
  std::vector<bool> separation_named_;  // per interaction: its table names `separation`
};

// ------------------------------------------------------------- --set --

struct PathStep {
  std::string key;
  std::optional<std::size_t> index;
};

[[noreturn]] void override_fail(const std::string& key, const std::string& what) {
  throw InputError(located(std::string(kSetPrefix) + key, 0, key, what));
}

// "section.key", "section[i].key", deeper tables with more dots.
std::vector<PathStep> parse_override_path(const std::string& key) {
  const std::string expected = "expected a key path like grid.cell or interaction[0].Dt";
  std::vector<PathStep> steps;
  std::istringstream parts(key);
  std::string part;
  while (std::getline(parts, part, '.')) {
    PathStep step;
    const auto bracket = part.find('[');
    step.key = part.substr(0, bracket);
    const bool bare =
        !step.key.empty() && std::all_of(step.key.begin(), step.key.end(), [](char c) {
          return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-';
        });
    if (!bare) override_fail(key, expected);
    if (bracket != std::string::npos) {
      const std::string digits = part.substr(bracket + 1, part.size() - bracket - 2);
      const bool ok =
          part.back() == ']' && !digits.empty() &&
          std::all_of(digits.begin(), digits.end(), [](char c) { return c >= '0' && c <= '9'; });
      if (!ok || digits.size() > 9) override_fail(key, expected);
      step.index = std::stoul(digits);
    }
    steps.push_back(step);
  }
  if (steps.empty() || key.back() == '.') override_fail(key, expected);
  return steps;
}

// toml11 parses nested arrays and inline tables by recursion: 20 000 levels
// overflowed the stack (a crash, not a message). No scene nests deeper than
// a few levels, so deeper input is refused before toml11 sees it. Returns
// the line where the nesting first passes kDeepestNesting, or 0. Strings
// and comments are skipped; malformed ones are left to toml11's message.
constexpr int kDeepestNesting = 64;
int line_nested_too_deep(const std::string& text) {
  int depth = 0, line = 1;
  const std::size_t n = text.size();
  for (std::size_t i = 0; i < n; ++i) {
    const char c = text[i];
    if (c == '\n') {
      ++line;
    } else if (c == '#') {
      while (i + 1 < n && text[i + 1] != '\n') ++i;
    } else if (c == '"' || c == '\'') {
      const std::string triple(3, c);
      const bool multiline = text.compare(i, 3, triple) == 0;
      i += multiline ? 3 : 1;
      while (i < n && (multiline ? text.compare(i, 3, triple) != 0 : text[i] != c)) {
        if (text[i] == '\n') {
          if (!multiline) break;
          ++line;
        }
        if (c == '"' && text[i] == '\\' && i + 1 < n && text[i + 1] != '\n') ++i;
        ++i;
      }
      if (multiline) i += 2;
      if (i < n && text[i] == '\n') ++line;
    } else if (c == '[' || c == '{') {
      if (++depth > kDeepestNesting) return line;
    } else if ((c == ']' || c == '}') && depth > 0) {
      --depth;
    }
  }
  return 0;
}
const std::string kNestingLimit =
    "arrays and inline tables nested at most " + std::to_string(kDeepestNesting) + " levels deep";

// Parses VALUE as the right-hand side of a TOML key; the value remembers
// "--set KEY" as its file, which is how later messages blame the override.
toml::value parse_override_value(const std::string& key, const std::string& text) {
  if (line_nested_too_deep(text) != 0) override_fail(key, "expected a value with " + kNestingLimit);
  std::istringstream in("v = " + text);
  toml::value doc;
  try {
    doc = toml::parse(in, std::string(kSetPrefix) + key);
  } catch (const toml::exception& e) {
    override_fail(
        key,
        "expected a TOML value (strings in quotes, arrays in brackets: --set 'KEY=\"text\"'): " +
            condense_toml_error(e.what()));
  }
  if (doc.as_table().size() != 1) override_fail(key, "expected a single TOML value");
  return doc.at("v");
}

// The table one step down `step`, creating a missing plain table (a valid
// key for a section absent from the file, e.g. [stop]).
toml::value& descend(toml::value& table, const PathStep& step, const std::string& key) {
  auto& entries = table.as_table();
  auto it = entries.find(step.key);
  if (it == entries.end()) {
    if (step.index) override_fail(key, "there is no [[" + step.key + "]] to index");
    entries[step.key] = parse_override_value(key, "{}");
    return entries[step.key];
  }
  toml::value& v = it->second;
  if (step.index) {
    if (!v.is_array())
      override_fail(key, quote(step.key) + " is not an array of tables; drop the [i]");
    auto& arr = v.as_array();
    if (*step.index >= arr.size()) {
      override_fail(
          key, "index " + std::to_string(*step.index) + " is out of range: there " +
                   (arr.size() == 1 ? "is 1 [[" : "are " + std::to_string(arr.size()) + " [[") +
                   step.key + "]] table" + (arr.size() == 1 ? "" : "s"));
    }
    if (!arr[*step.index].is_table())
      override_fail(key, quote(step.key) + " is not an array of tables");
    return arr[*step.index];
  }
  if (v.is_array()) {
    const auto& arr = v.as_array();
    if (!arr.empty() && arr.front().is_table())
      override_fail(key,
                    quote(step.key) + " is an array of tables; name one as " + step.key + "[i]");
    override_fail(key, quote(step.key) +
                           " is an array of values, not a table: set it whole, e.g. " + step.key +
                           "=[...]");
  }
  if (!v.is_table()) override_fail(key, quote(step.key) + " is not a table");
  return v;
}

void apply_override(toml::value& root, const std::string& spec) {
  const auto eq = spec.find('=');
  if (eq == std::string::npos) {
    throw InputError(located(std::string(kSetPrefix) + spec, 0, "",
                             "expected KEY=VALUE, e.g. --set grid.cell=[0.1,0.1]"));
  }
  const auto trim = [](std::string s) {
    const auto b = s.find_first_not_of(" \t");
    const auto e = s.find_last_not_of(" \t");
    return b == std::string::npos ? std::string() : s.substr(b, e - b + 1);
  };
  const std::string key = trim(spec.substr(0, eq));
  if (key.empty())
    throw InputError(located(std::string(kSetPrefix) + spec, 0, "", "expected KEY=VALUE"));
  const std::vector<PathStep> steps = parse_override_path(key);
  toml::value value = parse_override_value(key, spec.substr(eq + 1));
  toml::value* table = &root;
  for (std::size_t i = 0; i + 1 < steps.size(); ++i) table = &descend(*table, steps[i], key);
  const PathStep& last = steps.back();
  if (!last.index) {
    table->as_table()[last.key] = std::move(value);
    return;
  }
  auto& entries = table->as_table();
  const auto it = entries.find(last.key);
  if (it == entries.end() || !it->second.is_array())
    override_fail(key, quote(last.key) + " is not an array");
  auto& arr = it->second.as_array();
  if (*last.index >= arr.size()) {
    override_fail(key, "index " + std::to_string(*last.index) + " is out of range: " +
                           quote(last.key) + " has " + std::to_string(arr.size()) + " entries");
  }
  arr[*last.index] = std::move(value);
}

// toml11 3.7 takes time growing with the square of a line's length (an
// array of 2-number points on one line: 90 kB 0.5 s, 180 kB 2.0 s, 2 MB
// over a minute, while the same points one per line read in under a
// second), so a longer line is refused with the way round it.
constexpr std::size_t kLongestLine = 64 * 1024;
void check_line_lengths(const std::string& text, const std::string& label) {
  std::size_t start = 0;
  for (int line = 1; start <= text.size(); ++line) {
    std::size_t end = text.find('\n', start);
    if (end == std::string::npos) end = text.size();
    if (end - start > kLongestLine)
      throw InputError(located(label, line, "",
                               "line of " + std::to_string(end - start) +
                                   " characters; expected at most " + std::to_string(kLongestLine) +
                                   " (the TOML reader slows down with the square of a line's "
                                   "length): write a long array over several lines, e.g. one "
                                   "element per line"));
    start = end + 1;
  }
}

toml::value parse_toml(const std::string& text, const std::string& label) {
  check_line_lengths(text, label);
  if (const int line = line_nested_too_deep(text))
    throw InputError(located(label, line, "", "TOML nesting too deep: expected " + kNestingLimit));
  std::istringstream in(text);
  try {
    return toml::parse(in, label);
  } catch (const toml::exception& e) {
    throw InputError(located(label, static_cast<int>(e.location().line()), "",
                             "TOML syntax error: " + condense_toml_error(e.what())));
  } catch (const std::exception& e) {
    throw InputError(
        located(label, 0, "", std::string("TOML syntax error: ") + condense_toml_error(e.what())));
  }
}

std::string default_scene_name(const std::string& label) {
  const std::string stem = std::filesystem::path(label).stem().string();
  return stem.empty() ? "scene" : stem;
}

}  // namespace

Scene parse_scene_text(const std::string& text, const std::string& file_label,
                       const std::vector<std::string>& overrides) {
  toml::value root = parse_toml(text, file_label);
  for (const std::string& o : overrides) apply_override(root, o);
  const Source src(file_label);
  Scene scene = SceneReader(src, default_scene_name(file_label)).read(root);
  scene.source_file = file_label;
  scene.source_text = format_scene(scene);
  return scene;
}

// The largest scene file read: 16 MiB, ~400 000 polygon points written one
// per line (which toml11 reads at ~1 MB a second here).
constexpr std::uintmax_t kLargestSceneFile = 16u << 20;

Scene parse_scene_file(const std::string& path, const std::vector<std::string>& overrides) {
  // An ifstream opens a directory on Linux and reads it as empty, which
  // would be reported as a scene missing its keys.
  std::error_code ec;
  const std::filesystem::file_status status = std::filesystem::status(path, ec);
  if (std::filesystem::is_directory(status))
    throw InputError(located(path, 0, "", "is a directory; expected a scene file (TOML)"));
  // A device or a pipe would be read until it ends: /dev/zero filled the
  // memory, a FIFO with no writer waited for ever. (A missing file is left
  // to the open below.)
  if (std::filesystem::exists(status)) {
    if (!std::filesystem::is_regular_file(status))
      throw InputError(located(path, 0, "",
                               "is not a regular file (a device, pipe or socket); expected a "
                               "scene file (TOML)"));
    const std::uintmax_t bytes = std::filesystem::file_size(path, ec);
    if (!ec && bytes > kLargestSceneFile)
      throw InputError(located(path, 0, "",
                               "is " + std::to_string(bytes) +
                                   " bytes; expected a scene file of at most " +
                                   std::to_string(kLargestSceneFile) + " bytes"));
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(located(path, 0, "", "cannot open the scene file"));
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) throw InputError(located(path, 0, "", "cannot read the scene file"));
  return parse_scene_text(text.str(), path, overrides);
}

}  // namespace mmpm
