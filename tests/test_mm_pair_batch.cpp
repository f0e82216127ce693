// Two-material nodes in batches (kernels/mm_pair_batch.hpp) against the
// per-node path of the multimaterial pass (kernels/multimaterial.hpp): the
// same grids through pass A and MUSL's two passes B, then USF's next pass A
// (holding what the last pass B held) and its pass B, with
// MMConfig::batch_pairs on and off. Every law, normal method, traction law,
// separation method, force limit on/off, Δf on/off, perfect and zero
// stiffnesses, volume screening; 2D and 3D, double and float; and a grid of
// four fields (one rigid, one pair with the exact integration) where batched
// and per-node nodes mix in one chunk.
//
// Expected: the same stick flags and node counts, momenta and energies
// within round-off (relative to each array's largest value: 1e-13 in
// double, 1e-5 in float), interface forces within the round-off of the
// separations times the stiffness (force_tolerance). The lane code writes the same
// operations in the same order, but the compiler contracts a*b + c into
// FMAs differently in the two codes (-ffp-contract=fast), so the last bits
// differ; a missed case or a wrong sign differs by O(1).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <string>
#include <type_traits>
#include <vector>

#include "kernels/multimaterial.hpp"
#include "tests/mm_test_grid.hpp"

namespace {

using mmpm::ContactArea;
using mmpm::Integration;
using mmpm::Law;
using mmpm::MMStats;
using mmpm::NormalMethod;
using mmpm::PairParams;
using mmpm::Separation;
using mmpm::TractionLaw;
using mmpm::test::fill_random;
using mmpm::test::TestGrid;
using mmpm::test::TestSetup;

template <class Real>
constexpr double kTolerance = std::is_same_v<Real, float> ? 1e-5 : 1e-13;

struct Outcome {
  MMStats stats;
  std::vector<unsigned char> flags;
  long limited_total = 0;
};

// `reuse`: pass A's geometry kept from other calls (the solver keeps one
// across steps); else a fresh one.
template <int D, class Real>
Outcome run(TestGrid<D, Real>& grid, TestSetup<D, Real>& setup, bool batch,
            mmpm::PassAGeometry<D, Real>* reuse = nullptr) {
  setup.cfg.batch_pairs = batch;
  const auto& cfg = setup.config();
  EXPECT_EQ(mmpm::validate_multimaterial(grid.view, cfg), nullptr);
  std::vector<std::uint32_t> list;
  mmpm::find_multimaterial_nodes(grid.view, cfg.mass_threshold, list);
  Outcome out;
  out.stats.reset(setup.F);
  mmpm::PassAGeometry<D, Real> fresh;
  mmpm::PassAGeometry<D, Real>& geometry = reuse ? *reuse : fresh;
  mmpm::multimaterial_pass_a(grid.view, list, cfg, out.stats, out.flags, {}, &geometry);
  out.limited_total = out.stats.force_limited;
  auto update = [&] {
    for (std::size_t i = 0; i < grid.p[0].size(); ++i)
      for (int d = 0; d < D; ++d) grid.p[d][i] += Real(0.02) * grid.f[d][i];
  };
  auto update_then_pass_b = [&](mmpm::PassB which) {
    update();
    mmpm::multimaterial_pass_b(grid.view, list, cfg, out.flags, out.stats, {}, &geometry, which);
  };
  // MUSL: after the update, then its repeat on the re-extrapolated momenta,
  // which holds the pairs the first held (and sticks the Coulomb pairs it
  // held stuck).
  update_then_pass_b(mmpm::PassB::after_update);
  update_then_pass_b(mmpm::PassB::strain);
  // USF's next step on the same nodes: pass A holds the pairs the last pass B
  // held (and sticks the Coulomb pairs it held stuck), from new momenta (as
  // they were, a pair the strain pass stuck along n sits at dp.n = 0, where
  // the two codes' round-off decided a one-sided normal differently).
  update();
  std::vector<unsigned char> held(out.flags.size());
  for (std::size_t k = 0; k < held.size(); ++k) held[k] = out.flags[k] & mmpm::kPassBRecord;
  mmpm::multimaterial_pass_a(grid.view, list, cfg, out.stats, out.flags, {}, &geometry,
                             held.data());
  out.limited_total = out.stats.force_limited;  // both passes A
  update_then_pass_b(mmpm::PassB::after_update);
  return out;
}

// Largest |a − b| over an array, relative to the array's largest |b|.
template <class Real>
double relative_difference(const std::vector<Real>& a, const std::vector<Real>& b) {
  double worst = 0, scale = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    const double diff = std::abs(double(a[i]) - double(b[i]));
    worst = diff > worst || diff != diff ? diff : worst;
    scale = std::max(scale, std::abs(double(b[i])));
  }
  return scale > 0 ? worst / scale : worst;
}

template <class Real>
double largest_difference(const std::vector<Real>& a, const std::vector<Real>& b) {
  double worst = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    const double diff = std::abs(double(a[i]) - double(b[i]));
    worst = diff > worst || diff != diff ? diff : worst;
  }
  return worst;
}

// The interface force is D δ A with δ = mx_b/m_b − mx_a/m_a: its round-off
// is that of δ (|δ| ≤ 0.1 in fill_random's data, ε|δ| per operation) times
// the stiffness and the area (A ≤ 2 here), whatever the force itself. Where
// δ is nearly along n, δ_t = |δ − δ_n n| is all cancellation: the two codes'
// tangential forces then differ by D_t ε |δ| A while the force is small.
template <class Real>
double force_tolerance(double largest_finite_stiffness) {
  return 64 * double(std::numeric_limits<Real>::epsilon()) * largest_finite_stiffness * 0.1 * 2;
}

template <int D, class Real>
void expect_same(const std::string& what, const TestGrid<D, Real>& a, const Outcome& oa,
                 const TestGrid<D, Real>& b, const Outcome& ob, double force_tol) {
  SCOPED_TRACE(what);
  const double tol = kTolerance<Real>;
  for (int d = 0; d < D; ++d) {
    EXPECT_LE(relative_difference(a.p[d], b.p[d]), tol) << "momentum " << d;
    EXPECT_LE(largest_difference(a.fi[d], b.fi[d]), force_tol) << "interface force " << d;
  }
  EXPECT_EQ(oa.flags, ob.flags);
  EXPECT_NEAR(oa.stats.interface_energy, ob.stats.interface_energy,
              tol * std::abs(ob.stats.interface_energy));
  EXPECT_EQ(oa.stats.nodes_2, ob.stats.nodes_2);
  EXPECT_EQ(oa.stats.nodes_3plus, ob.stats.nodes_3plus);
  EXPECT_EQ(oa.stats.force_limited, ob.stats.force_limited);
  for (std::size_t j = 0; j < oa.stats.rigid_reaction.size(); ++j)
    for (int d = 0; d < 3; ++d)
      EXPECT_NEAR(oa.stats.rigid_reaction[j][d], ob.stats.rigid_reaction[j][d],
                  tol * (1 + std::abs(ob.stats.rigid_reaction[j][d])));
}

std::array<int, 3> dims_of(int D) {
  return D == 2 ? std::array<int, 3>{24, 20, 1} : std::array<int, 3>{8, 7, 6};
}

// At an interface node the two domain gradients point opposite ways (each out
// of its own material), and the gradient area ½|n·(g_a − g_b)| adds their
// projections. fill_random draws them independently, so the difference can
// cancel: its round-off (ε |n·g| in each of two codes that contract their
// dot products differently) then moved float energies apart by 1.6e-5 of
// the total. Field 1's gradient is set to −0.8 of field 0's, as at an interface.
template <int D, class Real>
void oppose_gradients(TestGrid<D, Real>& grid) {
  for (std::size_t i = 0; i < grid.view.nodes; ++i)
    for (int d = 0; d < D; ++d) grid.g[d][grid.at(1, i)] = Real(-0.8) * grid.g[d][grid.at(0, i)];
}

// Two fields, one pair: every combination of the pair's options.
template <int D, class Real>
void check_two_fields() {
  constexpr Real kInf = std::numeric_limits<Real>::infinity();
  const std::array<std::array<Real, 2>, 4> stiffness{
      {{Real(5e3), Real(2e3)}, {Real(1e8), Real(3e7)}, {kInf, Real(5e2)}, {Real(0), kInf}}};
  long cases = 0, seeded = 0, limited = 0, screened_cases = 0;
  double energy = 0;
  long area_changed[3] = {0, 0, 0};                  // by rule: paper, closed, gradient
  long one_sided_stuck = 0, one_sided_released = 0;  // pass A's decisions
  for (Law law : {Law::stick, Law::frictionless, Law::friction, Law::interface})
    for (NormalMethod normal : {NormalMethod::mvg, NormalMethod::avg, NormalMethod::specified,
                                NormalMethod::radial, NormalMethod::rigid})
      for (int variant = 0; variant < (law == Law::interface ? 96 : 4); ++variant) {
        PairParams<Real> pp;
        pp.law = law;
        pp.friction = Real(0.3);
        pp.normal_method = normal;
        pp.normal_vector = {Real(0.6), Real(-0.8), Real(0)};
        pp.radial_center = {Real(3), Real(4), Real(2)};
        pp.separation = variant & 1 ? Separation::position : Separation::displacement;
        pp.contact_offset = Real(0.65);  // not the default: the batch must read it
        pp.omega_min = variant & 2 ? Real(0.4) : Real(0);  // screens some nodes
        // A sliver of either partner is absent (kContactPresentFraction): contact laws only.
        if (law != Law::interface && (variant & 2)) pp.presence_min_volume = Real(0.2);
        // Stick's test, a sliver thin along the normal only: it reads g.
        pp.presence_thin_along_normal =
            law == Law::stick && mmpm::reads_domain_gradient(pp) && (variant & 1) != 0;
        pp.force_limit = (variant & 4) == 0;
        pp.traction_law = variant & 8 ? TractionLaw::bilinear : TractionLaw::linear;
        // A perfect compression branch (one-sided, docs/multimaterial.md §4.1) in half
        // of the bilinear cases.
        pp.Dn_compression = variant & 2 ? kInf : Real(7e3);
        // The area rules of docs/multimaterial.md §7: paper, closed, gradient.
        pp.area = std::array{ContactArea::paper, ContactArea::closed,
                             ContactArea::gradient}[std::size_t(variant >> 5)];
        const auto& k = stiffness[std::size_t((variant >> 3) % 4)];
        pp.Dn = k[0];
        pp.Dt = k[1];
        screened_cases += (variant & 2) != 0;
        for (bool with_df : {false, true}) {
          TestGrid<D, Real> batched(dims_of(D), 2), per_node(dims_of(D), 2);
          // The paper and closed cases keep the seeds they had before the
          // gradient area's 32 variants were added after them (seeded apart).
          const unsigned seed = unsigned(variant < 64 ? 100 + seeded++ : 100000 + cases);
          fill_random(batched, seed);
          fill_random(per_node, seed);
          if (pp.area == ContactArea::gradient) {
            oppose_gradients(batched);
            oppose_gradients(per_node);
          }
          TestSetup<D, Real> s1(2, Real(1e-3)), s2(2, Real(1e-3));
          // Connect (1, 0): specified and radial normals then point away
          // from field 1, so the batch's sign is −1 half of the time.
          const int first = variant & 16 ? 1 : 0;
          s1.connect(first, 1 - first, pp);
          s2.connect(first, 1 - first, pp);
          s1.cfg.use_force_difference = s2.cfg.use_force_difference = with_df;
          const Outcome o1 = run(batched, s1, true);
          const Outcome o2 = run(per_node, s2, false);
          double stiffest = std::isinf(pp.Dn_compression) ? 0.0 : double(pp.Dn_compression);
          for (Real x : k) stiffest = std::isinf(x) ? stiffest : std::max(stiffest, double(x));
          expect_same("law " + std::to_string(int(law)) + " normal " + std::to_string(int(normal)) +
                          " variant " + std::to_string(variant) + " df " + std::to_string(with_df),
                      batched, o1, per_node, o2, force_tolerance<Real>(stiffest));
          ++cases;
          limited += o2.limited_total;
          for (unsigned char f : o2.flags)
            if (f & mmpm::kOneSidedNormal)
              ++((f & mmpm::kStickNormal) ? one_sided_stuck : one_sided_released);
          energy += o2.stats.interface_energy;
          if (pp.area != ContactArea::paper) {  // the same nodes with the paper's area
            PairParams<Real> paper = pp;
            paper.area = ContactArea::paper;
            TestGrid<D, Real> again(dims_of(D), 2);
            fill_random(again, seed);
            TestSetup<D, Real> s3(2, Real(1e-3));
            s3.connect(first, 1 - first, paper);
            s3.cfg.use_force_difference = with_df;
            area_changed[std::size_t(pp.area)] +=
                run(again, s3, false).stats.interface_energy != o2.stats.interface_energy;
          }
          if (::testing::Test::HasFailure()) return;  // one failing case is enough to read
        }
      }
  // The cases exercised what they are meant to.
  EXPECT_GT(limited, 0) << "no direction hit the force limit";
  EXPECT_GT(energy, 0.0);
  EXPECT_GT(area_changed[std::size_t(ContactArea::closed)], 0) << "the closed area changed nothing";
  EXPECT_GT(area_changed[std::size_t(ContactArea::gradient)], 0)
      << "the gradient area changed nothing";
  EXPECT_GT(one_sided_stuck, 0) << "no perfect compression branch stuck";
  EXPECT_GT(one_sided_released, 0) << "no perfect compression branch was released";
  EXPECT_GT(screened_cases, 0);
}

TEST(MultimaterialPairBatch, TwoFieldsEveryOptionMatchesPerNode2D) {
  check_two_fields<2, double>();
}
TEST(MultimaterialPairBatch, TwoFieldsEveryOptionMatchesPerNode3D) {
  check_two_fields<3, double>();
}
TEST(MultimaterialPairBatch, TwoFieldsEveryOptionMatchesPerNode3DFloat) {
  check_two_fields<3, float>();
}
TEST(MultimaterialPairBatch, TwoFieldsEveryOptionMatchesPerNode2DFloat) {
  check_two_fields<2, float>();
}

// Nodes without a usable normal: both fields' domain gradients infinite,
// NaN or zero at every third listed node (mvg and avg normals). The
// per-node path skips such a node (normalized_or_zero gives zero). The lanes
// compute the normal as u times a selected scale, which is non-finite for a
// non-finite u, and must skip the node as well: finite_nonzero rejects it
// (kernels/mm_pair_batch.hpp). Expected: the per-node results, no interface
// force at those nodes, and every momentum finite. Dropping the finiteness
// test lets the NaN through to p and fi.
template <int D, class Real>
void check_unusable_normals() {
  const Real bad[3] = {std::numeric_limits<Real>::infinity(),
                       std::numeric_limits<Real>::quiet_NaN(), Real(0)};
  for (NormalMethod normal : {NormalMethod::mvg, NormalMethod::avg}) {
    PairParams<Real> pp;
    pp.law = Law::interface;
    pp.normal_method = normal;
    pp.Dn = Real(5e3);
    pp.Dt = Real(2e3);
    TestGrid<D, Real> batched(dims_of(D), 2), per_node(dims_of(D), 2);
    fill_random(batched, 11);
    fill_random(per_node, 11);
    TestSetup<D, Real> s1(2, Real(1e-3)), s2(2, Real(1e-3));
    s1.connect(0, 1, pp);
    s2.connect(0, 1, pp);
    std::vector<std::uint32_t> list;
    mmpm::find_multimaterial_nodes(batched.view, s1.config().mass_threshold, list);
    ASSERT_GT(list.size(), 30u);
    std::vector<std::uint32_t> poisoned;
    for (std::size_t k = 0; k < list.size(); k += 3) {
      const Real v = bad[(k / 3) % 3];
      for (TestGrid<D, Real>* grid : {&batched, &per_node})
        for (int field = 0; field < 2; ++field)
          for (int d = 0; d < D; ++d) grid->g[d][grid->at(field, list[k])] = v;
      poisoned.push_back(list[k]);
    }
    const Outcome o1 = run(batched, s1, true);
    const Outcome o2 = run(per_node, s2, false);
    expect_same("unusable normals, normal " + std::to_string(int(normal)), batched, o1, per_node,
                o2, force_tolerance<Real>(5e3));
    for (const std::uint32_t node : poisoned)
      for (int field = 0; field < 2; ++field)
        for (int d = 0; d < D; ++d)
          EXPECT_EQ(batched.fi[d][batched.at(field, node)], Real(0)) << "node " << node;
    for (int d = 0; d < D; ++d)
      for (std::size_t i = 0; i < batched.p[d].size(); ++i)
        ASSERT_TRUE(std::isfinite(batched.p[d][i])) << "momentum " << d << " entry " << i;
    long interacting = 0;  // the other nodes did interact
    for (std::size_t k = 0; k < list.size(); ++k)
      if (k % 3 != 0) interacting += batched.fi[0][batched.at(0, list[k])] != Real(0);
    EXPECT_GT(interacting, long(list.size() / 3));
  }
}

TEST(MultimaterialPairBatch, UnusableNormalsSkippedAsPerNode2D) {
  check_unusable_normals<2, double>();
}
TEST(MultimaterialPairBatch, UnusableNormalsSkippedAsPerNode3DFloat) {
  check_unusable_normals<3, float>();
}

// Four fields, field 3 rigid, six pairs with different laws and normals, one
// with the exact integration: chunks mix batched nodes (the first pair met),
// nodes of other pairs, nodes with three or four fields and rigid partners.
template <int D, class Real>
TestSetup<D, Real> mixed_four_fields() {
  return mmpm::test::four_field_setup<D, Real>(
      {Law::interface, Law::friction, Law::stick, Law::interface, Law::interface,
       Law::frictionless},
      {NormalMethod::mvg, NormalMethod::avg, NormalMethod::radial, NormalMethod::specified,
       NormalMethod::rigid, NormalMethod::mvg},
      3);
}

template <int D, class Real>
void check_mixed_fields() {
  TestGrid<D, Real> batched(dims_of(D), 4), per_node(dims_of(D), 4);
  fill_random(batched, 7);
  fill_random(per_node, 7);
  auto s1 = mixed_four_fields<D, Real>(), s2 = mixed_four_fields<D, Real>();
  const Outcome o1 = run(batched, s1, true);
  const Outcome o2 = run(per_node, s2, false);
  EXPECT_GT(o2.stats.nodes_2, 50);
  EXPECT_GT(o2.stats.nodes_3plus, 50);
  expect_same("four fields", batched, o1, per_node, o2, force_tolerance<Real>(5e3));
}

// Pass B takes pass A's batches (SavedBatch), which the solver keeps from
// step to step while its node list changes. A geometry kept from runs on
// other grids (a longer list, then a shorter one, both batched) must give
// bitwise the results of a fresh one: every chunk's batch is rewritten by
// its pass A, also where pass A batched nothing. Two targets: the
// four-field grid (mixed chunks, one pair with the exact integration) and
// two fields joined by an interface with the exact integration, where pass
// A batches no chunk and pass B sorts every chunk itself. A chunk keeping a
// stale count or lane map differs by O(1).
template <int D, class Real>
void check_kept_geometry() {
  auto exact_pair = [] {
    TestSetup<D, Real> setup(4, Real(1e-3));
    PairParams<Real> pp;
    pp.law = Law::interface;
    pp.integration = Integration::exact;
    pp.Dn = Real(5e3);
    pp.Dt = Real(2e3);
    setup.connect(0, 1, pp);
    return setup;
  };
  auto larger = dims_of(D), smaller = dims_of(D);
  larger[0] += 6;
  smaller[0] = smaller[0] * 2 / 3;
  for (bool exact : {false, true}) {
    SCOPED_TRACE(exact ? "exact pair" : "four fields");
    mmpm::PassAGeometry<D, Real> kept;
    for (const auto& dims : {larger, smaller}) {  // other grids, other lists
      TestGrid<D, Real> other(dims, 4);
      fill_random(other, 3);
      auto s = mixed_four_fields<D, Real>();
      run(other, s, true, &kept);
    }
    TestGrid<D, Real> with_kept(dims_of(D), 4), with_fresh(dims_of(D), 4);
    fill_random(with_kept, 7);
    fill_random(with_fresh, 7);
    auto s1 = exact ? exact_pair() : mixed_four_fields<D, Real>();
    auto s2 = exact ? exact_pair() : mixed_four_fields<D, Real>();
    const Outcome o1 = run(with_kept, s1, true, &kept);
    const Outcome o2 = run(with_fresh, s2, true);
    EXPECT_GT(o2.stats.nodes_2, 50);
    for (int d = 0; d < D; ++d) {
      EXPECT_EQ(std::memcmp(with_kept.p[d].data(), with_fresh.p[d].data(),
                            with_kept.p[d].size() * sizeof(Real)),
                0)
          << "momentum " << d;
      EXPECT_EQ(std::memcmp(with_kept.fi[d].data(), with_fresh.fi[d].data(),
                            with_kept.fi[d].size() * sizeof(Real)),
                0)
          << "interface force " << d;
    }
    EXPECT_EQ(o1.flags, o2.flags);
    EXPECT_EQ(o1.stats.interface_energy, o2.stats.interface_energy);
  }
}

TEST(MultimaterialPairBatch, KeptGeometryGivesTheFreshResult2D) {
  check_kept_geometry<2, double>();
}
TEST(MultimaterialPairBatch, KeptGeometryGivesTheFreshResult3DFloat) {
  check_kept_geometry<3, float>();
}

TEST(MultimaterialPairBatch, MixedChunksMatchPerNode2D) {
  check_mixed_fields<2, double>();
}
TEST(MultimaterialPairBatch, MixedChunksMatchPerNode3DFloat) {
  check_mixed_fields<3, float>();
}

}  // namespace
