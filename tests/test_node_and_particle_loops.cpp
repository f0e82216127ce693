// The vectorised constitutive and grid loops compute what the per-particle
// and per-node formulas compute (kernels/constitutive.hpp, grid_update.hpp;
// docs/performance.md "Loops the compiler vectorises").
//
// References: the per-particle IsotropicPoint::operator() and, for the grid,
// the branchy per-node formulas of ALGORITHM §2 step 4 written out below.
// Inputs: seeded random velocity gradients (|dt L| up to 1e-3), stresses
// and volumes; grids of 5000 nodes per field with heavy nodes, slivers
// (0 < m <= threshold) and empty nodes mixed, two fields one of which is
// rigid, gravity, interface forces and damping on and off.
// Tolerance: the two forms evaluate the same expressions in the same order;
// only the compiler's multiply-add contraction may differ between a scalar
// and a vector loop, so each value must agree within 8 ulp of the largest
// magnitude of its array (double) and the damping loss within 1e-13
// relative.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

#include "kernels/constitutive.hpp"
#include "kernels/grid_update.hpp"

namespace {

using namespace mmpm;

template <int D>
struct Particles {
  static constexpr int NS = kStressComponents<D>;
  std::vector<double> L[D * D], s[NS], V;
  std::vector<std::uint8_t> mat;
  ParticleView<D, double> P;

  Particles(std::size_t n, int materials, unsigned seed) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    for (auto& a : L) a.resize(n);
    for (auto& a : s) a.resize(n);
    V.resize(n);
    mat.resize(n);
    for (std::size_t p = 0; p < n; ++p) {
      for (auto& a : L) a[p] = 10.0 * u(rng);  // dt = 1e-4 below: |dt L| <= 1e-3
      for (auto& a : s) a[p] = 50.0 * u(rng);
      V[p] = 1.0 + 0.5 * u(rng);
      mat[p] = std::uint8_t(rng() % unsigned(materials));
    }
    P.n = n;
    for (int i = 0; i < D * D; ++i) P.L[i] = L[i].data();
    for (int i = 0; i < NS; ++i) P.s[i] = s[i].data();
    P.V = V.data();
    P.mat = mat.data();
  }
};

double max_abs(const std::vector<double>& a) {
  double m = 0;
  for (double x : a) m = std::max(m, std::abs(x));
  return m;
}

void expect_close(const std::vector<double>& got, const std::vector<double>& want,
                  const char* what) {
  ASSERT_EQ(got.size(), want.size());
  const double tol = 8 * std::numeric_limits<double>::epsilon() * std::max(1.0, max_abs(want));
  for (std::size_t i = 0; i < got.size(); ++i)
    ASSERT_NEAR(got[i], want[i], tol) << what << " at " << i;
}

ElasticKernelConstants isotropic(double E, double nu, bool plane_stress) {
  ElasticKernelConstants k;
  k.lambda = E * nu / ((1 + nu) * (1 - 2 * nu));
  k.mu = E / (2 * (1 + nu));
  k.Ep = E / (1 - nu * nu);
  k.nu = nu;
  k.plane_stress = plane_stress;
  return k;
}

template <int D>
void range_matches_pointwise(bool plane_stress) {
  const std::size_t n = 1037;  // not a multiple of any vector width
  Particles<D> a(n, 1, 7), b(n, 1, 7);
  const IsotropicPoint<D, double> update(isotropic(1000.0, 0.3, plane_stress), 1e-4);
  update.range(a.P, 0, n);
  for (std::size_t p = 0; p < n; ++p) update(b.P, p);
  for (int c = 0; c < kStressComponents<D>; ++c) expect_close(a.s[c], b.s[c], "stress");
  expect_close(a.V, b.V, "volume");
  // The loop really did something: stresses moved from their start.
  Particles<D> start(n, 1, 7);
  EXPECT_NE(a.s[0][5], start.s[0][5]);
  EXPECT_NE(a.V[5], start.V[5]);
}

TEST(ConstitutiveLoops, IsotropicRangeMatchesPointwisePlaneStrain) {
  range_matches_pointwise<2>(false);
}
TEST(ConstitutiveLoops, IsotropicRangeMatchesPointwisePlaneStress) {
  range_matches_pointwise<2>(true);
}
TEST(ConstitutiveLoops, IsotropicRangeMatchesPointwise3D) {
  range_matches_pointwise<3>(false);
}

template <int D>
void by_material_matches_per_material() {
  const std::size_t n = 2011;
  const int nm = 3;
  const double E[nm] = {1000.0, 4000.0, 70000.0}, nu[nm] = {0.3, 0.2, 0.45};
  Particles<D> a(n, nm, 11), b(n, nm, 11);
  IsotropicByMaterial<D, double> table;
  table.dt = 1e-4;
  std::vector<IsotropicPoint<D, double>> points;
  for (int i = 0; i < nm; ++i) {
    points.emplace_back(isotropic(E[i], nu[i], false), 1e-4);
    table.lam[std::size_t(i)] = points.back().lam;
    table.mu2[std::size_t(i)] = points.back().mu2;
  }
  table.range(a.P, 0, n);
  for (std::size_t p = 0; p < n; ++p) points[b.mat[p]](b.P, p);
  for (int c = 0; c < kStressComponents<D>; ++c) expect_close(a.s[c], b.s[c], "stress");
  expect_close(a.V, b.V, "volume");
}

// A range of one material takes IsotropicByMaterial's scalar-constant
// path, a mixed one the looked-up loop: the same particle must get the same
// bits either way. Materials in blocks (0, then 1, then mixed), updated
// once as one mixed range and once block by block. Bitwise.
template <int D>
void uniform_ranges_match_the_looked_up_loop() {
  const std::size_t n = 1501, first_block = 500, second_block = 1100;
  Particles<D> whole(n, 3, 17), blocks(n, 3, 17);
  for (Particles<D>* q : {&whole, &blocks})
    for (std::size_t p = 0; p < second_block; ++p) q->mat[p] = p < first_block ? 0 : 1;
  IsotropicByMaterial<D, double> table;
  table.dt = 1e-4;
  for (int i = 0; i < 3; ++i) {
    const ElasticKernelConstants k = isotropic(1000.0 * (i + 1), 0.2 + 0.1 * i, false);
    table.lam[std::size_t(i)] = k.lambda;
    table.mu2[std::size_t(i)] = 2 * k.mu;
  }
  table.range(whole.P, 0, n);
  table.range(blocks.P, 0, first_block);
  table.range(blocks.P, first_block, second_block);
  table.range(blocks.P, second_block, n);
  table.range(blocks.P, 7, 7);  // empty: nothing to do
  for (int c = 0; c < kStressComponents<D>; ++c)
    ASSERT_EQ(std::memcmp(blocks.s[c].data(), whole.s[c].data(), n * sizeof(double)), 0)
        << "stress " << c;
  ASSERT_EQ(std::memcmp(blocks.V.data(), whole.V.data(), n * sizeof(double)), 0) << "volume";
}

TEST(ConstitutiveLoops, OneMaterialRangesMatchTheLookedUpLoop) {
  uniform_ranges_match_the_looked_up_loop<2>();
  uniform_ranges_match_the_looked_up_loop<3>();
}

TEST(ConstitutiveLoops, IsotropicByMaterialMatchesPerMaterialUpdates2D) {
  by_material_matches_per_material<2>();
}
TEST(ConstitutiveLoops, IsotropicByMaterialMatchesPerMaterialUpdates3D) {
  by_material_matches_per_material<3>();
}

// Threads update blocks of particles whose ends depend on the thread count:
// a particle's result must not depend on where its block starts (a vector
// loop and its scalar remainder must compute alike), or 1 and 2 threads
// would differ. Bitwise.
template <int D, class Update>
void expect_same_bits_whatever_the_split(const Update& update, int materials) {
  const std::size_t n = 1037;
  Particles<D> whole(n, materials, 13);
  update.range(whole.P, 0, n);
  for (std::size_t cut : {std::size_t(1), std::size_t(3), std::size_t(7), std::size_t(333),
                          std::size_t(518), n - 5}) {
    Particles<D> parts(n, materials, 13);
    update.range(parts.P, 0, cut);
    update.range(parts.P, cut, n);
    for (int c = 0; c < kStressComponents<D>; ++c)
      ASSERT_EQ(std::memcmp(parts.s[c].data(), whole.s[c].data(), n * sizeof(double)), 0)
          << "stress " << c << ", cut at " << cut;
    ASSERT_EQ(std::memcmp(parts.V.data(), whole.V.data(), n * sizeof(double)), 0)
        << "volume, cut at " << cut;
  }
}

TEST(ConstitutiveLoops, SameBitsWhateverTheSplit) {
  expect_same_bits_whatever_the_split<2>(
      IsotropicPoint<2, double>(isotropic(1000.0, 0.3, false), 1e-4), 1);
  expect_same_bits_whatever_the_split<2>(
      IsotropicPoint<2, double>(isotropic(1000.0, 0.3, true), 1e-4), 1);
  expect_same_bits_whatever_the_split<3>(
      IsotropicPoint<3, double>(isotropic(1000.0, 0.3, false), 1e-4), 1);
  IsotropicByMaterial<2, double> t2;
  IsotropicByMaterial<3, double> t3;
  t2.dt = t3.dt = 1e-4;
  for (int i = 0; i < 3; ++i) {
    const ElasticKernelConstants k = isotropic(1000.0 * (i + 1), 0.2 + 0.1 * i, false);
    t2.lam[std::size_t(i)] = t3.lam[std::size_t(i)] = k.lambda;
    t2.mu2[std::size_t(i)] = t3.mu2[std::size_t(i)] = 2 * k.mu;
  }
  expect_same_bits_whatever_the_split<2>(t2, 3);
  expect_same_bits_whatever_the_split<3>(t3, 3);
}

TEST(ConstitutiveLoops, FirstUnsoundFindsTheFirstBadParticle) {
  const std::size_t n = 1500;  // three chunks of 512 (the last one partial)
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  struct Bad {
    bool volume;  // else stress
    double value;
  };
  const Bad kinds[] = {{true, 0.0}, {true, -1e-30}, {true, nan},
                       {true, inf}, {false, nan},   {false, -inf}};
  for (std::size_t at :
       {std::size_t(0), std::size_t(511), std::size_t(512), std::size_t(1100), n - 1})
    for (const Bad& k : kinds) {
      Particles<2> a(n, 1, 3);
      EXPECT_EQ(first_unsound(a.P, 0, n), SIZE_MAX);
      (k.volume ? a.V : a.s[0])[at] = k.value;
      if (at + 7 < n) a.V[at + 7] = nan;  // a later bad one must not be reported
      EXPECT_EQ(first_unsound(a.P, 0, n), at) << "bad particle at " << at;
      // A range that starts past it does not see it.
      EXPECT_EQ(first_unsound(a.P, std::min(n, at + 8), n), SIZE_MAX);
    }
}

// ------------------------------------------------------------------ grid
struct Grid2 {
  static constexpr int D = 2;
  std::size_t nodes;
  std::vector<double> m, p[D], f[D], fi[D], vel[D], dvel[D];
  GridView<D, double> G;
  GridVelocity<D, double> V;

  Grid2(std::size_t nodes_per_field, double thr, unsigned seed) : nodes(nodes_per_field) {
    const std::size_t n = 2 * nodes;
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    m.resize(n);
    for (int d = 0; d < D; ++d) {
      p[d].resize(n), f[d].resize(n), fi[d].resize(n), vel[d].resize(n), dvel[d].resize(n);
    }
    for (std::size_t i = 0; i < n; ++i) {
      const unsigned kind = rng() % 4;  // empty, sliver, heavy, heavy
      m[i] = kind == 0 ? 0.0 : (kind == 1 ? thr * (0.5 + 0.5 * u(rng)) : 2.0 + u(rng));
      for (int d = 0; d < D; ++d) {
        p[d][i] = m[i] * 3.0 * u(rng);
        f[d][i] = m[i] > 0 ? 5.0 * u(rng) : 0.0;
        fi[d][i] = m[i] > 0 ? 0.5 * u(rng) : 0.0;
        dvel[d][i] = 7.0 * u(rng);  // grid_velocities keeps a sliver's value
      }
    }
    G.nodes_per_dim = {int(nodes), 1, 1};
    G.nodes = nodes;
    G.fields = 2;
    G.m = m.data();
    for (int d = 0; d < D; ++d) {
      G.p[d] = p[d].data(), G.f[d] = f[d].data(), G.fi[d] = fi[d].data();
      V.vel[d] = vel[d].data(), V.dvel[d] = dvel[d].data();
    }
  }
};

// The per-node formulas of ALGORITHM §2 step 4, as a branchy scalar loop.
double reference_update(Grid2& g, const GridUpdateParams& q) {
  constexpr int D = 2;
  double loss = 0;
  for (int field = 0; field < 2; ++field) {
    const bool rigid = q.rigid && q.rigid[field];
    for (std::size_t n = 0; n < g.nodes; ++n) {
      const std::size_t i = std::size_t(field) * g.nodes + n;
      const double m = g.m[i];
      if (!(m > q.mass_threshold)) {
        for (int d = 0; d < D; ++d) {
          double force = g.f[d][i] + m * (rigid ? 0.0 : q.body_accel[d]);
          if (q.has_interface_force) force += g.fi[d][i];
          g.dvel[d][i] = m > 0 && !rigid ? q.dt * force / m : 0.0;
        }
        continue;
      }
      const double inv_m = 1.0 / m;
      double pv = 0;
      for (int d = 0; d < D; ++d) {
        const double p = g.p[d][i];
        g.dvel[d][i] = -p * inv_m;
        if (rigid) {
          g.p[d][i] = m * q.rigid_velocity[field][d];
          continue;
        }
        double force = g.f[d][i] + m * q.body_accel[d] - q.damping * p;
        if (q.has_interface_force) force += g.fi[d][i];
        g.p[d][i] = p + q.dt * force;
        pv += p * p * inv_m;
      }
      loss += q.damping * q.dt * pv;
    }
  }
  return loss;
}

// Field 1 rigid, moving at (0.25, -0.5); gravity; mass threshold 1e-6.
constexpr double kThreshold = 1e-6;
const unsigned char kRigid[2] = {0, 1};
const double kRigidVelocity[2][3] = {{0, 0, 0}, {0.25, -0.5, 0}};

GridUpdateParams update_params(bool interface, double damping) {
  GridUpdateParams q;
  q.dt = 1e-3;
  q.damping = damping;
  q.mass_threshold = kThreshold;
  q.body_accel[1] = -9.81;
  q.rigid = kRigid;
  q.rigid_velocity = kRigidVelocity;
  q.has_interface_force = interface;
  return q;
}

void grid_update_case(bool interface, double damping) {
  const double thr = kThreshold;
  Grid2 a(5000, thr, 5), b(5000, thr, 5);
  const GridUpdateParams q = update_params(interface, damping);
  const double loss = grid_update(a.G, a.V, q);
  const double want = reference_update(b, q);
  for (int d = 0; d < 2; ++d) {
    expect_close(a.p[d], b.p[d], "momentum");
    expect_close(a.dvel[d], b.dvel[d], "velocity change");
  }
  if (damping == 0) {
    EXPECT_EQ(loss, 0.0);
  } else {
    EXPECT_GT(want, 0.0);  // damping removes energy
    EXPECT_NEAR(loss, want, 1e-13 * want);
  }

  // Then the velocities (grid_velocities): v = p/m on heavy nodes, 0 on
  // slivers and empty nodes; dvel += v on heavy nodes only.
  grid_velocities(a.G, a.V, thr);
  for (std::size_t i = 0; i < b.m.size(); ++i)
    for (int d = 0; d < 2; ++d) {
      if (b.m[i] > thr) {
        const double v = b.p[d][i] * (1.0 / b.m[i]);
        b.vel[d][i] = v;
        b.dvel[d][i] += v;
      } else {
        b.vel[d][i] = 0.0;
      }
    }
  for (int d = 0; d < 2; ++d) {
    expect_close(a.vel[d], b.vel[d], "velocity");
    expect_close(a.dvel[d], b.dvel[d], "velocity change after grid_velocities");
  }
}

// grid_update with q.velocities (one pass) = grid_update, then
// grid_velocities, bitwise: the Stepper fuses them when no pass B runs in
// between, and the fused and separate paths must give the same run.
void fused_velocities_case(bool interface, double damping) {
  const double thr = kThreshold;
  Grid2 a(5000, thr, 9), b(5000, thr, 9);
  GridUpdateParams q = update_params(interface, damping);
  const double separate = grid_update(b.G, b.V, q);
  grid_velocities(b.G, b.V, thr);
  q.velocities = true;
  const double fused = grid_update(a.G, a.V, q);
  EXPECT_EQ(fused, separate);
  for (int d = 0; d < 2; ++d)
    for (auto [x, y] :
         {std::pair{&a.p[d], &b.p[d]}, {&a.vel[d], &b.vel[d]}, {&a.dvel[d], &b.dvel[d]}})
      EXPECT_EQ(std::memcmp(x->data(), y->data(), x->size() * sizeof(double)), 0);
}

TEST(GridLoops, FusedVelocitiesEqualSeparatePassBitwise) {
  fused_velocities_case(false, 0.0);
  fused_velocities_case(true, 0.0);
  fused_velocities_case(true, 0.7);
}

// grid_momentum_velocities = the branchy per-node division, bitwise: vel =
// p/m on heavy nodes, 0 on slivers and empty nodes (0/0 dropped), dvel and
// p untouched.
TEST(GridLoops, MomentumVelocitiesEqualPerNodeDivisionBitwise) {
  const double thr = kThreshold;
  Grid2 a(5003, thr, 11);
  for (int d = 0; d < 2; ++d) std::fill(a.vel[d].begin(), a.vel[d].end(), 123.0);
  const auto dvel_before = a.dvel[0];
  const auto p_before = a.p[1];
  grid_momentum_velocities(a.G, a.V, thr);
  std::size_t heavy = 0, empty = 0;
  for (std::size_t i = 0; i < a.m.size(); ++i) {
    heavy += a.m[i] > thr;
    empty += a.m[i] == 0.0;
    for (int d = 0; d < 2; ++d) {
      const double want = a.m[i] > thr ? a.p[d][i] / a.m[i] : 0.0;
      ASSERT_EQ(std::memcmp(&a.vel[d][i], &want, sizeof want), 0) << "node " << i;
    }
  }
  EXPECT_GT(heavy, 1000u);  // the case mix is real: heavy, sliver and empty nodes
  EXPECT_GT(empty, 500u);
  EXPECT_EQ(a.dvel[0], dvel_before);
  EXPECT_EQ(a.p[1], p_before);
}

TEST(GridLoops, UpdateMatchesPerNodeFormulas) {
  grid_update_case(false, 0.0);
}
TEST(GridLoops, UpdateMatchesPerNodeFormulasWithInterfaceForces) {
  grid_update_case(true, 0.0);
}
TEST(GridLoops, UpdateMatchesPerNodeFormulasWithDamping) {
  grid_update_case(false, 0.7);
}
TEST(GridLoops, UpdateMatchesPerNodeFormulasWithInterfaceAndDamping) {
  grid_update_case(true, 0.7);
}

}  // namespace
