// Particle-to-grid transfer (kernels/p2g.hpp) with the binning and coloring
// of kernels/binning.hpp, on random particle sets in 2D and 3D, several shape
// functions, double and float.
//
//  - Conservation: total grid mass = total particle mass, total grid momentum
//    = total particle momentum, sum of nodal forces = sum of the traction
//    forces (the internal forces -V sigma.G sum to zero because the gradients
//    of a partition of unity do), nodal domains sum to the particle areas,
//    the mass-weighted displacements to sum m (x - x0). Tolerance: relative
//    to the sum of magnitudes, 1e-12 in double, 2e-5 in float.
//  - The colored tile scatter as the solver runs it (counting_sort by the
//    TileLayout key, colors in order, the tiles of one color in parallel on 2
//    threads, each thread its TileSchedule share) is bitwise equal to the same scatter on 1
//    thread and to a plain serial loop of p2g_range over the tiles in color
//    order. It equals a serial p2g_range over all particles in sorted order
//    and one in the original (unsorted) order to 1e-12 relative (double;
//    float 1e-4), per array, relative to the array's largest magnitude.
//    (Not bitwise to the sorted-order scatter: a node at a tile corner gets
//    its contributions tile by tile in color order there, in tile-index order
//    here, and floating-point addition is not associative — e.g. the tiles
//    (0,1) [color 2] and (1,2) [color 1] share nodes; the sorted order adds
//    (0,1) first, the colored order (1,2) first. Thread-count independence
//    only needs the fixed color order, which is what is checked bitwise.)
//  - Tiles of one color never touch a common node (checked node by node, so
//    a coloring bug fails deterministically rather than by a lucky race).
//  - The windowed kernels (kernels/window.hpp: p2g_range, g2p_range) equal
//    the pointwise reference kernels (p2g_range_pointwise,
//    g2p_range_pointwise) to 1e-12 (double) / 2e-5 (float) relative to each
//    array's largest magnitude, with particles spread over the grid and with
//    half of them within 1.5 cells of an edge (where the window is shifted
//    inward), in tile order and in random order.
// Resolution: 2D grid 37 x 29 cells, 6000 particles; 3D 13 x 12 x 11 cells,
// 4000 particles; cells of unequal size; tile edges 4 (the minimum: TileLayout
// rounds the edge up to a power of two >= 4), 8 and 16.
#include <gtest/gtest.h>
#include <omp.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <map>
#include <random>
#include <string>
#include <vector>

#include "kernels/binning.hpp"
#include "kernels/g2p.hpp"
#include "kernels/grid_view.hpp"
#include "kernels/mixed_tiles.hpp"
#include "kernels/multimaterial.hpp"
#include "kernels/p2g.hpp"
#include "kernels/p2g_multimaterial.hpp"
#include "kernels/particle_view.hpp"
#include "kernels/separation_extrapolation.hpp"
#include "kernels/shape.hpp"
#include "kernels/weights.hpp"
#include "tests/shape_configs.hpp"

namespace {

using namespace mmpm;

using mmpm_test::Cfg;
using mmpm_test::CfgNames;

constexpr unsigned kAll = kMassMomentum | kForce | kMultimaterial | kDomainGradient;

// Owning particle arrays (SoA) and their view.
template <int D, class Real>
struct Particles {
  static constexpr int NS = kStressComponents<D>;
  std::size_t n = 0;
  std::array<std::vector<Real>, D> x, v, x0, lp, fext;
  std::vector<Real> m, V;
  std::array<std::vector<Real>, NS> s;
  std::vector<std::uint8_t> field;
  std::vector<std::uint32_t> key;

  ParticleView<D, Real> view(bool gimp) {
    ParticleView<D, Real> P;
    P.n = n;
    for (int d = 0; d < D; ++d) {
      P.x[d] = x[d].data();
      P.v[d] = v[d].data();
      P.x0[d] = x0[d].data();
      P.fext[d] = fext[d].data();
      P.lp[d] = gimp ? lp[d].data() : nullptr;
    }
    P.m = m.data();
    P.V = V.data();
    for (int c = 0; c < NS; ++c) P.s[c] = s[c].data();
    P.field = field.data();
    P.key = key.data();
    return P;
  }

  // The particles reordered: out[i] = this[perm[i]] (what the solver's sort does).
  Particles permuted(const std::vector<std::uint32_t>& perm) const {
    Particles o = *this;
    auto apply = [&](const auto& in, auto& out) {
      for (std::size_t i = 0; i < n; ++i) out[i] = in[perm[i]];
    };
    for (int d = 0; d < D; ++d) {
      apply(x[d], o.x[d]);
      apply(v[d], o.v[d]);
      apply(x0[d], o.x0[d]);
      apply(lp[d], o.lp[d]);
      apply(fext[d], o.fext[d]);
    }
    apply(m, o.m);
    apply(V, o.V);
    for (int c = 0; c < NS; ++c) apply(s[c], o.s[c]);
    apply(field, o.field);
    apply(key, o.key);
    return o;
  }
};

// Owning grid arrays (fields x nodes) and their view.
template <int D, class Real>
struct Grid {
  GridView<D, Real> G;
  std::vector<std::vector<Real>> arrays;  // m, p[D], f[D], mx[D], vol, g[D]
  std::array<int, 3> cells{1, 1, 1};

  Grid(const std::array<int, 3>& c, int fields) : cells(c) {
    const double h[3] = {0.5, 0.4, 0.6}, o[3] = {-1.0, 2.0, 0.5};
    G.nodes = 1;
    for (int d = 0; d < D; ++d) {
      G.nodes_per_dim[d] = c[d] + 1;
      G.h[d] = Real(h[d]);
      G.origin[d] = Real(o[d]);
      G.nodes *= std::size_t(c[d] + 1);
    }
    G.fields = fields;
    const std::size_t total = G.nodes * std::size_t(fields);
    arrays.assign(std::size_t(2 + 4 * D), std::vector<Real>(total, Real(0)));
    std::size_t k = 0;
    G.m = arrays[k++].data();
    for (int d = 0; d < D; ++d) G.p[d] = arrays[k++].data();
    for (int d = 0; d < D; ++d) G.f[d] = arrays[k++].data();
    for (int d = 0; d < D; ++d) G.mx[d] = arrays[k++].data();
    G.vol = arrays[k++].data();
    for (int d = 0; d < D; ++d) G.g[d] = arrays[k++].data();
  }
  Grid(const Grid&) = delete;

  double sum(const Real* a) const {
    double s = 0;
    for (std::size_t i = 0; i < G.nodes * std::size_t(G.fields); ++i) s += double(a[i]);
    return s;
  }
  double sum_field(const Real* a, int f) const {
    double s = 0;
    for (std::size_t i = 0; i < G.nodes; ++i) s += double(a[G.at(f, i)]);
    return s;
  }
};

template <int D>
std::array<int, 3> grid_cells() {
  return D == 2 ? std::array<int, 3>{37, 29, 1} : std::array<int, 3>{13, 12, 11};
}

// Random particles at least 2 cells inside the grid (bspline3 needs that), in
// 2 material fields, with random velocities, stresses, tractions, uGIMP half-widths.
template <int D, class Real>
Particles<D, Real> random_particles(const GridView<D, Real>& G, const std::array<int, 3>& cells,
                                    std::size_t n, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> U(0.0, 1.0);
  auto in = [&](double a, double b) { return a + (b - a) * U(rng); };
  Particles<D, Real> p;
  p.n = n;
  for (int d = 0; d < D; ++d) {
    for (auto* a : {&p.x[d], &p.v[d], &p.x0[d], &p.lp[d], &p.fext[d]}) a->resize(n);
  }
  p.m.resize(n);
  p.V.resize(n);
  for (auto& c : p.s) c.resize(n);
  p.field.resize(n);
  p.key.assign(n, 0);
  for (std::size_t i = 0; i < n; ++i) {
    for (int d = 0; d < D; ++d) {
      const double lo = double(G.origin[d]) + 2.05 * double(G.h[d]);
      const double hi = double(G.origin[d]) + (cells[d] - 2.05) * double(G.h[d]);
      p.x[d][i] = Real(in(lo, hi));
      p.x0[d][i] = Real(double(p.x[d][i]) - in(-0.2, 0.2));
      p.v[d][i] = Real(in(-1, 1));
      p.lp[d][i] = Real(in(0.1, 0.5));
      p.fext[d][i] = Real(in(-0.3, 0.3));
    }
    p.m[i] = Real(in(0.5, 2.0));
    p.V[i] = Real(in(0.01, 0.03));
    for (auto& c : p.s) c[i] = Real(in(-5, 5));
    p.field[i] = std::uint8_t(U(rng) < 0.5 ? 0 : 1);
  }
  return p;
}

// The solver's binning: keys from the cell (or the nearest node:
// kernels/shape.hpp binned_by_nearest_node) of every particle, stable
// counting sort.
template <class Shape, int D, class Real>
std::vector<std::uint32_t> sort_by_tile(Particles<D, Real>& p, const GridView<D, Real>& G,
                                        const TileLayout<D>& tiles) {
  const auto origin = key_origins<D, Shape>(G.origin, G.h);
  for (std::size_t i = 0; i < p.n; ++i) {
    std::array<int, 3> c{0, 0, 0};
    for (int d = 0; d < D; ++d) c[d] = cell_of(p.x[d][i], origin[d], Real(1) / G.h[d]);
    p.key[i] = tiles.key(c);
  }
  std::vector<std::uint32_t> offsets, perm;
  counting_sort(p.key.data(), p.n, tiles.key_count(), offsets, perm);
  return perm;
}

// The colored scatter (as Stepper::p2g runs it), with `threads` OpenMP threads.
// Returns the number of threads the parallel regions actually had.
template <int D, class Shape, class Real, unsigned What, bool MF, bool TR>
int colored_p2g(const ParticleView<D, Real>& P, const GridView<D, Real>& G, const P2GOptions& opt,
                const TileSchedule& r, int threads) {
  int team = 0;
  std::size_t bad = SIZE_MAX;
  for (std::size_t c = 0; c < r.tiles.size(); ++c) {
    const auto& list = r.tiles[c];
#pragma omp parallel num_threads(threads) reduction(min : bad)
    {
#pragma omp single
      team = std::max(team, omp_get_num_threads());
      const auto [first, last] =
          r.share(c, std::size_t(omp_get_num_threads()), std::size_t(omp_get_thread_num()));
      for (std::size_t k = first; k < last; ++k) {
        const std::uint32_t t = list[k];
        const std::size_t b = r.begin[t], e = r.begin[t + 1];
        const std::size_t got = p2g_range<D, Shape, Real, What, MF, TR>(P, G, opt, b, e);
        if (got != e) bad = std::min(bad, got);
      }
    }
  }
  EXPECT_EQ(bad, SIZE_MAX) << "a stencil left the grid";
  return team;
}

template <class Real>
bool bitwise_equal(const std::vector<Real>& a, const std::vector<Real>& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(Real)) == 0;
}

template <class Real>
std::size_t first_difference(const std::vector<Real>& a, const std::vector<Real>& b) {
  for (std::size_t i = 0; i < a.size(); ++i)
    if (std::memcmp(&a[i], &b[i], sizeof(Real)) != 0) return i;
  return a.size();
}

template <class C>
class P2G : public ::testing::Test {};

using Configs = ::testing::Types<
    Cfg<2, LinearShape, double>, Cfg<2, GimpShape, double>, Cfg<2, GimpShape, float>,
    Cfg<2, BSpline2Shape, double>, Cfg<2, BSpline3Shape, float>, Cfg<3, GimpShape, double>,
    Cfg<3, LinearShape, float>, Cfg<3, BSpline2Shape, double>, Cfg<3, BSpline3Shape, double>>;
TYPED_TEST_SUITE(P2G, Configs, CfgNames);

template <class Real>
constexpr double conservation_tol() {
  return sizeof(Real) == 8 ? 1e-12 : 2e-5;
}

// Conservation of mass, momentum, force, domain and displacement moments by
// one serial scatter in natural particle order.
template <int D, class Shape, class Real, bool MF, bool TR>
void check_conservation(unsigned seed, bool constant_stress) {
  constexpr int NS = kStressComponents<D>;
  const bool gimp = std::string(Shape::name) == "gimp";
  const int fields = MF ? 2 : 1;
  Grid<D, Real> g(grid_cells<D>(), fields);
  const std::size_t n = D == 2 ? 6000 : 4000;
  auto p = random_particles<D, Real>(g.G, g.cells, n, seed);
  if (constant_stress)
    for (int c = 0; c < NS; ++c) std::fill(p.s[c].begin(), p.s[c].end(), Real(1.5 + c));
  if (!MF) std::fill(p.field.begin(), p.field.end(), std::uint8_t(0));
  const auto P = p.view(gimp);
  P2GOptions opt;
  opt.inv_thickness = 0.5;  // 2D: Omega holds areas = V / thickness
  constexpr unsigned What = MF ? kAll : (kMassMomentum | kForce);
  ASSERT_EQ((p2g_range<D, Shape, Real, What, MF, TR>(P, g.G, opt, 0, n)), n);

  const double tol = conservation_tol<Real>();
  double m = 0, mf[2] = {0, 0}, mom[D] = {}, mom_abs = 0, fe[D] = {}, fe_abs = 0, area = 0,
         mx[D] = {}, mx_abs = 0, force_scale = 0;
  double inv_h = 0;
  for (int d = 0; d < D; ++d) inv_h = std::max(inv_h, 1.0 / double(g.G.h[d]));
  for (std::size_t i = 0; i < n; ++i) {
    m += double(p.m[i]);
    mf[p.field[i]] += double(p.m[i]);
    double smax = 0;
    for (int c = 0; c < NS; ++c) smax = std::max(smax, std::abs(double(p.s[c][i])));
    force_scale += double(p.V[i]) * smax * D * inv_h;
    area += double(p.V[i]) * (D == 2 ? opt.inv_thickness : 1.0);
    for (int d = 0; d < D; ++d) {
      mom[d] += double(p.m[i]) * double(p.v[d][i]);
      mom_abs += std::abs(double(p.m[i]) * double(p.v[d][i]));
      if (TR) fe[d] += double(p.fext[d][i]), fe_abs += std::abs(double(p.fext[d][i]));
      const double u = double(p.x[d][i]) - double(p.x0[d][i]);
      mx[d] += double(p.m[i]) * u;
      mx_abs += std::abs(double(p.m[i]) * u);
    }
  }
  EXPECT_NEAR(g.sum(g.G.m), m, tol * m) << "mass";
  if (MF) {
    for (int f = 0; f < 2; ++f) {
      EXPECT_NEAR(g.sum_field(g.G.m, f), mf[f], tol * m) << "mass of field " << f;
    }
  }
  for (int d = 0; d < D; ++d) {
    EXPECT_NEAR(g.sum(g.G.p[d]), mom[d], tol * mom_abs) << "momentum " << d;
    EXPECT_NEAR(g.sum(g.G.f[d]), fe[d], tol * (force_scale + fe_abs)) << "force sum " << d;
  }
  if (MF) {
    EXPECT_NEAR(g.sum(g.G.vol), area, tol * area) << "nodal domains";
    for (int d = 0; d < D; ++d) {
      EXPECT_NEAR(g.sum(g.G.mx[d]), mx[d], tol * mx_abs) << "mass-weighted displacement " << d;
      EXPECT_NEAR(g.sum(g.G.g[d]), 0.0, tol * area * D * inv_h * 4) << "domain gradient " << d;
    }
  }
}

TYPED_TEST(P2G, ConservesMassMomentumForceMultiField) {
  check_conservation<TypeParam::D, typename TypeParam::Shape, typename TypeParam::Real, true, true>(
      101, false);
}
TYPED_TEST(P2G, ConservesMassMomentumForceSingleField) {
  check_conservation<TypeParam::D, typename TypeParam::Shape, typename TypeParam::Real, false,
                     false>(102, false);
}
// Divergence of a constant stress field: the internal forces sum to zero.
TYPED_TEST(P2G, ConstantStressForcesSumToZero) {
  check_conservation<TypeParam::D, typename TypeParam::Shape, typename TypeParam::Real, false,
                     false>(103, true);
}

// Two tiles of one color never share a node under the shape function's
// stencil, nor under the windows the solver's kernels read and write
// (kernels/window.hpp: every row of W nodes, zero weights included, at the
// base the key's frame gives; binned by the nearest node in double).
TYPED_TEST(P2G, SameColorTilesTouchDisjointNodes) {
  constexpr int D = TypeParam::D;
  using Shape = typename TypeParam::Shape;
  using Real = typename TypeParam::Real;
  const bool gimp = std::string(Shape::name) == "gimp";
  for (int T : {4, 8, 16}) {
    Grid<D, Real> g(grid_cells<D>(), 1);
    auto p = random_particles<D, Real>(g.G, g.cells, D == 2 ? 6000 : 4000, 200 + unsigned(T));
    for (int d = 0; d < D; ++d)
      std::fill(p.lp[d].begin(), p.lp[d].end(), Real(0.5));  // widest uGIMP
    TileLayout<D> tiles;
    tiles.setup(T, g.cells);
    ASSERT_EQ(tiles.T, T);
    auto sorted = p.permuted(sort_by_tile<Shape>(p, g.G, tiles));
    const auto P = sorted.view(gimp);
    const std::array<Real, 3> inv_h{Real(1) / g.G.h[0], Real(1) / g.G.h[1], Real(1) / g.G.h[2]};
    std::vector<std::int64_t> owner(g.G.nodes);
    for (int color = 0; color < (1 << D); ++color) {
      std::fill(owner.begin(), owner.end(), -1);
      for (std::size_t i = 0; i < sorted.n; ++i) {
        const std::uint32_t tile = tiles.tile_of_key(sorted.key[i]);
        if (tiles.color(tile) != color) continue;
        Stencil<D, Shape, Real> st{};
        ASSERT_TRUE(st.build(P, g.G, inv_h, i));
        std::vector<std::size_t> nodes;
        for (int k = 0; k < st.count; ++k) nodes.push_back(st.base + st.node[k]);
        using Win = Window<D, Shape, Real>;
        if (Win::fits(g.G)) {
          Win w;
          const WindowBuilder<D, Shape, Real> builder(g.G);
          ASSERT_TRUE(builder.build(P, i, w));
          for (const std::size_t row : Win::offsets(g.G))
            for (int x = 0; x < Win::W; ++x) nodes.push_back(w.base + row + std::size_t(x));
          // Tighter: inside the node box of its key's tile (what the
          // multimaterial fields zero, kernels/tile_reach.hpp), unless moved
          // inward at the grid's edge (it adds zeros there). A key in
          // another frame than the window's puts a window one node out.
          const NodeBox box = tile_node_box(tiles, tile, g.G.nodes_per_dim, NodeReach::of<Shape>());
          std::size_t rest = w.base;
          for (int d = 0; d < D; ++d) {
            const int n = g.G.nodes_per_dim[std::size_t(d)];
            const int lo = int(rest % std::size_t(n)), hi = lo + Win::extent(d) - 1;
            rest /= std::size_t(n);
            if (lo == 0 || hi == n - 1) continue;
            ASSERT_GE(lo, box.lo[std::size_t(d)]) << "particle " << i << ", direction " << d;
            ASSERT_LE(hi, box.hi[std::size_t(d)]) << "particle " << i << ", direction " << d;
          }
        }
        for (const std::size_t node : nodes) {
          if (owner[node] >= 0) {
            ASSERT_EQ(owner[node], std::int64_t(tile))
                << "T=" << T << ": tiles " << owner[node] << " and " << tile << " (color " << color
                << ") share node " << node;
          }
          owner[node] = tile;
        }
      }
    }
  }
}

// The colored scatter: 2 threads = 1 thread = its serial twin, bitwise;
// = serial in sorted and in natural order to round-off.
template <int D, class Shape, class Real, bool MF, bool TR>
void check_colored(int T, unsigned seed) {
  constexpr unsigned What = MF ? kAll : (kMassMomentum | kForce);
  const bool gimp = std::string(Shape::name) == "gimp";
  const int fields = MF ? 2 : 1;
  const std::size_t n = D == 2 ? 6000 : 4000;
  Grid<D, Real> natural(grid_cells<D>(), fields), serial(grid_cells<D>(), fields),
      sorted_serial(grid_cells<D>(), fields), one(grid_cells<D>(), fields),
      two(grid_cells<D>(), fields);
  auto p = random_particles<D, Real>(natural.G, natural.cells, n, seed);
  if (!MF) std::fill(p.field.begin(), p.field.end(), std::uint8_t(0));
  P2GOptions opt;
  opt.inv_thickness = 0.5;

  ASSERT_EQ((p2g_range<D, Shape, Real, What, MF, TR>(p.view(gimp), natural.G, opt, 0, n)), n);

  TileLayout<D> tiles;
  tiles.setup(T, natural.cells);
  ASSERT_EQ(tiles.T, T) << "tile edges are powers of two";
  auto sorted = p.permuted(sort_by_tile<Shape>(p, natural.G, tiles));
  for (std::size_t i = 1; i < n; ++i)
    ASSERT_LE(sorted.key[i - 1], sorted.key[i]) << "sorted by key";
  const auto P = sorted.view(gimp);
  TileSchedule r;
  r.build(tiles, sorted.key.data(), n);
  int colors_used = 0;
  for (const auto& c : r.tiles) colors_used += !c.empty();
  ASSERT_EQ(colors_used, 1 << D) << "every color has tiles";

  ASSERT_EQ((p2g_range<D, Shape, Real, What, MF, TR>(P, sorted_serial.G, opt, 0, n)), n);
  for (const auto& list : r.tiles)  // serial twin of the colored scatter, no OpenMP
    for (std::uint32_t t : list)
      ASSERT_EQ(
          (p2g_range<D, Shape, Real, What, MF, TR>(P, serial.G, opt, r.begin[t], r.begin[t + 1])),
          r.begin[t + 1]);
  colored_p2g<D, Shape, Real, What, MF, TR>(P, one.G, opt, r, 1);
  const int team = colored_p2g<D, Shape, Real, What, MF, TR>(P, two.G, opt, r, 2);
  ASSERT_EQ(team, 2) << "the parallel scatter must really run on 2 threads";

  const double tol = sizeof(Real) == 8 ? 1e-12 : 1e-4;
  for (std::size_t a = 0; a < natural.arrays.size(); ++a) {
    const auto& nat = natural.arrays[a];
    const auto& c2 = two.arrays[a];
    EXPECT_TRUE(bitwise_equal(c2, one.arrays[a]))
        << "array " << a << ": 2 threads differ from 1 thread at entry "
        << first_difference(c2, one.arrays[a]);
    const std::size_t i = first_difference(c2, serial.arrays[a]);
    EXPECT_EQ(i, c2.size()) << "array " << a
                            << ": colored scatter differs from its serial twin at entry " << i
                            << ": " << (i < c2.size() ? double(c2[i]) : 0.0) << " vs "
                            << (i < c2.size() ? double(serial.arrays[a][i]) : 0.0);
    double scale = 0, diff_nat = 0, diff_sorted = 0;
    for (std::size_t k = 0; k < nat.size(); ++k) {
      scale = std::max(scale, std::abs(double(nat[k])));
      diff_nat = std::max(diff_nat, std::abs(double(nat[k]) - double(c2[k])));
      diff_sorted =
          std::max(diff_sorted, std::abs(double(sorted_serial.arrays[a][k]) - double(c2[k])));
    }
    if (MF || a < std::size_t(1 + 2 * D)) {
      EXPECT_GT(scale, 0.0) << "array " << a << " was filled";
    }
    EXPECT_LE(diff_nat, tol * scale) << "array " << a << ": colored vs natural order";
    EXPECT_LE(diff_sorted, tol * scale) << "array " << a << ": colored vs sorted order";
  }
}

TYPED_TEST(P2G, ColoredScatterMatchesSerialMultiFieldTile4) {
  check_colored<TypeParam::D, typename TypeParam::Shape, typename TypeParam::Real, true, true>(4,
                                                                                               301);
}
TYPED_TEST(P2G, ColoredScatterMatchesSerialSingleFieldTile8) {
  check_colored<TypeParam::D, typename TypeParam::Shape, typename TypeParam::Real, false, false>(
      8, 302);
}
TYPED_TEST(P2G, ColoredScatterMatchesSerialMultiFieldNoTraction) {
  check_colored<TypeParam::D, typename TypeParam::Shape, typename TypeParam::Real, true, false>(
      TypeParam::D == 2 ? 8 : 4, 303);
}

// kernels/p2g_multimaterial.hpp: mx, vol and g scattered only from the
// tiles that reach a multimaterial node equal, bitwise at every
// multimaterial node and field, those of the scatter of every particle
// (the solver's claim that the pass changes no result). Grid 37 x 29 (2D)
// or 13 x 12 x 11 (3D) cells, tile edge 4, 6000 / 4000 random particles in
// 2 fields: `banded` puts field 1 in a slab of x (a band of multimaterial
// nodes, most tiles skipped), else fields are mixed at random (nearly every
// node multimaterial). The arrays start as NaN, so a node the pass should
// have zeroed and did not shows up. Also on 2 threads, which must match 1.
template <int D, class Shape, class Real>
void check_multimaterial_fields(bool banded, double band_shift, unsigned seed) {
  const bool gimp = std::string(Shape::name) == "gimp";
  const std::size_t n = D == 2 ? 6000 : 4000;
  Grid<D, Real> full(grid_cells<D>(), 2), reach(grid_cells<D>(), 2), reach2(grid_cells<D>(), 2);
  auto p = random_particles<D, Real>(full.G, full.cells, n, seed);
  if (banded) {
    const double mid =
        double(full.G.origin[0]) + (0.5 * full.cells[0] + band_shift) * double(full.G.h[0]);
    for (std::size_t i = 0; i < n; ++i)
      p.field[i] = std::uint8_t(std::abs(double(p.x[0][i]) - mid) < 2.3 * double(full.G.h[0]));
  }
  P2GOptions opt;
  opt.inv_thickness = 0.5;
  TileLayout<D> tiles;
  tiles.setup(4, full.cells);
  auto sorted = p.permuted(sort_by_tile<Shape>(p, full.G, tiles));
  const auto P = sorted.view(gimp);
  TileSchedule r;
  r.build(tiles, sorted.key.data(), n);

  colored_p2g<D, Shape, Real, kAll, true, true>(P, full.G, opt, r, 1);
  std::vector<std::uint32_t> nodes;
  find_multimaterial_nodes(full.G, Real(0), nodes);
  ASSERT_FALSE(nodes.empty());
  ReachTiles rt;
  std::size_t tiles_used[2] = {0, 0};
  int k = 0;
  for (Grid<D, Real>* g : {&reach, &reach2}) {
    for (auto& a : g->arrays) std::fill(a.begin(), a.end(), std::numeric_limits<Real>::quiet_NaN());
    omp_set_num_threads(k + 1);
    const std::size_t reaching = find_reach_tiles<D, Shape, Real>(g->G, tiles, r, nodes, rt);
    EXPECT_GT(reaching, 0u);
    EXPECT_EQ((p2g_multimaterial_fields<D, Shape, Real>(P, g->G, opt, tiles, r, rt, true, k == 1)),
              SIZE_MAX);
    for (const auto& list : rt.tiles) tiles_used[k] += list.size();
    ++k;
  }
  omp_set_num_threads(2);
  std::size_t all_tiles = 0;
  for (const auto& list : r.tiles) all_tiles += list.size();
  EXPECT_EQ(tiles_used[0], tiles_used[1]);
  // 2D: 10 tile columns, the band's nodes reach 4 (3D: the particles fill 3
  // tile columns, all reached, too small a grid to show the skip).
  if (!banded) {
    EXPECT_EQ(tiles_used[0], all_tiles) << "mixed fields: every tile reaches some node";
  } else if (D == 2) {
    EXPECT_LT(tiles_used[0], all_tiles / 2) << "a band of nodes skips most tiles";
  }

  std::vector<const Real*> arrays_full{full.G.vol}, arrays_reach{reach.G.vol},
      arrays_reach2{reach2.G.vol};
  for (int d = 0; d < D; ++d) {
    arrays_full.insert(arrays_full.end(), {full.G.mx[d], full.G.g[d]});
    arrays_reach.insert(arrays_reach.end(), {reach.G.mx[d], reach.G.g[d]});
    arrays_reach2.insert(arrays_reach2.end(), {reach2.G.mx[d], reach2.G.g[d]});
  }
  std::size_t checked = 0, nonzero = 0;
  for (std::size_t a = 0; a < arrays_full.size(); ++a)
    for (const std::uint32_t node : nodes)
      for (int f = 0; f < 2; ++f) {
        const std::size_t i = full.G.at(f, node);
        ++checked;
        nonzero += arrays_full[a][i] != Real(0);
        ASSERT_EQ(std::memcmp(&arrays_full[a][i], &arrays_reach[a][i], sizeof(Real)), 0)
            << "array " << a << ", node " << node << ", field " << f << ": "
            << double(arrays_full[a][i]) << " (all tiles) vs " << double(arrays_reach[a][i]);
        ASSERT_EQ(std::memcmp(&arrays_reach2[a][i], &arrays_reach[a][i], sizeof(Real)), 0)
            << "2 threads vs 1, array " << a << ", node " << node << ", field " << f;
      }
  EXPECT_GT(nonzero, checked / 2) << "the compared values are mostly real sums, not zeros";
}

// The band's edges moved through a tile (quarter cells), so that the nodes
// a tile reaches only through its particles' far stencil nodes are hit.
TYPED_TEST(P2G, MultimaterialFieldsFromReachingTilesMatchFullScatterBand) {
  for (int k = 0; k < 16; ++k) {
    SCOPED_TRACE("band shifted by " + std::to_string(0.25 * k) + " cells");
    check_multimaterial_fields<TypeParam::D, typename TypeParam::Shape, typename TypeParam::Real>(
        true, 0.25 * k, 311 + unsigned(k));
  }
}
TYPED_TEST(P2G, MultimaterialFieldsFromReachingTilesMatchFullScatterMixed) {
  check_multimaterial_fields<TypeParam::D, typename TypeParam::Shape, typename TypeParam::Real>(
      false, 0.0, 312);
}

// kernels/separation_extrapolation.hpp: for a displacement field affine in
// x, u(x) = A x + b with its own A and b in each field, the extrapolated mx /
// m at every multimaterial node is u(x_node) (the centroid's mx / m is off
// it by A (x_centroid - x_node), up to 3/8 cell). Particles on a lattice of 2
// per cell per direction (the spread the extrapolation needs, and a node
// sqrt(3) standard deviations from its centroid, within
// kMaxExtrapolation), equal masses, field 1 for x above a grid line (2D 37 x 29, 3D 13 x 12 x 11
// cells of 0.5 x 0.4 (x 0.6)), so the nodes on and next to that line are
// multimaterial. Exact on the line, relative to the largest |u|: 1e-11 in
// double, 2e-5 in float; off it u is read within the stencil (B-splines reach
// a node 1.25 cells from one particle row, which gives no normal gradient).
// 2 threads give the 1-thread bits.
template <int D, class Shape, class Real>
void check_extrapolated_separation(unsigned seed) {
  const bool gimp = std::string(Shape::name) == "gimp";
  const std::array<int, 3> cells = grid_cells<D>();
  Grid<D, Real> g1(cells, 2), g2(cells, 2);
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> U(-1.0, 1.0);
  double A[2][3][3], b[2][3];
  for (auto& Af : A)
    for (auto& row : Af)
      for (double& a : row) a = 0.01 * U(rng);
  for (auto& bf : b)
    for (double& c : bf) c = 0.05 * U(rng);
  const auto& G = g1.G;
  const double x_line = double(G.origin[0]) + std::floor(0.5 * cells[0]) * double(G.h[0]);
  auto u_of = [&](int f, const double* x, int d) {
    double u = b[f][d];
    for (int e = 0; e < D; ++e) u += A[f][d][e] * x[e];
    return u;
  };
  Particles<D, Real> p;
  std::array<int, 3> per{1, 1, 1};  // particles per direction: 2 per cell, 3 cells in from the edge
  for (int d = 0; d < D; ++d) per[d] = 2 * (cells[d] - 6);
  const std::size_t n = std::size_t(per[0]) * std::size_t(per[1]) * std::size_t(per[2]);
  p.n = n;
  for (int d = 0; d < D; ++d)
    for (auto* a : {&p.x[d], &p.v[d], &p.x0[d], &p.lp[d], &p.fext[d]}) a->assign(n, Real(0));
  p.m.resize(n);
  p.V.assign(n, Real(0.01));
  for (auto& c : p.s) c.assign(n, Real(0));
  p.field.resize(n);
  p.key.assign(n, 0);
  for (std::size_t i = 0; i < n; ++i) {
    std::size_t rest = i;
    double x[3] = {0, 0, 0};
    for (int d = 0; d < D; ++d) {
      const std::size_t k = rest % std::size_t(per[d]);
      rest /= std::size_t(per[d]);
      x[d] = double(G.origin[d]) + (3.0 + 0.25 + 0.5 * double(k)) * double(G.h[d]);
      p.x[d][i] = Real(x[d]);
      p.lp[d][i] = Real(0.25);
    }
    const int f = x[0] > x_line ? 1 : 0;
    p.field[i] = std::uint8_t(f);
    p.m[i] = Real(1.5);
    for (int d = 0; d < D; ++d) p.x0[d][i] = Real(x[d] - u_of(f, x, d));
  }
  P2GOptions opt;
  opt.inv_thickness = 0.5;
  TileLayout<D> tiles;
  tiles.setup(4, cells);
  auto sorted = p.permuted(sort_by_tile<Shape>(p, G, tiles));
  const auto P = sorted.view(gimp);
  TileSchedule r;
  r.build(tiles, sorted.key.data(), n);

  std::vector<std::vector<Real>> moments[2];
  std::vector<std::uint32_t> nodes;
  int threads = 1;
  for (Grid<D, Real>* g : {&g1, &g2}) {
    colored_p2g<D, Shape, Real, kAll, true, false>(P, g->G, opt, r, 1);
    find_multimaterial_nodes(g->G, Real(0), nodes);
    ASSERT_FALSE(nodes.empty());
    ReachTiles rt;
    find_reach_tiles<D, Shape, Real>(g->G, tiles, r, nodes, rt);
    SeparationMoments<D, Real> M;
    auto& store = moments[threads - 1];
    store.assign(std::size_t(D + M.kSym + D * D),
                 std::vector<Real>(g->G.nodes * 2, std::numeric_limits<Real>::quiet_NaN()));
    std::size_t k = 0;
    for (int a = 0; a < D; ++a) M.r[a] = store[k++].data();
    for (int a = 0; a < M.kSym; ++a) M.rr[std::size_t(a)] = store[k++].data();
    for (int a = 0; a < D * D; ++a) M.ur[std::size_t(a)] = store[k++].data();
    omp_set_num_threads(threads);
    std::vector<std::uint8_t> listed;
    EXPECT_EQ((extrapolate_separation<D, Shape, Real>(P, g->G, M, r, rt, nodes, nullptr, Real(0),
                                                      listed, threads == 2)),
              SIZE_MAX);
    EXPECT_EQ(std::count(listed.begin(), listed.end(), std::uint8_t(1)), 0) << "flags left set";
    ++threads;
  }
  omp_set_num_threads(2);

  double scale = 0;
  for (int f = 0; f < 2; ++f)
    for (int d = 0; d < D; ++d) scale = std::max(scale, std::abs(b[f][d]) + 0.2);
  const double tol = (sizeof(Real) == 8 ? 1e-11 : 2e-5) * scale;
  // What the paper's centroid reads: the same sums without the shift.
  Grid<D, Real> plain(cells, 2);
  colored_p2g<D, Shape, Real, kAll, true, false>(P, plain.G, opt, r, 1);
  double norm_A[2] = {0, 0}, max_h = 0;
  for (int f = 0; f < 2; ++f)
    for (int d = 0; d < D; ++d)
      for (int e = 0; e < D; ++e) norm_A[f] += A[f][d][e] * A[f][d][e];
  for (double& a : norm_A) a = std::sqrt(a);
  for (int d = 0; d < D; ++d) max_h = std::max(max_h, double(G.h[d]));
  double worst_on_line = 0, centroid_on_line = 0;
  std::size_t on_line = 0;
  for (const std::uint32_t node : nodes) {
    const auto xn = G.position(node);
    const double x[3] = {double(xn[0]), double(xn[1]), double(xn[2])};
    // On the line and inside the particles' box (its ends reach fields from afar too).
    bool line = std::abs(x[0] - x_line) < 1e-3 * double(G.h[0]);
    for (int d = 1; d < D; ++d)
      line = line && x[d] > double(G.origin[d]) + 3.5 * double(G.h[d]) &&
             x[d] < double(G.origin[d]) + (cells[d] - 3.5) * double(G.h[d]);
    on_line += line;
    for (int f = 0; f < 2; ++f) {
      const std::size_t i = G.at(f, node);
      for (int d = 0; d < D; ++d) {
        ASSERT_EQ(std::memcmp(&g1.G.mx[d][i], &g2.G.mx[d][i], sizeof(Real)), 0)
            << "2 threads vs 1, node " << node << ", field " << f;
        const double exact = u_of(f, x, d);
        const double err = std::abs(double(g1.G.mx[d][i]) / double(g1.G.m[i]) - exact);
        const double centroid_err =
            std::abs(double(plain.G.mx[d][i]) / double(plain.G.m[i]) - exact);
        // Off the line, a field can reach a node with one particle row (B-splines:
        // 1.25 cells away); that direction keeps its centroid's coordinate, so u is
        // read at a point of the stencil: within |A| times its width.
        ASSERT_LE(err, norm_A[f] * Shape::S * max_h + tol)
            << "node " << node << ", field " << f << ", " << d;
        if (line) {
          worst_on_line = std::max(worst_on_line, err);
          centroid_on_line = std::max(centroid_on_line, centroid_err);
        }
      }
    }
  }
  std::printf(
      "[extrapolated separation %s] %zu nodes on the interface: |u - u(x_node)| %.2e "
      "(centroid %.2e)\n",
      Shape::name, on_line, worst_on_line, centroid_on_line);
  EXPECT_GT(on_line, 0u);
  EXPECT_LT(worst_on_line, tol);
  EXPECT_GT(centroid_on_line, 100 * tol) << "the centroid is off the node: the test can fail";
}

TYPED_TEST(P2G, ExtrapolatedSeparationIsExactForAffineDisplacements) {
  check_extrapolated_separation<TypeParam::D, typename TypeParam::Shape, typename TypeParam::Real>(
      413);
}

// The multimaterial node search reading only the nodes of tiles next to
// particles of two fields (kernels/mixed_tiles.hpp) lists the same nodes as
// the full scan. Fields split by the plane x = mid + shift (the two-layer
// scene's one interface), the plane moved through a tile in quarter cells,
// with one particle of field 1 deep inside field 0 (a patch of its own); and
// fields mixed everywhere, where every node is read. On 1 and 2 threads.
template <int D, class Shape, class Real>
void check_mixed_tile_search(bool split, double shift, unsigned seed) {
  const bool gimp = std::string(Shape::name) == "gimp";
  const std::size_t n = D == 2 ? 6000 : 4000;
  Grid<D, Real> g(grid_cells<D>(), 2);
  auto p = random_particles<D, Real>(g.G, g.cells, n, seed);
  const double h = double(g.G.h[0]), x0 = double(g.G.origin[0]);
  if (split) {
    const double mid = x0 + (0.5 * g.cells[0] + shift) * h;
    for (std::size_t i = 0; i < n; ++i) p.field[i] = std::uint8_t(double(p.x[0][i]) > mid);
    p.x[0][0] = Real(x0 + 3.3 * h);  // the lone particle of field 1
    p.field[0] = 1;
  }
  TileLayout<D> tiles;
  tiles.setup(4, g.cells);
  auto sorted = p.permuted(sort_by_tile<LinearShape>(p, g.G, tiles));
  TileSchedule r;
  r.build(tiles, sorted.key.data(), n);
  colored_p2g<D, Shape, Real, kMassMomentum, true, false>(sorted.view(gimp), g.G, P2GOptions{}, r,
                                                          1);
  std::vector<std::uint32_t> full;
  find_multimaterial_nodes(g.G, Real(0), full);
  ASSERT_FALSE(full.empty());
  MixedTiles<D> mixed;
  mixed.build(tiles, g.G.nodes_per_dim, r.begin, sorted.field.data());
  std::vector<std::uint32_t> list;
  find_multimaterial_nodes(g.G, Real(0), list, NodeOwnership{}, &mixed);
  EXPECT_EQ(list, full);
  const int saved = omp_get_max_threads();
  omp_set_num_threads(2);
  NodeOwnership own;
  own.split = {0, g.G.nodes / 3, g.G.nodes};
  std::vector<std::uint32_t> owned;
  find_multimaterial_nodes(g.G, Real(0), owned, own, &mixed);
  omp_set_num_threads(saved);
  EXPECT_EQ(owned, full);
  // 2D: 10 tile columns, the plane's neighbourhood is 3 or 4 of them (3D:
  // too small a grid to leave a tile out).
  const std::size_t scanned = mixed.mixed_node_count();
  if (!split) {
    EXPECT_EQ(scanned, g.G.nodes);
  } else if (D == 2) {
    EXPECT_LT(scanned, g.G.nodes / 2) << "the search skips the single-field tiles";
  }
}

TYPED_TEST(P2G, MixedTileSearchListsTheFullScansNodesSplit) {
  for (int k = 0; k < 16; ++k) {
    SCOPED_TRACE("plane shifted by " + std::to_string(0.25 * k) + " cells");
    check_mixed_tile_search<TypeParam::D, typename TypeParam::Shape, typename TypeParam::Real>(
        true, 0.25 * k, 511 + unsigned(k));
  }
}
TYPED_TEST(P2G, MixedTileSearchListsTheFullScansNodesMixed) {
  check_mixed_tile_search<TypeParam::D, typename TypeParam::Shape, typename TypeParam::Real>(
      false, 0.0, 512);
}

// Particles over the whole range a shape allows (window.hpp: linear
// [0, n-1), uGIMP/quadratic [1/2, n-3/2), cubic [1, n-2) in cell units),
// every second one within 1.5 cells of the low or high edge in a random
// direction.
template <int D, class Shape, class Real>
void spread_to_edges(Particles<D, Real>& p, const GridView<D, Real>& G, unsigned seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> U(0.0, 1.0);
  const double lo = Shape::W == 2 ? 0.0 : (Shape::S == 3 ? 0.5 : 1.0);
  const double margin = Shape::W == 2 ? 1.0 : (Shape::S == 3 ? 1.5 : 2.0);
  for (std::size_t i = 0; i < p.n; ++i) {
    const int edge_dim = int(U(rng) * D);
    for (int d = 0; d < D; ++d) {
      const double hi = double(G.nodes_per_dim[d]) - margin;
      double xi = lo + (hi - lo) * U(rng);
      if (i % 2 == 0 && d == edge_dim) xi = U(rng) < 0.5 ? lo + 1.5 * U(rng) : hi - 1.5 * U(rng);
      xi = std::min(std::max(xi, lo), std::nextafter(hi, lo) - 1e-6);
      p.x[d][i] = Real(double(G.origin[d]) + xi * double(G.h[d]));
      // Keep the Real position inside the range after rounding.
      const double back = (double(p.x[d][i]) - double(G.origin[d])) / double(G.h[d]);
      if (back < lo || back >= hi)
        p.x[d][i] = Real(double(G.origin[d]) + (lo + hi) * 0.5 * double(G.h[d]));
    }
  }
}

template <class Real>
double max_rel_diff(const std::vector<Real>& a, const std::vector<Real>& b, double& scale) {
  double diff = 0;
  scale = 0;
  for (std::size_t k = 0; k < a.size(); ++k) {
    scale = std::max(scale, std::abs(double(b[k])));
    diff = std::max(diff, std::abs(double(a[k]) - double(b[k])));
  }
  return scale > 0 ? diff / scale : diff;
}

template <int D, class Shape, class Real>
void check_window_p2g(bool edges, bool sorted, unsigned seed) {
  const bool gimp = std::string(Shape::name) == "gimp";
  Grid<D, Real> win(grid_cells<D>(), 2), ref(grid_cells<D>(), 2);
  const std::size_t n = D == 2 ? 6000 : 4000;
  auto p = random_particles<D, Real>(win.G, win.cells, n, seed);
  if (edges) spread_to_edges<D, Shape, Real>(p, win.G, seed + 1);
  if (sorted) {
    TileLayout<D> tiles;
    tiles.setup(4, win.cells);
    p = p.permuted(sort_by_tile<Shape>(p, win.G, tiles));
  }
  const auto P = p.view(gimp);
  P2GOptions opt;
  opt.inv_thickness = 0.5;
  ASSERT_EQ((p2g_range<D, Shape, Real, kAll, true, true>(P, win.G, opt, 0, n)), n);
  ASSERT_EQ((p2g_range_pointwise<D, Shape, Real, kAll, true, true>(P, ref.G, opt, 0, n)), n);
  const double tol = conservation_tol<Real>();
  for (std::size_t a = 0; a < win.arrays.size(); ++a) {
    double scale = 0;
    const double rel = max_rel_diff(win.arrays[a], ref.arrays[a], scale);
    EXPECT_GT(scale, 0.0) << "array " << a << " was filled";
    EXPECT_LE(rel, tol) << "array " << a << ": windowed vs pointwise scatter";
  }
  // The momentum-only transfer (MUSL's second P2G) on its own.
  Grid<D, Real> win2(grid_cells<D>(), 2), ref2(grid_cells<D>(), 2);
  ASSERT_EQ((p2g_range<D, Shape, Real, kMomentumOnly, true, false>(P, win2.G, opt, 0, n)), n);
  ASSERT_EQ((p2g_range_pointwise<D, Shape, Real, kMomentumOnly, true, false>(P, ref2.G, opt, 0, n)),
            n);
  for (int d = 0; d < D; ++d) {
    double scale = 0;
    EXPECT_LE(max_rel_diff(win2.arrays[std::size_t(1 + d)], ref2.arrays[std::size_t(1 + d)], scale),
              tol)
        << "momentum " << d;
    EXPECT_EQ(win2.sum(win2.G.m), 0.0) << "momentum-only transfer left the mass alone";
  }
}

TYPED_TEST(P2G, WindowedScatterMatchesPointwise) {
  check_window_p2g<TypeParam::D, typename TypeParam::Shape, typename TypeParam::Real>(false, true,
                                                                                      401);
}
TYPED_TEST(P2G, WindowedScatterMatchesPointwiseAtGridEdgesUnsorted) {
  check_window_p2g<TypeParam::D, typename TypeParam::Shape, typename TypeParam::Real>(true, false,
                                                                                      402);
}

// Two scatters, first(P, G, opt, n) and second(...), of particle set p into
// fresh grids: the same stopping particle, every grid array bitwise equal.
template <int D, class Shape, class Real, class First, class Second>
void expect_same_scatter_bits(Particles<D, Real> p, std::size_t stop_at, const std::string& what,
                              First first, Second second) {
  const bool gimp = std::string(Shape::name) == "gimp";
  Grid<D, Real> one(grid_cells<D>(), 2), two(grid_cells<D>(), 2);
  const auto P = p.view(gimp);
  P2GOptions opt;
  opt.inv_thickness = 0.5;
  const std::size_t n = p.n, expect = std::min(stop_at, n);
  ASSERT_EQ(first(P, one.G, opt, n), expect) << what;
  ASSERT_EQ(second(P, two.G, opt, n), expect) << what;
  for (std::size_t a = 0; a < one.arrays.size(); ++a)
    for (std::size_t i = 0; i < one.arrays[a].size(); ++i)
      ASSERT_EQ(std::memcmp(&one.arrays[a][i], &two.arrays[a][i], sizeof(Real)), 0)
          << what << ", array " << a << ", entry " << i << ": " << double(one.arrays[a][i])
          << " vs " << double(two.arrays[a][i]);
}

// The grouped scatter (GroupedScatter, kernels/window_block.hpp: the
// window's units in groups of UG, each run of particles with one window
// scattered group by group, a run cut by a batch's end carried into the
// next batch) against the one-block scatter: bitwise the same arrays, for
// several group sizes, with tile-sorted particles (runs of a few per
// window) and with 100 particles in one cell (a run longer than a weight
// batch). Also stops at the same particle off the grid, with the sums
// before it.
template <int D, class Shape, class Real, unsigned What, bool MF, bool TR, int UG>
void check_grouped_matches_one_block(const Particles<D, Real>& p, std::size_t stop_at) {
  expect_same_scatter_bits<D, Shape, Real>(
      p, stop_at, "UG " + std::to_string(UG) + ", What " + std::to_string(What),
      [](const auto& P, const auto& G, const P2GOptions& opt, std::size_t n) {
        return p2g_range_one_block<D, Shape, Real, What, MF, TR>(P, G, opt, 0, n);
      },
      [](const auto& P, const auto& G, const P2GOptions& opt, std::size_t n) {
        return p2g_range_grouped<D, Shape, Real, What, MF, TR, UG>(P, G, opt, 0, n);
      });
}

template <int D, class Shape, class Real, int UG>
void check_grouped_all_quantities(const Particles<D, Real>& p, std::size_t stop_at) {
  check_grouped_matches_one_block<D, Shape, Real, kAll, true, true, UG>(p, stop_at);
  check_grouped_matches_one_block<D, Shape, Real, kMassMomentum | kForce, false, false, UG>(
      p, stop_at);
  check_grouped_matches_one_block<D, Shape, Real, kMultimaterial | kDomainGradient, true, false,
                                  UG>(p, stop_at);
  check_grouped_matches_one_block<D, Shape, Real, kMomentumOnly, true, false, UG>(p, stop_at);
}

// The particle sets of the block comparisons (grouped, two-row and packed
// scatters, packed gathers): random particles in tile order (2 fields, runs
// of 1-6 per cell; 6000 in 2D, 4000 in 3D), 100 particles of field
// `crowded_field` in one cell (a run across 4 batches of 32), and the sorted
// set with particle `bad` off the grid.
template <int D, class Shape, class Real>
struct BlockTestSets {
  static constexpr std::size_t bad = 1235;
  Grid<D, Real> g{grid_cells<D>(), 2};
  Particles<D, Real> sorted, crowded, off_grid;
  BlockTestSets(unsigned seed, std::uint8_t crowded_field) {
    TileLayout<D> tiles;
    tiles.setup(4, g.cells);
    auto random = random_particles<D, Real>(g.G, g.cells, D == 2 ? 6000 : 4000, seed);
    sorted = random.permuted(sort_by_tile<Shape>(random, g.G, tiles));
    crowded = random_particles<D, Real>(g.G, g.cells, 100, seed + 1);
    for (std::size_t i = 0; i < crowded.n; ++i) {
      crowded.field[i] = crowded_field;
      for (int d = 0; d < D; ++d)
        crowded.x[d][i] =
            Real(double(g.G.origin[d]) + (5.3 + 0.4 * double(i % 7) / 7.0) * double(g.G.h[d]));
    }
    off_grid = sorted;
    off_grid.x[1][bad] = Real(1e6);
  }
  // f(list, the particle the kernels must stop at or SIZE_MAX).
  template <class F>
  void each(F&& f) const {
    f(sorted, SIZE_MAX);
    f(crowded, SIZE_MAX);
    f(off_grid, bad);
  }
};
template <class Real>
using PackedTestSets = BlockTestSets<2, LinearShape, Real>;

TYPED_TEST(P2G, GroupedScatterGivesTheOneBlockSumsBitwise) {
  constexpr int D = TypeParam::D;
  using Shape = typename TypeParam::Shape;
  using Real = typename TypeParam::Real;
  constexpr int U = ScatterUnits<D, Shape, Real>::units;
  const BlockTestSets<D, Shape, Real> sets(901, 1);
  sets.each([](const Particles<D, Real>& list, std::size_t stop_at) {
    // Groups of 1, 2 and 3 units: with 5 units (3D uGIMP and quadratic
    // B-splines in double) 2 and 3 leave a short last group, as do 3 of 4
    // and 3 of 8.
    check_grouped_all_quantities<D, Shape, Real, 1>(list, stop_at);
    if constexpr (U > 2) check_grouped_all_quantities<D, Shape, Real, 2>(list, stop_at);
    if constexpr (U > 3) check_grouped_all_quantities<D, Shape, Real, 3>(list, stop_at);
  });
}

// The scatters' units of two rows (ScatterUnits, kernels/window.hpp: 3D
// uGIMP and quadratic B-splines in double, 5 units with a padded last one)
// against Window's one-row units (RowUnits): every grid array bitwise the
// same, for every quantity set the solver scatters, through p2g_range as the
// solver calls it (grouped blocks), and the same stopping particle. Cases
// where the two layouts are the same type are skipped.
template <int D, class Shape, class Real, unsigned What, bool MF, bool TR>
void check_scatter_units_match_rows(const Particles<D, Real>& p, std::size_t stop_at) {
  expect_same_scatter_bits<D, Shape, Real>(
      p, stop_at, "What " + std::to_string(What),
      [](const auto& P, const auto& G, const P2GOptions& opt, std::size_t n) {
        return p2g_range<D, Shape, Real, What, MF, TR, RowUnits<D, Shape, Real>>(P, G, opt, 0, n);
      },
      [](const auto& P, const auto& G, const P2GOptions& opt, std::size_t n) {
        return p2g_range<D, Shape, Real, What, MF, TR>(P, G, opt, 0, n);
      });
}

TYPED_TEST(P2G, TwoRowScatterUnitsGiveTheOneRowSumsBitwise) {
  constexpr int D = TypeParam::D;
  using Shape = typename TypeParam::Shape;
  using Real = typename TypeParam::Real;
  if constexpr (std::is_same_v<ScatterUnits<D, Shape, Real>, RowUnits<D, Shape, Real>>) {
    GTEST_SKIP() << "one layout";
  } else {
    static_assert(ScatterUnits<D, Shape, Real>::units < RowUnits<D, Shape, Real>::units);
    const BlockTestSets<D, Shape, Real> sets(905, 1);
    sets.each([](const Particles<D, Real>& list, std::size_t stop_at) {
      check_scatter_units_match_rows<D, Shape, Real, kAll, true, true>(list, stop_at);
      check_scatter_units_match_rows<D, Shape, Real, kMassMomentum | kForce, false, false>(list,
                                                                                           stop_at);
      check_scatter_units_match_rows<D, Shape, Real, kMultimaterial | kDomainGradient, true, false>(
          list, stop_at);
      check_scatter_units_match_rows<D, Shape, Real, kMomentumOnly, true, false>(list, stop_at);
    });
  }
}

// The packed 2D linear scatter (kernels/p2g_packed.hpp: K particles per
// vector, each run of one window summed slot by slot) against the one-block
// scatter (one particle per vector): the same sums in another order, so
// equal to 1e-12 (double) / 2e-5 (float) of each array's largest magnitude,
// on tile-sorted particles (runs of 1-6, odd runs leaving empty slots,
// field changes inside a cell), on 100 particles in one cell (a run longer
// than a weight batch, carried from batch to batch) and with a particle off
// the grid (both stop there, with the sums before it). Every quantity set
// the solver scatters.
template <class Real, unsigned What, bool MF, bool TR>
void check_packed_matches_one_block(Particles<2, Real> p, std::size_t stop_at) {
  Grid<2, Real> one(grid_cells<2>(), 2), packed(grid_cells<2>(), 2);
  const auto P = p.view(false);
  P2GOptions opt;
  opt.inv_thickness = 0.5;
  const std::size_t n = p.n, expect = std::min(stop_at, n);
  ASSERT_EQ((p2g_range_one_block<2, LinearShape, Real, What, MF, TR>(P, one.G, opt, 0, n)), expect);
  ASSERT_EQ((p2g_range_packed<Real, What, MF, TR>(P, packed.G, opt, 0, n)), expect);
  const double tol = conservation_tol<Real>();
  for (std::size_t a = 0; a < one.arrays.size(); ++a) {
    double scale = 0;
    const double rel = max_rel_diff(packed.arrays[a], one.arrays[a], scale);
    EXPECT_LE(rel, tol) << "What " << What << ", array " << a;
  }
}

template <class Real>
void check_packed_all_quantities() {
  static_assert(packed_particles<2, LinearShape, Real>() > 1);
  const PackedTestSets<Real> t(911, 1);
  t.each([](const Particles<2, Real>& list, std::size_t stop_at) {
    check_packed_matches_one_block<Real, kAll, true, true>(list, stop_at);
    check_packed_matches_one_block<Real, kMassMomentum | kForce, false, false>(list, stop_at);
    check_packed_matches_one_block<Real, kMassMomentum | kForce, true, true>(list, stop_at);
    check_packed_matches_one_block<Real, kMassMomentum, false, false>(list, stop_at);
    check_packed_matches_one_block<Real, kForce, true, false>(list, stop_at);
    check_packed_matches_one_block<Real, kMultimaterial, true, false>(list, stop_at);
    check_packed_matches_one_block<Real, kMomentumOnly, true, false>(list, stop_at);
  });
}

#ifdef __AVX512F__
TEST(PackedLinearScatter, MatchesTheOneParticleBlockDouble) {
  check_packed_all_quantities<double>();
}
TEST(PackedLinearScatter, MatchesTheOneParticleBlockFloat) {
  check_packed_all_quantities<float>();
}
#endif

// A particle whose stencil leaves the grid is reported by both kernels at
// the same index.
TYPED_TEST(P2G, WindowedScatterReportsTheSameParticleOffTheGrid) {
  constexpr int D = TypeParam::D;
  using Shape = typename TypeParam::Shape;
  using Real = typename TypeParam::Real;
  Grid<D, Real> a(grid_cells<D>(), 1), b(grid_cells<D>(), 1);
  auto p = random_particles<D, Real>(a.G, a.cells, 200, 403);
  std::fill(p.field.begin(), p.field.end(), std::uint8_t(0));
  p.x[0][117] =
      a.G.origin[0] + Real(0.2) * a.G.h[0];  // too close to the low x edge for any shape but linear
  if (Shape::W == 2) p.x[0][117] = a.G.origin[0] - Real(0.2) * a.G.h[0];
  const auto P = p.view(std::string(Shape::name) == "gimp");
  EXPECT_EQ((p2g_range<D, Shape, Real, kMassMomentum, false, false>(P, a.G, P2GOptions{}, 0, 200)),
            117u);
  EXPECT_EQ((p2g_range_pointwise<D, Shape, Real, kMassMomentum, false, false>(P, b.G, P2GOptions{},
                                                                              0, 200)),
            117u);
}

// G2P: the solver's windowed gather against the pointwise reference, on a
// smooth random grid velocity field, all outputs (v, x, L).
// Random grid velocities (U(-1, 1)) and velocity changes (0.1 U(-1, 1)).
template <int D, class Real>
struct RandomGridVelocity {
  std::vector<std::vector<Real>> vel, dvel;
  GridVelocity<D, Real> V;
  RandomGridVelocity(std::size_t total, unsigned seed)
      : vel(D, std::vector<Real>(total)), dvel(D, std::vector<Real>(total)) {
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> U(-1.0, 1.0);
    for (int d = 0; d < D; ++d) {
      for (std::size_t i = 0; i < total; ++i)
        vel[d][i] = Real(U(rng)), dvel[d][i] = Real(0.1 * U(rng));
      V.vel[d] = vel[d].data();
      V.dvel[d] = dvel[d].data();
    }
  }
};

struct NoKeys {
  bool any_moved(const std::uint32_t*, std::size_t, std::size_t) const { return false; }
};

template <int D, class Shape, class Real>
void check_window_g2p(bool edges, unsigned seed) {
  const bool gimp = std::string(Shape::name) == "gimp";
  Grid<D, Real> g(grid_cells<D>(), 2);
  RandomGridVelocity<D, Real> gv(g.G.nodes * 2, seed);
  const GridVelocity<D, Real>& V = gv.V;
  const std::size_t n = D == 2 ? 6000 : 4000;
  auto base = random_particles<D, Real>(g.G, g.cells, n, seed);
  if (edges) spread_to_edges<D, Shape, Real>(base, g.G, seed + 1);
  auto a = base, b = base;
  std::array<std::vector<Real>, D * D> La, Lb;
  for (auto& l : La) l.assign(n, 0);
  for (auto& l : Lb) l.assign(n, 0);
  auto Pa = a.view(gimp), Pb = b.view(gimp);
  for (int c = 0; c < D * D; ++c) Pa.L[c] = La[c].data(), Pb.L[c] = Lb[c].data();
  G2PParams q;
  q.dt = 0.01;
  q.flip = 0.9;
  constexpr unsigned What = kUpdateMotion | kVelocityGradient;
  // The windowed gather itself (g2p_range picks the pointwise one for linear shapes).
  const auto ra =
      g2p_range_impl<D, Shape, Real, What, true, true, false, true>(Pa, g.G, V, q, NoKeys{}, 0, n);
  const auto rb =
      g2p_range_pointwise<D, Shape, Real, What, true, true, false>(Pb, g.G, V, q, NoKeys{}, 0, n);
  ASSERT_EQ(ra.bad, SIZE_MAX);
  ASSERT_EQ(rb.bad, SIZE_MAX);
  const double tol = conservation_tol<Real>();
  EXPECT_NEAR(ra.external_work, rb.external_work, tol * (1 + std::abs(rb.external_work)));
  for (int d = 0; d < D; ++d) {
    double scale = 0;
    EXPECT_LE(max_rel_diff(a.v[d], b.v[d], scale), tol) << "velocity " << d;
    // Positions: compare the displacement dt * v_grid, relative to its own size.
    std::vector<Real> ua(n), ub(n);
    for (std::size_t i = 0; i < n; ++i)
      ua[i] = a.x[d][i] - base.x[d][i], ub[i] = b.x[d][i] - base.x[d][i];
    EXPECT_LE(max_rel_diff(ua, ub, scale), sizeof(Real) == 8 ? 1e-9 : 2e-2) << "displacement " << d;
  }
  for (int c = 0; c < D * D; ++c) {
    double scale = 0;
    EXPECT_LE(max_rel_diff(La[c], Lb[c], scale), tol) << "velocity gradient " << c;
    EXPECT_GT(scale, 0.0);
  }
}

TYPED_TEST(P2G, WindowedGatherMatchesPointwise) {
  check_window_g2p<TypeParam::D, typename TypeParam::Shape, typename TypeParam::Real>(false, 501);
}
TYPED_TEST(P2G, WindowedGatherMatchesPointwiseAtGridEdges) {
  check_window_g2p<TypeParam::D, typename TypeParam::Shape, typename TypeParam::Real>(true, 502);
}

// The velocity gradients and end positions two G2P kernels write, for two
// copies a, b of one particle set: L zeroed; x_next starting at x (what a
// motion pass wrote), given to the views only when x_next.
template <int D, class Real>
struct GatherOutputs {
  std::array<std::vector<Real>, D * D> La, Lb;
  std::array<std::vector<Real>, D> xa, xb;
  GatherOutputs(const Particles<D, Real>& a, ParticleView<D, Real>& Pa, ParticleView<D, Real>& Pb,
                bool x_next) {
    for (std::size_t c = 0; c < std::size_t(D * D); ++c) {
      La[c].assign(a.n, 0), Lb[c].assign(a.n, 0);
      Pa.L[c] = La[c].data(), Pb.L[c] = Lb[c].data();
    }
    for (std::size_t d = 0; d < std::size_t(D); ++d) {
      xa[d] = a.x[d], xb[d] = a.x[d];
      if (x_next) Pa.x_next[d] = xa[d].data(), Pb.x_next[d] = xb[d].data();
    }
  }
};

// Two particles per vector in the 2D and 3D double gathers and the 2D float
// gathers of the shapes binned by the nearest node (G2PGather::gather_pair,
// AVX-512 builds): each particle of a pair gets
// the one-particle gather's bits, in every pass's mix of sums (motion, gradient, both); and a G2P
// range gives the same bits when its start moves by one particle, so that
// other particles pair up (as when a thread's range starts elsewhere).
// Particles come in runs of 1-5 within 0.42 h of one node, in one field,
// so the runs share windows; grid_cells<D>() cells, 2 fields, random grid
// velocities.
template <int D, class Real = double>
Particles<D, Real> node_runs(const Grid<D, Real>& g, std::size_t n, unsigned seed) {
  auto p = random_particles<D, Real>(g.G, g.cells, n, seed);
  std::mt19937_64 rng(seed + 7);
  std::uniform_real_distribution<double> U(0.0, 1.0);
  std::size_t i = 0;
  int field = 0;
  while (i < n) {
    const std::size_t run = std::min<std::size_t>(n - i, 1 + std::size_t(U(rng) * 5));
    double centre[D];
    for (int d = 0; d < D; ++d) {
      const int node = 3 + int(U(rng) * (g.cells[std::size_t(d)] - 6));
      centre[d] = double(g.G.origin[d]) + (node + 0.6 * (U(rng) - 0.5)) * double(g.G.h[d]);
    }
    for (std::size_t k = 0; k < run; ++k, ++i) {
      for (int d = 0; d < D; ++d)
        p.x[d][i] = Real(centre[d] + 0.24 * (U(rng) - 0.5) * double(g.G.h[d]));
      p.field[i] = std::uint8_t(field);
    }
    field ^= 1;
  }
  return p;
}

template <int D, class Shape, class Real, bool Motion, bool Gradient>
void check_pair_gather_bits(unsigned seed) {
  using Gather = G2PGather<D, Shape, Real, true>;
  if constexpr (!Gather::kPairs) {
    GTEST_SKIP() << "the pair gather needs AVX-512";
  } else {
    const bool gimp = std::string(Shape::name) == "gimp";
    Grid<D, Real> g(grid_cells<D>(), 2);
    RandomGridVelocity<D, Real> gv(g.G.nodes * 2, seed);
    const std::size_t n = 600;
    auto p = node_runs<D, Real>(g, n, seed);
    const auto P = p.view(gimp);
    const Gather st(g.G);
    std::vector<typename Gather::Weights> w(n);
    for (std::size_t i = 0; i < n; ++i) ASSERT_TRUE(st.builder.build(P, i, w[i])) << i;
    typename Gather::Held held_one, held_pair;
    int pairs = 0;
    for (std::size_t i = 0; i + 1 < n; ++i) {
      const std::size_t fa = field_offset<true>(P, g.G, i), fb = field_offset<true>(P, g.G, i + 1);
      if (w[i].base + fa != w[i + 1].base + fb) continue;
      Real vn1[2][D] = {}, dv1[2][D] = {}, L1[2][D * D] = {};
      Real vn2[2][D] = {}, dv2[2][D] = {}, L2[2][D * D] = {};
      st.template gather<Motion, Gradient>(w[i], gv.V, fa, held_one, vn1[0], dv1[0], L1[0]);
      st.template gather<Motion, Gradient>(w[i + 1], gv.V, fb, held_one, vn1[1], dv1[1], L1[1]);
      st.template gather_pair<Motion, Gradient>(w[i], w[i + 1], gv.V, w[i].base + fa, held_pair,
                                                vn2, dv2, L2);
      EXPECT_EQ(std::memcmp(vn1, vn2, sizeof vn1), 0) << "v, pair at " << i;
      EXPECT_EQ(std::memcmp(dv1, dv2, sizeof dv1), 0) << "dv, pair at " << i;
      EXPECT_EQ(std::memcmp(L1, L2, sizeof L1), 0) << "L, pair at " << i;
      if (Gradient) {
        EXPECT_NE(L2[1][D + 1], Real(0));
      }
      if (Motion) {
        EXPECT_NE(vn2[1][D - 1], Real(0));
      }
      ++pairs;
    }
    EXPECT_GT(pairs, 300);
  }
}

template <int D, class Shape, class Real = double>
void check_pair_gather_range_start(unsigned seed) {
  const bool gimp = std::string(Shape::name) == "gimp";
  Grid<D, Real> g(grid_cells<D>(), 2);
  RandomGridVelocity<D, Real> gv(g.G.nodes * 2, seed);
  const std::size_t n = 600;
  auto base = node_runs<D, Real>(g, n, seed);
  auto a = base, b = base;
  auto Pa = a.view(gimp), Pb = b.view(gimp);
  GatherOutputs<D, Real> out(a, Pa, Pb, false);
  G2PParams q;
  q.dt = 0.01;
  q.flip = 0.9;
  constexpr unsigned What = kUpdateMotion | kVelocityGradient;
  g2p_range<D, Shape, Real, What, true, true, false>(Pa, g.G, gv.V, q, NoKeys{}, 0, n);
  g2p_range<D, Shape, Real, What, true, true, false>(Pb, g.G, gv.V, q, NoKeys{}, 0, 1);
  g2p_range<D, Shape, Real, What, true, true, false>(Pb, g.G, gv.V, q, NoKeys{}, 1, n);
  for (int d = 0; d < D; ++d) {
    EXPECT_TRUE(bitwise_equal(a.v[d], b.v[d])) << "velocity " << d;
    EXPECT_TRUE(bitwise_equal(a.x[d], b.x[d])) << "position " << d;
  }
  for (int c = 0; c < D * D; ++c) EXPECT_TRUE(bitwise_equal(out.La[c], out.Lb[c])) << "L " << c;
}

// The whole G2P range with pairs (the solver's) and without
// (PairGathers = false) gives the same bits for each pass's mix of work:
// USL's (motion and gradient), MUSL's first pass (motion, momentum
// scattered after the batch) and its gradient pass (moving to x_next).
template <int D, class Shape, unsigned What, class Real = double>
void check_pairs_match_one_per_vector(unsigned seed) {
  const bool gimp = std::string(Shape::name) == "gimp";
  Grid<D, Real> ga(grid_cells<D>(), 2), gb(grid_cells<D>(), 2);
  RandomGridVelocity<D, Real> gv(ga.G.nodes * 2, seed);
  const std::size_t n = 600;
  auto a = node_runs<D, Real>(ga, n, seed), b = a;
  auto Pa = a.view(gimp), Pb = b.view(gimp);
  // x_next as MUSL's motion pass leaves it, for the gradient pass to commit.
  GatherOutputs<D, Real> out(a, Pa, Pb, true);
  const auto& [La, Lb, xa, xb] = out;
  G2PParams q;
  q.dt = 0.01;
  q.flip = 0.9;
  const auto ra = g2p_range_impl<D, Shape, Real, What, true, true, false, true, true>(
      Pa, ga.G, gv.V, q, NoKeys{}, 0, n);
  const auto rb = g2p_range_impl<D, Shape, Real, What, true, true, false, true, false>(
      Pb, gb.G, gv.V, q, NoKeys{}, 0, n);
  ASSERT_EQ(ra.bad, SIZE_MAX);
  ASSERT_EQ(rb.bad, SIZE_MAX);
  for (int d = 0; d < D; ++d) {
    EXPECT_TRUE(bitwise_equal(a.v[d], b.v[d])) << "velocity " << d;
    EXPECT_TRUE(bitwise_equal(a.x[d], b.x[d])) << "position " << d;
    EXPECT_TRUE(bitwise_equal(xa[std::size_t(d)], xb[std::size_t(d)])) << "x_next " << d;
    EXPECT_TRUE(bitwise_equal(ga.arrays[std::size_t(1 + d)], gb.arrays[std::size_t(1 + d)]))
        << "momentum " << d;
  }
  for (int c = 0; c < D * D; ++c)
    EXPECT_TRUE(bitwise_equal(La[std::size_t(c)], Lb[std::size_t(c)])) << "L " << c;
  // Each pass changed something: the comparison is not of untouched arrays.
  if constexpr ((What & kUpdateMotion) != 0) {
    EXPECT_FALSE(bitwise_equal(a.v[0], node_runs<D, Real>(ga, n, seed).v[0]));
  }
  if constexpr ((What & kVelocityGradient) != 0) {
    EXPECT_NE(La[std::size_t(D + 1)][n / 2], Real(0));
  }
  if constexpr ((What & kScatterMomentum) != 0) {
    EXPECT_NE(ga.sum(ga.G.p[1]), 0.0);
  }
}

template <int D, class Real = double>
void check_pairs_match_one_per_vector_every_pass(unsigned seed) {
  constexpr unsigned kUsl = kUpdateMotion | kVelocityGradient;
  constexpr unsigned kMuslMotion = kUpdateMotion | kScatterMomentum;
  constexpr unsigned kMuslGradient = kVelocityGradient | kCommitPosition;
  check_pairs_match_one_per_vector<D, GimpShape, kUsl, Real>(seed);
  check_pairs_match_one_per_vector<D, GimpShape, kMuslMotion, Real>(seed + 1);
  check_pairs_match_one_per_vector<D, GimpShape, kMuslGradient, Real>(seed + 2);
  check_pairs_match_one_per_vector<D, BSpline2Shape, kUsl, Real>(seed + 3);
  check_pairs_match_one_per_vector<D, BSpline2Shape, kMuslMotion, Real>(seed + 4);
  check_pairs_match_one_per_vector<D, BSpline2Shape, kMuslGradient, Real>(seed + 5);
}
TEST(G2PPairGather, WholeRangeSameBitsWithAndWithoutPairs) {
  check_pairs_match_one_per_vector_every_pass<3>(721);
}
TEST(G2PPairGather, WholeRangeSameBitsWithAndWithoutPairs2D) {
  check_pairs_match_one_per_vector_every_pass<2>(821);
}
TEST(G2PPairGather, WholeRangeSameBitsWithAndWithoutPairs2DFloat) {
  check_pairs_match_one_per_vector_every_pass<2, float>(921);
}

// Every mix of sums a pass gathers: motion and gradient, motion alone,
// gradient alone.
template <int D, class Shape, class Real = double>
void check_pair_gather_bits_every_mix(unsigned seed) {
  check_pair_gather_bits<D, Shape, Real, true, true>(seed);
  check_pair_gather_bits<D, Shape, Real, true, false>(seed + 1);
  check_pair_gather_bits<D, Shape, Real, false, true>(seed + 2);
}
TEST(G2PPairGather, SameBitsAsOneParticleGimp) {
  check_pair_gather_bits_every_mix<3, GimpShape>(711);
}
TEST(G2PPairGather, SameBitsAsOneParticleBSpline2) {
  check_pair_gather_bits_every_mix<3, BSpline2Shape>(714);
}
TEST(G2PPairGather, SameBitsAsOneParticleGimp2D) {
  check_pair_gather_bits_every_mix<2, GimpShape>(811);
}
TEST(G2PPairGather, SameBitsAsOneParticleBSpline2_2D) {
  check_pair_gather_bits_every_mix<2, BSpline2Shape>(814);
}
TEST(G2PPairGather, SameBitsAsOneParticleGimp2DFloat) {
  check_pair_gather_bits_every_mix<2, GimpShape, float>(911);
}
TEST(G2PPairGather, SameBitsAsOneParticleBSpline2_2DFloat) {
  check_pair_gather_bits_every_mix<2, BSpline2Shape, float>(914);
}
TEST(G2PPairGather, RangeStartChangesNoBit) {
  check_pair_gather_range_start<3, GimpShape>(716);
  check_pair_gather_range_start<3, BSpline2Shape>(717);
  check_pair_gather_range_start<2, GimpShape>(816);
  check_pair_gather_range_start<2, BSpline2Shape>(817);
  check_pair_gather_range_start<2, GimpShape, float>(916);
  check_pair_gather_range_start<2, BSpline2Shape, float>(917);
}

// End positions of two G2P kernels that differ only where x + dt v may or
// may not become one FMA (-ffp-contract=fast chooses per call site): 2 ulp.
template <class Real>
void expect_x_next_within_2ulp(const std::vector<Real>& xa, const std::vector<Real>& xb, int d) {
  for (std::size_t i = 0; i < xa.size(); ++i)
    ASSERT_LE(std::abs(double(xa[i]) - double(xb[i])),
              2 * double(std::numeric_limits<Real>::epsilon()) * std::abs(double(xb[i])))
        << "x_next " << d << " particle " << i;
}

// MUSL's fused pass (G2P of the updated velocity + P2G of the new momentum,
// kScatterMomentum) equals the two separate passes: the same velocities and
// grid momentum bit for bit, end positions (x_next) to 2 ulp (x + dt v may
// or may not become one FMA: -ffp-contract=fast lets the compiler choose
// per call site), for the windowed and the pointwise kernels. Then
// kCommitPosition moves x to x_next exactly.
template <int D, class Shape, class Real, bool Windowed>
void check_fused_musl(unsigned seed) {
  const bool gimp = std::string(Shape::name) == "gimp";
  Grid<D, Real> fused(grid_cells<D>(), 2), separate(grid_cells<D>(), 2);
  RandomGridVelocity<D, Real> gv(fused.G.nodes * 2, seed);
  const GridVelocity<D, Real>& V = gv.V;
  const std::size_t n = D == 2 ? 6000 : 4000;
  auto a = random_particles<D, Real>(fused.G, fused.cells, n, seed);
  TileLayout<D> tiles;
  tiles.setup(4, fused.cells);
  a = a.permuted(sort_by_tile<Shape>(a, fused.G, tiles));
  auto b = a;
  std::array<std::vector<Real>, D> xa, xb;
  auto Pa = a.view(gimp), Pb = b.view(gimp);
  for (int d = 0; d < D; ++d) {
    xa[d].assign(n, 0), xb[d].assign(n, 0);
    Pa.x_next[d] = xa[d].data(), Pb.x_next[d] = xb[d].data();
  }
  G2PParams q;
  q.dt = 0.01;
  q.flip = 0.95;
  const auto ra = g2p_range_impl<D, Shape, Real, kUpdateMotion | kScatterMomentum, true, false,
                                 false, Windowed>(Pa, fused.G, V, q, NoKeys{}, 0, n);
  const auto rb = g2p_range_impl<D, Shape, Real, kUpdateMotion, true, false, false, Windowed>(
      Pb, separate.G, V, q, NoKeys{}, 0, n);
  ASSERT_EQ(ra.bad, SIZE_MAX);
  ASSERT_EQ(rb.bad, SIZE_MAX);
  if constexpr (Windowed && packed_particles<D, Shape, Real>() > 1)
    // The fused pass scatters with the one-particle block; p2g_range's
    // packed 2D linear scatter sums in another order (PackedLinearScatter).
    ASSERT_EQ((p2g_range_one_block<D, Shape, Real, kMomentumOnly, true, false>(Pb, separate.G,
                                                                               P2GOptions{}, 0, n)),
              n);
  else if constexpr (Windowed)
    ASSERT_EQ(
        (p2g_range<D, Shape, Real, kMomentumOnly, true, false>(Pb, separate.G, P2GOptions{}, 0, n)),
        n);
  else
    ASSERT_EQ((p2g_range_pointwise<D, Shape, Real, kMomentumOnly, true, false>(Pb, separate.G,
                                                                               P2GOptions{}, 0, n)),
              n);
  for (int d = 0; d < D; ++d) {
    EXPECT_TRUE(bitwise_equal(a.v[d], b.v[d])) << "velocity " << d;
    expect_x_next_within_2ulp(xa[d], xb[d], d);
    EXPECT_TRUE(
        bitwise_equal(fused.arrays[std::size_t(1 + d)], separate.arrays[std::size_t(1 + d)]))
        << "momentum " << d;
    EXPECT_TRUE(bitwise_equal(a.x[d], b.x[d])) << "x stays at the step's start";
  }
  EXPECT_GT(fused.sum(fused.G.p[0]) * fused.sum(fused.G.p[0]), 0.0);
  // The gradient pass commits the positions.
  std::array<std::vector<Real>, D * D> La;
  for (int c = 0; c < D * D; ++c)
    La[std::size_t(c)].assign(n, 0), Pa.L[c] = La[std::size_t(c)].data();
  const auto rc = g2p_range_impl<D, Shape, Real, kVelocityGradient | kCommitPosition, true, false,
                                 false, Windowed>(Pa, fused.G, V, q, NoKeys{}, 0, n);
  ASSERT_EQ(rc.bad, SIZE_MAX);
  for (int d = 0; d < D; ++d)
    EXPECT_TRUE(bitwise_equal(a.x[d], xa[d])) << "x = x_next after the gradient pass";
}

TYPED_TEST(P2G, FusedMuslTransferMatchesSeparatePassesWindowed) {
  check_fused_musl<TypeParam::D, typename TypeParam::Shape, typename TypeParam::Real, true>(601);
}
TYPED_TEST(P2G, FusedMuslTransferMatchesSeparatePassesPointwise) {
  check_fused_musl<TypeParam::D, typename TypeParam::Shape, typename TypeParam::Real, false>(602);
}

// MUSL's fused pass scatters the momenta in a block beside the gathers or
// after each batch (MomentumScatterAt; the solver picks by register count,
// kernels/g2p.hpp): both are the same sums in the same order, so velocities
// and grid momenta agree bit for bit, whichever the solver picks; end
// positions to 2 ulp (x + dt v may or may not become one FMA in each
// instantiation, as in check_fused_musl; 2D float differs there). On the
// sorted and crowded sets of BlockTestSets (2 fields); with a particle off
// the grid both stop at it (the deferred scatter then drops the rest of
// that batch, so the momenta are not compared there).
template <int D, class Shape, class Real>
void check_momentum_scatter_placements(const Particles<D, Real>& list, std::size_t stop_at) {
  const bool gimp = std::string(Shape::name) == "gimp";
  Grid<D, Real> ga(grid_cells<D>(), 2), gb(grid_cells<D>(), 2);
  RandomGridVelocity<D, Real> gv(ga.G.nodes * 2, 603);
  auto a = list, b = list;
  auto Pa = a.view(gimp), Pb = b.view(gimp);
  const std::size_t n = list.n;
  const GatherOutputs<D, Real> out(a, Pa, Pb, true);
  const auto& xa = out.xa;
  const auto& xb = out.xb;
  G2PParams q;
  q.dt = 0.01;
  q.flip = 0.95;
  constexpr unsigned What = kUpdateMotion | kScatterMomentum;
  const auto ra =
      g2p_range_impl<D, Shape, Real, What, true, false, false, true, true,
                     MomentumScatterAt::inline_block>(Pa, ga.G, gv.V, q, NoKeys{}, 0, n);
  const auto rb = g2p_range_impl<D, Shape, Real, What, true, false, false, true, true,
                                 MomentumScatterAt::after_batch>(Pb, gb.G, gv.V, q, NoKeys{}, 0, n);
  ASSERT_EQ(ra.bad, stop_at);
  ASSERT_EQ(rb.bad, stop_at);
  for (int d = 0; d < D; ++d) {
    EXPECT_TRUE(bitwise_equal(a.v[d], b.v[d])) << "velocity " << d;
    expect_x_next_within_2ulp(xa[d], xb[d], d);
    if (stop_at == SIZE_MAX) {
      EXPECT_EQ(first_difference(ga.arrays[std::size_t(1 + d)], gb.arrays[std::size_t(1 + d)]),
                ga.arrays[std::size_t(1 + d)].size())
          << "momentum " << d;
    }
  }
  EXPECT_NE(ga.sum(ga.G.p[0]), 0.0);
}

TYPED_TEST(P2G, FusedMuslMomentumInlineOrAfterBatchSameBits) {
  constexpr int D = TypeParam::D;
  using Shape = typename TypeParam::Shape;
  using Real = typename TypeParam::Real;
  const BlockTestSets<D, Shape, Real> sets(604, 1);
  sets.each([](const Particles<D, Real>& list, std::size_t stop_at) {
    check_momentum_scatter_placements<D, Shape, Real>(list, stop_at);
  });
}

// The packed 2D linear gather (kernels/g2p_packed.hpp, what g2p_range runs
// for 2D linear) against the one-particle
// windowed gather: the gathered values are the same operations in the same
// order, so L, which is stored as gathered, must be bitwise equal; v, x and
// x_next are computed from them by the same code at another call site,
// where -ffp-contract=fast may fuse a multiply-add differently: 2 ulp.
// Passes: motion + gradient (traction and gravity work, one rigid field),
// motion into x_next, gradient + commit. Particles: tile-sorted random
// (2 fields, runs of 1-6), 100 in one cell (a run across 4 batches of 32),
// the sorted set with one particle off the grid (both report it), and
// particles spread to the grid's edges.
//
// With kScatterMomentum (MUSL's fused pass) the packed kernel scatters m v
// with the packed scatter's block: its momenta equal the one-particle fused
// pass's to round-off (another order of sums, conservation_tol) and, bit
// for bit, p2g_range_packed's kMomentumOnly scatter of the particles it
// updated (the same groups, lanes and products).
template <class Real, unsigned What>
void check_packed_gather(Particles<2, Real> a, std::size_t bad, bool x_next, unsigned seed) {
  Grid<2, Real> g(grid_cells<2>(), 2), g_one(grid_cells<2>(), 2);
  RandomGridVelocity<2, Real> gv(g.G.nodes * 2, seed);
  const std::size_t n = a.n;
  auto b = a;
  auto Pa = a.view(false), Pb = b.view(false);
  GatherOutputs<2, Real> out(a, Pa, Pb, x_next);
  auto& [La, Lb, xa, xb] = out;
  // Float: both kernels keep the positions' low parts (kernels/
  // position_sum.hpp), from the same random start within half an ulp.
  std::array<std::vector<Real>, 2> loa, lob;
  const auto x_start = a.x;
  auto ulp = [](Real x) {
    return double(std::nextafter(std::abs(x), Real(1e30))) - double(std::abs(x));
  };
  if constexpr (std::is_same_v<Real, float>) {
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> U(-0.5, 0.5);
    for (int d = 0; d < 2; ++d) {
      loa[std::size_t(d)].resize(n);
      for (std::size_t i = 0; i < n; ++i) loa[std::size_t(d)][i] = Real(U(rng) * ulp(a.x[d][i]));
      lob[std::size_t(d)] = loa[std::size_t(d)];
      Pa.xlo[d] = loa[std::size_t(d)].data(), Pb.xlo[d] = lob[std::size_t(d)].data();
    }
  }
  const auto lo_start = loa;
  const unsigned char rigid[2] = {0, 1};
  const double rigid_velocity[2][3] = {{0, 0, 0}, {0.25, -0.5, 0}};
  G2PParams q;
  q.dt = 0.01;
  q.flip = 0.9;
  q.rigid = rigid;
  q.rigid_velocity = rigid_velocity;
  q.body_accel[1] = -9.81;
  const auto ra = g2p_range_packed<Real, What, true, true, true>(Pa, g.G, gv.V, q, NoKeys{}, 0, n,
                                                                 NoStressUpdate{});
  const auto rb = g2p_range_impl<2, LinearShape, Real, What, true, true, true, true>(
      Pb, g_one.G, gv.V, q, NoKeys{}, 0, n);
  ASSERT_EQ(ra.bad, rb.bad);
  ASSERT_EQ(ra.bad, bad);
  const double eps = double(std::numeric_limits<Real>::epsilon());
  auto close = [&](const std::vector<Real>& u, const std::vector<Real>& w, const char* what) {
    for (std::size_t i = 0; i < n; ++i)
      ASSERT_LE(std::abs(double(u[i]) - double(w[i])), 2 * eps * (1 + std::abs(double(w[i]))))
          << what << ", particle " << i << " (What " << What << ")";
  };
  for (int c = 0; c < 4; ++c)
    EXPECT_TRUE(bitwise_equal(La[std::size_t(c)], Lb[std::size_t(c)])) << "L " << c;
  for (int d = 0; d < 2; ++d) {
    close(a.v[d], b.v[d], "v");
    close(a.x[d], b.x[d], "x");
    close(xa[std::size_t(d)], xb[std::size_t(d)], "x_next");
  }
  // x + xlo of the two kernels: the same sum of x, xlo and the move, which
  // differs by the one rounding of the move (2 eps of it) and of move + lo.
  if constexpr (std::is_same_v<Real, float>)
    for (int d = 0; d < 2; ++d) {
      const auto& end_a = x_next ? xa[std::size_t(d)] : a.x[d];
      const auto& end_b = x_next ? xb[std::size_t(d)] : b.x[d];
      const auto& la = loa[std::size_t(d)];
      const auto& lb = lob[std::size_t(d)];
      for (std::size_t i = 0; i < n; ++i) {
        const double pa = double(end_a[i]) + double(la[i]), pb = double(end_b[i]) + double(lb[i]);
        const double start = double(x_start[d][i]) + double(lo_start[std::size_t(d)][i]);
        const double tol = 4 * eps * (std::abs(pb - start) + ulp(x_start[d][i]));
        ASSERT_NEAR(pa, pb, tol) << "x + xlo " << d << ", particle " << i << " (What " << What
                                 << ")";
        ASSERT_LE(std::abs(double(la[i])), 0.5 * ulp(end_a[i]))
            << "xlo " << d << ", particle " << i;
      }
    }
  EXPECT_NEAR(ra.external_work, rb.external_work, 1e3 * eps * (1 + std::abs(rb.external_work)));
  if constexpr ((What & kUpdateMotion) != 0) {
    EXPECT_NE(rb.external_work, 0.0);
  }
  if constexpr ((What & kScatterMomentum) != 0) {
    EXPECT_GT(g.sum(g.G.p[0]) * g.sum(g.G.p[0]), 0.0);
    for (std::size_t k = 0; k < g.arrays.size(); ++k) {
      double scale = 0;
      EXPECT_LE(max_rel_diff(g.arrays[k], g_one.arrays[k], scale), conservation_tol<Real>())
          << "array " << k;
    }
    if (bad == SIZE_MAX) {  // p2g_range_packed stops at a particle off the grid
      Grid<2, Real> scattered(grid_cells<2>(), 2);
      ASSERT_EQ(
          (p2g_range_packed<Real, kMomentumOnly, true, false>(Pa, scattered.G, P2GOptions{}, 0, n)),
          n);
      for (std::size_t k = 0; k < g.arrays.size(); ++k)
        EXPECT_TRUE(bitwise_equal(g.arrays[k], scattered.arrays[k])) << "array " << k;
    }
  }
}

template <class Real>
void check_packed_gather_all() {
  static_assert(packed_particles<2, LinearShape, Real>() > 1);
  const PackedTestSets<Real> t(921, 0);
  auto edges = t.sorted;
  spread_to_edges<2, LinearShape, Real>(edges, t.g.G, 923);
  unsigned seed = 930;
  const Particles<2, Real>* const lists[] = {&t.sorted, &t.crowded, &t.off_grid, &edges};
  for (const auto* list : lists) {
    const std::size_t expect = list == &t.off_grid ? t.bad : SIZE_MAX;
    check_packed_gather<Real, kUpdateMotion | kVelocityGradient>(*list, expect, false, ++seed);
    check_packed_gather<Real, kUpdateMotion>(*list, expect, true, ++seed);
    check_packed_gather<Real, kUpdateMotion | kScatterMomentum>(*list, expect, true, ++seed);
    check_packed_gather<Real, kVelocityGradient | kCommitPosition>(*list, expect, true, ++seed);
  }
}

// A grid velocity change of +inf at the node below-left of particle 777:
// every particle whose window holds the node gets a non-finite velocity,
// and the packed kernel (its K-lane update, update_group, and its particle
// by particle update) reports the same first one as the one-particle
// kernel. Tile-sorted random particles (one field, so whole groups take the
// K-lane update) and the 100 particles in one cell.
template <class Real>
void check_packed_gather_non_finite() {
  const PackedTestSets<Real> t(941, 0);
  for (const auto* list : {&t.sorted, &t.crowded}) {
    Particles<2, Real> a = *list, b = *list;
    const std::size_t n = a.n, poisoned = std::min<std::size_t>(777, n / 2);
    for (std::size_t p = 0; p < n; ++p) a.field[p] = b.field[p] = 0;
    Grid<2, Real> ga(grid_cells<2>(), 2), gb(grid_cells<2>(), 2);
    RandomGridVelocity<2, Real> gv(ga.G.nodes * 2, 943);
    std::size_t node = 0, stride = 1;
    for (int d = 0; d < 2; ++d) {
      const double c = (double(a.x[d][poisoned]) - double(ga.G.origin[d])) / double(ga.G.h[d]);
      node += std::size_t(std::floor(c)) * stride;
      stride *= std::size_t(ga.G.nodes_per_dim[d]);
    }
    gv.dvel[1][node] = std::numeric_limits<Real>::infinity();
    std::array<std::vector<Real>, 2> xa, xb;
    auto Pa = a.view(false), Pb = b.view(false);
    for (int d = 0; d < 2; ++d) {
      xa[std::size_t(d)].assign(n, 0), xb[std::size_t(d)].assign(n, 0);
      Pa.x_next[d] = xa[std::size_t(d)].data(), Pb.x_next[d] = xb[std::size_t(d)].data();
    }
    G2PParams q;
    q.dt = 0.01;
    q.flip = 0.9;
    const auto ra = g2p_range_packed<Real, kUpdateMotion, true, false, false>(
        Pa, ga.G, gv.V, q, NoKeys{}, 0, n, NoStressUpdate{});
    const auto rb = g2p_range_impl<2, LinearShape, Real, kUpdateMotion, true, false, false, true>(
        Pb, gb.G, gv.V, q, NoKeys{}, 0, n);
    ASSERT_NE(rb.bad, SIZE_MAX);
    EXPECT_LE(rb.bad, poisoned);
    EXPECT_EQ(ra.bad, rb.bad);
    EXPECT_FALSE(std::isfinite(double(a.v[1][ra.bad])));
  }
}

#ifdef __AVX512F__
TEST(PackedLinearGather, MatchesTheOneParticleGatherDouble) {
  check_packed_gather_all<double>();
}
TEST(PackedLinearGather, MatchesTheOneParticleGatherFloat) {
  check_packed_gather_all<float>();
}
TEST(PackedLinearGather, ReportsTheFirstNonFiniteParticleDouble) {
  check_packed_gather_non_finite<double>();
}
TEST(PackedLinearGather, ReportsTheFirstNonFiniteParticleFloat) {
  check_packed_gather_non_finite<float>();
}
#endif

// TileSchedule::share: for 1 to 4 threads, the threads' shares of every
// color are contiguous, disjoint and cover the color's tiles in order, and
// each thread's particle count is within one tile's count of the color's
// particles / threads (the split is by particle quantiles). 2D grid 37 x 29
// cells, tile edge 4, 6000 random particles (non-uniform: two thirds of
// them in the left quarter of the grid, so equal tile counts would not
// balance).
TEST(TileSchedule, SharesPartitionEachColorByParticleQuantiles) {
  Grid<2, double> g(grid_cells<2>(), 1);
  auto p = random_particles<2, double>(g.G, g.cells, 6000, 77);
  for (std::size_t i = 0; i < p.n; i += 3)
    p.x[0][i] = g.G.origin[0] + 0.25 * (p.x[0][i] - g.G.origin[0]);
  for (std::size_t i = 1; i < p.n; i += 3)
    p.x[0][i] = g.G.origin[0] + 0.25 * (p.x[0][i] - g.G.origin[0]);
  TileLayout<2> tiles;
  tiles.setup(4, g.cells);
  auto sorted = p.permuted(sort_by_tile<LinearShape>(p, g.G, tiles));
  TileSchedule r;
  r.build(tiles, sorted.key.data(), sorted.n);
  ASSERT_EQ(r.begin.back(), sorted.n);
  for (std::size_t c = 0; c < 4; ++c) {
    const auto& list = r.tiles[c];
    ASSERT_FALSE(list.empty());
    std::size_t total = 0, largest = 0;
    for (std::uint32_t t : list) {
      const std::size_t count = r.begin[t + 1] - r.begin[t];
      EXPECT_GT(count, 0u) << "only non-empty tiles are listed";
      EXPECT_EQ(tiles.color(tiles.tile_of_slot(t)), int(c));
      total += count, largest = std::max(largest, count);
    }
    for (std::size_t threads = 1; threads <= 4; ++threads) {
      std::size_t next = 0;
      for (std::size_t i = 0; i < threads; ++i) {
        const auto [first, last] = r.share(c, threads, i);
        EXPECT_EQ(first, next) << "color " << c << ", thread " << i << " of " << threads;
        EXPECT_LE(first, last);
        std::size_t mine = 0;
        for (std::size_t k = first; k < last; ++k) mine += r.begin[list[k] + 1] - r.begin[list[k]];
        EXPECT_LE(std::abs(double(mine) - double(total) / double(threads)), double(largest) + 1.0)
            << "color " << c << ", thread " << i << " of " << threads;
        next = last;
      }
      EXPECT_EQ(next, list.size()) << "color " << c << ", " << threads << " threads";
    }
  }
}

}  // namespace
