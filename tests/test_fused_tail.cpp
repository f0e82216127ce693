// [simulation] fuse_step_tail (default true) runs MUSL's gradient G2P, the
// constitutive update and the next step's P2G tile by tile, color by color
// (solver/stepper_impl.hpp fused_step_tail). It is a change of loop order
// only: each node receives its P2G sums in the colored P2G's order, so
// every particle field, energy and reaction must be bitwise those of the
// run with fuse_step_tail = false, step after step. Tolerance: none
// (bitwise).
//
// Scenes, each run for a fixed number of steps both ways:
//  - two blocks colliding at 6 mm/ms with tiles of 4 cells (contact, two
//    fields): particles change tile, so the tail skips the P2G of those
//    tiles and the next step re-sorts and scatters again;
//  - the two-layer specimen (imperfect interface, multimaterial fields),
//    with mx, Omega scattered apart and with the first P2G;
//  - a block sliding down a rigid incline under gravity (rigid material);
//  - the series bars with a traction ramp of 20 steps: the tail stays off
//    while the ramp rewrites the tractions, then takes over;
//  - three materials in one field (isotropic, transverse, neo-Hookean:
//    the per-material particle lists), uGIMP and linear;
//  - 3D uGIMP, one block with a non-uniform velocity.
// Each checks that the tail really ran (StepCounters::p2g_from_tail > 0),
// and the first two that it also handed back (re-sorts) when it had to.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "bitwise_same.hpp"
#include "scene/parse.hpp"
#include "solver/simulation.hpp"
#include "validation_util.hpp"

namespace {

using namespace mmpm;
using mmpm::testing::expect_bitwise_same;

const std::string kInputs = std::string(MMPM_SOURCE_DIR) + "/inputs/";

std::vector<std::string> with(std::vector<std::string> sets, bool fuse) {
  sets.push_back(std::string("simulation.fuse_step_tail=") + (fuse ? "true" : "false"));
  return sets;
}

struct Outcome {
  long from_tail = 0;  // steps whose P2G the previous step's tail had done
  long steps = 0;
};

// Steps both runs, comparing after every `check` steps; returns the fused
// run's counts.
Outcome run_both(const Scene& fused_scene, const Scene& separate_scene, int steps, int check,
                 const std::vector<double>* velocity = nullptr) {
  auto fused = make_simulation(fused_scene);
  auto separate = make_simulation(separate_scene);
  if (velocity) {
    fused->set_particle_field("velocity", *velocity);
    separate->set_particle_field("velocity", *velocity);
  }
  for (int s = 1; s <= steps; ++s) {
    fused->step();
    separate->step();
    if (s % check == 0 || s == steps) {
      expect_bitwise_same(*fused, *separate, fused_scene.name + " step " + std::to_string(s));
      if (::testing::Test::HasFailure()) break;
    }
  }
  EXPECT_EQ(separate->counters().p2g_from_tail, 0);
  std::printf("%s: %ld of %ld steps took their P2G from the tail\n", fused_scene.name.c_str(),
              fused->counters().p2g_from_tail, fused->step_count());
  return {fused->counters().p2g_from_tail, fused->step_count()};
}

Outcome run_file(const std::string& file, const std::vector<std::string>& sets, int steps,
                 int check) {
  return run_both(parse_scene_file(kInputs + file, with(sets, true)),
                  parse_scene_file(kInputs + file, with(sets, false)), steps, check);
}

// Compared after every step: a step whose tail skipped some tiles' P2G
// (grid_ready_ false) once took its kinetic_unresolved from the partly
// re-scattered m, and only those steps showed it.
TEST(FusedStepTail, CollisionWithTileChangesBitwise) {
  const Outcome o = run_file("collision.toml", {"grid.tile=4"}, 120, 1);
  EXPECT_GT(o.from_tail, 0);
  EXPECT_LT(o.from_tail, o.steps - 1) << "no re-sort: the hand-back path was not exercised";
}

// The traction ramp shortened to a few steps (the tail waited for a ramp to
// end until the loads left the transfers, 2026-11-28).
std::string short_ramp(const std::string& file, int steps) {
  const double dt = make_simulation(parse_scene_file(kInputs + file))->dt();
  return "load[0].ramp=" + std::to_string(steps * dt);
}

TEST(FusedStepTail, TwoLayerInterfaceBitwise) {
  const std::string ramp = short_ramp("two_layer.toml", 10);
  EXPECT_GT(run_file("two_layer.toml", {ramp}, 80, 20).from_tail, 60);
  // mx, Omega scattered with the first P2G (so by the tail too).
  EXPECT_GT(run_file("two_layer.toml", {ramp, "simulation.mm_fields_share=0.0"}, 80, 20).from_tail,
            60);
}

TEST(FusedStepTail, RigidInclineWithGravityBitwise) {
  const Outcome o = run_file("incline_block.toml", {}, 80, 20);
  EXPECT_GT(o.from_tail, 0);
}

// The loads act at the faces after the P2G (apply_face_tractions), so the
// tail runs during a ramp as well: every step but the first and those
// after a re-sort takes its P2G from the tail, with the same bits.
TEST(FusedStepTail, TractionRampThenTailBitwise) {
  const Outcome o = run_file("series_bars.toml", {short_ramp("series_bars.toml", 20)}, 60, 10);
  EXPECT_GT(o.from_tail, 55);
}

std::string three_materials(const std::string& shape) {
  return "[simulation]\ndimension = 2\nplane = \"strain\"\nend_time = 1.0\ncfl = 0.4\n\n"
         "[grid]\norigin = [0.0, 0.0]\ncell = [1.0, 1.0]\ncells = [68, 28]\nshape = \"" +
         shape +
         "\"\ntile = 8\n\n"
         "[[material]]\nname = \"iso\"\ntype = \"isotropic\"\ndensity = 1.0e-3\nE = 1000.0\n"
         "nu = 0.3\n\n"
         "[[material]]\nname = \"wood\"\ntype = \"transverse\"\ndensity = 5.0e-4\nEA = 4000.0\n"
         "ET = 800.0\nGA = 300.0\nnuA = 0.2\nnuT = 0.3\naxis = [1.0, 1.0]\n\n"
         "[[material]]\nname = \"rubber\"\ntype = \"neohookean\"\ndensity = 1.0e-3\nE = 500.0\n"
         "nu = 0.45\n\n"
         "[[body]]\nmaterial = \"iso\"\nshape = \"box\"\nmin = [4.0, 4.0]\nmax = [24.0, 24.0]\n"
         "particles_per_cell = 2\n\n"
         "[[body]]\nmaterial = \"wood\"\nshape = \"box\"\nmin = [24.0, 4.0]\nmax = [44.0, 24.0]\n"
         "particles_per_cell = 2\n\n"
         "[[body]]\nmaterial = \"rubber\"\nshape = \"box\"\nmin = [44.0, 4.0]\nmax = [64.0, 24.0]\n"
         "particles_per_cell = 2\n";
}

// A non-uniform velocity (every particle strains; some change tile).
std::vector<double> swirl(const Scene& scene, int dim) {
  const auto x = make_simulation(scene)->particle_field("position").values;
  std::vector<double> v(x.size());
  for (std::size_t p = 0; p < x.size() / std::size_t(dim); ++p) {
    const double* xp = &x[p * std::size_t(dim)];
    v[p * std::size_t(dim)] = 3.0 * std::sin(xp[1] / 4.0) + 0.05 * (xp[0] - 14.0);
    v[p * std::size_t(dim) + 1] = 2.0 * std::cos(xp[0] / 5.0);
    if (dim == 3) v[p * 3 + 2] = 1.5 * std::sin((xp[0] + xp[1]) / 6.0);
  }
  return v;
}

TEST(FusedStepTail, ThreeMaterialTypesBitwise) {
  for (const char* shape : {"gimp", "linear"}) {
    const std::string text = three_materials(shape);
    const Scene fused = parse_scene_text(text, "three.toml", with({}, true));
    const Scene separate = parse_scene_text(text, "three.toml", with({}, false));
    const std::vector<double> v = swirl(fused, 2);
    const Outcome o = run_both(fused, separate, 60, 15, &v);
    EXPECT_GT(o.from_tail, 0) << shape;
  }
}

TEST(FusedStepTail, Gimp3DBitwise) {
  const std::string text =
      "[simulation]\ndimension = 3\nend_time = 1.0\ncfl = 0.4\n\n"
      "[grid]\norigin = [0.0, 0.0, 0.0]\ncell = [1.0, 1.0, 1.0]\ncells = [20, 20, 16]\n"
      "shape = \"gimp\"\ntile = 4\n\n"
      "[[material]]\nname = \"steel\"\ntype = \"isotropic\"\ndensity = 7.8e-3\nE = 200000.0\n"
      "nu = 0.3\n\n"
      "[[body]]\nmaterial = \"steel\"\nshape = \"box\"\nmin = [3.0, 3.0, 3.0]\n"
      "max = [17.0, 17.0, 13.0]\nparticles_per_cell = 2\n";
  const Scene fused = parse_scene_text(text, "g3d.toml", with({}, true));
  const Scene separate = parse_scene_text(text, "g3d.toml", with({}, false));
  const std::vector<double> v = swirl(fused, 3);
  const Outcome o = run_both(fused, separate, 40, 10, &v);
  EXPECT_GT(o.from_tail, 0);
}

// The key reaches only MUSL: a USL run asks for the tail and runs without it.
TEST(FusedStepTail, OtherSchemesRunTheSeparatePasses) {
  const Outcome o = run_file("two_layer.toml", {"simulation.scheme=\"USL\""}, 10, 10);
  EXPECT_EQ(o.from_tail, 0);
}

}  // namespace
