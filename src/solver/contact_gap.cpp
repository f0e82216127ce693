#include "solver/contact_gap.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <sstream>
#include <utility>

#include "scene/format.hpp"
#include "scene/interaction_warning.hpp"
#include "solver/field_plan.hpp"
#include "solver/simulation.hpp"

namespace mmpm {
namespace {

// A pair of velocity fields the multimaterial pass treats with a contact
// law, and the closest their particles come.
struct OpenContact {
  int law = 0;          // index into FieldPlan::laws: an interaction, or the default law after them
  int fields[2]{0, 0};  // the pair's velocity fields
  double nearest = 0;   // closest particles of the two fields (inf: none near)
  double touching = 0;  // the largest distance that counts as touching
};

bool is_contact_law(Law law) {
  return law == Law::stick || law == Law::frictionless || law == Law::friction;
}

// The particle spacing of a field's bodies, the largest over directions
// and bodies (0: the field has no body).
double spacing_of(const Scene& scene, const FieldPlan& plan, int field) {
  double s = 0;
  const int dim = scene.simulation.dimension;
  for (const auto& b : scene.bodies) {
    const int m = scene.material_index(b.material);
    if (m < 0 || plan.field_of_material[std::size_t(m)] != field) continue;
    for (int d = 0; d < dim; ++d)
      s = std::max(s, scene.grid.cell[std::size_t(d)] / double(b.particles_per_cell));
  }
  return s;
}

// Particles binned by grid cell: (cell key, particle) sorted by key.
using Binned = std::vector<std::pair<std::uint64_t, std::uint32_t>>;

struct CellGrid {
  int dim = 2;
  std::array<long, 3> cells{1, 1, 1};
  std::array<double, 3> origin{0, 0, 0}, h{1, 1, 1};
  std::array<long, 3> cell_of(const double* x) const {
    std::array<long, 3> c{0, 0, 0};
    for (int d = 0; d < dim; ++d)
      c[std::size_t(d)] =
          std::clamp(long(std::floor((x[d] - origin[std::size_t(d)]) / h[std::size_t(d)])), 0L,
                     cells[std::size_t(d)] - 1);
    return c;
  }
  std::uint64_t key(const std::array<long, 3>& c) const {
    return (std::uint64_t(c[2]) * std::uint64_t(cells[1]) + std::uint64_t(c[1])) *
               std::uint64_t(cells[0]) +
           std::uint64_t(c[0]);
  }
};

Binned bin(const CellGrid& g, const std::vector<double>& x, const std::vector<double>& mat,
           const FieldPlan& plan, int field) {
  Binned out;
  for (std::size_t p = 0; p < mat.size(); ++p)
    if (plan.field_of_material[std::size_t(mat[p])] == field)
      out.emplace_back(g.key(g.cell_of(&x[p * std::size_t(g.dim)])), std::uint32_t(p));
  std::sort(out.begin(), out.end());
  return out;
}

// The smallest distance from a particle of `a` to one of `b` within `reach`
// cells, stopping as soon as one is at most `touching` (inf: none in reach).
double nearest_pair(const CellGrid& g, const std::vector<double>& x, const Binned& a,
                    const Binned& b, const std::array<long, 3>& reach, double touching) {
  double best = std::numeric_limits<double>::infinity();
  const int D = g.dim;
  for (std::size_t i = 0; i < a.size();) {
    std::size_t j = i;
    while (j < a.size() && a[j].first == a[i].first) ++j;  // the particles of one a-cell
    const std::array<long, 3> c = g.cell_of(&x[std::size_t(a[i].second) * std::size_t(D)]);
    std::array<long, 3> lo{0, 0, 0}, hi{0, 0, 0};
    for (int d = 0; d < D; ++d) {
      lo[std::size_t(d)] = std::max(0L, c[std::size_t(d)] - reach[std::size_t(d)]);
      hi[std::size_t(d)] =
          std::min(g.cells[std::size_t(d)] - 1, c[std::size_t(d)] + reach[std::size_t(d)]);
    }
    std::array<long, 3> n{0, 0, 0};
    for (n[2] = lo[2]; n[2] <= hi[2]; ++n[2])
      for (n[1] = lo[1]; n[1] <= hi[1]; ++n[1])
        for (n[0] = lo[0]; n[0] <= hi[0]; ++n[0]) {
          const std::uint64_t k = g.key(n);
          auto it = std::lower_bound(b.begin(), b.end(), std::make_pair(k, std::uint32_t(0)));
          for (; it != b.end() && it->first == k; ++it)
            for (std::size_t q = i; q < j; ++q) {
              const double* xa = &x[std::size_t(a[q].second) * std::size_t(D)];
              const double* xb = &x[std::size_t(it->second) * std::size_t(D)];
              double r2 = 0;
              for (int d = 0; d < D; ++d) r2 += (xa[d] - xb[d]) * (xa[d] - xb[d]);
              best = std::min(best, std::sqrt(r2));
              if (best <= touching) return best;
            }
        }
    i = j;
  }
  return best;
}

// The pairs of fields whose law `wanted` accepts (the default law's pairs
// included; two rigid fields never meet in the multimaterial pass), each
// with the closest its particles come.
template <class Wanted>
std::vector<OpenContact> measured_pairs(const Scene& scene, const FieldPlan& plan,
                                        const Simulation& sim, Wanted&& wanted) {
  std::vector<OpenContact> out;
  std::vector<OpenContact> checked;
  const std::size_t F = std::size_t(plan.fields);
  for (std::size_t a = 0; a < F; ++a)
    for (std::size_t b = a + 1; b < F; ++b) {
      const int l = plan.pair[a * F + b];
      if (l < 0 || !wanted(plan.laws[std::size_t(l)].law)) continue;
      if (plan.rigid[a] && plan.rigid[b]) continue;
      checked.push_back({l, {int(a), int(b)}, 0, 0});
    }
  if (checked.empty()) return out;

  CellGrid g;
  g.dim = scene.simulation.dimension;
  for (int d = 0; d < g.dim; ++d) {
    g.cells[std::size_t(d)] = std::max(1L, long(scene.grid.cells[std::size_t(d)]));
    g.origin[std::size_t(d)] = scene.grid.origin[std::size_t(d)];
    g.h[std::size_t(d)] = scene.grid.cell[std::size_t(d)];
  }
  const std::vector<double> x = sim.particle_field("position").values;
  const std::vector<double> mat = sim.particle_field("material").values;
  for (OpenContact c : checked) {
    const double sa = spacing_of(scene, plan, c.fields[0]);
    const double sb = spacing_of(scene, plan, c.fields[1]);
    if (sa == 0 || sb == 0) continue;  // a field without particles
    c.touching = 0.75 * (sa + sb);
    std::array<long, 3> reach{0, 0, 0};
    for (int d = 0; d < g.dim; ++d)
      reach[std::size_t(d)] = long(std::ceil(c.touching / g.h[std::size_t(d)]));
    Binned a = bin(g, x, mat, plan, c.fields[0]), b = bin(g, x, mat, plan, c.fields[1]);
    if (a.empty() || b.empty()) continue;
    if (a.size() > b.size()) std::swap(a, b);  // walk the cells of the smaller set
    c.nearest = nearest_pair(g, x, a, b, reach, c.touching);
    // The search sees every pair up to `reach` cells apart; a larger
    // distance found is not known to be the nearest.
    double seen = std::numeric_limits<double>::infinity();
    for (int d = 0; d < g.dim; ++d)
      seen = std::min(seen, double(reach[std::size_t(d)]) * g.h[std::size_t(d)]);
    if (c.nearest > seen * (1 + 1e-9)) c.nearest = std::numeric_limits<double>::infinity();
    out.push_back(c);
  }
  return out;
}

std::vector<OpenContact> open_contacts(const Scene& scene, const FieldPlan& plan,
                                       const Simulation& sim) {
  std::vector<OpenContact> out;
  if (!plan.multimaterial || plan.position_separation) return out;
  for (const OpenContact& c : measured_pairs(scene, plan, sim, is_contact_law))
    if (c.nearest > c.touching) out.push_back(c);
  return out;
}

// The materials of a field, quoted and joined ("'a'", "'a' and 'b'").
std::string materials_of(const Scene& scene, const FieldPlan& plan, int field) {
  std::vector<std::string> names;
  for (const std::size_t m : materials_in_field(plan, field))
    names.push_back("'" + scene.materials[m].name + "'");
  std::string s;
  for (std::size_t i = 0; i < names.size(); ++i)
    s += (i == 0 ? "" : i + 1 == names.size() ? " and " : ", ") + names[i];
  return s;
}

std::string open_contact_warning(const Scene& scene, const FieldPlan& plan, const OpenContact& c) {
  std::ostringstream m;
  m.precision(4);
  const std::size_t l = std::size_t(c.law);
  if (l < scene.interactions.size()) {  // plan.laws starts with the scene's interactions
    const InteractionSpec& it = scene.interactions[l];
    m << interaction_warning(scene, l, "separation") << "materials '" << it.materials[0]
      << "' and '" << it.materials[1] << "' start apart";
  } else {
    // The key's line when the scene sets it (the default law has none).
    m << warning_at(scene, scene.simulation.default_law_where) << "key 'simulation.default_law' ("
      << scene_name(plan.laws[l].law)
      << ", displacement separation): " << materials_of(scene, plan, c.fields[0]) << " and "
      << materials_of(scene, plan, c.fields[1])
      << " share no [[interaction]], so the default law applies, and they start apart";
  }
  m << " (their nearest particles are ";
  if (std::isfinite(c.nearest))
    m << c.nearest;
  else
    m << "more than " << c.touching;
  m << " apart; touching bodies' are at most " << c.touching
    << "). With separation = \"displacement\" they count as in contact as soon as their "
       "particles share grid nodes, a cell or more before their surfaces meet; separation = "
       "\"position\" is meant for bodies that start apart";
  if (l >= scene.interactions.size())
    m << " (an [[interaction]] of theirs, or default_law = \"separate\" if they never meet)";
  return m.str();
}

}  // namespace

std::vector<std::string> open_contact_warnings(const Scene& scene, const Simulation& sim) {
  std::vector<std::string> out;
  const FieldPlan plan = plan_fields(scene);
  for (const OpenContact& c : open_contacts(scene, plan, sim))
    out.push_back(open_contact_warning(scene, plan, c));
  return out;
}

std::vector<std::string> bonded_position_interface_warnings(const Scene& scene,
                                                            const Simulation& sim) {
  std::vector<std::string> out;
  const FieldPlan plan = plan_fields(scene);
  if (!plan.multimaterial || !plan.position_separation) return out;
  auto interface = [](Law law) { return law == Law::interface; };
  for (const OpenContact& c : measured_pairs(scene, plan, sim, interface)) {
    const std::size_t l = std::size_t(c.law);
    if (!(c.nearest <= c.touching) || l >= scene.interactions.size()) continue;
    const InteractionSpec& it = scene.interactions[l];
    std::ostringstream m;
    m.precision(4);
    m << interaction_warning(scene, l, "separation") << "materials '" << it.materials[0]
      << "' and '" << it.materials[1] << "' start bonded (their nearest particles are " << c.nearest
      << " apart; touching bodies' are at most " << c.touching
      << "), and their interface reads its opening from the particles' positions: the "
         "centroids of two bonded materials lie about 3/4 of a cell apart at a node, so the "
         "interface starts loaded by D (that offset - contact_offset x h) and by the "
         "centroids' tangential offsets. separation = \"displacement\" (the default) is "
         "meant for interfaces that start bonded";
    out.push_back(m.str());
  }
  return out;
}

}  // namespace mmpm
