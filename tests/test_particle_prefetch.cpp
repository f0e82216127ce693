// [simulation] prefetch_particles (default true): the transfers request the
// particle columns they stream a batch ahead (kernels/particle_prefetch.hpp).
// A request is a hint, so runs with and without it must agree bit for bit,
// on one and two threads, through every kernel that requests: the packed 2D
// linear P2G and G2P (double, float, USL's pass with L in columns), the
// windowed uGIMP transfers with two fields and the grouped scatter of cubic
// B-splines. The solver requests only in 2D, when a pass's columns take
// kPrefetchMinParticleBytes or more; these scenes are smaller, so their
// steppers are told to request from 0 bytes on.
#include <gtest/gtest.h>

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "kernels/g2p_particle.hpp"
#include "kernels/particle_prefetch.hpp"
#include "kernels/shape.hpp"
#include "scene/format.hpp"
#include "scene/parse.hpp"
#include "solver/simulation.hpp"
#include "solver/stepper.hpp"
#include "switch_checks.hpp"

namespace {

using namespace mmpm;

const std::string kInputs = std::string(MMPM_SOURCE_DIR) + "/inputs/";

// The stepper behind a Simulation of D, Shape, Real told to request from 0
// bytes on (when on), or null when the scene runs another instantiation.
template <int D, class Shape, class Real>
Stepper<D, Shape, Real>* request_always(Simulation& sim) {
  auto* stepper = dynamic_cast<Stepper<D, Shape, Real>*>(&sim);
  if (stepper) stepper->set_prefetch_min_particle_bytes(0);
  return stepper;
}

template <int D, class Shape, class Real>
void expect_same_with_and_without(const std::string& file, const std::vector<std::string>& sets,
                                  int steps) {
  std::vector<std::string> off_sets = sets;
  off_sets.push_back("simulation.prefetch_particles=false");
  mmpm_test::expect_switch_changes_nothing(
      file + " " + ::testing::PrintToString(sets), steps, [&](const std::string& what) {
        mmpm_test::SimulationPair sims(make_simulation(parse_scene_file(kInputs + file, sets)),
                                       make_simulation(parse_scene_file(kInputs + file, off_sets)));
        auto* stepper = request_always<D, Shape, Real>(*sims.first);
        // Every pass of the scene requests (its columns exist from the start).
        if (!stepper || !stepper->particles_ahead(kStreamScatter).on()) {
          ADD_FAILURE() << what << ": not the instantiation the test means, or no requests";
          sims.first.reset();
        }
        return sims;
      });
}

TEST(ParticlePrefetch, TwoLayerInterfaceBitwise) {
  // uGIMP windows (lp columns), two fields (the field byte), MUSL's fused tail.
  expect_same_with_and_without<2, GimpShape, double>("two_layer.toml", {}, 40);
  // The tail as three passes: P2G and the gradient pass request on their own.
  expect_same_with_and_without<2, GimpShape, double>("two_layer.toml",
                                                     {"simulation.fuse_step_tail=false"}, 30);
}

TEST(ParticlePrefetch, PackedLinearBitwise) {
  // The packed 2D linear kernels, two fields in contact; float's low parts;
  // USL's pass that moves x and writes the L columns.
  const std::string linear = "grid.shape=\"linear\"";
  expect_same_with_and_without<2, LinearShape, double>("shear_blocks.toml", {linear}, 40);
  expect_same_with_and_without<2, LinearShape, float>(
      "shear_blocks.toml", {linear, "simulation.precision=\"float\""}, 40);
  expect_same_with_and_without<2, LinearShape, double>("shear_blocks.toml",
                                                       {linear, "simulation.scheme=\"USL\""}, 40);
}

TEST(ParticlePrefetch, CubicBsplinesBitwise) {
  // The grouped scatter (the widest 2D window).
  expect_same_with_and_without<2, BSpline3Shape, double>("collision.toml",
                                                         {"grid.shape=\"bspline3\""}, 30);
}

TEST(ParticlePrefetch, NotIn3D) {
  // The 3D step did not gain from the requests (Stepper::particles_ahead).
  auto sim = make_simulation(parse_scene_file(kInputs + "fibre_slab.toml", {}));
  auto* stepper = request_always<3, GimpShape, double>(*sim);
  ASSERT_NE(stepper, nullptr);
  EXPECT_FALSE(stepper->particles_ahead(kStreamScatter).on());
}

TEST(ParticlePrefetch, OnlyPastTheThreshold) {
  auto sim = make_simulation(parse_scene_file(kInputs + "two_layer.toml", {}));
  auto* stepper = dynamic_cast<Stepper<2, GimpShape, double>*>(sim.get());
  ASSERT_NE(stepper, nullptr);
  // A few thousand particles: far below kPrefetchMinParticleBytes.
  const std::size_t n = stepper->particles().n;
  ASSERT_GT(n, 0u);
  const ParticleLinesAhead all = ParticleLinesAhead(stepper->particles(), kStreamScatter, true);
  ASSERT_LT(n * all.bytes_per_particle(), kPrefetchMinParticleBytes);
  EXPECT_FALSE(stepper->particles_ahead(kStreamScatter).on());
  // Just at the threshold, and just past it.
  stepper->set_prefetch_min_particle_bytes(n * all.bytes_per_particle() + 1);
  EXPECT_FALSE(stepper->particles_ahead(kStreamScatter).on());
  stepper->set_prefetch_min_particle_bytes(n * all.bytes_per_particle());
  EXPECT_TRUE(stepper->particles_ahead(kStreamScatter).on());

  auto off = make_simulation(
      parse_scene_file(kInputs + "two_layer.toml", {"simulation.prefetch_particles=false"}));
  auto* off_stepper = request_always<2, GimpShape, double>(*off);
  ASSERT_NE(off_stepper, nullptr);
  EXPECT_FALSE(off_stepper->particles_ahead(kStreamScatter).on());
}

TEST(ParticlePrefetch, WrittenBackOnlyWhenOff) {
  mmpm_test::expect_written_back_only_when_off(kInputs + "two_layer.toml", "prefetch_particles",
                                               &SimulationSpec::prefetch_particles);
}

// The columns of each pass, from a view whose columns are distinct fake
// addresses (never dereferenced: the counts only read the pointers).
TEST(ParticlePrefetch, ColumnsOfEachPass) {
  std::vector<double> store(64);
  std::uint8_t bytes[4] = {};
  ParticleView<2, double> P;
  P.n = 1000;
  std::size_t next = 0;
  auto column = [&] { return store.data() + next++; };
  for (int d = 0; d < 2; ++d) {
    P.x[std::size_t(d)] = column();
    P.v[std::size_t(d)] = column();
    P.x_next[std::size_t(d)] = column();
  }
  P.m = column();
  P.V = column();
  for (auto& s : P.s) s = column();
  for (auto& l : P.L) l = column();
  // P2G: x (2), m, v (2), V and the force's three stress components.
  const ParticleLinesAhead scatter(P, kStreamScatter, true);
  EXPECT_EQ(scatter.columns(), 9);
  EXPECT_EQ(scatter.bytes_per_particle(), 9 * sizeof(double));
  // MUSL's velocity pass: x, v, m, x_next.
  EXPECT_EQ(ParticleLinesAhead(P, g2p_streams(kUpdateMotion | kScatterMomentum), true).columns(),
            7);
  // The gradient pass with the commit: x, x_next; L in columns or not.
  EXPECT_EQ(
      ParticleLinesAhead(P, g2p_streams(kVelocityGradient | kCommitPosition), false).columns(), 4);
  EXPECT_EQ(ParticleLinesAhead(P, g2p_streams(kVelocityGradient | kCommitPosition), true).columns(),
            8);
  // The fused tail: the gradient pass's, the stress update's and P2G's,
  // each column once: x, x_next, V, sigma (4), m, v (2).
  const ParticleLinesAhead tail(
      P, g2p_streams(kVelocityGradient | kCommitPosition) | kStreamConstitutive | kStreamScatter,
      false);
  EXPECT_EQ(tail.columns(), 12);
  EXPECT_EQ(tail.bytes_per_particle(), 12 * sizeof(double));
  // Optional columns count only when the scene has them.
  P.field = bytes;
  P.mat = bytes + 1;
  for (auto& l : P.lp) l = column();
  EXPECT_EQ(ParticleLinesAhead(P, kStreamScatter, true).columns(), 12);
  EXPECT_EQ(ParticleLinesAhead(P, kStreamConstitutive, true).columns(), 6);
  // Nothing streamed: nothing requested.
  EXPECT_FALSE(ParticleLinesAhead(P, 0u, true).on());
  EXPECT_FALSE(ParticleLinesAhead().on());
}

}  // namespace
