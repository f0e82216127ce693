#include "solver/contact_gap.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <sstream>
#include <utility>

#include "solver/simulation.hpp"

namespace mmpm {
namespace {

struct OpenContact {
  std::size_t interaction = 0;  // index into scene.interactions
  double nearest = 0;           // closest particles of the two materials (inf: none near)
  double touching = 0;          // the largest distance that counts as touching
};

bool is_contact_law(Law law) {
  return law == Law::stick || law == Law::frictionless || law == Law::friction;
}

// The particle spacing of a material's bodies, the largest over directions
// and bodies (0: the material has no body).
double spacing_of(const Scene& scene, const std::string& material) {
  double s = 0;
  const int dim = scene.simulation.dimension;
  for (const auto& b : scene.bodies) {
    if (b.material != material) continue;
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
           int material) {
  Binned out;
  for (std::size_t p = 0; p < mat.size(); ++p)
    if (int(mat[p]) == material)
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

std::vector<OpenContact> open_contacts(const Scene& scene, const Simulation& sim) {
  std::vector<OpenContact> out;
  std::vector<std::size_t> checked;
  for (std::size_t i = 0; i < scene.interactions.size(); ++i) {
    const InteractionSpec& it = scene.interactions[i];
    if (is_contact_law(it.law) && it.separation == Separation::displacement) checked.push_back(i);
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
  for (const std::size_t i : checked) {
    const InteractionSpec& it = scene.interactions[i];
    const int ma = scene.material_index(it.materials[0]);
    const int mb = scene.material_index(it.materials[1]);
    const double sa = spacing_of(scene, it.materials[0]), sb = spacing_of(scene, it.materials[1]);
    if (ma < 0 || mb < 0 || sa == 0 || sb == 0) continue;  // a material without particles
    const double touching = 0.75 * (sa + sb);
    std::array<long, 3> reach{0, 0, 0};
    for (int d = 0; d < g.dim; ++d)
      reach[std::size_t(d)] = long(std::ceil(touching / g.h[std::size_t(d)]));
    Binned a = bin(g, x, mat, ma), b = bin(g, x, mat, mb);
    if (a.empty() || b.empty()) continue;
    if (a.size() > b.size()) std::swap(a, b);  // walk the cells of the smaller set
    double nearest = nearest_pair(g, x, a, b, reach, touching);
    // The search sees every pair up to `reach` cells apart; a larger
    // distance found is not known to be the nearest.
    double seen = std::numeric_limits<double>::infinity();
    for (int d = 0; d < g.dim; ++d)
      seen = std::min(seen, double(reach[std::size_t(d)]) * g.h[std::size_t(d)]);
    if (nearest > seen * (1 + 1e-9)) nearest = std::numeric_limits<double>::infinity();
    if (nearest > touching) out.push_back({i, nearest, touching});
  }
  return out;
}

std::string open_contact_warning(const Scene& scene, const OpenContact& c) {
  const InteractionSpec& it = scene.interactions[c.interaction];
  std::ostringstream m;
  m.precision(4);
  m << (it.where.file.empty() ? scene.source_file : it.where.file);
  if (it.where.line > 0) m << ":" << it.where.line;
  m << ": warning: key 'interaction[" << c.interaction << "].separation': materials '"
    << it.materials[0] << "' and '" << it.materials[1]
    << "' start apart (their nearest particles are ";
  if (std::isfinite(c.nearest))
    m << c.nearest;
  else
    m << "more than " << c.touching;
  m << " apart; touching bodies' are at most " << c.touching
    << "). With separation = \"displacement\" they count as in contact as soon as their "
       "particles share grid nodes, a cell or more before their surfaces meet; separation = "
       "\"position\" is meant for bodies that start apart";
  return m.str();
}

}  // namespace

std::vector<std::string> open_contact_warnings(const Scene& scene, const Simulation& sim) {
  std::vector<std::string> out;
  for (const OpenContact& c : open_contacts(scene, sim))
    out.push_back(open_contact_warning(scene, c));
  return out;
}

}  // namespace mmpm
