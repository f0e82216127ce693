// Test fixtures of the multimaterial pass: a grid owning its per-field
// arrays, the pair table behind an MMConfig, and random node data.
#pragma once

#include <array>
#include <random>
#include <vector>

#include "kernels/multimaterial.hpp"

namespace mmpm::test {

// A grid that owns its per-field arrays and exposes them as a GridView.
template <int D, class Real>
struct TestGrid {
  mmpm::GridView<D, Real> view;
  std::vector<Real> m, vol;
  std::array<std::vector<Real>, D> p, f, mx, g, fi;

  TestGrid(std::array<int, 3> nodes_per_dim, int fields, std::array<Real, 3> h = {1, 1, 1}) {
    view.nodes_per_dim = nodes_per_dim;
    view.h = h;
    view.fields = fields;
    std::size_t n = 1;
    for (int d = 0; d < D; ++d) n *= std::size_t(nodes_per_dim[d]);
    view.nodes = n;
    const std::size_t total = n * std::size_t(fields);
    m.assign(total, 0);
    vol.assign(total, 0);
    view.m = m.data();
    view.vol = vol.data();
    for (int d = 0; d < D; ++d) {
      for (auto* v : {&p[d], &f[d], &mx[d], &g[d], &fi[d]}) v->assign(total, 0);
      view.p[d] = p[d].data();
      view.f[d] = f[d].data();
      view.mx[d] = mx[d].data();
      view.g[d] = g[d].data();
      view.fi[d] = fi[d].data();
    }
  }
  TestGrid(const TestGrid&) = delete;
  TestGrid& operator=(const TestGrid&) = delete;

  std::size_t at(int field, std::size_t node) const { return view.at(field, node); }
  // Set mass, velocity (p = m v), mean position/displacement (mx = m x) and domain.
  void set(int field, std::size_t node, Real mass, std::array<Real, 3> v, std::array<Real, 3> x,
           Real domain) {
    const std::size_t i = at(field, node);
    m[i] = mass;
    vol[i] = domain;
    for (int d = 0; d < D; ++d) {
      p[d][i] = mass * v[d];
      mx[d][i] = mass * x[d];
    }
  }
  void set_gradient(int field, std::size_t node, std::array<Real, 3> gradient) {
    for (int d = 0; d < D; ++d) g[d][at(field, node)] = gradient[d];
  }
  Real velocity(int field, std::size_t node, int d) const {
    return p[d][at(field, node)] / m[at(field, node)];
  }
  Real momentum(int field, std::size_t node, int d) const { return p[d][at(field, node)]; }
  Real force(int field, std::size_t node, int d) const { return fi[d][at(field, node)]; }
};

// Pair table, params and rigid flags behind an MMConfig.
template <int D, class Real>
struct TestSetup {
  int F;
  std::vector<int> pair;
  std::vector<mmpm::PairParams<Real>> params;
  std::vector<unsigned char> rigid;
  mmpm::MMConfig<D, Real> cfg;

  explicit TestSetup(int fields, Real dt = Real(0.125)) : F(fields) {
    pair.assign(std::size_t(F * F), -1);
    rigid.assign(std::size_t(F), 0);
    cfg.fields = F;
    cfg.dt = dt;
    cfg.thickness = 1;
    cfg.mass_threshold = Real(1e-12);
  }
  // Adds params for the pair (a, b); the specified/radial normal points from a to b.
  mmpm::PairParams<Real>& connect(int a, int b, mmpm::PairParams<Real> pp) {
    pp.first_field = a;
    params.push_back(pp);
    pair[std::size_t(a * F + b)] = pair[std::size_t(b * F + a)] = int(params.size() - 1);
    return params.back();
  }
  const mmpm::MMConfig<D, Real>& config() {
    cfg.pair = pair.data();
    cfg.params = params.data();
    cfg.rigid = rigid.data();
    return cfg;
  }
};

// Every field present at 3 nodes in 4, with random mass, velocity, mean
// position, domain, gradient and force.
template <int D, class Real>
void fill_random(TestGrid<D, Real>& grid, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1, 1), pos(0.05, 1);
  std::uniform_int_distribution<int> coin(0, 3);
  for (int j = 0; j < grid.view.fields; ++j)
    for (std::size_t i = 0; i < grid.view.nodes; ++i) {
      if (coin(rng) == 0) continue;  // empty field at this node
      grid.set(j, i, Real(pos(rng)), {Real(u(rng)), Real(u(rng)), Real(u(rng))},
               {Real(0.05 * u(rng)), Real(0.05 * u(rng)), Real(0.05 * u(rng))}, Real(pos(rng)));
      grid.set_gradient(j, i, {Real(u(rng)), Real(u(rng)), Real(u(rng))});
      for (int d = 0; d < D; ++d) grid.f[d][grid.at(j, i)] = Real(u(rng));
    }
}

// Four fields, field 3 rigid, the six pairs (0,1) (0,2) (0,3) (1,2) (1,3)
// (2,3) with the given laws and normal methods, pair `exact_pair` with the
// exact integration, Δf_i on; Dn 5e3, Dt 2e3, μ 0.3, radial centre (3, 4, 5).
template <int D, class Real>
TestSetup<D, Real> four_field_setup(const std::array<mmpm::Law, 6>& laws,
                                    const std::array<mmpm::NormalMethod, 6>& normals,
                                    int exact_pair) {
  TestSetup<D, Real> setup(4, Real(1e-3));
  setup.rigid[3] = 1;
  mmpm::PairParams<Real> pp;
  pp.Dn = Real(5e3);
  pp.Dt = Real(2e3);
  pp.friction = Real(0.3);
  pp.radial_center = {3, 4, 5};
  int k = 0;
  for (int a = 0; a < 4; ++a)
    for (int b = a + 1; b < 4; ++b, ++k) {
      pp.law = laws[std::size_t(k)];
      pp.normal_method = normals[std::size_t(k)];
      pp.integration = k == exact_pair ? mmpm::Integration::exact : mmpm::Integration::explicit_;
      setup.connect(a, b, pp);
    }
  setup.cfg.use_force_difference = true;
  return setup;
}

}  // namespace mmpm::test
