#include "scene/format.hpp"

#include <charconv>
#include <cmath>
#include <sstream>

namespace mmpm {

std::string face_name(int axis, bool max_side) {
  static constexpr std::array<char, 3> kAxes{'x', 'y', 'z'};
  return std::string(1, kAxes.at(static_cast<std::size_t>(axis))) + (max_side ? "_max" : "_min");
}

std::string format_number(double x) {
  // to_chars without a precision gives the shortest text that round-trips,
  // so a resolved scene reproduces the run bit for bit. Plain decimals read
  // better (200000, 0.0012), so they win unless much longer (1e-08, 1e+12).
  std::array<char, 64> fixed{};
  std::array<char, 64> sci{};
  const auto f =
      std::to_chars(fixed.data(), fixed.data() + fixed.size(), x, std::chars_format::fixed);
  const auto e =
      std::to_chars(sci.data(), sci.data() + sci.size(), x, std::chars_format::scientific);
  const auto fixed_len = f.ptr - fixed.data();
  const auto sci_len = e.ptr - sci.data();
  if (f.ec == std::errc() && fixed_len <= sci_len + 3) return std::string(fixed.data(), f.ptr);
  return std::string(sci.data(), e.ptr);
}

std::string format_toml_float(double x) {
  if (std::isinf(x)) return x > 0 ? "inf" : "-inf";
  if (std::isnan(x)) return "nan";
  std::string s = format_number(x);
  if (s.find_first_of(".e") == std::string::npos) s += ".0";
  return s;
}

std::string format_vector(const Vec3& v, int dim) {
  std::string s = "[";
  for (int k = 0; k < dim; ++k)
    s += (k > 0 ? ", " : "") + format_number(v[static_cast<std::size_t>(k)]);
  return s + "]";
}

namespace {

std::string quoted(std::string_view s) {
  std::string out = "\"";
  for (const char c : s) {
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (static_cast<unsigned char>(c) < 0x20) {
      // TOML basic strings forbid raw control characters.
      static constexpr char kHex[] = "0123456789ABCDEF";
      out += "\\u00";
      out += kHex[(c >> 4) & 0xF];
      out += kHex[c & 0xF];
    } else {
      out += c;
    }
  }
  return out + "\"";
}

// Builds "key = value" lines in scene-file syntax; vectors are cut to the
// scene's dimension so the text reads back with the same validation.
class Writer {
 public:
  explicit Writer(int dim) : dim_(dim) {}

  void section(std::string_view header) {
    if (out_.tellp() > 0) out_ << '\n';
    out_ << header << '\n';
  }
  void line(std::string_view key, const std::string& value) {
    out_ << key << " = " << value << '\n';
  }
  void num(std::string_view key, double x) { line(key, format_toml_float(x)); }
  void integer(std::string_view key, long long n) { line(key, std::to_string(n)); }
  void boolean(std::string_view key, bool b) { line(key, b ? "true" : "false"); }
  void str(std::string_view key, std::string_view s) { line(key, quoted(s)); }
  template <class E>
  void word(std::string_view key, E e) {
    line(key, quoted(scene_name(e)));
  }
  void vec(std::string_view key, const Vec3& v) { line(key, vec_text(v)); }
  void stiffness(std::string_view key, double d) {
    line(key, std::isinf(d) ? quoted("perfect") : format_toml_float(d));
  }

  std::string vec_text(const Vec3& v) const {
    std::string s = "[";
    for (int k = 0; k < dim_; ++k) {
      if (k > 0) s += ", ";
      s += format_toml_float(v[static_cast<std::size_t>(k)]);
    }
    return s + "]";
  }
  std::string text() const { return out_.str(); }

 private:
  int dim_;
  std::ostringstream out_;
};

void write_simulation(Writer& w, const Scene& s) {
  const SimulationSpec& sim = s.simulation;
  w.section("[simulation]");
  w.str("name", s.name);
  w.integer("dimension", sim.dimension);
  if (sim.dimension == 2) {
    w.word("plane", sim.plane);
    w.num("thickness", sim.thickness);
  }
  w.num("end_time", sim.end_time);
  w.num("cfl", sim.cfl);
  if (sim.dt) w.num("dt", *sim.dt);
  w.word("scheme", sim.scheme);
  w.num("flip", sim.flip);
  // Written only when on, as prefetch_grid below. It was not written at
  // all until 2026-12-07: a restart (which reads the checkpoint's resolved
  // scene) went on without XPIC, and the resolved scene run again gave
  // other results (found by an outside review).
  if (sim.xpic_order > 0) w.integer("xpic_order", sim.xpic_order);
  w.word("precision", sim.precision);
  w.word("default_law", sim.default_law);
  w.boolean("force", sim.force);
  w.integer("sort_every", sim.sort_every);
  w.boolean("fuse_constitutive", sim.fuse_constitutive);
  w.boolean("fuse_step_tail", sim.fuse_step_tail);
  w.boolean("skip_empty_nodes", sim.skip_empty_nodes);
  // Written only when off: a scene resolved before the key existed (the
  // scene a checkpoint stores, run_driver.cpp) stays equal to its
  // re-resolved self.
  if (!sim.prefetch_grid) w.boolean("prefetch_grid", false);
  if (!sim.prefetch_particles) w.boolean("prefetch_particles", false);
  w.word("particle_order", sim.particle_order);
  w.boolean("compensated_positions", sim.compensated_positions);
  w.num("mm_fields_share", sim.mm_fields_share);
}

void write_grid(Writer& w, const GridSpec& g, int dim) {
  w.section("[grid]");
  w.vec("origin", g.origin);
  w.vec("cell", g.cell);
  std::string cells = "[";
  for (int k = 0; k < dim; ++k) {
    if (k > 0) cells += ", ";
    cells += std::to_string(g.cells[static_cast<std::size_t>(k)]);
  }
  w.line("cells", cells + "]");
  w.word("shape", g.shape);
  w.num("damping", g.damping);
  w.integer("tile", g.tile);
}

std::string velocity_table_text(const Writer& w, const VelocityTable& t) {
  std::string times = "[";
  std::string rows = "[";
  for (std::size_t i = 0; i < t.time.size(); ++i) {
    if (i > 0) {
      times += ", ";
      rows += ", ";
    }
    times += format_toml_float(t.time[i]);
    rows += w.vec_text(t.velocity[i]);
  }
  return "{ time = " + times + "], velocity = " + rows + "] }";
}

void write_material(Writer& w, const MaterialSpec& m) {
  w.section("[[material]]");
  w.str("name", m.name);
  w.word("type", m.type);
  w.num("density", m.density);
  switch (m.type) {
    case MaterialType::isotropic:
    case MaterialType::neohookean:
      w.num("E", m.E);
      w.num("nu", m.nu);
      break;
    case MaterialType::transverse:
      w.num("EA", m.EA);
      w.num("ET", m.ET);
      w.num("GA", m.GA);
      w.num("nuA", m.nuA);
      w.num("nuT", m.nuT);
      w.vec("axis", m.axis);
      break;
    case MaterialType::rigid:
      // One row at time 0 is the constant form of the key.
      if (m.velocity.time.size() == 1 && m.velocity.time[0] == 0.0) {
        w.vec("velocity", m.velocity.velocity[0]);
      } else if (!m.velocity.time.empty()) {
        w.line("velocity", velocity_table_text(w, m.velocity));
      }
      break;
  }
}

void write_body(Writer& w, const BodySpec& b, int dim) {
  w.section("[[body]]");
  w.str("name", b.name);
  w.str("material", b.material);
  w.word("shape", b.shape);
  switch (b.shape) {
    case BodyShape::box:
      w.vec("min", b.min);
      w.vec("max", b.max);
      break;
    case BodyShape::cylinder:
      w.vec("center", b.center);
      w.num("radius", b.radius);
      w.num("length", b.length);
      w.vec("axis", b.axis);
      break;
    case BodyShape::disk:
    case BodyShape::sphere:
      w.vec("center", b.center);
      w.num("radius", b.radius);
      break;
    case BodyShape::polygon: {
      std::string pts = "[";
      for (std::size_t i = 0; i < b.points.size(); ++i)
        pts += (i > 0 ? ", " : "") + w.vec_text(b.points[i]);
      w.line("points", pts + "]");
      break;
    }
  }
  if (dim == 2) w.num("rotate", b.rotate);
  if (dim == 2 && b.pivot) w.vec("pivot", *b.pivot);
  w.integer("particles_per_cell", b.particles_per_cell);
  w.vec("velocity", b.velocity);
  if (b.clip) {
    w.line("clip",
           "{ min = " + w.vec_text(b.clip->first) + ", max = " + w.vec_text(b.clip->second) + " }");
  }
}

void write_interaction(Writer& w, const InteractionSpec& in) {
  w.section("[[interaction]]");
  std::string pair = "[";  // built by appending: see the -Wrestrict note in error.cpp
  pair += quoted(in.materials[0]) + ", " + quoted(in.materials[1]) + "]";
  w.line("materials", pair);
  w.word("law", in.law);
  w.num("friction", in.friction);
  w.stiffness("Dn", in.Dn);
  w.stiffness("Dt", in.Dt);
  w.word("traction_law", in.traction_law);
  w.stiffness("Dn_compression", in.Dn_compression);
  w.word("normal", in.normal);
  w.vec("normal_vector", in.normal_vector);
  w.vec("center", in.center);
  // Read only with the radial normal in 3D (parse.cpp rejects it otherwise).
  if (in.radial_axis != Vec3{0, 0, 0}) w.vec("axis", in.radial_axis);
  w.word("separation", in.separation);
  w.num("min_volume", in.min_volume);
  // Read only with the position method (parse.cpp rejects it otherwise).
  if (in.separation == Separation::position) w.num("contact_offset", in.contact_offset);
  w.boolean("force_limit", in.force_limit);
  w.word("integration", in.integration);
  // Read only with the interface law (parse.cpp rejects it otherwise).
  if (in.law == Law::interface) w.word("area", in.area);
}

std::string boundary_where_text(const Writer& w, const BoundarySpec& b) {
  switch (b.kind) {
    case BoundaryWhere::face:
      return quoted(face_name(b.face_axis, b.face_max));
    case BoundaryWhere::plane:
      return "{ " + std::string(1, "xyz"[b.plane_axis]) + " = " + format_toml_float(b.plane_value) +
             " }";
    case BoundaryWhere::box:
      return "{ min = " + w.vec_text(b.box_min) + ", max = " + w.vec_text(b.box_max) + " }";
  }
  return "\"?\"";
}

void write_boundary(Writer& w, const BoundarySpec& b, int dim) {
  w.section("[[boundary]]");
  w.line("where", boundary_where_text(w, b));
  std::string fix = "[";
  for (int k = 0; k < dim; ++k) {
    if (!b.fix[static_cast<std::size_t>(k)]) continue;
    if (fix.size() > 1) fix += ", ";
    fix += quoted(std::string(1, "xyz"[k]));
  }
  w.line("fix", fix + "]");
  if (b.has_displacement) w.vec("displacement", b.displacement);
  w.num("ramp", b.ramp);
}

void write_load(Writer& w, const LoadSpec& l) {
  w.section("[[load]]");
  w.word("kind", l.kind);
  if (l.kind == LoadKind::traction) {
    w.line("where", "{ body = " + quoted(l.body) +
                        ", face = " + quoted(face_name(l.face_axis, l.face_max)) + " }");
    w.vec("traction", l.traction);
  } else {
    w.vec("acceleration", l.acceleration);
  }
  w.num("ramp", l.ramp);
}

// ["a", "b"] as TOML.
std::string quoted_list(const std::vector<std::string>& names) {
  std::string out = "[";
  for (std::size_t i = 0; i < names.size(); ++i) out += (i > 0 ? ", " : "") + quoted(names[i]);
  return out + "]";
}

void write_output(Writer& w, const OutputSpec& o) {
  w.section("[output]");
  w.num("every", o.every);
  w.line("fields", quoted_list(o.fields));
  if (!o.grid_fields.empty()) w.line("grid_fields", quoted_list(o.grid_fields));
  w.integer("series", o.series);
  w.num("checkpoint_minutes", o.checkpoint_minutes);
  w.str("directory", o.directory);
}

void write_stop(Writer& w, const StopSpec& s) {
  w.section("[stop]");
  w.boolean("enabled", s.enabled);
  w.num("kinetic_ratio", s.kinetic_ratio);
  w.integer("hold_steps", s.hold_steps);
}

}  // namespace

std::string format_scene(const Scene& scene) {
  const int dim = scene.simulation.dimension;
  Writer w(dim);
  write_simulation(w, scene);
  write_grid(w, scene.grid, dim);
  for (const MaterialSpec& m : scene.materials) write_material(w, m);
  for (const BodySpec& b : scene.bodies) write_body(w, b, dim);
  for (const InteractionSpec& in : scene.interactions) write_interaction(w, in);
  for (const BoundarySpec& b : scene.boundaries) write_boundary(w, b, dim);
  for (const LoadSpec& l : scene.loads) write_load(w, l);
  write_output(w, scene.output);
  write_stop(w, scene.stop);
  return w.text();
}

}  // namespace mmpm
